"""The S2.12 exchange (``workcell.sim.protocol.exchange``): coordination
knows the arms only from their records, and the records are frames of the
medium.

A coordinator is built here with no controller at all: the arms are the
channel's ends that a test drives by hand. Its answers to departure
requests follow the motion reports it was sent (its book) and the motions
it cleared, and its orders come back as records; a full run passes the
guard stand-in only frozen views, the mover in its own place in the book.
The records travel on the medium: in order, counted, delayed and lost like
the other frames.
"""

from __future__ import annotations

import dataclasses
import functools
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

from workcell.sim import SimOptions, simulate
from workcell.sim.comms.link import Link
from workcell.sim.comms.medium import MESSAGE_BYTES, FixedLatencyMedium, IdealMedium
from workcell.sim.coordination.centralized import Coordinator
from workcell.sim.coordination.distributed import DistributedPolicy
from workcell.sim.coordination.guard import GeometryGuard
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
from workcell.sim.harness.faults import MessageLoss
from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.exchange import (
    KINDS,
    ArmView,
    Departure,
    DepartureRequest,
    Excursion,
    MotionReport,
    ReleaseHold,
    TaskStarted,
)
from workcell.sim.protocol.messages import Leg, Station


def _standing(a: int, q: Any, **kw: Any) -> ArmView:
    return ArmView(a, None, 0, 0.0, 0.0, False, np.asarray(q, dtype=float), **kw)


def _wired(
    cell: Any, medium: Any = None, loss: Any = None
) -> tuple[EventLoop, Trace, Link, ControlChannel]:
    kernel = EventLoop()
    trace = Trace()
    names = ["coordinator", *cell.problem.arm_names]
    med = medium(kernel, 3) if medium is not None else IdealMedium(kernel, 3)
    link = Link(kernel, med, trace, names, loss, np.random.default_rng(0))
    channel = ControlChannel(2, link)
    for a in (0, 1):
        link.receivers[a + 1] = functools.partial(channel.at_station, a)
    return kernel, trace, link, channel


@pytest.mark.parametrize("policy", [Coordinator, DistributedPolicy])
def test_departures_are_answered_from_the_reports_alone(cell: Any, plan: Any, policy: Any) -> None:
    """Arm 1 reports that it moves: arm 0's departure request is answered
    *stop* (the stand-in blocks on any moving arm of the book); arm 1
    reports that it stopped: the coordination looks again and orders arm
    0's hold released. No controller exists."""
    kernel, trace, link, channel = _wired(cell)
    orders: dict[int, list[Any]] = {0: [], 1: []}
    for a in (0, 1):
        channel.attach_arm(a, orders[a].append, lambda kind, payload: None)
    asked: list[tuple[ArmView, tuple[ArmView, ...]]] = []

    def answer(mover: ArmView, book: Sequence[ArmView]) -> list[int]:
        asked.append((mover, tuple(book)))
        return [v.index for v in book if v.index != mover.index and v.running]

    coord = policy(cell, plan, kernel, link, trace, channel, guard_answer=answer)
    q0, q1 = cell.cell.start
    mover = _standing(0, q0)
    channel.report(0, DepartureRequest(mover, 1))
    kernel.run(until=0.5)
    assert orders[0] == [Departure(True, 1)]
    assert asked[-1][0] is mover and asked[-1][1][0] is mover

    channel.report(1, MotionReport(dataclasses.replace(_standing(1, q1), running=True), True))
    channel.report(0, DepartureRequest(mover, 2))
    kernel.run(until=1.0)
    assert orders[0][-1] == Departure(False, 2)
    assert coord.geo_held == {0: [1]}
    assert coord.book[1].running

    channel.report(0, MotionReport(_standing(0, q0, held=True, waiting=True), False))
    channel.report(1, MotionReport(_standing(1, q1), True))  # stopped: look again
    kernel.run(until=2.0)
    assert ReleaseHold() in orders[0]
    assert orders[1] == []  # nothing ordered to an arm that is not held


