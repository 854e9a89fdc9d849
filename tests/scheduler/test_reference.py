"""The no-wait reference and the zone-free bound (scheduler.reference, S2.6, S2.12).

Seeded campaigns over small generated zone problems (arms, zones, tools,
setups, start zones and blocking varied): every schedule validates, no bound
ever exceeds a known feasible makespan, and the no-wait optimum is never above
a schedule without waits from the tree search. Data with an exact unit and data
with none (rounded outwards for schedules, inwards for bounds) are both tried.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from scheduler import Problem, lower_bound, solve, validate
from scheduler.generate import random_problem
from scheduler.io import problem_from_dict
from scheduler.reference import nowait_model, relaxation_bound, solve_reference

SEEDS = range(8)


def _small(seed: int) -> Problem:
    return random_problem(
        n_arms=2 + seed % 2,
        n_tasks=5 + seed % 3,
        n_zones=1 + seed % 3,
        n_tools=seed % 2,
        seed=seed,
        setups=seed % 4 != 3,
        start_zones=seed % 3 == 1,
        blocking=seed % 4 == 2,
        zone_fraction=0.9,
    )


def _stretched(p: Problem, factor: float) -> Problem:
    """The same problem with every time multiplied by ``factor`` (no exact unit left)."""
    d: dict[str, Any] = p.to_dict()
    for task in d["tasks"]:
        task["release"] *= factor
        for mode in task["modes"]:
            mode["duration"] *= factor
            for w in mode["windows"]:
                w["start"] *= factor
                w["end"] *= factor
    return problem_from_dict(d)


@pytest.mark.parametrize("seed", SEEDS)
def test_reference_is_valid_and_below_every_schedule_without_waits(seed: int) -> None:
    p = _small(seed)
    tree_nowait = solve(p, "tree", time_limit=1, seed=seed, waits=False)
    tree = solve(p, "tree", time_limit=1, seed=seed)
    r = solve_reference(p, 5, seed, hint=tree.schedule, bound_time=2)
    assert r.schedule is not None
    assert validate(p, r.schedule) == pytest.approx(r.makespan)
    assert all(float(w.sum()) == 0.0 for w in r.schedule.waits)  # no waits at borders
    # the bound of the true problem is below every valid schedule, waits or not
    assert r.bound <= tree.objective + 1e-6
    assert r.bound <= r.makespan + 1e-6
    assert r.bound >= lower_bound(p) - 1e-9
    assert r.nowait_bound <= r.makespan + 1e-6
    assert r.exact_unit  # generated data are integers
    if r.status == "optimal":
        assert r.oracle_clean
        assert r.makespan <= tree_nowait.objective + 1e-6
        assert r.nowait_bound == pytest.approx(r.makespan)


@pytest.mark.parametrize("seed", SEEDS)
def test_outward_schedules_and_inward_bounds_without_an_exact_unit(seed: int) -> None:
    p = _stretched(random_problem(2, 6, 2, 1, seed=seed, setups=False, zone_fraction=0.9), 0.7071)
    tree = solve(p, "tree", time_limit=1, seed=seed)
    tree_nowait = solve(p, "tree", time_limit=1, seed=seed, waits=False)
    for unit in (0.001, 0.25):
        r = solve_reference(p, 5, seed, unit=unit, bound_time=2)
        assert not r.exact_unit
        assert r.schedule is not None
        assert validate(p, r.schedule) == pytest.approx(r.makespan)
        assert r.bound <= min(tree.objective, r.makespan) + 1e-6
        # the inward no-wait model bounds every schedule without waits
        assert r.nowait_bound <= tree_nowait.objective + 1e-6
        if r.status == "optimal":
            assert r.makespan - r.nowait_bound <= 0.01 + 1e-9


@pytest.mark.parametrize("seed", SEEDS)
def test_zone_free_relaxation_bounds_the_tree(seed: int) -> None:
    p = _small(seed + 100)
    b = relaxation_bound(p, 2, seed)
    for waits in (True, False):
        assert b <= solve(p, "tree", time_limit=0.5, seed=seed, waits=waits).objective + 1e-6


def test_nowait_model_rejects_bad_options() -> None:
    from multiarm.errors import UsageError

    p = _small(0)
    with pytest.raises(UsageError, match="unit"):
        nowait_model(p, 100.0, unit=-1.0)
    with pytest.raises(UsageError, match="rounding"):
        nowait_model(p, 100.0, unit=0.5, rounding="sideways")


def test_supersigma_under_a_work_limit_is_repeatable() -> None:
    """On a compiled cell (no exact unit, 152 zones, a blocking oracle): one
    worker and a deterministic limit give the same valid schedule twice."""
    from workcell import compile_cell, load_example

    p = compile_cell(load_example("supersigma")).problem
    runs = [
        solve_reference(p, None, 0, workers=1, max_deterministic_time=0.3, bound_time=0)
        for _ in range(2)
    ]
    a, b = runs
    assert a.schedule is not None and b.schedule is not None
    assert not a.exact_unit
    assert a.makespan == b.makespan and list(a.schedule.start) == list(b.schedule.start)
    assert validate(p, a.schedule) == pytest.approx(a.makespan)
    assert lower_bound(p) == a.bound <= a.makespan
    assert math.isfinite(a.makespan)


@pytest.mark.parametrize("seed", range(4))
def test_small_problems_without_zones_are_proven_to_10_ms(seed: int) -> None:
    """Without zones the zone-free relaxation is the problem itself. With no
    exact unit, up to FINE_TASKS tasks its bound is taken at the no-wait
    model's 1 ms, so it meets the reference's (valid) schedule within the
    10 ms a proof allows (at 10 ms, five rounded durations on a chain
    already lose more)."""
    from scheduler.reference import FINE_TASKS

    p = _stretched(random_problem(2, 6, 0, 0, seed=seed, setups=False), 1 / 3)
    assert p.n_tasks <= FINE_TASKS
    r = solve_reference(p, None, seed, workers=1, bound_deterministic_time=5.0)
    assert not r.exact_unit and r.schedule is not None
    assert validate(p, r.schedule) == pytest.approx(r.makespan)
    assert r.bound <= r.makespan + 1e-9
    assert r.makespan - r.zone_free_bound <= 0.01
