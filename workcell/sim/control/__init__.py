"""The control layer of the simulation (S2.1, S2.2, S2.3, S1).

* :mod:`.controller` -- the S2.3 arm controller: a dynamic and a
  communication processor, their six internal messages, the pipeline of
  offset + 2 points, stops matched by id;
* :mod:`.force` -- the wrist force sensor, the reflex arc and force-guided
  insertion (S1.2, S1.7);
* :mod:`.supersigma` -- the SUPERSIGMA central control unit and its
  programs (S1).

The controllers talk to the coordination layer only through frames on the
medium (:mod:`workcell.sim.comms`) carrying the records of
:mod:`workcell.sim.protocol`; they never import :mod:`workcell.sim.coordination`.
"""
