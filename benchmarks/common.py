"""Helpers shared by the benchmark scripts: timing, machine info, writing results."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

RESULTS = Path(os.environ.get("MULTIARM_RESULTS", Path(__file__).resolve().parent / "results"))
"""Where results go (``MULTIARM_RESULTS`` overrides, e.g. for smoke tests)."""


def machine() -> dict[str, Any]:
    """What ran the benchmark (results are only comparable within one run)."""
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=False,
            cwd=Path(__file__).parent,
        ).stdout.strip()
    except OSError:
        commit = ""
    return {
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "commit": commit,
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
    }


def best_rate(fn: Callable[[], int], repeat: int = 5) -> tuple[float, list[float]]:
    """Run ``fn`` (which returns how many operations it did) ``repeat`` times;
    return the best rate (ops/s) and every rate. Best-of damps machine noise."""
    rates = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        n = fn()
        rates.append(n / (time.perf_counter() - t0))
    return max(rates), rates


def write(name: str, data: dict[str, Any], table: str) -> Path:
    """Write ``results/<name>.json`` and ``results/<name>.md``."""
    RESULTS.mkdir(exist_ok=True)
    data = {"machine": machine(), **data}
    (RESULTS / f"{name}.json").write_text(json.dumps(data, indent=2, default=str) + "\n")
    (RESULTS / f"{name}.md").write_text(table)
    return RESULTS / f"{name}.md"
