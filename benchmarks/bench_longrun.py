"""The tree search on the built-in cells with more time: how much of each gap is the plan's.

The cells table (``bench_cells``) gives the tree's plan at 10 s next to the
best bound of each cell. A gap there is the plan's, the bound's, or both.
This benchmark runs the tree on ``supersigma``, ``scara4`` and ``cell8`` in
independent runs at 10 s, 60 s and 300 s (seed 0, the default options, so
two processes on the machine's two cores), sweep
``benchmarks/sweeps/longrun.toml``, and writes, per cell:

* the makespans of the three runs and their gaps to the best bound (the
  ``best bound (s)`` of ``results/cells.json``'s reference table when it is
  there, else :func:`scheduler.lower_bound`, the runner's ``lower_bound``);
* the best schedule known (the shortest of these runs and of the exact
  search's schedule in ``cells.json``), and the share of the 10 s plan's gap
  to the bound that a longer search closes: that share is the 10 s plan's
  fault, whatever the bound;
* the improvement curve of the 300 s run (the best makespan found by 1, 2,
  5, ..., 300 s). The curve holds the main process's improvements as they
  came and a worker process's best only at the moment it was found (a
  worker reports once, at the end), so it may lie above what the search
  held at a moment, never below (likewise a last phase of the tree, e.g.
  its exact polish, which records its schedule as it ends);
* ``docs/images/longrun.png`` (``longrun.png`` in the temporary directory
  with ``--quick``): the curves as makespan over the best bound, with the
  independent runs as dots.

Run: ``python -m benchmarks.bench_longrun [--fresh] [--quick]`` (about 19
minutes; ``--quick``: the small cells at 1 s into a temporary directory).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from benchmarks.common import RESULTS, output_dir, publish, run_table_sweep, sweep_arguments

NAME = "longrun"
DOCS_PLOT = Path(__file__).resolve().parents[1] / "docs" / "images" / "longrun.png"
"""Where the plot goes (not with ``--quick``)."""
CHECKPOINTS = (1.0, 2.0, 5.0, 10.0, 30.0, 60.0, 120.0, 300.0)
"""Seconds at which the improvement curve of the longest run is read."""


def reference_of(cells_json: Path) -> dict[str, dict[str, Any]]:
    """Per cell, the reference row of ``cells.json`` (empty when the file is missing).

    Parameters
    ----------
    cells_json : Path

    Returns
    -------
    dict
    """
    if not cells_json.is_file():
        return {}
    data = json.loads(cells_json.read_text())
    return {str(r["cell"]): r for r in data.get("reference", [])}


def _number(v: Any) -> float | None:
    """``v`` as a finite float, else None (the cells table writes '-' for none)."""
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def best_at(improvements: list[list[float]], t: float) -> float | None:
    """The best makespan found by ``t`` seconds (None: nothing yet).

    Parameters
    ----------
    improvements : list of [seconds, makespan]
    t : float

    Returns
    -------
    float or None

    Examples
    --------
    >>> best_at([[0.1, 9.0], [2.0, 7.0], [1.0, 8.0]], 1.5)
    8.0
    >>> best_at([[0.1, 9.0]], 0.05) is None
    True
    """
    found = [mk for s, mk in improvements if s <= t]
    return min(found) if found else None


def summarise(df: Any, reference: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    """One record per cell: the runs, the bound, the best known and the gap's split.

    Parameters
    ----------
    df : pandas.DataFrame
        The sweep's results.
    reference : dict
        :func:`reference_of` the cells table.

    Returns
    -------
    list of dict
    """
    out = []
    for cell, rows in df.groupby("instance", sort=False):
        rows = rows.sort_values("time_limit")
        ref = reference.get(str(cell), {})
        bound = _number(ref.get("best bound (s)"))
        source = "cells.md best bound" if bound is not None else "lower_bound"
        if bound is None:
            bound = float(rows["lower_bound"].max())
        runs = {
            float(r["time_limit"]): float(r["makespan"])
            for _, r in rows.iterrows()
            if _number(r["makespan"]) is not None
        }
        exact = _number(ref.get("exact (s)"))
        if ref.get("proven?") == "yes" and exact is not None:
            bound = exact  # the proven optimum (the table rounds its bound to 10 ms)
        candidates = list(runs.values()) + ([exact] if exact is not None else [])
        best = min(candidates) if candidates else math.nan
        best_from = (
            "exact search (cells.md)"
            if exact is not None and best == exact and exact < min(runs.values(), default=math.inf)
            else "these runs"
        )
        longest = rows.iloc[-1]
        curve_raw = json.loads(longest["improvements"]) if longest["improvements"] else []
        limit = float(longest["time_limit"])
        # at the limit: everything the run returned (a last phase, e.g. the tree's
        # exact polish, records its schedule as it ends, a moment past the limit)
        curve = {
            t: best_at(curve_raw, t if t < limit else math.inf) for t in CHECKPOINTS if t <= limit
        }
        first = runs.get(min(runs), math.nan) if runs else math.nan
        closed = (
            (first - best) / (first - bound)
            if runs and first - bound > 1e-9 and best >= bound - 1e-9
            else math.nan
        )
        out.append(
            {
                "cell": str(cell),
                "tasks": int(rows["n_tasks"].iloc[0]),
                "bound": bound,
                "bound_source": source,
                "proven": ref.get("proven?") == "yes",
                "runs": runs,
                "best_known": best,
                "best_from": best_from,
                "shortest_above_best": (first - best) / best if runs else math.nan,
                "share_of_gap_closed": closed,
                "curve": curve,
                "curve_raw": curve_raw,
                "curve_limit": float(longest["time_limit"]),
            }
        )
    return out


def _pct(x: float) -> str:
    """A share as a percentage ('-': none); below 0 only by rounding, so shown as 0."""
    return "-" if not math.isfinite(x) else f"{100 * max(x, 0.0):.1f}%"


def render(cells: list[dict[str, Any]], png: str | None) -> str:
    """The Markdown tables of :func:`summarise`'s records.

    Parameters
    ----------
    cells : list of dict
    png : str or None
        The plot's file name, if drawn.

    Returns
    -------
    str
    """
    limits = sorted({t for c in cells for t in c["runs"]})
    head = " | ".join(f"tree {t:g} s | gap" for t in limits)
    lines = [
        "# The tree search with more time on the built-in cells",
        "",
        "Independent runs of the tree search (seed 0, default options: two processes on "
        "the machine's two cores), makespans in seconds, validated. Gap: to the best "
        "bound. Best known: the shortest of these runs and of the exact search's schedule "
        "(cells.md). Shortest run above best: how far the shortest run's plan is from "
        "the best schedule known. Gap closed: the share of the shortest run's gap to the bound "
        "that the best schedule known closes, i.e. at least that much of it is the short "
        "plan's fault, whatever the bound; the rest lies between the best schedule known "
        "and the bound, the plan's or the bound's.",
        "",
        f"| cell | tasks | best bound | bound source | proven? | {head} | best known | "
        "from | shortest run above best | gap closed |",
        "|---|---|---|---|---|" + "---|---|" * len(limits) + "---|---|---|---|",
    ]
    for c in cells:
        cols = []
        for t in limits:
            mk = c["runs"].get(t)
            cols.append("-" if mk is None else f"{mk:.2f} | {_pct((mk - c['bound']) / c['bound'])}")
        lines.append(
            f"| {c['cell']} | {c['tasks']} | {c['bound']:.2f} | {c['bound_source']} | "
            f"{'yes' if c['proven'] else 'no'} | "
            + " | ".join(cols)
            + f" | {c['best_known']:.2f} | {c['best_from']} | "
            f"{_pct(c['shortest_above_best'])} | {_pct(c['share_of_gap_closed'])} |"
        )
    cps = [t for t in CHECKPOINTS if any(t in c["curve"] for c in cells)]
    lines += [
        "",
        "## The longest run's improvement curve (best makespan found by each moment, s)",
        "",
        "A worker process reports its best once, at the end, with the moment it found "
        "it, and the tree's last phase (a polish) records its schedule as the phase "
        "ends (the last column holds everything the run returned): earlier "
        "improvements are not in the curve, so it may lie above what the search held "
        "at a moment, never below. '-': no schedule yet.",
        "",
        "| cell | run (s) | " + " | ".join(f"{t:g} s" for t in cps) + " |",
        "|---|---|" + "---|" * len(cps),
    ]
    for c in cells:
        vals = []
        for t in cps:
            v = c["curve"].get(t)
            vals.append("-" if v is None else f"{v:.2f}")
        lines.append(f"| {c['cell']} | {c['curve_limit']:g} | " + " | ".join(vals) + " |")
    if png:
        lines += ["", f"Plot of the curves over the best bound: `{png}`."]
    return "\n".join(lines) + "\n"


def plot(cells: list[dict[str, Any]], path: Path) -> None:
    """Draw each cell's curve (makespan over its best bound, log time) and its runs.

    Parameters
    ----------
    cells : list of dict
        :func:`summarise`'s records.
    path : Path
        The PNG to write.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.2))
    for c in cells:
        pts = sorted((s, mk) for s, mk in c["curve_raw"] if s > 0)
        xs, ys, cur = [], [], math.inf
        for s, mk in pts:
            cur = min(cur, mk)
            xs.append(s)
            ys.append(cur / c["bound"])
        if xs:
            xs.append(c["curve_limit"])
            ys.append(ys[-1])
            (line,) = ax.step(xs, ys, where="post", label=c["cell"])
            colour = line.get_color()
        else:
            colour = None
        rx = sorted(c["runs"])
        ax.plot(rx, [c["runs"][t] / c["bound"] for t in rx], "o", color=colour)
    ax.axhline(1.0, color="grey", lw=0.8, ls="--")
    ax.set_xscale("log")
    ax.set_xlabel("seconds (log)")
    ax.set_ylabel("makespan / best bound")
    ax.set_title("Tree search on the built-in cells: the 300 s run's curve, runs as dots")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    """Run the sweep (resuming unless ``--fresh``) and write the tables and the plot.

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
    cells = summarise(df, reference_of(RESULTS / "cells.json"))
    png = out / f"{NAME}.png" if args.quick else DOCS_PLOT
    png.parent.mkdir(parents=True, exist_ok=True)
    plot(cells, png)
    where = png.name if args.quick else str(png.relative_to(DOCS_PLOT.parents[2]))
    path = publish(
        NAME,
        df,
        render(cells, where),
        out,
        quick=args.quick,
        flags="--fresh",
        extra={
            "plot": where,
            "cells": [{k: v for k, v in c.items() if k != "curve_raw"} for c in cells],
        },
    )
    print(path.read_text())


if __name__ == "__main__":  # pragma: no cover
    main()
