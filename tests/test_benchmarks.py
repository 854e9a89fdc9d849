"""Benchmark scripts still run (smoke runs at tiny sizes; nothing is timed here)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run_quick(script: str, out: Path, *flags: str) -> subprocess.CompletedProcess[str]:
    """``python -m benchmarks.<script> <flags> --quick`` writing into ``out``; it must
    succeed (returned, for its output)."""
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
    return proc


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
        "bench_relaxed",
    ],
)
def test_benchmark_smoke(script: str, tmp_path: Path) -> None:
    _run_quick(script, tmp_path)
    out = list(tmp_path.glob("*.json"))
    assert out, "no JSON result written"
    data = json.loads(out[0].read_text())
    assert "machine" in data and ("seed" in data or "seeds" in data)
    assert (tmp_path / out[0].with_suffix(".md").name).is_file()


def test_cells_smoke_and_render(tmp_path: Path) -> None:
    """``bench_cells --quick``, then ``--render --quick`` in the same directory: the
    render runs nothing (every run is recorded), writes the same schedule rows,
    and says where the grid table comes from (none recorded here)."""
    _run_quick("bench_cells", tmp_path)
    first = json.loads((tmp_path / "cells.json").read_text())
    assert "machine" in first and "seeds" in first
    assert first["rendered_from_recorded_runs"] is False
    proc = _run_quick("bench_cells", tmp_path, "--render")
    assert proc.stdout.count(" 0 runs now, ") == 3, proc.stdout
    again = json.loads((tmp_path / "cells.json").read_text())
    assert again["rendered_from_recorded_runs"] is True
    assert again["rows"] == first["rows"]
    text = (tmp_path / "cells.md").read_text()
    assert "## The space grid" in text
    assert "No grid measurements are recorded: `python -m benchmarks.bench_grid`" in text


def test_cells_render_refuses_fresh() -> None:
    from benchmarks import bench_cells

    with pytest.raises(SystemExit, match="--render keeps the recorded runs"):
        bench_cells.main(["--render", "--fresh", "--quick"])


def test_cells_grid_section_reads_the_recorded_grid(tmp_path: Path) -> None:
    """The grid table in ``cells.md`` comes from ``bench_grid``'s recorded runs (here
    the published ones), under a second-level heading, with their own provenance."""
    import shutil

    from benchmarks.bench_cells import grid_section

    shutil.copy(ROOT / "benchmarks" / "results" / "grid.parquet", tmp_path / "grid.parquet")
    text = grid_section(tmp_path)
    assert text.count("## The space grid: block size against compile time") == 1
    assert "\n# " not in text
    assert "| cell | grid (m) | compile (s) | zones (grid) |" in text
    # the plans at the 10 s beside the work-limited ones, one heading level down
    assert "\n### The tree at 10 s\n" in text and "The price of the grid at 10 s" in text
    assert "| cell | grid (m) | windows | makespan (s) | x 0.3 | work-limited (s) |" in text
    for cell in ("supersigma", "scara4", "cell8"):
        assert f"| {cell} | 0.3 |" in text
    assert "Measured by `bench_grid`, not by this script's run" in text
    assert (
        "Reproduce: `python -m benchmarks.bench_grid` (sweep `benchmarks/sweeps/grid.toml`)" in text
    )


def test_outside_seeds_smoke(tmp_path: Path) -> None:
    """``bench_outside --seeds --quick``: both solvers with solver seeds 0-2, the
    per-seed and on-the-mean counts, and a note whose command reruns this sweep."""
    _run_quick("bench_outside", tmp_path, "--seeds")
    text = (tmp_path / "outside_seeds.md").read_text()
    assert "| problem | tree: seeds 0-2 | tree mean (min-max) | cpsat: seeds 0-2 |" in text
    assert "- tree behind cpsat with the same seed: seed 0 on " in text
    assert "beyond the spread (the tree's best seed longer than cpsat's worst): " in text
    assert "`python -m benchmarks.bench_outside --seeds --quick`" in text
    data = json.loads((tmp_path / "outside_seeds.json").read_text())
    assert data["seeds"] == [0, 1, 2] and len(data["rows"]) == 6


def _seed_runs(runs: dict[str, Any], family: str) -> Any:
    """The results frame ``seed_table`` reads: per problem, the tree's and
    CP-SAT's makespans with seeds 0 and 1."""
    import pandas as pd

    rows = [
        (name, label, seed, mk[seed])
        for name, both in runs.items()
        for label, mk in zip(("tree", "cpsat"), both, strict=True)
        for seed in (0, 1)
    ]
    return pd.DataFrame(rows, columns=["instance", "label", "seed", "makespan"]).assign(
        family=family, time_limit=1.0, instance_params='{"tasks": 5}'
    )


