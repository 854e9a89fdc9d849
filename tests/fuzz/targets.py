"""Fuzz targets: one function per input format, each taking the raw bytes of a file.

The contract every target checks (issue "bad inputs are refused early by
name"): an input either loads, or the loader raises an exception of our family
(:class:`multiarm.errors.MultiarmError`) whose message names where the problem
is (the file, ``file:line:col``, or the file and the field path). Anything
else escaping a target is a finding: a builtin or dependency exception, a
recursion error, an :class:`Unlocated` error of ours that names nothing, and
(checked by the fuzzer's ``-timeout``) a hang.

Each target goes through the real file loader: the bytes are written to a
file in a work folder and read by ``load_sdl``, ``load_taskset``,
``load_cell``, ... exactly as a user's file would be (UTF-8 decoding and its
errors included). The ``compile`` target is a harness of its own: it decodes
the bytes into changes of numeric fields of a small built-in cell and
compiles it with a tiny task set.

The targets import only public names of the package, except the fault-file
reader, which today is the command line's (``workcell.cli._load_faults``);
the fault targets then check the records against the built-in supersigma cell
(:func:`workcell.faultcheck.check_faults`, the names; no compile).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import struct
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from multiarm.errors import InfeasibleError, MultiarmError, ScheduleError, SourceError

__all__ = [
    "ALL",
    "ALL_ORDER",
    "COMPILE_FIELDS",
    "KNOWN_FOREIGN",
    "PENDING_RANGES",
    "TARGETS",
    "Multiplex",
    "Target",
    "Unlocated",
    "check",
    "compile_cell_data",
    "compile_cells_seen",
    "compile_mutations",
    "compile_tasks_file",
    "faults_cell",
    "seed_files",
    "seed_inputs",
]

ROOT = Path(__file__).resolve().parents[2]
"""The repository's root (the seeds are shipped files below it)."""

HERE = Path(__file__).resolve().parent


class Unlocated(AssertionError):
    """An error of ours whose message names neither the file nor a field (a finding)."""


@dataclass(frozen=True, slots=True)
class Target:
    """One fuzz target.

    Attributes
    ----------
    name : str
        The target's name (folder names under ``corpus/`` and ``crashes/``).
    suffix : str
        The file suffix its inputs are written with (the loaders go by it).
    load : callable
        ``load(path)``: reads the file at ``path`` with the real loader.
    seeds : tuple of str
        Glob patterns, relative to the repository root, of the shipped files
        that seed its corpus (besides ``tests/fuzz/corpus/<name>/``).
    """

    name: str
    suffix: str
    load: Callable[[Path], object]
    seeds: tuple[str, ...] = ()

    def __call__(self, data: bytes, workdir: Path) -> None:
        """Run the target on ``data``; raise only findings (see :func:`check`)."""
        path = workdir / f"input{self.suffix}"
        path.write_bytes(data)
        check(lambda: self.load(path), path)


def check(run: Callable[[], object], path: Path) -> None:
    """Call ``run()``; an error of ours must name ``path`` (or be located in a file).

    An :class:`~multiarm.errors.InfeasibleError` (a well-formed input with no
    answer, e.g. a task no arm of a compiled cell can do) names the task or
    arm rather than a place in the file, and is accepted as it is.

    Raises
    ------
    Unlocated
        An error of ours that names no place.
    BaseException
        Anything not of our family, unchanged (the finding itself).
    """
    try:
        run()
    except InfeasibleError:
        pass  # well-formed input without an answer: the message names the task or arm
    except MultiarmError as exc:
        text = str(exc)
        located = isinstance(exc, SourceError) and exc.filename is not None
        if not (located or path.name in text):
            raise Unlocated(f"{type(exc).__name__} names no place: {text!r}") from exc


# --------------------------------------------------------------- loaders


def _load_sdl(path: Path) -> object:
    from zones import load_sdl

    return load_sdl(path)


def _load_tdl(path: Path) -> object:
    from tasklib import load_tdl

    return load_tdl(path)


