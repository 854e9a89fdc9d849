"""Benchmark scripts still run (smoke runs at tiny sizes; nothing is timed here)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run_quick(script: str, out: Path, *flags: str) -> None:
    """``python -m benchmarks.<script> <flags> --quick`` writing into ``out``; it must succeed."""
    proc = subprocess.run(
        [sys.executable, "-m", f"benchmarks.{script}", *flags, "--quick"],
        cwd=ROOT,
        env={**os.environ, "MULTIARM_RESULTS": str(out)},
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize(
    "script",
    [
        "bench_zones",
        "bench_kernel",
        "bench_fjsp",
        "bench_fjsp_seeds",
        "bench_generated",
        "bench_setups",
        "bench_lines",
        "bench_outside",
        "bench_polish",
        "bench_scale",
        "bench_resolve",
        "bench_resolve_loop",
        "bench_geometry",
        "bench_oracle",
        "bench_cells",
        "bench_sim",
        "bench_simkernel",
        "bench_network",
        "bench_sweep",
        "bench_small",
        "bench_grid",
        "bench_urdf",
        "bench_policies",
        "gap_anatomy",
        "bench_longrun",
        "bench_bounds",
    ],
)
def test_benchmark_smoke(script: str, tmp_path: Path) -> None:
    _run_quick(script, tmp_path)
    out = list(tmp_path.glob("*.json"))
    assert out, "no JSON result written"
    data = json.loads(out[0].read_text())
    assert "machine" in data and ("seed" in data or "seeds" in data)
    assert (tmp_path / out[0].with_suffix(".md").name).is_file()


def test_polish_tuning_smoke(tmp_path: Path) -> None:
    """``bench_polish --tune --quick``: the tuning sweep's table, with its four tree
    labels and CP-SAT, and a note whose command reruns the tuning sweep."""
    _run_quick("bench_polish", tmp_path, "--tune")
    text = (tmp_path / "polish_tune.md").read_text()
    assert "| tree_off | tree_p40 | tree_p60 | tree_p80 | cpsat |" in text
    assert "`python -m benchmarks.bench_polish --tune --quick`" in text
    assert json.loads((tmp_path / "polish_tune.json").read_text())["quick"] is True


def test_polish_retuning_smoke(tmp_path: Path) -> None:
    """``bench_polish --retune --quick``: every label has the polish, so the table
    compares the shares with the reference label (0.6), not with a ``tree_off``."""
    _run_quick("bench_polish", tmp_path, "--retune")
    text = (tmp_path / "polish_retune.md").read_text()
    assert "| tree_p60 | tree_p70 | tree_p80 | tree_p90 | cpsat |" in text
    assert "- tree_p80: behind cpsat on" in text and "against tree_p60 lower on" in text
    assert "tree_off" not in text
    assert "`python -m benchmarks.bench_polish --retune --quick`" in text


@pytest.mark.parametrize(
    ("flag", "name", "off"),
    [("--fjsp", "polish_fjsp_tune", "pure FJSP"), ("--setups", "polish_setup_tune", "setup times")],
)
def test_polish_size_rule_tuning_smoke(flag: str, name: str, off: str, tmp_path: Path) -> None:
    """``bench_polish --fjsp`` / ``--setups`` with ``--quick``: the size rule's tuning
    table (the tree without that polish, with it, CP-SAT), saying what ``tree_off`` is."""
    _run_quick("bench_polish", tmp_path, flag)
    text = (tmp_path / f"{name}.md").read_text()
    assert "| tree_off | tree_polish | cpsat |" in text and off in text
    assert f"`python -m benchmarks.bench_polish {flag} --quick`" in text


def test_polish_sweeps_are_exclusive() -> None:
    from benchmarks import bench_polish

    with pytest.raises(SystemExit):
        bench_polish.main(["--tune", "--fjsp", "--quick"])
