"""Sweep results: one row per run, with provenance, in one Parquet file.

Each row holds what identifies the run (sweep, instance, solver label and
options, limits, seed, repetition), what came out (status, the makespan
:func:`scheduler.validate` computed, the solver's objective and bound, our
lower bound, the improvements over time, counts, times) and where it came
from (package version, git commit, dependency versions, Python, host, CPU
count, process). :data:`COLUMNS` lists every column with its type
(:mod:`workcell.experiments.rows` builds the rows,
:mod:`workcell.experiments.provenance` their provenance).

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
import os
from pathlib import Path
from typing import Any

from multiarm.errors import FormatError, UsageError
from workcell.experiments.provenance import DEPENDENCIES, provenance
from workcell.experiments.rows import COLUMNS, benchmark_row, error_row, result_row

__all__ = [
    "COLUMNS",
    "DEPENDENCIES",
    "Journal",
    "benchmark_row",
    "check_output",
    "error_row",
    "provenance",
    "read_results",
    "result_row",
    "write_results",
]


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


def check_output(path: Path) -> None:
    """Refuse a results path that cannot be written, before any run starts.

    Raises
    ------
    UsageError
        ``path`` is a directory, its folder cannot be created, or the folder
        or an existing file is not writable (the message names the path).
    """
    if path.is_dir():
        raise UsageError(
            f"--out: {path} is a directory; give a results file such as {path / 'results.parquet'}"
        )
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(
            f"--out: cannot create the folder of {path}: {exc.strerror or exc}"
        ) from None
    if not path.parent.is_dir() or not os.access(path.parent, os.W_OK | os.X_OK):
        raise UsageError(f"--out: cannot write in {path.parent}")
    for p in (path, path.with_name(path.name + ".journal")):
        if p.exists() and (p.is_dir() or not os.access(p, os.W_OK)):
            raise UsageError(f"--out: {p} exists and cannot be written")


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
        check_output(self.path)
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
