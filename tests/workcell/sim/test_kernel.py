"""The event kernel: ordering, tie-breaks, replay, cancel, processes, pacing."""

from __future__ import annotations

import pytest

from multiarm.errors import UsageError
from workcell.sim.events.loop import Event, EventLoop, ProcessGenerator


def test_time_order_then_priority_then_schedule_order() -> None:
    k = EventLoop()
    trace: list[str] = []
    k.schedule(2.0, trace.append, "t2")
    k.schedule(1.0, trace.append, "t1-second", priority=1)
    k.schedule(1.0, trace.append, "t1-first", priority=0)
    k.schedule(1.0, trace.append, "t1-first-b", priority=0)
    k.schedule(0.5, trace.append, "abs", absolute=True)
    k.run()
    assert trace == ["abs", "t1-first", "t1-first-b", "t1-second", "t2"]
    assert k.now == 2.0
    assert k.events_run == 5


def _trace_of(seed_order: list[float]) -> list[tuple[float, int]]:
    k = EventLoop()
    out: list[tuple[float, int]] = []
    for i, t in enumerate(seed_order):
        k.schedule(t, lambda i=i: out.append((k.now, i)))
    k.run()
    return out


def test_same_inputs_same_trace() -> None:
    times = [0.3, 0.1, 0.3, 0.2, 0.1, 0.3]
    a = _trace_of(times)
    assert a == _trace_of(times)
    # ties keep scheduling order
    assert [i for t, i in a if t == 0.3] == [0, 2, 5]


def test_cancel() -> None:
    k = EventLoop()
    trace: list[int] = []
    h = k.schedule(1.0, trace.append, 1)
    k.schedule(2.0, trace.append, 2)
    h.cancel()
    assert k.peek() == 2.0
    k.run()
    assert trace == [2]


def test_handle_fields() -> None:
    k = EventLoop()
    h = k.schedule(1.5, print, "x", priority=3)
    h2 = k.schedule(0.5, print)
    assert (h.time, h.priority, h.seq, h.callback, h.args) == (1.5, 3, 0, print, ("x",))
    assert h2.seq == 1 and h2.args == ()
    states = [h.cancelled]
    assert "t=1.5 prio=3 #0 print" in repr(h)
    h.cancel()
    h2.cancel()
    states.append(h.cancelled)
    assert states == [False, True] and repr(h).endswith("cancelled>")
    k.run()
    assert k.events_run == 0


def test_until_stops_and_sets_clock() -> None:
    k = EventLoop()
    trace: list[int] = []
    k.schedule(1.0, trace.append, 1)
    k.schedule(3.0, trace.append, 3)
    k.run(until=2.0)
    assert trace == [1] and k.now == 2.0
    k.run()
    assert trace == [1, 3]


def test_past_and_bad_arguments_refused() -> None:
    k = EventLoop(start=5.0)
    with pytest.raises(UsageError, match="past"):
        k.schedule(-1.0, print)
    with pytest.raises(UsageError, match="past"):
        k.schedule(4.0, print, absolute=True)
    with pytest.raises(UsageError, match="until"):
        k.run(until=1.0)
    with pytest.raises(UsageError, match="realtime"):
        k.run(realtime=0.0)


def test_processes_wait_on_delays_and_events() -> None:
    k = EventLoop()
    ev = k.event()
    log: list[tuple[str, float, object]] = []

    def producer() -> ProcessGenerator:
        yield 2.0
        ev.succeed("hello")
        return "p-done"

    def consumer() -> ProcessGenerator:
        value = yield ev
        log.append(("got", k.now, value))
        yield k.timeout(1.5)
        log.append(("after", k.now, None))

    p = k.process(producer())
    k.process(consumer())
    k.run()
    assert log == [("got", 2.0, "hello"), ("after", 3.5, None)]
    assert p.triggered and p.value == "p-done"


def test_process_waiting_on_process() -> None:
    k = EventLoop()

    def child() -> ProcessGenerator:
        yield 1.0
        return 42

    def parent() -> ProcessGenerator:
        v = yield k.process(child())
        return int(v) + 1

    p = k.process(parent())
    k.run()
    assert p.value == 43 and k.now == 1.0


