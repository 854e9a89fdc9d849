"""Re-solving in the loop on a compiled cell (``cell8``): every call's latency and its parts.

One plan (the tree search's, seeded) of the compiled cell; seeded fault
scenarios (a part arriving late, a crash stopping an arm, an arm failing for
good: :func:`benchmarks.bench_sim._scenarios`) are simulated with re-solving
on, and every :func:`scheduler.reschedule` call the coordinator makes is
recorded (its inputs, its wall time in the loop, its result).

Reported:

* **in the loop** -- the wall time of each call as the simulation measured
  it (``SimResult.metrics.resolve_latency``), the part of it the cell's
  blocking oracle spent answering questions not asked before (a detour
  search each: once per question for the problem's lifetime), and the
  executed makespans;
* **replayed side by side** -- each recorded call made again, in
  alternating order, as the coordinator makes it now (``check=False``: the
  new plan is not validated in the call) and as it was made before
  (``check=True``: validated in every call), and the warm start alone
  (``evaluations=1``: the floor of a call that decodes the whole remaining
  list); for each: wall and CPU time p50/p90/p99/max, the mean of each part
  (:attr:`scheduler.Rescheduled.phases`) and the mean re-solved makespan.

The recording intercepts the name :mod:`workcell.sim.coordination.recovery`
calls (a measurement only: the call and its result are passed through).

A thin wrapper of the sweep ``benchmarks/sweeps/resolve_loop.toml`` (one
``benchmark`` run of :func:`measure`); it measures again on every call.
Results: ``benchmarks/results/resolve_loop.parquet``, ``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_resolve_loop [--quick]`` (``--quick``:
supersigma, three scenarios; seconds).
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

import workcell.sim.coordination.recovery as recovery
from benchmarks.bench_sim import _scenarios
from benchmarks.common import table_main
from multiarm.errors import MultiarmError
from scheduler import solve
from scheduler.reschedule import Rescheduled, reschedule
from workcell import compile_cell, load_example
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import simulate

NAME = "resolve_loop"
BUDGET_MS = 15.0
"""The issue's budget: p99 of the in-loop re-solve (simulate's default ``resolve_budget``)."""

PARTS = ("prepare", "state", "first", "search", "decodes", "build", "validate")

MODES: dict[str, dict[str, Any]] = {
    "now (check=False)": {"check": False},
    "before (check=True)": {"check": True},
    "warm start only (evaluations=1)": {"evaluations": 1},
}
"""The replayed variants: keyword overrides of the recorded call."""


def _oracle_work(problem: Any) -> tuple[float, int]:
    """Seconds the problem's blocking oracle has spent answering, and the
    questions it answered (not from its cache), so far ((0, 0) without one)."""
    stats = getattr(problem.blocking, "stats", None)
    if stats is None:
        return 0.0, 0
    return float(stats.seconds), int(stats.queries - stats.cached)


@contextmanager
def _recording(calls: list[dict[str, Any]], oracle: list[tuple[float, int]]) -> Iterator[None]:
    """Record every re-solve the coordinator makes (its keywords and problem)
    and what the blocking oracle answered within it (seconds, new answers)."""

    def record(problem: Any, **kw: Any) -> Rescheduled:
        s0, n0 = _oracle_work(problem)
        res = reschedule(problem, **kw)
        s1, n1 = _oracle_work(problem)
        calls.append({"problem": problem, **kw})
        oracle.append(((s1 - s0) * 1e3, n1 - n0))
        return res

    recovery.reschedule = record  # type: ignore[assignment]
    try:
        yield
    finally:
        recovery.reschedule = reschedule


def _one(kw: dict[str, Any]) -> dict[str, Any]:
    """One replayed call: wall and CPU seconds, its parts and its makespan."""
    c0 = time.thread_time()
    t0 = time.perf_counter()
    r = reschedule(**kw)
    wall = time.perf_counter() - t0
    cpu = time.thread_time() - c0
    return {
        "wall_ms": wall * 1e3,
        "cpu_ms": cpu * 1e3,
        "makespan": r.makespan,
        "phases_ms": {k: v * 1e3 for k, v in r.phases},
        "ok": r.schedule is not None,
    }


def measure(seed: int, cell: str, scenarios: int, time_limit: float, repeat: int) -> dict[str, Any]:
    """The whole table: the scenarios simulated with re-solving on, then every
    recorded call replayed ``repeat`` times in each variant (:data:`MODES`)."""
    load = os.getloadavg()[0]
    cc = compile_cell(load_example(cell))
    p = cc.problem
    r = solve(p, "tree", time_limit=time_limit, seed=seed)
    if r.schedule is None:
        raise MultiarmError(f"cell {cell!r}: the tree search found no plan in {time_limit:g} s")
    plan = r.schedule
    simulate(cc, plan, seed=0, options=SimOptions(monitor=False))  # warm caches and compiled code
    calls: list[dict[str, Any]] = []
    oracle: list[tuple[float, int]] = []
    loop_ms: list[float] = []
    runs: list[dict[str, Any]] = []
    for label, faults in _scenarios(cc, plan, scenarios, seed):
        print(f"bench_resolve_loop: {label}", file=sys.stderr, flush=True)
        before = len(calls)
        with _recording(calls, oracle):
            res = simulate(cc, plan, seed=seed, faults=faults, options=SimOptions(monitor=False))
        m = res.metrics
        lat = (np.asarray(m.resolve_latency, dtype=float) * 1e3).tolist()
        loop_ms += lat
        runs.append(
            {
                "fault": label,
                "resolves": len(calls) - before,
                "latency_ms": lat,
                "oracle_ms": [x[0] for x in oracle[before:]],
                "oracle_answers": [x[1] for x in oracle[before:]],
                "executed_makespan": float(m.executed_makespan),
                "failed": int(m.failed_tasks),
            }
        )
    replay: dict[str, list[dict[str, Any]]] = {mode: [] for mode in MODES}
    names = list(MODES)
    for i, kw in enumerate(calls):
        for rep in range(repeat):
            order = names if (i + rep) % 2 == 0 else names[::-1]  # alternate which runs first
            for mode in order:
                replay[mode].append({"call": i, **_one({**kw, **MODES[mode]})})
    return {
        "cell": cell,
        "seed": seed,
        "n_arms": p.n_arms,
        "n_tasks": p.n_tasks,
        "planned_makespan": float(plan.makespan),
        "scenarios": runs,
        "calls": len(calls),
        "remaining": [p.n_tasks - len(kw["done"]) - len(kw["running"]) for kw in calls],
        "loop_ms": loop_ms,
        "replay": replay,
        "repeat": repeat,
        "load_average_start": load,
        "load_average_end": os.getloadavg()[0],
    }


def table(r: Any) -> str:
    """The Markdown tables of the one measured row."""
    loop = np.asarray(r["loop_ms"], dtype=float)

    def q(xs: Any, k: float) -> str:
        xs = np.asarray(xs, dtype=float)
        return f"{float(np.percentile(xs, k)):.1f}" if xs.size else "-"

    def mx(xs: Any) -> str:
        xs = np.asarray(xs, dtype=float)
        return f"{float(xs.max()):.1f}" if xs.size else "-"

    remaining = r["remaining"]
    lines = [
        f"# Re-solving in the loop: {r['cell']} ({r['n_arms']} arms, {r['n_tasks']} tasks)",
        "",
        f"Plan: tree search, seed {r['seed']}, makespan {r['planned_makespan']:.1f} s. "
        f"{len(r['scenarios'])} seeded fault scenarios simulated with re-solving on: "
        f"{r['calls']} re-solves, "
        + (
            f"{np.mean(remaining):.0f} tasks left on average (min {min(remaining)}, "
            f"max {max(remaining)}). "
            if remaining
            else ""
        )
        + f"Budget {BUDGET_MS:g} ms (p99).",
        "",
        "## Latency (ms)",
        "",
        "| calls | n | wall p50 | wall p90 | wall p99 | wall max | CPU p50 | CPU p99 "
        "| mean re-solved makespan (s) |",
        "|---|---|---|---|---|---|---|---|---|",
        f"| in the loop (as simulated) | {loop.size} | {q(loop, 50)} | {q(loop, 90)} | "
        f"{q(loop, 99)} | {mx(loop)} | - | - | - |",
    ]
    for mode, rows in r["replay"].items():
        wall = [x["wall_ms"] for x in rows]
        cpu = [x["cpu_ms"] for x in rows]
        mk = [x["makespan"] for x in rows if x["ok"]]
        lines.append(
            f"| replayed: {mode} | {len(rows)} | {q(wall, 50)} | {q(wall, 90)} | {q(wall, 99)} | "
            f"{mx(wall)} | {q(cpu, 50)} | {q(cpu, 99)} | "
            + (f"{np.mean(mk):.3f}" if mk else "-")
            + " |"
        )
    lines += [
        "",
        "## Where a call's time goes (mean ms per call, replayed)",
        "",
        "| calls | " + " | ".join(PARTS) + " |",
        "|---|" + "---|" * len(PARTS),
    ]
    for mode, rows in r["replay"].items():
        cells = [
            f"{np.mean([x['phases_ms'].get(k, 0.0) for x in rows]):.1f}" if rows else "-"
            for k in PARTS
        ]
        lines.append(f"| {mode} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "`decodes` is the part of `first` and `search` spent in the decoder; `prepare` "
        "the dropped tasks and the warm start, `state` the frozen prefix committed, "
        "`build` the schedule record, `validate` the check of the new plan.",
        "",
        "## Scenarios (re-solving on)",
        "",
        "| fault | re-solves | latency in the loop (ms) | of which the blocking oracle "
        "(ms, new answers) | executed makespan (s) | failed |",
        "|---|---|---|---|---|---|",
    ]
    for sc in r["scenarios"]:
        lat = ", ".join(f"{x:.1f}" for x in sc["latency_ms"]) or "-"
        orc = (
            ", ".join(
                f"{ms:.1f} ({n})"
                for ms, n in zip(sc.get("oracle_ms", []), sc.get("oracle_answers", []), strict=True)
            )
            or "-"
        )
        lines.append(
            f"| {sc['fault']} | {sc['resolves']} | {lat} | {orc} | "
            f"{sc['executed_makespan']:.1f} | {sc['failed']} |"
        )
    lines += [
        "",
        f"Load average {r['load_average_start']:.1f} at the start and "
        f"{r['load_average_end']:.1f} at the end (wall times grow with the machine's load; "
        "the CPU times of the calling thread less so; the variants are replayed in "
        f"alternating order, {r['repeat']} times each).",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    table_main(NAME, table, argv, __doc__, speed=True, one_row=True)


if __name__ == "__main__":
    main()
