"""The procedural, C-style task API (S2.10)."""

from __future__ import annotations

from pathlib import Path

import pytest

from multiarm.errors import TDLError, UsageError, ValidationError
from tasklib import capi as c
from tasklib.arrivals import PoissonArrivals
from tasklib.pose import Pose
from tasklib.steps import Insert, UseTool


def build() -> c.TaskSetHandle:
    ts = c.taskset_open("t")
    c.feeder_add(ts, "f", ["a", "b"], (0, 0, 0), PoissonArrivals(1.0))
    c.part_add(ts, "a")
    c.part_add(ts, "b", ["a"])
    c.part_add(ts, "c")
    c.tdl_add(ts, "trajectory go { taught { stop (0, 0, 1) } }")
    return ts


def test_every_step_call_builds_its_record() -> None:
    ts = build()
    t = c.task_open(ts, "all", ["camera"], part="a")
    c.task_consume(t, "a")
    c.task_move(t, (0, 0, 1))
    c.task_move(t, trajectory="go", interpolation="linear", speed=0.5)
    c.task_approach(t, (0, 0, 0.5, 1, 0, 0, 0), 0.1)
    c.task_grasp(t, "a")
    c.task_insert(t, "a", Pose((0, 0, 0.2)), 0.01, max_tries=4, pattern="grid")
    c.task_use_tool(t, "press", 2.0)
    c.task_actuate(t, "clamp", "close", 0.5)
    c.task_detect(t, (0, 0, 0), (1, 0, 0), "measure")
    c.task_set_flag(t, "done")
    c.task_wait_flag(t, "done", 3.0)
    c.task_dwell(t, 1.0)
    c.task_release(t, "a")
    c.task_depart(t)
    c.task_produce(t, "c")
    task = c.task_close(t)
    kinds = [s.kind for s in task.steps]
    assert kinds == [
        "move",
        "move",
        "approach",
        "grasp",
        "insert",
        "use_tool",
        "actuate",
        "detect",
        "set_flag",
        "wait_flag",
        "dwell",
        "release",
        "depart",
    ]
    assert task.tool == "press"  # declared by the first use
    ins = task.steps[4]
    assert isinstance(ins, Insert) and ins.search.max_tries == 4 and ins.search.pattern == "grid"
    assert isinstance(task.steps[5], UseTool)
    t2 = c.task_open(ts, "next", part="b")
    c.task_require(t2, "all")
    c.task_dwell(t2, 0.5)
    c.task_close(t2)
    result = c.taskset_close(ts)
    assert result.precedence()["next"] == ("all",)
    assert [p.tasks for p in result.parts] == [("all",), ("next",), ()]


def test_bad_step_fails_at_the_call_naming_task_and_step() -> None:
    ts = build()
    t = c.task_open(ts, "x")
    c.task_dwell(t, 1.0)
    with pytest.raises(ValidationError, match="task 'x' step 2: move speed"):
        c.task_move(t, (0, 0, 0), speed=3.0)
    with pytest.raises(ValidationError, match="task 'x' step 2: a pose is 3"):
        c.task_move(t, (0, 0))
    with pytest.raises(ValidationError, match="task 'x' step 2: force search"):
        c.task_insert(t, "a", (0, 0, 0), max_tries=0)
    assert len(t.steps) == 1  # nothing half-added


def test_usage_errors() -> None:
    ts = build()
    t = c.task_open(ts, "x")
    with pytest.raises(UsageError, match="task 'x' is still open"):
        c.taskset_close(ts)
    with pytest.raises(ValidationError, match="duplicate task id 'x'"):
        c.task_open(ts, "x")
    c.task_dwell(t, 1.0)
    c.task_close(t)
    with pytest.raises(UsageError, match="already closed"):
        c.task_dwell(t, 1.0)
    with pytest.raises(UsageError, match="already closed"):
        c.task_close(t)
    with pytest.raises(UsageError, match="already closed"):
        c.task_require(t, "y")
    c.taskset_close(ts)
    with pytest.raises(UsageError, match="task set 't' is already closed"):
        c.task_open(ts, "y")
    with pytest.raises(ValidationError, match="duplicate part id"):
        p = build()
        c.part_add(p, "a")
    with pytest.raises(ValidationError, match="duplicate feeder id"):
        c.feeder_add(build(), "f", ["z"])
    with pytest.raises(ValidationError, match="both a part and a group"):
        c.task_open(build(), "q", part="a", group="g")


def test_unknown_owner_and_empty_task() -> None:
    ts = build()
    t = c.task_open(ts, "x", part="nope")
    c.task_dwell(t, 1.0)
    c.task_close(t)
    with pytest.raises(ValidationError, match="unknown part 'nope'"):
        c.taskset_close(ts)
    ts = build()
    t = c.task_open(ts, "empty")
    with pytest.raises(ValidationError, match="has no step"):
        c.task_close(t)


def test_tdl_load(tmp_path: Path) -> None:
    ts = build()
    f = tmp_path / "more.tdl"
    f.write_text("trajectory back { taught { stop (0, 0, 2) } }")
    c.tdl_load(ts, f)
    assert ts.tdl.names() == ("go", "back")
    with pytest.raises(TDLError, match="defined twice"):
        c.tdl_load(ts, f)
