"""The coordination layer of the simulation (S2.1, S2.4-S2.7, S2.12).

* :mod:`.centralized` -- the centralized coordinator of S2.7.

The coordinator talks to the arm controllers only through frames on the
medium (:mod:`workcell.sim.comms`) carrying the records of
:mod:`workcell.sim.protocol`; it never imports :mod:`workcell.sim.control`.
"""
