"""The sweep file: its TOML schema, validation and records (a grid of runs).

Declarative sweeps: a TOML file names a grid of solver runs; run it locally or on Dask.

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

Sizes are capped before any run: at most
:data:`~workcell.experiments._fields.MAX_RUNS` (100,000) runs in a sweep
file, generated instances of at most 1,000 arms, 10,000 tasks, 1,000 zones
and tools, time limits in 1e-6 .. 1e6 s, seeds below 2**62; a field over
its cap is an error naming it (``s.toml: sweep.repetitions: ...``).

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
``file:line:col``. Every FJSP file and cell file an instance names is read
once when the sweep file is, so a broken one stops the sweep before any run,
naming the sweep file, the field, the instance file and its own error.
"""

from __future__ import annotations

import glob
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import fields
from fnmatch import fnmatchcase
from os import PathLike, fspath
from pathlib import Path
from typing import Any

from multiarm.errors import FormatError, MultiarmError, UsageError
from multiarm.text import parse_toml, read_source
from scheduler import REGISTRY, SOLVERS, read_fjsp
from scheduler.generate import GENERATORS
from workcell.cell import EXAMPLES, load_cell
from workcell.experiments._fields import (
    MAX_GENERATED,
    MAX_RUNS,
    _int,
    _list,
    _number,
    _param,
    _readable,
    _str,
    _table,
    _unknown,
    _Where,
)
from workcell.experiments.grid import BENCHMARK, InstanceSpec, Run, SolverConfig, Sweep
from workcell.experiments.instances import (
    CAMPAIGN_BATCH,
    benchmark_function,
    campaign_instances,
)

__all__ = [
    "BENCHMARK",
    "InstanceSpec",
    "Run",
    "SolverConfig",
    "Sweep",
    "benchmark_function",
    "load_sweep",
    "parse_sweep",
    "sweep_from_dict",
]


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
    "generator": str,
    "setup_fraction": float,
    "flexibility": float,
    "stay_fraction": float,
    "shared_fraction": float,
    "reach": int,
    "waits": bool,
}
_SOLVER_KEYS = {"label", "solver", "time_limit", "seeds", "options"}
_FUNCTION = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")


# ------------------------------------------------------------------ parsing


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
    data = parse_toml(text, fname, FormatError, "sweep file")
    return sweep_from_dict(data, filename=fname, base_dir=base_dir)


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
    repetitions = _int(w, head.get("repetitions", 1), "sweep.repetitions", least=1, most=MAX_RUNS)
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
    per_rep = sum(
        1 if inst.kind == "benchmark" else sum(len(c.seeds) for c in solvers) for inst in instances
    )
    if per_rep * repetitions > MAX_RUNS:
        raise w.fail(
            "sweep.repetitions",
            f"{per_rep} runs x {repetitions} repetitions make {per_rep * repetitions} runs, "
            f"more than {MAX_RUNS}: split the sweep",
        )
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
        out["repetitions"] = _int(w, q["repetitions"], "quick.repetitions", least=1, most=MAX_RUNS)
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
    if not isinstance(kind, str) or kind not in _INSTANCE_KEYS:
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
                _readable(w, f"{where}.files[{j}]", Path(m), read_fjsp)
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
                if typ is str:
                    ok = v in GENERATORS
                    if not ok:
                        raise w.fail(
                            f"{where}.{key}",
                            f"expected one of {', '.join(map(repr, GENERATORS))}, got {v!r}",
                        )
                elif typ is float:
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
                _int(w, v, f"{sw}[{k}]", least=1 if k < 2 else 0, most=MAX_GENERATED[k])
                for k, v in enumerate(size)
            )
            for s in seeds:
                label = f"{arms}x{tasks}x{zones}x{tools}"
                if params.get("waits") is False:  # solved without waits at zone borders
                    label += "-nowait"
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
            _readable(w, f"{where}.cells[{j}]", p, load_cell)
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
    cells = []
    for j, c in enumerate(_list(w, item.get("cells"), f"{where}.cells")):
        c = _str(w, c, f"{where}.cells[{j}]")
        p = Path(c) if Path(c).is_absolute() else base / c
        if c not in EXAMPLES and not p.is_file():
            raise w.fail(
                f"{where}.cells[{j}]",
                f"{c!r} is neither a built-in cell ({', '.join(EXAMPLES)}) nor a file",
            )
        if c not in EXAMPLES:
            _readable(w, f"{where}.cells[{j}]", p, load_cell)
        cells.append(c if c in EXAMPLES else fspath(p.resolve()))
    episodes = _int(w, item.get("episodes"), f"{where}.episodes", least=1, most=MAX_RUNS * 1000)
    batch = _int(w, item.get("batch", CAMPAIGN_BATCH), f"{where}.batch", least=1)
    seeds = [
        _int(w, s, f"{where}.seeds[{j}]")
        for j, s in enumerate(_list(w, item.get("seeds", [0]), f"{where}.seeds"))
    ]
    runs = len(cells) * len(seeds) * -(-episodes // batch)
    if runs > MAX_RUNS:
        raise w.fail(
            f"{where}.episodes",
            f"{len(cells)} cells x {len(seeds)} seeds x {episodes} episodes in batches of "
            f"{batch} make {runs} runs, more than {MAX_RUNS} (raise batch or split the sweep)",
        )
    return campaign_instances(cells, episodes, seeds, batch, family)


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
    _unknown(w, item, _SOLVER_KEYS, where)
    solver = item.get("solver")
    if not isinstance(solver, str) or solver not in REGISTRY:
        raise w.fail(f"{where}.solver", f"expected one of {', '.join(SOLVERS)}, got {solver!r}")
    label = _str(w, item.get("label", solver), f"{where}.label")
    opts = dict(_table(w, item.get("options", {}), f"{where}.options"))
    cls = REGISTRY[solver].options
    names = {f.name for f in fields(cls)}
    for k in opts:
        if k not in names:
            raise w.fail(
                f"{where}.options.{k}",
                f"solver {solver!r} has no option {k!r} (it takes: {', '.join(sorted(names))})",
            )
    try:
        cls(**opts)
    except MultiarmError as exc:
        raise w.fail(f"{where}.options", str(exc)) from None
    if opts.get("max_deterministic_time") is not None:  # a float in the run's key, as before
        opts["max_deterministic_time"] = float(opts["max_deterministic_time"])
    options = tuple(sorted(opts.items()))
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
            "cpsat": opts.get("max_deterministic_time") is not None,
            "greedy": True,
        }[solver]
        if not work:
            need = "max_evaluations" if solver == "tree" else "max_deterministic_time"
            raise w.fail(
                f"{where}.time_limit",
                f"missing: a {solver!r} run needs a time limit or the work limit options.{need}",
            )
    return [SolverConfig(label, solver, lim, options, tuple(seeds)) for lim in limits]