def _load_taskset(path: Path) -> object:
    from tasklib import load_taskset

    return load_taskset(path)


def _load_cell(path: Path) -> object:
    from workcell.cell import load_cell

    return load_cell(path)


def _load_problem(path: Path) -> object:
    from scheduler.io import load_problem

    return load_problem(path)


@functools.cache
def schedule_problem() -> Any:
    """The fixed problem the ``schedule`` target's files are read against:
    3 arms, 8 tasks, 2 zones, a tool and setups (so that waits have borders)."""
    from scheduler.generate import random_problem

    return random_problem(3, 8, 2, 1, seed=0)


def _load_schedule(path: Path) -> object:
    from scheduler import validate
    from scheduler.io import load_schedule

    problem = schedule_problem()
    sched = load_schedule(path, problem)
    try:
        validate(problem, sched)
    except ScheduleError as exc:
        # a well-formed file breaking a constraint: the message names the task
        if not any(f"{t!r}" in str(exc) for t in problem.task_names):
            raise
    return sched


def _load_fjsp(path: Path) -> object:
    from scheduler.fjsp import read_fjsp

    return read_fjsp(path)


@functools.cache
def faults_cell() -> Any:
    """The built-in cell the ``faults_*`` targets' records are checked against."""
    from workcell import load_example

    return load_example("supersigma")


def _load_faults(path: Path) -> object:
    from workcell import cli
    from workcell.faultcheck import check_faults

    plan = cli._load_faults(str(path))
    check_faults(faults_cell(), plan, source=str(path))
    return plan


def _load_sweep(path: Path) -> object:
    from workcell.experiments.sweep import load_sweep

    return load_sweep(path)


# --------------------------------------------------------- compile harness

COMPILE_FIELDS: tuple[tuple[str, ...], ...] = (
    ("compile", "padding", ""),
    ("arms", "left", "base", "0"),
    ("arms", "left", "base", "2"),
    ("arms", "left", "base", "3"),
    ("arms", "left", "rails", "x", "0"),
    ("arms", "left", "rails", "x", "1"),
    ("arms", "left", "rails", "z", "1"),
    ("arms", "left", "height", ""),
    ("arms", "left", "payload", ""),
    ("arms", "left", "start", "0"),
    ("arms", "left", "start", "2"),
    ("arms", "right", "base", "1"),
    ("arms", "right", "rails", "y", "1"),
    ("arms", "right", "height", ""),
    ("arms", "right", "start", "0"),
    ("arms", "right", "start", "3"),
)
"""The numeric fields of the ``compile`` target's cell that its bytes change
(a trailing list index, or ``""`` for a plain number)."""

_EXTREMES = (0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300, math.inf, -math.inf, math.nan, 1e-6, 1e6)


PENDING_RANGES: dict[tuple[str, ...], tuple[float, float]] = {}
"""Fields whose physical range the cell file does not check yet, with the
open interval of values it accepts but should refuse: the ``compile``
harness leaves values inside these intervals out (they are known
findings of the cell file's checks, listed in ``KNOWN_FOREIGN``)."""


def compile_mutations(data: bytes) -> list[tuple[tuple[str, ...], float]]:
    """The field changes encoded by ``data``: up to 4 records of 9 bytes.

    Byte 0 picks the field (modulo :data:`COMPILE_FIELDS`); with its high bit
    set, byte 1 picks one of the extremes (0, ±1e-300, ±1e300, ±inf, nan,
    1e-6, 1e6), otherwise bytes 1-8 are a little-endian float64 (any value,
    non-finite ones included).
    """
    out = []
    for k in range(0, min(len(data), 36) - 8, 9):
        rec = data[k : k + 9]
        field = COMPILE_FIELDS[rec[0] % len(COMPILE_FIELDS)]
        if rec[0] & 0x80:
            value = _EXTREMES[rec[1] % len(_EXTREMES)]
        else:
            value = struct.unpack("<d", rec[1:9])[0]
        lo, hi = PENDING_RANGES.get(field, (0.0, 0.0))
        if not lo < value < hi:
            out.append((field, value))
    return out


