"""Regression tests: five ways a faulted run stalled or started a task early.

Each test builds the scenario of one cause from its description (the fault,
the medium and the timing) and checks the run through its public records
(``SimResult.tasks_frame()``, the trace, the metrics):

1. an emergency stop reaching an arm that already stands at a task start
   (through a medium with delay) must be released, and the arm pass on;
2. a zone activation falling exactly on a task's end (ideal medium) must
   release the arm whose task just ended;
3. with re-solving off, a surviving arm must not wait for good on the
   successor of a failed arm's task;
4. a withdrawal must not be overtaken by a retransmitted trajectory it
   cancels (message loss): the stale frame is dropped by its sequence number;
5. a part late from time 0 must hold back the task it gates.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from multiarm.errors import InternalError
from workcell.sim import (
    ActivateZones,
    ArmFailure,
    EmergencyStop,
    FaultPlan,
    Frame,
    IdealMedium,
    LatePart,
    MessageLoss,
    SimOptions,
    simulate,
)
from workcell.sim.coordination.centralized import CAUSE_KINDS

UNEXPLAINED = "not completed when the simulation ended"


@pytest.fixture(scope="module")
def serial_run(scara4: Any, scara4_plan: Any) -> Any:
    """scara4 on the serial bus, no fault: execution lags the plan (every
    message takes milliseconds), so arms are sent tasks whose predecessors
    on other arms are still running and stand at their starts and borders."""
    return simulate(scara4, scara4_plan, medium=SERIAL, options=SimOptions(monitor=False))


SERIAL = "serial-bus"


def _failed(r: Any) -> dict[str, str]:
    tf = r.tasks_frame()
    bad = tf[tf["status"] != "done"]
    return dict(zip(bad["task"], bad["cause"], strict=True))


def _handover(cc: Any, plan: Any) -> tuple[str, str, str]:
    """(failing arm, its task, the surviving arm) of scara4's greedy plan:
    ``place_cover1`` on one arm precedes ``screw1_3`` on another, which also
    has later work (``screw2_*``) that does not depend on the first arm."""
    p = cc.problem
    arms = plan.arms(p)
    pred, succ = p.task_names.index("place_cover1"), p.task_names.index("screw1_3")
    assert pred in p.task_preds[succ] and arms[pred] != arms[succ]
    return p.arm_names[int(arms[pred])], "place_cover1", p.arm_names[int(arms[succ])]


def _doable(cc: Any, plan: Any, r: Any, failed_arm: str) -> list[str]:
    """Tasks that neither are a failed arm's unfinished work (re-solving
    off) nor come after one."""
    p = cc.problem
    arms = plan.arms(p)
    tf = r.tasks_frame().set_index("task")
    lost = {
        x
        for x in range(p.n_tasks)
        if p.arm_names[int(arms[x])] == failed_arm and tf.loc[p.task_names[x], "status"] != "done"
    }
    stack = list(lost)
    while stack:
        x = stack.pop()
        for y in p.task_succs[x]:
            if y not in lost:
                lost.add(y)
                stack.append(y)
    return [p.task_names[x] for x in range(p.n_tasks) if x not in lost]


# ---------------------------------------------------------------- cause 1


def test_an_emergency_stop_reaching_an_arm_at_its_station_is_released(
    scara4: Any, scara4_plan: Any, serial_run: Any
) -> None:
    """On the serial bus an arm stands at a zone border until its grant
    comes (a wake-up); an emergency stop reaches it there just before, and
    the grant comes during the stop. When the stop is cleared (each stop
    matched by its release) the arm must pass: every task completes."""
    wakes = [e for e in serial_run.trace if e.kind == "message" and e.message == "wake_up"]
    assert len(wakes) >= 2
    for w in wakes[:2]:
        r = simulate(
            scara4,
            scara4_plan,
            medium=SERIAL,
            faults=[EmergencyStop(w.time - 0.1, 1.0)],
            options=SimOptions(monitor=False),
        )
        assert _failed(r) == {}, f"e-stop just before the wake-up at {w.time}"
        clears = [e for e in r.trace if e.kind == "message" and e.detail.startswith("alarm_clear")]
        assert len(clears) == scara4.problem.n_arms


# ---------------------------------------------------------------- cause 2


def test_an_activation_exactly_at_a_task_end_releases_every_arm_it_stopped(
    scara4: Any, scara4_plan: Any
) -> None:
    """Ideal medium: a zone activation falls exactly on the end of a task (the
    coordinator still believes the arm busy, the arm is done when the stop
    reaches it). Every stop is matched by a wake-up: all tasks complete."""
    nominal = simulate(scara4, scara4_plan, options=SimOptions(monitor=False)).tasks_frame()
    zones = tuple(scara4.cell.zone_map.zone_names())
    for at in sorted(set(nominal["end"]))[:2]:
        r = simulate(
            scara4,
            scara4_plan,
            faults=[ActivateZones(at, zones)],
            options=SimOptions(monitor=False),
        )
        assert _failed(r) == {}, f"activation at the task end {at}"


# ---------------------------------------------------------------- cause 3


def test_without_re_solving_a_surviving_arm_is_not_stranded_by_a_failed_arm(
    scara4: Any, scara4_plan: Any, serial_run: Any
) -> None:
    """``resolve=False`` on the serial bus: an arm fails in the middle of a
    task whose successor another arm was already sent (it waits at that
    successor's start). The successor can never run, but the surviving arm
    goes on with every task that does not depend on the failed arm."""
    arm, task, other = _handover(scara4, scara4_plan)
    tf = serial_run.tasks_frame().set_index("task")
    s, e = float(tf.loc[task, "start"]), float(tf.loc[task, "end"])
    r = simulate(
        scara4,
        scara4_plan,
        medium=SERIAL,
        faults=[ArmFailure(arm, s + 0.6 * (e - s))],
        options=SimOptions(monitor=False, resolve=False),
    )
    out = r.tasks_frame().set_index("task")
    free = _doable(scara4, scara4_plan, r, arm)
    assert any(out.loc[x, "arm"] == other for x in free), "the other arm has independent work"
    assert (out.loc[free, "status"] == "done").all(), _failed(r)
    assert not any(UNEXPLAINED in c for c in _failed(r).values())


# ---------------------------------------------------------------- cause 4


def test_a_withdrawal_is_not_overtaken_by_the_retransmitted_trajectory(
    scara4: Any, scara4_plan: Any
) -> None:
    """Trajectories are lost often and retransmitted 2 s later. An arm fails
    just after the other arm's trajectory for the failed arm's successor was
    lost, so the re-solve withdraws that task before the retransmission
    arrives. The arm's stream is taken in order: the withdrawal, sent
    later, waits for the retransmitted trajectory and is taken after it, so
    the arm never runs a withdrawn task, and every task a working arm can
    do is done."""
    arm, task, other = _handover(scara4, scara4_plan)
    loss = MessageLoss(0.7, kinds=("trajectory",), timeout=2.0)
    lossy = simulate(
        scara4, scara4_plan, medium=SERIAL, seed=0, faults=[loss], options=SimOptions(monitor=False)
    )
    tf = lossy.tasks_frame().set_index("task")
    s, e = float(tf.loc[task, "start"]), float(tf.loc[task, "end"])
    lost = [
        ev.time
        for ev in lossy.trace
        if ev.kind == "fault" and ev.message == "trajectory" and ev.arm == other and s < ev.time < e
    ]
    assert lost, "a trajectory to the other arm is lost while the task runs"
    names = scara4.problem.task_names
    checked = 0
    for at in lost[:2]:
        r = simulate(
            scara4,
            scara4_plan,
            medium=SERIAL,
            seed=0,
            faults=[loss, ArmFailure(arm, at + 0.01)],
            options=SimOptions(monitor=False),
        )
        assert _failed(r) == {}, at  # the re-solve gives the failed arm's work to others
        mine = [ev for ev in r.trace if ev.arm == other]
        for ev in mine:
            if not (ev.kind == "message" and ev.message == "sleep" and "withdraw" in ev.detail):
                continue
            t = names[int(ev.detail.split()[3])]
            # the withdrawal reached the station while its trajectory was
            # still being sent again: it waited for it, and was taken after it
            late = [
                x.time
                for x in mine
                if x.message == "TRAJECTORY" and x.task == t and x.time > ev.time
            ]
            if not late:
                continue
            ends = [
                x.time
                for x in mine
                if x.message == "trajectory_end" and x.detail == "withdrawn" and x.time >= late[0]
            ]
            assert ends, f"the withdrawn {t!r} was never given back"
            started = [x for x in mine if x.kind == "task_start" and x.task == t]
            assert not [x for x in started if late[0] <= x.time <= ends[0]]
            checked += 1
    assert checked > 0, "a withdrawal waited for its retransmitted trajectory"


# ---------------------------------------------------------------- cause 5


@pytest.mark.parametrize("resolve", [True, False])
def test_a_part_late_from_time_zero_holds_back_its_task(
    cell: Any, plan: Any, resolve: bool
) -> None:
    """A part expected at time 0 comes 5 s late: the tasks it gates start
    after it comes, whether the plan is re-solved or kept."""
    ts = cell.cell.taskset
    arrivals = ts.expected_arrivals()
    part = next(x for x, at in sorted(arrivals.items()) if at == 0.0)
    gated = [t.id for t in ts.tasks if part in ts.gating_parts(t.id)]
    assert gated
    r = simulate(cell, plan, faults=[LatePart(part, 5.0)], options=SimOptions(resolve=resolve))
    tf = r.tasks_frame().set_index("task")
    assert _failed(r) == {}
    assert (tf.loc[gated, "start"] >= 5.0 - 1e-9).all(), tf.loc[gated, "start"]


@pytest.mark.parametrize("resolve", [True, False])
def test_parts_late_at_one_expected_arrival_all_hold_back_their_tasks(
    scara4: Any, scara4_plan: Any, resolve: bool
) -> None:
    """Two parts found late at the same expected arrival (10 s), over
    Ethernet: the first notice re-dispatches tasks; none may go out with its
    start permitted while the second notice of that instant still holds it
    back (``multiarm campaign scara4 --replay 0:69`` found a task started
    before its part: the withdrawal came after the start)."""
    ts = scara4.cell.taskset
    arrivals = ts.expected_arrivals()
    first, second = "seal2", "housing1"
    assert arrivals[first] == arrivals[second] == 10.0
    faults = [LatePart(first, 117.9), LatePart(second, 104.8)]
    r = simulate(
        scara4,
        scara4_plan,
        seed=1756357820,
        faults=faults,
        medium="ethernet",
        options=SimOptions(resolve=resolve, strict=True),
    )
    tf = r.tasks_frame().set_index("task")
    assert _failed(r) == {}
    for f in faults:
        gated = [t.id for t in ts.tasks if f.part in ts.gating_parts(t.id)]
        assert gated
        assert (tf.loc[gated, "start"] >= 10.0 + f.delay - 1e-9).all(), tf.loc[gated, "start"]


@pytest.mark.parametrize("coordination", ["centralized", "distributed"])
def test_late_part_notices_are_typed_records(cell: Any, plan: Any, coordination: str) -> None:
    """The feeder's notice is a frozen ``LateNotice`` (the gated tasks, the
    arrival, the part), read by name by both policies: the trace says what
    the record says, and the gated tasks wait for the arrival it names."""
    import dataclasses
    import math

    from workcell.sim.protocol.messages import LateNotice

    ts = cell.cell.taskset
    arrivals = ts.expected_arrivals()
    part = next(x for x, at in sorted(arrivals.items()) if at > 0.0)
    gated = tuple(i for i, t in enumerate(ts.tasks) if part in ts.gating_parts(t.id))
    notice = LateNotice(gated, float(arrivals[part]) + 4.0, part)
    with pytest.raises(dataclasses.FrozenInstanceError):
        notice.arrival = 0.0  # type: ignore[misc]
    r = simulate(
        cell,
        plan,
        faults=[LatePart(part, 4.0)],
        coordination=coordination,
        options=SimOptions(resolve=False),
    )
    faults = [e for e in r.trace if e.kind == "fault" and e.detail == notice.describe()]
    assert len(faults) == 1 and math.isclose(faults[0].time, float(arrivals[part]))
    tf = r.tasks_frame()
    starts = tf.set_index("task").loc[[cell.problem.task_names[t] for t in gated], "start"]
    assert (starts >= notice.arrival - 1e-9).all()
    never = LateNotice(gated, math.inf, part)
    assert never.describe() == f"part {part!r} is late: never comes"


# ------------------------------------------------- liveness, explained failures


class _LosesGrants(IdealMedium):
    """A broken medium (a test double through the public medium factory):
    grants and wake-ups vanish, neither delivered nor reported dropped."""

    def _transmit(self, frame: Frame) -> None:
        if frame.kind not in ("zone_grant", "wake_up"):
            super()._transmit(frame)


def test_a_stall_is_named_and_strict_runs_raise(scara4: Any, scara4_plan: Any) -> None:
    """An arm that has work, no stop in force and no event pending (here made
    by a medium that loses grants silently) is a stall: its task fails with
    a cause of kind "stall" naming it, and ``strict`` raises InternalError."""
    r = simulate(scara4, scara4_plan, medium=_LosesGrants, options=SimOptions(monitor=False))
    tf = r.tasks_frame()
    stalls = tf[tf["cause_kind"] == "stall"]
    assert len(stalls) > 0
    assert stalls["cause"].str.startswith("stall: arm ").all()
    assert not tf["cause"].str.contains(UNEXPLAINED).any()
    with pytest.raises(InternalError, match="stall"):
        simulate(
            scara4, scara4_plan, medium=_LosesGrants, options=SimOptions(monitor=False, strict=True)
        )


@pytest.mark.parametrize("episode", range(8))
def test_random_fault_plans_end_with_every_failure_explained(
    scara4: Any, scara4_plan: Any, episode: int
) -> None:
    """Seeded random fault plans (1-4 faults of every sampled kind, times over
    the plan and exactly at task starts and ends), over the media, re-solving
    on and off, with ``strict``: no stall, every failed task's cause in
    :data:`CAUSE_KINDS`, and no task failed that a working arm could do
    while re-solving is on."""
    rng = np.random.default_rng(episode)
    p = scara4.problem
    media = ["ideal", "serial-bus", "multibus2", "ethernet"]
    medium = media[episode % len(media)]
    resolve = episode % 2 == 0
    faults = list(
        FaultPlan.sample(
            p.arm_names,
            float(scara4_plan.makespan),
            rng,
            n=int(rng.integers(1, 4)),
            kinds=("crash", "emergency_stop", "message_loss", "arm_failure"),
        )
    )
    edges = sorted(set(scara4_plan.start.tolist()) | set(scara4_plan.end.tolist()))
    at = float(edges[int(rng.integers(len(edges)))])
    faults.append(EmergencyStop(at, float(rng.uniform(0.1, 2.0))))
    r = simulate(
        scara4,
        scara4_plan,
        seed=episode,
        faults=faults,
        medium=medium,
        options=SimOptions(resolve=resolve, monitor=False, strict=True),
    )
    tf = r.tasks_frame()
    failed = tf[tf["status"] == "failed"]
    assert set(failed["cause_kind"]) <= set(CAUSE_KINDS) - {"stall"}, failed["cause"].tolist()
    if resolve:
        assert set(failed["cause_kind"]) <= {"arm_failed", "predecessor"}
