"""Task-set files: exact JSON/TOML round trips and errors that name the place."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from multiarm.errors import FormatError, TDLError, ValidationError
from tasklib import EXAMPLES, load_taskset, save_taskset, taskset_from_dict, taskset_to_dict
from tasklib.model import TaskSet
from tests.strategies import task_sets


@pytest.mark.parametrize("name", sorted(EXAMPLES))
@pytest.mark.parametrize("ext", ["toml", "json"])
def test_examples_round_trip(name: str, ext: str, tmp_path: Path) -> None:
    ts = EXAMPLES[name]()
    path = save_taskset(ts, tmp_path / f"{name}.{ext}")
    assert load_taskset(path) == ts


@settings(suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(task_sets())
def test_random_task_sets_round_trip(ts: TaskSet) -> None:
    assert taskset_from_dict(taskset_to_dict(ts)) == ts
    with tempfile.TemporaryDirectory() as d:
        for ext in ("toml", "json"):
            path = save_taskset(ts, Path(d) / f"x.{ext}")
            assert load_taskset(path) == ts


def base() -> dict:  # type: ignore[type-arg]
    return {
        "format": "multiarm.taskset/1",
        "name": "t",
        "tdl": "trajectory go { taught { stop (0, 0, 1) } }",
        "parts": [{"id": "p"}],
        "feeders": [{"id": "f", "parts": ["p"], "arrival": {"model": "poisson", "rate": 1}}],
        "tasks": [
            {
                "id": "a",
                "consumes": ["p"],
                "steps": [{"kind": "move", "trajectory": "go"}, {"kind": "grasp", "part": "p"}],
            }
        ],
    }


def test_base_is_valid() -> None:
    ts = taskset_from_dict(base())
    assert ts.tasks[0].steps[1].part == "p"  # type: ignore[union-attr]
    assert ts.feeders[0].arrival.rate == 1.0  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda d: d.update(format="other/2"), "unsupported format"),
        (lambda d: d.update(colour="red"), "unknown top-level key 'colour'"),
        (lambda d: d.pop("name"), "needs a 'name'"),
        (lambda d: d["tasks"][0].update(sped=1), r"tasks\[0\]: unknown key 'sped'"),
        (lambda d: d["tasks"][0].pop("steps"), r"tasks\[0\]: missing key 'steps'"),
        (
            lambda d: d["tasks"][0]["steps"][0].update(kind="fly"),
            r"tasks\[0\]\.steps\[0\]: unknown step kind 'fly'",
        ),
        (
            lambda d: d["tasks"][0]["steps"][0].pop("kind"),
            r"tasks\[0\]\.steps\[0\]: a step needs a 'kind'",
        ),
        (
            lambda d: d["tasks"][0]["steps"][0].update(speed="fast"),
            r"tasks\[0\]\.steps\[0\]\.speed: expected a number",
        ),
        (lambda d: d["tasks"][0]["steps"][0].update(speed=True), r"expected a number, got True"),
        (
            lambda d: d["tasks"][0]["steps"][0].update(interpolation="spline"),
            r"'spline' is not one of",
        ),
        (
            lambda d: d["tasks"][0]["steps"][0].update(speed=2.0),
            r"tasks\[0\]\.steps\[0\]: move speed must be a fraction",
        ),
        (lambda d: d["tasks"][0].update(steps="move"), r"tasks\[0\]\.steps: expected a list"),
        (
            lambda d: d["feeders"][0]["arrival"].update(model="magic"),
            r"unknown arrival model 'magic'",
        ),
        (
            lambda d: d["feeders"][0].update(position=[0, 0]),
            r"feeders\[0\]\.position: expected 3 values",
        ),
        (lambda d: d.update(tasks={"id": "a"}), r"tasks: expected a list"),
        (lambda d: d["tasks"][0].update(id=7), r"tasks\[0\]\.id: expected text"),
    ],
)
def test_structural_errors_name_the_place(mutate, message: str) -> None:  # type: ignore[no-untyped-def]
    d = base()
    mutate(d)
    with pytest.raises(FormatError, match=message) as info:
        taskset_from_dict(d, filename="my.toml")
    assert info.value.filename == "my.toml"


def test_semantic_errors_stay_validation_errors(tmp_path: Path) -> None:
    d = base()
    d["tasks"][0]["prerequisites"] = ["ghost"]
    p = tmp_path / "t.json"
    p.write_text(json.dumps(d))
    with pytest.raises(ValidationError, match="requires unknown task 'ghost'") as info:
        load_taskset(p)
    assert str(info.value).startswith(f"{p}: ")


def test_tdl_errors_inside_files(tmp_path: Path) -> None:
    d = base()
    d["tdl"] = "trajectory go {\n taught { stop (0, 0) } }"
    with pytest.raises(TDLError) as info:
        taskset_from_dict(d, filename="x.toml")
    assert info.value.filename == "x.toml[tdl]" and info.value.line == 2


def test_file_level_errors(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match=r"use \.toml or \.json"):
        load_taskset(tmp_path / "x.yaml")
    with pytest.raises(FormatError, match="cannot read"):
        load_taskset(tmp_path / "missing.toml")
    bad = tmp_path / "bad.json"
    bad.write_text('{"name": "x",\n  "tasks": [}')
    with pytest.raises(FormatError) as info:
        load_taskset(bad)
    assert info.value.line == 2
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\ntasks = [\n')
    with pytest.raises(FormatError, match="TOML syntax error"):
        load_taskset(bad)
    bad.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(FormatError, match="UTF-8"):
        load_taskset(bad)


def test_rule_broken_after_parsing_still_names_the_file(tmp_path: Path) -> None:
    from multiarm.errors import CycleError

    path = tmp_path / "cyc.toml"
    path.write_text(
        'name = "cyc"\n'
        '[[tasks]]\nid = "a"\nprerequisites = ["b"]\n[[tasks.steps]]\nkind = "dwell"\nduration = 1.0\n'
        '[[tasks]]\nid = "b"\nprerequisites = ["a"]\n[[tasks.steps]]\nkind = "dwell"\nduration = 1.0\n',
        encoding="utf-8",
    )
    with pytest.raises(CycleError, match=r"cyc\.toml: task prerequisite cycle: a -> b -> a") as ei:
        load_taskset(path)
    assert ei.value.cycle == ("a", "b", "a")
