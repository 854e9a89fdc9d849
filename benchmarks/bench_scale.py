"""Scale: the first schedule and its quality at 16 arms x 1000 tasks x 30 zones.

Measures, on seeded generated problems: building the problem, the first
valid schedule (the earliest-finish-time list schedule that also starts the
tree search), the tree search's schedule after the time limit, and the lower
bound. The first-schedule time is measured warm (the compiled kernel loaded
once before timing; the one-off compile or cache load is reported apart).
Results: ``benchmarks/results/scale.json`` and ``scale.md``.

Run: ``python -m benchmarks.bench_scale [--time-limit 10] [--seeds 0 1 2] [--quick]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.common import write
from scheduler import lower_bound, solve, validate
from scheduler.generate import random_problem
from scheduler.kernel import compiled


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--time-limit", type=float, default=10.0)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument(
        "--size",
        type=int,
        nargs=4,
        default=[16, 1000, 30, 4],
        metavar=("ARMS", "TASKS", "ZONES", "TOOLS"),
    )
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    if args.quick:
        args.size, args.seeds, args.time_limit = [4, 60, 6, 1], [0], 1.0
    A, T, Z, K = args.size
    t0 = time.perf_counter()
    warm = random_problem(2, 5, 2, 1, seed=99)
    solve(warm, "greedy")
    solve(warm, "tree", time_limit=0.2)
    load = time.perf_counter() - t0
    rows = []
    for seed in args.seeds:
        t0 = time.perf_counter()
        p = random_problem(A, T, Z, K, seed=seed, start_zones=True)
        build = time.perf_counter() - t0
        t0 = time.perf_counter()
        compiled(p)  # compile the problem for the kernel (part of the first schedule)
        g = solve(p, "greedy", seed=seed)
        first = time.perf_counter() - t0
        assert g.schedule is not None and validate(p, g.schedule) == g.objective
        t0 = time.perf_counter()
        lb = lower_bound(p)
        lb_time = time.perf_counter() - t0
        tree = solve(p, "tree", time_limit=args.time_limit, seed=seed)
        assert tree.schedule is not None and validate(p, tree.schedule) == tree.objective
        rows.append(
            {
                "seed": seed,
                "build_s": build,
                "first_schedule_s": first,
                "first_makespan": g.objective,
                "tree_makespan": tree.objective,
                "tree_first_s": tree.stats.first_time,
                "lower_bound": lb,
                "lower_bound_s": lb_time,
                "greedy_gap_to_lb": (g.objective - lb) / lb,
                "tree_gap_to_lb": (tree.objective - lb) / lb,
                "evaluations": tree.stats.evaluations,
            }
        )
        print(rows[-1], flush=True)
    lines = [
        f"# Scale: {A} arms x {T} tasks x {Z} zones x {K} tools",
        "",
        f"seeds {args.seeds}; tree time limit {args.time_limit:g} s; kernel compile/cache load once per process: "
        f"{load:.2f} s (not in the times below).",
        "",
        "| seed | build s | first schedule s | first makespan | tree makespan | lower bound | first gap to LB | "
        "tree gap to LB | tree evaluations |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['seed']} | {r['build_s']:.2f} | {r['first_schedule_s']:.3f} | {r['first_makespan']:.0f} | "
            f"{r['tree_makespan']:.0f} | {r['lower_bound']:.1f} | {100 * r['greedy_gap_to_lb']:.1f}% | "
            f"{100 * r['tree_gap_to_lb']:.1f}% | {r['evaluations']} |"
        )
    lines += [
        "",
        f"- first valid schedule: mean {np.mean([r['first_schedule_s'] for r in rows]):.3f} s, "
        f"max {np.max([r['first_schedule_s'] for r in rows]):.3f} s (target: under 1 s)",
    ]
    path = write(
        "scale",
        {
            "size": args.size,
            "seeds": args.seeds,
            "time_limit": args.time_limit,
            "kernel_load_s": load,
            "rows": rows,
        },
        "\n".join(lines) + "\n",
    )
    print(path.read_text())


if __name__ == "__main__":
    main()
