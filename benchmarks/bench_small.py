"""Small zone-constrained problems: time to optimal and final makespan, tree vs CP-SAT.

About 20 problems from :func:`scheduler.generate.random_problem` (2-3 arms,
8-14 tasks, exclusive and shared zones, a tool, travel setups; half with arms
starting in exclusive zones), each solved by ``tree`` and ``cpsat`` (1 worker)
at the same time limit. Time to optimal is when the solver proved its
schedule optimal (status ``optimal``: its runtime, as it stops there); "-"
when it did not within the limit. Results: ``benchmarks/results/small.json``
and ``small.md``.

Run: ``python -m benchmarks.bench_small [--time-limit 5] [--quick]``.
"""

from __future__ import annotations

import argparse
from typing import Any

from benchmarks.common import write
from scheduler import CpSatOptions, solve, validate
from scheduler.generate import random_problem

# (arms, tasks, zones, tools, start_zones), seeds
CASES = [
    ((2, 8, 3, 1, False), (0, 1, 2)),
    ((2, 10, 3, 1, True), (0, 1, 2)),
    ((3, 10, 4, 1, False), (0, 1, 2)),
    ((3, 12, 4, 1, True), (0, 1, 2)),
    ((3, 14, 4, 1, False), (0, 1, 2, 3)),
    ((2, 12, 4, 1, True), (0, 1, 2, 3)),
]


def main(argv: list[str] | None = None) -> None:
    """Run the benchmark and write the tables.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--time-limit", type=float, default=5.0)
    ap.add_argument("--quick", action="store_true", help="one seed per size, 1 s")
    args = ap.parse_args(argv)
    limit = 1.0 if args.quick else args.time_limit
    rows: list[dict[str, Any]] = []
    for (arms, tasks, zones, tools, sz), seeds in CASES:
        for seed in seeds[:1] if args.quick else seeds:
            p = random_problem(arms, tasks, zones, tools, seed=seed, start_zones=sz)
            row: dict[str, Any] = {
                "size": f"{arms}x{tasks}x{zones}{' sz' if sz else ''}",
                "seed": seed,
            }
            for name in ("tree", "cpsat"):
                opts = CpSatOptions(workers=1) if name == "cpsat" else None
                r = solve(p, name, time_limit=limit, seed=0, options=opts)
                if r.schedule is not None:
                    validate(p, r.schedule)
                row[name] = {
                    "status": r.status.value,
                    "objective": r.objective,
                    "bound": r.bound,
                    "runtime": r.runtime,
                    "to_optimal": r.runtime if r.status.value == "optimal" else None,
                }
            rows.append(row)
            t, c = row["tree"], row["cpsat"]
            print(
                f"{row['size']:>14} seed {seed}: tree {t['objective']:g} {t['status']} "
                f"{t['runtime']:.2f}s | cpsat {c['objective']:g} {c['status']} {c['runtime']:.2f}s",
                flush=True,
            )

    def fmt(x: float | None) -> str:
        return "-" if x is None else f"{x:.2f}"

    lines = [
        "# Small zone problems: tree vs CP-SAT (1 worker)",
        "",
        f"Time limit {limit:g} s per solver and problem, solver seed 0; problems from "
        "`random_problem(arms, tasks, zones, tools, seed, start_zones=sz)`. Time to optimal: "
        "seconds until the solver proved optimality ('-': not within the limit).",
        "",
        "| problem | seed | tree makespan | tree status | tree to optimal (s) "
        "| CP-SAT makespan | CP-SAT status | CP-SAT to optimal (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        t, c = row["tree"], row["cpsat"]
        lines.append(
            f"| {row['size']} | {row['seed']} | {t['objective']:g} | {t['status']} "
            f"| {fmt(t['to_optimal'])} | {c['objective']:g} | {c['status']} | {fmt(c['to_optimal'])} |"
        )
    worse = sum(r["tree"]["objective"] > r["cpsat"]["objective"] + 1e-9 for r in rows)
    proven_t = sum(r["tree"]["status"] == "optimal" for r in rows)
    proven_c = sum(r["cpsat"]["status"] == "optimal" for r in rows)
    lines += [
        "",
        f"tree worse than CP-SAT on {worse} of {len(rows)}; proven optimal: tree {proven_t}, "
        f"CP-SAT {proven_c}.",
        "",
    ]
    path = write("small", {"time_limit": limit, "rows": rows}, "\n".join(lines))
    print(path)


if __name__ == "__main__":
    main()
