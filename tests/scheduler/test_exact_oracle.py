"""An idle blocking oracle (S2.6) can be dropped without changing the problem.

``scheduler.exact.oracle_binding`` asks the oracle every question a schedule
can raise; when all answers are 0, ``without_idle_oracle`` drops it. Seeded
campaigns over small generated problems check that this is exact: every
schedule has the same makespan under both problems, and the exact branch and
bound on the problem without the oracle is never above a schedule of the
problem with it (its optimum is one of the true problem).
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from scheduler import Problem, solve, validate
from scheduler.exact import branch_and_bound, oracle_binding, without_idle_oracle
from scheduler.generate import GridBlocking, random_problem


def _with_oracle(seed: int, cost: float) -> Problem:
    p = random_problem(
        n_arms=2 + seed % 2,
        n_tasks=4 + seed % 3,
        n_zones=1 + seed % 2,
        n_tools=seed % 2,
        seed=seed,
        setups=seed % 3 != 2,
        blocking=True,
        zone_fraction=0.9,
    )
    assert isinstance(p.blocking, GridBlocking)
    return replace(p, blocking=replace(p.blocking, cost_s=cost))


@pytest.mark.parametrize("seed", range(6))
def test_an_idle_oracle_is_dropped_and_changes_nothing(seed: int) -> None:
    p = _with_oracle(seed, 0.0)
    assert oracle_binding(p) is False
    free = without_idle_oracle(p)
    assert free.blocking is None and free.n_modes == p.n_modes
    for solver in ("greedy", "tree"):
        for q in (p, free):
            s = solve(q, solver, time_limit=0.5, seed=seed).schedule
            assert s is not None
            assert validate(p, s) == validate(free, s)
    # the exact optimum without the oracle is a schedule, and a bound, of the problem with it
    tree = solve(p, "tree", time_limit=0.5, seed=seed)
    res = branch_and_bound(free, deadline=math.inf)
    assert res.complete and res.schedule is not None
    assert validate(p, res.schedule) == pytest.approx(res.makespan)
    assert res.makespan <= tree.objective + 1e-6


@pytest.mark.parametrize("seed", range(6))
def test_a_charging_oracle_is_kept(seed: int) -> None:
    p = _with_oracle(seed, 3.0)
    asked = [
        p.blocking.cost(m, b, pose)  # type: ignore[union-attr]
        for m in range(p.n_modes)
        for b in range(p.n_arms)
        if b != p.mode_arm[m]
        for pose in [-1, *range(p.n_tasks)]
        if pose < 0 or p.mode_of[b, pose] >= 0
    ]
    assert oracle_binding(p) is any(c > 0 for c in asked)
    if oracle_binding(p):
        assert without_idle_oracle(p) is p


def test_no_oracle_and_too_many_questions() -> None:
    p = _with_oracle(0, 0.0)
    assert oracle_binding(replace(p, blocking=None)) is False
    assert oracle_binding(p, max_queries=1) is None
    assert without_idle_oracle(p, max_queries=1) is p
