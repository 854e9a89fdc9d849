"""The spread of a solver table over seeds (``benchmarks/results/fjsp_seeds.md``).

:func:`seed_spread_table` renders the results of a sweep that runs each
solver with several seeds on instances with best-known makespans
(``benchmarks/sweeps/fjsp_seeds.toml``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from multiarm.errors import UsageError
from workcell.experiments.analysis.gaps import INSTANCE, need_columns
from workcell.experiments.analysis.tables import _fmt, _pct

__all__ = ["seed_spread_table"]


def seed_spread_table(df: Any, solvers: Sequence[str] = ("tree", "cpsat")) -> str:
    """The seed spread of ``benchmarks/results/fjsp_seeds.md`` from the results of ``sweeps/fjsp_seeds.toml``.

    Parameters
    ----------
    df : pandas.DataFrame
        Results with one run per (instance, solver label, seed), ``best_known`` set.
    solvers : sequence of str
        Solver labels, in column order (those with runs).

    Returns
    -------
    str
        Markdown: per instance each seed's makespan and their mean and range;
        per seed the mean gap to the best-known makespans over the instances;
        per solver the spread of that mean.

    Raises
    ------
    UsageError
        Without the columns it needs, or without runs of any of ``solvers``.

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({
    ...     "family": ["b"] * 4, "instance": ["m1", "m1", "m2", "m2"], "label": ["tree"] * 4,
    ...     "seed": [0, 1, 0, 1], "makespan": [10.0, 11.0, 20.0, 20.0],
    ...     "best_known": [10.0, 10.0, 20.0, 20.0], "time_limit": [1.0] * 4})
    >>> print(seed_spread_table(df).splitlines()[-3])
    | 1 | 5.00% |
    """
    need_columns(
        df,
        [*INSTANCE, "label", "seed", "makespan", "best_known", "time_limit"],
        "seed_spread_table",
    )
    asked = list(solvers)
    solvers = [s for s in asked if (df["label"] == s).any()]
    if not solvers:
        raise UsageError(f"seed_spread_table: no runs of the solvers {asked}")
    limits = sorted({float(v) for v in df["time_limit"].dropna()})
    seeds = sorted({int(v) for v in df["seed"].dropna()})
    keys = sorted({(str(f), str(i)) for f, i in zip(df["family"], df["instance"], strict=True)})
    mk: dict[tuple[str, str, str, int], float] = {}
    bks: dict[tuple[str, str], float] = {}
    for r in df.itertuples(index=False):
        key = (str(r.family), str(r.instance))
        mk[(str(r.label), *key, int(r.seed))] = float(r.makespan)
        bks[key] = float(r.best_known)
    if seeds == list(range(seeds[0], seeds[-1] + 1)):
        seed_txt = f"{seeds[0]}-{seeds[-1]}"
    else:
        seed_txt = ", ".join(map(str, seeds))
    lines = [
        "# FJSP: the spread over seeds",
        "",
        f"Time limit {', '.join(f'{t:g}' for t in limits)} s per solver, instance and seed; "
        f"solver seeds {seed_txt}. Makespans validated. Gap = (makespan - best known) / best known.",
        "",
        "| instance | BKS | "
        + " | ".join(f"{s}: seeds {seed_txt} | {s} mean (min-max)" for s in solvers)
        + " |",
        "|---|---|" + "---|---|" * len(solvers),
    ]
    gaps: dict[str, dict[int, list[float]]] = {s: {k: [] for k in seeds} for s in solvers}
    best_gap: dict[str, list[float]] = {s: [] for s in solvers}
    every: dict[str, int] = dict.fromkeys(solvers, 0)
    for key in keys:
        b = bks[key]
        cells = []
        for s in solvers:
            got = [mk.get((s, *key, k), math.nan) for k in seeds]
            for k, v in zip(seeds, got, strict=True):
                gaps[s][k].append((v - b) / b)
            best_gap[s].append((min(got) - b) / b)
            every[s] += all(v <= b for v in got)
            cells.append(
                " ".join(_fmt(v) for v in got)
                + f" | {float(np.mean(got)):.1f} ({_fmt(min(got))}-{_fmt(max(got))})"
            )
        lines.append(f"| {key[1]} | {b:g} | " + " | ".join(cells) + " |")
    lines += ["", "Mean gap to the best-known makespans over the instances, per seed:", ""]
    lines.append("| seed | " + " | ".join(solvers) + " |")
    lines.append("|---|" + "---|" * len(solvers))
    for k in seeds:
        lines.append(
            f"| {k} | " + " | ".join(_pct(float(np.mean(gaps[s][k]))) for s in solvers) + " |"
        )
    lines.append("")
    for s in solvers:
        per_seed = [float(np.mean(gaps[s][k])) for k in seeds]
        lines.append(
            f"- **{s}**: mean gap {_pct(float(np.mean(per_seed)))} over the seeds "
            f"(from {_pct(min(per_seed))} to {_pct(max(per_seed))}); the best seed of each "
            f"instance: {_pct(float(np.mean(best_gap[s])))}; every seed at the best known on "
            f"{every[s]} of {len(keys)} instances"
        )
    return "\n".join(lines) + "\n"
