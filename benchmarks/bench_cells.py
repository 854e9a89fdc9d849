"""The built-in cells: compile time, detours, and schedule quality, side by side in one run.

``python -m benchmarks.bench_cells [--quick]`` writes ``results/cells.md`` and
``results/cells.json``:

1. Compile time per cell, cold (first in the process: numba's one-time
   compiles included) and warm (again in the same process), and per mode.
2. Detours on ``scara4`` with arms parked at their last poses (``park =
   "last"``): every blocking query of every mode against every other arm
   parked after each of its tasks; how they were settled (pre-test, no
   contact, detour, none) and the OMPL detour times (median, p95) and the
   share solved within 100 ms.
3. The detour planner's single-state validity check on ``scara4`` (arm 0
   against arm 1 parked at home, uniform random joints, seed 0): the
   compiled path (compiled forward kinematics, one compiled bounding-capsule
   call, FCL only for candidates) next to the numpy reference path (numpy
   forward kinematics and matmul shape poses, then the same capsule test and
   FCL), in one run; both must give the same answers.
4. Schedule quality on the compiled cells: greedy, tree and CP-SAT at the
   same time limit (seed 0), makespans checked by ``scheduler.validate``.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace
from typing import Any

import numpy as np

from benchmarks.common import write
from scheduler import lower_bound, solve, validate
from workcell import compile_cell_detailed, load_example
from workcell.oracle import CellOracle


def _compile(names: list[str]) -> list[dict[str, Any]]:
    rows = []
    for name in names:
        cell = load_example(name)
        t0 = time.perf_counter()
        cc = compile_cell_detailed(cell)
        cold = time.perf_counter() - t0
        t0 = time.perf_counter()
        compile_cell_detailed(cell)
        warm = time.perf_counter() - t0
        m = cc.problem.n_modes
        rows.append(
            {
                "cell": name,
                "tasks": cc.problem.n_tasks,
                "modes": m,
                "cold (s)": round(cold, 2),
                "warm (s)": round(warm, 2),
                "per mode, warm (ms)": round(1000 * warm / m, 1),
                "oracle (s)": round(cc.problem.blocking.stats.seconds, 2),  # type: ignore[union-attr]
            }
        )
    return rows


def _detours(quick: bool) -> dict[str, Any]:
    cell = replace(load_example("scara4"), park="last")
    cc = compile_cell_detailed(cell)
    p, o = cc.problem, cc.problem.blocking
    assert isinstance(o, CellOracle)
    t0 = time.perf_counter()
    costs = []
    modes = range(0, p.n_modes, 4 if quick else 1)
    for m in modes:
        for b in range(p.n_arms):
            for pose in [t for t in range(p.n_tasks) if p.mode_of[b, t] >= 0]:
                costs.append(o.cost(m, b, pose))
    wall = time.perf_counter() - t0
    c = np.array(costs)
    plans = np.array(o.stats.plan_seconds)
    s = o.stats
    return {
        "queries": len(costs),
        "distinct": s.queries - s.cached,
        "pre-test free": s.pretest_free,
        "checked free": s.checked_free,
        "detoured": s.detoured,
        "no detour": s.infeasible,
        "budget stops": s.budget_stops,
        "finite > 0": int(np.sum((c > 0) & np.isfinite(c))),
        "wall (s)": round(wall, 2),
        "plans": len(plans),
        "plan median (ms)": round(1000 * float(np.median(plans)), 1) if len(plans) else math.nan,
        "plan p95 (ms)": round(1000 * float(np.percentile(plans, 95)), 1)
        if len(plans)
        else math.nan,
        "plans within 100 ms": f"{float(np.mean(plans <= 0.1)):.1%}" if len(plans) else "-",
    }


def _checks(n: int) -> dict[str, Any]:
    from workcell.geometry._sweep_jit import capsules_touch
    from workcell.geometry.planner import DetourPlanner, ObstacleSet

    cell = load_example("scara4")
    mover, blocker = cell.arms[0], cell.arms[1]
    ctx = DetourPlanner(
        mover, ObstacleSet.from_arm(blocker, blocker.home, 0.005), resolution=0.005, clearance=0.005
    )
    lo, hi = mover.joint_limits[:, 0], mover.joint_limits[:, 1]
    qs = np.random.default_rng(0).uniform(lo, hi, (n, mover.dof))
    idx = np.array([s.frame for s in mover.shapes])
    off = np.stack([s.offset for s in mover.shapes])

    def reference(q: np.ndarray) -> bool:
        row = q.reshape(1, -1)
        if not ctx._in_limits(row[0]):
            return False
        tfs = np.matmul(mover._frames_numpy(row)[:, idx], off)  # type: ignore[attr-defined]
        rot, trans = tfs[..., :3, :3], tfs[..., :3, 3]
        p0 = np.matmul(rot, ctx._local[:, 0, :, None])[..., 0] + trans
        p1 = np.matmul(rot, ctx._local[:, 1, :, None])[..., 0] + trans
        near = capsules_touch(p0, p1, ctx._rad, ctx._ob0, ctx._ob1, ctx._orad, 0.0)
        if not near[0]:
            return True
        return bool(ctx._world.first_collision("arm", tfs, "obstacles") < 0)

    for q in qs[:50]:  # warm up (numba's cache loads)
        reference(q)
        ctx.is_valid(q)
    times = {}
    answers = {}
    for name, f in (("compiled", ctx.is_valid), ("numpy reference", reference)):
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            got = [f(q) for q in qs]
            best = min(best, time.perf_counter() - t0)
        times[name] = 1e6 * best / n
        answers[name] = got
    assert answers["compiled"] == answers["numpy reference"], "the two checks disagree"
    return {
        "states": n,
        "valid": f"{float(np.mean(answers['compiled'])):.1%}",
        "compiled (us/check)": round(times["compiled"], 1),
        "numpy reference (us/check)": round(times["numpy reference"], 1),
        "speed-up": round(times["numpy reference"] / times["compiled"], 1),
    }


def _quality(names: list[str], limit: float) -> list[dict[str, Any]]:
    rows = []
    for name in names:
        p = compile_cell_detailed(load_example(name)).problem
        lb = lower_bound(p)
        for solver in ("greedy", "tree", "cpsat"):
            r = solve(p, solver, time_limit=limit, seed=0)
            mk = validate(p, r.schedule) if r.schedule is not None else math.inf
            rows.append(
                {
                    "cell": name,
                    "solver": solver,
                    "status": r.status.value,
                    "makespan (s)": round(mk, 1) if math.isfinite(mk) else "none",
                    "lower bound (s)": round(lb, 1),
                    "time (s)": round(r.runtime, 1),
                }
            )
    return rows


def _table(rows: list[dict[str, Any]]) -> str:
    cols = list(rows[0])
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(str(r[c]) for c in cols) + " |" for r in rows]
    return "\n".join(out) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="small sizes, a smoke run")
    args = ap.parse_args()
    names = ["supersigma", "scara4"] if args.quick else ["supersigma", "scara4", "cell8"]
    limit = 1.0 if args.quick else 10.0
    comp = _compile(names)
    det = _detours(args.quick)
    chk = _checks(500 if args.quick else 5000)
    qual = _quality(names, limit)
    md = (
        "# Built-in cells (`python -m benchmarks.bench_cells"
        + (" --quick" if args.quick else "")
        + "`)\n\nMachine: 2 cores shared with other work while this ran; times are"
        + " noisy (compare the ratios in one run, not absolute times across runs).\n"
        + "\n## Compile\n\n"
        + _table(comp)
        + "\n## Detours on scara4, arms parked at their last poses\n\n"
        + _table([det])
        + "\n## Single-state validity check on scara4 (best of 3 passes)\n\n"
        + _table([chk])
        + f"\n## Schedules at {limit:g} s per solver (seed 0, validated)\n\n"
        + _table(qual)
    )
    path = write(
        "cells", {"seed": 0, "compile": comp, "detours": det, "checks": chk, "quality": qual}, md
    )
    print(md)
    print(f"written to {path}")


if __name__ == "__main__":
    main()
