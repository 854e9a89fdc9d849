"""The built-in cell ``parking``: the S2.6 geometric deadlock in the main job.

``sb`` waits between jobs beside the press die, inside the shared press zone
(``park = "last"``); ``sa``'s swing from the die to the out-station passes
it. The plan sends ``sa`` around the parked ``sb`` on an OMPL detour (S2.12
"continue with alternative trajectory") instead of waiting for ``sb`` to
leave, and the simulated coordinator executes that detour.

Everything here is deterministic: the tree search runs on a work limit
(decoded schedules), the detour planner on a work limit of checked
configurations, the simulation on a seed.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from multiarm.errors import UsageError
from scheduler import Result, TreeOptions, solve, validate
from workcell import CompileOptions, compile_cell, load_example, simulate
from workcell.compile import CompiledCell
from workcell.detours import DetourComparison, compare_detours, plan_detours
from workcell.geometry import ObstacleSet, check_path
from workcell.sim.harness.options import SimOptions

EVALUATIONS = 2000


@pytest.fixture(scope="module")
def compiled() -> CompiledCell:
    return compile_cell(load_example("parking"))


@pytest.fixture(scope="module")
def comparison(compiled: CompiledCell) -> DetourComparison:
    return compare_detours(compiled.cell, compiled=compiled, evaluations=EVALUATIONS)


def _tree(cc: CompiledCell, seed: int = 0) -> Result:
    return solve(
        cc, "tree", time_limit=None, seed=seed, options=TreeOptions(max_evaluations=EVALUATIONS)
    )


def test_the_cell_parks_an_arm_in_the_other_ones_way(compiled: CompiledCell) -> None:
    cell, p = compiled.cell, compiled.problem
    assert cell.park == "last" and p.n_arms == 2
    # the press zone, where sb waits, is shared (S2.5): one mover at a time
    assert not bool(p.zone_exclusive[p.zone_names.index("press")])
    sa, sb = p.arm_names.index("sa"), p.arm_names.index("sb")
    deliver = int(p.mode_of[sa, p.task_names.index("deliver1")])
    press = p.task_names.index("press1")
    # sb parked after a press job is in deliver1's way, but a detour exists ...
    cost = compiled.oracle.cost(deliver, sb, press)
    assert 0.0 < cost < math.inf
    # ... and it goes around sb: collision-free against sb where it stands
    (detour,) = compiled.oracle.detours(deliver, sb, press)
    obstacles = ObstacleSet.from_arm(cell.arms[sb], compiled.oracle.parked_joints(sb, press))
    assert check_path(cell.arms[sa], detour.path, obstacles, step=0.005)
    assert detour.extra == pytest.approx(cost)
    # while the direct swing between the same two knots hits sb
    straight = np.stack([detour.path[0], detour.path[-1]])
    assert not check_path(cell.arms[sa], straight, obstacles, step=0.005)
    # sb resting at its start joints is in nobody's way
    assert compiled.oracle.cost(deliver, sb, -1) == 0.0


def test_the_tree_plan_takes_a_detour_and_beats_every_plan_without(
    compiled: CompiledCell, comparison: DetourComparison
) -> None:
    c = comparison
    assert c.cell == "parking" and c.solver == "tree"
    assert c.detours >= 1 and c.detour_tasks == ("deliver1",)
    assert c.makespan < c.makespan_without < math.inf
    assert c.saved == pytest.approx(c.makespan_without - c.makespan) and c.saved > 1.0
    # the same plan, solved again, validates to the same makespan and charges the detour
    plan = _tree(compiled).schedule
    assert plan is not None
    assert validate(compiled, plan) == pytest.approx(c.makespan)
    assert plan_detours(compiled, plan) == {"deliver1": 1}
    assert c.detour_seconds == pytest.approx(float(np.sum(plan.blocking)))
    # without detours the parked arm costs infinity: sa waits until sb leaves
    without = compile_cell(compiled.cell, options=replace(compiled.options, detours=False))
    other = _tree(without).schedule
    assert other is not None and not np.any(other.blocking > 0)
    assert plan_detours(without, other) == {}
    assert validate(without, other) == pytest.approx(c.makespan_without)
    press2 = without.problem.task_names.index("press2")
    deliver1 = without.problem.task_names.index("deliver1")
    assert other.start[deliver1] >= other.start[press2]
    # the greedy baseline finds the same trade
    g = compare_detours(compiled.cell, compiled=compiled, solver="greedy")
    assert g.detours >= 1 and g.makespan < g.makespan_without


def test_the_line_says_what_the_detour_bought(comparison: DetourComparison) -> None:
    line = comparison.line()
    assert line.startswith("parking: detours (tree): 1 OMPL detour around a parked arm")
    assert f"makespan {comparison.makespan:.1f} s" in line
    assert f"without detours {comparison.makespan_without:.1f} s" in line
    assert f"save {comparison.saved:.1f} s" in line
    none = replace(comparison, makespan_without=math.inf)
    assert none.line().endswith("without detours no plan was found")


def test_compare_detours_refuses_a_cell_compiled_without_detours(
    compiled: CompiledCell,
) -> None:
    off = compile_cell(compiled.cell, options=CompileOptions(detours=False))
    with pytest.raises(UsageError, match="detours on"):
        compare_detours(compiled.cell, compiled=off)
    with pytest.raises(UsageError, match="unknown solver"):
        compare_detours(compiled.cell, compiled=compiled, solver="magic")  # type: ignore[arg-type]


def test_the_simulation_executes_the_detour_and_the_monitor_stays_clean(
    compiled: CompiledCell,
) -> None:
    plan = _tree(compiled).schedule
    assert plan is not None
    result = simulate(compiled, plan, seed=0, options=SimOptions(monitor=True))  # raises on contact
    m = result.metrics
    assert m.detours >= 1
    summary = m.summary()
    assert summary["done_tasks"] == compiled.problem.n_tasks and summary["failed_tasks"] == 0
    assert result.safety is not None and result.safety.samples > 0
    # the detour is S2.12's alternative trajectory for deliver1, not a back-off
    (event,) = [e for e in result.trace.of_kind("detour")]
    assert event.arm == "sa" and event.task == "deliver1"
    assert "alternative trajectory around arm(s) 'sb'" in event.detail
    assert event.time < plan.start[compiled.problem.task_names.index("press2")]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_other_detour_seeds_tell_the_same_story(compiled: CompiledCell, seed: int) -> None:
    """The trade does not hang on one lucky OMPL path: other planner seeds
    give other detours, and the plan still takes one and still wins."""
    cc = compile_cell(compiled.cell, options=replace(compiled.options, detour_seed=seed))
    c = compare_detours(cc.cell, compiled=cc, evaluations=EVALUATIONS, seed=seed)
    assert c.detours >= 1 and c.makespan < c.makespan_without


def test_with_the_space_grid_the_simulation_executes_the_detour(
    compiled: CompiledCell,
) -> None:
    """With the space grid on, zone borders (stations of the task's leg) fall
    inside the stretch of ``sa``'s swing that touches the parked ``sb``. The
    coordinator used to plan its detour to the next station, which touches
    ``sb`` (``goal_in_collision``), so ``sa`` waited for ``sb`` to leave. Now
    the detour runs over the whole contact stretch, past those stations (as
    the compile's oracle plans it, knot before the contact to knot after),
    holding their zones: it is executed, every task is done, the live
    monitor (collisions and zone invariants) stays quiet."""
    cc = compile_cell(compiled.cell, options=replace(compiled.options, grid=0.3))
    p = cc.problem
    plan = _tree(cc).schedule
    assert plan is not None and plan_detours(cc, plan) == {"deliver1": 1}  # planned ...
    result = simulate(cc, plan, seed=0)  # the live monitor raises on a contact
    m = result.metrics
    assert m.detours >= 1  # ... and executed
    assert m.summary()["failed_tasks"] == 0 and m.done_tasks == p.n_tasks
    assert result.safety is not None and result.safety.samples > 0
    assert not result.trace.of_kind("monitor")
    (event,) = result.trace.of_kind("detour")
    assert event.arm == "sa" and event.task == "deliver1"
    assert "alternative trajectory around arm(s) 'sb'" in event.detail
    assert "station(s) to offset" in event.detail  # past the borders in the contact
    # the zones of the borders it passed were reserved and given back as planned:
    # every exclusive zone of deliver1's mode has its reservation in the run
    mode = int(plan.mode[p.task_names.index("deliver1")])
    zones = {p.zone_names[r] for r, _s, _e in p.shapes[mode].exclusive}
    res = result.reservations_frame()
    mine = res[(res["task"] == "deliver1") & (res["arm"] == "sa")]
    assert zones <= set(mine["resource"])
    assert len(mine) >= len(p.shapes[mode].exclusive)
    # the detour leg ran in the task, between its start and its end
    tf = result.tasks_frame().set_index("task")
    assert tf.loc["deliver1", "start"] < event.time < tf.loc["deliver1", "end"]


def test_without_detours_the_arm_waits_for_the_parked_arm(compiled: CompiledCell) -> None:
    """``SimOptions(detours=False)`` (the ablation): the coordinator plans no
    alternative trajectory; ``sa`` waits for ``sb`` to leave (or ``sb`` backs
    off), later than with the detour, and every task is still done."""
    plan = _tree(compiled).schedule
    assert plan is not None
    with_detour = simulate(compiled, plan, seed=0, options=SimOptions(monitor=False))
    without = simulate(compiled, plan, seed=0, options=SimOptions(monitor=False, detours=False))
    assert not [e for e in without.trace.of_kind("detour") if "alternative" in e.detail]
    assert without.metrics.done_tasks == compiled.problem.n_tasks
    assert without.metrics.executed_makespan > with_detour.metrics.executed_makespan


@pytest.mark.parametrize(
    ("field", "bad", "match"),
    [
        ("detours", 1, "SimOptions.detours must be True or False"),
        ("detour_checks", 0, r"SimOptions.detour_checks must be an integer in \[1, 1e\+07\]"),
        ("detour_checks", 2.5, "SimOptions.detour_checks must be an integer"),
        ("guard_answer", "sb", "SimOptions.guard_answer must be None or a callable"),
    ],
)
def test_the_detour_options_are_checked_by_field(field: str, bad: object, match: str) -> None:
    with pytest.raises(UsageError, match=match):
        SimOptions(**{field: bad})  # type: ignore[arg-type]
