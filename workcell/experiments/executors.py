"""Where the runs of a sweep execute: this process, a local process pool, or a Dask cluster.

:func:`run_sweep` runs every run not yet recorded in the results (an
interrupted sweep resumes where it stopped), in a local process pool by
default or on a Dask cluster (``dask_address="tcp://host:8786"`` or a
``distributed.Client``); results stream to a journal as they finish and end
up in one Parquet file. A run that raises is recorded with status
``"error"`` and its message; the others go on.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import re
import signal
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

from multiarm.errors import UsageError
from workcell.experiments.analysis.tables import summary_table
from workcell.experiments.grid import Run, Sweep
from workcell.experiments.results import Journal, read_results
from workcell.experiments.rows import error_row
from workcell.experiments.runner import run_one
from workcell.experiments.spec import load_sweep

__all__ = ["SweepOutcome", "check_dask_address", "run_sweep"]


@dataclass(frozen=True, slots=True)
class SweepOutcome:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    out : Path
        The Parquet file holding every recorded run of the sweep.
    total : int
        Runs in the grid.
    ran, skipped, failed : int
        Runs executed now, skipped as already recorded, and recorded now with
        status ``"error"``.
    wall_time : float
        Seconds this call took.
    keys : frozenset of str
        The keys of the sweep's runs (its results file may also hold runs of
        an earlier version of the sweep file).
    failures : tuple of str
        One line per run recorded now with status ``"error"``: its instance
        (family/name and the instance file, where there is one), solver
        label, seed, and the error's type and message.
    """

    out: Path
    total: int
    ran: int
    skipped: int
    failed: int
    wall_time: float
    keys: frozenset[str] = frozenset()
    failures: tuple[str, ...] = ()

    @property
    def runs_per_minute(self) -> float:
        """Throughput of this call (runs executed per minute of wall clock)."""
        return 60.0 * self.ran / self.wall_time if self.wall_time > 0 else math.inf

    def results(self, current: bool = False) -> Any:
        """Every recorded run as a pandas DataFrame (:func:`~workcell.experiments.results.read_results`).

        Parameters
        ----------
        current : bool
            Only the runs of the sweep as it was run now (leaving out rows of
            an earlier grid kept in the same results file).

        Returns
        -------
        pandas.DataFrame
        """
        df = read_results(self.out)
        if current:
            df = df[df["key"].isin(self.keys)].reset_index(drop=True)
        return df

    def report(self) -> str:
        """What ``multiarm sweep`` prints at the end: the result table, each failure, the totals.

        Returns
        -------
        str
            :func:`~workcell.experiments.analysis.summary_table` of the
            sweep's runs, then one line per run that failed now (naming its
            instance, file and error), then the counts and the results file.
        """
        lines = []
        if self.out.exists() or self.out.with_name(self.out.name + ".journal").exists():
            lines.append(summary_table(self.results(current=True)))
        lines += [f"failed: {f}" for f in self.failures]
        lines.append(
            f"{self.ran} runs in {self.wall_time:.1f} s ({self.runs_per_minute:.1f} runs/min), "
            f"{self.skipped} already done, {self.failed} failed; results: {self.out}"
        )
        return "\n".join(lines)


def _progress_bar(total: int, initial: int, enabled: bool, desc: str) -> Any:
    if not enabled:
        return None
    from tqdm import tqdm  # type: ignore[import-untyped]

    return tqdm(total=total, initial=initial, desc=desc, unit="run", dynamic_ncols=True)


def _iter_local(pending: Sequence[Run], workers: int) -> Iterator[dict[str, Any]]:
    if workers <= 1:
        for r in pending:
            yield run_one(r)
        return
    # spawn: workers inherit no threads or locks (tqdm, OR-Tools, Dask) from the caller;
    # they ignore Ctrl-C, which the caller handles by stopping them
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(
        max_workers=workers, mp_context=ctx, initializer=_ignore_sigint
    ) as pool:
        futures = {pool.submit(run_one, r): r for r in pending}
        try:
            todo = set(futures)
            while todo:
                done, todo = wait(todo, return_when=FIRST_COMPLETED)
                for fut in done:
                    exc = fut.exception()
                    if exc is not None and not isinstance(exc, Exception):
                        raise KeyboardInterrupt  # a run was cut short: not recorded
                    if exc is not None:  # the worker process died (run_one itself never raises)
                        yield error_row(futures[fut], exc, repr(exc), wall_time=math.nan)
                    else:
                        yield fut.result()
        except BaseException:
            procs = list((getattr(pool, "_processes", None) or {}).values())
            for proc in procs:
                proc.terminate()  # runs still going are redone on resume
            pool.shutdown(wait=False, cancel_futures=True)
            raise


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


_ADDRESS = re.compile(
    r"^(?:(tcp|tls|inproc|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)(?::(\d{1,5}))?$"
)


def check_dask_address(address: str) -> str:
    """``address`` if it is a Dask scheduler address, else a clear error.

    Accepts ``[protocol://]host[:port]`` with a protocol Dask knows (``tcp``,
    ``tls``, ``inproc``, ``ucx``, ``ws``, ``wss``) and a port in 1-65535;
    this is checked before any run starts, so a typo never reaches Dask's
    own parser.

    Parameters
    ----------
    address : str

    Returns
    -------
    str

    Raises
    ------
    UsageError
        Not of that form (the message shows the form expected).

    Examples
    --------
    >>> check_dask_address("tcp://10.0.0.5:8786")
    'tcp://10.0.0.5:8786'
    >>> check_dask_address("tcp//host")
    Traceback (most recent call last):
    ...
    multiarm.errors.UsageError: --dask-address: 'tcp//host' is not a Dask scheduler address (expected [protocol://]host[:port], e.g. tcp://host:8786)
    """
    m = _ADDRESS.match(address) if isinstance(address, str) else None
    port = m.group(3) if m else None
    if m is None or (port is not None and not 1 <= int(port) <= 65535):
        raise UsageError(
            f"--dask-address: {address!r} is not a Dask scheduler address "
            "(expected [protocol://]host[:port], e.g. tcp://host:8786)"
        )
    return address


