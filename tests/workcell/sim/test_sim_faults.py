"""Faults in the simulated cell: described as data, seeded, nothing lost (S1.2, S1.6, S2.7)."""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import UsageError, ValidationError
from scheduler import solve
from workcell import compile_cell, load_example
from workcell.sim import (
    ArmFailure,
    Crash,
    EmergencyStop,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
    SimOptions,
    simulate,
)


def _nothing_lost(r: Any, n: int) -> None:
    tf = r.tasks_frame()
    assert len(tf) == n
    assert set(tf["status"]) <= {"done", "failed"}
    assert (tf.loc[tf["status"] == "failed", "cause"] != "").all()
    assert (tf.loc[tf["status"] == "done", "cause"] == "").all()


def test_arm_failure_reassigns_its_tasks_by_a_resolve(cell: Any, plan: Any) -> None:
    p = cell.problem
    r = simulate(cell, plan, faults=[ArmFailure("right", 20.0)])
    _nothing_lost(r, p.n_tasks)
    assert r.metrics.resolves >= 1 and len(r.metrics.resolve_latency) == r.metrics.resolves
    tf = r.tasks_frame()
    moved = tf[(tf["status"] == "done") & (tf["arm"] == "left") & (tf["start"] > 20.0)]
    planned_right = {p.task_names[t] for t in range(p.n_tasks) if plan.arms(p)[t] == 1}
    assert planned_right & set(moved["task"])  # some of the right arm's work went left
    assert not ((tf["arm"] == "right") & (tf["start"] > 20.0)).any()


def _mid_tool_task(cc: Any, plan: Any) -> tuple[str, str, float]:
    """(arm, task, time) in the middle of the first task that uses a tool on
    an arm and that another arm could also do."""
    p = cc.problem
    arms = plan.arms(p)
    for t in sorted(range(p.n_tasks), key=lambda t: float(plan.start[t])):
        m = int(plan.mode[t])
        a = int(arms[t])
        if p.mode_tools[m] and any(int(p.mode_arm[n]) != a for n in p.task_modes[t]):
            at = float(plan.start[t]) + 0.3 * float(plan.end[t] - plan.start[t])
            return p.arm_names[a], p.task_names[t], round(at, 3)
    raise AssertionError("no tool task another arm could do")


@pytest.mark.parametrize("name", ["supersigma", "scara4"])
def test_a_failed_arm_gives_its_tools_back_before_another_takes_them(
    name: str, cell: Any, plan: Any, scara4: Any, scara4_plan: Any
) -> None:
    """An arm fails while holding a tool (supersigma's screwdriver, scara4's
    press or screwdriver): it is retracted and gives the tool back at once,
    the interrupted task is done by another arm after that, and no two arms
    ever hold one tool (the safety monitor, on, would raise)."""
    cc, sched = (cell, plan) if name == "supersigma" else (scara4, scara4_plan)
    arm, task, at = _mid_tool_task(cc, sched)
    r = simulate(cc, sched, faults=[ArmFailure(arm, at)])  # monitor on
    _nothing_lost(r, cc.problem.n_tasks)
    tf = r.tasks_frame().set_index("task")
    assert tf.loc[task, "status"] == "done" and tf.loc[task, "arm"] != arm
    assert tf.loc[task, "start"] >= at
    tools = r.reservations_frame()
    tools = tools[tools["kind"] == "tool"].sort_values("start")
    failed_use = tools[(tools["arm"] == arm) & (tools["task"] == task)]
    assert len(failed_use) == 1 and failed_use["end"].iloc[0] == pytest.approx(at)
    for _tool, uses in tools.groupby("resource"):
        starts, ends = uses["start"].to_numpy(), uses["end"].to_numpy()
        assert (starts[1:] >= ends[:-1] - 1e-9).all()


