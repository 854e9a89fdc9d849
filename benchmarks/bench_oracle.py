"""Decoding with a blocking oracle: no oracle, a cold cache and a warm cache, side by side.

A blocking oracle (``scheduler.BlockingOracle``) answers, for a mode and an
arm parked at the end pose of a task, the detour the mode needs. Its answers
live in an array the compiled decoder reads (``scheduler.kernel.OracleTable``);
unknown ones are asked from Python between passes. This script decodes the
same seeded problems (8 arms x 200 tasks, ``scheduler.generate``) with a
simple deterministic oracle attached:

* **no oracle**: the problem without one (list decoding, earliest-finish mode);
* **no oracle, chronological**: the same, chronological (what the oracle forces);
* **cold cache**: a fresh table each decode (the oracle is asked for every
  answer the decode needs);
* **warm cache**: every answer known (the steady state of a search).

(Every decoder of the package now reads the compiled table; the former
Python loop with a dict cache is gone, so it has no column any more.)

The target is warm <= 2x no oracle. A thin wrapper of the sweep
``benchmarks/sweeps/oracle.toml`` (one ``benchmark`` run of :func:`measure`
per problem seed: every setting on that problem, side by side in one run);
it measures again on every call. Results:
``benchmarks/results/oracle.parquet``, ``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_oracle [--quick]``.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from benchmarks.common import best_rate, table_main
from scheduler.generate import random_problem
from scheduler.kernel import compiled, decode, warm_up
from scheduler.problem import Problem
from scheduler.search import priority_order

NAME = "oracle"


class HashOracle:
    """Deterministic oracle: a detour of 1-3 s for about one (mode, arm, pose) in five.

    Counts its calls (``calls``) to show how often the decoder asks.
    """

    def __init__(self) -> None:
        self.calls = 0

    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        self.calls += 1
        h = (mode * 7919 + arm * 104729 + (pose_task + 1) * 1299709) % 97
        return float(1 + h % 3) if h < 19 else 0.0


def _with_oracle(p: Problem) -> Problem:
    return dataclasses.replace(p, blocking=HashOracle())


def measure(seed: int, size: list[int] | tuple[int, ...], repeat: int) -> dict[str, Any]:
    """Decodes per second of one problem in each setting (one row of the table)."""
    kernel_load = warm_up()  # compile or load before any timing (once per process)
    size = list(size)
    plain = random_problem(size[0], size[1], size[2], size[3], seed=seed)
    order = priority_order(plain)
    free = np.full(plain.n_tasks, -1, dtype=np.int64)
    inst0 = compiled(plain)

    def run(fn: Any, n: int) -> Any:
        def go() -> int:
            for _ in range(n):
                fn()
            return n

        return go

    row: dict[str, Any] = {"size": size, "seed": seed, "repeat": repeat}
    row["kernel_load_s"] = kernel_load
    row["plain"], _ = best_rate(run(lambda: decode(inst0, order, free), 20), repeat)
    row["plain_chrono"], _ = best_rate(
        run(lambda: decode(inst0, order, free, chrono=True), 20), repeat
    )
    # cold: a fresh problem object (fresh table) every decode
    asked: list[int] = []

    def cold() -> None:
        q = _with_oracle(plain)
        inst = compiled(q)
        t0 = time.perf_counter()
        code, _st = decode(inst, order, free)
        assert code == 0
        cold_times.append(time.perf_counter() - t0)
        asked.append(q.blocking.calls)  # type: ignore[union-attr]

    cold_times: list[float] = []
    for _ in range(max(repeat, 2)):
        cold()
    row["cold"] = 1.0 / min(cold_times)
    row["oracle_calls_cold"] = asked[-1]
    # warm: the same problem again and again
    q = _with_oracle(plain)
    inst = compiled(q)
    code, _st = decode(inst, order, free)
    assert code == 0
    calls = q.blocking.calls  # type: ignore[union-attr]
    row["warm"], _ = best_rate(run(lambda: decode(inst, order, free), 20), repeat)
    row["oracle_calls_warm"] = q.blocking.calls - calls  # type: ignore[union-attr]
    row["warm_over_plain"] = row["plain"] / row["warm"]
    return row


def table(m: Any) -> str:
    """The Markdown table of the measured rows."""
    size = "x".join(map(str, m["size"].iloc[0])) if len(m) else "?"
    lines = [
        "# Decoding with a blocking oracle",
        "",
        f"Full decodes per second (best of {', '.join(map(str, sorted(set(m['repeat']))))}), "
        f"{size} (arms x tasks x zones x tools), `scheduler.generate.random_problem`, a "
        "deterministic oracle (`HashOracle` in the script). Cold: a fresh answer table per "
        "decode (the oracle is asked every answer the decode needs); warm: every answer known. "
        "Target: warm within 2x of no oracle.",
        "",
        "| seed | no oracle /s | no oracle, chrono /s | cold /s (oracle calls) | warm /s | "
        "no oracle / warm |",
        "|---|---|---|---|---|---|",
    ]
    for _, r in m.iterrows():
        lines.append(
            f"| {r['seed']} | {r['plain']:.1f} | {r['plain_chrono']:.1f} | {r['cold']:.1f} "
            f"({r['oracle_calls_cold']}) | {r['warm']:.1f} | {r['warm_over_plain']:.2f}x |"
        )
    lines += [
        "",
        f"Kernel compile or load before timing: {float(m['kernel_load_s'].sum()):.1f} s.",
    ]
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
