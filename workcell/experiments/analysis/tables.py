"""The Markdown tables of ``benchmarks/results/`` from sweep results, and what ran.

:func:`fjsp_table`, :func:`generated_table`, :func:`small_table`,
:func:`cells_table`, :func:`scale_table` build the tables from the results
of the sweep files in ``benchmarks/sweeps/``; :func:`sweep_note` says what
ran, on what; :func:`measurements` gathers the rows that ``benchmark`` runs
measured; :func:`summary_table` is the short table printed at the end of a
sweep.
"""

from __future__ import annotations

import datetime
import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from workcell.experiments.analysis.gaps import INSTANCE, need_columns, with_gaps

__all__ = [
    "cells_table",
    "fjsp_table",
    "generated_table",
    "measurements",
    "scale_table",
    "small_table",
    "summary_table",
    "sweep_note",
]


def _fmt(x: float, spec: str = ".0f") -> str:
    return format(x, spec) if math.isfinite(x) else "none"


def _pct(x: float, sign: bool = False) -> str:
    if not math.isfinite(x):
        return "-"
    return f"{100 * x:+.2f}%" if sign else f"{100 * x:.2f}%"


def _gap1(x: float) -> str:
    return f"{100 * x:.1f}%" if math.isfinite(x) else "-"


def _one(df: Any, label: str) -> Any:
    sub = df[df["label"] == label]
    return sub.set_index(INSTANCE)


def fjsp_table(df: Any, solvers: Sequence[str] = ("tree", "greedy", "cpsat")) -> str:
    """The FJSP table of ``benchmarks/results/fjsp.md`` from the results of ``sweeps/fjsp.toml``.

    Parameters
    ----------
    df : pandas.DataFrame
        Results with one run per (instance, solver label), ``best_known`` set.
    solvers : sequence of str
        Solver labels, in column order.

    Returns
    -------
    str
        Markdown: per instance the makespan, gap to the best known, and the
        times of the first and best schedules; per family the mean gaps.
    """
    need_columns(df, [*INSTANCE, "label", "makespan", "best_known", "lower_bound"], "fjsp_table")
    limits = sorted({float(v) for v in df["time_limit"].dropna()})
    seeds = sorted({int(v) for v in df["seed"].dropna()})
    lines = [
        "# FJSP benchmark",
        "",
        f"Time limit {', '.join(f'{t:g}' for t in limits)} s per solver and instance, seed "
        f"{', '.join(map(str, seeds))} (sweep `benchmarks/sweeps/fjsp.toml`). Makespans validated. "
        "Gap = (makespan - best known) / best known.",
        "",
        "| instance | tasks | arms | BKS | our LB | "
        + " | ".join(f"{s} (gap, first s, best s)" for s in solvers)
        + " |",
        "|---|---|---|---|---|" + "---|" * len(solvers),
    ]
    per = {s: _one(df, s) for s in solvers}
    first = per[solvers[0]]
    order = sorted(first.index, key=lambda k: (k[0], k[1]))
    gaps: dict[str, dict[str, list[float]]] = {}
    for fam, inst in order:
        r0 = first.loc[(fam, inst)]
        bks = float(r0["best_known"])
        cells = []
        for s in solvers:
            r = per[s].loc[(fam, inst)]
            mk = float(r["makespan"])
            gap = (mk - bks) / bks
            gaps.setdefault(fam, {}).setdefault(s, []).append(gap)
            cells.append(
                f"{_fmt(mk)} ({100 * gap:.1f}%, {float(r['first_time']):.2f}, "
                f"{float(r['best_time']):.2f})"
            )
        lines.append(
            f"| {inst} | {int(r0['n_tasks'])} | {int(r0['n_arms'])} | {bks:g} | "
            f"{float(r0['lower_bound']):.1f} | " + " | ".join(cells) + " |"
        )
    lines.append("")
    for fam in sorted(gaps):
        g = gaps[fam]
        n = len(next(iter(g.values())))
        lines.append(
            f"- **{fam}**: mean gap to BKS "
            + ", ".join(f"{s} {100 * float(np.mean(v)):.2f}%" for s, v in g.items())
            + f" ({n} instances)"
        )
        if "tree" in per and "cpsat" in per:
            t = per["tree"].xs(fam, level="family")["makespan"].astype(float)
            c = per["cpsat"].xs(fam, level="family")["makespan"].astype(float)
            better, worse = int((t < c).sum()), int((t > c).sum())
            lines.append(
                f"  - tree better than cpsat on {better}, worse on {worse}, "
                f"equal on {len(t) - better - worse}"
            )
    mk10 = [(fam, inst) for fam, inst in order if inst == "mk10"]
    if mk10:  # the open instance: its soft lower bound (../shared/data/fjsp/README.md)
        lines.append(
            "- mk10 gap to its soft lower bound 189: "
            + ", ".join(
                f"{s} {100 * (float(per[s].loc[mk10[0]]['makespan']) - 189) / 189:.1f}%"
                for s in solvers
            )
        )
    return "\n".join(lines) + "\n"


