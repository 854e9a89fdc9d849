"""Wrist force sensing and force-guided insertion tries at run time (S1.7, S1.2).

The built-in ``supersigma`` cell has one insert task (``insert_pin``, step 6:
13 tries at most, 0.4 mm spiral, 25 N raised threshold, 0.4 s a try); its
greedy plan puts it on the left arm with the nominal single try.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from multiarm.errors import UsageError, ValidationError
from scheduler import solve
from tasklib.steps import ForceSearch
from workcell import CompileOptions, compile_cell, load_example
from workcell.sim import Crash, EmergencyStop, FaultPlan, SimOptions, simulate
from workcell.sim.control.force import (
    CRASH_FORCE,
    FREE_THRESHOLD,
    ForceSensor,
    free_thresholds,
    insert_searches,
    task_rng,
    tries_needed,
)
from workcell.sim.events.trace import KINDS

TASK = "insert_pin"


@pytest.fixture(scope="module")
def cell() -> Any:
    return compile_cell(load_example("supersigma"))


@pytest.fixture(scope="module")
def plan(cell: Any) -> Any:
    return solve(cell.problem, "greedy", seed=0).schedule


@pytest.fixture(scope="module")
def drawn(cell: Any, plan: Any) -> Any:
    """Seed 1: the hole is found at the fourth try (three more than planned)."""
    return simulate(cell, plan, seed=1, options=SimOptions(insertion="drawn"))


def _search(cell: Any, plan: Any, seed: int, **kw: Any) -> Any:
    t = cell.problem.task_names.index(TASK)
    (s,) = insert_searches(cell, seed, **kw)[int(plan.mode[t])]
    return s


def _row(r: Any, task: str = TASK) -> Any:
    tf = r.tasks_frame()
    return tf[tf["task"] == task].iloc[0]


def _force(r: Any, task: str = TASK) -> list[Any]:
    return [e for e in r.trace if e.kind == "force" and e.task == task]


def _stops(r: Any) -> list[float]:
    return [e.time for e in r.trace if e.kind == "message" and e.message == "STOP_D"]


# ------------------------------------------------------------ the model


def test_tries_needed_is_the_first_offset_in_the_hole() -> None:
    """The tries are the index of the first offset of the search pattern
    within the tolerance of the hole on both axes, plus one (S1.7)."""
    fs = ForceSearch(max_tries=9, step=0.001)
    offsets = fs.offsets()
    for k, off in enumerate(offsets, start=1):
        assert tries_needed(fs, off + 0.0004) == (k, True)
    assert tries_needed(fs, (0.0, 0.0006)) == (4, True)  # (0, 1) mm is the fourth
    assert tries_needed(fs, (0.0, 0.0006), tolerance=0.0007) == (1, True)
    assert tries_needed(fs, (0.0021, 0.0)) == (9, False)
    grid = ForceSearch(max_tries=4, step=0.001, pattern="grid")
    assert tries_needed(grid, (0.0006, 0.0006)) == (4, True)


def test_sensor_commands_read_and_set_thresholds() -> None:
    s = ForceSensor(5.0)
    assert (s.thresholds.tolist(), s.raised) == ([5.0, 5.0, 5.0], False)
    assert s.exceeds(5.5) and not s.exceeds(5.0)
    s.set_thresholds([25.0, 25.0, 30.0])
    assert (s.raised, s.exceeds(29.0), s.exceeds(31.0)) == (True, False, True)
    assert s.exceeds(29.0, axis=0)  # 29 N > 25 N on x
    s.force[1] = 3.5
    assert s.read(1) == 3.5
    s.restore()
    assert not s.raised
    with pytest.raises(UsageError, match="thresholds must be > 0"):
        s.set_thresholds(-1.0)
    with pytest.raises(UsageError, match="axis must be 0, 1 or 2"):
        s.read(3)


def test_free_thresholds_per_arm_and_errors() -> None:
    assert free_thresholds(7.0, ["a", "b"]) == {"a": 7.0, "b": 7.0}
    assert free_thresholds({"b": 2.0}, ["a", "b"]) == {"a": FREE_THRESHOLD, "b": 2.0}
    with pytest.raises(UsageError, match="unknown arm 'c'"):
        free_thresholds({"c": 2.0}, ["a", "b"])
    with pytest.raises(UsageError, match="force_threshold must be a number > 0"):
        free_thresholds(0.0, ["a"])


def test_crash_records_carry_a_force() -> None:
    assert Crash("left", 1.0).force == CRASH_FORCE > FREE_THRESHOLD
    plan = FaultPlan.from_dicts([{"kind": "crash", "arm": "left", "at": 1.0, "force": 12}])
    assert plan[0] == Crash("left", 1.0, 1.0, 12.0)
    assert plan.to_dicts()[0]["force"] == 12.0
    with pytest.raises(ValidationError, match=r"^faults\[0\]\.force: must be"):
        FaultPlan.from_dicts([{"kind": "crash", "arm": "left", "at": 1.0, "force": -1}])


def test_simulate_checks_the_new_arguments(cell: Any, plan: Any) -> None:
    with pytest.raises(UsageError, match="insertion must be one of 'planned', 'drawn'"):
        simulate(cell, plan, options=SimOptions(insertion="sampled"))
    with pytest.raises(UsageError, match="insertion_sigma must be a number >= 0"):
        simulate(cell, plan, options=SimOptions(insertion="drawn", insertion_sigma=-1.0))
    with pytest.raises(UsageError, match="insertion_tolerance must be None or a number > 0"):
        simulate(cell, plan, options=SimOptions(insertion_tolerance=0.0))
    with pytest.raises(UsageError, match="unknown arm 'middle'"):
        simulate(cell, plan, options=SimOptions(force_threshold={"middle": 3.0}))


# ------------------------------------------------------------ draws


def test_drawn_tries_are_deterministic_and_differ_across_seeds(cell: Any, plan: Any) -> None:
    a, b = insert_searches(cell, 5), insert_searches(cell, 5)
    assert a == b
    tries = {_search(cell, plan, seed).tries for seed in range(8)}
    assert len(tries) > 1, tries
    # one stream per task: the same draw for every arm that can do the task
    t = cell.problem.task_names.index(TASK)
    modes = cell.problem.task_modes[t]
    assert len(modes) == 2 and len({(a[int(m)][0].tries, a[int(m)][0].error) for m in modes}) == 1
    rng = task_rng(5, t)
    assert a[int(modes[0])][0].error == tuple(float(x) for x in rng.normal(0.0, 1.0, 2) * 2.5e-4)


def test_draws_do_not_depend_on_the_order_of_events(cell: Any, plan: Any, drawn: Any) -> None:
    """An emergency stop before the insertion shifts every later event; the
    tries drawn for the task are the same."""
    r = simulate(
        cell, plan, seed=1, faults=[EmergencyStop(5.0, 2.0)], options=SimOptions(insertion="drawn")
    )
    reads = [e.detail for e in _force(r) if e.detail.startswith("read")]
    assert reads == [e.detail for e in _force(drawn) if e.detail.startswith("read")]
    assert len(reads) == _search(cell, plan, 1).tries == 4


# ------------------------------------------------------------ thresholds


def test_thresholds_raised_and_restored_around_insertions(cell: Any, plan: Any, drawn: Any) -> None:
    assert "force" in KINDS
    s = _search(cell, plan, 1)
    row = _row(drawn)
    ev = _force(drawn)
    assert [e.arm for e in ev] == ["left"] * len(ev)
    assert ev[0].detail.startswith("set thresholds 25 N")
    assert ev[0].time == pytest.approx(row["start"] + s.start, abs=1e-9)  # at the search dwell
    assert [e.detail.split(":")[0] for e in ev[1:-1]] == ["read force on axis 2"] * 4
    assert [e.detail.endswith(": in the hole") for e in ev[1:-1]] == [False, False, False, True]
    assert ev[-1].detail.startswith("set thresholds 5 N")
    assert ev[-1].time == pytest.approx(ev[0].time + 4 * 0.4, abs=1e-9)
    assert {e.task for e in drawn.trace if e.kind == "force"} == {TASK}  # no other task pushes
    # the free threshold can be set per arm
    r = simulate(
        cell, plan, seed=1, options=SimOptions(insertion="drawn", force_threshold={"left": 8.0})
    )
    assert _force(r)[-1].detail.startswith("set thresholds 8 N")


def test_planned_insertion_is_the_default_and_runs_as_planned(cell: Any, plan: Any) -> None:
    """With the defaults the search is not simulated (no force events) and
    the run is the plan; drawn with a hole exactly where planned also is."""
    r = simulate(cell, plan, seed=1)
    assert not [e for e in r.trace if e.kind == "force"]
    exact = simulate(cell, plan, seed=1, options=SimOptions(insertion="drawn", insertion_sigma=0.0))
    assert len(_force(exact)) == 3  # raise, one try in the hole, restore
    for res in (r, exact):
        assert res.executed is not None
        assert np.allclose(res.executed.start, plan.start, atol=1e-6)
        assert np.allclose(res.executed.end, plan.end, atol=1e-6)


# ------------------------------------------------------------ crashes


def _crash_run(cell: Any, plan: Any, at: float, force: float) -> Any:
    return simulate(
        cell,
        plan,
        seed=1,
        faults=[Crash("left", at, 0.5, force)],
        options=SimOptions(insertion="drawn"),
    )


def test_a_crash_below_the_raised_threshold_does_not_stop(cell: Any, plan: Any, drawn: Any) -> None:
    raised = _force(drawn)[0].time
    for at in (raised + 0.2, raised + 1.4):  # during an extra try, during a planned one
        r = _crash_run(cell, plan, at, 20.0)
        (fault,) = [e for e in r.trace if e.kind == "fault" and e.time == at]
        assert "20 N not above the 25 N threshold in force (pushing" in fault.detail
        assert at not in _stops(r)
        assert _row(r)["end"] == _row(drawn)["end"]


def test_a_crash_above_the_raised_threshold_stops(cell: Any, plan: Any, drawn: Any) -> None:
    raised = _force(drawn)[0].time
    for at in (raised + 0.2, raised + 1.4):
        r = _crash_run(cell, plan, at, 40.0)
        faults = [e for e in r.trace if e.kind == "fault" and e.time == at]
        assert "reflex-arc stop (S1.2): 40 N above the 25 N threshold" in faults[0].detail
        assert "after the fact" in faults[1].detail  # the coordinator is told afterwards
        assert at in _stops(r)
        assert _row(r)["end"] == pytest.approx(_row(drawn)["end"] + 0.5, abs=1e-9)


def test_a_crash_during_a_free_move_reflex_stops(cell: Any, plan: Any, drawn: Any) -> None:
    r = _crash_run(cell, plan, 12.0, CRASH_FORCE)
    faults = [e for e in r.trace if e.kind == "fault" and e.time == 12.0]
    assert "50 N above the 5 N threshold" in faults[0].detail
    left = [e for e in r.trace if e.kind == "message" and e.arm == "left"]
    stop = next(e for e in left if e.message == "STOP_D")
    alarm = next(e for e in left if e.message == "alarm" and e.src == 1)
    assert stop.time == 12.0 and alarm.time >= stop.time
    # a light touch in free motion is not a crash, unless the threshold is lower
    light = _crash_run(cell, plan, 12.0, 3.0)
    assert 12.0 not in _stops(light)
    assert light.metrics.executed_makespan == drawn.metrics.executed_makespan
    low = simulate(
        cell,
        plan,
        seed=1,
        faults=[Crash("left", 12.0, 0.5, 3.0)],
        options=SimOptions(insertion="drawn", force_threshold=2.0),
    )
    assert 12.0 in _stops(low)


# ------------------------------------------------------------ time and failure


def test_executed_duration_is_the_plan_plus_the_extra_tries(
    cell: Any, plan: Any, drawn: Any
) -> None:
    s = _search(cell, plan, 1)
    assert (s.planned, s.tries, s.found) == (1, 4, True)
    row = _row(drawn)
    planned = row["planned_end"] - row["planned_start"]
    assert row["end"] - row["start"] == pytest.approx(planned + 3 * 0.4, abs=1e-9)
    assert s.extra == pytest.approx(1.2)
    assert set(drawn.tasks_frame()["status"]) == {"done"}
    # the same decisions when every controller tick is modelled (S2.3)
    ticked = simulate(cell, plan, seed=1, options=SimOptions(insertion="drawn", tick=1e-3))
    assert _row(ticked)["end"] == pytest.approx(row["end"], abs=1e-9)


def test_a_hole_never_found_fails_the_task_and_loses_nothing(cell: Any, plan: Any) -> None:
    p = cell.problem
    r = simulate(cell, plan, seed=0, options=SimOptions(insertion="drawn", insertion_sigma=0.01))
    tf = r.tasks_frame()
    assert len(tf) == p.n_tasks and set(tf["status"]) == {"done", "failed"}
    cause = "insertion failed after 13 tries (step 6)"
    assert _row(r)["status"] == "failed" and _row(r)["cause"] == cause
    reads = [e for e in _force(r) if e.detail.startswith("read")]
    assert len(reads) == 13 and reads[-1].detail.endswith(cause)
    after = set(tf.loc[tf["status"] == "failed", "task"]) - {TASK}
    assert after == {"place_cap", "screw_cap", "unload"}  # everything after it
    for task in after:
        assert _row(r, task)["cause"] == f"predecessor {TASK!r} failed: {cause}"
    assert (tf.loc[tf["status"] == "done", "cause"] == "").all()
    assert r.metrics.failed_tasks == 4 and r.metrics.done_tasks == p.n_tasks - 4


def test_fewer_tries_than_planned_skip_the_rest_of_the_dwell() -> None:
    """Compiled with the worst case (all 13 tries planned), a hole found at
    the first try skips the rest of the search dwell; the arm then waits at
    its next zone border for the plan's time (it never passes it early)."""
    worst = compile_cell(load_example("supersigma"), options=CompileOptions(plan_with="worst"))
    plan = solve(worst.problem, "greedy", seed=0).schedule
    assert plan is not None
    s = _search(worst, plan, 0)
    assert (s.planned, s.tries, s.found) == (13, 1, True)
    r = simulate(worst, plan, seed=0, options=SimOptions(insertion="drawn"))
    ev = _force(r)
    assert len(ev) == 3 and ev[2].time == pytest.approx(ev[0].time + 0.4, abs=1e-9)
    after = [e for e in r.trace if e.kind == "segment" and e.task == TASK and e.time >= ev[2].time]
    assert after[0].time == ev[2].time and after[0].detail == f"task from offset {s.end:.6g} s"
    row = _row(r)
    assert row["end"] == pytest.approx(row["planned_end"], abs=1e-6)
