"""The grid of a sweep: instances, solver configurations, runs (the records a sweep file becomes)."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, replace
from fnmatch import fnmatchcase
from pathlib import Path
from typing import Any, Literal

__all__ = ["BENCHMARK", "InstanceKind", "InstanceSpec", "Run", "SolverConfig", "Sweep"]

InstanceKind = Literal["fjsp", "generated", "cell", "benchmark"]
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
        Fields of the solver's options class (work limits included:
        ``max_evaluations``, CP-SAT's ``max_deterministic_time``), sorted by name.
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
        >>> from workcell.experiments.spec import parse_sweep
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
