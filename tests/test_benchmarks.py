"""Benchmark scripts still run (smoke runs at tiny sizes; nothing is timed here)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("script", ["bench_zones"])
def test_benchmark_smoke(script: str, tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", f"benchmarks.{script}", "--quick"],
        cwd=ROOT,
        env={"MULTIARM_RESULTS": str(tmp_path), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    out = list(tmp_path.glob("*.json"))
    assert out, "no JSON result written"
    data = json.loads(out[0].read_text())
    assert "machine" in data and "seed" in data
