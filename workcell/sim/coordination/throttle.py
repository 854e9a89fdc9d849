"""The throttled look-again of the geometric check (S2.6, S2.12), one copy for both policies.

A held arm's way is looked at again whenever something moves or stops
(watch and notify): the centralized coordinator looks at every arm it told
*stop* (:func:`~workcell.sim.coordination.geometric.arm_moved`), a
distributed peer at its own arm (:meth:`~workcell.sim.coordination.
distributed.sight.Sight._notify`). Both use one :class:`Throttle`, which
guarantees progress: at most ``limit`` looks run at one instant; after
that the next look comes one ``period`` later (the kernel's time advances),
and after ``max_stalled`` such deferred looks with no progress (a task
starting or ending: :meth:`Throttle.progress`) no look is scheduled at all:
the arms still held stay held (an unresolved geometric deadlock, reported
per task).

Examples
--------
>>> from workcell.sim.events.loop import EventLoop
>>> k = EventLoop()
>>> looks = []
>>> th = Throttle(k, lambda: (looks.append(k.now), th.poke()), limit=2, max_stalled=1, period=0.5)
>>> th.poke()
>>> k.run()
>>> looks   # each look pokes again: 2 at 0, the 3rd a period later (+2 more), then none
[0.0, 0.0, 0.5, 0.5, 0.5]
"""

from __future__ import annotations

import math
from collections.abc import Callable

from workcell.sim.events.loop import EventLoop, Handle

__all__ = ["Throttle"]


class Throttle:
    """Schedules ``look`` after a change, at most ``limit`` times per instant.

    Parameters
    ----------
    kernel : EventLoop
    look : callable
        ``look()``: the look again (runs as its own event, priority 1: after
        the other events of its instant).
    limit : int
        Looks at one instant before the next waits ``period``.
    max_stalled : int
        Deferred looks with no :meth:`progress` before the looks stop.
    period : float
        Seconds a deferred look waits (the geometric check's sampling step).
    """

    __slots__ = (
        "_at",
        "_handle",
        "_n",
        "kernel",
        "limit",
        "look",
        "max_stalled",
        "period",
        "stalled",
    )

    def __init__(
        self,
        kernel: EventLoop,
        look: Callable[[], None],
        *,
        limit: int,
        max_stalled: int,
        period: float,
    ) -> None:
        self.kernel = kernel
        self.look = look
        self.limit = int(limit)
        self.max_stalled = int(max_stalled)
        self.period = float(period)
        self.stalled = 0
        """Deferred looks since the last :meth:`progress`."""
        self._handle: Handle | None = None
        self._at = -math.inf
        self._n = 0

    @property
    def pending(self) -> bool:
        """A look is scheduled and has not run yet."""
        return self._handle is not None

    def poke(self) -> None:
        """Something changed: look again (now, later, or not at all; module docstring)."""
        if self._handle is not None:
            return
        now = self.kernel.now
        if now != self._at:
            self._at, self._n = now, 0
        self._n += 1
        delay = 0.0
        if self._n > self.limit:
            if self.stalled >= self.max_stalled:
                return
            self.stalled += 1
            delay = self.period
        self._handle = self.kernel.schedule(delay, self._fire, priority=1)

    def progress(self) -> None:
        """A task started or ended: the stalled count starts again."""
        self.stalled = 0

    def _fire(self) -> None:
        self._handle = None
        self.look()
