"""The space grid keeps arms that move at the same time apart (workcell.geometry.reach).

The simulator's independent safety monitor (FCL at every sample) judges the
greedy plans executed exactly as planned, with the coordinator's own
geometric check off: with the grid no two arms ever touch; without it the
same cells' plans collide (so the test can fail).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from multiarm.errors import ValidationError
from scheduler import solve
from workcell import SimOptions, compile_cell, load_example, simulate
from workcell.geometry.reach import block_name, shared_blocks
from workcell.sim.harness.monitor import SafetyViolation


@pytest.mark.parametrize("name", ["supersigma", "scara4"])
def test_plans_with_the_space_grid_never_collide(name: str) -> None:
    cc = compile_cell(load_example(name))
    assert any(z.startswith("grid_") for z in cc.problem.zone_names)
    plan = solve(cc.problem, "greedy", seed=0).schedule
    run = simulate(cc, plan, seed=0, options=SimOptions(geometry_guard=False))  # the monitor is on
    assert run.metrics.executed_makespan == pytest.approx(run.metrics.planned_makespan, abs=1e-6)


@pytest.mark.parametrize("name", ["supersigma", "scara4"])
def test_without_the_space_grid_the_same_cells_collide(name: str) -> None:
    cell = dataclasses.replace(load_example(name), grid=0.0)
    cc = compile_cell(cell)
    assert not any(z.startswith("grid_") for z in cc.problem.zone_names)
    plan = solve(cc.problem, "greedy", seed=0).schedule
    with pytest.raises(SafetyViolation, match="collide"):
        simulate(cc, plan, seed=0, options=SimOptions(geometry_guard=False))


def test_blocks_cover_exactly_the_shared_region() -> None:
    a = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.5]])
    b = np.array([[0.8, 0.0, 0.0], [2.0, 1.0, 0.5]])
    c = np.array([[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]])  # shares nothing
    zm = shared_blocks([a, b, c], 0.25)
    assert zm.n_zones == 2 * 5 * 3
    assert block_name(3, 0, 0) in zm.zone_names() and block_name(2, 0, 0) not in zm.zone_names()
    assert shared_blocks([a, c], 0.25).n_zones == 0
    with pytest.raises(ValidationError, match="block size"):
        shared_blocks([a, b], 0.0)
    with pytest.raises(ValidationError, match="larger blocks"):
        shared_blocks([a, b], 1e-3)
