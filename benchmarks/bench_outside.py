"""Zone problems from two families the solvers were not developed on: tree against CP-SAT.

A thin wrapper of the sweep ``benchmarks/sweeps/outside.toml``: problems
from :mod:`scheduler.families` (``routes``: a flexible job shop whose
operations enter zones for part of their time; ``stations``: assembly kits
at exclusive stations behind shared corridors, with travel setups), 2-6
arms, 20-100 tasks, 2-6 zones, 0-2 tools, waits on and off, each solved by
``tree`` and ``cpsat`` at the same wall budget on the same 2 cores. Per
problem the table gives both makespans and statuses, the time each found
its final schedule and, when it proved it optimal, the time of the proof
(its runtime, as it stops there); per family how often the tree is behind
CP-SAT, and the tree's mean gap to CP-SAT's proven optima. It runs the
sweep (resuming; ``--fresh`` to start over) into
``benchmarks/results/outside.parquet`` and writes :func:`outside_table` to
``outside.md`` and ``outside.json``.

Run: ``python -m benchmarks.bench_outside [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

from benchmarks.common import output_dir, publish, run_table_sweep, sweep_arguments

NAME = "outside"


def _fmt(x: float) -> str:
    return f"{x:g}" if math.isfinite(x) else "none"


def outside_table(df: Any, *, sweep: str = NAME, tree: str = "tree", cpsat: str = "cpsat") -> str:
    """The Markdown table of ``benchmarks/results/outside.md`` from the sweep's results.

    Parameters
    ----------
    df : pandas.DataFrame
        Results of ``sweeps/<sweep>.toml`` (one run per instance and label).
    sweep : str
        The sweep file's stem (named in the heading).
    tree, cpsat : str
        The two solver labels compared.

    Returns
    -------
    str
        Markdown: per family a table of both solvers' makespans, statuses,
        time of their final schedule and of their proof, and the summary
        lines (behind / ahead / equal, proven optima reached, mean gap).
    """
    a = df[df["label"] == tree].set_index(["family", "instance"])
    b = df[df["label"] == cpsat].set_index(["family", "instance"])
    limit = float(df["time_limit"].max())
    lines = [
        f"# Zone problems from other generators: {tree} vs {cpsat}",
        "",
        f"{limit:g} s per solver and problem, both on the machine's 2 cores (sweep "
        f"`benchmarks/sweeps/{sweep}.toml`); size = arms x tasks x zones x tools, '-nowait': "
        "solved with `waits=False`. 'found': seconds to the final schedule; 'proof': seconds "
        "to the proof of optimality (the run ends there; '-': none within the limit).",
    ]
    total_behind = total = 0
    for family in sorted({k[0] for k in a.index}):
        keys = sorted(
            (k for k in a.index if k[0] == family and k in b.index),
            key=lambda k: (json.loads(str(a.loc[k]["instance_params"]))["tasks"], k[1]),
        )
        lines += [
            "",
            f"## {family}",
            "",
            f"| problem | {tree} | status | found | proof | {cpsat} | status | found | proof | "
            "difference |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        behind = ahead = 0
        closed: list[tuple[float, float, float, float]] = []  # (tree mk, optimum, proofs)
        for k in keys:
            ra, rb = a.loc[k], b.loc[k]
            ma, mb = float(ra["makespan"]), float(rb["makespan"])
            cells = []
            for r in (ra, rb):
                found = float(r["best_time"]) if math.isfinite(float(r["makespan"])) else math.nan
                proof = f"{float(r['runtime']):.2f}" if r["status"] == "optimal" else "-"
                cells.append(
                    f"{_fmt(float(r['makespan']))} | {r['status']} | {found:.2f} | {proof}"
                    if math.isfinite(found)
                    else f"none | {r['status']} | - | -"
                )
            if ma > mb + 1e-9:
                behind += 1
            elif ma < mb - 1e-9:
                ahead += 1
            diff = (
                (ma - mb) / mb if math.isfinite(ma) and math.isfinite(mb) and mb > 0 else math.nan
            )
            dtxt = f"{100 * diff:+.2f}%" if math.isfinite(diff) else "-"
            lines.append(f"| {k[1]} | " + " | ".join(cells) + f" | {dtxt} |")
            if rb["status"] == "optimal":
                proof_a = float(ra["runtime"]) if ra["status"] == "optimal" else math.nan
                closed.append((ma, mb, proof_a, float(rb["runtime"])))
        n = len(keys)
        total += n
        total_behind += behind
        lines += [
            "",
            f"- {tree} behind {cpsat} at the same {limit:g} s on {behind} of {n}, ahead on "
            f"{ahead}, equal on {n - behind - ahead}",
        ]
        if closed:
            hit = sum(ma <= opt + 1e-9 for ma, opt, _, _ in closed)
            proved = [pa for _, _, pa, _ in closed if math.isfinite(pa)]
            gap = sum((ma - opt) / opt for ma, opt, _, _ in closed) / len(closed)
            cp_mean = sum(pb for _, _, _, pb in closed) / len(closed)
            lines.append(
                f"- {cpsat} proved {len(closed)} of {n} optimal (mean time to the proof "
                f"{cp_mean:.2f} s); on those {tree} returns the optimum on {hit}, proves it on "
                f"{len(proved)}"
                + (f" (mean {sum(proved) / len(proved):.2f} s)" if proved else "")
                + f", mean gap {100 * gap:.2f}%"
            )
    lines += ["", f"All: {tree} behind {cpsat} on {total_behind} of {total}."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sweep_arguments(ap)
    args = ap.parse_args(argv)
    out = output_dir(args.quick)
    df = run_table_sweep(NAME, args, out)
    path = publish(NAME, df, outside_table(df), out, quick=args.quick, flags="--fresh")
    print(path.read_text())


if __name__ == "__main__":
    main()
