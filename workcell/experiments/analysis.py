"""Sweep results in pandas, the standard plots of the scheduling literature, and the tables.

Every plot function returns a :class:`matplotlib.figure.Figure` built
without pyplot (no global state, no display needed: it renders with Agg,
``fig.savefig("x.png")``); each has a ``*_data`` twin that returns the
numbers behind it as a DataFrame.

* :func:`performance_profile`: Dolan and Moré's profiles. For solver ``s``
  and instance ``p``, the ratio ``r(p, s) = m(p, s) / min_s' m(p, s')`` of
  its makespan to the best one; the profile ``rho_s(tau)`` is the share of
  instances with ``r(p, s) <= tau`` (a run without a schedule has ratio inf).
  ``rho_s(1)`` is the share where ``s`` is best; the curve's height at large
  ``tau`` the share solved at all.
* :func:`gap_over_time`: the median gap ``(incumbent - reference) /
  reference`` of each solver's runs over time, from the improvements each
  run recorded; the reference is the best-known makespan where the sweep
  file gives one, else the best makespan of any run on the instance
  (:func:`reference`).
* :func:`time_to_target`: the share of runs whose incumbent came within a
  relative ``target`` of the reference by time ``t`` (an empirical CDF).
* :func:`scaling`: a measure (runtime, gap, makespan, ...) against problem
  size (tasks, arms or zones): median and inter-quartile band per solver.
* :func:`box_per_solver`: the distribution of a measure per solver.
* :func:`fjsp_table`, :func:`generated_table`, :func:`small_table`,
  :func:`cells_table`, :func:`scale_table`: the Markdown tables of
  ``benchmarks/results/`` from the results of the sweep files in
  ``benchmarks/sweeps/``; :func:`sweep_note` says what ran, on what.
* :func:`measurements`: the rows the ``benchmark`` runs of a sweep measured
  (the speed tables), as one DataFrame.

Examples
--------
>>> import pandas as pd
>>> df = pd.DataFrame({
...     "family": ["f"] * 4, "instance": ["a", "a", "b", "b"],
...     "label": ["x", "y", "x", "y"], "makespan": [10.0, 12.0, 8.0, 4.0]})
>>> performance_profile_data(df, taus=[1.0, 1.2, 2.0]).to_dict("list")  # x best on a, y on b
{'x': [0.5, 0.5, 1.0], 'y': [0.5, 1.0, 1.0]}
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from multiarm.errors import UsageError

__all__ = [
    "box_per_solver",
    "cells_table",
    "fjsp_table",
    "gap_over_time",
    "gap_over_time_data",
    "generated_table",
    "incumbent_at",
    "measurements",
    "performance_profile",
    "performance_profile_data",
    "reference",
    "scale_table",
    "scaling",
    "scaling_data",
    "small_table",
    "sweep_note",
    "time_to_target",
    "time_to_target_data",
    "with_gaps",
]

_INSTANCE = ["family", "instance"]


def _need(df: Any, columns: Sequence[str], what: str) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise UsageError(f"{what} needs the columns {missing} (results of run_sweep have them)")


def _figure(width: float = 6.4, height: float = 4.0) -> tuple[Any, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    return fig, fig.add_subplot()


def reference(df: Any, how: str = "best_known") -> Any:
    """The reference makespan of each row's instance (for gaps).

    Parameters
    ----------
    df : pandas.DataFrame
        Results (:func:`~workcell.experiments.results.read_results`).
    how : {"best_known", "best", "bound"}
        ``best_known``: the sweep file's best-known value where there is one,
        else the best makespan any run found on the instance; ``best``: always
        the best found; ``bound``: the largest lower bound any run proved.

    Returns
    -------
    pandas.Series
        Aligned with ``df``.

    Raises
    ------
    UsageError
        An unknown ``how`` or missing columns.
    """
    _need(df, [*_INSTANCE, "makespan"], "reference")
    best = df.groupby(_INSTANCE)["makespan"].transform("min").astype(float)
    if how == "best":
        return best
    if how == "bound":
        _need(df, ["bound"], "reference(how='bound')")
        return df.groupby(_INSTANCE)["bound"].transform("max").astype(float)
    if how != "best_known":
        raise UsageError(f"how must be 'best_known', 'best' or 'bound', got {how!r}")
    if "best_known" not in df.columns:
        return best
    bk = df["best_known"].astype(float)
    return bk.where(bk.notna(), best)


def with_gaps(df: Any, how: str = "best_known") -> Any:
    """A copy of ``df`` with ``reference`` and ``gap`` (relative, inf without a schedule).

    Parameters
    ----------
    df : pandas.DataFrame
    how : str
        See :func:`reference`.

    Returns
    -------
    pandas.DataFrame
    """
    out = df.copy()
    out["reference"] = reference(df, how)
    ref = out["reference"].astype(float)
    mk = out["makespan"].astype(float)
    out["gap"] = np.where(ref > 0, (mk - ref) / ref.where(ref > 0, 1.0), 0.0)
    return out


def performance_profile_data(
    df: Any, *, by: str = "label", metric: str = "makespan", taus: Sequence[float] | None = None
) -> Any:
    """The Dolan-Moré performance profile: share of instances within ``tau`` of the best.

    Parameters
    ----------
    df : pandas.DataFrame
        Results; one row per (instance, solver) — repetitions are averaged.
    by : str
        The column naming the solvers compared (default ``label``).
    metric : str
        What is compared, smaller is better (``makespan``, ``runtime``, ...).
    taus : sequence of float, optional
        Where to evaluate (default: every ratio that occurs, and 1).

    Returns
    -------
    pandas.DataFrame
        Index ``tau``, one column per solver.
    """
    import pandas as pd

    _need(df, [*_INSTANCE, by, metric], "performance_profile")
    table = df.pivot_table(index=_INSTANCE, columns=by, values=metric, aggfunc="mean")
    values = table.to_numpy(dtype=float)
    best = np.min(np.where(np.isfinite(values), values, np.inf), axis=1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(best > 0, values / best, np.where(values == best, 1.0, np.inf))
    ratio[~np.isfinite(values)] = np.inf
    if taus is None:
        finite = ratio[np.isfinite(ratio)]
        taus = sorted({1.0, *finite.round(12).tolist()})
    t = np.asarray(taus, dtype=float)
    share = (ratio[None, :, :] <= t[:, None, None] + 1e-12).mean(axis=1)
    out = pd.DataFrame(share, index=pd.Index(t, name="tau"), columns=table.columns)
    out.columns.name = by
    return out


def performance_profile(
    df: Any, *, by: str = "label", metric: str = "makespan", max_tau: float | None = None
) -> Any:
    """Plot the Dolan-Moré performance profile (step curves, log-scaled ``tau``).

    Parameters
    ----------
    df : pandas.DataFrame
    by, metric : str
        See :func:`performance_profile_data`.
    max_tau : float, optional
        Right end of the axis (default: the largest finite ratio, times 1.05).

    Returns
    -------
    matplotlib.figure.Figure
    """
    data = performance_profile_data(df, by=by, metric=metric)
    fig, ax = _figure()
    top = float(data.index.max()) if len(data) else 1.0
    right = max_tau or max(1.05, top * 1.05)
    for col in data.columns:
        x = np.append(data.index.to_numpy(dtype=float), right)
        y = np.append(data[col].to_numpy(dtype=float), data[col].iloc[-1])
        ax.step(x, y, where="post", label=str(col))
    ax.set_xscale("log")
    ax.set_xlim(1.0, right)
    ax.set_ylim(0.0, 1.02)
    ax.set_xlabel(f"tau ({metric} / best {metric})")
    ax.set_ylabel("share of instances within tau of the best")
    ax.set_title("Performance profile")
    ax.legend()
    return fig


def _improvements(row: Any) -> list[tuple[float, float]]:
    raw = row.get("improvements") if hasattr(row, "get") else None
    pts: list[tuple[float, float]] = []
    if isinstance(raw, str) and raw:
        pts = [(float(t), float(v)) for t, v in json.loads(raw)]
    mk = float(row["makespan"])
    if math.isfinite(mk):
        end = float(row["runtime"]) if math.isfinite(float(row["runtime"])) else 0.0
        if not pts:
            pts = [(end, mk)]
        elif pts[-1][1] > mk + 1e-9:  # a final improvement the solver did not announce
            pts.append((max(end, pts[-1][0]), mk))
    return pts


def incumbent_at(row: Any, times: Sequence[float] | np.ndarray) -> Any:
    """The run's best makespan known at each time (inf before the first schedule).

    Parameters
    ----------
    row : mapping or pandas.Series
        A results row (``improvements``, ``makespan``, ``runtime``).
    times : sequence of float
        Seconds since the solver started.

    Returns
    -------
    numpy.ndarray
        (len(times),) float.
    """
    pts = _improvements(row)
    t = np.asarray(times, dtype=float)
    out = np.full(t.shape, np.inf)
    for when, value in pts:
        out = np.where(t >= when, np.minimum(out, value), out)
    return out


def gap_over_time_data(
    df: Any, times: Sequence[float] | None = None, *, by: str = "label", how: str = "best_known"
) -> Any:
    """Median gap to the reference of each solver's runs over time.

    Parameters
    ----------
    df : pandas.DataFrame
    times : sequence of float, optional
        Seconds (default: 50 points, log-spaced up to the longest runtime).
    by : str
    how : str
        The reference (:func:`reference`).

    Returns
    -------
    pandas.DataFrame
        Index ``time``, one column per solver; inf while most runs have no schedule.
    """
    import pandas as pd

    _need(df, [*_INSTANCE, by, "makespan", "runtime", "improvements"], "gap_over_time")
    g = with_gaps(df, how)
    if times is None:
        hi = float(np.nanmax(g["runtime"].astype(float))) if len(g) else 1.0
        t = np.geomspace(1e-3, max(hi, 2e-3), 50)
    else:
        t = np.asarray(times, dtype=float)
    cols = {}
    for name, sub in g.groupby(by):
        curves = []
        for _, row in sub.iterrows():
            ref = float(row["reference"])
            inc = incumbent_at(row, t)
            curves.append((inc - ref) / ref if ref > 0 else np.where(np.isfinite(inc), 0.0, np.inf))
        cols[name] = np.median(np.array(curves), axis=0)
    out = pd.DataFrame(cols, index=pd.Index(t, name="time"))
    out.columns.name = by
    return out


def gap_over_time(
    df: Any, times: Sequence[float] | None = None, *, by: str = "label", how: str = "best_known"
) -> Any:
    """Plot the median gap to the reference over time, per solver (log time axis).

    Parameters
    ----------
    df : pandas.DataFrame
    times : sequence of float, optional
    by, how : str
        See :func:`gap_over_time_data`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    data = gap_over_time_data(df, times, by=by, how=how)
    fig, ax = _figure()
    for col in data.columns:
        y = data[col].to_numpy(dtype=float)
        ax.step(data.index, np.where(np.isfinite(y), 100 * y, np.nan), where="post", label=str(col))
    ax.set_xscale("log")
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"median gap to {how.replace('_', '-')} (%)")
    ax.set_title("Gap over time")
    ax.legend()
    return fig