def compile_tasks_file(folder: Path) -> Path:
    """Writes (once per folder) the 2-task set the compile harnesses use: the
    first two tasks of the supersigma set without prerequisites or parts."""
    from tasklib import load_example, save_taskset

    tasks = folder / "tiny_tasks.json"
    if not tasks.is_file():
        full = load_example("supersigma")
        keep = tuple(t for t in full.tasks if not t.prerequisites and not t.consumes)[:2]
        save_taskset(dataclasses.replace(full, tasks=keep, groups=()), tasks)
    return tasks


@functools.cache
def _compile_base(workdir: Path) -> tuple[dict[str, Any], Path]:
    """The supersigma cell's data with the 2-task set written into ``workdir``."""
    text = resources.files("workcell.examples").joinpath("supersigma.toml").read_text("utf-8")
    data = tomllib.loads(text)
    data["tasks"] = compile_tasks_file(workdir).name
    return data, workdir


def _set(data: dict[str, Any], field: tuple[str, ...], value: float) -> None:
    node: Any = data
    for key in field[:-2]:
        node = node[key]
    last, index = field[-2], field[-1]
    if index == "":
        node[last] = value
    elif isinstance(node.get(last), list):
        items = list(node[last])
        items[int(index)] = value
        node[last] = items
    else:  # a table of axes (rails.x = [lo, hi])
        node[last] = value


_COMPILED: set[tuple[tuple[tuple[str, ...], bytes], ...]] = set()
"""Mutation lists whose cell the ``compile`` harness has already compiled
without a finding: the compile is deterministic, so an input decoding to one
of them is answered at once (libFuzzer's mutations of short inputs decode
to the same few cells again and again)."""


def compile_cells_seen() -> int:
    """Distinct cells the ``compile`` harness has compiled in this process."""
    return len(_COMPILED)


def compile_cell_data(
    mutations: list[tuple[tuple[str, ...], float]], workdir: Path
) -> tuple[dict[str, Any], Path]:
    """The ``compile`` harness's cell (the supersigma cell with the 2-task set
    written into ``workdir``) as the data of a cell file, with ``mutations``
    (:func:`compile_mutations`) applied; and the folder it is read from."""
    import copy

    base, folder = _compile_base(workdir)
    cell_data = copy.deepcopy(base)
    for field, value in mutations:
        _set(cell_data, field, value)
    return cell_data, folder


def _compile_target(data: bytes, workdir: Path) -> None:
    import sys

    from workcell import compile_cell
    from workcell.cell import cell_from_dict

    mutations = compile_mutations(data)
    key = tuple((field, struct.pack("<d", value)) for field, value in mutations)
    if key in _COMPILED:
        return
    cell_data, folder = compile_cell_data(mutations, workdir)
    path = workdir / "compile.toml"

    def run() -> object:
        cell = cell_from_dict(cell_data, filename=path.name, base_dir=folder)
        return compile_cell(cell)

    check(run, path)
    _COMPILED.add(key)
    if len(_COMPILED) % 50 == 0:
        print(f"compile harness: {len(_COMPILED)} distinct cells", file=sys.stderr, flush=True)


@dataclass(frozen=True, slots=True)
class _Harness:
    """A target with its own decoding of the bytes (not a file)."""

    name: str
    run: Callable[[bytes, Path], None]
    seeds: tuple[str, ...] = ()
    suffix: str = ".bin"

    def __call__(self, data: bytes, workdir: Path) -> None:
        self.run(data, workdir)


# ------------------------------------------------------------- the targets

