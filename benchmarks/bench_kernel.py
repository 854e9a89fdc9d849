"""What compiling the kernel buys: decodes per second, numba vs plain Python.

The placement kernel (:mod:`scheduler.kernel`) runs compiled by numba; with
``MULTIARM_NO_JIT=1`` the very same code runs as plain Python. Both are run
here, in two processes side by side, on the same seeded problems, and the
ratio is reported. A thin wrapper of the sweep ``benchmarks/sweeps/kernel.toml``
(one ``benchmark`` run of :func:`measure` per size): it measures again on
every call (``--resume`` keeps recorded runs), stores the rows in
``benchmarks/results/kernel.parquet`` and writes ``kernel.md`` and ``kernel.json``.

Run: ``python -m benchmarks.bench_kernel [--quick]``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from benchmarks.common import table_main

NAME = "kernel"

PROBE = """
import json, sys, time
import numpy as np
from scheduler.generate import random_problem
from scheduler.kernel import compiled, decode, jit_enabled, warm_up
from scheduler.search import priority_order
seconds = float(sys.argv[1]); size = json.loads(sys.argv[2]); seed = int(sys.argv[3])
warm_up()  # compile or load
p = random_problem(*size, seed=seed)
inst = compiled(p)
order = priority_order(p); free = np.full(p.n_tasks, -1)
decode(inst, order, free)
n = 0; t0 = time.perf_counter()
while time.perf_counter() - t0 < seconds:
    decode(inst, order, free); n += 1
print(json.dumps({"jit": jit_enabled(), "decodes_per_s": n / (time.perf_counter() - t0)}))
"""


def run(seconds: float, size: list[int], jit: bool, seed: int = 0) -> dict[str, float]:
    """Decodes per second of one problem in a new process, compiled or plain Python."""
    env = dict(os.environ)
    if not jit:
        env["MULTIARM_NO_JIT"] = "1"
    out = subprocess.run(
        [sys.executable, "-c", PROBE, str(seconds), json.dumps(size), str(seed)],
        env=env,
        cwd=Path(__file__).resolve().parents[1],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def measure(seed: int, size: list[int] | tuple[int, ...], seconds: float) -> dict[str, Any]:
    """One row of the table: numba and plain Python on the problem of ``size`` and ``seed``."""
    fast = run(seconds, list(size), True, seed)
    slow = run(seconds, list(size), False, seed)
    return {
        "size": list(size),
        "seconds": seconds,
        "numba": fast["decodes_per_s"],
        "python": slow["decodes_per_s"],
        "ratio": fast["decodes_per_s"] / slow["decodes_per_s"],
    }


def table(m: Any) -> str:
    """The Markdown table of the measured rows."""
    lines = [
        "# Kernel: numba vs plain Python",
        "",
        f"Full decodes (earliest-finish mode choice, waits) per second, "
        f"{', '.join(f'{s:g}' for s in sorted(set(m['seconds'])))} s each, same code, two "
        f"processes side by side; problem seeds {sorted(set(map(int, m['seed'])))}.",
        "",
        "| arms x tasks x zones x tools | plain Python /s | numba /s | ratio |",
        "|---|---|---|---|",
    ]
    for _, r in m.iterrows():
        lines.append(
            f"| {'x'.join(map(str, r['size']))} | {r['python']:.1f} | {r['numba']:.1f} | "
            f"{r['ratio']:.0f}x |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    table_main(NAME, table, argv, __doc__, speed=True)


if __name__ == "__main__":
    main()