def test_without_re_solving_the_plan_is_kept(cell: Any, plan: Any) -> None:
    """``resolve=False``: no re-solve; a failed arm's remaining tasks fail
    with that cause (re-solving gives them to the other arm), a late part
    only pushes back the tasks it gates."""
    p = cell.problem
    arm, _task, at = _mid_tool_task(cell, plan)
    kept = simulate(cell, plan, faults=[ArmFailure(arm, at)], options=SimOptions(resolve=False))
    _nothing_lost(kept, p.n_tasks)
    assert kept.metrics.resolves == 0 and len(kept.metrics.resolve_latency) == 0
    assert [e.detail for e in kept.trace if e.kind == "resolve"] == [
        f"arm {arm!r} failed: re-solving off; plan kept"
    ]
    tf = kept.tasks_frame()
    lost = tf[tf["status"] == "failed"]
    a = p.arm_names.index(arm)
    mine = {p.task_names[t] for t in range(p.n_tasks) if plan.arms(p)[t] == a}
    assert (lost["arm"] == arm).any() and set(lost.loc[lost["arm"] == arm, "task"]) <= mine
    assert (lost.loc[lost["arm"] == arm, "cause"].str.contains("re-solving off")).all()
    # the others go on with the rest of the plan: only the failed arm's tasks
    # and the tasks after them are lost
    assert lost["cause"].str.contains("re-solving off").all()
    redone = simulate(cell, plan, faults=[ArmFailure(arm, at)])
    assert redone.metrics.resolves == 1
    assert redone.metrics.failed_tasks < kept.metrics.failed_tasks
    late = simulate(cell, plan, faults=[LatePart("pin", 30.0)], options=SimOptions(resolve=False))
    assert late.metrics.resolves == 0 and late.metrics.done_tasks == p.n_tasks
    assert late.tasks_frame().set_index("task").loc["insert_pin", "start"] >= 2.0 + 30.0
    with pytest.raises(UsageError, match="resolve must be True or False"):
        simulate(cell, plan, options=SimOptions(resolve="no"))  # type: ignore[arg-type]


def _lost_wrongly(r: Any, p: Any, failed_arm: int) -> list[str]:
    """Failed tasks that a working arm could do and whose predecessors could all run."""
    status = dict(zip(r.tasks_frame()["task"], r.tasks_frame()["status"], strict=True))
    dead: dict[int, bool] = {}
    for t in p.topological_order:
        dead[t] = status[p.task_names[t]] != "done" and (
            all(int(p.mode_arm[m]) == failed_arm for m in p.task_modes[t])
            or any(dead[q] for q in p.task_preds[t])
        )
    return [
        p.task_names[t]
        for t in range(p.n_tasks)
        if status[p.task_names[t]] == "failed" and not dead[t]
    ]


def test_a_failed_arm_whose_tasks_others_can_do_loses_nothing(
    scara4: Any, scara4_plan: Any
) -> None:
    """Every task has a working arm: after the failure the re-solve
    reassigns the failed arm's tasks (the arm goes to the scheduler as out
    of service, ``tests/workcell/sim/test_reschedule.py``) and nothing fails."""
    p = scara4.problem
    r = simulate(scara4, scara4_plan, faults=[ArmFailure("sw", 0.3 * scara4_plan.makespan)])
    assert r.metrics.resolves == 1
    assert r.metrics.failed_tasks == 0
    late = r.tasks_frame()
    after = late[late["start"] > 0.3 * scara4_plan.makespan]
    assert len(after) and (after["arm"] != "sw").all()
    assert r.metrics.done_tasks == p.n_tasks


def test_a_re_solve_never_drops_a_task_a_working_arm_can_do(cell: Any, plan: Any) -> None:
    """Some tasks only the failed arm can do (they fail, with their
    successors, each with its cause); every other task runs."""
    p = cell.problem
    left = p.arm_names.index("left")
    r = simulate(
        cell,
        plan,
        faults=[ArmFailure("left", 0.2 * plan.makespan)],
        options=SimOptions(monitor=False),
    )
    assert r.metrics.failed_tasks > 0
    assert _lost_wrongly(r, p, left) == []
    causes = set(r.tasks_frame()["cause"]) - {""}
    assert all("every" in c and "failed" in c for c in causes), causes


