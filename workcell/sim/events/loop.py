"""A deterministic discrete-event loop in virtual time (the simulation's
event kernel; "kernel" alone in this package means the scheduler's numba
kernel, so the loop is called :class:`EventLoop`).

The loop keeps a heap of ``(time, priority, counter)`` keys. The counter is
a tie-break that grows with every schedule call, so two events at the same
time and priority run in the order they were scheduled and the same inputs
replay bit for bit. Callbacks are plain functions; *processes* are Python
generators that ``yield`` a delay (seconds, float) or an :class:`Event` and are
resumed when the delay has elapsed or the event has fired.

``run(until, realtime=factor)`` paces the run against a wall clock so that
virtual time advances at ``factor`` times wall time (``factor=1`` is real
time, ``2`` twice as fast); the clock and the sleep are injectable so the
pacing is testable without real time.

Why an own kernel rather than SimPy. Not speed: SimPy (4.1.2) has the same
design (a heap with a tie-break counter, generator processes, a real-time
variant), and ``python -m benchmarks.bench_simkernel`` measures both side by
side on the same seeded workloads (timer chains of plain callbacks, and
generator processes): they run at about the same rate, within the noise of
a shared machine (see ``benchmarks/results/simkernel.md`` for the latest
ratios). What the own kernel gives is what the network media need and SimPy
lacks or makes indirect: plain callbacks with arguments, a :class:`Handle`
that *cancels* a scheduled callback (a collision cuts a transmission short;
in SimPy a timeout cannot be withdrawn, only ignored when it fires), a
priority per callback, a wall clock and sleep that can be injected so that
real-time pacing is tested without real time, and no dependency for the
simulation core (SimPy is only a development dependency, for the benchmark).

Examples
--------
>>> k = EventLoop()
>>> trace = []
>>> _ = k.schedule(2.0, trace.append, "b")
>>> _ = k.schedule(1.0, trace.append, "a")
>>> def proc(k):
...     yield 0.5
...     trace.append(("p", k.now))
>>> _ = k.process(proc(k))
>>> k.run()
>>> trace
[('p', 0.5), 'a', 'b']
>>> k.now
2.0
"""

from __future__ import annotations

import gc
import heapq
import math
import time
from collections.abc import Callable, Generator
from typing import Any

from multiarm.errors import UsageError, ValidationError

__all__ = ["Event", "EventLoop", "Handle", "Kernel", "Process", "ProcessGenerator"]

_INF = math.inf
_heappush = heapq.heappush

ProcessGenerator = Generator["float | Event", Any, Any]
"""What :meth:`EventLoop.process` accepts: a generator yielding delays or events."""


class Handle(list[Any]):
    """A scheduled callback; :meth:`cancel` removes it before it runs.

    A list ``[time, priority, seq, callback, args, cancelled]`` built in C
    (no Python ``__init__`` per schedule); the heap holds ``(time, priority,
    seq, handle)`` tuples, compared in C, ``seq`` unique.

    It is built from ``(time, priority, seq, callback, args, False)``:
    virtual time (seconds), priority (lower runs first among callbacks at the
    same time), tie-break counter (the order of scheduling), the function and
    its positional arguments.
    """

    __slots__ = ()

    @property
    def time(self) -> float:
        """Virtual time at which the callback runs, seconds."""
        return float(self[0])

    @property
    def priority(self) -> int:
        """Priority among callbacks due at the same time (lower first)."""
        return int(self[1])

    @property
    def seq(self) -> int:
        """Tie-break counter: the order of scheduling."""
        return int(self[2])

    @property
    def callback(self) -> Callable[..., object]:
        """The function to call."""
        cb: Callable[..., object] = self[3]
        return cb

    @property
    def args(self) -> tuple[object, ...]:
        """Its positional arguments."""
        args: tuple[object, ...] = self[4]
        return args

    @property
    def cancelled(self) -> bool:
        """Whether :meth:`cancel` was called."""
        return bool(self[5])

    def cancel(self) -> None:
        """Do not run the callback (no effect if it has already run)."""
        self[5] = True

    def __repr__(self) -> str:
        name = getattr(self.callback, "__name__", repr(self.callback))
        state = " cancelled" if self.cancelled else ""
        return f"<Handle t={self.time!r} prio={self.priority} #{self.seq} {name}{state}>"


