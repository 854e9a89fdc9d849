"""The results row of a run: its columns and how a finished, measured or failed run fills them.

:data:`COLUMNS` lists every column with its Arrow type; :func:`result_row`,
:func:`benchmark_row` and :func:`error_row` build the row of a solver run, a
``benchmark`` run and a run that raised (:mod:`workcell.experiments.results`
stores the rows).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from typing import Any

from multiarm.errors import UsageError
from scheduler import Problem, Result
from workcell.experiments.grid import Run
from workcell.experiments.provenance import provenance

__all__ = ["COLUMNS", "benchmark_row", "error_row", "result_row"]

COLUMNS: dict[str, str] = {
    # what ran
    "key": "string",
    "sweep": "string",
    "family": "string",
    "instance": "string",
    "kind": "string",
    "source": "string",
    "instance_params": "string",
    "instance_seed": "int64",
    "best_known": "float64",
    "n_arms": "int64",
    "n_tasks": "int64",
    "n_zones": "int64",
    "n_tools": "int64",
    "n_modes": "int64",
    "label": "string",
    "solver": "string",
    "options": "string",
    "time_limit": "float64",
    "seed": "int64",
    "repetition": "int64",
    # what came out
    "status": "string",
    "makespan": "float64",
    "objective": "float64",
    "bound": "float64",
    "lower_bound": "float64",
    "runtime": "float64",
    "wall_time": "float64",
    "build_time": "float64",
    "warmup_time": "float64",
    "first_time": "float64",
    "best_time": "float64",
    "first_objective": "float64",
    "improvements": "string",
    "phases": "string",
    "nodes": "int64",
    "pruned": "int64",
    "evaluations": "int64",
    "error_type": "string",
    "error": "string",
    "metrics": "string",
    # where it came from
    "started": "float64",
    "load_average": "float64",
    "package_version": "string",
    "git_commit": "string",
    "dependencies": "string",
    "python": "string",
    "platform": "string",
    "host": "string",
    "cpus": "int64",
    "pid": "int64",
}
"""Every column of a results row and its Arrow type.

