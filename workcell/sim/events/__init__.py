"""The event layer of the simulation: the deterministic event loop and the trace.

Every other sub-package of :mod:`workcell.sim` builds on this one:

* :mod:`.loop` -- :class:`EventLoop`, one heap in virtual time with a
  tie-break counter, callbacks, generator processes, cancellable handles;
* :mod:`.trace` -- :class:`Trace` (the event log every layer writes to) and
  :class:`Metrics`.

Examples
--------
>>> loop = EventLoop()
>>> seen = []
>>> _ = loop.schedule(1.0, seen.append, "a")
>>> loop.run()
>>> seen, loop.now
(['a'], 1.0)
"""

from workcell.sim.events.loop import Event, EventLoop, Handle, Kernel, Process, ProcessGenerator
from workcell.sim.events.trace import KINDS, Metrics, Trace, TraceEvent

__all__ = [
    "KINDS",
    "Event",
    "EventLoop",
    "Handle",
    "Kernel",
    "Metrics",
    "Process",
    "ProcessGenerator",
    "Trace",
    "TraceEvent",
]
