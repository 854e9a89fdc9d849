"""Declarative sweeps: a TOML file names a grid of solver runs; run it locally or on Dask.

A sweep is every combination of an *instance* (an FJSP file, a generated
problem, a built-in cell or a cell file) with a *solver configuration*
(solver, options, time or work limit) and a *solver seed*, repeated
``repetitions`` times. Each combination is one **run**: one task of the local
process pool or of a ``dask.distributed`` cluster, and one row of the results
(:mod:`workcell.experiments.results`).

The sweep file
--------------
Paths are relative to the sweep file::

    [sweep]
    name = "fjsp"                        # names the results
    description = "Brandimarte and Fattahi at 10 s"
    out = "results/fjsp.parquet"         # where results go (default: <file stem>.parquet)
    repetitions = 1                      # each run repeated; repetition r adds r to the seed

    [[instances]]                        # FJSP files (globs)
    kind = "fjsp"
    family = "brandimarte"               # a label for tables and plots
    files = ["data/fjsp/brandimarte/*.fjs"]
    best_known = { mk01 = 40, mk02 = 26 }  # optional, by file stem: the reference of gaps

    [[instances]]                        # generated problems: scheduler.generate.random_problem
    kind = "generated"
    sizes = [[2, 8, 2, 1], [3, 12, 3, 1]]  # arms, tasks, zones, tools
    seeds = [0, 1, 2]                    # problem seeds
    start_zones = false                  # any other keyword of random_problem

    [[instances]]                        # cells: built-in names or cell files, compiled once per worker
    kind = "cell"
    cells = ["supersigma", "scara4"]

    [[solvers]]
    label = "tree"                       # unique; default: the solver's name
    solver = "tree"                      # "tree", "greedy" or "cpsat"
    time_limit = 10.0                    # seconds (or a list: a grid); omit for none
    seeds = [0]                          # solver seeds; "instance" uses the problem's seed
    options = { workers = 2 }            # TreeOptions / GreedyOptions / CpSatOptions fields

``[sweep] workers`` sets the local processes used when the caller names none
(timed comparisons set 1). An optional ``[quick]`` table reduces the grid
for a smoke run (:meth:`Sweep.quick_version`): ``instances`` (names or shell
patterns to keep), ``solvers`` (labels to keep), ``time_limit`` (replaces
every wall-clock limit), ``repetitions``, ``params`` (benchmark parameters).

An instance of kind ``benchmark`` runs no solver: it names a measurement
function, ``function = "module:function"`` (imported from ``path``,
relative to the sweep file), with keyword arguments ``params`` (a table, or
a list of tables: one instance each, named by their ``name``) and
``seeds``; its run calls ``function(seed=..., **params)`` and stores the
row (a dict) or rows (a list of dicts) it returns. A speed comparison is
one such run, measuring every side of it in one process.

An instance of kind ``campaign`` is a fault campaign
(:mod:`workcell.campaign`): ``cells``, ``episodes`` per cell and seed,
``batch`` episodes per run (default 25) and campaign ``seeds`` (default
``[0]``); each batch is one ``benchmark`` run of
``workcell.campaign:campaign_batch``, whose rows (one per episode) land in
the ``metrics`` column.

A run without a wall-clock limit needs a work limit, so that it cannot hang
and its result depends on the seed only: ``options.max_evaluations`` for
``tree``, ``options.max_deterministic_time`` (CP-SAT's deterministic time,
with ``workers = 1``) for ``cpsat``; ``greedy`` is one list pass.

Every error names the file and the field (``fjsp.toml: solvers[1].options:
TreeOptions.workers must be an int >= 1, got 0``); TOML syntax errors give
``file:line:col``.

Running
-------
:func:`run_sweep` runs every run not yet recorded in the results (an
interrupted sweep resumes where it stopped), in a local process pool by
default or on a Dask cluster (``scheduler="tcp://host:8786"`` or a
``distributed.Client``); results stream to a journal as they finish and end
up in one Parquet file. A run that raises is recorded with status
``"error"`` and its message; the others go on.

Examples
--------
>>> sweep = parse_sweep('''
... [sweep]
... name = "tiny"
... [[instances]]
... kind = "generated"
... sizes = [[2, 6, 2, 1]]
... seeds = [0, 1]
... [[solvers]]
... solver = "greedy"
... [[solvers]]
... solver = "tree"
... options = { max_evaluations = 50 }
... ''', filename="tiny.toml")
>>> len(sweep.runs()), sweep.runs()[0].instance.name
(4, '2x6x2x1-s0')
>>> row = run_one(sweep.runs()[0])
>>> row["status"], row["makespan"] == row["objective"]
('feasible', True)
"""

from __future__ import annotations

import glob
import hashlib
import json
import math
import os
import re
import time
import tomllib
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields
from functools import lru_cache
from os import PathLike, fspath
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from multiarm.errors import FormatError, MultiarmError, UsageError, ValidationError
from multiarm.text import read_source

if TYPE_CHECKING:
    from scheduler import Problem, Result