def time_to_target_data(
    df: Any, target: float = 0.01, *, by: str = "label", how: str = "best_known"
) -> Any:
    """When each run's incumbent first came within ``target`` of the reference.

    Parameters
    ----------
    df : pandas.DataFrame
    target : float
        Relative gap, e.g. 0.01 for 1 %.
    by, how : str

    Returns
    -------
    pandas.DataFrame
        Columns ``family``, ``instance``, ``by``, ``time`` (inf: never).
    """
    import pandas as pd

    _need(df, [*_INSTANCE, by, "makespan", "runtime", "improvements"], "time_to_target")
    g = with_gaps(df, how)
    rows = []
    for _, row in g.iterrows():
        goal = float(row["reference"]) * (1.0 + target)
        when = next((t for t, v in _improvements(row) if v <= goal + 1e-9), math.inf)
        rows.append(
            {"family": row["family"], "instance": row["instance"], by: row[by], "time": when}
        )
    return pd.DataFrame(rows, columns=["family", "instance", by, "time"])


def time_to_target(
    df: Any, target: float = 0.01, *, by: str = "label", how: str = "best_known"
) -> Any:
    """Plot the share of runs within ``target`` of the reference by each time (ECDF).

    Parameters
    ----------
    df : pandas.DataFrame
    target : float
    by, how : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    data = time_to_target_data(df, target, by=by, how=how)
    fig, ax = _figure()
    finite = data["time"][np.isfinite(data["time"])]
    right = max(float(finite.max()) * 1.5, 1e-2) if len(finite) else 1.0
    for name, sub in data.groupby(by):
        t = np.sort(sub["time"].to_numpy(dtype=float))
        ok = t[np.isfinite(t)]
        x = np.concatenate([[1e-4], np.maximum(ok, 1e-4), [right]])
        y = np.concatenate([[0.0], np.arange(1, len(ok) + 1) / len(t), [len(ok) / len(t)]])
        ax.step(x, y, where="post", label=str(name))
    ax.set_xscale("log")
    ax.set_ylim(0.0, 1.02)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"share of runs within {100 * target:g} % of {how.replace('_', '-')}")
    ax.set_title("Time to target")
    ax.legend()
    return fig


def scaling_data(
    df: Any, x: str = "n_tasks", y: str = "runtime", *, by: str = "label", how: str = "best_known"
) -> Any:
    """Median and quartiles of ``y`` per value of ``x``, per solver.

    Parameters
    ----------
    df : pandas.DataFrame
    x : str
        A size column: ``n_tasks``, ``n_arms``, ``n_zones``, ``n_modes``.
    y : str
        ``runtime``, ``wall_time``, ``makespan``, ``evaluations``, ... or
        ``gap`` (to the reference, :func:`with_gaps`).
    by, how : str

    Returns
    -------
    pandas.DataFrame
        Columns ``by``, ``x``, ``median``, ``q25``, ``q75``, ``runs``.
    """
    g = with_gaps(df, how) if y == "gap" else df
    _need(g, [x, y, by], "scaling")
    ok = g[np.isfinite(g[y].astype(float))]
    grouped = ok.groupby([by, x])[y]
    out = grouped.median().rename("median").to_frame()
    out["q25"] = grouped.quantile(0.25)
    out["q75"] = grouped.quantile(0.75)
    out["runs"] = grouped.size()
    return out.reset_index()


def scaling(
    df: Any,
    x: str = "n_tasks",
    y: str = "runtime",
    *,
    by: str = "label",
    how: str = "best_known",
    log: bool = True,
) -> Any:
    """Plot ``y`` against problem size ``x``: median line and quartile band per solver.

    Parameters
    ----------
    df : pandas.DataFrame
    x, y, by, how : str
        See :func:`scaling_data`.
    log : bool
        Log-scaled axes (the y axis only where all values are positive).

    Returns
    -------
    matplotlib.figure.Figure
    """
    data = scaling_data(df, x, y, by=by, how=how)
    fig, ax = _figure()
    for name, sub in data.groupby(by):
        sub = sub.sort_values(x)
        xs = sub[x].to_numpy(dtype=float)
        ax.plot(xs, sub["median"], marker="o", label=str(name))
        ax.fill_between(xs, sub["q25"].astype(float), sub["q75"].astype(float), alpha=0.2)
    if log:
        ax.set_xscale("log")
        if len(data) and (data["q25"].astype(float) > 0).all():
            ax.set_yscale("log")
    ax.set_xlabel(x.replace("n_", "").replace("_", " "))
    ax.set_ylabel(y)
    ax.set_title(f"Scaling of {y} with {x.replace('n_', '')}")
    ax.legend()
    return fig


def box_per_solver(df: Any, y: str = "gap", *, by: str = "label", how: str = "best_known") -> Any:
    """Box plots of ``y`` per solver (runs without a finite value are left out and counted).

    Parameters
    ----------
    df : pandas.DataFrame
    y : str
        ``gap`` (to the reference, in %), ``runtime``, ``makespan``, ...
    by, how : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    g = with_gaps(df, how) if y == "gap" else df
    _need(g, [y, by], "box_per_solver")
    names, data, missing = [], [], []
    for name, sub in g.groupby(by):
        v = sub[y].to_numpy(dtype=float)
        names.append(str(name))
        data.append(v[np.isfinite(v)] * (100 if y == "gap" else 1))
        missing.append(int((~np.isfinite(v)).sum()))
    fig, ax = _figure()
    ax.boxplot(
        data,
        tick_labels=[f"{n}\n({m} none)" if m else n for n, m in zip(names, missing, strict=True)],
    )
    ax.set_ylabel(f"{y} (%)" if y == "gap" else y)
    ax.set_title(f"{y} per solver")
    return fig