class Event:
    """Something that happens once; processes may ``yield`` it to wait for it.

    Parameters
    ----------
    kernel : EventLoop
        The kernel the event belongs to.

    Examples
    --------
    >>> k = EventLoop()
    >>> ev = Event(k)
    >>> got = []
    >>> def waiter():
    ...     value = yield ev
    ...     got.append((k.now, value))
    >>> _ = k.process(waiter())
    >>> _ = k.schedule(3.0, ev.succeed, "done")
    >>> k.run()
    >>> got
    [(3.0, 'done')]
    """

    __slots__ = ("_callbacks", "kernel", "triggered", "value")

    def __init__(self, kernel: EventLoop) -> None:
        self.kernel = kernel
        self.triggered = False
        self.value: object = None
        self._callbacks: list[Callable[[Event], object]] = []

    def add_callback(self, callback: Callable[[Event], object]) -> None:
        """Call ``callback(event)`` when the event fires (at once, as a new
        kernel callback at the current time, if it already has).

        Parameters
        ----------
        callback : callable
            Receives the event.
        """
        if self.triggered:
            self.kernel.schedule(0.0, callback, self)
        else:
            self._callbacks.append(callback)

    def succeed(self, value: object = None) -> Event:
        """Fire the event now; waiting processes resume at the current time.

        Parameters
        ----------
        value : object, optional
            Sent into every waiting process as the value of its ``yield``.

        Returns
        -------
        Event
            ``self``.

        Raises
        ------
        UsageError
            If the event has already fired.
        """
        if self.triggered:
            raise UsageError(f"event {self!r} has already fired")
        self.triggered = True
        self.value = value
        callbacks, self._callbacks = self._callbacks, []
        for cb in callbacks:
            self.kernel.schedule(0.0, cb, self)
        return self


class Process(Event):
    """A generator run by the kernel; as an :class:`Event` it fires when the
    generator returns, with its return value.

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    generator : generator
        Yields a delay (float, seconds, >= 0) or an :class:`Event`.
    """

    __slots__ = ("generator",)

    def __init__(self, kernel: EventLoop, generator: ProcessGenerator) -> None:
        super().__init__(kernel)
        self.generator = generator
        kernel.schedule(0.0, self._resume)

    def _resume(self, sent: object = None) -> None:
        if isinstance(sent, Event):
            sent = sent.value
        try:
            target = self.generator.send(sent)
        except StopIteration as stop:
            self.succeed(stop.value)
            return
        if type(target) is float or isinstance(target, int):  # a delay: the common case
            self.kernel.schedule(float(target), self._resume)
        elif isinstance(target, Event):
            target.add_callback(self._resume)
        elif isinstance(target, float):
            self.kernel.schedule(float(target), self._resume)
        else:
            raise UsageError(
                f"process {self.generator!r} yielded {target!r}; yield a delay (float) or an Event"
            )


