"""Online re-solving from a state of the cell: frozen prefix kept, failures and late parts honoured."""

from __future__ import annotations

import numpy as np
import pytest

from multiarm.errors import UsageError
from scheduler import solve, validate
from scheduler.generate import random_problem
from scheduler.online import CellState, reschedule


def plan_and_state(seed: int = 3, now: float = 15.0):  # type: ignore[no-untyped-def]
    p = random_problem(4, 40, 4, 2, seed=seed)
    plan = solve(p, "greedy").schedule
    assert plan is not None
    done = {
        t: (int(plan.mode[t]), float(plan.start[t]), float(plan.end[t]), plan.waits[t].tolist())
        for t in range(p.n_tasks)
        if plan.start[t] < now
    }
    return p, plan, done


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_frozen_prefix_is_kept_and_the_rest_starts_after_now(seed: int) -> None:
    p, plan, done = plan_and_state(seed)
    state = CellState(time=15.0, done=done)
    r = reschedule(p, state, plan, time_limit=30.0, max_evaluations=200)
    s = r.schedule
    assert s is not None and validate(p, s) == r.objective
    for t, (m, start, end, _w) in done.items():
        assert (s.mode[t], s.start[t], s.end[t]) == (m, start, end)
    rest = [t for t in range(p.n_tasks) if t not in done]
    assert np.all(s.start[rest] >= 15.0 - 1e-9)
    # nothing departed from the plan, so the plan is still valid: the re-solve,
    # warm-started from it, never returns anything longer
    assert r.objective <= validate(p, plan) + 1e-9


def test_failed_arm_gets_no_new_task_and_late_parts_wait() -> None:
    p, plan, done = plan_and_state()
    rest = [t for t in range(p.n_tasks) if t not in done]
    # fail an arm that still has work in the plan
    arms = plan.arms(p)
    busy = [
        a
        for a in range(p.n_arms)
        if any(arms[t] == a for t in rest)
        and all(any(p.mode_arm[m] != a for m in p.task_modes[t]) for t in rest)
    ]
    failed = busy[0]
    late = rest[0]
    state = CellState(
        time=15.0,
        done=done,
        failed_arms={p.arm_names[failed]},
        releases={p.task_names[late]: 60.0},
        arm_busy_until={(failed + 1) % p.n_arms: 30.0},
    )
    r = reschedule(p, state, plan, time_limit=30.0, max_evaluations=100)
    s = r.schedule
    assert s is not None
    new_arms = s.arms(p)[rest]
    assert failed not in new_arms.tolist()
    assert s.start[late] >= 60.0
    other = (failed + 1) % p.n_arms
    assert all(s.start[t] >= 30.0 for t in rest if s.arms(p)[t] == other)


def test_same_seed_same_plan() -> None:
    p, plan, done = plan_and_state(seed=4)
    state = CellState(time=10.0, done=done)
    # a work limit instead of a time limit makes the result depend on the seed only
    a = reschedule(p, state, plan, time_limit=30.0, seed=1, max_evaluations=300)
    b = reschedule(p, state, plan, time_limit=30.0, seed=1, max_evaluations=300)
    assert a.schedule == b.schedule


def test_a_release_override_never_advances_a_task() -> None:
    p, plan, done = plan_and_state()
    rest = [t for t in range(p.n_tasks) if t not in done]
    late = max(rest, key=lambda t: p.task_release[t])
    early = float(p.task_release[late]) - 5.0
    r = reschedule(
        p,
        CellState(time=15.0, done=done, releases={late: early}),
        plan,
        time_limit=30.0,
        max_evaluations=100,
    )
    assert r.schedule is not None and r.schedule.start[late] >= p.task_release[late]


def test_without_a_previous_plan() -> None:
    p, _plan, done = plan_and_state()
    r = reschedule(p, CellState(time=15.0, done=done), None, time_limit=30.0, max_evaluations=100)
    assert r.schedule is not None and validate(p, r.schedule) == r.objective


def test_bad_states() -> None:
    p, _plan, done = plan_and_state()
    with pytest.raises(UsageError, match="unknown task 'nope'"):
        reschedule(p, CellState(time=1.0, releases={"nope": 3.0}))
    with pytest.raises(UsageError, match="unknown arm 'robo'"):
        reschedule(p, CellState(time=1.0, failed_arms={"robo"}))
    t = next(iter(done))
    with pytest.raises(UsageError, match="is not one of its modes"):
        reschedule(
            p,
            CellState(time=1.0, done={t: (p.n_modes - 1 if p.mode_task[-1] != t else 0, 0.0, 1.0)}),
        )
    succ = next((s for s in range(p.n_tasks) if p.task_preds[s]), None)
    assert succ is not None
    m = p.task_modes[succ][0]
    with pytest.raises(UsageError, match="but its predecessor"):
        reschedule(p, CellState(time=1.0, done={succ: (m, 0.0, 1.0)}))