``makespan`` is :func:`scheduler.validate`'s (inf without a schedule);
``objective`` the solver's own; ``bound`` the solver's best proven bound;
``lower_bound`` :func:`scheduler.lower_bound`'s. Times are seconds:
``runtime`` the solver's, ``wall_time`` the whole run (building the problem
included), ``build_time`` building it (0 when cached in the worker),
``warmup_time`` loading the scheduler's compiled kernel before the
solver's clock started (once per process, else 0).
``improvements`` is a JSON list of ``[seconds, makespan]`` pairs (each
improved incumbent); ``phases`` a JSON object of the solver's
phases and the seconds each took (every solver's ``bound``, CP-SAT's
``model``, the tree's ``beam``, ``improve``, ``polish``, ``exact``, ...;
empty for a ``benchmark`` run or an error, null in files written before
the column existed); ``options``, ``instance_params`` and ``dependencies``
are JSON objects. ``status`` is a :class:`scheduler.SolveStatus` value or
``"error"`` (then ``error_type`` and ``error`` say what happened) or, for a
``benchmark`` run, ``"measured"``: then ``metrics`` holds what its
measurement function returned (a JSON list of rows) and the solver columns
are empty. ``load_average`` is the machine's one-minute load average when
the run started (timed runs on a busy machine are slower)."""


def _run_fields(run: Run) -> dict[str, Any]:
    inst, cfg = run.instance, run.config
    return {
        "key": run.key,
        "sweep": run.sweep,
        "family": inst.family,
        "instance": inst.name,
        "kind": inst.kind,
        "source": inst.source,
        "instance_params": json.dumps(dict(inst.params), sort_keys=True),
        "instance_seed": inst.seed,
        "best_known": math.nan if inst.best_known is None else inst.best_known,
        "label": cfg.label,
        "solver": cfg.solver,
        "options": json.dumps(dict(cfg.options), sort_keys=True, default=str),
        "time_limit": math.nan if cfg.time_limit is None else cfg.time_limit,
        "seed": run.seed,
        "repetition": run.repetition,
    }


def result_row(
    run: Run,
    problem: Problem,
    result: Result,
    makespan: float,
    lower_bound: float,
    *,
    build_time: float,
    wall_time: float,
    started: float,
    warmup_time: float = 0.0,
) -> dict[str, Any]:
    """The results row of a finished run.

    Parameters
    ----------
    run : Run
    problem : scheduler.Problem
    result : scheduler.Result
    makespan : float
        :func:`scheduler.validate` of the result's schedule (inf without one).
    lower_bound : float
        :func:`scheduler.lower_bound` of the problem.
    build_time, wall_time, started : float
        Seconds building the problem, seconds of the whole run, and the
        run's start (Unix time).
    warmup_time : float
        Seconds loading the compiled kernel before the solver's clock.

    Returns
    -------
    dict
    """
    s = result.stats
    return {
        **_run_fields(run),
        "n_arms": problem.n_arms,
        "n_tasks": problem.n_tasks,
        "n_zones": problem.n_zones,
        "n_tools": problem.n_tools,
        "n_modes": problem.n_modes,
        "status": result.status.value,
        "makespan": float(makespan),
        "objective": float(result.objective),
        "bound": float(result.bound),
        "lower_bound": float(lower_bound),
        "runtime": float(result.runtime),
        "wall_time": float(wall_time),
        "build_time": float(build_time),
        "warmup_time": float(warmup_time),
        "first_time": float(s.first_time),
        "best_time": float(s.best_time),
        "first_objective": float(s.first_objective),
        "improvements": json.dumps([[float(t), float(v)] for t, v in s.improvements]),
        "phases": json.dumps({str(k): float(v) for k, v in s.phases.items()}, sort_keys=True),
        "nodes": int(s.nodes),
        "pruned": int(s.pruned),
        "evaluations": int(s.evaluations),
        "error_type": "",
        "error": "",
        "metrics": "",
        "started": started,
        "load_average": _load_average(),
        **provenance(),
    }


def _load_average() -> float:
    try:
        return float(os.getloadavg()[0])
    except (AttributeError, OSError):  # not on every platform
        return math.nan


def _plain(value: Any, where: str) -> Any:
    """``value`` as JSON data (numpy scalars and arrays, tuples to lists); else a UsageError."""
    if isinstance(value, bool | str) or value is None:
        return value
    if isinstance(value, int | float):
        return value
    if isinstance(value, Mapping):
        return {str(k): _plain(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v, f"{where}[{i}]") for i, v in enumerate(value)]
    tolist = getattr(value, "tolist", None)  # numpy scalars and arrays
    if callable(tolist):
        return _plain(tolist(), where)
    raise UsageError(
        f"{where}: a measurement must be numbers, strings, lists or dicts, got {value!r}"
    )


def benchmark_row(run: Run, measured: Any, *, wall_time: float, started: float) -> dict[str, Any]:
    """The results row of a ``benchmark`` run (status ``"measured"``).

    Parameters
    ----------
    run : Run
    measured : dict or list of dict
        What the measurement function returned: one row of a table, or
        several.
    wall_time, started : float

    Returns
    -------
    dict

    Raises
    ------
    UsageError
        ``measured`` is not a dict or a list of dicts of plain data.
    """
    rows = [measured] if isinstance(measured, Mapping) else measured
    if not isinstance(rows, list | tuple) or not all(isinstance(r, Mapping) for r in rows):
        raise UsageError(
            f"benchmark {run.instance.source!r} must return a dict or a list of dicts, "
            f"got {type(measured).__name__}"
        )
    nan = math.nan
    row: dict[str, Any] = {c: None for c in COLUMNS}
    row.update(_run_fields(run))
    row.update(
        {
            "status": "measured",
            "makespan": nan,
            "objective": nan,
            "bound": nan,
            "lower_bound": nan,
            "runtime": float(wall_time),
            "wall_time": float(wall_time),
            "build_time": 0.0,
            "warmup_time": 0.0,
            "first_time": nan,
            "best_time": nan,
            "first_objective": nan,
            "improvements": "[]",
            "phases": "{}",
            "error_type": "",
            "error": "",
            "metrics": json.dumps(_plain(list(rows), run.instance.source), allow_nan=True),
            "started": started,
            "load_average": _load_average(),
            **provenance(),
        }
    )
    return row


def error_row(
    run: Run, exc: BaseException, detail: str, *, wall_time: float, started: float = math.nan
) -> dict[str, Any]:
    """The results row of a run that raised (status ``"error"``).

    Parameters
    ----------
    run : Run
    exc : BaseException
    detail : str
        The end of the traceback (kept in ``error`` after the message).
    wall_time, started : float

    Returns
    -------
    dict
    """
    nan = math.nan
    row: dict[str, Any] = {c: None for c in COLUMNS}
    row.update(_run_fields(run))
    row.update(
        {
            "status": "error",
            "makespan": math.inf,
            "objective": math.inf,
            "bound": nan,
            "lower_bound": nan,
            "runtime": nan,
            "wall_time": wall_time,
            "build_time": nan,
            "first_time": nan,
            "best_time": nan,
            "first_objective": math.inf,
            "improvements": "[]",
            "phases": "{}",
            "error_type": type(exc).__name__,
            "error": f"{exc}\n{detail}".strip(),
            "metrics": "",
            "started": started,
            "load_average": _load_average(),
            **provenance(),
        }
    )
    return row