def generated_table(
    df: Any,
    *,
    reference_label: str = "reference",
    tree: str = "tree",
    short: str = "cpsat_short",
    greedy: str = "greedy",
    title: str = "Zone-constrained generated problems",
    sweep: str = "generated",
) -> str:
    """The table of ``benchmarks/results/generated.md`` from the results of ``sweeps/generated.toml``.

    The target of each problem is the reference run's makespan when it
    proved it optimal, else the reference's bound (then gaps are upper
    bounds of the true gaps).

    Parameters
    ----------
    df : pandas.DataFrame
    reference_label, tree, short, greedy : str
        The solver labels of the sweep file.
    title, sweep : str
        The table's heading and the sweep it names (``sweeps/<sweep>.toml``).

    Returns
    -------
    str
        Markdown.
    """
    need_columns(df, [*INSTANCE, "label", "makespan", "bound", "status"], "generated_table")
    ref, tr, sh, gr = (_one(df, x) for x in (reference_label, tree, short, greedy))
    tl = {x: float(_one(df, x)["time_limit"].max()) for x in (reference_label, tree)}
    rows = []
    for key in ref.index:
        r = ref.loc[key]
        opt = r["status"] == "optimal"
        target = float(r["makespan"]) if opt else float(r["bound"])
        params = json.loads(str(r["instance_params"]))
        mk = {
            n: float(t.loc[key]["makespan"])
            for n, t in (("tree", tr), ("short", sh), ("greedy", gr))
        }
        refmk = float(r["makespan"])
        rows.append(
            {
                "size": f"{params['arms']}x{params['tasks']}x{params['zones']}x{params['tools']}"
                + (" no waits" if params.get("waits") is False else ""),
                "order": (params["tasks"], params["arms"], params.get("waits") is False),
                "seed": int(r["instance_seed"]),
                "opt": opt,
                "target": target,
                "reference": refmk,
                **mk,
                "tree_gap": (mk["tree"] - target) / target if target > 0 else 0.0,
                "short_gap": (mk["short"] - target) / target if target > 0 else 0.0,
                "greedy_gap": (mk["greedy"] - target) / target if target > 0 else 0.0,
                "vs": (mk["tree"] - refmk) / refmk if math.isfinite(refmk) else math.nan,
            }
        )
    rows.sort(key=lambda r: (r["order"], r["seed"]))
    lines = [
        f"# {title}",
        "",
        f"tree, cpsat (short) and greedy: {tl[tree]:g} s; reference CP-SAT: {tl[reference_label]:g} s "
        f"(sweep `benchmarks/sweeps/{sweep}.toml`); size = arms x tasks x zones x tools. Target = "
        "the reference's optimum when proven, else its best bound (then gaps are upper bounds on "
        "the true gaps). 'no waits': every solver solved it with `waits=False`.",
        "",
        "| size | seed | optimal? | target | reference | tree | cpsat short | greedy | tree gap | "
        "cpsat short gap | tree vs reference |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['size']} | {r['seed']} | {'yes' if r['opt'] else 'no'} | {r['target']:.1f} | "
            f"{_fmt(r['reference'])} | {_fmt(r['tree'])} | {_fmt(r['short'])} | "
            f"{_fmt(r['greedy'])} | {_pct(r['tree_gap'])} | {_pct(r['short_gap'])} | "
            f"{_pct(r['vs'], sign=True)} |"
        )
    opt = [r for r in rows if r["opt"]]
    lines.append("")
    behind = sum(r["tree"] > r["short"] + 1e-6 for r in rows)
    ahead = sum(r["tree"] < r["short"] - 1e-6 for r in rows)
    lines.append(
        f"- tree against CP-SAT at the same {tl[tree]:g} s: behind on {behind}, ahead on "
        f"{ahead}, equal on {len(rows) - behind - ahead} of {len(rows)} problems"
    )
    if opt:
        hit = sum(r["tree"] <= r["target"] + 1e-6 for r in opt)
        lines.append(
            f"- tree at {tl[tree]:g} s reaches the proven optimum on {hit} of {len(opt)} problems"
        )
    if opt:
        lines.append(
            f"- on the {len(opt)} problems CP-SAT solved to optimality: mean gap of tree "
            f"{100 * np.mean([r['tree_gap'] for r in opt]):.2f}%, of CP-SAT at {tl[tree]:g} s "
            f"{100 * np.mean([r['short_gap'] for r in opt]):.2f}%, of greedy "
            f"{100 * np.mean([r['greedy_gap'] for r in opt]):.2f}%"
        )
    rest = [r for r in rows if not r["opt"]]
    with_ref = [r for r in rest if math.isfinite(r["vs"])]
    if with_ref:
        lines.append(
            f"- on the other {len(rest)}, where CP-SAT found a schedule in "
            f"{tl[reference_label]:g} s ({len(with_ref)}): tree "
            f"{100 * np.mean([r['vs'] for r in with_ref]):+.2f}% against it on average "
            "(negative: tree is shorter)"
        )
    if len(with_ref) < len(rest):
        lines.append(
            f"- CP-SAT found no schedule within {tl[reference_label]:g} s on "
            f"{len(rest) - len(with_ref)} problems"
        )
    return "\n".join(lines) + "\n"