def _iter_dask(pending: Sequence[Run], scheduler: Any) -> Iterator[dict[str, Any]]:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - distributed is in the analysis extra
        raise UsageError(
            "running a sweep on a cluster needs dask.distributed (pip install distributed)"
        ) from exc
    own = isinstance(scheduler, str)
    if own:
        try:
            client = Client(scheduler, timeout="20s")  # type: ignore[no-untyped-call]
        except (OSError, TimeoutError) as exc:
            raise UsageError(
                f"--dask-address: cannot reach the Dask scheduler at {scheduler!r}: {exc}"
            ) from None
    else:
        client = scheduler
    try:
        futures = [
            client.submit(run_one, r, key=f"multiarm-run-{r.key}", pure=False) for r in pending
        ]
        by_key = {f.key: r for f, r in zip(futures, pending, strict=True)}
        try:
            for fut in as_completed(futures):  # type: ignore[no-untyped-call]
                try:
                    yield fut.result()
                except Exception as exc:  # the worker died or lost the task
                    yield error_row(by_key[fut.key], exc, repr(exc), wall_time=math.nan)
                fut.release()
        except BaseException:
            client.cancel(futures)  # type: ignore[no-untyped-call]  # redone on resume
            raise
    finally:
        if own:
            client.close()  # type: ignore[no-untyped-call]


def run_sweep(
    sweep: Sweep | str | PathLike[str],
    *,
    dask_address: Any = None,
    workers: int | None = None,
    out: str | PathLike[str] | None = None,
    progress: bool = True,
    retry_failed: bool = False,
    on_row: Callable[[dict[str, Any]], None] | None = None,
    scheduler: Any = None,
) -> SweepOutcome:
    """Run every run of a sweep not yet recorded in its results.

    Parameters
    ----------
    sweep : Sweep, str or path-like
        A sweep, or the path of a sweep file.
    dask_address : str, distributed.Client or None
        A Dask scheduler's address (``"tcp://host:8786"``, checked by
        :func:`check_dask_address` before anything runs) or a connected
        client: run on that cluster. ``None`` (default): a local process pool.
    workers : int or None
        Local processes (default: the sweep file's ``workers``, else the CPU
        count; 1 runs in this process). Ignored on a cluster, which has its
        own workers.
    out : str or path-like, optional
        The results file (default: the sweep file's ``out``).
    progress : bool
        Show a progress bar (tqdm, on stderr).
    retry_failed : bool
        Run again the runs recorded with status ``"error"``.
    on_row : callable, optional
        Called with each results row as it arrives.
    scheduler : str, distributed.Client or None
        Deprecated name of ``dask_address`` (*scheduler* names the package).

    Returns
    -------
    SweepOutcome

    Raises
    ------
    UsageError
        ``workers`` < 1, an unreachable scheduler, or results of another sweep in ``out``.
    KeyboardInterrupt
        After writing every run finished so far (the next call resumes).
    """
    t0 = time.perf_counter()
    if scheduler is not None:
        warnings.warn(
            "run_sweep(scheduler=...) is deprecated: use dask_address=",
            DeprecationWarning,
            stacklevel=2,
        )
        if dask_address is None:
            dask_address = scheduler
    if isinstance(dask_address, str):
        check_dask_address(dask_address)
    spec = sweep if isinstance(sweep, Sweep) else load_sweep(sweep)
    if workers is None:
        workers = spec.workers or os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise UsageError(f"workers must be an int >= 1, got {workers!r}")
    path = Path(out) if out is not None else spec.out
    runs = spec.runs()
    journal = Journal(path, spec.name)
    done = journal.done_keys(include_errors=not retry_failed)
    pending = [r for r in runs if r.key not in done]
    skipped = len(runs) - len(pending)
    bar = _progress_bar(len(runs), skipped, progress and bool(pending), spec.name)
    ran = failed = 0
    failures: list[str] = []
    rows: Iterable[dict[str, Any]] = (
        _iter_local(pending, workers) if dask_address is None else _iter_dask(pending, dask_address)
    )
    try:
        for row in rows:
            journal.append(row)
            ran += 1
            if row["status"] == "error":
                failed += 1
                failures.append(_failure_line(row))
            if on_row is not None:
                on_row(row)
            if bar is not None:
                bar.update(1)
                if failed:
                    bar.set_postfix(failed=failed)
    finally:
        if bar is not None:
            bar.close()
        journal.consolidate()
    return SweepOutcome(
        path,
        len(runs),
        ran,
        skipped,
        failed,
        time.perf_counter() - t0,
        frozenset(r.key for r in runs),
        tuple(failures),
    )


def _failure_line(row: dict[str, Any]) -> str:
    """``family/instance (file) [label, seed s]: ErrorType: first line of the message``."""
    source = str(row.get("source") or "")
    where = f"{row.get('family')}/{row.get('instance')}"
    if source and source != row.get("instance") and row.get("kind") != "benchmark":
        where += f" ({source})"
    message = (str(row.get("error") or "").strip().splitlines() or [""])[0]
    return (
        f"{where} [{row.get('label')}, seed {row.get('seed')}]: {row.get('error_type')}: {message}"
    )
