"""FJSP benchmark: Brandimarte MK01-MK10 and Fattahi SFJS/MFJS with every solver.

Each solver gets the same time limit and seed on every instance; makespans
are the ones :func:`scheduler.validate` computes. Gaps are to the best-known
makespans of ``../shared/data/fjsp/README.md`` (for mk10 also to its soft
lower bound 189). Results: ``benchmarks/results/fjsp.json`` and ``fjsp.md``.

Run: ``python -m benchmarks.bench_fjsp [--time-limit 10] [--seed 0]
[--sets brandimarte fattahi] [--solvers tree greedy cpsat] [--quick]``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from benchmarks.common import write
from scheduler import lower_bound, read_fjsp, solve, validate

SHARED = Path(os.environ.get("MULTIARM_SHARED", Path(__file__).resolve().parents[2] / "shared"))
DATA = SHARED / "data" / "fjsp"

# best-known makespans (README of ../shared/data/fjsp)
BKS = {
    "mk01": 40,
    "mk02": 26,
    "mk03": 204,
    "mk04": 60,
    "mk05": 172,
    "mk06": 57,
    "mk07": 139,
    "mk08": 523,
    "mk09": 307,
    "mk10": 193,
    "sfjs01": 66,
    "sfjs02": 107,
    "sfjs03": 221,
    "sfjs04": 355,
    "sfjs05": 119,
    "sfjs06": 320,
    "sfjs07": 397,
    "sfjs08": 253,
    "sfjs09": 210,
    "sfjs10": 516,
    "mfjs01": 468,
    "mfjs02": 446,
    "mfjs03": 466,
    "mfjs04": 554,
    "mfjs05": 514,
    "mfjs06": 634,
    "mfjs07": 879,
    "mfjs08": 884,
    "mfjs09": 1055,
    "mfjs10": 1196,
}


def instances(sets: list[str]) -> list[Path]:
    out = []
    for s in sets:
        out += sorted((DATA / s).glob("*.fjs"))
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--time-limit", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sets", nargs="+", default=["brandimarte", "fattahi"])
    ap.add_argument("--solvers", nargs="+", default=["tree", "greedy", "cpsat"])
    ap.add_argument("--instances", nargs="*", help="only these (e.g. mk01 mk06)")
    ap.add_argument("--quick", action="store_true", help="two instances, 1 s each (smoke run)")
    args = ap.parse_args(argv)
    if not DATA.is_dir():
        raise SystemExit(f"FJSP data not found at {DATA} (set MULTIARM_SHARED)")
    paths = instances(args.sets)
    if args.instances:
        paths = [p for p in paths if p.stem in args.instances]
    if args.quick:
        paths = [p for p in paths if p.stem in ("sfjs01", "mk01")]
        args.time_limit = 1.0
    rows = []
    for path in paths:
        p = read_fjsp(path)
        row: dict[str, object] = {
            "instance": path.stem,
            "set": path.parent.name,
            "tasks": p.n_tasks,
            "arms": p.n_arms,
            "bks": BKS[path.stem],
            "lb": lower_bound(p),
        }
        for s in args.solvers:
            r = solve(p, s, time_limit=args.time_limit, seed=args.seed)  # type: ignore[arg-type]
            mk = validate(p, r.schedule) if r.schedule is not None else float("inf")
            row[s] = {
                "makespan": mk,
                "status": r.status.value,
                "bound": r.bound,
                "runtime": r.runtime,
                "first_time": r.stats.first_time,
                "best_time": r.stats.best_time,
                "gap": (mk - BKS[path.stem]) / BKS[path.stem],
            }
        rows.append(row)
        print(
            path.stem, " ".join(f"{s}={row[s]['makespan']:.0f}" for s in args.solvers), flush=True
        )  # type: ignore[index]
    lines = [
        "# FJSP benchmark",
        "",
        f"Time limit {args.time_limit:g} s per solver and instance, seed {args.seed}, 2 cores (CP-SAT uses 2 "
        "workers, tree 2 processes (TreeOptions.workers), greedy one). Makespans validated. Gap = (makespan - best known) / best known.",
        "",
        "| instance | tasks | arms | BKS | our LB | "
        + " | ".join(f"{s} (gap, first s, best s)" for s in args.solvers)
        + " |",
        "|---|---|---|---|---|" + "---|" * len(args.solvers),
    ]
    for row in rows:
        cells = []
        for s in args.solvers:
            d = row[s]  # type: ignore[index]
            cells.append(
                f"{d['makespan']:.0f} ({100 * d['gap']:.1f}%, {d['first_time']:.2f}, {d['best_time']:.2f})"
            )
        lines.append(
            f"| {row['instance']} | {row['tasks']} | {row['arms']} | {row['bks']} | {row['lb']:.1f} | "
            + " | ".join(cells)
            + " |"
        )
    lines.append("")
    for st in sorted({str(r["set"]) for r in rows}):
        sub = [r for r in rows if r["set"] == st]
        means = {s: float(np.mean([r[s]["gap"] for r in sub])) for s in args.solvers}  # type: ignore[index]
        lines.append(
            f"- **{st}**: mean gap to BKS "
            + ", ".join(f"{s} {100 * m:.2f}%" for s, m in means.items())
            + f" ({len(sub)} instances)"
        )
        if "tree" in args.solvers and "cpsat" in args.solvers:
            better = sum(r["tree"]["makespan"] < r["cpsat"]["makespan"] for r in sub)  # type: ignore[index]
            worse = sum(r["tree"]["makespan"] > r["cpsat"]["makespan"] for r in sub)  # type: ignore[index]
            lines.append(
                f"  - tree better than cpsat on {better}, worse on {worse}, equal on {len(sub) - better - worse}"
            )
    mk10 = next((r for r in rows if r["instance"] == "mk10"), None)
    if mk10 is not None:
        lines.append(
            "- mk10 gap to its soft lower bound 189: "
            + ", ".join(f"{s} {100 * (mk10[s]['makespan'] - 189) / 189:.1f}%" for s in args.solvers)
        )  # type: ignore[index]
    path = write(
        "fjsp",
        {"time_limit": args.time_limit, "seed": args.seed, "rows": rows},
        "\n".join(lines) + "\n",
    )
    print(path.read_text())


if __name__ == "__main__":
    main()
