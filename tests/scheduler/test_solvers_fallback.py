"""Heuristics find a schedule whenever one exists (the exact fallback), the
one solve interface (typed options, argument checks), progress and Ctrl-C."""

from __future__ import annotations

import math

import numpy as np
import pytest

from multiarm.errors import UsageError
from scheduler import (
    SOLVERS,
    CpSatOptions,
    GreedyOptions,
    Model,
    Problem,
    Progress,
    TreeOptions,
    Window,
    solve,
    validate,
)
from scheduler.generate import random_problem

WORK = {
    "tree": dict(time_limit=None, options=TreeOptions(max_evaluations=300, max_width=4)),
    "greedy": dict(time_limit=None),
    "cpsat": dict(time_limit=None, options=CpSatOptions(workers=1)),
}


def swap_problem() -> Problem:
    """Each arm starts in an exclusive zone; its only task enters the other's start zone.

    Both tasks start at 0 (each arm leaves its zone at once): the optimum is 2.
    """
    m = Model("swap")
    m.add_zone("ZA")
    m.add_zone("ZB")
    m.add_arm("A", start_zones=["ZA"])
    m.add_arm("B", start_zones=["ZB"])
    m.add_task("ta")
    m.add_mode("ta", "A", 2.0, windows=[Window("ZB", 0.5, 1.5)])
    m.add_task("tb")
    m.add_mode("tb", "B", 2.0, windows=[Window("ZA", 0.5, 1.5)])
    return m.build()


@pytest.mark.parametrize("solver", SOLVERS)
def test_start_zone_swap_is_solved_to_optimality(solver: str) -> None:
    p = swap_problem()
    r = solve(p, solver, seed=0, **WORK[solver])  # type: ignore[arg-type]
    assert r.status.value == "optimal", r.summary()
    assert r.objective == 2.0
    assert r.schedule is not None and validate(p, r.schedule) == 2.0


def test_tree_fallback_respects_a_work_limit() -> None:
    # with only a work limit, the tree must not give up on its own: it hands over to CP-SAT
    p = swap_problem()
    r = solve(p, "tree", time_limit=None, options=TreeOptions(max_evaluations=20))
    assert r.status.value == "optimal" and r.objective == 2.0
    assert r.stats.extra["fallback"] == "optimal"


def test_greedy_without_fallback_reports_unknown() -> None:
    r = solve(swap_problem(), "greedy", options=GreedyOptions(fallback=False))
    assert r.status.value == "unknown" and r.schedule is None


# the random problems (start zones in every arm, 90 % of tasks in zones) on
# which list decoding alone found nothing although CP-SAT finds a schedule
DEADLOCKS = [(19, 3, 4, 4, True), (132, 3, 2, 3, False)]


@pytest.mark.parametrize(("seed", "arms", "tasks", "zones", "blocking"), DEADLOCKS)
@pytest.mark.parametrize("solver", ["greedy", "tree"])
def test_heuristics_find_a_schedule_where_list_decoding_deadlocks(
    solver: str, seed: int, arms: int, tasks: int, zones: int, blocking: bool
) -> None:
    p = random_problem(
        arms, tasks, zones, 1, seed=seed, start_zones=True, blocking=blocking, zone_fraction=0.9
    )
    alone = solve(p, "greedy", options=GreedyOptions(fallback=False))
    assert alone.schedule is None  # the case still exercises the fallback
    r = solve(p, solver, seed=0, **WORK[solver])  # type: ignore[arg-type]
    assert r.schedule is not None, r.summary()
    assert validate(p, r.schedule) == r.objective


def test_unschedulable_problem_is_proven_infeasible() -> None:
    # B stands in exclusive zone E for good (it has no task), and the only task needs E
    m = Model()
    m.add_zone("E")
    m.add_arm("A")
    m.add_arm("B", start_zones=["E"])
    m.add_task("t")
    m.add_mode("t", "A", 1.0, windows=[Window("E", 0.0, 1.0)])
    p = m.build()
    for solver in SOLVERS:
        r = solve(p, solver, seed=0, **WORK[solver])  # type: ignore[arg-type]
        assert r.status.value == "infeasible" and r.schedule is None, (solver, r.summary())


