"""What compiling the kernel buys: decodes per second, numba vs plain Python.

The placement kernel (:mod:`scheduler.kernel`) runs compiled by numba; with
``MULTIARM_NO_JIT=1`` the very same code runs as plain Python. Both are run
here, in two processes side by side, on the same seeded problems, and the
ratio is reported. Results: ``benchmarks/results/kernel.json`` and ``kernel.md``.

Run: ``python -m benchmarks.bench_kernel [--seconds 3] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from benchmarks.common import write

PROBE = """
import json, sys, time
import numpy as np
from scheduler.generate import random_problem
from scheduler.kernel import compiled, decode, jit_enabled, warm_up
from scheduler.search import priority_order
seconds = float(sys.argv[1]); size = json.loads(sys.argv[2])
warm_up()  # compile or load
p = random_problem(*size, seed=0)
inst = compiled(p)
order = priority_order(p); free = np.full(p.n_tasks, -1)
decode(inst, order, free)
n = 0; t0 = time.perf_counter()
while time.perf_counter() - t0 < seconds:
    decode(inst, order, free); n += 1
print(json.dumps({"jit": jit_enabled(), "decodes_per_s": n / (time.perf_counter() - t0)}))
"""


def run(seconds: float, size: list[int], jit: bool) -> dict[str, float]:
    env = dict(os.environ)
    if not jit:
        env["MULTIARM_NO_JIT"] = "1"
    out = subprocess.run(
        [sys.executable, "-c", PROBE, str(seconds), json.dumps(size)],
        env=env,
        cwd=Path(__file__).resolve().parents[1],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    sizes = [[4, 50, 4, 1], [8, 200, 8, 2], [16, 1000, 30, 4]]
    if args.quick:
        sizes, args.seconds = sizes[:1], 0.3
    rows: list[dict[str, Any]] = []
    for size in sizes:
        fast = run(args.seconds, size, True)
        slow = run(args.seconds, size, False)
        rows.append(
            {
                "size": size,
                "numba": fast["decodes_per_s"],
                "python": slow["decodes_per_s"],
                "ratio": fast["decodes_per_s"] / slow["decodes_per_s"],
            }
        )
        print(rows[-1], flush=True)
    lines = [
        "# Kernel: numba vs plain Python",
        "",
        f"Full decodes (earliest-finish mode choice, waits) per second, {args.seconds:g} s each, same code, "
        "two processes side by side.",
        "",
        "| arms x tasks x zones x tools | plain Python /s | numba /s | ratio |",
        "|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {'x'.join(map(str, r['size']))} | {r['python']:.1f} | {r['numba']:.1f} | {r['ratio']:.0f}x |"
        )
    path = write(
        "kernel", {"seconds": args.seconds, "seed": 0, "rows": rows}, "\n".join(lines) + "\n"
    )
    print(path.read_text())


if __name__ == "__main__":
    main()
