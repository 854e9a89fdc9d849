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