def test_a_cleared_motion_stays_reserved_until_the_arm_acknowledges_it(
    cell: Any, plan: Any
) -> None:
    """On a medium with delay the coordinator's book is old: a motion it
    cleared is reserved (checked against whatever the time) until a report
    sent after the arm took the answer comes back. Arm 1's departure
    request, answered while arm 0's clearance is unacknowledged, sees arm
    0 moving; once arm 0's report (acknowledging the answer) is in, the
    reservation is gone."""
    kernel, trace, link, channel = _wired(
        cell, lambda k, n: FixedLatencyMedium(k, stations=n, latency=0.01)
    )
    orders: dict[int, list[Any]] = {0: [], 1: []}
    for a in (0, 1):
        channel.attach_arm(a, orders[a].append, lambda kind, payload: None)
    seen: list[tuple[int, list[bool]]] = []

    def answer(mover: ArmView, book: Sequence[ArmView]) -> list[int]:
        seen.append((mover.index, [v.running for v in coord.reserved(1 - mover.index)]))
        return []

    coord = Coordinator(cell, plan, kernel, link, trace, channel, guard_answer=answer)
    q0, q1 = cell.cell.start
    channel.report(0, DepartureRequest(_standing(0, q0), 1))
    kernel.run(until=0.015)  # the request is in, the answer on its way
    assert orders[0] == [] and len(coord.reserved(0)) == 1
    channel.report(1, DepartureRequest(_standing(1, q1), 1))
    kernel.run(until=0.05)
    assert orders[0] == [Departure(True, 1)] and orders[1] == [Departure(True, 1)]
    assert seen[-1] == (1, [True])  # arm 0 counted as moving
    assert channel.taken[0] == 0  # arm 0's station took the answer (number 0)
    channel.report(0, MotionReport(_standing(0, q0), True))  # acknowledges it
    kernel.run(until=0.1)
    assert coord.reserved(0) == []


def test_the_streams_deliver_in_order_through_loss(cell: Any) -> None:
    """Half of the frames are lost and sent again after a timeout: later
    frames arrive first, wait, and every record is still taken once, in
    the order sent (a go never overtakes the stop sent before it)."""
    kernel, _trace, link, channel = _wired(cell, loss=MessageLoss(0.5, timeout=0.003))
    got: list[int] = []
    channel.attach_arm(0, lambda rec: got.append(rec.ask), lambda kind, payload: None)
    channel.attach_arm(1, lambda rec: None, lambda kind, payload: None)
    for i in range(40):
        kernel.schedule(i * 1e-4, channel.order, 0, Departure(i % 2 == 0, i))
    kernel.run(until=5.0)
    assert got == list(range(40))
    assert channel.waited > 0 and link.retransmissions > 0


def test_task_notices_reach_the_coordinator_as_frames(cell: Any, plan: Any) -> None:
    """A task start is a frame of the medium: the coordinator moves the
    task to running only when it arrives (its dispatch went out on the
    medium too)."""
    kernel, trace, link, channel = _wired(cell)
    got: list[Any] = []
    for a in (0, 1):
        channel.attach_arm(a, lambda order: None, lambda kind, payload, a=a: got.append(payload))
    coord = Coordinator(cell, plan, kernel, link, trace, channel)
    coord.start()
    kernel.run(until=float(np.min(plan.start)) + 1e-9)
    sent = [p for p in got if hasattr(p, "legs")]
    assert sent
    t = sent[0].legs[-1].task  # a Trajectory record
    a = int(cell.problem.mode_arm[int(plan.mode[t])])
    assert coord.status[t] == "dispatched"
    channel.report(a, TaskStarted(t, kernel.now))
    assert coord.status[t] == "dispatched"  # on its way
    kernel.run(until=kernel.now + 0.01)
    assert coord.status[t] == "running"
    assert [e.kind for e in trace if e.task == cell.problem.task_names[t]][-1] == "task_start"
    assert "task_started" in {e.message for e in trace.of_kind("message")}


def test_the_exchange_is_counted_on_the_medium(cell: Any, plan: Any) -> None:
    """A run's S2.12 records are frames of their own kinds and sizes: in
    the trace's message rows, in the link's count, with their delays."""
    r = simulate(cell, plan, medium="ethernet", options=SimOptions(monitor=False))
    rows = [e for e in r.trace.of_kind("message") if e.src != e.dst]
    kinds = Counter(e.message for e in rows)
    assert kinds["departure_request"] == kinds["departure"] > 0
    assert kinds["task_started"] == kinds["task_ended"] == cell.problem.n_tasks
    for e in rows:
        if e.message in KINDS.values():
            assert e.size == MESSAGE_BYTES[e.message]
            assert e.delay > 0  # delayed like the rest
    assert r.metrics.messages == len(rows)


@pytest.fixture(scope="module")
def parking() -> Any:
    from workcell import compile_cell, load_example

    return compile_cell(load_example("parking"))


