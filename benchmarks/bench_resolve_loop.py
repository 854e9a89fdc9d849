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
  alternating order, as the coordinator makes it (work-limited: the same
  plan whatever the machine's load), with a wall-clock budget instead
  (``time_limit`` = the 15 ms budget: the repaired plan plus the search
  decodes that fit; the plan then depends on the machine's speed), and the
  smaller work limits (``evaluations=8`` and ``6``: what a call would
  cost and give with less search) and the warm start alone
  (``evaluations=1``); for each: wall and CPU time
  p50/p90/p99/max, the mean of each part
  (:attr:`scheduler.Rescheduled.phases`), the mean re-solved makespan and a
  hash of every plan (starts and modes);
* **the baseline** (``baseline``, a git revision, e.g. ``53e9ddf``): the same
  scenarios simulated and the same calls replayed by that revision's code,
  in a second process fed call by call, alternating with this one: its
  in-loop latencies and executed makespans, its replayed wall and CPU
  times, and whether its plans hash the same.

The recording intercepts the name :mod:`workcell.sim.coordination.recovery`
calls (a measurement only: the call and its result are passed through).

A thin wrapper of the sweep ``benchmarks/sweeps/resolve_loop.toml`` (one
``benchmark`` run of :func:`measure`); it measures again on every call.
Results: ``benchmarks/results/resolve_loop.parquet``, ``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_resolve_loop [--quick]`` (``--quick``:
supersigma, three scenarios, no baseline; seconds; with the baseline the
revision's kernel is compiled once in a temporary copy, a few minutes).
"""

from __future__ import annotations

import hashlib
import os
import pickle
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

import workcell.sim.coordination.recovery as recovery
from benchmarks.bench_sim import _scenarios
from benchmarks.common import RevisionProcess, table_main
from multiarm.errors import MultiarmError
from scheduler import solve
from scheduler.reschedule import FrozenTask, Rescheduled, reschedule
from scheduler.schedule import Schedule
from scheduler.tree import TreeOptions
from workcell import compile_cell, load_example
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import simulate

NAME = "resolve_loop"
BUDGET_MS = 15.0
"""The issue's budget: p99 of the in-loop re-solve (simulate's default ``resolve_budget``)."""

PARTS = ("prepare", "state", "first", "search", "decodes", "build", "validate")

MODES: dict[str, dict[str, Any]] = {
    "work-limited (default)": {},
    "budget 15 ms (time_limit=0.015)": {"time_limit": BUDGET_MS / 1e3},
    "work limit 8 (evaluations=8)": {"evaluations": 8},
    "work limit 6 (evaluations=6)": {"evaluations": 6},
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


def plan_hash(r: Rescheduled) -> str:
    """A short hash of a re-solved plan's starts and modes ("" without one)."""
    s = r.schedule
    if s is None:
        return ""
    data = np.asarray(s.start, dtype=np.float64).tobytes() + np.asarray(s.mode, np.int64).tobytes()
    return hashlib.sha256(data).hexdigest()[:16]


def _one(kw: dict[str, Any]) -> dict[str, Any]:
    """One replayed call: wall and CPU seconds, its parts, its makespan and plan hash."""
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
        "hash": plan_hash(r),
    }


def _plain(x: Any) -> Any:
    """Schedules and frozen tasks as tuples of arrays (read by another revision)."""
    if isinstance(x, Schedule):
        return ("schedule", x.mode, x.start, x.end, [np.asarray(w) for w in x.waits], x.blocking)
    if isinstance(x, FrozenTask):
        return ("frozen", x.mode, x.start, x.end, x.waits)
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    return x


_CHILD = r"""
import json, pickle, sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
import scheduler
assert scheduler.__file__.startswith(sys.argv[1]), scheduler.__file__
from scheduler.reschedule import FrozenTask, reschedule
from scheduler.schedule import Schedule
from workcell import compile_cell, load_example
from workcell.sim.harness.faults import FaultPlan
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import simulate
import hashlib
import io

def back(x):
    if isinstance(x, tuple) and x and x[0] == "schedule":
        return Schedule(x[1], x[2], x[3], tuple(x[4]), x[5])
    if isinstance(x, tuple) and x and x[0] == "frozen":
        return FrozenTask(int(x[1]), float(x[2]), float(x[3]), tuple(x[4]))
    if isinstance(x, dict):
        return {k: back(v) for k, v in x.items()}
    return x

job = pickle.load(open(sys.argv[2], "rb"))
cc = compile_cell(load_example(job["cell"]))
p = cc.problem
plan = back(job["plan"])
calls = [{k: back(v) for k, v in kw.items()} for kw in job["calls"]]
simulate(cc, plan, seed=0, options=SimOptions(monitor=False))
for kw in calls:
    reschedule(p, **kw)
print("ready", flush=True)
for line in sys.stdin:
    cmd, i = line.split()
    i = int(i)
    if cmd == "sim":
        res = simulate(cc, plan, seed=job["seed"], faults=FaultPlan.from_dicts(job["faults"][i]),
                       options=SimOptions(monitor=False))
        m = res.metrics
        out = {"latency_ms": (np.asarray(m.resolve_latency, dtype=float) * 1e3).tolist(),
               "executed_makespan": float(m.executed_makespan), "failed": int(m.failed_tasks)}
    else:
        c0 = time.thread_time(); t0 = time.perf_counter()
        r = reschedule(p, **calls[i])
        wall = time.perf_counter() - t0; cpu = time.thread_time() - c0
        s = r.schedule
        h = "" if s is None else hashlib.sha256(np.asarray(s.start, dtype=np.float64).tobytes()
                                                + np.asarray(s.mode, np.int64).tobytes()).hexdigest()[:16]
        out = {"wall_ms": wall * 1e3, "cpu_ms": cpu * 1e3, "makespan": r.makespan,
               "ok": s is not None, "hash": h}
    print(json.dumps(out), flush=True)
"""
"""The baseline's process: the same plan, scenarios and calls, one command per line."""


def measure(
    seed: int, cell: str, scenarios: int, evaluations: int, repeat: int, baseline: str = ""
) -> dict[str, Any]:
    """The whole table: on the tree search's plan after ``evaluations``
    decodes (work-limited: the same plan, scenarios and calls on every
    machine), the scenarios simulated with re-solving on, then every
    recorded call replayed ``repeat`` times in each variant (:data:`MODES`);
    with a ``baseline`` revision, its process simulates each scenario and
    replays each call alternately with this one."""
    load = os.getloadavg()[0]
    cc = compile_cell(load_example(cell))
    p = cc.problem
    r = solve(
        p, "tree", time_limit=None, seed=seed, options=TreeOptions(max_evaluations=evaluations)
    )
    if r.schedule is None:
        raise MultiarmError(
            f"cell {cell!r}: the tree search found no plan in {evaluations} decodes"
        )
    plan = r.schedule
    simulate(cc, plan, seed=0, options=SimOptions(monitor=False))  # warm caches and compiled code
    scen = _scenarios(cc, plan, scenarios, seed)
    calls: list[dict[str, Any]] = []
    oracle: list[tuple[float, int]] = []
    loop_ms: list[float] = []
    runs: list[dict[str, Any]] = []
    for label, faults in scen:
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
    base: dict[str, Any] = {}
    child: RevisionProcess | None = None
    if baseline:
        print(f"bench_resolve_loop: starting the baseline {baseline}", file=sys.stderr, flush=True)
        child = RevisionProcess(
            baseline,
            _CHILD,
            pickle.dumps(
                {
                    "cell": cell,
                    "seed": seed,
                    "plan": _plain(plan),
                    "faults": [f.to_dicts() for _label, f in scen],
                    "calls": [
                        {k: _plain(v) for k, v in kw.items() if k != "problem"} for kw in calls
                    ],
                }
            ),
        )
        base = {"revision": child.rev, "scenarios": [], "loop_ms": [], "replay": []}
        # the scenarios again, alternating: the baseline's, then this revision's
        for i, (label, faults) in enumerate(scen):
            print(f"bench_resolve_loop: side by side: {label}", file=sys.stderr, flush=True)
            got = child.ask(f"sim {i}")
            base["scenarios"].append({"fault": label, **got})
            base["loop_ms"] += got["latency_ms"]
            res = simulate(cc, plan, seed=seed, faults=faults, options=SimOptions(monitor=False))
            m = res.metrics
            runs[i]["latency_ms_again"] = (
                np.asarray(m.resolve_latency, dtype=float) * 1e3
            ).tolist()
    replay: dict[str, list[dict[str, Any]]] = {mode: [] for mode in MODES}
    names = list(MODES)
    for i, kw in enumerate(calls):
        for rep in range(repeat):
            order = names if (i + rep) % 2 == 0 else names[::-1]  # alternate which runs first
            if child is not None and rep % 2 == 0:
                base["replay"].append({"call": i, **child.ask(f"call {i}")})
            for mode in order:
                replay[mode].append({"call": i, **_one({**kw, **MODES[mode]})})
            if child is not None and rep % 2 == 1:
                base["replay"].append({"call": i, **child.ask(f"call {i}")})
    if child is not None:
        child.close()
    return {
        "cell": cell,
        "seed": seed,
        "n_arms": p.n_arms,
        "n_tasks": p.n_tasks,
        "planned_makespan": float(plan.makespan),
        "evaluations": evaluations,
        "scenarios": runs,
        "calls": len(calls),
        "remaining": [p.n_tasks - len(kw["done"]) - len(kw["running"]) for kw in calls],
        "loop_ms": loop_ms,
        "replay": replay,
        "baseline": base,
        "repeat": repeat,
        "load_average_start": load,
        "load_average_end": os.getloadavg()[0],
    }


def table(r: Any) -> str:
    """The Markdown tables of the one measured row."""
    loop = np.asarray(r["loop_ms"], dtype=float)
    base = r.get("baseline") or {}

    def q(xs: Any, k: float) -> str:
        xs = np.asarray(xs, dtype=float)
        return f"{float(np.percentile(xs, k)):.1f}" if xs.size else "-"

    def mx(xs: Any) -> str:
        xs = np.asarray(xs, dtype=float)
        return f"{float(xs.max()):.1f}" if xs.size else "-"

    # the plan of each call as the default (work-limited) variant made it
    default: list[dict[str, Any]] = next(iter(r["replay"].values()), [])
    want = {x["call"]: x.get("hash", "") for x in default}

    def same(rows: list[dict[str, Any]]) -> str:
        if not rows or not want:
            return "-"
        k = sum(1 for x in rows if x.get("hash", "") == want.get(x["call"]))
        return f"{k}/{len(rows)}"

    remaining = r["remaining"]
    lines = [
        f"# Re-solving in the loop: {r['cell']} ({r['n_arms']} arms, {r['n_tasks']} tasks)",
        "",
        f"Plan: tree search, seed {r['seed']}, {r['evaluations']} decodes, "
        f"makespan {r['planned_makespan']:.1f} s. "
        f"{len(r['scenarios'])} seeded fault scenarios simulated with re-solving on: "
        f"{r['calls']} re-solves, "
        + (
            f"{np.mean(remaining):.0f} tasks left on average (min {min(remaining)}, "
            f"max {max(remaining)}). "
            if remaining
            else ""
        )
        + f"Budget {BUDGET_MS:g} ms (p99)."
        + (
            f" Baseline: revision {base['revision']}, in a second process fed the same "
            "scenarios and calls one at a time, alternating with this one."
            if base
            else ""
        ),
        "",
        "## Latency (ms)",
        "",
        "| calls | n | wall p50 | wall p90 | wall p99 | wall max | CPU p50 | CPU p99 "
        "| mean re-solved makespan (s) | plans as the default's |",
        "|---|---|---|---|---|---|---|---|---|---|",
        f"| in the loop (as simulated) | {loop.size} | {q(loop, 50)} | {q(loop, 90)} | "
        f"{q(loop, 99)} | {mx(loop)} | - | - | - | - |",
    ]
    if base:
        again = np.asarray(
            [x for sc in r["scenarios"] for x in sc.get("latency_ms_again", [])], dtype=float
        )
        bl = np.asarray(base["loop_ms"], dtype=float)
        lines += [
            f"| in the loop, side by side: this revision | {again.size} | {q(again, 50)} | "
            f"{q(again, 90)} | {q(again, 99)} | {mx(again)} | - | - | - | - |",
            f"| in the loop, side by side: baseline {base['revision']} | {bl.size} | "
            f"{q(bl, 50)} | {q(bl, 90)} | {q(bl, 99)} | {mx(bl)} | - | - | - | - |",
        ]
    rows_all = list(r["replay"].items())
    if base:
        rows_all.append((f"baseline {base['revision']} (its default)", base["replay"]))
    for mode, rows in rows_all:
        wall = [x["wall_ms"] for x in rows]
        cpu = [x["cpu_ms"] for x in rows]
        mk = [x["makespan"] for x in rows if x["ok"]]
        lines.append(
            f"| replayed: {mode} | {len(rows)} | {q(wall, 50)} | {q(wall, 90)} | {q(wall, 99)} | "
            f"{mx(wall)} | {q(cpu, 50)} | {q(cpu, 99)} | "
            + (f"{np.mean(mk):.3f}" if mk else "-")
            + f" | {same(rows)} |"
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
        "`build` the schedule record, `validate` the check of the new plan (off).",
        "",
        "## Scenarios (re-solving on)",
        "",
        "| fault | re-solves | latency in the loop (ms) | of which the blocking oracle "
        "(ms, new answers) | executed makespan (s) | failed |"
        + (" baseline: latency (ms) | baseline: executed makespan (s) |" if base else ""),
        "|---|---|---|---|---|---|" + ("---|---|" if base else ""),
    ]
    for i, sc in enumerate(r["scenarios"]):
        lat = ", ".join(f"{x:.1f}" for x in sc["latency_ms"]) or "-"
        orc = (
            ", ".join(
                f"{ms:.1f} ({n})"
                for ms, n in zip(sc.get("oracle_ms", []), sc.get("oracle_answers", []), strict=True)
            )
            or "-"
        )
        row = (
            f"| {sc['fault']} | {sc['resolves']} | {lat} | {orc} | "
            f"{sc['executed_makespan']:.1f} | {sc['failed']} |"
        )
        if base:
            b = base["scenarios"][i]
            blat = ", ".join(f"{x:.1f}" for x in b["latency_ms"]) or "-"
            row += f" {blat} | {b['executed_makespan']:.1f} |"
        lines.append(row)
    if base:
        mine = [sc["executed_makespan"] for sc in r["scenarios"]]
        theirs = [b["executed_makespan"] for b in base["scenarios"]]
        lines += [
            "",
            f"Mean executed makespan: {np.mean(mine):.3f} s (this revision), "
            f"{np.mean(theirs):.3f} s (baseline {base['revision']}).",
        ]
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
