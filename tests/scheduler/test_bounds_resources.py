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

from scheduler import Model, Problem, Schedule, Window, lower_bound, solve, validate
from scheduler.generate import random_problem
from scheduler.resource_bound import busiest_resources, busy_resources_bound, busy_resources_model


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
    bound, status = busy_resources_bound(p, None, workers=1)
    assert status == "OPTIMAL"
    assert lower_bound(p) + 3.0 <= bound <= opt.objective + 1e-6


def _image_is_a_solution(p: Problem, s: Schedule, k: int, unit: float) -> bool:
    """Fix the relaxation's starts, ends and modes to a valid schedule's (rounded down):
    CP-SAT must find the windows a place."""
    import math

    from ortools.sat.python import cp_model

    mdl, v = busy_resources_model(p, float(s.end.max()), busiest_resources(p, k), unit)
    for t in range(p.n_tasks):
        mdl.add(v["S"][t] == math.floor(float(s.start[t]) / unit + 1e-9))
        mdl.add(v["E"][t] == math.floor(float(s.end[t]) / unit + 1e-9))
        mdl.add(v["X"][int(s.mode[t])] == 1)
    solver = cp_model.CpSolver()
    solver.parameters.num_workers = 1
    solver.parameters.max_time_in_seconds = 30
    return solver.solve(mdl) in (cp_model.OPTIMAL, cp_model.FEASIBLE)


@pytest.mark.parametrize("seed", range(12))
def test_every_plan_with_waits_is_a_solution(seed: int) -> None:
    """The image of a valid schedule that waits at borders (inside windows, also
    inside a shared zone's move window, where the arm stands still and another
    may move) is a solution of the relaxation."""
    p = random_problem(3, 12, 2, 1, seed=seed, zone_fraction=1.0, setups=False)
    s = solve(p, "greedy", seed=seed).schedule
    assert s is not None and validate(p, s) > 0
    assert _image_is_a_solution(p, s, 4, 0.01)


def test_a_wait_inside_a_move_window_lets_another_arm_move() -> None:
    """Regression: arm a moves in shared zone z during [0, 4] of its task and stands
    still 10 s at the border at 2 (zone y starts there) while arm b moves in z
    for 10 s. Valid (a standing arm does not move); its image must be a solution
    (a move window is one interval per stretch between borders, not one)."""
    m = Model()
    a, b = m.add_arm("a"), m.add_arm("b")
    z, y = m.add_zone("z", "shared"), m.add_zone("y")
    ta, tb = m.add_task("ta"), m.add_task("tb")
    m.add_mode(
        ta, a, 4.0, windows=[Window(z, 0.0, 4.0), Window(z, 0.0, 4.0, "move"), Window(y, 2.0, 3.0)]
    )
    m.add_mode(tb, b, 10.0, windows=[Window(z, 0.0, 10.0), Window(z, 0.0, 10.0, "move")])
    p = m.build()
    s = Schedule.from_starts(p, [0, 1], [0.0, 2.0], waits=[[10.0], []])
    assert validate(p, s) == 14.0
    assert _image_is_a_solution(p, s, 4, 0.01)


@pytest.mark.parametrize(("k", "unit"), [(-1, 0.01), (2.5, 0.01), (2, 0.0), (2, float("nan"))])
def test_bad_arguments_name_themselves(k: object, unit: object) -> None:
    from multiarm.errors import UsageError

    p = random_problem(2, 4, 2, 1, seed=0)
    with pytest.raises(UsageError, match="k must be" if unit == 0.01 else "unit must be"):
        busy_resources_bound(p, 1, k=k, unit=unit, workers=1)  # type: ignore[arg-type]
