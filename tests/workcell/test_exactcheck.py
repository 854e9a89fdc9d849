"""The exact re-timing of a plan (workcell.exactcheck, S2.12's grid compromise measured).

Every re-timed plan is checked by the independent safety monitor (simulated
with the coordinator's geometric check off, so only the plan keeps the arms
apart), never ends a task later than the grid plan it came from, and
reproduces exactly. Plans come from the tree search under a work limit, so
the cases are the same on any machine.
"""

from __future__ import annotations

import numpy as np
import pytest

from multiarm.errors import UsageError, ValidationError
from scheduler import TreeOptions, solve, validate
from workcell import CompileOptions, SimOptions, compile_cell, load_example, simulate
from workcell.arms.base import LinkShape
from workcell.exactcheck import ExactRetiming, inert_grid, retime_exact
from workcell.geometry import CollisionWorld
from workcell.geometry.reach import grid_block
from workcell.sim.harness.monitor import SafetyViolation


@pytest.fixture(scope="module")
def grid_cc():  # type: ignore[no-untyped-def]
    return compile_cell(load_example("supersigma"), options=CompileOptions(grid=0.6))


@pytest.fixture(scope="module")
def grid_plan(grid_cc):  # type: ignore[no-untyped-def]
    return solve(grid_cc, "tree", seed=0, options=TreeOptions(max_evaluations=200)).plan


@pytest.fixture(scope="module")
def exact(grid_cc, grid_plan) -> ExactRetiming:  # type: ignore[no-untyped-def]
    return retime_exact(grid_cc, grid_plan)


def _monitored(ex: ExactRetiming) -> float:
    """Simulate with only the plan keeping arms apart; the monitor raises on a contact."""
    res = simulate(ex.compiled, ex.schedule, seed=0, options=SimOptions(geometry_guard=False))
    return float(res.metrics.executed_makespan)


def test_the_retimed_plan_is_valid_and_the_monitor_sees_no_contact(exact, grid_plan) -> None:
    assert validate(exact.compiled, exact.schedule) == pytest.approx(exact.makespan)
    assert exact.grid_makespan == pytest.approx(grid_plan.makespan)
    # it runs exactly as re-timed, with no contact (SafetyViolation otherwise)
    assert _monitored(exact) == pytest.approx(exact.makespan, abs=1e-6)


def test_the_retiming_keeps_modes_orders_and_never_ends_a_task_later(exact, grid_plan) -> None:
    s, g = exact.schedule, grid_plan.schedule
    assert s.mode.tolist() == g.mode.tolist()
    p = exact.compiled.problem
    assert s.sequences(p) == g.sequences(grid_plan.problem)
    assert np.all(s.end <= g.end + 1e-6)
    assert exact.makespan <= grid_plan.makespan + 1e-6
    # the grid kept arms apart that could pass: the exact plan is strictly shorter here
    assert exact.makespan < grid_plan.makespan - 1.0
    assert exact.ratio == pytest.approx(exact.makespan / grid_plan.makespan)


@pytest.mark.parametrize("seed", [1, 2])
def test_plans_of_other_seeds_retime_clean_and_never_later(grid_cc, seed: int) -> None:
    # a small seeded campaign: other tree plans of the same cell (other orders)
    plan = solve(grid_cc, "tree", seed=seed, options=TreeOptions(max_evaluations=60)).plan
    ex = retime_exact(grid_cc, plan)
    assert np.all(ex.schedule.end <= plan.schedule.end + 1e-6)
    assert _monitored(ex) == pytest.approx(ex.makespan, abs=1e-6)


def test_the_retiming_is_deterministic(grid_cc, grid_plan, exact) -> None:
    again = retime_exact(grid_cc, grid_plan.schedule)
    assert again.schedule == exact.schedule
    assert (again.passes, again.fcl_checks) == (exact.passes, exact.fcl_checks)


