"""Fuzz campaigns: each target in its own process, one after the other.

Usage::

    python -m tests.fuzz.campaign [--runs N] [--max-time S] [--timeout S]
                                  [--seed N] [--targets a,b,...] [--out PREFIX]
                                  [--artifacts DIR] [--crashes DIR]

Each target (:data:`tests.fuzz.targets.TARGETS`) runs under atheris with its
seeds (the shipped examples and ``tests/fuzz/corpus/<target>/``) until it has
executed ``--runs`` inputs or spent ``--max-time`` seconds. A finding (an
exception outside our family, an error naming no place, a hang longer than
``--timeout`` seconds, more than ``--rss-limit`` MB) stops that target; its
input is written to ``--artifacts`` (``.fuzz/`` by default) and shown, and
with ``--crashes DIR`` also copied to ``DIR/<target>/`` (``make fuzz``:
``tests/fuzz/crashes``, where the tests replay it). With
``--out PREFIX`` the figures go to ``PREFIX.json`` and ``PREFIX.md``.
``make fuzz`` runs the long campaign; the test suite runs a short one
(``tests/fuzz/test_fuzz.py``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from tests.fuzz.targets import ALL, ALL_ORDER, ROOT, TARGETS, seed_inputs

__all__ = ["FuzzRun", "fuzz_target", "main"]


@dataclass(frozen=True, slots=True)
class FuzzRun:
    """The figures of one target's run.

    Attributes
    ----------
    target : str
    status : str
        ``"ok"`` (no finding), ``"crash"`` (an exception escaped the target),
        ``"timeout"`` (a hang), ``"oom"``, ``"killed"`` (by a signal from
        outside, say the kernel's out-of-memory killer) or ``"error"`` (the
        run itself failed; see ``log``).
    inputs : int
        Inputs executed (libFuzzer's ``number_of_executed_units``).
    seconds : float
        Wall time of the process, start-up included.
    exec_per_s : float
        libFuzzer's average executions per second.
    coverage : int or None
        Coverage counters reached (libFuzzer's ``cov``: Python branches of our
        packages and lark).
    features : int or None
        libFuzzer's ``ft`` (coverage features).
    corpus : int or None
        Inputs kept in the corpus at the end.
    seeds : int
        Seed files given.
    artifact : str or None
        The input of the finding.
    log : str
        The last lines of the fuzzer's output.
    per_target : dict of str to int, or None
        For the multiplexed target ``all``: inputs run by each target (as
        last reported by the process, every 200 inputs).
    distinct : int or None
        For ``compile``: distinct cells compiled (the harness answers a cell
        it has compiled before from a memo; reported every 50).
    """

    target: str
    status: str
    inputs: int
    seconds: float
    exec_per_s: float
    coverage: int | None
    features: int | None
    corpus: int | None
    seeds: int
    artifact: str | None
    log: str
    per_target: dict[str, int] | None = None
    distinct: int | None = None


def _excerpt(stdout: str, stderr: str) -> str:
    """The lines that explain a run: from the first error report (an uncaught
    exception, libFuzzer's ``==ERROR``, a deadly signal) on, else the last 60
    lines of each stream, and the return status."""
    lines = (stdout + "\n" + stderr).splitlines()
    marks = ("Uncaught Python exception", "==ERROR", "ERROR: libFuzzer", "deadly signal")
    first = next((i for i, line in enumerate(lines) if any(m in line for m in marks)), None)
    if first is not None:
        return "\n".join(lines[max(0, first - 5) : first + 80])
    return "\n".join([*stdout.splitlines()[-60:], "--- stderr:", *stderr.splitlines()[-60:]])


def _last_int(pattern: str, text: str) -> int | None:
    found = re.findall(pattern, text)
    return int(found[-1]) if found else None


def fuzz_target(
    name: str,
    *,
    runs: int,
    max_time: int,
    timeout: int = 10,
    seed: int = 1,
    rss_limit_mb: int = 2048,
    artifacts: Path | None = None,
    seeds: list[tuple[str, bytes]] | None = None,
    crashes: Path | None = None,
) -> FuzzRun:
    """Run target ``name`` in a subprocess and return its figures.

    Parameters
    ----------
    name : str
        A key of :data:`~tests.fuzz.targets.TARGETS`, or ``"all"`` (every
        target in one process, :class:`~tests.fuzz.targets.Multiplex`).
    runs : int
        Inputs to execute (libFuzzer ``-runs``).
    max_time : int
        Seconds at most (libFuzzer ``-max_total_time``).
    timeout : int
        Seconds one input may take before it counts as a hang.
    seed : int
        libFuzzer's random seed (> 0; the same seed mutates the same way).
    rss_limit_mb : int
        Memory limit of the process.
    artifacts : Path, optional
        Folder the input of a finding is written to (a temporary one, deleted
        with the rest, when not given).
    seeds : list of (str, bytes), optional
        The seed inputs (default: :func:`~tests.fuzz.targets.seed_inputs` of
        ``name``; required for a ``module:function`` target).
    crashes : Path, optional
        Also copy the input of a finding to ``crashes/<target>/`` (the
        reproducers replayed by the tests, ``tests/fuzz/crashes``), named
        ``<status>-<first 12 hex digits of its sha1><the target's suffix>``.

    Notes
    -----
    The input of a finding is the test unit libFuzzer wrote, else the one the
    target process wrote itself (``finding input written to``), else, when
    the process died without either (killed from outside, say by the
    out-of-memory killer), the input it was running (``<prefix>current``,
    kept as ``<name>-lost-<sha1>``).
    """
    short = name.rsplit(":", 1)[-1]  # a module:function target by its function's name
    with tempfile.TemporaryDirectory(prefix=f"multiarm-fuzz-{short}-") as tmp:
        work, seed_dir, corpus = Path(tmp, "work"), Path(tmp, "seeds"), Path(tmp, "corpus")
        for d in (work, seed_dir, corpus):
            d.mkdir()
        files = seed_inputs(name) if seeds is None else seeds
        for i, (label, data) in enumerate(files):
            (seed_dir / f"{i:03d}_{label}").write_bytes(data)
        out = Path(artifacts) if artifacts is not None else Path(tmp, "artifacts")
        out.mkdir(parents=True, exist_ok=True)
        cmd = [
            sys.executable,
            "-m",
            "tests.fuzz.run",
            name,
            str(work),
            f"-runs={runs}",
            f"-max_total_time={max_time}",
            f"-timeout={timeout}",
            f"-rss_limit_mb={rss_limit_mb}",
            f"-seed={seed}",
            f"-artifact_prefix={out}/{short}-",
            "-print_final_stats=1",
            str(corpus),
            str(seed_dir),
        ]
        t0 = time.perf_counter()
        proc = subprocess.run(
            cmd,
            cwd=ROOT,
            capture_output=True,
            text=True,
            errors="replace",
            timeout=max_time + 10 * timeout + 300,
            check=False,
        )
        seconds = time.perf_counter() - t0
        log = proc.stdout + proc.stderr
        status = _status(log, proc.returncode)
        written = _finding_input(log, Path(f"{out}/{short}-"), status)
        if written is not None and crashes is not None:
            written_copy = _keep_reproducer(name, Path(written), status, crashes)
            print(f"{name}: reproducer kept as {written_copy}", file=sys.stderr, flush=True)
    counts = re.findall(r"multiplex counts: (\{.*\})", log)
    if artifacts is None:
        written = None
    return FuzzRun(
        target=name,
        status=status,
        inputs=_last_int(r"stat::number_of_executed_units:\s*(\d+)", log) or 0,
        seconds=round(seconds, 1),
        exec_per_s=float(_last_int(r"stat::average_exec_per_sec:\s*(\d+)", log) or 0),
        coverage=_last_int(r"\bcov: (\d+)", log),
        features=_last_int(r"\bft: (\d+)", log),
        corpus=_last_int(r"\bcorp: (\d+)", log),
        seeds=len(files),
        artifact=written,
        log=_excerpt(proc.stdout, proc.stderr),
        per_target=json.loads(counts[-1]) if counts else None,
        distinct=_last_int(r"compile harness: (\d+) distinct cells", log),
    )


def _status(log: str, returncode: int) -> str:
    """The status of a run (:class:`FuzzRun`) from its output and exit status."""
    if "Uncaught Python exception" in log or "fuzz target exited" in log:
        return "crash"
    if "ALARM: working on the last Unit" in log or "libFuzzer: timeout" in log:
        return "timeout"
    if "out-of-memory" in log:
        return "oom"
    if returncode < 0:
        return f"killed (signal {-returncode})"
    if returncode != 0:
        return f"error (status {returncode})"
    return "ok"


def _finding_input(log: str, prefix: Path, status: str) -> str | None:
    """The file holding the input of the run's finding (see :func:`fuzz_target`),
    or None when the run found nothing; removes ``<prefix>current``."""
    current = Path(f"{prefix}current")
    units = re.findall(r"Test unit written to (\S+)", log)
    units += re.findall(r"finding input written to (\S+)", log)
    units = [u for u in units if Path(u).is_file()]
    try:
        if status == "ok":
            return None
        if units:
            return units[0]
        if current.is_file():
            data = current.read_bytes()
            lost = Path(f"{prefix}lost-{hashlib.sha1(data).hexdigest()}")
            lost.write_bytes(data)
            return str(lost)
        return None
    finally:
        current.unlink(missing_ok=True)


def _keep_reproducer(name: str, unit: Path, status: str, crashes: Path) -> Path:
    """Copy the input of a finding of target ``name`` to ``crashes/<target>/``."""
    data = unit.read_bytes()
    if name == ALL:  # the first byte picked the target
        name, data = ALL_ORDER[data[0] % len(ALL_ORDER)] if data else ALL_ORDER[0], data[1:]
    suffix = TARGETS[name].suffix if name in TARGETS else ".bin"
    kind = status.split()[0]
    folder = crashes / name.rsplit(":", 1)[-1]
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{kind}-{hashlib.sha1(data).hexdigest()[:12]}{suffix}"
    path.write_bytes(data)
    return path


_ORDER = {name: i for i, name in enumerate([*TARGETS, ALL])}


def _notes(md: Path) -> str:
    """The text after the table of an existing ``PREFIX.md`` (how each row was
    run, findings): kept by ``--merge``, which rewrites only the table."""
    if not md.is_file():
        return ""
    lines = md.read_text(encoding="utf-8").splitlines()
    rows = [i for i, line in enumerate(lines) if line.startswith("|")]
    if not rows:
        return ""
    end = rows[0]  # the end of the first table (the notes may hold tables of their own)
    while end + 1 < len(lines) and lines[end + 1].startswith("|"):
        end += 1
    return "\n".join(lines[end + 1 :]).strip("\n")


def _markdown(results: list[FuzzRun], args: argparse.Namespace, notes: str = "") -> str:
    lines = [
        "# Fuzzing the parsers",
        "",
        "Coverage-guided fuzzing with atheris (libFuzzer), one target per input format "
        "(tests/fuzz/targets.py). The contract: every input loads, or raises an error of "
        "ours naming the file, line and column or the field; any other exception, "
        f"or an input taking more than {args.timeout} s, is a finding.",
        "",
        f"Command: `python -m tests.fuzz.campaign --runs {args.runs} --max-time {args.max_time} "
        f"--timeout {args.timeout} --seed {args.seed}`"
        + (f" `--targets {args.targets}`" if args.targets and not args.merge else "")
        + ". Machine: 2 cores shared with other work; exec/s are noisy.",
        "",
        "| target | status | inputs | exec/s | coverage (cov) | features (ft) | corpus | seeds | wall (s) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        inputs = f"{r.inputs}" + (f" ({r.distinct}+ distinct cells)" if r.distinct else "")
        lines.append(
            f"| {r.target} | {r.status} | {inputs} | {r.exec_per_s:.0f} | {r.coverage} "
            f"| {r.features} | {r.corpus} | {r.seeds} | {r.seconds} |"
        )
    if notes:
        lines += ["", notes]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """The command line (module docstring); exit status 1 when any target found something."""
    ap = argparse.ArgumentParser(prog="python -m tests.fuzz.campaign", description=__doc__)
    ap.add_argument("--runs", type=int, default=100_000, help="inputs per target (default 1e5)")
    ap.add_argument("--max-time", type=int, default=3600, help="seconds per target at most")
    ap.add_argument("--timeout", type=int, default=10, help="seconds per input (a hang)")
    ap.add_argument("--seed", type=int, default=1, help="libFuzzer seed (> 0)")
    ap.add_argument("--rss-limit", type=int, default=2048, help="MB per process")
    ap.add_argument("--targets", default="", help="comma-separated (default: all)")
    ap.add_argument("--artifacts", type=Path, default=ROOT / ".fuzz", help="findings go here")
    ap.add_argument(
        "--crashes",
        type=Path,
        default=None,
        help="also copy each finding's input to CRASHES/<target>/ (make fuzz: tests/fuzz/crashes)",
    )
    ap.add_argument("--out", type=Path, default=None, help="write PREFIX.json and PREFIX.md")
    ap.add_argument(
        "--merge",
        action="store_true",
        help="keep the rows of PREFIX.json of the targets not run now (one table, many "
        "runs) and the text under the table of PREFIX.md",
    )
    args = ap.parse_args(argv)
    names = [n for n in args.targets.split(",") if n] or list(TARGETS)
    unknown = [n for n in names if n not in TARGETS and n != ALL]
    if unknown:
        ap.error(f"unknown target {unknown[0]!r} (known: {', '.join(TARGETS)})")
    kept: list[FuzzRun] = []
    notes = _notes(args.out.with_suffix(".md")) if args.merge and args.out is not None else ""
    if args.merge and args.out is not None and args.out.with_suffix(".json").is_file():
        old = json.loads(args.out.with_suffix(".json").read_text(encoding="utf-8"))
        kept = [FuzzRun(**(r | {"log": ""})) for r in old if r["target"] not in names]
    results: list[FuzzRun] = []
    for name in names:
        r = fuzz_target(
            name,
            runs=args.runs,
            max_time=args.max_time,
            timeout=args.timeout,
            seed=args.seed,
            rss_limit_mb=args.rss_limit,
            artifacts=args.artifacts,
            crashes=args.crashes,
        )
        results.append(r)
        print(
            f"{name}: {r.status}, {r.inputs} inputs, {r.exec_per_s:.0f} exec/s, "
            f"cov {r.coverage}, {r.seconds} s" + (f", finding: {r.artifact}" if r.artifact else ""),
            flush=True,
        )
        if r.status != "ok":
            print(r.log, flush=True)
        if args.out is not None:
            table = sorted(kept + results, key=lambda x: _ORDER.get(x.target, len(_ORDER)))
            args.out.with_suffix(".json").write_text(
                json.dumps([asdict(x) | {"log": None} for x in table], indent=1) + "\n",
                encoding="utf-8",
            )
            args.out.with_suffix(".md").write_text(_markdown(table, args, notes), encoding="utf-8")
    return 0 if all(r.status == "ok" for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
