"""The standard plots of the scheduling literature, from sweep results.

Every plot function returns a :class:`matplotlib.figure.Figure` built
without pyplot (no global state, no display needed: it renders with Agg,
``fig.savefig("x.png")``); each has a ``*_data`` twin that returns the
numbers behind it as a DataFrame (:mod:`workcell.experiments.analysis`
describes each plot).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from workcell.experiments.analysis.gaps import (
    INSTANCE,
    improvements_of,
    incumbent_at,
    need_columns,
    with_gaps,
)

__all__ = [
    "box_per_solver",
    "gap_over_time",
    "gap_over_time_data",
    "performance_profile",
    "performance_profile_data",
    "scaling",
    "scaling_data",
    "time_to_target",
    "time_to_target_data",
]


def _figure(width: float = 6.4, height: float = 4.0) -> tuple[Any, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    return fig, fig.add_subplot()


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

    need_columns(df, [*INSTANCE, by, metric], "performance_profile")
    table = df.pivot_table(index=INSTANCE, columns=by, values=metric, aggfunc="mean")
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

    need_columns(df, [*INSTANCE, by, "makespan", "runtime", "improvements"], "gap_over_time")
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

    need_columns(df, [*INSTANCE, by, "makespan", "runtime", "improvements"], "time_to_target")
    g = with_gaps(df, how)
    rows = []
    for _, row in g.iterrows():
        goal = float(row["reference"]) * (1.0 + target)
        when = next((t for t, v in improvements_of(row) if v <= goal + 1e-9), math.inf)
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
    need_columns(g, [x, y, by], "scaling")
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
    need_columns(g, [y, by], "box_per_solver")
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
