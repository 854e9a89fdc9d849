"""The arm-independent motion programs of tasks (workcell.program)."""

from __future__ import annotations

import numpy as np
import pytest

from multiarm.errors import ValidationError
from tasklib import Task, load_example
from tasklib.pose import Pose
from tasklib.steps import (
    Approach,
    Depart,
    Detect,
    Dwell,
    ForceSearch,
    Grasp,
    Insert,
    Move,
    SetFlag,
    WaitFlag,
)
from tasklib.tdl import TDLDocument, parse_tdl
from workcell.program import TOOL_DOWN, expand_task

DOWN = (0.0, 1.0, 0.0, 0.0)


def _xyz(seg) -> list[float]:  # type: ignore[no-untyped-def]
    return np.round(seg.target[:3, 3], 6).tolist()


def test_approach_comes_down_the_tool_axis_and_depart_backs_off() -> None:
    task = Task("t", (Approach(Pose((0.5, 0.2, 0.1), DOWN), 0.05), Grasp("p", 0.3), Depart(0.04)))
    prog = expand_task(task, TDLDocument())
    kinds = [(s.kind, s.interpolation) for s in prog.segments]
    assert kinds == [("move", "axis"), ("move", "linear"), ("dwell", "axis"), ("move", "linear")]
    # tool z points down: "back along the tool axis" is up
    assert _xyz(prog.segments[0]) == [0.5, 0.2, 0.15]
    assert _xyz(prog.segments[1]) == [0.5, 0.2, 0.1]
    assert prog.segments[2].duration == 0.3
    assert _xyz(prog.segments[3]) == [0.5, 0.2, 0.14]


def test_depart_first_is_an_error_naming_the_task() -> None:
    with pytest.raises(ValidationError, match="task 'x' step 1: depart before any pose"):
        expand_task(Task("x", (Depart(0.1),)), TDLDocument())


def test_insert_nominal_is_one_try_worst_is_every_try() -> None:
    search = ForceSearch(max_tries=7, try_time=0.5)
    task = Task("t", (Insert("pin", Pose((0, 0, 0.1), DOWN), 0.02, search=search),))
    nominal = expand_task(task, TDLDocument(), "nominal")
    worst = expand_task(task, TDLDocument(), "worst")
    assert nominal.dwell_time() == pytest.approx(0.5)
    assert worst.dwell_time() == pytest.approx(3.5)


def test_search_scan_is_half_the_line_nominal_and_whole_worst() -> None:
    a, b = Pose((0.0, 1.0, 0.1), DOWN), Pose((0.6, 1.0, 0.1), DOWN)
    task = Task("t", (Detect(a, b, "search"),))
    assert _xyz(expand_task(task, TDLDocument()).segments[-1]) == [0.3, 1.0, 0.1]
    assert _xyz(expand_task(task, TDLDocument(), "worst").segments[-1]) == [0.6, 1.0, 0.1]
    measure = Task("m", (Detect(a, b, "measure"),))
    assert _xyz(expand_task(measure, TDLDocument()).segments[-1]) == [0.6, 1.0, 0.1]


def test_trajectory_points_keep_the_previous_orientation_and_use_their_frame() -> None:
    doc = parse_tdl(
        "frame f = (1, 0, 0)\n"
        "trajectory tr { frame f taught interp axis { via (0, 0, 0.3) }\n"
        "  taught interp linear { stop (0.1, 0, 0.2) } }\n"
    )
    task = Task("t", (Move(Pose((0.9, 0, 0.3), DOWN)), Move(trajectory="tr")))
    prog = expand_task(task, doc)
    assert [s.interpolation for s in prog.segments] == ["axis", "axis", "linear"]
    assert _xyz(prog.segments[1]) == [1.0, 0.0, 0.3]
    assert _xyz(prog.segments[2]) == [1.1, 0.0, 0.2]
    for s in prog.segments:
        assert np.allclose(s.target[:3, :3], TOOL_DOWN[:3, :3])


def test_flags_mark_their_place_in_the_program() -> None:
    task = Task("t", (Dwell(1.0), SetFlag("f"), Dwell(2.0), WaitFlag("g"), Dwell(0.5)))
    prog = expand_task(task, TDLDocument())
    assert prog.flags_set == (("f", 1),)
    assert prog.flags_waited == (("g", 2),)


@pytest.mark.parametrize("name", ["supersigma", "scara4", "cell8"])
def test_every_builtin_task_expands(name: str) -> None:
    ts = load_example(name)
    for task in ts.tasks:
        for plan in ("nominal", "worst"):
            prog = expand_task(task, ts.trajectories, plan)  # type: ignore[arg-type]
            assert prog.segments
            assert all(0 < s.speed <= 1 for s in prog.segments)
