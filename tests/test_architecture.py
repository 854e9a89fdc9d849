"""The import direction of DESIGN.md, enforced (import-linter contracts in
pyproject.toml), and the packaging promises (py.typed, one exception root)."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ["multiarm", "tasklib", "zones", "scheduler", "workcell"]


def test_import_contracts_hold() -> None:
    lint = Path(sys.executable).with_name("lint-imports")
    proc = subprocess.run(
        [str(lint), "--config", str(ROOT / "pyproject.toml")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "8 kept, 0 broken" in proc.stdout


def _lint_with_bad_module(
    tmp_path: Path, where: str, code: str
) -> subprocess.CompletedProcess[str]:
    """Run the contracts on a copy of the tree with one bad module added."""
    import shutil

    for pkg in PACKAGES:
        shutil.copytree(ROOT / pkg, tmp_path / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    folder = tmp_path / where
    if not folder.is_dir():  # a package that does not exist yet (e.g. workcell/replay)
        folder.mkdir(parents=True)
        (folder / "__init__.py").write_text('"""A package to come."""\n')
    (folder / "_bad.py").write_text(code)
    lint = Path(sys.executable).with_name("lint-imports")
    return subprocess.run(
        [str(lint), "--config", str(tmp_path / "pyproject.toml")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
        env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"},
    )


def test_a_second_fcl_importer_is_detected(tmp_path: Path) -> None:
    # FCL stays behind workcell.geometry.world: another workcell module
    # importing it breaks a contract.
    proc = _lint_with_bad_module(tmp_path, "workcell", "import fcl\n")
    assert proc.returncode != 0
    assert "workcell._bad -> fcl" in proc.stdout


def test_a_broken_layer_is_detected(tmp_path: Path) -> None:
    # The contract must be able to fail: a copy of the tree in which zones
    # imports scheduler breaks it.
    proc = _lint_with_bad_module(tmp_path, "zones", "import scheduler\n")
    assert proc.returncode != 0
    assert "zones._bad -> scheduler" in proc.stdout


@pytest.mark.parametrize(
    ("where", "code", "arrow"),
    [
        # nothing below the face imports it: the simulation importing the CLI
        ("workcell/sim", "import workcell.cli\n", "workcell.sim._bad -> workcell.cli"),
        # the geometry is below the plots
        ("workcell/geometry", "import workcell.viz\n", "workcell.geometry._bad -> workcell.viz"),
        # experiments are below the campaigns that use them
        (
            "workcell/experiments",
            "import workcell.campaign\n",
            "workcell.experiments._bad -> workcell.campaign",
        ),
        # the replay sits under the simulation (SimResult.to_html imports it)
        ("workcell/replay", "import workcell.sim\n", "workcell.replay._bad -> workcell.sim"),
    ],
)
def test_a_broken_workcell_layer_is_detected(
    tmp_path: Path, where: str, code: str, arrow: str
) -> None:
    # the layers inside workcell (docs/design.md) can fail, each for its arrow
    proc = _lint_with_bad_module(tmp_path, where, code)
    assert proc.returncode != 0
    assert "Inside workcell, layers go one way" in proc.stdout and "BROKEN" in proc.stdout
    assert arrow in proc.stdout


def test_a_workcell_module_in_no_layer_is_detected(tmp_path: Path) -> None:
    # the workcell layers are exhaustive: a new top-level module must be given a layer
    proc = _lint_with_bad_module(tmp_path, "workcell", "X = 1\n")
    assert proc.returncode != 0
    assert "workcell._bad" in proc.stdout


@pytest.mark.parametrize("pkg", PACKAGES)
def test_package_is_typed(pkg: str) -> None:
    assert (ROOT / pkg / "py.typed").is_file()


def test_every_module_imports() -> None:
    for pkg in PACKAGES:
        mod = importlib.import_module(pkg)
        for info in pkgutil.walk_packages(mod.__path__, prefix=f"{pkg}."):
            importlib.import_module(info.name)


def test_one_exception_root() -> None:
    import multiarm.errors as e

    for name in e.__all__:
        cls = getattr(e, name)
        assert issubclass(cls, e.MultiarmError), name


@pytest.mark.parametrize(
    ("folder", "most"),
    [("workcell/cli", 250), ("workcell/experiments", 600)],
)
def test_the_face_and_the_studies_stay_small(folder: str, most: int) -> None:
    """Issue 20: each command module is arguments, one call and printing
    (<= 250 lines); no module of the experiments is over 600 lines."""
    over = {
        str(p.relative_to(ROOT)): n
        for p in sorted((ROOT / folder).rglob("*.py"))
        if (n := len(p.read_text().splitlines())) > most
    }
    assert not over, over
