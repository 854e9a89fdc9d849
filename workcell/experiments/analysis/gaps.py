"""Gaps to a reference makespan, and the incumbent of a run over time.

The reference of an instance is its best-known makespan where the sweep file
gives one, else the best makespan any run found on it (:func:`reference`);
the gap of a run is ``(makespan - reference) / reference`` (:func:`with_gaps`).
:func:`incumbent_at` replays a run's improvements (the ``improvements``
column of :data:`~workcell.experiments.rows.COLUMNS`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from multiarm.errors import UsageError

__all__ = ["INSTANCE", "improvements_of", "incumbent_at", "need_columns", "reference", "with_gaps"]

INSTANCE = ["family", "instance"]
"""The columns that name an instance in a results frame."""


def need_columns(df: Any, columns: Sequence[str], what: str) -> None:
    """Refuse ``df`` without ``columns`` (a UsageError naming them and ``what`` needs them)."""
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise UsageError(f"{what} needs the columns {missing} (results of run_sweep have them)")


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
    need_columns(df, [*INSTANCE, "makespan"], "reference")
    best = df.groupby(INSTANCE)["makespan"].transform("min").astype(float)
    if how == "best":
        return best
    if how == "bound":
        need_columns(df, ["bound"], "reference(how='bound')")
        return df.groupby(INSTANCE)["bound"].transform("max").astype(float)
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


def improvements_of(row: Any) -> list[tuple[float, float]]:
    """The ``(seconds, makespan)`` improvements of a results row, ending at its final makespan."""
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
    pts = improvements_of(row)
    t = np.asarray(times, dtype=float)
    out = np.full(t.shape, np.inf)
    for when, value in pts:
        out = np.where(t >= when, np.minimum(out, value), out)
    return out
