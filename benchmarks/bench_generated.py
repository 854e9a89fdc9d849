"""Zone-constrained problems from the seeded generator: gaps to CP-SAT.

Problems come from :func:`scheduler.generate.random_problem` (arms of
different speeds and capabilities, precedence, releases, exclusive and shared
zones, tools, travel setups). CP-SAT gets a long limit to prove optima; tree
and greedy get the short one. Where CP-SAT proved its schedule optimal, the
gap is to the optimum; elsewhere to CP-SAT's best bound (and tree is also
compared with CP-SAT's schedule at the long limit). Results:
``benchmarks/results/generated.json`` and ``generated.md``.

Run: ``python -m benchmarks.bench_generated [--time-limit 10] [--reference-limit 60]
[--seeds 0 1 2] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import numpy as np

from benchmarks.common import RESULTS, write
from scheduler import solve, validate
from scheduler.generate import random_problem

# (arms, tasks, zones, tools) and the seeds run at that size: the small sizes,
# which CP-SAT can prove, get more seeds
SIZES = [
    ((2, 8, 2, 1), (0, 1, 2, 3, 4)),
    ((3, 12, 3, 1), (0, 1, 2, 3, 4)),
    ((2, 10, 2, 1), (0, 1, 2)),
    ((3, 20, 4, 1), (0, 1, 2)),
    ((4, 40, 6, 2), (0, 1, 2)),
    ((6, 100, 8, 2), (0, 1, 2)),
    ((8, 200, 12, 3), (0, 1, 2)),
]


def _num(x: float) -> str:
    """A makespan, or "none" when the solver returned no schedule."""
    return f"{x:.0f}" if math.isfinite(x) else "none"


def _pct(x: float, sign: bool = False) -> str:
    """A ratio as a percentage, or "-" when one side has no schedule."""
    if not math.isfinite(x):
        return "-"
    return f"{100 * x:+.2f}%" if sign else f"{100 * x:.2f}%"


def report(rows: list[dict[str, Any]], time_limit: float, reference_limit: float) -> str:
    """The markdown table and summary of the rows."""
    lines = [
        "# Zone-constrained generated problems",
        "",
        f"tree, cpsat (short) and greedy: {time_limit:g} s; reference CP-SAT: {reference_limit:g} s; "
        "seeds per size as listed; size = arms x tasks x zones x tools. Target = the reference's optimum when "
        "proven, else its best bound (then gaps are upper bounds on the true gaps).",
        "",
        "| size | seed | optimal? | target | reference | tree | cpsat short | greedy | tree gap | cpsat short gap | "
        "tree vs reference |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['size']} | {r['seed']} | {'yes' if r['proven_optimal'] else 'no'} | {r['target']:.1f} | "
            f"{_num(r['reference'])} | {_num(r['tree'])} | {_num(r['cpsat_short'])} | {_num(r['greedy'])} | "
            f"{_pct(r['tree_gap'])} | {_pct(r['cpsat_short_gap'])} | {_pct(r['tree_vs_reference'], sign=True)} |"
        )
    opt = [r for r in rows if r["proven_optimal"]]
    lines.append("")
    if opt:
        lines.append(
            f"- on the {len(opt)} problems CP-SAT solved to optimality: mean gap of tree "
            f"{100 * np.mean([r['tree_gap'] for r in opt]):.2f}%, of CP-SAT at {time_limit:g} s "
            f"{100 * np.mean([r['cpsat_short_gap'] for r in opt]):.2f}%, of greedy "
            f"{100 * np.mean([r['greedy_gap'] for r in opt]):.2f}%"
        )
    rest = [r for r in rows if not r["proven_optimal"]]
    with_ref = [r for r in rest if math.isfinite(r["tree_vs_reference"])]
    if with_ref:
        lines.append(
            f"- on the other {len(rest)}, where CP-SAT found a schedule in {reference_limit:g} s "
            f"({len(with_ref)}): tree {100 * np.mean([r['tree_vs_reference'] for r in with_ref]):+.2f}% "
            "against it on average (negative: tree is shorter)"
        )
    if len(with_ref) < len(rest):
        lines.append(
            f"- CP-SAT found no schedule within {reference_limit:g} s on {len(rest) - len(with_ref)} problems"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--time-limit", type=float, default=10.0, help="tree and greedy, seconds")
    ap.add_argument("--reference-limit", type=float, default=60.0, help="CP-SAT, seconds")
    ap.add_argument("--seeds", type=int, nargs="+", help="override the seeds of every size")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument(
        "--report-only", action="store_true", help="rebuild the markdown from the saved JSON"
    )
    args = ap.parse_args(argv)
    if args.report_only:
        data = json.loads((RESULTS / "generated.json").read_text())
        (RESULTS / "generated.md").write_text(
            report(data["rows"], data["time_limit"], data["reference_limit"])
        )
        print((RESULTS / "generated.md").read_text())
        return
    sizes = [(s, tuple(args.seeds) if args.seeds else seeds) for s, seeds in SIZES]
    if args.quick:
        sizes, args.time_limit, args.reference_limit = [(SIZES[0][0], (0,))], 1.0, 2.0
    rows = []
    for (arms, tasks, zones, tools), seeds in sizes:
        for seed in seeds:
            p = random_problem(arms, tasks, zones, tools, seed=seed)
            ref = solve(p, "cpsat", time_limit=args.reference_limit, seed=seed)
            tree = solve(p, "tree", time_limit=args.time_limit, seed=seed)
            cp_short = solve(p, "cpsat", time_limit=args.time_limit, seed=seed)
            greedy = solve(p, "greedy", seed=seed)
            for r in (ref, tree, cp_short, greedy):
                if r.schedule is not None:
                    assert validate(p, r.schedule) == r.objective
            optimal = ref.status.value == "optimal"
            target = ref.objective if optimal else ref.bound
            row = {
                "size": f"{arms}x{tasks}x{zones}x{tools}",
                "seed": seed,
                "proven_optimal": optimal,
                "reference": ref.objective,
                "reference_bound": ref.bound,
                "target": target,
                "tree": tree.objective,
                "tree_status": tree.status.value,
                "cpsat_short": cp_short.objective,
                "greedy": greedy.objective,
                "tree_first_time": tree.stats.first_time,
                "tree_gap": (tree.objective - target) / target if target > 0 else 0.0,
                "cpsat_short_gap": (cp_short.objective - target) / target if target > 0 else 0.0,
                "greedy_gap": (greedy.objective - target) / target if target > 0 else 0.0,
                "tree_vs_reference": (tree.objective - ref.objective) / ref.objective
                if math.isfinite(ref.objective)
                else math.nan,
            }
            rows.append(row)
            print(
                row["size"],
                seed,
                f"opt={optimal}",
                f"ref={ref.objective:.0f}",
                f"tree={tree.objective:.0f}",
                f"cp{args.time_limit:g}={cp_short.objective:.0f}",
                f"greedy={greedy.objective:.0f}",
                flush=True,
            )
    text = report(rows, args.time_limit, args.reference_limit)
    path = write(
        "generated",
        {
            "time_limit": args.time_limit,
            "reference_limit": args.reference_limit,
            "seed": args.seeds,
            "rows": rows,
        },
        text,
    )
    print(path.read_text())


if __name__ == "__main__":
    main()
