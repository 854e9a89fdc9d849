"""The tree's polish (``TreeOptions.polish_share``): tuned on ``routes``, checked on ``zones``.

A thin wrapper of two sweeps. The polish gives the last share of a
wall-clock budget to CP-SAT hinted with the tree's best schedule
(:func:`scheduler.tree.solve_tree`, docs/scheduler.md "Portfolio").

* ``--tune``: ``benchmarks/sweeps/polish_tune.toml``, the ``routes``
  problems of the outside table with seeds 2-3 (the table uses 0-1), the
  tree with the polish off, at 0.4, 0.6 and 0.8 of the budget, and CP-SAT
  alone, at 10 s each; writes ``polish_tune.md``.
* ``--retune``: ``benchmarks/sweeps/polish_retune.toml``, the same
  problems again after the CP-SAT fix of 2026-11-29, the tree at 0.6 (the
  reference label, the default when it ran), 0.7, 0.8 and 0.9 of the
  budget, and CP-SAT alone; writes ``polish_retune.md``.
* ``--fjsp``: ``benchmarks/sweeps/polish_fjsp_tune.toml``, the tuning of
  ``TreeOptions.polish_fjsp_max_tasks`` on random FJSPs without setups
  (:func:`scheduler.generate.random_setup_fjsp`, ``setup_fraction = 0``),
  the tree without the FJSP polish and with it at every size, and CP-SAT
  alone; writes ``polish_fjsp_tune.md``. Its check is the FJSP table
  (``bench_fjsp``).
* ``--setups``: ``benchmarks/sweeps/polish_setup_tune.toml``, the tuning of
  ``TreeOptions.polish_setup_max_tasks`` on the ``stations`` problems (travel
  setups) of the outside table up to 50 tasks, with seeds 2-3; writes
  ``polish_setup_tune.md``. Its checks are the outside table's ``stations``
  rows (seeds 0-1) and the generated, lines and setups tables.
* default: ``benchmarks/sweeps/polish.toml``, the check on a family the
  share was not tuned on, :func:`scheduler.generate.random_problem` without
  travel setups: the tree with the polish off and with its default, and
  CP-SAT alone; writes ``polish.md``.

Each table gives, per problem, every label's makespan ('(optimal)' where
the run proved it) and, per tree label, how often it is behind CP-SAT and
how it compares with the tree without the polish.

Run: ``python -m benchmarks.bench_polish [--tune | --retune | --fjsp | --setups] [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

from benchmarks.common import output_dir, publish, run_table_sweep, sweep_arguments

NAME = "polish"

_OFF = "the tree without the polish (`polish_share=0`)"
SWEEPS: dict[str, tuple[str, str, str]] = {
    "": (
        NAME,
        "The polish on random_problem without setups (a family it was not tuned on)",
        _OFF,
    ),
    "tune": ("polish_tune", "Tuning the polish share on the routes family (seeds 2-3)", _OFF),
    "retune": (
        "polish_retune",
        "Re-tuning the polish share on the routes family (seeds 2-3), after the CP-SAT fix",
        "the tree with the polish share of 0.6, the default when this ran",
    ),
    "fjsp": (
        "polish_fjsp_tune",
        "Tuning the polish's size rule on random FJSPs without setups (seeds 0-1)",
        "the tree as it is by default, without the polish on a pure FJSP",
    ),
    "setups": (
        "polish_setup_tune",
        "Tuning the polish's size rule on stations problems with travel setups (seeds 2-3)",
        "the tree as it is by default, without the polish on setup times",
    ),
}
"""The sweeps by command-line flag ('': the default): sweep name, title, what
the reference label (:data:`REFERENCE`, else ``tree_off``) is."""

REFERENCE = {"retune": "tree_p60"}
"""The reference label of a sweep whose runs all have the polish (by flag)."""


def _fmt(x: float) -> str:
    return f"{x:g}" if math.isfinite(x) else "none"


def polish_table(
    df: Any, *, title: str, sweep: str, off: str = "tree_off", off_text: str = _OFF
) -> str:
    """The Markdown table of ``polish.md`` or ``polish_tune.md`` from a sweep's results.

    Parameters
    ----------
    df : pandas.DataFrame
        Results (one run per instance and label); the labels ``off`` and
        ``cpsat`` must be among them, every other label is a tree with the polish.
    title : str
        The heading.
    sweep : str
        The sweep file's stem (named in the text).
    off : str
        The label of the tree without the polish.
    off_text : str
        What ``off`` is, in the table's text.

    Returns
    -------
    str
        Markdown: per problem every label's makespan; per tree label the
        count behind / ahead of CP-SAT and, for the polished ones, lower /
        higher than ``off`` with the mean relative change.

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({
    ...     "instance": ["a"] * 3 + ["b"] * 3, "label": ["tree_off", "tree", "cpsat"] * 2,
    ...     "makespan": [10.0, 9.0, 9.0, 20.0, 20.0, 21.0], "status": ["feasible"] * 6,
    ...     "instance_params": ['{"tasks": 5}'] * 3 + ['{"tasks": 7}'] * 3, "time_limit": [1.0] * 6})
    >>> print(polish_table(df, title="T", sweep="s").split("## Summary")[1].strip())
    - tree_off: behind cpsat on 1 of 2, ahead on 1
    - tree: behind cpsat on 0 of 2, ahead on 1; against tree_off lower on 1, higher on 0, mean -5.00%
    """
    labels = [off, *sorted(x for x in set(df["label"]) if x not in (off, "cpsat")), "cpsat"]
    t = {x: df[df["label"] == x].set_index("instance") for x in labels}
    keys = sorted(
        t["cpsat"].index,
        key=lambda k: (json.loads(str(t["cpsat"].loc[k]["instance_params"]))["tasks"], k),
    )
    tl = float(df["time_limit"].max())
    lines = [
        f"# {title}",
        "",
        f"{tl:g} s per run on the machine's 2 cores (sweep `benchmarks/sweeps/{sweep}.toml`); "
        f"size = arms x tasks x zones x tools, '-nowait': solved with `waits=False`. `{off}`: "
        f"{off_text}; `cpsat`: CP-SAT alone on 2 workers; the other labels: the tree with "
        "the polish (see the sweep file for its options). '(optimal)': the run proved "
        "its schedule optimal.",
        "",
        "| problem | tasks | " + " | ".join(labels) + " |",
        "|---|---|" + "---|" * len(labels),
    ]
    mk: dict[str, list[float]] = {x: [] for x in labels}
    for k in keys:
        tasks = int(json.loads(str(t["cpsat"].loc[k]["instance_params"]))["tasks"])
        cells = []
        for x in labels:
            m = float(t[x].loc[k]["makespan"])
            mk[x].append(m)
            cells.append(_fmt(m) + (" (optimal)" if t[x].loc[k]["status"] == "optimal" else ""))
        lines.append(f"| {k} | {tasks} | " + " | ".join(cells) + " |")
    lines += ["", "## Summary", ""]
    cp = mk["cpsat"]
    n = len(keys)
    for x in labels[:-1]:
        behind = sum(a > c + 1e-9 for a, c in zip(mk[x], cp, strict=True))
        ahead = sum(a < c - 1e-9 for a, c in zip(mk[x], cp, strict=True))
        line = f"- {x}: behind cpsat on {behind} of {n}, ahead on {ahead}"
        if x != off:
            pairs = [(a, o) for a, o in zip(mk[x], mk[off], strict=True) if math.isfinite(a + o)]
            lower = sum(a < o - 1e-9 for a, o in pairs)
            higher = sum(a > o + 1e-9 for a, o in pairs)
            mean = sum((a - o) / o for a, o in pairs) / len(pairs) if pairs else math.nan
            line += f"; against {off} lower on {lower}, higher on {higher}, mean {100 * mean:+.2f}%"
        lines.append(line)
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
    which = ap.add_mutually_exclusive_group()
    for flag, (sweep, _title, _off) in SWEEPS.items():
        if flag:
            which.add_argument(
                f"--{flag}",
                dest="which",
                action="store_const",
                const=flag,
                help=f"run the tuning sweep {sweep}.toml instead (writes {sweep}.md)",
            )
    args = ap.parse_args(argv)
    flag = args.which or ""
    name, title, off_text = SWEEPS[flag]
    flags = f"--{flag} --fresh" if flag else "--fresh"
    out = output_dir(args.quick)
    df = run_table_sweep(name, args, out)
    off = REFERENCE.get(flag, "tree_off")
    table = polish_table(df, title=title, sweep=name, off=off, off_text=off_text)
    path = publish(name, df, table, out, quick=args.quick, flags=flags, script="bench_polish")
    print(path.read_text())


if __name__ == "__main__":
    main()
