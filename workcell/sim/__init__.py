"""Discrete-event simulation of the cell's communication (S1, S2.7-S2.9).

* :mod:`workcell.sim.kernel` -- the deterministic event kernel;
* :mod:`workcell.sim.medium` -- frames and the medium interface;
* :mod:`workcell.sim.network` -- serial, Multibus II, Ethernet CSMA/CD and
  CSMA/DCR media, the S2.9 delay bound :func:`dcr_bound`;
* :mod:`workcell.sim.supersigma` -- the SUPERSIGMA CCU and MICROBUS (S1);
* :func:`simulate` -- a schedule executed by the coordinator
  (:mod:`.coordinator`) and the S2.3 arm controllers (:mod:`.controller`),
  with faults (:mod:`.faults`), the safety monitor (:mod:`.monitor`), traces
  and metrics (:mod:`.trace`).

Examples
--------
>>> k = Kernel()
>>> m = IdealMedium(k, 2)
>>> round(dcr_bound() * 1e6)
604
"""

from workcell.sim.faults import (
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
)
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
from workcell.sim.monitor import SafetyViolation
from workcell.sim.network.dcr import dcr_bound
from workcell.sim.options import SimOptions
from workcell.sim.run import SimResult, simulate
from workcell.sim.trace import Metrics, Trace, TraceEvent

__all__ = [
    "BROADCAST",
    "MESSAGE_BYTES",
    "ActivateZones",
    "ArmFailure",
    "Crash",
    "DelayStats",
    "EmergencyStop",
    "Event",
    "FaultPlan",
    "FixedLatencyMedium",
    "Frame",
    "Handle",
    "IdealMedium",
    "Kernel",
    "LatePart",
    "LostSync",
    "Medium",
    "MessageLoss",
    "Metrics",
    "Process",
    "SafetyViolation",
    "SimOptions",
    "SimResult",
    "Trace",
    "TraceEvent",
    "dcr_bound",
    "simulate",
]
