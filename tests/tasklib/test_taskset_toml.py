"""The short, hand-writable TOML task-set format (docs/tasklib.md, issue 18)."""

from __future__ import annotations

import tempfile
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from multiarm.errors import FormatError
from tasklib import (
    DOWN,
    Approach,
    Grasp,
    Insert,
    Move,
    Part,
    Pose,
    Task,
    TaskSet,
    load_taskset,
    pose,
    save_taskset,
    taskset_from_dict,
)
from tasklib.io import taskset_to_toml
from tests.strategies import task_sets, unit_quats

coords = st.floats(-3.0, 3.0, allow_nan=False)
down_or_any = st.one_of(st.just(DOWN), unit_quats())


@st.composite
def pose_heavy_task_sets(draw: st.DrawFn) -> TaskSet:
    """Task sets whose steps have poses, about half of them with the tool down."""
    tasks = []
    for i in range(draw(st.integers(1, 4))):
        p = [Pose((draw(coords), draw(coords), draw(coords)), draw(down_or_any)) for _ in range(3)]
        steps = (
            Move(target=p[0], speed=draw(st.floats(0.01, 1.0))),
            Approach(p[1], draw(st.floats(0.001, 1.0))),
            Grasp(),
            Insert("x", p[2], 0.01),
        )
        tasks.append(Task(f"t{i}", steps, description=draw(st.text(max_size=8))))
    return TaskSet(draw(st.text(min_size=1, max_size=8)), tuple(tasks), (Part("x"),))


@settings(max_examples=60, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(pose_heavy_task_sets(), task_sets()))
def test_the_short_toml_form_round_trips_exactly(ts: TaskSet) -> None:
    text = taskset_to_toml(ts)
    assert taskset_from_dict(tomllib.loads(text)) == ts
    with tempfile.TemporaryDirectory() as d:
        path = save_taskset(ts, Path(d) / "x.toml")
        assert path.read_text(encoding="utf-8") == text
        assert load_taskset(path) == ts
    # one line a step: the file grows with the steps, not with the numbers
    n_steps = sum(len(t.steps) for t in ts.tasks)
    assert text.count("{ kind = ") == n_steps


def test_a_tool_down_pose_is_written_as_three_numbers() -> None:
    ts = TaskSet("s", (Task("t", (Move(target=pose(0.5, 0.25, 0.1)), Grasp())),))
    text = taskset_to_toml(ts)
    assert '{ kind = "move", target = [0.5, 0.25, 0.1] }' in text
    assert '{ kind = "grasp" }' in text  # defaults are left out
    tilted = TaskSet("s", (Task("t", (Move(target=pose(0.5, 0.25, 0.1, tool="up")),)),))
    assert "target = [0.5, 0.25, 0.1, 1.0, 0.0, 0.0, 0.0]" in taskset_to_toml(tilted)


HAND_WRITTEN = """\
name = "by hand"

[[feeders]]
id = "tray"
parts = ["pin"]
position = [0.1, 0.5, 0.0]
arrival = { model = "poisson", rate = 0.2 }

[[parts]]
id = "pin"

[[tasks]]
id = "insert_pin"
consumes = ["pin"]
steps = [
    { kind = "approach", target = [0.1, 0.5, 0.02], distance = 0.1 },
    { kind = "grasp", part = "pin" },
    { kind = "insert", part = "pin", target = [0.5, 0.5, 0.1, 0, 1, 0, 0], depth = 0.02 },
    { kind = "move", target = { position = [0.5, 0.5, 0.3], orientation = [0, 1, 0, 0] } },
]
"""


def test_a_hand_written_file_reads_with_every_pose_form(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text(HAND_WRITTEN, encoding="utf-8")
    ts = load_taskset(path)
    steps = ts.tasks[0].steps
    assert [s.kind for s in steps] == ["approach", "grasp", "insert", "move"]
    assert steps[0].target == pose(0.1, 0.5, 0.02)  # type: ignore[union-attr]
    assert steps[2].target == pose(0.5, 0.5, 0.1)  # type: ignore[union-attr]
    assert steps[3].target == pose(0.5, 0.5, 0.3)  # type: ignore[union-attr]
    assert ts.feeders[0].arrival.rate == 0.2  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            ("target = [0.1, 0.5, 0.02]", "target = [0.1, 0.5]"),
            r"mine\.toml: tasks\[0\]\.steps\[0\]\.target: a pose is \[x, y, z\]",
        ),
        (
            ("target = [0.1, 0.5, 0.02]", 'target = [0.1, 0.5, "low"]'),
            r"tasks\[0\]\.steps\[0\]\.target: a pose is",
        ),
        (
            ("[0.5, 0.5, 0.1, 0, 1, 0, 0]", "[0.5, 0.5, 0.1, 0, 2, 0, 0]"),
            r"tasks\[0\]\.steps\[2\]\.target: pose orientation is not a unit quaternion",
        ),
        (("depth = 0.02", "dept = 0.02"), r"tasks\[0\]\.steps\[2\]: unknown key 'dept'"),
        (('kind = "grasp"', 'kind = "grab"'), r"tasks\[0\]\.steps\[1\]: unknown step kind 'grab'"),
        (("rate = 0.2", 'rate = "often"'), r"feeders\[0\]\.arrival\.rate: expected a number"),
    ],
)
def test_errors_name_the_file_and_the_field_path(
    tmp_path: Path, edit: tuple[str, str], message: str
) -> None:
    old, new = edit
    assert old in HAND_WRITTEN
    path = tmp_path / "mine.toml"
    path.write_text(HAND_WRITTEN.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(FormatError, match=message) as info:
        load_taskset(path)
    assert info.value.filename == str(path)


@pytest.mark.parametrize(
    ("text", "line", "column"),
    [
        ('name = "x"\n[[tasks]]\nid = "a"\nsteps = [ { kind = "dwell" duration = 1 } ]\n', 4, None),
        ('name = "x"\ntasks = [\n', 3, 1),
        ('name = "x"\nname = "y"\n', 2, None),
    ],
)
def test_toml_syntax_errors_give_file_line_col(
    tmp_path: Path, text: str, line: int, column: int | None
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(FormatError) as info:
        load_taskset(path)
    err = info.value
    assert (err.filename, err.line) == (str(path), line)
    assert err.column is not None and (column is None or err.column == column)
    assert str(err).startswith(f"{path}:{line}:{err.column}: TOML syntax error")