def test_outside_seed_table_counts() -> None:
    """The seed table tells a difference of one seed from one beyond the spread."""

    from benchmarks.bench_outside import seed_table

    runs = {  # per problem: the tree's and CP-SAT's makespans with seeds 0 and 1
        "p": ((10.0, 12.0), (11.0, 11.0)),  # behind with seed 1 only, equal on the mean
        "q": ((9.0, 9.0), (8.0, 8.0)),  # behind with every seed, beyond the spread
        "r": ((21.0, 18.0), (20.0, 20.0)),  # ahead on the mean, behind with seed 0
    }
    text = seed_table(_seed_runs(runs, "routes"))
    assert "| q | 9 9 | 9.0 (9-9) | 8 8 | 8.0 (8-8) | +12.50% |" in text
    assert "| r | 21 18 | 19.5 (18-21) | 20 20 | 20.0 (20-20) | -2.50% |" in text
    assert "- tree behind cpsat with the same seed: seed 0 on 2 of 3, seed 1 on 2 of 3" in text
    assert "- behind on the mean: 1 of 3 (by 12.50% at most);" in text
    assert "longer than cpsat's worst): 1 of 3" in text


def test_outside_seed_table_counts_a_run_without_a_schedule_as_longest() -> None:
    """A run without a schedule (nan) is longer than any schedule: it is behind with
    its seed, its mean is 'none' and behind any finite mean, and it is counted."""

    from benchmarks.bench_outside import seed_table

    nan = float("nan")
    runs = {
        "a": ((30.0, 31.0), (nan, 32.0)),  # CP-SAT without a schedule with seed 0
        "b": ((nan, nan), (nan, 40.0)),  # the tree never, CP-SAT once
        "c": ((nan, nan), (nan, nan)),  # neither: nobody is behind
    }
    text = seed_table(_seed_runs(runs, "stations"))
    assert "| a | 30 31 | 30.5 (30-31) | none 32 | none (32-none) | - |" in text
    assert "| b | none none | none (none-none) | none 40 | none (40-none) | - |" in text
    assert "- tree behind cpsat with the same seed: seed 0 on 0 of 3, seed 1 on 1 of 3" in text
    assert "- behind on the mean: 0 of 3;" in text
    assert "longer than cpsat's worst): 0 of 3" in text
    assert "runs without a schedule ('none'" in text and "tree 4 of 6, cpsat 4 of 6" in text


def test_outside_sweeps_are_exclusive() -> None:
    from benchmarks import bench_outside

    with pytest.raises(SystemExit):
        bench_outside.main(["--tune", "--seeds", "--quick"])


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


def test_revision_process_runs_a_revision_and_answers_line_by_line() -> None:
    """``RevisionProcess`` (the baselines of ``bench_sim`` and ``bench_resolve_loop``):
    the revision's tree unpacked first on the child's path, its job file read, one
    JSON line per line sent, and the tree removed on close. The quick runs of those
    benchmarks run without a baseline (its kernels compile for about a minute)."""
    from benchmarks.common import RevisionProcess

    script = (
        "import json, sys\n"
        "root, job = sys.argv[1], sys.argv[2]\n"
        "sys.path.insert(0, root)\n"
        "import benchmarks.common as c\n"
        "data = open(job, 'rb').read().decode()\n"
        "print('ready', flush=True)\n"
        "for line in sys.stdin:\n"
        "    print(json.dumps({'got': line.strip(), 'job': data,\n"
        "                      'from_root': c.__file__.startswith(root)}), flush=True)\n"
    )
    child = RevisionProcess("HEAD", script, b"the job")
    where = Path(child.dir.name)
    try:
        assert (where / "benchmarks" / "common.py").is_file()
        assert child.rev and len(child.rev) >= 7
        for word in ("one", "two"):
            assert child.ask(word) == {"got": word, "job": "the job", "from_root": True}
    finally:
        child.close()
    assert not where.exists()