def test_a_colliding_plan_is_made_safe() -> None:
    # without the grid the tree's plan makes the two gantries collide (the monitor
    # says so); re-timed under the exact check, the same plan runs clean
    cc = compile_cell(load_example("supersigma"), options=CompileOptions(grid=0))
    plan = solve(cc, "tree", seed=0, options=TreeOptions(max_evaluations=200)).plan
    with pytest.raises(SafetyViolation):
        simulate(cc, plan.schedule, seed=0, options=SimOptions(geometry_guard=False))
    ex = retime_exact(cc, plan)
    assert ex.compiled is cc  # no grid: nothing to make inert
    assert _monitored(ex) == pytest.approx(ex.makespan, abs=1e-6)
    assert ex.makespan > plan.makespan  # moving the colliding tasks apart costs time


def test_tasks_that_touch_at_every_start_keep_their_time_and_are_named(
    grid_cc, grid_plan, exact
) -> None:
    # 10 cm of growth on every shape: the gantries, parked, "touch" each other's
    # paths whatever the starts; those tasks stay put and are reported
    ex = retime_exact(grid_cc, grid_plan, padding=0.1)
    assert ex.unresolved and set(ex.unresolved) <= set(grid_plan.problem.task_names)
    assert np.all(ex.schedule.end <= grid_plan.schedule.end + 1e-6)
    assert validate(ex.compiled, ex.schedule) == pytest.approx(ex.makespan)
    assert not exact.unresolved  # at 2 cm nothing is left


def test_inert_grid_keeps_the_modes_and_frees_the_blocks(grid_cc, grid_plan) -> None:
    free = inert_grid(grid_cc)
    p, q = grid_cc.problem, free.problem
    assert q.n_modes == p.n_modes and q.n_windows == p.n_windows
    assert all(q.mode_borders(m) == p.mode_borders(m) for m in range(p.n_modes))
    grid = np.array([grid_block(n) is not None for n in q.zone_names])
    assert grid.any() and not q.zone_exclusive[grid].any()
    assert q.zone_exclusive[~grid].tolist() == p.zone_exclusive[~grid].tolist()
    assert not q.win_move[grid[q.win_zone]].any()
    # a grid plan is a plan of the inert compile
    assert validate(free, grid_plan.schedule) == pytest.approx(grid_plan.makespan)


def test_bad_arguments_name_the_culprit(grid_cc, grid_plan) -> None:
    with pytest.raises(UsageError, match="padding"):
        retime_exact(grid_cc, grid_plan, padding=0.0)
    with pytest.raises(UsageError, match="margin"):
        retime_exact(grid_cc, grid_plan, margin=-1.0)
    with pytest.raises(UsageError, match="max_passes"):
        retime_exact(grid_cc, grid_plan, max_passes=0)
    with pytest.raises(UsageError, match="settle"):
        retime_exact(grid_cc, grid_plan, settle=float("nan"))
    with pytest.raises(UsageError, match=r"expected a scheduler\.Plan"):
        retime_exact(grid_cc, "plan")


def test_collide_configurations_answers_each_pair() -> None:
    w = CollisionWorld()
    w.add_link_shape("a", LinkShape("a", "sphere", (0.1,), 0), group="left")
    w.add_link_shape("b", LinkShape("b", "sphere", (0.1,), 0), group="right")
    xs = np.array([0.0, 0.15, 0.25, 0.5])
    ta = np.repeat(np.eye(4)[None, None], 1, axis=0)
    tb = np.repeat(np.eye(4)[None, None], len(xs), axis=0)
    tb[:, 0, 0, 3] = xs
    pairs = np.array([[0, 3], [0, 1], [0, 2], [0, 0]])
    got = w.collide_configurations("left", ta, "right", tb, pairs)
    assert got.tolist() == [False, True, False, True]  # touching below 0.2 m apart
    with pytest.raises(ValidationError, match="out of range"):
        w.collide_configurations("left", ta, "right", tb, np.array([[1, 0]]))
    with pytest.raises(UsageError, match="two groups"):
        w.collide_configurations("left", ta, "left", ta, pairs)