def test_the_guard_reserves_a_moving_arm_whatever_the_time(parking: Any) -> None:
    """A moving arm of the book is checked anywhere on what is left of its
    leg, from where it reported: arm 1 goes out to a pose touching arm 0
    and back. Its report says it set off long ago, so by the clock it is
    back already; it may as well have stopped on the way (a crash, an
    alarm) or be late by the medium's delay, so arm 0 is told *stop*. Once
    a report puts it past that pose, arm 0 may go (S2.12)."""
    from workcell.geometry import CollisionWorld

    cell = parking
    arm_a, arm_b = cell.cell.arms
    qb = np.asarray(cell.cell.start[1], dtype=float)
    p = cell.problem
    poses = [[], []]  # every compiled task pose of each arm, every 0.1 s
    for m, cm in enumerate(cell.modes):
        tr = cm.trajectory
        poses[int(p.mode_arm[m])].extend(tr.sample(np.arange(0.0, tr.duration, 0.1)))
    world = CollisionWorld()
    world.add_arm(arm_a, q=cell.cell.start[0])
    world.add_arm(arm_b, q=qb)
    touching = None
    for q1 in poses[1]:
        world.set_group_transforms(arm_b.name, arm_b.shape_transforms(q1[None, :])[0])
        for q0 in poses[0]:
            world.set_group_transforms(arm_a.name, arm_a.shape_transforms(q0[None, :])[0])
            if world.collide(arm_a.name, arm_b.name):
                touching = (q0, q1)
                break
        if touching is not None:
            break
    assert touching is not None
    qa, hit = touching
    world.set_group_transforms(arm_b.name, arm_b.shape_transforms(qb[None, :])[0])
    assert not world.collide(arm_a.name, arm_b.name)
    there_and_back = arm_b.time_path(np.stack([qb, hit, qb]), "sync")
    d = float(there_and_back.duration)
    leg_b = Leg("task", 0, -1, there_and_back, [Station(d, end=True)])
    nudge = arm_a.move(qa, qa + 1e-3, arm_a.interpolation)
    nudge_leg = Leg("task", 1, -1, nudge, [Station(nudge.duration, end=True)])
    now = 100.0
    mover = ArmView(0, nudge_leg, 0, 0.0, now, False, qa)
    guard = GeometryGuard(cell, clock=lambda: now)
    long_ago = ArmView(1, leg_b, 0, 0.0, now - 0.95 * d, True, qb)
    assert np.allclose(long_ago.position(now), there_and_back.sample(np.array([0.95 * d]))[0])
    assert guard.blockers(mover, [mover, long_ago]) == [1]
    past_it = ArmView(1, leg_b, 0, 0.95 * d, now, True, qb)  # reported on its way back
    assert guard.blockers(mover, [mover, past_it]) == []
    home = ArmView(1, None, 0, 0.0, 0.0, False, qb)
    assert guard.blockers(mover, [mover, home]) == []


def test_a_run_shows_the_guard_only_frozen_views(cell: Any, plan: Any) -> None:
    """Over a whole run (supersigma, an emergency stop on the way) every
    departure request's view and every book entry are frozen ``ArmView``
    records, the mover in its own place, standing (it asks before it sets
    off); an arm's book entry changes only by a new report (a new record),
    never in place."""
    from workcell.sim import EmergencyStop

    seen: list[tuple[ArmView, tuple[ArmView, ...]]] = []

    def answer(mover: ArmView, book: Sequence[ArmView]) -> list[int]:
        seen.append((mover, tuple(book)))
        return []

    r = simulate(
        cell,
        plan,
        faults=[EmergencyStop(0.3 * plan.makespan, 2.0)],
        medium="ethernet",
        options=SimOptions(monitor=False, guard_answer=answer),
    )
    assert r.metrics.done_tasks == cell.problem.n_tasks
    assert len(seen) > 2 * cell.problem.n_tasks  # at least travel and task legs
    for mover, book in seen:
        assert isinstance(mover, ArmView) and book[mover.index] is mover
        assert all(isinstance(v, ArmView) for v in book)
        assert mover.leg is not None and not mover.running
    with pytest.raises(dataclasses.FrozenInstanceError):
        seen[0][0].tau = 1.0  # type: ignore[misc]
    ex = Excursion(seen[0][0].leg, 0, 0.0, False)  # type: ignore[arg-type]
    with pytest.raises(dataclasses.FrozenInstanceError):
        ex.tau = 1.0  # type: ignore[misc]