# ------------------------------------------------------------ the interface


@pytest.mark.parametrize("limit", [math.inf, -1.0, 0.0, math.nan, "10"])
def test_time_limit_must_be_finite_and_positive(limit: object) -> None:
    with pytest.raises(UsageError, match="time_limit"):
        solve(swap_problem(), "greedy", time_limit=limit)  # type: ignore[arg-type]


@pytest.mark.parametrize("seed", [-1, 2**31, 1.5, True])
def test_seed_must_be_an_int_in_range(seed: object) -> None:
    with pytest.raises(UsageError, match="seed"):
        solve(swap_problem(), "greedy", seed=seed)  # type: ignore[arg-type]


def test_typed_options_are_checked() -> None:
    with pytest.raises(UsageError, match=r"TreeOptions\.max_width"):
        TreeOptions(max_width=0)
    with pytest.raises(UsageError, match=r"TreeOptions\.beam_share"):
        TreeOptions(beam_share=2.0)
    with pytest.raises(UsageError, match=r"CpSatOptions\.workers"):
        CpSatOptions(workers=0)
    with pytest.raises(UsageError, match="takes options=GreedyOptions"):
        solve(swap_problem(), "greedy", options=TreeOptions())
    with pytest.raises(UsageError, match="has no option 'beam'"):
        solve(swap_problem(), "tree", beam=3)


def test_legacy_keywords_still_work() -> None:
    p = swap_problem()
    r = solve(p, "cpsat", time_limit=None, workers=1, hint=False)
    assert r.status.value == "optimal" and r.objective == 2.0
    r = solve(p, "tree", time_limit=None, max_evaluations=50)
    assert r.status.value == "optimal" and r.objective == 2.0


def test_progress_reports_every_improvement() -> None:
    p = random_problem(3, 20, 3, 1, seed=3)
    seen: list[Progress] = []
    r = solve(
        p, "tree", time_limit=None, options=TreeOptions(max_evaluations=300), progress=seen.append
    )
    assert seen, "no progress reported"
    assert [s.objective for s in seen] == [o for _, o in r.stats.improvements]
    assert all(s.solver == "tree" and s.bound <= s.objective for s in seen)
    assert seen[-1].objective == r.objective


def test_ctrl_c_returns_the_best_schedule_so_far() -> None:
    # a KeyboardInterrupt raised at the second improvement stands for Ctrl-C
    p = random_problem(3, 20, 3, 1, seed=3)
    calls: list[float] = []

    def interrupt(pr: Progress) -> None:
        calls.append(pr.objective)
        if len(calls) == 2:
            raise KeyboardInterrupt

    r = solve(
        p, "tree", time_limit=None, options=TreeOptions(max_evaluations=300), progress=interrupt
    )
    assert r.stats.interrupted is True
    assert r.status.value == "feasible"
    assert r.schedule is not None and validate(p, r.schedule) == r.objective
    assert r.objective <= calls[0]


def test_ctrl_c_before_any_schedule_is_unknown() -> None:
    def interrupt(pr: Progress) -> None:
        raise KeyboardInterrupt

    r = solve(random_problem(2, 6, 2, 1, seed=1), "greedy", progress=interrupt)
    assert r.stats.interrupted is True
    assert r.status.value == "unknown" and r.schedule is None


def test_result_to_dataframe() -> None:
    r = solve(swap_problem(), "greedy")
    df = r.to_dataframe()
    assert df.shape[0] == 1
    assert df.loc[0, "status"] == "optimal" and df.loc[0, "objective"] == 2.0
    _ = np


def test_every_solver_schedules_a_small_zone_problem(any_solver: str) -> None:
    # runs once per solver through the ``any_solver`` fixture of tests/conftest.py
    p = random_problem(2, 6, 2, 1, seed=4, start_zones=True)
    r = solve(p, any_solver, seed=0, **WORK[any_solver])  # type: ignore[arg-type]
    assert r.schedule is not None and validate(p, r.schedule) == r.objective
