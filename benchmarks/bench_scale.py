"""Scale: the first schedule and its quality at 16 arms x 1000 tasks x 30 zones.

A thin wrapper of the sweep ``benchmarks/sweeps/scale.toml``: on seeded
generated problems, the greedy run is the first valid schedule (the
earliest-finish-time list schedule that also starts the tree search; its
``build_time`` is building the problem, its ``runtime`` the time to the
first schedule, measured warm: the compiled kernel is loaded before the
clock, reported apart as ``warmup_time``), then the tree search's schedule
after the time limit, and the lower bound. It runs the sweep (resuming;
``--fresh`` to start over) into ``benchmarks/results/scale.parquet`` and
writes the table of :func:`workcell.experiments.analysis.scale_table` to
``scale.md`` and ``scale.json``, followed by every part of
:func:`scheduler.lower_bounds` per problem (:func:`bounds_table`, the
problems built again from the sweep's rows) and the tree's gap to each.

Run: ``python -m benchmarks.bench_scale [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

import json
import time
from typing import Any

from benchmarks.common import table_main

NAME = "scale"

PARTS = ("critical_path", "load", "capability", "resources", "one_machine")
"""The parts of :class:`scheduler.bounds.LowerBounds` in the table, in its column order."""


def bounds_table(df: Any, tree: str = "tree") -> str:
    """Every part of the lower bound of each problem, its cost, and the tree's gap to it.

    Parameters
    ----------
    df : pandas.DataFrame
        The sweep's results (the ``tree`` rows give the problems and makespans).
    tree : str
        The tree's solver label.

    Returns
    -------
    str
        Markdown.
    """
    from scheduler import lower_bounds
    from scheduler.generate import generate_problem

    rows = df[df["label"] == tree].sort_values("instance_seed")
    lines = [
        "",
        "## Lower bounds, part by part (`scheduler.lower_bounds`)",
        "",
        "critical path: releases, availability and travel into each mode, chains at "
        "their shortest modes; load LP: arms and every zone, movement and tool in one LP; "
        "capability: capability subsets; resources: head-body-tail per zone, movement and "
        "tool; one-machine: the preemptive one-machine (Jackson) bound of each. bound s: "
        "the wall time of `lower_bounds` (warm, in this process). The plans' time goes to "
        "travel, not to waiting: `benchmarks/results/gap_anatomy.md` "
        "(`python -m benchmarks.gap_anatomy`).",
        "",
        "| seed | critical path | load LP | capability | resources | one-machine | lower bound "
        "| bound s | tree makespan | tree gap |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for _, r in rows.iterrows():
        params = dict(json.loads(str(r["instance_params"])))
        params.pop("waits", None)
        p = generate_problem(
            params.pop("generator", "zones"),
            params.pop("arms"),
            params.pop("tasks"),
            params.pop("zones"),
            params.pop("tools"),
            seed=int(r["instance_seed"]),
            **params,
        )
        lower_bounds(p)  # imports and caches outside the clock
        t0 = time.perf_counter()
        lb = lower_bounds(p)
        took = time.perf_counter() - t0
        ms = float(r["makespan"])
        lines.append(
            f"| {int(r['instance_seed'])} | "
            + " | ".join(f"{getattr(lb, k):.1f}" for k in PARTS)
            + f" | {lb.value:.1f} | {took:.2f} | {ms:.0f} | {100 * (ms - lb.value) / lb.value:.1f}% |"
        )
    return "\n".join(lines) + "\n"


def _render(df: Any) -> str:
    from workcell.experiments.analysis import scale_table

    return str(scale_table(df)) + bounds_table(df)


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    table_main(NAME, _render, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
