"""The tree search's worker processes on a problem with a blocking oracle
(TreeOptions.relaxed_workers): they search the problem without the oracle,
and each plan they return is checked against it, kept where no parked arm is
in its way, else decoded again with the detours."""

from __future__ import annotations

import numpy as np
import pytest

from multiarm.errors import UsageError
from scheduler import solve, validate
from scheduler.generate import random_problem
from scheduler.problem import Problem
from scheduler.result import SearchStats
from scheduler.schedule import ScheduleError
from scheduler.search import Evaluator
from scheduler.tree import TreeOptions, _checked_against_oracle, _member_problem


def _blocking(seed: int) -> Problem:
    return random_problem(3, 12, 3, 1, seed=seed, blocking=True, start_zones=True)


def test_the_workers_search_the_problem_without_its_oracle() -> None:
    p = _blocking(6)
    q = _member_problem(p, TreeOptions())
    assert p.blocking is not None and q.blocking is None
    assert q.n_tasks == p.n_tasks and q.n_windows == p.n_windows
    assert np.array_equal(q.mode_duration, p.mode_duration)
    assert _member_problem(p, TreeOptions(relaxed_workers=False)) is p
    plain = random_problem(3, 12, 3, 1, seed=6)
    assert _member_problem(plain, TreeOptions()) is plain


@pytest.mark.parametrize("seed", [6, 7, 11])
def test_a_plan_a_parked_arm_meets_is_decoded_again_with_the_detours(seed: int) -> None:
    p = _blocking(seed)
    plan = solve(_member_problem(p, TreeOptions()), "greedy", seed=0).schedule
    assert plan is not None
    with pytest.raises(ScheduleError, match="parked in its way"):
        validate(p, plan)
    ev = Evaluator(p)
    stats = SearchStats()
    sol, kept = _checked_against_oracle(p, ev, plan, stats)
    assert sol is not None and sol.state is not None and kept is None
    assert stats.extra["worker_plan"] == "decoded again with the oracle"
    sched = ev.schedule(sol)
    assert validate(p, sched) == pytest.approx(sol.makespan)
    assert (sched.mode == plan.mode).all()  # the plan's modes, detours added
    assert sched.blocking.sum() > 0


def test_a_plan_no_parked_arm_meets_is_kept_as_it_is() -> None:
    p = _blocking(0)
    plan = solve(_member_problem(p, TreeOptions()), "greedy", seed=0).schedule
    assert plan is not None
    mk = validate(p, plan)
    stats = SearchStats()
    sol, kept = _checked_against_oracle(p, Evaluator(p), plan, stats)
    assert sol is not None and sol.makespan == mk and sol.state is None
    assert stats.extra["worker_plan"] == "valid with the oracle"
    assert kept is plan  # _finish returns the plan itself (no decoder state)


@pytest.mark.parametrize("relaxed", [True, False])
def test_the_portfolio_returns_a_valid_plan_either_way(relaxed: bool) -> None:
    p = _blocking(7)
    r = solve(
        p, "tree", time_limit=1.5, seed=0, options=TreeOptions(workers=2, relaxed_workers=relaxed)
    )
    assert r.schedule is not None
    assert validate(p, r.schedule) == pytest.approx(r.objective)


def test_relaxed_workers_must_be_a_bool() -> None:
    with pytest.raises(UsageError, match="relaxed_workers must be True or False"):
        TreeOptions(relaxed_workers=1)  # type: ignore[arg-type]