TARGETS: dict[str, Target | _Harness] = {
    t.name: t
    for t in (
        Target(
            "sdl",
            ".sdl",
            _load_sdl,
            ("zones/examples/*.sdl", "docs/files/*.sdl", "tests/zones/malformed/*.sdl"),
        ),
        Target("tdl", ".tdl", _load_tdl, ("tasklib/examples/*.tdl", "docs/files/*.tdl")),
        Target("taskset_toml", ".toml", _load_taskset),
        Target("taskset_json", ".json", _load_taskset),
        Target("cell", ".toml", _load_cell, ("workcell/examples/*.toml",)),
        Target("problem", ".json", _load_problem),
        Target("schedule", ".json", _load_schedule),
        Target(
            "fjsp",
            ".fjs",
            _load_fjsp,
            ("../shared/data/fjsp/brandimarte/mk0[1-3].fjs", "../shared/data/fjsp/fattahi/*.fjs"),
        ),
        Target("faults_toml", ".toml", _load_faults),
        Target("faults_json", ".json", _load_faults),
        Target("sweep", ".toml", _load_sweep, ("benchmarks/sweeps/*.toml",)),
    )
}
TARGETS["compile"] = _Harness("compile", _compile_target)

KNOWN_FOREIGN: dict[str, tuple[str, ...]] = {}
"""Reproducers (file names under ``crashes/<target>/``) of findings outside the
fuzzed parsers, not fixed yet: the test does not run them (some exhaust the
memory) and the fuzz harnesses leave such inputs out (:data:`PENDING_RANGES`).
Empty an entry once the code it names refuses the input."""


ALL = "all"
"""The multiplexed target: every target in one process (the bounded run of the
test suite). The first byte of an input picks the target (its index in
:data:`ALL_ORDER`, modulo their number), the rest is that target's input."""

ALL_ORDER: tuple[str, ...] = tuple(sorted(TARGETS))

ALL_CAPS: dict[str, int] = {"compile": 40}
"""Most inputs a target runs inside the multiplexed one (the compile harness
compiles a cell per new input; the parsers take milliseconds)."""


class Multiplex:
    """Every target behind one input function (:data:`ALL`); counts per target.

    Every ``report_every`` inputs (and at the cap of each target) the counts
    are printed to stderr as ``multiplex counts: {json}``, so that the
    driver can read them after libFuzzer has ended the process.
    """

    def __init__(self, report_every: int = 200) -> None:
        self.counts: dict[str, int] = dict.fromkeys(ALL_ORDER, 0)
        self.report_every = report_every
        self._seen = 0

    def __call__(self, data: bytes, workdir: Path) -> None:
        name = ALL_ORDER[data[0] % len(ALL_ORDER)] if data else ALL_ORDER[0]
        if self.counts[name] >= ALL_CAPS.get(name, 1 << 62):
            return
        self.counts[name] += 1
        self._seen += 1
        if self._seen % self.report_every == 0:
            self.report()
        TARGETS[name](data[1:], workdir)

    def report(self) -> None:
        import json
        import sys

        print(f"multiplex counts: {json.dumps(self.counts)}", file=sys.stderr, flush=True)


def seed_inputs(name: str) -> list[tuple[str, bytes]]:
    """The seed inputs of target ``name`` (or :data:`ALL`) as ``(label, bytes)``;
    those of :data:`ALL` carry their target's index as the first byte."""
    if name != ALL:
        return [(f.name, f.read_bytes()) for f in seed_files(name)]
    out = []
    for i, target in enumerate(ALL_ORDER):
        files = seed_files(target) or []
        out += [(f"{target}_{f.name}", bytes([i]) + f.read_bytes()) for f in files]
        if not files:
            out.append((f"{target}_empty", bytes([i])))
    return out


def seed_files(name: str) -> list[Path]:
    """The seed inputs of target ``name``: its shipped files and ``corpus/<name>/``."""
    target = TARGETS[name]
    files: list[Path] = []
    for pattern in target.seeds:
        base = ROOT
        while pattern.startswith("../"):
            base, pattern = base.parent, pattern[3:]
        files += sorted(p for p in base.glob(pattern) if p.is_file())
    corpus = HERE / "corpus" / name
    if corpus.is_dir():
        files += sorted(p for p in corpus.iterdir() if p.is_file())
    return files
