"""The tree's relaxed worker process (``TreeOptions.relaxed_workers``), off and on.

On a problem with a blocking oracle, the tree's second process searches the
problem without the oracle, and each plan it returns is checked against the
oracle: kept where no parked arm is in its way, else its modes and start
order are decoded again with the detours (docs/scheduler.md, "Solvers"). The
option has no parameter, so nothing was tuned; this table is its check, a
thin wrapper of the sweep ``benchmarks/sweeps/relaxed.toml``: the tree at
10 s with the option off and on (the default), solver seeds 0-2, on
``cell8`` and on generated problems with a blocking oracle and start zones
(:func:`scheduler.generate.random_problem`, problem seed 300). Writes
``results/relaxed.md``, ``.json`` and ``.parquet``.

Run: ``python -m benchmarks.bench_relaxed [--fresh] [--quick]`` (about 6
minutes, one run at a time: the tree uses both cores).
"""

from __future__ import annotations

import math
from typing import Any

from benchmarks.common import table_main

NAME = "relaxed"


def _fmt(x: float) -> str:
    return f"{x:.2f}".rstrip("0").rstrip(".") if math.isfinite(x) else "none"


def relaxed_table(df: Any) -> str:
    """The Markdown table of ``relaxed.md`` from the sweep's results.

    Parameters
    ----------
    df : pandas.DataFrame
        One run per problem, label (``off``, ``on``) and solver seed.

    Returns
    -------
    str
        Per problem the makespans of every seed with the option off and on and
        their means; then how often ``on`` is lower, higher or equal, per run
        (problem and seed) and per problem (the means).

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({
    ...     "instance": ["a"] * 4, "label": ["off", "on"] * 2, "seed": [0, 0, 1, 1],
    ...     "makespan": [10.0, 9.0, 8.0, 8.0], "n_tasks": [5] * 4, "n_arms": [2] * 4,
    ...     "time_limit": [1.0] * 4})
    >>> print(relaxed_table(df).split("## Summary")[1].strip())
    - per run (problem and seed): on lower on 1 of 2, higher on 0, equal on 1; mean -5.00%
    - per problem (mean over the seeds): on lower on 1 of 1, higher on 0, equal on 0; mean -5.56%
    """
    seeds = sorted({int(s) for s in df["seed"]})
    tl = float(df["time_limit"].max())
    order = sorted(
        set(df["instance"]), key=lambda k: (int(df[df["instance"] == k]["n_tasks"].iloc[0]), k)
    )
    head = " | ".join(f"off s{s}" for s in seeds) + " | " + " | ".join(f"on s{s}" for s in seeds)
    lines = [
        "# The relaxed worker process: the tree with its second process searching without the oracle",
        "",
        f"The tree search at {tl:g} s (the machine's 2 cores: the main process and one worker),"
        " solver seeds " + ", ".join(map(str, seeds)) + ", makespans in seconds, validated with"
        " the oracle. `off`: `TreeOptions(relaxed_workers=False)`, both processes search with"
        " the blocking oracle; `on` (the default): the worker searches the problem without"
        " it, and its plan is checked against the oracle (kept, or decoded again with the"
        " detours). The option has no parameter; nothing was tuned here.",
        "",
        f"| problem | arms | tasks | {head} | off mean | on mean | on vs off |",
        "|---|---|---|" + "---|" * (2 * len(seeds) + 3),
    ]
    runs: list[tuple[float, float]] = []
    means: list[tuple[float, float]] = []
    for k in order:
        rows = df[df["instance"] == k]
        got: dict[str, dict[int, float]] = {"off": {}, "on": {}}
        for _, r in rows.iterrows():
            got[str(r["label"])][int(r["seed"])] = float(r["makespan"])
        off = [got["off"].get(s, math.nan) for s in seeds]
        on = [got["on"].get(s, math.nan) for s in seeds]
        runs += [(a, b) for a, b in zip(off, on, strict=True) if math.isfinite(a + b)]
        mo = sum(off) / len(off)
        mn = sum(on) / len(on)
        if math.isfinite(mo + mn):
            means.append((mo, mn))
        change = f"{100 * (mn - mo) / mo:+.2f}%" if math.isfinite(mo + mn) else "-"
        lines.append(
            f"| {k} | {int(rows['n_arms'].iloc[0])} | {int(rows['n_tasks'].iloc[0])} | "
            + " | ".join(_fmt(x) for x in off + on)
            + f" | {_fmt(mo)} | {_fmt(mn)} | {change} |"
        )
    lines += ["", "## Summary", ""]
    for what, pairs in (
        ("per run (problem and seed)", runs),
        ("per problem (mean over the seeds)", means),
    ):
        lower = sum(b < a - 1e-9 for a, b in pairs)
        higher = sum(b > a + 1e-9 for a, b in pairs)
        mean = sum((b - a) / a for a, b in pairs) / len(pairs) if pairs else math.nan
        lines.append(
            f"- {what}: on lower on {lower} of {len(pairs)}, higher on {higher}, equal on"
            f" {len(pairs) - lower - higher}; mean {100 * mean:+.2f}%"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    table_main(NAME, relaxed_table, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
