"""Lower bounds against proven optima: how far below the optimum each bound stays.

On generated problems whose few zones and a tool most tasks need (3 arms x 8
tasks, 2 zones, 1 tool, 90 % of the tasks in a zone, 30 % with the tool;
start zones on even seeds; seeds 0-29), CP-SAT's general model (waits at
borders allowed, one worker, 30 s) proves the optimum; the table gives the
mean gap of the optimum to :func:`scheduler.lower_bound` (no solver), to each
of its parts, and to the largest of it and
:func:`scheduler.resource_bound.busy_resources_bound` (10 s, one worker),
over the problems proven. Every bound must stay at or below every optimum
(the run stops otherwise).

Run: ``python -m benchmarks.bench_bounds [--quick]`` (writes
``benchmarks/results/bounds.md`` and ``.json``; ``--quick``: seeds 0-2 into a
temporary directory).
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from benchmarks.common import output_dir, write

PARTS = ("critical_path", "load", "capability", "resources", "one_machine")


def measure(seeds: list[int]) -> list[dict[str, Any]]:
    """One row per proven problem: the optimum and every bound (seconds)."""
    from scheduler import lower_bounds, solve
    from scheduler.generate import random_problem
    from scheduler.resource_bound import busy_resources_bound

    rows = []
    for seed in seeds:
        p = random_problem(
            3,
            8,
            2,
            1,
            seed=seed,
            zone_fraction=0.9,
            tool_fraction=0.3,
            start_zones=seed % 2 == 0,
        )
        r = solve(p, "cpsat", time_limit=30, workers=1)
        if r.status.value != "optimal":
            continue
        lb = lower_bounds(p)
        busy, status = busy_resources_bound(p, None, workers=1, max_deterministic_time=5.0)
        row = {"seed": seed, "optimum": r.objective, "lower_bound": lb.value, "busy": busy}
        row.update({k: getattr(lb, k) for k in PARTS})
        row["busy status"] = status
        if max(lb.value, busy) > r.objective + 1e-6:
            raise SystemExit(f"seed {seed}: a bound above the optimum: {row}")
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> None:
    """Measure and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="seeds 0-2, into a temporary directory")
    args = ap.parse_args(argv)
    seeds = list(range(3 if args.quick else 30))
    rows = measure(seeds)
    opt = np.array([r["optimum"] for r in rows])

    def gap(values: list[float]) -> str:
        return f"{100 * float(np.mean((opt - np.array(values)) / opt)):.1f}%"

    cols = [*PARTS, "lower_bound"]
    table = "\n".join(
        [
            "# Lower bounds against proven optima",
            "",
            f"3 arms x 8 tasks, 2 zones, 1 tool (zone_fraction 0.9, tool_fraction 0.3), "
            f"seeds {seeds[0]}-{seeds[-1]}: {len(rows)} proven by CP-SAT (30 s, one worker). "
            "Mean gap of the optimum to each bound (lower is tighter); busy resources: "
            "the largest of lower_bound and the busy-resources relaxation (CP-SAT, one "
            "worker, 5 deterministic units: repeatable). Reproduce: `python -m benchmarks.bench_bounds`.",
            "",
            "| " + " | ".join(cols) + " | busy resources |",
            "|---" * (len(cols) + 1) + "|",
            "| "
            + " | ".join(gap([r[k] for r in rows]) for k in cols)
            + f" | {gap([max(r['lower_bound'], r['busy']) for r in rows])} |",
            "",
        ]
    )
    path = write("bounds", {"seeds": seeds, "rows": rows}, table, output_dir(args.quick))
    print(table)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
