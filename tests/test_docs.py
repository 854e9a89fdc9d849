"""The examples in docs/ are real: every SDL and TDL block there parses."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tasklib import parse_tdl
from zones import parse_sdl

DOCS = Path(__file__).resolve().parents[1] / "docs"


def blocks(name: str) -> list[str]:
    text = (DOCS / name).read_text()
    return re.findall(r"```\n(.*?)```", text, flags=re.S)


def test_sdl_reference_example_parses(tmp_path: Path) -> None:
    import trimesh

    example = blocks("sdl.md")[0]
    (tmp_path / "meshes").mkdir()
    jig = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    jig.apply_translation((0.6, 0.3, 0.1))
    jig.export(tmp_path / "meshes" / "jig.stl")
    zm = parse_sdl(example, str(tmp_path / "cell.sdl"))
    assert zm.n_zones == 8 and zm.tools[0].name == "screwdriver"
    assert zm.phase("idle").zones == ()


def test_tdl_reference_example_parses() -> None:
    doc = parse_tdl(blocks("tdl.md")[0])
    assert doc.names() == ("pick_and_place",)


def test_cell_file_example_in_docs_loads() -> None:
    import tomllib

    from workcell import cell_from_dict, compile_cell

    block = re.findall(r"```toml\n(.*?)```", (DOCS / "workcell.md").read_text(), flags=re.S)[0]
    cell = cell_from_dict(tomllib.loads(block), filename="cell.toml")
    assert [a.name for a in cell.arms] == ["left", "right"]
    assert compile_cell(cell).problem.n_arms == 2


@pytest.mark.parametrize(
    "name",
    [
        "tasklib.md",
        "zones.md",
        "scheduler.md",
        "workcell.md",
        "networks.md",
        "simulation.md",
        "plots.md",
        "cli.md",
        "replay.md",
        "README",
    ],
)
def test_python_examples_in_docs_run(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = DOCS.parent / "README.md" if name == "README" else DOCS / name
    code = re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)
    assert code
    import shutil

    # the examples read the small files shipped in docs/files/, and run as written
    monkeypatch.chdir(tmp_path)
    for f in (DOCS / "files").iterdir():
        shutil.copy(f, tmp_path / f.name)
    namespace: dict[str, object] = {}
    for block in code:
        exec(compile(block, f"{path.name}", "exec"), namespace)


@pytest.mark.parametrize("name", ["getting-started.md", "sweeps.md"])
def test_python_examples_of_the_site_pages_run(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    code = re.findall(r"```python\n(.*?)```", (DOCS / name).read_text(), flags=re.S)
    assert code
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    for block in code:
        exec(compile(block, name, "exec"), namespace)


@pytest.mark.slow
def test_the_docs_site_builds_with_warnings_as_errors(tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=DOCS.parent,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        check=False,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    site = tmp_path / "site"
    for page in ("index", "getting-started", "sweeps", "benchmarks", "timing", "papers"):
        assert (site / (page + "/index.html" if page != "index" else "index.html")).is_file()
    api = (site / "api" / "scheduler" / "index.html").read_text()
    assert "validate" in api and "lower_bound" in api  # written from the docstrings
    tutorial = (site / "tutorials" / "tutorial" / "index.html").read_text()
    assert "gantt" in tutorial and (site / "tutorials" / "tutorial.ipynb").is_file()
    bench = (site / "benchmarks" / "index.html").read_text()
    assert "mk01" in bench  # the stored tables are included


def test_the_task_set_file_example_of_tasklib_md_loads(tmp_path: Path) -> None:
    from tasklib import load_taskset, pose, save_taskset

    block = re.findall(r"```toml\n(.*?)```", (DOCS / "tasklib.md").read_text(), flags=re.S)[0]
    path = tmp_path / "pins.toml"
    path.write_text(block, encoding="utf-8")
    ts = load_taskset(path)
    assert [t.id for t in ts.tasks] == ["place_base", "insert_pin", "screw_cap"]
    assert ts.tasks[1].steps[2].target == pose(0.8, 0.5, 0.08)  # type: ignore[union-attr]
    assert load_taskset(save_taskset(ts, tmp_path / "again.toml")) == ts


def test_the_step_table_of_tasklib_md_is_the_records() -> None:
    """Every step kind's keys and defaults in docs/tasklib.md are the dataclasses' own."""
    import dataclasses
    import tomllib

    from tasklib.steps import STEP_KINDS

    text = (DOCS / "tasklib.md").read_text()
    table = text[text.index("**Steps**") : text.index("**`[[parts]]`**")]
    rows = dict(re.findall(r"^\| `(\w+)` \| (.*) \|$", table, flags=re.M))
    rows.pop("kind", None)  # the header
    assert set(rows) == set(STEP_KINDS)
    for kind, cls in STEP_KINDS.items():
        row = rows[kind]
        for f in dataclasses.fields(cls):
            if f.name in ("line", "column") or f.name.startswith("_"):
                continue
            assert f"`{f.name}" in row, (kind, f.name)
            written = re.search(rf"`{f.name} = ([^`]+)`", row)
            if written and f.default is not dataclasses.MISSING:
                assert tomllib.loads(f"v = {written.group(1)}")["v"] == f.default, (kind, f.name)


def test_the_arm_key_reference_of_workcell_md_is_the_metadata() -> None:
    """The tables are generated from ARM_KEYS, which the checks use: docs and checks agree."""
    from multiarm.errors import ValidationError
    from workcell.arms.spec import ARM_KEYS, ARM_TYPES, arm_from_dict, arm_keys_markdown

    text = (DOCS / "workcell.md").read_text()
    begin = text.index("<!-- arm-keys: generated by workcell.arms.spec.arm_keys_markdown() -->")
    end = text.index("<!-- arm-keys: end -->")
    written = text[text.index("\n", begin) + 1 : end]
    assert written == arm_keys_markdown(), (
        "regenerate the block with workcell.arms.spec.arm_keys_markdown()"
    )
    for kind in ARM_TYPES:  # every accepted key is in the reference, and no other
        documented = {k.name for k in ARM_KEYS["common"] + ARM_KEYS[kind]} - {"start"}
        with pytest.raises(ValidationError, match=r"unknown field 'zzz' \(known: (.*)\)") as e:
            arm_from_dict("a", {"type": kind, "zzz": 1}, "c.toml: arms.a")
        known = re.search(r"\(known: (.*)\)", str(e.value))
        assert known is not None and set(known.group(1).split(", ")) == documented


def _lines_match(expected: list[str], actual: list[str]) -> bool:
    """Whether ``actual`` matches ``expected``, where ``...`` in a line matches any
    text and a line that is only ``...`` matches any number of lines."""
    if not expected:
        return not actual
    head, rest = expected[0], expected[1:]
    if head == "...":
        return any(_lines_match(rest, actual[i:]) for i in range(len(actual) + 1))
    if not actual:
        return False
    pattern = ".*".join(re.escape(part) for part in head.split("..."))
    return re.fullmatch(pattern, actual[0]) is not None and _lines_match(rest, actual[1:])


def test_the_first_cell_page_runs_exactly_as_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """docs/first-cell.md: its files written from its code blocks, its commands run,
    their outputs compared with the page's (issue 18)."""
    import shlex

    from workcell.cli import main

    text = (DOCS / "first-cell.md").read_text(encoding="utf-8")
    files = re.findall(r"^\*\*`([\w.]+)`\*\*\n\n```\w*\n(.*?)```", text, flags=re.S | re.M)
    assert [name for name, _ in files] == ["cell.sdl", "tasks.toml", "cell.toml", "faults.toml"]
    monkeypatch.chdir(tmp_path)
    for name, body in files:
        (tmp_path / name).write_text(body, encoding="utf-8")
    sessions = re.findall(r"```console\n(.*?)```", text, flags=re.S)
    assert len(sessions) == 3
    for session in sessions:
        command, *expected = session.rstrip("\n").split("\n")
        assert command.startswith("$ multiarm ")
        capsys.readouterr()
        assert main(shlex.split(command)[2:]) == 0, capsys.readouterr().err
        actual = [line.rstrip() for line in capsys.readouterr().out.rstrip("\n").split("\n")]
        expected = [line.rstrip() for line in expected]
        assert _lines_match(expected, actual), "\n".join([command, *actual])
    assert (tmp_path / "run" / "tasks.csv").is_file()


def test_the_line_matcher_of_the_page_test() -> None:
    assert _lines_match(["a ... c", "..."], ["a b c", "x", "y"])
    assert _lines_match(["a", "...", "d"], ["a", "d"])
    assert not _lines_match(["a ... c"], ["a b d"])
    assert not _lines_match(["a", "b"], ["a"])
    assert not _lines_match(["a"], ["a", "b"])