def test_tasks_frame_takes_each_row_from_one_plan(cell: Any, plan: Any) -> None:
    """After re-solves, every row's planned times and arm come from the plan
    named in its ``plan`` column (no sentinel time: dropped tasks keep the
    times of the last plan that planned them to run); a task interrupted by
    its arm's failure keeps its start."""
    p = cell.problem
    at = 0.2 * plan.makespan
    r = simulate(cell, plan, faults=[ArmFailure("left", at)], options=SimOptions(monitor=False))
    tf = r.tasks_frame()
    assert r.metrics.resolves == 1 and set(tf["plan"]) <= {0, 1} and (tf["plan"] == 1).any()
    last = r.plan.schedule
    for row in tf[tf["plan"] == 1].itertuples():
        t = p.task_names.index(row.task)
        assert (row.planned_start, row.planned_end) == (float(last.start[t]), float(last.end[t]))
        if row.status == "failed":
            assert row.arm == p.arm_names[int(last.arms(p)[t])]
    for row in tf[tf["plan"] == 0].itertuples():
        t = p.task_names.index(row.task)
        assert (row.planned_start, row.planned_end) == (float(plan.start[t]), float(plan.end[t]))
    assert (tf["planned_end"] < 10 * plan.makespan).all()
    interrupted = [e.task for e in r.trace if e.kind == "task_failed" and "interrupted" in e.detail]
    failed = tf.set_index("task")
    for task in interrupted:
        if failed.loc[task, "status"] == "failed":
            assert failed.loc[task, "start"] <= at


def test_crash_is_a_reflex_stop_told_afterwards(cell: Any, plan: Any) -> None:
    r = simulate(cell, plan, faults=[Crash("left", 3.0, 2.0)])
    msgs = [(e.time, e.message) for e in r.trace if e.kind == "message" and e.arm == "left"]
    stop_d = [t for t, m in msgs if m == "STOP_D"]
    alarm = [t for t, m in msgs if m == "alarm"]
    assert stop_d and alarm and alarm[0] >= stop_d[0]
    assert r.metrics.done_tasks == cell.problem.n_tasks


def test_lost_synchronism_is_silent_until_homing(cell: Any, plan: Any) -> None:
    r = simulate(cell, plan, faults=[LostSync("right", 0, 3.0, steps=80)])
    faults = [e for e in r.trace if e.kind == "fault" and e.arm == "right"]
    assert "lost 80 steps" in faults[0].detail
    homing = [e for e in faults if "homing" in e.detail]
    assert len(homing) == 1 and homing[0].delay > 0
    assert r.metrics.done_tasks == cell.problem.n_tasks


def test_servo_axes_do_not_lose_synchronism(scara4: Any, scara4_plan: Any) -> None:
    cc, sched = scara4, scara4_plan
    with pytest.raises(ValidationError, match=r"servo joint; only stepper axes"):
        simulate(cc, sched, faults=[LostSync("sw", 0, 1.0)])


def test_lost_messages_are_sent_again(cell: Any, plan: Any) -> None:
    r = simulate(cell, plan, faults=[MessageLoss(0.3, timeout=0.01)], seed=2)
    lost = [e for e in r.trace if e.kind == "fault" and "lost" in e.detail]
    assert len(lost) == r.metrics.retransmissions > 0
    assert r.metrics.done_tasks == cell.problem.n_tasks


def test_late_part_postpones_its_tasks_and_resolves(cell: Any, plan: Any) -> None:
    r = simulate(cell, plan, faults=[LatePart("pin", 30.0)])
    tf = r.tasks_frame().set_index("task")
    assert tf.loc["insert_pin", "start"] >= 2.0 + 30.0
    assert r.metrics.resolves == 1
    assert r.metrics.done_tasks == cell.problem.n_tasks