def small_table(df: Any, solvers: Sequence[str] = ("tree", "cpsat")) -> str:
    """The table of ``benchmarks/results/small.md`` from the results of ``sweeps/small.toml``.

    Parameters
    ----------
    df : pandas.DataFrame
    solvers : sequence of str
        Two solver labels.

    Returns
    -------
    str
        Markdown: makespan, status and time to optimal (the runtime of runs
        that proved optimality) per problem and solver.
    """
    need_columns(df, [*INSTANCE, "label", "makespan", "status", "runtime"], "small_table")
    a, b = (_one(df, s) for s in solvers)
    limit = float(df["time_limit"].max())
    limits = f"Time limit {limit:g} s" if math.isfinite(limit) else "Work-limited runs"
    lines = [
        f"# Small zone problems: {solvers[0]} vs {solvers[1]}",
        "",
        f"{limits} per solver and problem (sweep `benchmarks/sweeps/small.toml`). "
        "Time to optimal: seconds until the solver proved optimality ('-': not within the limit).",
        "",
        "| family | problem | "
        + " | ".join(f"{s} makespan | {s} status | {s} to optimal (s)" for s in solvers)
        + " |",
        "|---|---|" + "---|---|---|" * len(solvers),
    ]
    worse = 0
    for key in sorted(a.index, key=lambda k: (k[0], k[1])):
        cells = []
        for t in (a, b):
            r = t.loc[key]
            to = f"{float(r['runtime']):.2f}" if r["status"] == "optimal" else "-"
            cells.append(f"{_fmt(float(r['makespan']), 'g')} | {r['status']} | {to}")
        worse += float(a.loc[key]["makespan"]) > float(b.loc[key]["makespan"]) + 1e-9
        lines.append(f"| {key[0]} | {key[1]} | " + " | ".join(cells) + " |")
    proven = [int((t["status"] == "optimal").sum()) for t in (a, b)]
    lines += [
        "",
        f"{solvers[0]} worse than {solvers[1]} on {worse} of {len(a)}; proven optimal: "
        f"{solvers[0]} {proven[0]}, {solvers[1]} {proven[1]}.",
    ]
    return "\n".join(lines) + "\n"