__all__ = [
    "BENCHMARK",
    "InstanceSpec",
    "Run",
    "SolverConfig",
    "Sweep",
    "SweepOutcome",
    "benchmark_function",
    "build_problem",
    "load_sweep",
    "parse_sweep",
    "run_one",
    "run_sweep",
]

InstanceKind = Literal["fjsp", "generated", "cell", "benchmark"]

_TOML_POS = re.compile(r"\(at line (\d+), column (\d+)\)")
_SWEEP_KEYS = {"name", "description", "out", "repetitions", "workers"}
_QUICK_KEYS = {"instances", "solvers", "time_limit", "params", "repetitions"}
_INSTANCE_KEYS = {
    "fjsp": {"kind", "family", "files", "best_known"},
    "generated": {"kind", "family", "sizes", "seeds", "best_known"},
    "cell": {"kind", "family", "cells", "best_known"},
    "benchmark": {"kind", "family", "function", "path", "params", "seeds"},
    "campaign": {"kind", "family", "cells", "episodes", "batch", "seeds"},
}
_GENERATOR_KEYS = {
    "precedence": float,
    "release_fraction": float,
    "zone_fraction": float,
    "tool_fraction": float,
    "setups": bool,
    "start_zones": bool,
    "blocking": bool,
    "grid": int,
}
_SOLVER_KEYS = {"label", "solver", "time_limit", "seeds", "options"}
_CPSAT_RUNNER_KEYS = {"max_deterministic_time"}
"""CP-SAT options the runner passes to ``scheduler.cpsat.solve_cpsat`` itself."""
_FUNCTION = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")
BENCHMARK = "benchmark"
"""The solver name of the runs of ``benchmark`` instances (which run no solver)."""


# ------------------------------------------------------------------ records


@dataclass(frozen=True, slots=True)
class InstanceSpec:
    """One problem of a sweep.

    Attributes
    ----------
    kind : {"fjsp", "generated", "cell", "benchmark"}
    family : str
        The label the sweep file gives (tables and plots group by it).
    name : str
        ``mk01`` (file stem), ``2x8x2x1-s0`` (generated), ``scara4`` (cell),
        the ``name`` of a benchmark's parameter table (with ``-s<seed>``).
    source : str
        The file (relative to the sweep file, or absolute), the built-in
        cell's name, ``""`` for generated problems, ``module:function`` for
        benchmarks.
    params : tuple of (str, object)
        Generated problems: ``arms``, ``tasks``, ``zones``, ``tools`` and the
        generator's keywords; benchmarks: the function's keyword arguments
        (lists as tuples); sorted by name.
    seed : int
        The problem's or the measurement's seed (0 for files and cells).
    best_known : float or None
        The reference of gaps given by the sweep file.
    base_dir : str
        Directory that ``source`` is relative to (for benchmarks: the
        directory the function's module is imported from, ``""`` for none).
    """

    kind: InstanceKind
    family: str
    name: str
    source: str = ""
    params: tuple[tuple[str, Any], ...] = ()
    seed: int = 0
    best_known: float | None = None
    base_dir: str = "."

    def describe(self) -> dict[str, Any]:
        """The instance as plain data (what identifies it, without its directory)."""
        return {
            "kind": self.kind,
            "family": self.family,
            "name": self.name,
            "source": self.source,
            "params": dict(self.params),
            "seed": self.seed,
        }


@dataclass(frozen=True, slots=True)
class SolverConfig:
    """One solver configuration of a sweep.

    Attributes
    ----------
    label : str
        Unique within the sweep; names the configuration in results.
    solver : {"tree", "greedy", "cpsat"}
    time_limit : float or None
        Seconds of wall clock (None: a work-limited run).
    options : tuple of (str, object)
        Fields of the solver's options class (and, for ``cpsat``,
        ``max_deterministic_time``), sorted by name.
    seeds : tuple of int or "instance"
    """

    label: str
    solver: str
    time_limit: float | None
    options: tuple[tuple[str, Any], ...] = ()
    seeds: tuple[int | str, ...] = (0,)


@dataclass(frozen=True, slots=True)
class Run:
    """One cell of the grid: an instance, a solver configuration, a seed and a repetition.

    Attributes
    ----------
    sweep : str
    instance : InstanceSpec
    config : SolverConfig
    seed : int
        The solver's seed (with the repetition added).
    repetition : int
    key : str
        A digest of everything that determines the run: the resume key.
    """

    sweep: str
    instance: InstanceSpec
    config: SolverConfig
    seed: int
    repetition: int
    key: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if not self.key:
            ident = {
                "sweep": self.sweep,
                "instance": self.instance.describe(),
                "label": self.config.label,
                "solver": self.config.solver,
                "time_limit": self.config.time_limit,
                "options": dict(self.config.options),
                "seed": self.seed,
                "repetition": self.repetition,
            }
            digest = hashlib.sha1(
                json.dumps(ident, sort_keys=True, default=str).encode()
            ).hexdigest()
            object.__setattr__(self, "key", digest[:16])


