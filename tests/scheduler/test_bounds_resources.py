"""The busy-resources relaxation (scheduler.resource_bound): a bound of the true problem.

Checked against CP-SAT's proven optima of the general model (waits at
borders allowed) on generated problems whose few zones and tools most tasks
need (S2.12 zones, S2.6 waits at their borders), with and without travel
and start zones, and against the makespan of every plan the other solvers
find on larger seeded problems (a blocking oracle on some: detours only
lengthen tasks). These families were not used to choose ``k`` or the unit.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scheduler import lower_bound, solve, validate
from scheduler.generate import random_problem
from scheduler.resource_bound import busiest_resources, busy_resources_bound


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10_000), st.integers(2, 3), st.integers(4, 7), st.booleans())
def test_never_above_the_proven_optimum(seed: int, arms: int, tasks: int, travel: bool) -> None:
    p = random_problem(
        arms,
        tasks,
        2,
        1,
        seed=seed,
        zone_fraction=0.9,
        tool_fraction=0.3,
        setups=seed % 3 != 0,
        start_zones=seed % 2 == 0,
    )
    r = solve(p, "cpsat", time_limit=None, workers=1)
    assert r.status.value == "optimal"
    b, status = busy_resources_bound(p, 20, seed=seed, k=2, workers=1)
    assert status in ("OPTIMAL", "FEASIBLE", "UNKNOWN")
    assert b <= r.objective + 1e-6


@pytest.mark.parametrize("seed", range(4))
def test_never_above_a_plan_on_larger_problems(seed: int) -> None:
    p = random_problem(
        4, 24, 3, 1, seed=seed, zone_fraction=0.8, start_zones=True, blocking=seed % 2 == 1
    )
    b, _ = busy_resources_bound(p, 3, seed=seed, k=3, workers=1, travel=seed % 2 == 0)
    for solver in ("greedy", "tree"):
        r = solve(p, solver, time_limit=None if solver == "greedy" else 1.0, seed=seed)
        assert validate(p, r.schedule) >= b - 1e-6


def test_sees_what_one_resource_at_a_time_does_not() -> None:
    """Three arms, seven tasks, two zones and a tool that most of them need: the
    relaxation, solved to its optimum, is far above every cheap bound (each
    looks at the arms or at one resource at a time) and below the optimum."""
    p = random_problem(3, 7, 2, 1, seed=5, zone_fraction=0.9, tool_fraction=0.3)
    opt = solve(p, "cpsat", time_limit=None, workers=1)
    assert opt.status.value == "optimal"
    assert busiest_resources(p, 6) == busiest_resources(p, 2)  # both zones' resources kept
    bound, status = busy_resources_bound(p, 20, workers=1)
    assert status == "OPTIMAL"
    assert lower_bound(p) + 3.0 <= bound <= opt.objective + 1e-6
