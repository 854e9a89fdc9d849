"""``multiarm check`` explains a cell: per arm what it can do and why not, zones, tools,
warnings; broken cell files are read as cell files (issue 18)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from workcell import load_example
from workcell.check import explain_cell, reason_category
from workcell.cli import main

SDL = """\
cell (-1, -1, 0) (3, 2, 1.5)
zone press exclusive box (0.3, 0.3, 0) (0.7, 0.7, 0.4)
tool press rack (1.5, 1.5, 0.3)
"""

TASKS = """\
name = "t"

[[tasks]]
id = "pick"
steps = [{ kind = "approach", target = [0.5, 0.5, 0.1] }, { kind = "grasp" }]

[[tasks]]
id = "drill"
tool = "drill"
steps = [
    { kind = "move", target = [0.5, 0.5, 0.2] },
    { kind = "use_tool", tool = "drill", duration = 1.0 },
]
"""

CELL = """\
name = "warn"
zones = "cell.sdl"
tasks = "tasks.toml"

[arms.g]
type = "gantry"
rails = { x = [0.0, 1.0], y = [0.0, 1.0], z = [0.0, 0.4] }
capabilities = ["gripper", "tool_changer"]
tools = ["drill"]

[arms.s1]
type = "scara"
base = [2.5, 1.5, 0.0, 0.0]

[arms.s2]
type = "scara"
base = [2.5, 1.0, 0.0, 0.0]
start = [1.5707963, 0.0, 0.35, 0.0]

[arms.bare]
type = "scara"
base = [-0.5, -0.5, 0.0, 0.0]
capabilities = []
start = [0.0, 0.0, 0.35, 0.0]
"""


@pytest.fixture
def warn_cell(tmp_path: Path) -> Path:
    (tmp_path / "cell.sdl").write_text(SDL, encoding="utf-8")
    (tmp_path / "tasks.toml").write_text(TASKS, encoding="utf-8")
    path = tmp_path / "cell.toml"
    path.write_text(CELL, encoding="utf-8")
    return path


def test_check_prints_the_per_arm_table_and_every_warning(
    warn_cell: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["check", str(warn_cell)]) == 0  # warnings only
    out = capsys.readouterr().out
    assert out.startswith(f"{warn_cell}: ok with 6 warnings (cell 'warn': 4 arms, 2 tasks")
    lines = out.splitlines()
    assert "    g     gantry  2/2 tasks: pick, drill" in lines
    assert "    bare  scara   0/2 tasks: none" in lines
    assert "    bare pick (capability): lacks capability 'gripper'" in lines
    assert any(x.startswith("    s1 pick (reach): arm 's1': the point is") for x in lines)
    assert "    press (exclusive): tasks pick, drill; arms g" in lines
    assert "    drill (NOT declared in the SDL): tasks drill; mounted by g" in lines
    warnings = [x for x in lines if x.startswith("  warning: ")]
    assert len(warnings) == 6
    assert any("arms 's1' and 's2' collide at their start joints" in w for w in warnings)
    assert any("'press' is the name of a zone and of a tool" in w for w in warnings)
    assert any("tool 'drill' (of tasks drill) is declared by no SDL 'tool'" in w for w in warnings)
    for arm in ("s1", "s2", "bare"):
        assert any(f"arm {arm!r} can do no task" in w for w in warnings)


def test_check_json_is_the_same_report(warn_cell: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", "--json", str(warn_cell)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["ok"] is True
    (f,) = doc["files"]
    assert (f["file"], f["kind"], f["ok"], f["error"]) == (str(warn_cell), "cell", True, None)
    arms = {a["name"]: a for a in f["cell"]["arms"]}
    assert arms["g"]["tasks"] == ["pick", "drill"] and arms["g"]["kind"] == "gantry"
    assert {r["category"] for r in arms["bare"]["rejected"]} == {"capability"}
    assert {(t["name"], t["declared"]) for t in f["cell"]["tools"]} == {
        ("drill", False),
        ("press", True),
    }
    assert len(f["cell"]["warnings"]) == 6


def test_a_clean_cell_has_no_warning_and_names_what_each_arm_cannot_do() -> None:
    report = explain_cell(load_example("supersigma"))
    assert report.error is None and report.warnings == ()
    right = report.arms[1]
    assert (right.name, right.kind) == ("right", "gantry")
    assert [(r.task, r.category) for r in right.rejected] == [("scan_board", "capability")]
    fixture = next(z for z in report.zones if z.name == "fixture")
    assert fixture.policy == "shared" and set(fixture.arms) == {"left", "right"}


def test_a_cell_that_does_not_compile_is_an_error_that_keeps_its_warnings(
    warn_cell: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # without the gantry nobody can drill: an error (exit 1) naming the task
    text = warn_cell.read_text(encoding="utf-8")
    gantry = text[text.index("[arms.g]") : text.index("[arms.s1]")]
    warn_cell.write_text(text.replace(gantry, ""), encoding="utf-8")
    assert main(["check", str(warn_cell)]) == 1
    captured = capsys.readouterr()
    assert f"error: {warn_cell}: cell 'warn': no arm can do task 'pick'" in captured.err
    assert "collide at their start joints" in captured.out


@pytest.mark.parametrize(
    ("content", "where", "message"),
    [
        (b"", ":1:1:", "the cell file is empty"),
        (b"  \n\n", ":1:1:", "the cell file is empty"),
        (b'name = "caf\xe9"\n', ":1:12:", "cell file is not UTF-8 text (byte 0xe9"),
        (b'name = "x"\nzones = [\n', ":3:1:", "TOML syntax error"),
        (b'name = "x"\n[arms.a]\ntype = gantry\n', ":3:8:", "TOML syntax error"),
    ],
)
def test_a_broken_cell_file_is_read_as_a_cell(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    content: bytes,
    where: str,
    message: str,
) -> None:
    path = tmp_path / "cell.toml"
    path.write_bytes(content)
    assert main(["check", str(path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"error: {path}{where} {message}"), err
    assert "task set" not in err and "Traceback" not in err


def test_a_task_set_toml_is_still_checked_as_a_task_set(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "tasks.toml"
    path.write_text(TASKS, encoding="utf-8")
    assert main(["check", str(path)]) == 0
    assert f"{path}: ok (task set 't': 2 tasks, 0 parts, depth 1)" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("reason", "category"),
    [
        ("lacks capability 'gripper'", "capability"),
        ("cannot mount tool 'drill'", "tool"),
        ("would hit arm 'b' resting at its start joints", "collision at rest"),
        (
            "arm 'a' keeps its tool vertical (pointing down); the pose tilts it by 90 degrees",
            "orientation",
        ),
        ("arm 'a': the point is 2 m from the base axis, outside the reach [0.05, 0.85] m", "reach"),
        ("arm 'a': move needs joint 'x' = 3, outside its limits [0, 1]", "reach"),
    ],
)
def test_reason_categories(reason: str, category: str) -> None:
    assert reason_category(reason) == category


def test_a_builtin_cell_is_checked_by_name(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", "supersigma"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("supersigma: ok (cell 'supersigma': 2 arms, 10 tasks")
    assert "    right scan_board (capability): lacks capability 'object_detector'" in out
