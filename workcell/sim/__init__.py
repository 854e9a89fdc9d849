"""Discrete-event simulation of the cell's communication (S1, S2.7-S2.9).

* :mod:`workcell.sim.kernel` -- the deterministic event kernel;
* :mod:`workcell.sim.medium` -- frames and the medium interface;
* :mod:`workcell.sim.network` -- serial, Multibus II, Ethernet CSMA/CD and
  CSMA/DCR media, the S2.9 delay bound :func:`dcr_bound`;
* :mod:`workcell.sim.supersigma` -- the SUPERSIGMA CCU and MICROBUS (S1).

Examples
--------
>>> k = Kernel()
>>> m = IdealMedium(k, 2)
>>> round(dcr_bound() * 1e6)
604
"""

from workcell.sim.kernel import Event, Handle, Kernel, Process
from workcell.sim.medium import (
    BROADCAST,
    MESSAGE_BYTES,
    DelayStats,
    FixedLatencyMedium,
    Frame,
    IdealMedium,
    Medium,
)
from workcell.sim.network.dcr import dcr_bound

__all__ = [
    "BROADCAST",
    "MESSAGE_BYTES",
    "DelayStats",
    "Event",
    "FixedLatencyMedium",
    "Frame",
    "Handle",
    "IdealMedium",
    "Kernel",
    "Medium",
    "Process",
    "dcr_bound",
]