def test_event_fires_once_and_bad_yield() -> None:
    k = EventLoop()
    ev = Event(k)
    ev.succeed()
    with pytest.raises(UsageError, match="already fired"):
        ev.succeed()

    def bad() -> ProcessGenerator:
        yield "soon"  # type: ignore[misc]

    k.process(bad())
    with pytest.raises(UsageError, match="yielded 'soon'"):
        k.run()


class FakeClock:
    def __init__(self) -> None:
        self.t = 100.0
        self.sleeps: list[float] = []

    def clock(self) -> float:
        return self.t

    def sleep(self, s: float) -> None:
        self.sleeps.append(s)
        self.t += s


def test_realtime_pacing_with_injected_clock() -> None:
    fc = FakeClock()
    k = EventLoop(clock=fc.clock, sleep=fc.sleep)
    seen: list[tuple[float, float]] = []
    for t in (1.0, 2.0, 4.0):
        k.schedule(t, lambda: seen.append((k.now, fc.t)))
    k.run(until=6.0, realtime=2.0)  # virtual runs twice as fast as wall
    assert seen == [(1.0, 100.5), (2.0, 101.0), (4.0, 102.0)]
    assert fc.t == pytest.approx(103.0)
    assert fc.sleeps == pytest.approx([0.5, 0.5, 1.0, 1.0])


def test_realtime_does_not_sleep_when_behind() -> None:
    fc = FakeClock()
    k = EventLoop(clock=fc.clock, sleep=fc.sleep)

    def slow() -> None:
        fc.t += 10.0  # the callback itself takes 10 s of wall time

    k.schedule(1.0, slow)
    k.schedule(2.0, slow)
    k.run(realtime=1.0)
    assert fc.sleeps == [1.0]


def _periodic(k: EventLoop, period: float, times: list[float], inline: bool) -> None:
    """A periodic process (as the controllers' tick loop): every ``period``,
    the next period inline when the loop allows it (``inline``)."""

    def tick(n: int) -> None:
        times.append(k.now)
        if n == 0:
            return
        t = k.now + period
        if not (inline and k.advance(t)):
            k.schedule(t, tick, n - 1, absolute=True)
            return
        tick(n - 1)

    k.schedule(0.0, tick, 20)


def _ticks_and_others(inline: bool) -> tuple[list[float], list[tuple[float, float]], EventLoop]:
    k = EventLoop()
    ticks: list[float] = []
    others: list[tuple[float, float]] = []
    _periodic(k, 0.25, ticks, inline)
    # callbacks between, at and (with a higher priority) before ticks
    k.schedule(1.1, lambda: others.append((k.now, ticks[-1])))
    k.schedule(2.0, lambda: others.append((k.now, ticks[-1])))
    k.schedule(3.0, lambda: others.append((k.now, ticks[-1])), priority=-1)
    k.run()
    return ticks, others, k


def test_advance_runs_the_next_period_inline_only_when_nothing_else_is_due() -> None:
    for inline in (False, True):
        ticks, others, k = _ticks_and_others(inline)
        # the same order either way: a callback due at a tick's time runs first
        # (it was scheduled before the tick), and one of a higher priority too
        assert ticks == [0.25 * i for i in range(21)]
        assert others == [(1.1, 1.0), (2.0, 1.75), (3.0, 2.75)]
        assert k.now == 5.0
        # inline periods are not callbacks of the loop: inline, the ticks at
        # 0, 1.25, 2.0 and 3.0 are (each the first after another callback)
        assert k.events_run == (21 + 3 if not inline else 4 + 3)


def test_advance_refuses_past_until_paced_or_outside_a_run() -> None:
    k = EventLoop()
    assert not k.advance(1.0)  # not running
    got: list[bool] = []
    k.schedule(1.0, lambda: got.append(k.advance(1.5)))  # beyond until
    k.schedule(1.2, lambda: got.append(k.advance(1.3)))  # within: moves
    k.run(until=1.4)
    assert got == [False, True]
    assert k.now == 1.4
    fc = FakeClock()
    paced = EventLoop(clock=fc.clock, sleep=fc.sleep)
    paced.schedule(1.0, lambda: got.append(paced.advance(1.5)))
    paced.run(realtime=1.0)
    assert got[-1] is False and paced.now == 1.0
