"""Sweep results: one row per run, with provenance, in one Parquet file.

Each row holds what identifies the run (sweep, instance, solver label and
options, limits, seed, repetition), what came out (status, the makespan
:func:`scheduler.validate` computed, the solver's objective and bound, our
lower bound, the improvements over time, counts, times) and where it came
from (package version, git commit, dependency versions, Python, host, CPU
count, process). :data:`COLUMNS` lists every column with its type.

While a sweep runs, rows are appended to a journal beside the results file
(``<out>.journal``, one JSON line per run, flushed at once), so that nothing
finished is lost when the sweep is interrupted; :meth:`Journal.consolidate`
merges the journal into the Parquet file (written atomically) and removes it.
:func:`read_results` reads both.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> from workcell.experiments.sweep import parse_sweep, run_sweep
>>> d = Path(tempfile.mkdtemp())
>>> sweep = parse_sweep('''
... [sweep]
... name = "doc"
... out = "doc.parquet"
... [[instances]]
... kind = "generated"
... sizes = [[2, 6, 2, 1]]
... seeds = [0]
... [[solvers]]
... solver = "greedy"
... ''', base_dir=d)
>>> outcome = run_sweep(sweep, workers=1, progress=False)
>>> df = read_results(outcome.out)
>>> len(df), df.loc[0, "status"], df.loc[0, "package_version"] != ""
(1, 'feasible', True)
>>> run_sweep(sweep, workers=1, progress=False).skipped  # resumed: nothing left to do
1
"""

from __future__ import annotations

import json
import math
import os
import platform
import socket
import subprocess
from collections.abc import Mapping
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from multiarm.errors import FormatError, UsageError

if TYPE_CHECKING:
    from scheduler import Problem, Result
    from workcell.experiments.grid import Run

