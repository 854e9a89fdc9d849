"""Helpers shared by the benchmark scripts: timing, machine info, running sweeps, writing results.

Every published table comes from a sweep file in ``benchmarks/sweeps/``: a
script runs its sweep (:func:`run_table_sweep`, resuming where a previous run
stopped unless ``--fresh``), renders the table from the Parquet results and
writes ``results/NAME.md`` and ``NAME.json`` (:func:`publish`). With
``--quick`` it runs the sweep file's reduced ``[quick]`` grid into a
temporary directory (or ``MULTIARM_RESULTS``), never over the published
results.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

RESULTS = Path(os.environ.get("MULTIARM_RESULTS", Path(__file__).resolve().parent / "results"))
"""Where results go (``MULTIARM_RESULTS`` overrides, e.g. for smoke tests)."""

SWEEPS = Path(__file__).resolve().parent / "sweeps"
"""The sweep files, one per published table (``NAME.toml``)."""


def machine() -> dict[str, Any]:
    """What ran the benchmark (results are only comparable within one run)."""
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            check=False,
            cwd=Path(__file__).parent,
        ).stdout.strip()
    except OSError:
        commit = ""
    try:
        load = round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        load = None
    return {
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "commit": commit,
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "load_average": load,
    }


def best_rate(fn: Callable[[], int], repeat: int = 5) -> tuple[float, list[float]]:
    """Run ``fn`` (which returns how many operations it did) ``repeat`` times;
    return the best rate (ops/s) and every rate. Best-of damps machine noise."""
    rates = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        n = fn()
        rates.append(n / (time.perf_counter() - t0))
    return max(rates), rates


def write(name: str, data: dict[str, Any], table: str, out: Path | None = None) -> Path:
    """Write ``<out>/<name>.json`` and ``<out>/<name>.md`` (``out``: :data:`RESULTS`)."""
    where = RESULTS if out is None else out
    where.mkdir(parents=True, exist_ok=True)
    data = {"machine": machine(), **data}
    (where / f"{name}.json").write_text(json.dumps(data, indent=2, default=str) + "\n")
    (where / f"{name}.md").write_text(table)
    return where / f"{name}.md"


def output_dir(quick: bool) -> Path:
    """Where a run writes: ``MULTIARM_RESULTS`` if set, else a new temporary
    directory for a quick run (never the published results), else :data:`RESULTS`."""
    if "MULTIARM_RESULTS" in os.environ:
        return Path(os.environ["MULTIARM_RESULTS"])
    if not quick:
        return RESULTS
    return Path(tempfile.mkdtemp(prefix="multiarm-quick-"))


def sweep_arguments(ap: argparse.ArgumentParser, *, fresh: bool = False) -> None:
    """Add ``--quick``, ``--fresh`` (or ``--resume``) and ``--workers`` to a wrapper's parser.

    ``fresh=True`` (the speed tables): every run measures again unless
    ``--resume``; else (solver tables) the sweep resumes unless ``--fresh``.
    """
    ap.add_argument(
        "--quick",
        action="store_true",
        help="the sweep file's [quick] grid, into a temporary directory (smoke run)",
    )
    if fresh:
        ap.add_argument(
            "--resume",
            dest="fresh",
            action="store_false",
            help="keep the measurements already recorded (default: measure everything again)",
        )
        ap.set_defaults(fresh=True)
    else:
        ap.add_argument(
            "--fresh",
            action="store_true",
            help="discard the recorded runs and run the whole sweep again (default: resume)",
        )
    ap.add_argument(
        "--workers",
        type=int,
        default=None,
        help="local processes (default: the sweep file's workers, 1 for every published table)",
    )


def run_table_sweep(
    name: str, args: argparse.Namespace, out: Path, *, sweep_file: str | None = None
) -> Any:
    """Run ``sweeps/<sweep_file or name>.toml`` into ``<out>/<stem>.parquet``; return its results.

    Parameters
    ----------
    name : str
        The table's name (the script's ``NAME``).
    args : argparse.Namespace
        With ``quick``, ``fresh`` and ``workers`` (:func:`sweep_arguments`).
    out : Path
        The results directory (:func:`output_dir`).
    sweep_file : str, optional
        The sweep file's stem when it is not ``name``.

    Returns
    -------
    pandas.DataFrame
        The rows of this sweep's runs (not of an earlier version of the file).
    """
    from multiarm.errors import MultiarmError
    from workcell.experiments import load_sweep, run_sweep

    stem = sweep_file or name
    try:
        sweep = load_sweep(SWEEPS / f"{stem}.toml")
    except MultiarmError as exc:  # e.g. the FJSP files beside the repository are missing
        raise SystemExit(f"bench_{name}: {exc}") from None
    if args.quick:
        sweep = sweep.quick_version()
    path = out / f"{stem}.parquet"
    if args.fresh:
        for p in (path, path.with_name(path.name + ".journal")):
            p.unlink(missing_ok=True)
    outcome = run_sweep(sweep, workers=args.workers, out=path, progress=sys.stderr.isatty())
    print(
        f"{stem}: {outcome.ran} runs now, {outcome.skipped} recorded before, "
        f"{outcome.failed} failed; {path}",
        flush=True,
    )
    df = outcome.results(current=True)
    failed = df[df["status"] == "error"]
    if len(failed):
        first = failed.iloc[0]
        raise SystemExit(
            f"{stem}: {len(failed)} runs failed, e.g. {first['instance']} / {first['label']}: "
            f"{first['error_type']}: {str(first['error']).splitlines()[0]} "
            "(run again with --fresh or fix the cause)"
        )
    return df


def publish(
    name: str,
    df: Any,
    table: str,
    out: Path,
    *,
    rows: Any = None,
    sweeps: tuple[str, ...] = (),
    quick: bool = False,
    flags: str = "",
    extra: dict[str, Any] | None = None,
    script: str | None = None,
) -> Path:
    """Write ``<out>/<name>.md`` (the table and its provenance note) and ``<name>.json``.

    Parameters
    ----------
    name : str
    df : pandas.DataFrame
        The sweep's results (for the provenance note and the seeds).
    table : str
        The rendered Markdown table.
    out : Path
    rows : pandas.DataFrame, optional
        The rows the JSON holds (default: ``df`` without the dependency list).
    sweeps : tuple of str
        The sweep files' stems (default: ``name``).
    quick : bool
        A smoke run (said in the command line of the note).
    flags : str
        Options of the command that reproduces the table (``--fresh`` for a
        solver table: without it the script only renders recorded runs); a
        quick run's command keeps them but ``--fresh``, and adds ``--quick``.
    extra : dict, optional
        More fields of the JSON.
    script : str, optional
        The module that reproduces the table (default: ``bench_<name>``).

    Returns
    -------
    Path
        The Markdown file.
    """
    from workcell.experiments.analysis import sweep_note

    stems = sweeps or (name,)
    command = " ".join(
        [
            "python -m benchmarks." + (script or "bench_" + name),
            *(
                [f for f in flags.split() if f != "--fresh"] + ["--quick"]
                if quick
                else flags.split()
            ),
        ]
    )
    files = [f"benchmarks/sweeps/{s}.toml" for s in stems]
    note = sweep_note(df, sweep_file=files, command=command)
    data_rows = df.drop(columns=["dependencies"], errors="ignore") if rows is None else rows
    seeds = sorted({int(s) for s in df["seed"].dropna()}) if "seed" in df.columns else []
    data = {
        "command": command,
        "sweeps": [f"{s}.toml" for s in stems],
        "results": [f"{s}.parquet" for s in stems],
        "quick": quick,
        "seeds": seeds,
        **(extra or {}),
        "rows": json.loads(data_rows.to_json(orient="records")),
    }
    return write(name, data, table.rstrip("\n") + "\n\n" + note, out)


def table_main(
    name: str,
    render: Callable[[Any], str],
    argv: list[str] | None,
    description: str | None,
    *,
    speed: bool,
    one_row: bool = False,
) -> Path:
    """The whole of a wrapper script: parse its arguments, run its sweep, write its table.

    Parameters
    ----------
    name : str
        The table (``sweeps/<name>.toml``, ``results/<name>.md``).
    render : callable
        Makes the Markdown table: of the sweep's results (a solver table) or
        of :func:`~workcell.experiments.analysis.measurements` of them (a
        speed table; of its first row with ``one_row``).
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    description : str or None
        The script's docstring (its ``--help``).
    speed : bool
        A speed table: measured again on every call, the JSON holds the
        measured rows. Else a solver table: the sweep resumes unless
        ``--fresh``, the JSON holds the results rows.

    Returns
    -------
    Path
        The Markdown file written.
    """
    from workcell.experiments.analysis import measurements

    ap = argparse.ArgumentParser(
        description=description, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sweep_arguments(ap, fresh=speed)
    args = ap.parse_args(argv)
    out = output_dir(args.quick)
    df = run_table_sweep(name, args, out)
    if speed:
        m = measurements(df)
        md = render(m.iloc[0] if one_row else m)
        path = publish(name, df, md, out, quick=args.quick, rows=m)
    else:
        path = publish(name, df, render(df), out, quick=args.quick, flags="--fresh")
    print(path.read_text())
    return path


class RevisionProcess:
    """Another git revision's code in a second process, fed one line at a time.

    The revision is unpacked (``git archive``) into a temporary directory;
    ``script`` runs there as ``python -c script ROOT JOB`` (``ROOT`` the
    unpacked tree, to put first on ``sys.path``; ``JOB`` a file holding
    ``job``), prints ``ready`` once set up, then answers each line sent with
    one line of JSON. Benchmarks measure the baseline side by side this way,
    alternating with their own runs, so ratios hold on a loaded machine.

    Parameters
    ----------
    rev : str
        A git revision of this repository.
    script : str
        The child's Python source.
    job : bytes
        What the child reads from ``JOB``.
    """

    def __init__(self, rev: str, script: str, job: bytes) -> None:
        import io
        import tarfile

        self.dir = tempfile.TemporaryDirectory(prefix="multiarm-baseline-")
        root = Path(self.dir.name)
        repo = Path(__file__).resolve().parent.parent
        tar = subprocess.run(
            ["git", "archive", "--format=tar", rev], cwd=repo, capture_output=True, check=True
        ).stdout
        with tarfile.open(fileobj=io.BytesIO(tar)) as tf:
            tf.extractall(root, filter="data")
        self.rev = subprocess.run(
            ["git", "rev-parse", "--short", rev], cwd=repo, capture_output=True, text=True
        ).stdout.strip()
        (root / "job").write_bytes(job)
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        self.proc = subprocess.Popen(
            [sys.executable, "-c", script, str(root), str(root / "job")],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=root,
            env=env,
        )
        if self._line() != "ready":
            self.close()
            raise RuntimeError(f"the baseline {rev!r} did not start")

    def _line(self) -> str:
        assert self.proc.stdout is not None
        return self.proc.stdout.readline().strip()

    def ask(self, line: str) -> dict[str, Any]:
        """Send one line; return the child's answer (one line of JSON)."""
        assert self.proc.stdin is not None
        self.proc.stdin.write(line.rstrip("\n") + "\n")
        self.proc.stdin.flush()
        got = self._line()
        if not got:
            raise RuntimeError("the baseline process stopped")
        out: dict[str, Any] = json.loads(got)
        return out

    def close(self) -> None:
        """End the child and remove its tree."""
        if self.proc.stdin is not None and not self.proc.stdin.closed:
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=60)
        finally:
            self.dir.cleanup()
