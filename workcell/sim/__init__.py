"""Discrete-event simulation of the cell's coordination and control (S1, S2).

The package is split into the paper's layers (S2.1), one sub-package each,
importing downwards only (import-linter contracts in ``pyproject.toml``):

* :mod:`workcell.sim.events` -- the deterministic event loop and the trace;
* :mod:`workcell.sim.comms` -- frames, the medium interface, serial,
  Multibus II, Ethernet CSMA/CD and CSMA/DCR media, the S2.9 delay bound
  :func:`dcr_bound`, the SUPERSIGMA MICROBUS (S1.3);
* :mod:`workcell.sim.protocol` -- the messages between coordination and
  control, the published motion records, the state machines;
* :mod:`workcell.sim.control` -- the S2.3 arm controllers, force sensing
  and the reflex arc, the SUPERSIGMA unit (S1);
* :mod:`workcell.sim.coordination` -- the coordination policies (S2.7);
* :mod:`workcell.sim.harness` -- faults, options, the safety monitor and
  :func:`simulate`.

Examples
--------
>>> k = EventLoop()
>>> m = IdealMedium(k, 2)
>>> round(dcr_bound() * 1e6)
604
"""

from workcell.sim.comms.dcr import dcr_bound
from workcell.sim.comms.medium import (
    BROADCAST,
    MESSAGE_BYTES,
    DelayStats,
    FixedLatencyMedium,
    Frame,
    IdealMedium,
    Medium,
)
from workcell.sim.events.loop import Event, EventLoop, Handle, Kernel, Process
from workcell.sim.events.trace import Metrics, Trace, TraceEvent
from workcell.sim.harness.faults import (
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
)
from workcell.sim.harness.monitor import SafetyViolation
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import SimResult, simulate

__all__ = [
    "BROADCAST",
    "MESSAGE_BYTES",
    "ActivateZones",
    "ArmFailure",
    "Crash",
    "DelayStats",
    "EmergencyStop",
    "Event",
    "EventLoop",
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