class EventLoop:
    """The event kernel: virtual clock, event heap, run loop.

    Parameters
    ----------
    start : float, optional
        Initial virtual time, seconds (default 0).
    clock : callable, optional
        Wall clock used by real-time pacing (default :func:`time.monotonic`).
    sleep : callable, optional
        Sleep used by real-time pacing (default :func:`time.sleep`).

    Attributes
    ----------
    events_run : int
        How many callbacks have run (work counter, for tests and benchmarks).
    """

    __slots__ = ("_clock", "_heap", "_limit", "_now", "_paced", "_seq", "_sleep", "events_run")

    def __init__(
        self,
        start: float = 0.0,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], object] = time.sleep,
    ) -> None:
        if not math.isfinite(start):
            raise ValidationError(f"EventLoop: start time must be finite, got {start!r}")
        self._now = float(start)
        self._heap: list[tuple[float, int, int, Handle]] = []
        self._seq = 0
        self._clock = clock
        self._sleep = sleep
        self.events_run = 0
        self._limit = -math.inf  # while running: the run's ``until`` (inf: none)
        self._paced = False  # while running: paced against the wall clock

    @property
    def now(self) -> float:
        """Current virtual time, seconds."""
        return self._now

    def schedule(
        self,
        at_or_delay: float,
        callback: Callable[..., object],
        *args: object,
        absolute: bool = False,
        priority: int = 0,
    ) -> Handle:
        """Run ``callback(*args)`` later.

        Parameters
        ----------
        at_or_delay : float
            Delay from now (seconds, >= 0), or the absolute virtual time
            (>= now) when ``absolute`` is true.
        callback : callable
            The function to call.
        *args : object
            Its arguments.
        absolute : bool, optional
            Read ``at_or_delay`` as an absolute time.
        priority : int, optional
            Lower runs first among callbacks due at the same time.

        Returns
        -------
        Handle
            Call ``handle.cancel()`` to withdraw it.

        Raises
        ------
        UsageError
            For a negative delay, a time in the past, or a non-finite time.
        """
        now = self._now
        t = float(at_or_delay) if absolute else now + at_or_delay
        if not (now <= t < _INF):
            raise UsageError(
                f"EventLoop.schedule: {callback!r} at {at_or_delay!r} "
                f"({'absolute' if absolute else 'delay'}) is in the past or not finite "
                f"(now = {self._now!r})"
            )
        seq = self._seq
        self._seq = seq + 1
        h = Handle((t, priority, seq, callback, args, False))
        _heappush(self._heap, (t, priority, seq, h))
        return h

    def event(self) -> Event:
        """A new, not yet fired :class:`Event` of this kernel.

        Returns
        -------
        Event
            The event.
        """
        return Event(self)

    def timeout(self, delay: float, value: object = None) -> Event:
        """An event that fires ``delay`` seconds from now.

        Parameters
        ----------
        delay : float
            Seconds, >= 0.
        value : object, optional
            The event's value.

        Returns
        -------
        Event
            The event.
        """
        ev = Event(self)
        self.schedule(delay, ev.succeed, value)
        return ev

    def process(self, generator: ProcessGenerator) -> Process:
        """Start a generator process at the current time.

        Parameters
        ----------
        generator : generator
            Yields delays (float, seconds) or events.

        Returns
        -------
        Process
            An event that fires with the generator's return value.
        """
        return Process(self, generator)

    def peek(self) -> float:
        """Time of the next pending callback (``inf`` if none).

        Returns
        -------
        float
            Seconds.
        """
        heap = self._heap
        while heap and heap[0][3][5]:
            heapq.heappop(heap)
        return heap[0][0] if heap else math.inf

    def advance(self, t: float) -> bool:
        """Move the clock to ``t`` from inside a callback, as if a callback
        scheduled now for ``t`` ran next: only when no other callback is due
        at or before ``t``, ``t`` is within the run's ``until`` and the run is
        not paced against the wall clock. A periodic process (the
        controllers' tick loop) runs its next period at once this way
        instead of through the heap; it does not count in :attr:`events_run`.

        Parameters
        ----------
        t : float
            Seconds, >= now.

        Returns
        -------
        bool
            Whether the clock moved (else it is unchanged: schedule instead).
        """
        if self._paced or not (self._now <= t <= self._limit) or self.peek() <= t:
            return False
        self._now = t
        return True

    def run(self, until: float | None = None, realtime: float | None = None) -> None:
        """Run callbacks in time order.

        Parameters
        ----------
        until : float, optional
            Stop before the first callback later than ``until`` and set the
            clock to ``until``; by default run until no callback is left.
        realtime : float, optional
            Pace the run so that virtual time advances at ``realtime`` times
            wall time (sleeping with the injected ``sleep``).

        Raises
        ------
        UsageError
            If ``until`` is before now or ``realtime`` is not positive.
        """
        if until is not None and until < self._now:
            raise UsageError(f"EventLoop.run: until={until!r} is before now={self._now!r}")
        if realtime is not None and not (realtime > 0 and math.isfinite(realtime)):
            raise UsageError(f"EventLoop.run: realtime factor must be > 0, got {realtime!r}")
        heap = self._heap
        pop = heapq.heappop
        limit = math.inf if until is None else until
        wall0 = self._clock() if realtime is not None else 0.0
        virt0 = self._now
        n = 0
        # The cyclic garbage collector is paused while callbacks run: a run
        # allocates many small, acyclic records (frames, trace rows, motion
        # records), and every full collection would walk all of them again;
        # the reference counts free them as before, and the collector is
        # restored (and catches up) when the run returns or raises.
        collecting = gc.isenabled()
        if collecting:
            gc.disable()
        self._limit = limit
        self._paced = realtime is not None
        try:
            while heap:
                t, _, _, h = heap[0]
                if t > limit:
                    break
                pop(heap)
                if h[5]:
                    continue
                if realtime is not None:
                    wait = wall0 + (t - virt0) / realtime - self._clock()
                    if wait > 0:
                        self._sleep(wait)
                self._now = t
                n += 1
                args = h[4]
                if args:
                    h[3](*args)
                else:
                    h[3]()
        finally:
            self.events_run += n
            self._limit = -math.inf
            self._paced = False
            if collecting:
                gc.enable()
        if until is not None:
            if realtime is not None:
                wait = wall0 + (until - virt0) / realtime - self._clock()
                if wait > 0:
                    self._sleep(wait)
            self._now = until


Kernel = EventLoop
"""The former name of :class:`EventLoop` (kept for one release)."""
