"""The S2.12 exchange (``workcell.sim.protocol.exchange``): coordination
knows the arms only from their records on the control channel.

A coordinator is built here with no controller at all: the arms are the
channel's two ends that a test drives by hand. Its answers to departure
requests follow the motion reports it was sent (its book), and its orders
come back as records; a full run passes the guard stand-in only frozen
views, the mover in its own place in the book.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

from workcell.sim import SimOptions, simulate
from workcell.sim.comms.link import Link
from workcell.sim.comms.medium import IdealMedium
from workcell.sim.coordination.centralized import Coordinator
from workcell.sim.coordination.distributed import DistributedPolicy
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
from workcell.sim.protocol.exchange import (
    ArmView,
    ControlChannel,
    Departure,
    DepartureRequest,
    Excursion,
    MotionReport,
    ReleaseHold,
    TaskStarted,
)


def _standing(a: int, q: Any, **kw: Any) -> ArmView:
    return ArmView(a, None, 0, 0.0, 0.0, False, np.asarray(q, dtype=float), **kw)


@pytest.mark.parametrize("policy", [Coordinator, DistributedPolicy])
def test_departures_are_answered_from_the_reports_alone(cell: Any, plan: Any, policy: Any) -> None:
    """Arm 1 reports that it moves: arm 0's departure request is answered
    *stop* (the stand-in blocks on any moving arm of the book); arm 0
    reports its hold, arm 1 reports that it stopped: the coordination looks
    again and orders arm 0's hold released. No controller exists."""
    kernel = EventLoop()
    trace = Trace()
    names = ["coordinator", *cell.problem.arm_names]
    link = Link(kernel, IdealMedium(kernel, 3), trace, names, None, np.random.default_rng(0))
    for st in (1, 2):
        link.receivers[st] = lambda frame: None  # the arms' medium ends: silent
    channel = ControlChannel(2)
    orders: dict[int, list[Any]] = {0: [], 1: []}
    for a in (0, 1):
        channel.attach_arm(a, orders[a].append)
    asked: list[tuple[ArmView, tuple[ArmView, ...]]] = []

    def answer(mover: ArmView, book: Sequence[ArmView]) -> list[int]:
        asked.append((mover, tuple(book)))
        return [v.index for v in book if v.index != mover.index and v.running]

    coord = policy(cell, plan, kernel, link, trace, channel, guard_answer=answer)
    q0, q1 = cell.cell.start
    mover = _standing(0, q0)
    channel.report(0, DepartureRequest(mover))
    assert orders[0] == [Departure(True)]
    assert asked[-1][0] is mover and asked[-1][1][0] is mover

    channel.report(1, MotionReport(dataclasses.replace(_standing(1, q1), running=True), True))
    channel.report(0, DepartureRequest(mover))
    assert orders[0][-1] == Departure(False)
    assert coord.geo_held == {0: [1]}
    assert coord.book[1].running

    channel.report(0, MotionReport(_standing(0, q0, held=True, waiting=True), False))
    channel.report(1, MotionReport(_standing(1, q1), True))  # stopped: look again
    kernel.run(until=1.0)
    assert ReleaseHold() in orders[0]
    assert orders[1] == []  # nothing ordered to an arm that is not held


def test_task_notices_reach_the_coordinator_as_records(cell: Any, plan: Any) -> None:
    """A task start is a record on the channel: the coordinator moves the
    task to running only when told (its dispatch went out on the medium)."""
    kernel = EventLoop()
    trace = Trace()
    names = ["coordinator", *cell.problem.arm_names]
    link = Link(kernel, IdealMedium(kernel, 3), trace, names, None, np.random.default_rng(0))
    got: list[Any] = []
    for st in (1, 2):
        link.receivers[st] = got.append
    channel = ControlChannel(2)
    for a in (0, 1):
        channel.attach_arm(a, lambda order: None)
    coord = Coordinator(cell, plan, kernel, link, trace, channel)
    coord.start()
    kernel.run(until=float(np.min(plan.start)) + 1e-9)
    sent = [f for f in got if f.kind == "trajectory"]
    assert sent
    t = sent[0].payload[0].legs[-1].task  # a Trajectory record
    assert coord.status[t] == "dispatched"
    channel.report(sent[0].dst - 1, TaskStarted(t, kernel.now))
    assert coord.status[t] == "running"
    assert [e.kind for e in trace if e.task == cell.problem.task_names[t]][-1] == "task_start"


def test_a_run_shows_the_guard_only_frozen_views(cell: Any, plan: Any) -> None:
    """Over a whole run (supersigma, an emergency stop on the way) every
    departure request's view and every book entry are frozen ``ArmView``
    records, the mover in its own place (a moving mover only once an arm
    stopped off its plan); an arm's book entry changes only by
    a new report (a new record), never in place."""
    from workcell.sim import EmergencyStop

    seen: list[tuple[ArmView, tuple[ArmView, ...]]] = []

    def answer(mover: ArmView, book: Sequence[ArmView]) -> list[int]:
        seen.append((mover, tuple(book)))
        return []

    r = simulate(
        cell,
        plan,
        faults=[EmergencyStop(0.3 * plan.makespan, 2.0)],
        options=SimOptions(monitor=False, guard_answer=answer),
    )
    assert r.metrics.done_tasks == cell.problem.n_tasks
    assert len(seen) > 2 * cell.problem.n_tasks  # at least travel and task legs
    for mover, book in seen:
        assert isinstance(mover, ArmView) and book[mover.index] is mover
        assert all(isinstance(v, ArmView) for v in book)
        assert mover.leg is not None
        # a moving arm is checked only against an arm that stopped off its
        # plan (here by the emergency stop): S2.12's *stop* for arms on the way
        assert not mover.running or any(
            not v.running and v.leg is not None and not v.at_station for v in book
        )
    assert any(not mover.running for mover, _book in seen)
    with pytest.raises(dataclasses.FrozenInstanceError):
        seen[0][0].tau = 1.0  # type: ignore[misc]
    ex = Excursion(seen[0][0].leg, 0, 0.0, False)  # type: ignore[arg-type]
    with pytest.raises(dataclasses.FrozenInstanceError):
        ex.tau = 1.0  # type: ignore[misc]
