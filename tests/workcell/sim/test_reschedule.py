"""Re-solving belongs to the scheduler: ``scheduler.reschedule`` takes what the
coordinator knows (tasks done and running, frozen with their times; tasks
failed; arms out; parts late) and returns a new plan and the tasks dropped
(SEEDS.md S2.11-S2.12). Checked through its public records, on the built-in
cells' greedy plans."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import UsageError, ValidationError
from scheduler import FrozenTask, Rescheduled, reschedule, validate


def _frozen_before(p: Any, plan: Any, now: float) -> dict[int, FrozenTask]:
    """The tasks the plan ends by ``now`` (a prefix closed under predecessors)."""
    out: dict[int, FrozenTask] = {}
    for t in p.topological_order:
        if float(plan.end[t]) <= now and all(q in out for q in p.task_preds[t]):
            out[t] = FrozenTask(
                int(plan.mode[t]),
                float(plan.start[t]),
                float(plan.end[t]),
                tuple(plan.waits[t].tolist()),
            )
    return out


def _only_on(p: Any, arm: int, done: Any = ()) -> set[int]:
    """Tasks not done that no other arm can do, and every task after them."""
    out: set[int] = set()
    for t in p.topological_order:
        if t in done:
            continue
        if all(int(p.mode_arm[m]) == arm for m in p.task_modes[t]) or any(
            q in out for q in p.task_preds[t]
        ):
            out.add(t)
    return out


def test_an_arm_out_gets_no_task_and_the_done_tasks_stay(scara4: Any, scara4_plan: Any) -> None:
    p, plan = scara4.problem, scara4_plan
    out = p.arm_names.index("sw")
    now = 0.3 * plan.makespan
    done = _frozen_before(p, plan, now)
    r = reschedule(p, now=now, previous=plan, done=done, arms_out={out})
    assert isinstance(r, Rescheduled) and r.schedule is not None and r.reason == ""
    assert r.dropped == frozenset(_only_on(p, out, done)) == frozenset()
    s = r.schedule
    for t in range(p.n_tasks):
        if t in done:
            f = done[t]
            assert (int(s.mode[t]), float(s.start[t]), float(s.end[t])) == (f.mode, f.start, f.end)
        else:
            assert int(s.arms(p)[t]) != out
            assert float(s.start[t]) >= now - 1e-9
    assert validate(p, s) == pytest.approx(r.makespan)
    assert r.latency >= 0.0


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), share=st.floats(0.05, 0.35))
def test_dropped_tasks_come_after_every_task_that_runs(
    cell: Any, plan: Any, seed: int, share: float
) -> None:
    """The tasks only the arm out could do (and those after them) are
    dropped; every other task is planned, before any dropped one, on a
    working arm; the same inputs and seed give the same plan."""
    p = cell.problem
    out = p.arm_names.index("left")
    now = share * plan.makespan
    done = _frozen_before(p, plan, now)
    kw: dict[str, Any] = {"now": now, "previous": plan, "done": done, "arms_out": {out}}
    r = reschedule(p, seed=seed, evaluations=50, **kw)
    assert r.schedule is not None
    expected = _only_on(p, out, done)
    assert r.dropped == frozenset(expected)
    live = [t for t in range(p.n_tasks) if t not in r.dropped]
    s = r.schedule
    if r.dropped:
        assert max(float(s.start[t]) for t in live) < min(float(s.start[t]) for t in r.dropped)
    assert all(int(s.arms(p)[t]) != out for t in live if t not in done)
    assert r.makespan == max(float(s.end[t]) for t in live)
    again = reschedule(p, seed=seed, evaluations=50, **kw)
    assert again.schedule is not None
    assert np.array_equal(again.schedule.start, s.start)
    assert np.array_equal(again.schedule.mode, s.mode)


def test_a_late_part_holds_back_its_task_and_a_missing_one_drops_it(cell: Any, plan: Any) -> None:
    p = cell.problem
    t = p.task_names.index("insert_pin")
    r = reschedule(p, now=0.0, previous=plan, parts_late={t: 40.0})
    assert r.schedule is not None and not r.dropped
    assert float(r.schedule.start[t]) >= 40.0
    never = reschedule(p, now=0.0, previous=plan, parts_late={t: math.inf})
    after = {t}
    for x in p.topological_order:
        if any(q in after for q in p.task_preds[x]):
            after.add(x)
    assert never.dropped == frozenset(after)
    failed = reschedule(p, now=0.0, previous=plan, failed={t})
    assert failed.dropped == never.dropped


def test_a_running_task_is_kept_exactly(cell: Any, plan: Any) -> None:
    p = cell.problem
    first = int(np.argmin(plan.start))
    run = FrozenTask(int(plan.mode[first]), float(plan.start[first]), float(plan.end[first]) + 3)
    r = reschedule(p, now=float(plan.start[first]) + 0.1, previous=plan, running={first: run})
    assert r.schedule is not None
    assert float(r.schedule.end[first]) == run.end and int(r.schedule.mode[first]) == run.mode


def test_bad_input_names_the_culprit(cell: Any, plan: Any) -> None:
    p = cell.problem
    with pytest.raises(UsageError, match="task 999 is not a task"):
        reschedule(p, now=0.0, previous=plan, failed={999})
    with pytest.raises(UsageError, match="arm 7 is not an arm"):
        reschedule(p, now=0.0, previous=plan, arms_out={7})
    with pytest.raises(ValidationError, match="FrozenTask"):
        FrozenTask(0, 5.0, 1.0)