def cells_table(df: Any, solvers: Sequence[str] = ("greedy", "tree", "cpsat")) -> str:
    """The schedules table of ``benchmarks/results/cells.md`` from ``sweeps/cells.toml``.

    Parameters
    ----------
    df : pandas.DataFrame
    solvers : sequence of str
        Solver labels in row order (within a cell; cells by size).

    Returns
    -------
    str
        Markdown: per cell and solver the status, makespan, the solver's own
        bound (``bound``, where the results have it: the tree's is its proof's
        when it proves its plan, e.g. with the problem without zones), the
        problem's :func:`scheduler.lower_bound` and the time.

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({"instance": ["parking"], "label": ["tree"], "status": ["optimal"],
    ...     "makespan": [19.3215], "bound": [19.3215], "lower_bound": [18.2295],
    ...     "runtime": [0.1]})
    >>> print(cells_table(df).splitlines()[2])
    | parking | tree | optimal | 19.3 | 19.32 | 18.2 | 0.1 |
    """
    need_columns(
        df, ["instance", "label", "status", "makespan", "lower_bound", "runtime"], "cells_table"
    )
    lines = [
        "| cell | solver | status | makespan (s) | solver's bound (s) | lower bound (s) | time (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    rank = {s: i for i, s in enumerate(solvers)}
    order = sorted(
        df.index,
        key=lambda i: (
            int(df.loc[i, "n_tasks"]) if "n_tasks" in df.columns else 0,
            str(df.loc[i, "instance"]),
            rank.get(str(df.loc[i, "label"]), len(rank)),
            str(df.loc[i, "label"]),
        ),
    )
    for _, r in df.loc[order].iterrows():
        own = float(r["bound"]) if "bound" in r.index else math.nan
        lines.append(
            f"| {r['instance']} | {r['label']} | {r['status']} | {_fmt(float(r['makespan']), '.1f')} "
            f"| {_fmt(own, '.2f') if own > 0 else '-'} "
            f"| {float(r['lower_bound']):.1f} | {float(r['runtime']):.1f} |"
        )
    return "\n".join(lines) + "\n"


def scale_table(df: Any, *, first: str = "greedy", tree: str = "tree") -> str:
    """The table of ``benchmarks/results/scale.md`` from the results of ``sweeps/scale.toml``.

    The first schedule is the ``first`` (greedy) run: its ``runtime`` is the
    time to the first valid schedule (compiling the problem for the kernel
    and the lower bound included; loading the compiled kernel, once per
    process, is not: it is ``warmup_time``, reported apart); the build time
    is its ``build_time`` (the generator's).

    Parameters
    ----------
    df : pandas.DataFrame
    first, tree : str
        The solver labels of the sweep file.

    Returns
    -------
    str
        Markdown: per problem the build and first-schedule times, the
        makespans, the lower bound and both gaps to it, the tree's evaluations.
    """
    need = [*INSTANCE, "label", "makespan", "lower_bound", "runtime", "build_time"]
    need_columns(df, [*need, "evaluations", "instance_params", "instance_seed"], "scale_table")
    g, t = _one(df, first), _one(df, tree)
    keys = sorted(g.index, key=lambda k: (k[0], int(g.loc[k]["instance_seed"])))
    params = json.loads(str(g.loc[keys[0]]["instance_params"])) if keys else {}
    size = " x ".join(f"{params.get(k, '?')} {k}" for k in ("arms", "tasks", "zones", "tools"))
    tl = float(t["time_limit"].max()) if "time_limit" in t.columns else math.nan
    load = float(df["warmup_time"].max()) if "warmup_time" in df.columns else math.nan
    lines = [
        f"# Scale: {size}",
        "",
        f"seeds {[int(g.loc[k]['instance_seed']) for k in keys]}; tree time limit {tl:g} s "
        "(sweep `benchmarks/sweeps/scale.toml`); first schedule = the greedy run's runtime; "
        f"kernel compile/cache load once per process: {_fmt(load, '.2f')} s (not in the "
        "times below).",
        "",
        "| seed | build s | first schedule s | first makespan | tree makespan | lower bound "
        "| first gap to LB | tree gap to LB | tree evaluations |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    firsts = []
    for k in keys:
        a, b = g.loc[k], t.loc[k]
        lb = float(a["lower_bound"])
        fm, tm = float(a["makespan"]), float(b["makespan"])
        firsts.append(float(a["runtime"]))
        lines.append(
            f"| {int(a['instance_seed'])} | {float(a['build_time']):.2f} | "
            f"{float(a['runtime']):.3f} | {_fmt(fm)} | {_fmt(tm)} | {lb:.1f} | "
            f"{_gap1((fm - lb) / lb)} | {_gap1((tm - lb) / lb)} | {int(b['evaluations'])} |"
        )
    if firsts:
        lines += [
            "",
            f"- first valid schedule: mean {float(np.mean(firsts)):.3f} s, "
            f"max {float(np.max(firsts)):.3f} s (target: under 1 s)",
        ]
    return "\n".join(lines) + "\n"


def measurements(df: Any, family: str | None = None) -> Any:
    """The rows measured by the ``benchmark`` runs of a sweep, one DataFrame row each.

    Parameters
    ----------
    df : pandas.DataFrame
        Results (:func:`~workcell.experiments.results.read_results`); rows
        without measurements (solver runs, errors) are left out.
    family : str, optional
        Only the runs of this family (one table: its columns are exactly
        the fields its rows measured).

    Returns
    -------
    pandas.DataFrame
        ``family``, ``instance``, ``seed``, ``repetition``, ``load_average``
        of the run, then the measured fields, in the order of the sweep's
        runs and of each run's rows.

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({"family": ["k"], "instance": ["a-s0"], "seed": [0],
    ...     "repetition": [0], "status": ["measured"], "load_average": [0.5],
    ...     "metrics": ['[{"n": 1, "rate": 2.5}, {"n": 2, "rate": 3.0}]']})
    >>> measurements(df)[["instance", "n", "rate"]].to_dict("list")
    {'instance': ['a-s0', 'a-s0'], 'n': [1, 2], 'rate': [2.5, 3.0]}
    """
    import pandas as pd

    need_columns(
        df, ["family", "instance", "seed", "repetition", "status", "metrics"], "measurements"
    )
    out = []
    keep = df["status"] == "measured"
    if family is not None:
        keep &= df["family"] == family
    for _, r in df[keep].iterrows():
        head = {
            "family": r["family"],
            "instance": r["instance"],
            "seed": int(r["seed"]),
            "repetition": int(r["repetition"]),
            "load_average": float(r["load_average"]) if "load_average" in r else math.nan,
        }
        for m in json.loads(str(r["metrics"])):
            out.append({**head, **m})
    return pd.DataFrame(out)


def sweep_note(df: Any, sweep_file: str | Sequence[str] = "", command: str = "") -> str:
    """What ran, on what: the provenance line under a benchmark table.

    Parameters
    ----------
    df : pandas.DataFrame
        Results of one sweep.
    sweep_file : str or sequence of str
        The sweep file (or files), as the reader should type it.
    command : str
        The command that reproduces the table.

    Returns
    -------
    str
        Markdown: the command and sweep file, the solver configurations
        (label, solver, limit, options), the runs and failed runs, the
        machine (CPUs, Python, platform), the package's git commit, when the
        runs started and the load average meanwhile.
    """
    lines = []
    files = [sweep_file] if isinstance(sweep_file, str) else list(sweep_file)
    files = [f for f in files if f]
    if command or files:
        sweeps = " and ".join(f"`{f}`" for f in files)
        if command:
            what = f"`{command}`" + (f" (sweep {sweeps})" if files else "")
        else:
            what = f"sweep {sweeps}"
        lines.append(f"Reproduce: {what}.")
    if "label" in df.columns and "solver" in df.columns:
        cfg = []
        cols = [c for c in ("label", "solver", "time_limit", "options") if c in df.columns]
        for _, r in df[cols].drop_duplicates().iterrows():
            if str(r["solver"]) == "benchmark":
                continue
            opts = json.loads(str(r.get("options", "{}")) or "{}")
            limit = float(r.get("time_limit", math.nan))
            parts = [f"{r['solver']}"]
            parts.append(f"{limit:g} s" if math.isfinite(limit) else "work-limited")
            parts += [f"{k}={v}" for k, v in sorted(opts.items())]
            cfg.append(f"{r['label']} ({', '.join(parts)})")
        if cfg:
            lines.append("Solvers: " + "; ".join(cfg) + ".")
    facts = [f"{len(df)} runs"]
    if "status" in df.columns:
        failed = int((df["status"] == "error").sum())
        if failed:
            facts.append(f"{failed} failed")
    first = df.iloc[0] if len(df) else None
    if first is not None:
        for col, fmt in (("cpus", "{} CPUs"), ("python", "Python {}"), ("platform", "{}")):
            if col in df.columns and str(first[col]) not in ("", "<NA>", "None"):
                facts.append(fmt.format(first[col]))
        if "git_commit" in df.columns:
            commits = sorted(
                {
                    str(c)[:12] + ("+dirty" if str(c).endswith("+dirty") else "")
                    for c in df["git_commit"].dropna()
                    if str(c)
                }
            )
            if commits:
                facts.append("commit " + ", ".join(commits))
    if "started" in df.columns:
        st = df["started"].astype(float)
        st = st[np.isfinite(st)]
        if len(st):
            day = datetime.datetime.fromtimestamp(float(st.min()), datetime.UTC)
            facts.append(f"started {day:%Y-%m-%d %H:%M} UTC")
    if "load_average" in df.columns:
        la = df["load_average"].astype(float)
        la = la[np.isfinite(la)]
        if len(la):
            facts.append(f"load average {float(la.min()):.1f}-{float(la.max()):.1f}")
    lines.append("Ran: " + ", ".join(facts) + ".")
    return "\n".join(lines) + "\n"


def summary_table(df: Any) -> str:
    """The short table printed at the end of a sweep: one line per family and solver.

    Parameters
    ----------
    df : pandas.DataFrame
        Results of one sweep (:meth:`~workcell.experiments.SweepOutcome.results`).

    Returns
    -------
    str
        Aligned plain-text columns: ``family``, ``solver`` (the label),
        ``runs``, ``failed`` (status ``"error"``), the mean ``makespan`` and
        mean ``gap`` (to the reference of :func:`with_gaps`) over the runs
        with a schedule, and the mean solver ``time`` in seconds (the whole
        measurement for a ``benchmark`` run); ``-`` where there is nothing to
        average. An empty frame gives ``"no runs"``.

    Examples
    --------
    >>> import pandas as pd
    >>> df = pd.DataFrame({"family": ["g"] * 3, "instance": ["a", "a", "b"],
    ...     "label": ["x", "y", "x"], "status": ["feasible", "feasible", "error"],
    ...     "makespan": [10.0, 12.0, float("inf")], "runtime": [0.5, 1.5, float("nan")]})
    >>> print(summary_table(df))
    family  solver  runs  failed  makespan  gap    time (s)
    g       x       2     1       10.0      0.0%   0.50
    g       y       1     0       12.0      20.0%  1.50
    """
    need_columns(df, [*INSTANCE, "label", "status", "makespan", "runtime"], "summary_table")
    if len(df) == 0:
        return "no runs"
    solved = df[np.isfinite(df["makespan"].astype(float))]
    gaps = with_gaps(solved) if len(solved) else solved.assign(gap=[])
    head = ["family", "solver", "runs", "failed", "makespan", "gap", "time (s)"]
    body = []
    for (family, label), g in df.groupby(["family", "label"], sort=True):
        mk = g["makespan"].astype(float)
        mk = mk[np.isfinite(mk)]
        gp = gaps[(gaps["family"] == family) & (gaps["label"] == label)]["gap"].astype(float)
        gp = gp[np.isfinite(gp)]
        t = g["runtime"].astype(float)
        t = t[np.isfinite(t)]
        body.append(
            [
                str(family),
                str(label),
                str(len(g)),
                str(int((g["status"] == "error").sum())),
                f"{float(mk.mean()):.1f}" if len(mk) else "-",
                _gap1(float(gp.mean())) if len(gp) else "-",
                f"{float(t.mean()):.2f}" if len(t) else "-",
            ]
        )
    widths = [max(len(r[i]) for r in [head, *body]) for i in range(len(head))]
    return "\n".join(
        "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
        for r in [head, *body]
    )