@dataclass(frozen=True, slots=True)
class Sweep:
    """A parsed sweep file: instances x solver configurations x seeds x repetitions.

    Attributes
    ----------
    name, description : str
    out : Path
        The results file (Parquet).
    repetitions : int
    instances : tuple of InstanceSpec
    solvers : tuple of SolverConfig
    filename : str
        The sweep file (for messages).
    workers : int or None
        Local processes to use when the caller names none (``[sweep]
        workers``; None: the CPU count). Timed comparisons set 1, so that
        runs never share the machine with each other.
    quick : tuple of (str, object)
        The ``[quick]`` table: how :meth:`quick_version` reduces the grid.
    """

    name: str
    description: str
    out: Path
    repetitions: int
    instances: tuple[InstanceSpec, ...]
    solvers: tuple[SolverConfig, ...]
    filename: str = "<string>"
    workers: int | None = None
    quick: tuple[tuple[str, Any], ...] = ()

    def runs(self) -> list[Run]:
        """Every run of the grid, in a fixed order (instance, solver, seed, repetition).

        A ``benchmark`` instance runs no solver: it gives one run per
        repetition (its seed plus the repetition), under the solver
        configuration ``benchmark``.

        Returns
        -------
        list of Run
        """
        out = []
        for inst in self.instances:
            if inst.kind == "benchmark":
                cfg = SolverConfig(BENCHMARK, BENCHMARK, None, (), ("instance",))
                for rep in range(self.repetitions):
                    out.append(Run(self.name, inst, cfg, inst.seed + rep, rep))
                continue
            for cfg in self.solvers:
                for s in cfg.seeds:
                    base = inst.seed if s == "instance" else int(s)
                    for rep in range(self.repetitions):
                        out.append(Run(self.name, inst, cfg, base + rep, rep))
        return out

    def quick_version(self) -> Sweep:
        """The reduced grid of the sweep file's ``[quick]`` table (a smoke run).

        ``[quick]`` may keep only some instances (``instances``: names or
        shell patterns) and solver configurations (``solvers``: labels),
        replace every wall-clock limit (``time_limit``), replace benchmark
        parameters (``params``: each applies to the benchmarks that have a
        parameter of that name) and set ``repetitions``. Without
        a ``[quick]`` table the sweep is returned unchanged.

        Returns
        -------
        Sweep
            Same name and output file; its runs have their own keys (their
            limits differ), so they never pass for runs of the full grid.

        Examples
        --------
        >>> s = parse_sweep('''
        ... [sweep]
        ... name = "q"
        ... [quick]
        ... instances = ["2x6x2x1-s0"]
        ... time_limit = 0.5
        ... [[instances]]
        ... kind = "generated"
        ... sizes = [[2, 6, 2, 1]]
        ... seeds = [0, 1]
        ... [[solvers]]
        ... solver = "tree"
        ... time_limit = 10.0
        ... ''')
        >>> [(r.instance.name, r.config.time_limit) for r in s.quick_version().runs()]
        [('2x6x2x1-s0', 0.5)]
        """
        from dataclasses import replace
        from fnmatch import fnmatchcase

        q = dict(self.quick)
        if not q:
            return self
        instances = self.instances
        if "instances" in q:
            instances = tuple(
                i for i in instances if any(fnmatchcase(i.name, pat) for pat in q["instances"])
            )
        if "params" in q:
            extra = dict(q["params"])
            instances = tuple(
                replace(
                    i,
                    params=tuple(
                        sorted((k, extra.get(k, v)) for k, v in i.params)  # only keys it has
                    ),
                )
                if i.kind == "benchmark"
                else i
                for i in instances
            )
        solvers = self.solvers
        if "solvers" in q:
            solvers = tuple(c for c in solvers if c.label in q["solvers"])
        if "time_limit" in q:
            solvers = tuple(
                replace(c, time_limit=q["time_limit"]) if c.time_limit is not None else c
                for c in solvers
            )
        return replace(
            self,
            instances=instances,
            solvers=solvers,
            repetitions=int(q.get("repetitions", self.repetitions)),
            quick=(),
        )


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
    """

    out: Path
    total: int
    ran: int
    skipped: int
    failed: int
    wall_time: float
    keys: frozenset[str] = frozenset()

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
        from workcell.experiments.results import read_results

        df = read_results(self.out)
        if current:
            df = df[df["key"].isin(self.keys)].reset_index(drop=True)
        return df


# ------------------------------------------------------------------ parsing


class _Where:
    """Builds ``file: field.path: message`` errors."""

    def __init__(self, filename: str) -> None:
        self.filename = filename

    def fail(self, path: str, message: str) -> ValidationError:
        return ValidationError(f"{self.filename}: {path}: {message}" if path else message)


def load_sweep(path: str | PathLike[str]) -> Sweep:
    """Read a sweep file (TOML, see the module docstring).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    Sweep

    Raises
    ------
    FormatError
        Unreadable file or TOML syntax error (``file:line:col``).
    ValidationError
        A field is wrong (``file: field.path: message``), e.g. a glob that
        matches no file or an unknown solver option.
    """
    name = fspath(path)
    text = read_source(path, FormatError, "sweep")
    return parse_sweep(text, filename=name, base_dir=Path(path).parent)


def parse_sweep(text: str, filename: str | None = None, base_dir: Path | None = None) -> Sweep:
    """Parse the text of a sweep file.

    Parameters
    ----------
    text : str
    filename : str, optional
        Named in every error message; default ``<string>``.
    base_dir : Path, optional
        Directory that relative paths are relative to (default: the current one).

    Returns
    -------
    Sweep

    Raises
    ------
    FormatError
        TOML syntax error (``file:line:col``).
    ValidationError
        A field is wrong (``file: field.path: message``).
    """
    fname = filename or "<string>"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        m = _TOML_POS.search(msg)
        line = int(m.group(1)) if m else None
        col = int(m.group(2)) if m else None
        raise FormatError(
            f"TOML syntax error: {_TOML_POS.sub('', msg).strip()}",
            filename=fname,
            line=line,
            column=col,
        ) from None
    return sweep_from_dict(data, filename=fname, base_dir=base_dir)


def _unknown(w: _Where, data: Mapping[str, Any], known: set[str], where: str) -> None:
    bad = sorted(set(data) - known)
    if bad:
        raise w.fail(
            f"{where}.{bad[0]}" if where else bad[0],
            f"unknown field (known: {', '.join(sorted(known))})",
        )


def _table(w: _Where, value: Any, where: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise w.fail(where, f"expected a table, got {type(value).__name__}")
    return value


def _list(w: _Where, value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise w.fail(where, f"expected a list, got {value!r}")
    if not value:
        raise w.fail(where, "expected a non-empty list")
    return value


def _int(w: _Where, value: Any, where: str, least: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < least:
        raise w.fail(where, f"expected an integer >= {least}, got {value!r}")
    return value


def _str(w: _Where, value: Any, where: str) -> str:
    if not isinstance(value, str) or not value:
        raise w.fail(where, f"expected a non-empty string, got {value!r}")
    return value


def _number(w: _Where, value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise w.fail(where, f"expected a number, got {value!r}")
    if not (math.isfinite(value) and value > 0):
        raise w.fail(where, f"expected a finite number > 0, got {value!r}")
    return float(value)


def sweep_from_dict(
    data: Mapping[str, Any], *, filename: str = "<string>", base_dir: Path | None = None
) -> Sweep:
    """Build a :class:`Sweep` from plain data (a parsed sweep file).

    Parameters
    ----------
    data : mapping
    filename : str
        Named in every error message.
    base_dir : Path, optional
        Directory that relative paths are relative to.

    Returns
    -------
    Sweep

    Raises
    ------
    ValidationError
        Naming the file and the field path.
    """
    w = _Where(filename)
    base = Path(base_dir) if base_dir is not None else Path(".")
    _unknown(w, data, {"sweep", "instances", "solvers", "quick"}, "")
    head = _table(w, data.get("sweep", {}), "sweep")
    _unknown(w, head, _SWEEP_KEYS, "sweep")
    stem = Path(filename).stem if filename != "<string>" else "sweep"
    name = _str(w, head.get("name", stem), "sweep.name")
    description = head.get("description", "")
    if not isinstance(description, str):
        raise w.fail("sweep.description", f"expected a string, got {description!r}")
    default_out = f"{stem if filename != '<string>' else name}.parquet"
    out = Path(_str(w, head.get("out", default_out), "sweep.out"))
    if not out.is_absolute():
        out = base / out
    repetitions = _int(w, head.get("repetitions", 1), "sweep.repetitions", least=1)
    workers = _int(w, head["workers"], "sweep.workers", least=1) if "workers" in head else None
    if "instances" not in data:
        raise w.fail("instances", "missing: at least one [[instances]] table")
    instances: list[InstanceSpec] = []
    for i, item in enumerate(_list(w, data["instances"], "instances")):
        instances += _instances(w, _table(w, item, f"instances[{i}]"), f"instances[{i}]", base)
    if "solvers" not in data and any(i.kind != "benchmark" for i in instances):
        raise w.fail("solvers", "missing: at least one [[solvers]] table")
    seen: dict[tuple[str, str], str] = {}
    for inst in instances:
        k = (inst.family, inst.name)
        if k in seen:
            raise w.fail(
                "instances",
                f"instance {inst.name!r} of family {inst.family!r} appears twice "
                f"({seen[k]!r} and {inst.source!r}): give the tables different families",
            )
        seen[k] = inst.source
    solvers: list[SolverConfig] = []
    for i, item in enumerate(_list(w, data["solvers"], "solvers") if "solvers" in data else []):
        solvers += _solvers(w, _table(w, item, f"solvers[{i}]"), f"solvers[{i}]")
    labels: set[tuple[str, float | None]] = set()
    for cfg in solvers:
        if (cfg.label, cfg.time_limit) in labels:
            raise w.fail("solvers", f"label {cfg.label!r} is used twice: give each a unique label")
        labels.add((cfg.label, cfg.time_limit))
    quick = _quick(w, data.get("quick", {}), instances, solvers)
    return Sweep(
        name,
        description,
        out,
        repetitions,
        tuple(instances),
        tuple(solvers),
        filename,
        workers,
        quick,
    )


def _quick(
    w: _Where, value: Any, instances: Sequence[InstanceSpec], solvers: Sequence[SolverConfig]
) -> tuple[tuple[str, Any], ...]:
    from fnmatch import fnmatchcase

    q = _table(w, value, "quick")
    _unknown(w, q, _QUICK_KEYS, "quick")
    out: dict[str, Any] = {}
    if "instances" in q:
        pats = [
            _str(w, v, f"quick.instances[{j}]")
            for j, v in enumerate(_list(w, q["instances"], "quick.instances"))
        ]
        for j, pat in enumerate(pats):
            if not any(fnmatchcase(i.name, pat) for i in instances):
                raise w.fail(f"quick.instances[{j}]", f"{pat!r} matches no instance")
        out["instances"] = tuple(pats)
    if "solvers" in q:
        labels = [
            _str(w, v, f"quick.solvers[{j}]")
            for j, v in enumerate(_list(w, q["solvers"], "quick.solvers"))
        ]
        known = {c.label for c in solvers}
        for j, lab in enumerate(labels):
            if lab not in known:
                raise w.fail(
                    f"quick.solvers[{j}]",
                    f"no solver configuration is labelled {lab!r} "
                    f"(labels: {', '.join(sorted(known))})",
                )
        out["solvers"] = tuple(labels)
    if "time_limit" in q:
        out["time_limit"] = _number(w, q["time_limit"], "quick.time_limit")
    if "repetitions" in q:
        out["repetitions"] = _int(w, q["repetitions"], "quick.repetitions", least=1)
    if "params" in q:
        params = _table(w, q["params"], "quick.params")
        have = {k for i in instances if i.kind == "benchmark" for k, _ in i.params}
        for k in params:
            if k not in have:
                raise w.fail(f"quick.params.{k}", "no benchmark instance has this parameter")
        out["params"] = tuple(
            sorted((k, _param(w, v, f"quick.params.{k}")) for k, v in params.items())
        )
    return tuple(sorted(out.items()))


def _param(w: _Where, value: Any, where: str) -> Any:
    """A benchmark parameter: a number, string or boolean, or a list of them (as a tuple)."""
    if isinstance(value, list):
        return tuple(_param(w, v, f"{where}[{j}]") for j, v in enumerate(value))
    if isinstance(value, bool | int | str) or (isinstance(value, float) and math.isfinite(value)):
        return value
    raise w.fail(where, f"expected a number, string, boolean or list of them, got {value!r}")


def _import_path(path: str) -> None:
    """Make ``path`` importable (benchmark functions live beside the sweep file)."""
    import sys

    if path and path not in sys.path:
        sys.path.insert(0, path)


def benchmark_function(instance: InstanceSpec) -> Callable[..., Any]:
    """The measurement function of a ``benchmark`` instance (imported by name).

    Parameters
    ----------
    instance : InstanceSpec
        Of kind ``benchmark``: ``source`` is ``module:function`` and
        ``base_dir`` the directory the module is imported from.

    Returns
    -------
    callable

    Raises
    ------
    UsageError
        The module cannot be imported or has no such function.
    """
    import importlib

    module, _, attr = instance.source.partition(":")
    _import_path(instance.base_dir)
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise UsageError(
            f"benchmark {instance.source!r}: cannot import {module!r}: {exc}"
        ) from None
    fn = getattr(mod, attr, None)
    if not callable(fn):
        raise UsageError(f"benchmark {instance.source!r}: {module!r} has no function {attr!r}")
    return fn  # type: ignore[no-any-return]


def _best_known(w: _Where, item: Mapping[str, Any], where: str) -> dict[str, float]:
    bk = _table(w, item.get("best_known", {}), f"{where}.best_known")
    out = {}
    for k, v in bk.items():
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise w.fail(f"{where}.best_known.{k}", f"expected a number, got {v!r}")
        out[k] = float(v)
    return out


def _instances(w: _Where, item: Mapping[str, Any], where: str, base: Path) -> list[InstanceSpec]:
    kind = item.get("kind")
    if kind not in _INSTANCE_KEYS:
        raise w.fail(
            f"{where}.kind", f"expected one of {', '.join(map(repr, _INSTANCE_KEYS))}, got {kind!r}"
        )
    known = _INSTANCE_KEYS[kind] | (set(_GENERATOR_KEYS) if kind == "generated" else set())
    _unknown(w, item, known, where)
    family = _str(w, item.get("family", kind), f"{where}.family")
    bk = _best_known(w, item, where)
    out: list[InstanceSpec] = []
    if kind == "fjsp":
        if "files" not in item:
            raise w.fail(f"{where}.files", "missing: a list of .fjs files or globs")
        for j, pattern in enumerate(_list(w, item["files"], f"{where}.files")):
            pat = _str(w, pattern, f"{where}.files[{j}]")
            full = pat if Path(pat).is_absolute() else fspath(base / pat)
            matches = sorted(glob.glob(full))
            if not matches:
                raise w.fail(f"{where}.files[{j}]", f"{pat!r} matches no file (looked for {full})")
            for m in matches:
                rel = m if Path(pat).is_absolute() else os.path.relpath(m, base)
                out.append(
                    InstanceSpec(
                        "fjsp",
                        family,
                        Path(m).stem,
                        source=rel,
                        best_known=bk.get(Path(m).stem),
                        base_dir=fspath(base),
                    )
                )
    elif kind == "generated":
        for key in ("sizes", "seeds"):
            if key not in item:
                raise w.fail(f"{where}.{key}", "missing")
        params: dict[str, Any] = {}
        for key, typ in _GENERATOR_KEYS.items():
            if key in item:
                v = item[key]
                ok = isinstance(v, bool) if typ is bool else not isinstance(v, bool)
                if typ is float:
                    ok = ok and isinstance(v, int | float) and math.isfinite(v) and v >= 0
                elif typ is int:
                    ok = ok and isinstance(v, int) and v >= 1
                if not ok:
                    raise w.fail(f"{where}.{key}", f"expected a {typ.__name__}, got {v!r}")
                params[key] = typ(v)
        seeds = [
            _int(w, s, f"{where}.seeds[{j}]")
            for j, s in enumerate(_list(w, item["seeds"], f"{where}.seeds"))
        ]
        for j, size in enumerate(_list(w, item["sizes"], f"{where}.sizes")):
            sw = f"{where}.sizes[{j}]"
            if not isinstance(size, list) or len(size) != 4:
                raise w.fail(sw, f"expected [arms, tasks, zones, tools], got {size!r}")
            arms, tasks, zones, tools = (
                _int(w, v, f"{sw}[{k}]", least=1 if k < 2 else 0) for k, v in enumerate(size)
            )
            for s in seeds:
                label = f"{arms}x{tasks}x{zones}x{tools}"
                name = f"{label}-s{s}"
                allp = {"arms": arms, "tasks": tasks, "zones": zones, "tools": tools, **params}
                out.append(
                    InstanceSpec(
                        "generated",
                        family,
                        name,
                        params=tuple(sorted(allp.items())),
                        seed=s,
                        best_known=bk.get(name, bk.get(label)),
                    )
                )
    elif kind == "benchmark":
        out += _benchmarks(w, item, where, base, family)
    elif kind == "campaign":
        out += _campaign(w, item, where, base, family)
    else:
        from workcell.cell import EXAMPLES

        if "cells" not in item:
            raise w.fail(f"{where}.cells", "missing: built-in cell names or cell files")
        for j, c in enumerate(_list(w, item["cells"], f"{where}.cells")):
            c = _str(w, c, f"{where}.cells[{j}]")
            if c in EXAMPLES:
                out.append(InstanceSpec("cell", family, c, source=c, best_known=bk.get(c)))
                continue
            p = Path(c) if Path(c).is_absolute() else base / c
            if not p.is_file():
                raise w.fail(
                    f"{where}.cells[{j}]",
                    f"{c!r} is neither a built-in cell ({', '.join(EXAMPLES)}) nor a file",
                )
            out.append(
                InstanceSpec(
                    "cell",
                    family,
                    p.stem,
                    source=c,
                    best_known=bk.get(p.stem),
                    base_dir=fspath(base),
                )
            )
    return out


def _campaign(
    w: _Where, item: Mapping[str, Any], where: str, base: Path, family: str
) -> list[InstanceSpec]:
    """A fault campaign (:mod:`workcell.campaign`): one ``benchmark`` run per batch."""
    from workcell.campaign import campaign_instances
    from workcell.cell import EXAMPLES

    cells = []
    for j, c in enumerate(_list(w, item.get("cells"), f"{where}.cells")):
        c = _str(w, c, f"{where}.cells[{j}]")
        p = Path(c) if Path(c).is_absolute() else base / c
        if c not in EXAMPLES and not p.is_file():
            raise w.fail(
                f"{where}.cells[{j}]",
                f"{c!r} is neither a built-in cell ({', '.join(EXAMPLES)}) nor a file",
            )
        cells.append(c if c in EXAMPLES else fspath(p.resolve()))
    episodes = _int(w, item.get("episodes"), f"{where}.episodes", least=1)
    batch = _int(w, item.get("batch", 25), f"{where}.batch", least=1)
    seeds = [
        _int(w, s, f"{where}.seeds[{j}]")
        for j, s in enumerate(_list(w, item.get("seeds", [0]), f"{where}.seeds"))
    ]
    out: list[InstanceSpec] = campaign_instances(cells, episodes, seeds, batch, family)
    return out


def _benchmarks(
    w: _Where, item: Mapping[str, Any], where: str, base: Path, family: str
) -> list[InstanceSpec]:
    fn = _str(w, item.get("function"), f"{where}.function")
    if not _FUNCTION.match(fn):
        raise w.fail(f"{where}.function", f"expected 'module:function', got {fn!r}")
    path = ""
    if "path" in item:
        p = Path(_str(w, item["path"], f"{where}.path"))
        full = p if p.is_absolute() else base / p
        if not full.is_dir():
            raise w.fail(f"{where}.path", f"{fspath(p)!r} is not a directory (looked for {full})")
        path = fspath(full.resolve())
    probe = InstanceSpec("benchmark", family, "", source=fn, base_dir=path)
    try:
        benchmark_function(probe)
    except UsageError as exc:
        raise w.fail(f"{where}.function", str(exc)) from None
    raw = item.get("params", [{}])
    tables = [raw] if isinstance(raw, Mapping) else _list(w, raw, f"{where}.params")
    seeds = [
        _int(w, s, f"{where}.seeds[{j}]")
        for j, s in enumerate(_list(w, item.get("seeds", [0]), f"{where}.seeds"))
    ]
    out = []
    for j, t in enumerate(tables):
        pw = f"{where}.params" if isinstance(raw, Mapping) else f"{where}.params[{j}]"
        params = dict(_table(w, t, pw))
        label = _str(w, params.pop("name", family if len(tables) == 1 else f"{family}{j}"), pw)
        if "seed" in params:
            raise w.fail(f"{pw}.seed", "the seed comes from the seeds field, not the parameters")
        values = {k: _param(w, v, f"{pw}.{k}") for k, v in params.items()}
        for s in seeds:
            out.append(
                InstanceSpec(
                    "benchmark",
                    family,
                    f"{label}-s{s}",
                    source=fn,
                    params=tuple(sorted(values.items())),
                    seed=s,
                    base_dir=path,
                )
            )
    return out


def _solvers(w: _Where, item: Mapping[str, Any], where: str) -> list[SolverConfig]:
    from scheduler import REGISTRY, SOLVERS

    _unknown(w, item, _SOLVER_KEYS, where)
    solver = item.get("solver")
    if solver not in REGISTRY:
        raise w.fail(f"{where}.solver", f"expected one of {', '.join(SOLVERS)}, got {solver!r}")
    label = _str(w, item.get("label", solver), f"{where}.label")
    opts = dict(_table(w, item.get("options", {}), f"{where}.options"))
    cls = REGISTRY[solver].options
    names = {f.name for f in fields(cls)}
    runner = {
        k: opts.pop(k)
        for k in list(opts)
        if solver == "cpsat" and k in _CPSAT_RUNNER_KEYS and k not in names
    }
    for k in opts:
        if k not in names:
            extra = sorted(names | (_CPSAT_RUNNER_KEYS if solver == "cpsat" else set()))
            raise w.fail(
                f"{where}.options.{k}",
                f"solver {solver!r} has no option {k!r} (it takes: {', '.join(extra)})",
            )
    try:
        cls(**opts)
    except MultiarmError as exc:
        raise w.fail(f"{where}.options", str(exc)) from None
    if "max_deterministic_time" in runner:
        runner["max_deterministic_time"] = _number(
            w, runner["max_deterministic_time"], f"{where}.options.max_deterministic_time"
        )
    options = tuple(sorted({**opts, **runner}.items()))
    raw_seeds = _list(w, item.get("seeds", [0]), f"{where}.seeds")
    seeds: list[int | str] = []
    for j, s in enumerate(raw_seeds):
        if s == "instance":
            seeds.append("instance")
        else:
            seeds.append(_int(w, s, f"{where}.seeds[{j}]"))
    tl = item.get("time_limit")
    limits: list[float | None]
    if tl is None:
        limits = [None]
    elif isinstance(tl, list):
        limits = [_number(w, v, f"{where}.time_limit[{j}]") for j, v in enumerate(tl)]
        if not limits:
            raise w.fail(f"{where}.time_limit", "expected a non-empty list")
    else:
        limits = [_number(w, tl, f"{where}.time_limit")]
    if None in limits:
        work = {
            "tree": "max_evaluations" in opts,
            "cpsat": "max_deterministic_time" in runner or "max_deterministic_time" in opts,
            "greedy": True,
        }[solver]
        if not work:
            need = "max_evaluations" if solver == "tree" else "max_deterministic_time"
            raise w.fail(
                f"{where}.time_limit",
                f"missing: a {solver!r} run needs a time limit or the work limit options.{need}",
            )
    return [SolverConfig(label, solver, lim, options, tuple(seeds)) for lim in limits]


# ------------------------------------------------------------------ running


@lru_cache(maxsize=32)
def build_problem(instance: InstanceSpec) -> Problem:
    """The scheduling problem of ``instance``, built once per process and cached.

    Built-in cells and cell files are compiled (FCL sweeps, travel setups,
    the blocking oracle); FJSP files are read; generated problems come from
    :func:`scheduler.generate.random_problem` with the instance's seed.

    Parameters
    ----------
    instance : InstanceSpec

    Returns
    -------
    scheduler.Problem
    """
    if instance.kind == "fjsp":
        from scheduler import read_fjsp

        path = Path(instance.source)
        return read_fjsp(path if path.is_absolute() else Path(instance.base_dir) / path)
    if instance.kind == "generated":
        from scheduler.generate import random_problem

        p = dict(instance.params)
        return random_problem(
            p.pop("arms"), p.pop("tasks"), p.pop("zones"), p.pop("tools"), seed=instance.seed, **p
        )
    from workcell.cell import EXAMPLES, load_cell, load_example
    from workcell.compile import compile_cell

    if instance.source in EXAMPLES:
        return compile_cell(load_example(instance.source))
    path = Path(instance.source)
    return compile_cell(load_cell(path if path.is_absolute() else Path(instance.base_dir) / path))


def _solve(problem: Problem, config: SolverConfig, seed: int) -> Result:
    from scheduler import REGISTRY, solve

    opts = dict(config.options)
    cls = REGISTRY[config.solver].options
    if (
        config.solver == "cpsat"
        and "max_deterministic_time" in opts
        and "max_deterministic_time" not in {f.name for f in fields(cls)}
    ):
        # CP-SAT's deterministic time is a work limit: the run depends on the seed only
        # (passed straight to solve_cpsat where CpSatOptions does not take it)
        from scheduler.cpsat import solve_cpsat
        from scheduler.solve import CpSatOptions

        dt = float(opts.pop("max_deterministic_time"))
        o = CpSatOptions(**opts)
        return solve_cpsat(
            problem,
            config.time_limit,
            seed,
            workers=o.workers,
            hint=o.hint,
            log=o.log,
            max_deterministic_time=dt,
        )
    options = cls(**opts)
    return solve(problem, config.solver, time_limit=config.time_limit, seed=seed, options=options)  # type: ignore[arg-type]


def run_one(run: Run) -> dict[str, Any]:
    """Execute one run and return its results row; never raises for the run's own failures.

    The problem is built (cached per process), solved, and the schedule
    checked by :func:`scheduler.validate`, whose makespan is recorded; any
    exception is recorded as status ``"error"`` with its type and message.
    The scheduler's compiled kernel is loaded before the solver's clock
    starts (the seconds it took, once per process, go to ``warmup_time``).

    A ``benchmark`` run calls its measurement function with
    ``seed=run.seed`` and the instance's parameters; what it returns (one
    dict, or a list of dicts: rows of a table) is recorded as JSON in the
    ``metrics`` column, with status ``"measured"``.

    Parameters
    ----------
    run : Run

    Returns
    -------
    dict
        One row (:data:`workcell.experiments.results.COLUMNS`).
    """
    from workcell.experiments.results import benchmark_row, error_row, result_row

    t0 = time.perf_counter()
    started = time.time()
    try:
        if run.instance.kind == "benchmark":
            fn = benchmark_function(run.instance)
            t0 = time.perf_counter()
            measured = fn(seed=run.seed, **dict(run.instance.params))
            return benchmark_row(run, measured, wall_time=time.perf_counter() - t0, started=started)
        problem = build_problem(run.instance)
        build = time.perf_counter() - t0
        warmup = _warm_up()
        result = _solve(problem, run.config, run.seed)
        if result.stats.interrupted:  # Ctrl-C cut the search short: not a result to keep
            raise KeyboardInterrupt
        from scheduler import lower_bound, validate

        makespan = validate(problem, result.schedule) if result.schedule is not None else math.inf
        return result_row(
            run,
            problem,
            result,
            makespan,
            lower_bound(problem),
            build_time=build,
            wall_time=time.perf_counter() - t0,
            started=started,
            warmup_time=warmup,
        )
    except Exception as exc:  # recorded, never lost: the sweep goes on
        return error_row(
            run,
            exc,
            "".join(traceback.format_exception(exc)[-3:]),
            wall_time=time.perf_counter() - t0,
            started=started,
        )


def _warm_up() -> float:
    """Load the scheduler's compiled kernel before a solver's clock starts (seconds taken)."""
    from scheduler.kernel import warm_up

    return float(warm_up(announce=lambda _msg: None))


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
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

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
                        from workcell.experiments.results import error_row

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
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


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
                f"--scheduler: cannot reach the Dask scheduler at {scheduler!r}: {exc}"
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
                    from workcell.experiments.results import error_row

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
    scheduler: Any = None,
    workers: int | None = None,
    out: str | PathLike[str] | None = None,
    progress: bool = True,
    retry_failed: bool = False,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> SweepOutcome:
    """Run every run of a sweep not yet recorded in its results.

    Parameters
    ----------
    sweep : Sweep, str or path-like
        A sweep, or the path of a sweep file.
    scheduler : str, distributed.Client or None
        A Dask scheduler's address (``"tcp://host:8786"``) or a connected
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
    from workcell.experiments.results import Journal

    t0 = time.perf_counter()
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
    rows: Iterable[dict[str, Any]] = (
        _iter_local(pending, workers) if scheduler is None else _iter_dask(pending, scheduler)
    )
    try:
        for row in rows:
            journal.append(row)
            ran += 1
            failed += row["status"] == "error"
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
    )
