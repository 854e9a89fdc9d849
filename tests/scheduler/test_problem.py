"""The problem builder: validation naming the culprit, arrays, setups, JSON."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from multiarm.errors import CycleError, FormatError, UsageError, ValidationError
from scheduler import (
    FunctionSetup,
    MatrixSetup,
    Model,
    TravelSetup,
    Window,
    load_problem,
    save_problem,
)
from scheduler.generate import random_problem


def two_arm() -> Model:
    m = Model("demo")
    m.add_arm("left", available=1.0, capabilities=("gripper",))
    m.add_arm("right")
    m.add_zone("fixture", "shared")
    m.add_zone("feeder")
    m.add_tool("driver")
    m.add_task("a", release=2.0)
    m.add_task("b", predecessors=["a"])
    m.add_mode("a", "left", 4.0, windows=[Window("feeder", 0.0, 2.0)])
    m.add_mode(
        "b",
        "left",
        5.0,
        windows=[Window("fixture", 1.0, 4.0), Window("fixture", 2.0, 3.0, "move")],
        tools=["driver"],
    )
    m.add_mode("b", "right", 6.0, windows=[Window("fixture", 1.0, 5.0, "move")])
    return m


def test_build_arrays() -> None:
    p = two_arm().build()
    assert (p.n_arms, p.n_tasks, p.n_modes, p.n_zones, p.n_tools, p.n_windows) == (2, 2, 3, 2, 1, 4)
    assert p.task_modes == ((0,), (1, 2))
    assert p.task_preds == ((), (0,))
    assert p.task_succs == ((1,), ())
    assert p.mode_of.tolist() == [[0, 1], [-1, 2]]
    assert p.mode_tools == ((), (0,), ())
    assert p.zone_exclusive.tolist() == [False, True]
    assert p.mode_borders(1) == (1.0, 2.0)
    assert p.min_duration().tolist() == [4.0, 5.0]
    with pytest.raises(ValueError):
        p.task_release[0] = 5.0  # read-only


@pytest.mark.parametrize(
    ("edit", "error", "message"),
    [
        (lambda m: m.add_arm("left"), ValidationError, "duplicate arm name 'left'"),
        (lambda m: m.add_task("c"), ValidationError, "task 'c' has no mode: no arm can do it"),
        (lambda m: m.add_predecessors("a", ["b"]), CycleError, "precedence cycle: .*a.*b"),
        (
            lambda m: m.add_predecessors("a", ["zz"]),
            ValidationError,
            "task 'a' has unknown predecessor 'zz'",
        ),
        (
            lambda m: m.add_mode("a", "right", -1.0),
            ValidationError,
            "task 'a' on arm 'right': duration must be finite and >= 0",
        ),
        (lambda m: m.add_mode("a", "right", math.nan), ValidationError, "duration must be finite"),
        (
            lambda m: m.add_mode("a", "right", 3.0, windows=[Window("fixture", 1.0, 4.0)]),
            ValidationError,
            r"window \[1.0, 4.0\) in zone 'fixture' is outside the mode",
        ),
        (
            lambda m: m.add_mode("a", "right", 3.0, windows=[Window("fixture", 2.0, 2.0)]),
            ValidationError,
            "outside the mode",
        ),
        (
            lambda m: m.add_mode("a", "right", 3.0, windows=[Window("attic", 0.0, 1.0)]),
            ValidationError,
            "task 'a' on arm 'right': window in unknown zone 'attic'",
        ),
        (
            lambda m: m.add_mode("a", "right", 3.0, windows=[Window("fixture", 0.0, 1.0, "fly")]),
            ValidationError,  # type: ignore[arg-type]
            "window kind",
        ),
        (
            lambda m: m.add_mode("a", "right", 3.0, tools=["hammer"]),
            ValidationError,
            "unknown tool 'hammer'",
        ),
        (
            lambda m: m.add_mode("a", "nobody", 3.0),
            ValidationError,
            "task 'a': a mode names unknown arm 'nobody'",
        ),
        (
            lambda m: m.add_mode("zz", "left", 3.0),
            ValidationError,
            "a mode names unknown task 'zz'",
        ),
        (
            lambda m: m.add_mode("a", "left", 3.0),
            ValidationError,
            "task 'a' has two modes on arm 'left'",
        ),
        (
            lambda m: m.add_task("c", release=-1.0),
            ValidationError,
            "task 'c': release must be finite and >= 0",
        ),
        (
            lambda m: m.add_arm("x", available=math.inf),
            ValidationError,
            "available time must be finite",
        ),
        (
            lambda m: m.add_arm("x", start_zones=["nowhere"]),
            ValidationError,
            "unknown zone 'nowhere'",
        ),
    ],
)
def test_bad_input_is_named(edit, error: type[Exception], message: str) -> None:  # type: ignore[no-untyped-def]
    m = two_arm()
    edit(m)
    with pytest.raises(error, match=message):
        m.build()


def test_two_arms_cannot_start_in_one_exclusive_zone() -> None:
    m = two_arm()
    m.add_arm("third", start_zones=["feeder"])
    m.add_arm("fourth", start_zones=["feeder"])
    with pytest.raises(ValidationError, match="cannot all start in exclusive zone 'feeder'"):
        m.build()


def test_no_arm_and_bad_policy() -> None:
    with pytest.raises(ValidationError, match="at least one arm"):
        Model().build()
    with pytest.raises(ValidationError, match="policy"):
        Model().add_zone("z", "open")  # type: ignore[arg-type]


def test_setup_kinds_agree() -> None:
    p0 = random_problem(3, 8, 2, 1, seed=3)
    assert isinstance(p0.setup, TravelSetup)
    assert p0._setup.is_metric()
    A, T = p0.n_arms, p0.n_tasks
    dense = np.zeros((A, T + 1, T))
    for a in range(A):
        for prev in range(-1, T):
            dense[a, prev + 1] = np.where(p0.mode_of[a] >= 0, p0.setup_row(a, prev), 0.0)
    for setup in (
        MatrixSetup(dense),
        FunctionSetup(lambda a, prev, t: float(dense[a, prev + 1, t])),
    ):
        q = _rebuild_with_setup(p0, setup)
        for a in range(A):
            tasks = np.flatnonzero(p0.mode_of[a] >= 0).tolist()
            for prev in (-1, *tasks):
                for t in tasks:
                    assert q.setup_time(a, prev, t) == p0.setup_time(a, prev, t)


def _rebuild_with_setup(p, setup):  # type: ignore[no-untyped-def]
    m = Model()
    d = p.to_dict()
    for z in d["zones"]:
        m.add_zone(z["name"], z["policy"])
    for k in d["tools"]:
        m.add_tool(k)
    for a in d["arms"]:
        m.add_arm(a["name"], available=a["available"], start_zones=a["start_zones"])
    for t in d["tasks"]:
        m.add_task(t["name"], release=t["release"], predecessors=t["predecessors"])
    for t in d["tasks"]:
        for md in t["modes"]:
            m.add_mode(
                t["name"],
                md["arm"],
                md["duration"],
                windows=[Window(w["zone"], w["start"], w["end"], w["kind"]) for w in md["windows"]],
                tools=md["tools"],
            )
    m.set_setup(setup)
    return m.build()


def test_bad_setups() -> None:
    m = two_arm()
    m.set_setup(MatrixSetup(np.zeros((2, 3, 2)) - 1.0))
    with pytest.raises(
        ValidationError,
        match="setup time of arm 'left' from its initial pose to task 'a' must be finite and >= 0",
    ):
        m.build()
    with pytest.raises(ValidationError, match="shape"):
        MatrixSetup(np.zeros((2, 2, 2)))
    m.set_setup(MatrixSetup(np.zeros((3, 4, 3))))
    with pytest.raises(ValidationError, match=r"must have shape \(2, 3, 2\)"):
        m.build()
    with pytest.raises(ValidationError, match="metric"):
        TravelSetup(np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((2, 3)), metric="chebyshev")  # type: ignore[arg-type]


def test_non_metric_setup_is_detected() -> None:
    m = Model()
    m.add_arm("a")
    for t in ("x", "y", "z"):
        m.add_task(t)
        m.add_mode(t, "a", 1.0)
    times = np.zeros((1, 4, 3))
    times[0, 1 + 0, 2] = 10.0  # x -> z is slow, but x -> y -> z is quick
    m.set_setup(MatrixSetup(times))
    p = m.build()
    assert not p._setup.is_metric()


def test_json_round_trip(tmp_path: Path) -> None:
    p = random_problem(4, 15, 3, 2, seed=9, start_zones=True)
    path = save_problem(p, tmp_path / "p.json")
    q = load_problem(path)
    assert q.to_dict() == p.to_dict()
    assert np.array_equal(q.win_start, p.win_start) and q.arm_start_zones == p.arm_start_zones
    with pytest.raises(FormatError, match="cannot read"):
        load_problem(tmp_path / "none.json")
    (tmp_path / "bad.json").write_text('{"format": "other"}')
    with pytest.raises(FormatError, match="unsupported problem format"):
        load_problem(tmp_path / "bad.json")
    (tmp_path / "bad2.json").write_text('{"zones": []}')
    with pytest.raises(FormatError, match=r"bad2\.json: missing key 'arms'"):
        load_problem(tmp_path / "bad2.json")


def test_function_setup_cannot_be_written() -> None:
    m = two_arm()
    m.set_setup(FunctionSetup(lambda a, p, t: 1.0))
    p = m.build()
    with pytest.raises(UsageError, match="cannot be written"):
        p.to_dict()