# ------------------------------------------------------------------ tables


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
    return sub.set_index(_INSTANCE)


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
    _need(df, [*_INSTANCE, "label", "makespan", "best_known", "lower_bound"], "fjsp_table")
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

    Returns
    -------
    str
        Markdown.
    """
    _need(df, [*_INSTANCE, "label", "makespan", "bound", "status"], "generated_table")
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
                "size": f"{params['arms']}x{params['tasks']}x{params['zones']}x{params['tools']}",
                "order": (params["tasks"], params["arms"]),
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
        "# Zone-constrained generated problems",
        "",
        f"tree, cpsat (short) and greedy: {tl[tree]:g} s; reference CP-SAT: {tl[reference_label]:g} s "
        "(sweep `benchmarks/sweeps/generated.toml`); size = arms x tasks x zones x tools. Target = "
        "the reference's optimum when proven, else its best bound (then gaps are upper bounds on "
        "the true gaps).",
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
    _need(df, [*_INSTANCE, "label", "makespan", "status", "runtime"], "small_table")
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
        Markdown: per cell and solver the status, makespan, lower bound and time.
    """
    _need(df, ["instance", "label", "status", "makespan", "lower_bound", "runtime"], "cells_table")
    lines = [
        "| cell | solver | status | makespan (s) | lower bound (s) | time (s) |",
        "|---|---|---|---|---|---|",
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
        lines.append(
            f"| {r['instance']} | {r['label']} | {r['status']} | {_fmt(float(r['makespan']), '.1f')} "
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
    need = [*_INSTANCE, "label", "makespan", "lower_bound", "runtime", "build_time"]
    _need(df, [*need, "evaluations", "instance_params", "instance_seed"], "scale_table")
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

    _need(df, ["family", "instance", "seed", "repetition", "status", "metrics"], "measurements")
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
    import datetime

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
