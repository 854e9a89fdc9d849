"""The harness of the simulation: what puts the layers together and judges them.

* :mod:`.faults` -- the fault records and :class:`FaultPlan`;
* :mod:`.options` -- :class:`SimOptions`;
* :mod:`.monitor` -- the independent safety monitor (reads only the
  published motion records, :mod:`workcell.sim.protocol`);
* :mod:`.simulate` -- :func:`simulate` and :class:`SimResult`.
"""