__all__ = [
    "COLUMNS",
    "DEPENDENCIES",
    "Journal",
    "benchmark_row",
    "error_row",
    "provenance",
    "read_results",
    "result_row",
    "write_results",
]

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
improved incumbent); ``options``, ``instance_params`` and ``dependencies``
are JSON objects. ``status`` is a :class:`scheduler.SolveStatus` value or
``"error"`` (then ``error_type`` and ``error`` say what happened) or, for a
``benchmark`` run, ``"measured"``: then ``metrics`` holds what its
measurement function returned (a JSON list of rows) and the solver columns
are empty. ``load_average`` is the machine's one-minute load average when
the run started (timed runs on a busy machine are slower)."""

DEPENDENCIES = (
    "numpy",
    "numba",
    "ortools",
    "python-fcl",
    "ompl",
    "trimesh",
    "scipy",
    "lark",
    "pandas",
    "pyarrow",
    "dask",
    "distributed",
)
"""Distributions whose versions each row records."""


@lru_cache(maxsize=1)
def provenance() -> dict[str, Any]:
    """Where this process's runs come from (computed once per process).

    Returns
    -------
    dict
        ``package_version``, ``git_commit`` (of the checkout the package
        runs from, ``""`` outside one), ``dependencies`` (JSON), ``python``,
        ``platform``, ``host``, ``cpus``, ``pid``.
    """
    from multiarm import __version__

    deps: dict[str, str | None] = {}
    for name in DEPENDENCIES:
        try:
            deps[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            deps[name] = None
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            check=False,
            cwd=Path(__file__).resolve().parent,
            timeout=10,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            check=False,
            cwd=Path(__file__).resolve().parent,
            timeout=10,
        ).stdout.strip()
        if commit and dirty:
            commit += "+dirty"
    except (OSError, subprocess.SubprocessError):
        commit = ""
    return {
        "package_version": __version__,
        "git_commit": commit,
        "dependencies": json.dumps(deps, sort_keys=True),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "host": socket.gethostname(),
        "cpus": os.cpu_count() or 0,
        "pid": os.getpid(),
    }


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
            "error_type": type(exc).__name__,
            "error": f"{exc}\n{detail}".strip(),
            "metrics": "",
            "started": started,
            "load_average": _load_average(),
            **provenance(),
        }
    )
    return row


def _arrow() -> tuple[Any, Any]:
    """pyarrow and pyarrow.parquet (imported when results are read or written)."""
    import pyarrow as pa  # type: ignore[import-untyped]
    import pyarrow.parquet as pq  # type: ignore[import-untyped]

    return pa, pq


def _schema() -> Any:
    pa, _ = _arrow()
    types = {"string": pa.string(), "int64": pa.int64(), "float64": pa.float64()}
    return pa.schema([(c, types[t]) for c, t in COLUMNS.items()])


def write_results(rows: list[dict[str, Any]], path: str | os.PathLike[str]) -> Path:
    """Write rows as one Parquet file (atomically: a temporary file renamed).

    Parameters
    ----------
    rows : list of dict
        Results rows (missing columns become null).
    path : str or path-like

    Returns
    -------
    Path
    """
    pa, pq = _arrow()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pylist([{c: r.get(c) for c in COLUMNS} for r in rows], schema=_schema())
    tmp = out.with_name(out.name + ".tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, out)
    return out


def _read_parquet_rows(path: Path) -> list[dict[str, Any]]:
    _, pq = _arrow()
    try:
        table = pq.read_table(path)
    except Exception as exc:  # pyarrow raises several types for a damaged file
        raise FormatError(f"cannot read the results: {exc}", filename=str(path)) from None
    rows: list[dict[str, Any]] = table.to_pylist()
    return rows


def _read_journal_rows(path: Path) -> list[dict[str, Any]]:
    rows = []
    with path.open(encoding="utf-8") as fh:
        for i, line in enumerate(fh, 1):
            if not line.strip():
                continue
            try:
                rows.append(json.loads(line))
            except json.JSONDecodeError:
                if line.endswith("\n"):
                    raise FormatError(
                        "malformed results line", filename=str(path), line=i
                    ) from None
                # the last line of a journal cut off mid-write: that run is simply redone
    return rows


class Journal:
    """The results of one sweep: the Parquet file and its journal of new rows.

    Parameters
    ----------
    path : path-like
        The Parquet file.
    sweep : str
        The sweep's name; rows of another sweep in ``path`` are refused.

    Raises
    ------
    UsageError
        ``path`` holds results of another sweep.
    """

    def __init__(self, path: str | os.PathLike[str], sweep: str) -> None:
        self.path = Path(path)
        self.journal = self.path.with_name(self.path.name + ".journal")
        self.sweep = sweep
        self.rows: list[dict[str, Any]] = []
        if self.path.exists():
            self.rows += _read_parquet_rows(self.path)
        if self.journal.exists():
            self.rows += _read_journal_rows(self.journal)
        others = {r.get("sweep") for r in self.rows} - {sweep}
        if others:
            raise UsageError(
                f"{self.path} holds results of sweep {sorted(map(str, others))[0]!r}, "
                f"not {sweep!r}: choose another output file"
            )

    def done_keys(self, include_errors: bool = True) -> set[str]:
        """Keys of the runs recorded (with or without those that failed)."""
        return {str(r["key"]) for r in self.rows if include_errors or r.get("status") != "error"}

    def append(self, row: dict[str, Any]) -> None:
        """Record a finished run at once (one flushed JSON line)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self.journal.open("a", encoding="utf-8") as fh:
            fh.write(json.dumps(row, default=str) + "\n")
            fh.flush()
        self.rows.append(row)

    def consolidate(self) -> Path | None:
        """Merge the journal into the Parquet file (the last row of each key wins).

        Returns
        -------
        Path or None
            The Parquet file (None when there is nothing to write).
        """
        if not self.rows:
            return None
        latest: dict[str, dict[str, Any]] = {}
        for r in self.rows:
            latest[str(r["key"])] = r
        write_results(list(latest.values()), self.path)
        self.journal.unlink(missing_ok=True)
        return self.path


def read_results(*paths: str | os.PathLike[str]) -> Any:
    """Read results files (and any journal of a sweep still running) into one DataFrame.

    Parameters
    ----------
    *paths : str or path-like
        Parquet files written by :func:`~workcell.experiments.run_sweep`.

    Returns
    -------
    pandas.DataFrame
        One row per run, with the columns of :data:`COLUMNS` (the last row of
        a key wins when a failed run was run again).

    Raises
    ------
    FormatError
        A file that is not readable results.
    UsageError
        No file given, or none exists.
    """
    import pandas as pd

    if not paths:
        raise UsageError("read_results needs at least one results file")
    rows: list[dict[str, Any]] = []
    found = False
    for p in map(Path, paths):
        journal = p.with_name(p.name + ".journal")
        if p.exists():
            rows += _read_parquet_rows(p)
            found = True
        if journal.exists():
            rows += _read_journal_rows(journal)
            found = True
    if not found:
        raise UsageError(f"no results at {', '.join(map(str, paths))}")
    latest: dict[str, dict[str, Any]] = {}
    for r in rows:
        latest[str(r["key"])] = r
    df = pd.DataFrame(
        [{c: r.get(c) for c in COLUMNS} for r in latest.values()], columns=list(COLUMNS)
    )
    for c, t in COLUMNS.items():
        if t == "float64":
            df[c] = pd.to_numeric(df[c], errors="coerce").astype("float64")
        elif t == "int64":
            df[c] = pd.to_numeric(df[c], errors="coerce").astype("Int64")
        else:
            df[c] = df[c].astype("string")
    return df.reset_index(drop=True)