def test_a_part_that_never_comes_fails_its_tasks_with_the_cause(cell: Any, plan: Any) -> None:
    r = simulate(cell, plan, faults=[LatePart("pin", math.inf)])
    tf = r.tasks_frame().set_index("task")
    _nothing_lost(r, cell.problem.n_tasks)
    assert tf.loc["insert_pin", "status"] == "failed"
    assert "pin" in tf.loc["insert_pin", "cause"]
    assert tf.loc["screw_cap", "status"] == "failed"  # after insert_pin
    assert tf.loc["scan_board", "status"] == "done"  # independent of the pin


def test_emergency_stop_holds_every_arm(cell: Any, plan: Any) -> None:
    base = simulate(cell, plan, options=SimOptions(monitor=False))
    r = simulate(cell, plan, faults=[EmergencyStop(5.0, 3.0)], options=SimOptions(monitor=False))
    alarms = [e for e in r.trace if e.kind == "message" and e.message == "alarm"]
    assert {e.dst for e in alarms} == {1, 2}
    assert r.metrics.executed_makespan >= base.metrics.executed_makespan


def test_fault_records_are_checked() -> None:
    with pytest.raises(ValidationError, match=r"faults\[0\]\.kind: unknown fault kind 'meteor'"):
        FaultPlan.from_dicts([{"kind": "meteor"}])
    with pytest.raises(
        ValidationError, match=r"faults\[0\]: unknown field 'when' of a crash record"
    ):
        FaultPlan.from_dicts([{"kind": "crash", "arm": "a", "at": 1, "when": 2}])
    with pytest.raises(ValidationError, match=r"^faults\[0\]\.at: must"):
        FaultPlan.from_dicts([{"kind": "arm_failure", "arm": "a", "at": -1}])
    with pytest.raises(ValidationError, match=r"^MessageLoss\.probability: must be in"):
        MessageLoss(1.5)
    with pytest.raises(ValidationError, match=r"^LatePart\.delay: must be > 0"):
        LatePart("pin", 0.0)
    with pytest.raises(ValidationError, match=r"faults\[1\]: expected a fault record"):
        FaultPlan([Crash("a", 1.0), "boom"])  # type: ignore[list-item]
    plan = FaultPlan([Crash("a", 1.0), MessageLoss(0.1, ("trajectory",))])
    assert FaultPlan.from_dicts(plan.to_dicts()) == plan


def test_sampled_fault_plans_are_valid_plans(cell: Any, plan: Any) -> None:
    """A sampled plan holds at most one arm failure and one message-loss
    record (simulate refuses a second one): seed 5 drew three before."""
    for seed in range(60):
        faults = FaultPlan.sample(cell.problem.arm_names, plan.makespan, seed, n=3)
        assert sum(isinstance(f, MessageLoss) for f in faults) <= 1, seed
        assert sum(isinstance(f, ArmFailure) for f in faults) <= 1, seed
    r = simulate(cell, plan, faults=FaultPlan.sample(cell.problem.arm_names, 100.0, 5, n=3))
    _nothing_lost(r, cell.problem.n_tasks)


@settings(max_examples=3, deadline=None)
@given(seed=st.integers(0, 2**16), n=st.integers(1, 3))
def test_random_fault_plans_are_safe_and_lose_nothing(seed: int, n: int) -> None:
    """Hypothesis over seeded random fault plans (crashes, emergency stops,
    message loss, an arm failure): the monitor never fires on a
    coordinator-driven run, every task ends done or failed with a cause, and
    the same seed gives the same trace."""
    cc = _CELL.get("cc") or _CELL.setdefault("cc", compile_cell(load_example("supersigma")))
    sched = _CELL.get("plan") or _CELL.setdefault(
        "plan", solve(cc.problem, "greedy", seed=0).schedule
    )
    faults = FaultPlan.sample(cc.problem.arm_names, sched.makespan, seed, n=n)
    r = simulate(cc, sched, faults=faults, seed=seed)  # monitor on: raises if unsafe
    _nothing_lost(r, cc.problem.n_tasks)
    if seed % 2 == 0:
        again = simulate(cc, sched, faults=faults, seed=seed, options=SimOptions(monitor=False))
        assert again.trace.to_json() == r.trace.to_json()


_CELL: dict[str, Any] = {}
