"""The main job as one call: compile → solve → validate → simulate → write.

:func:`run_cell` is the pipeline every command (``demo``, ``simulate``,
``schedule``, ``campaign``), the notebooks and the sweeps go through, so
that the steps are written once:

1. the faults are read (a file, records or a :class:`~workcell.FaultPlan`)
   and checked before any long work (:func:`load_faults`);
2. the cell is compiled (:func:`workcell.compile_cell`), unless a
   :class:`~workcell.CompiledCell` is given;
3. the problem is solved (:func:`scheduler.solve`) and the schedule checked
   (:func:`scheduler.validate`);
4. the schedule is executed in the simulated cell (:func:`workcell.simulate`);
5. with ``out``, the run's files are written (:func:`write_run`).

Steps 2-3 are :func:`solve_cell` (``multiarm schedule`` and the fault
campaign's plan stop there), steps 4-5 :func:`run_solved` (the demo runs one
solved cell twice: as planned and with an arm failing).

**Reproducible by default.** The tree search stops at a *work limit*
(schedules evaluated, ``TreeOptions.max_evaluations``) derived from the time
limit at :data:`EVALUATIONS_PER_SECOND`, a rate a loaded 2-core machine
reaches several times over: the same cell, solver and seed then give the
same plan on any machine. The wall-clock cap of that search is
:data:`WALL_CAP_FACTOR` times the time limit; when the clock, and not the
work limit, stopped it, :attr:`SolvedCell.time_bound` says so (the plan may
then differ from run to run). ``greedy`` is deterministic;
``cpsat`` runs on a wall-clock limit (pass ``CpSatOptions(workers=1,
max_deterministic_time=...)`` to :func:`scheduler.solve` for a repeatable one).

Examples
--------
>>> from workcell import load_example
>>> run = run_cell(load_example("supersigma"), solver="greedy")
>>> run.status.value, run.failed_tasks, len(run.written)
('ok', 0, 0)
>>> run.result.objective == run.sim.metrics.planned_makespan
True
>>> default_evaluations(5.0)
2000
"""

from __future__ import annotations

import enum
import json
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

from multiarm.errors import FormatError, NoFeasibleSchedule, UsageError
from multiarm.text import parse_json, parse_toml
from scheduler import Problem, Progress, Result, Schedule, solve, validate
from scheduler.problem import ProblemLike
from scheduler.solve import MAX_SEED
from scheduler.tree import TreeOptions
from workcell.cell import EXAMPLES, Cell, load_cell, load_example
from workcell.compile import CompiledCell, compile_cell
from workcell.compiled import CompileOptions
from workcell.faultcheck import check_faults
from workcell.sim.harness.faults import Fault, FaultPlan, as_plan
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import MediumSpec, SimResult, simulate

if TYPE_CHECKING:
    from scheduler.solve import SolverName

__all__ = [
    "DEFAULT_TIME_LIMIT",
    "EVALUATIONS_PER_SECOND",
    "MAX_EVALUATIONS",
    "MAX_FRAMES",
    "MAX_TIME_LIMIT",
    "RUN_FILES",
    "STEPS",
    "WALL_CAP_FACTOR",
    "CellRun",
    "FaultsLike",
    "RunStatus",
    "SolvedCell",
    "StepCallback",
    "check_out_dir",
    "default_evaluations",
    "failure_candidate",
    "faults_source",
    "load_cell_or_example",
    "load_faults",
    "run_cell",
    "run_solved",
    "solve_cell",
    "solve_limited",
    "write_run",
]

DEFAULT_TIME_LIMIT = 5.0
"""Seconds: the default wall-clock cap of one solve."""

EVALUATIONS_PER_SECOND = 400
"""Schedules evaluated per second of time limit in the default work limit
(:func:`default_evaluations`). Measured on the built-in cells
(docs/cli.md): a loaded 2-core machine evaluates several times more, so the
work limit, not the clock, ends the search."""

MAX_EVALUATIONS = 10_000_000
"""The largest work limit accepted (hours of search)."""

WALL_CAP_FACTOR = 4.0
"""The tree search's wall-clock cap, in multiples of the time limit, when a
work limit ends it: slack for a loaded machine, so that the work limit, not
the clock, decides (measured rates in docs/cli.md)."""

MAX_TIME_LIMIT = 86_400.0
"""The longest time limit accepted, seconds (a day)."""

MAX_FRAMES = 1_000
"""The most motion frames (PNG images) one run writes."""

STEPS: tuple[str, ...] = ("compile", "solve", "simulate", "write")
"""The steps of :func:`run_cell`, in order, as passed to its ``progress``."""

RUN_FILES: tuple[str, ...] = (
    "trace.json",
    "metrics.json",
    "tasks.csv",
    "schedule.json",
    "gantt.png",
    "zones.png",
    "instants.png",
    "replay.json",
    "replay.html",
)
"""The files :func:`write_run` writes into a run's directory (and ``frames/``):
the records, the plots, and the 3D replay (:mod:`workcell.replay`; ``multiarm
view DIR`` rebuilds the page from ``replay.json``)."""

StepCallback = Callable[[str, str], None]
"""``progress(step, detail)``: called as each step of the pipeline begins
(``step`` one of :data:`STEPS`; ``detail`` a short description)."""

FaultsLike = FaultPlan | Sequence[Fault] | Sequence[Mapping[str, Any]] | str | PathLike[str] | None
"""What ``faults=`` accepts: a plan, records, dicts, or a ``.toml``/``.json`` file."""


class RunStatus(enum.Enum):
    """How a simulated run ended (its tasks, not the process)."""

    OK = "ok"
    """Every task done."""
    TASKS_FAILED = "tasks failed"
    """At least one task failed (an arm failure, a crash, an emergency stop...)."""


def default_evaluations(time_limit: float) -> int:
    """The tree search's default work limit for ``time_limit`` seconds.

    ``EVALUATIONS_PER_SECOND * time_limit``, at least 100 and at most
    :data:`MAX_EVALUATIONS`.
    """
    return int(min(MAX_EVALUATIONS, max(100, round(EVALUATIONS_PER_SECOND * time_limit))))


@dataclass(frozen=True, slots=True)
class SolvedCell:
    """A compiled cell and the solver's answer (:func:`solve_cell`).

    Attributes
    ----------
    compiled : CompiledCell
    result : scheduler.Result
        Its ``schedule`` is never None here and has passed :func:`scheduler.validate`.
    time_limit : float or None
        The wall-clock cap of the solve, seconds (None: none).
    evaluations : int or None
        The tree search's work limit (None for other solvers).
    """

    compiled: CompiledCell
    result: Result
    time_limit: float | None
    evaluations: int | None

    @property
    def problem(self) -> Problem:
        """The scheduling problem (``compiled.problem``)."""
        return self.compiled.problem

    @property
    def schedule(self) -> Schedule:
        """The solver's schedule."""
        assert self.result.schedule is not None  # solve_cell raises otherwise
        return self.result.schedule

    @property
    def time_bound(self) -> bool:
        """Whether the wall clock, not the work limit, stopped a tree search or CP-SAT
        before it proved its schedule optimal: the plan may then differ from run to run."""
        r = self.result
        if r.solver == "greedy" or r.status.value == "optimal":
            return False
        if self.evaluations is not None and r.stats.evaluations >= self.evaluations:
            return False
        return self.time_limit is not None and r.runtime >= 0.99 * self.time_limit


@dataclass(frozen=True, slots=True)
class CellRun:
    """What :func:`run_cell` returns: every product of the pipeline.

    Attributes
    ----------
    compiled : CompiledCell
        The compiled cell (``compiled.problem`` is the scheduler's Problem).
    result : scheduler.Result
        The solver's result; ``result.schedule`` is the plan that was simulated.
    sim : SimResult
        The simulated run (``sim.trace``, ``sim.metrics``, ``sim.tasks_frame()``).
    written : tuple of Path
        The files written (empty without ``out``).
    status : RunStatus
        ``OK`` when every task was done, ``TASKS_FAILED`` otherwise.
    evaluations : int or None
        The tree search's work limit used (None for other solvers).
    time_bound : bool
        :attr:`SolvedCell.time_bound`.
    """

    compiled: CompiledCell
    result: Result
    sim: SimResult
    written: tuple[Path, ...]
    status: RunStatus
    evaluations: int | None = None
    time_bound: bool = False

    @property
    def ok(self) -> bool:
        """Whether every task was done."""
        return self.status is RunStatus.OK

    @property
    def failed_tasks(self) -> int:
        """Tasks that failed in the run."""
        return int(self.sim.metrics.failed_tasks)


def load_cell_or_example(name: str | PathLike[str]) -> Cell:
    """A cell from a cell file (``.toml``) or a built-in cell's name.

    Raises
    ------
    UsageError
        A file that is not ``.toml``, or neither a file nor a built-in name
        (the built-in names are listed).
    ValidationError, FormatError
        A broken cell file (file and field named).
    """
    path = Path(name)
    if path.is_file():
        if path.suffix.lower() != ".toml":
            raise UsageError(f"{name}: a cell file is a .toml file")
        return load_cell(path)
    if str(name) in EXAMPLES:
        return load_example(str(name))
    raise UsageError(
        f"unknown cell {str(name)!r}: no such file, and no built-in cell of that name "
        f"(known: {', '.join(EXAMPLES)})"
    )


def _read_fault_file(path: Path) -> FaultPlan:
    name = str(path)
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise UsageError(f"{name}: expected a .toml or .json file")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise UsageError(f"cannot read {name!r}: {why}") from None
    parse = parse_toml if suffix == ".toml" else parse_json
    data: object = parse(text, name, FormatError, "faults file")
    if isinstance(data, dict):
        if set(data) != {"faults"} or not isinstance(data["faults"], list):
            raise FormatError("expected a list of fault records under 'faults'", filename=name)
        data = data["faults"]
    if not isinstance(data, list):
        raise FormatError("expected a list of fault records", filename=name)
    try:
        return FaultPlan.from_dicts(data)
    except FormatError:
        raise
    except (UsageError, ValueError) as exc:
        raise FormatError(str(exc), filename=name) from None


def load_faults(faults: FaultsLike, cell: Cell | CompiledCell | None = None) -> FaultPlan:
    """Fault records as a :class:`~workcell.FaultPlan`, read and checked before any long work.

    This is the one place where :func:`run_cell` reads and checks faults,
    before the compile.

    Parameters
    ----------
    faults : FaultPlan, records, dicts, path or None
        A path is a ``.toml`` file of ``[[faults]]`` tables or a ``.json``
        list of records (or ``{"faults": [...]}``); None is no fault.
    cell : Cell or CompiledCell, optional
        The cell the faults are for: their arms, parts, zones and message
        kinds are checked against it (:func:`workcell.faultcheck.check_faults`);
        against a compiled cell, their times too (none after any possible
        plan end).

    Returns
    -------
    FaultPlan

    Raises
    ------
    UsageError
        An unreadable file, or a file that is not ``.toml`` or ``.json``.
    ValidationError
        A record that does not fit the cell (an unknown arm, part, zone or
        message kind; an arm failing twice; a time after any plan's end).
    FormatError
        A malformed file or record (``file:line:col``, or the file and the
        record's index and field).
    """
    plan = _read_fault_file(Path(faults)) if isinstance(faults, str | PathLike) else as_plan(faults)
    if cell is not None:
        check_faults(cell, plan, source=faults_source(faults))
    return plan


def faults_source(faults: FaultsLike) -> str | None:
    """The name fault errors start with: the file's path, or None for records."""
    return str(faults) if isinstance(faults, str | PathLike) else None


def check_out_dir(out: str | PathLike[str], *, create: bool = True) -> Path:
    """``out`` as a writable directory, checked before any long work.

    Parameters
    ----------
    out : str or path-like
    create : bool
        Create it (and its parents) when missing; False: only check that it
        could be created (its nearest existing ancestor is a writable directory).

    Raises
    ------
    UsageError
        A file in the way, a directory that cannot be created or is not writable.
    """
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise UsageError(f"{str(path)!r} is not a directory")
    if not create and not path.exists():
        parent = path.parent
        while not parent.exists() and parent != parent.parent:
            parent = parent.parent
        if not parent.is_dir():
            raise UsageError(f"cannot create directory {str(path)!r}: {str(parent)!r} is a file")
        if not os.access(parent, os.W_OK):
            raise UsageError(
                f"cannot create directory {str(path)!r}: {str(parent)!r} is not writable"
            )
        return path
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"cannot create directory {str(path)!r}: {exc.strerror}") from None
    if not os.access(path, os.W_OK):
        raise UsageError(f"directory {str(path)!r} is not writable")
    return path


def _check_frames(frames: int) -> None:
    if isinstance(frames, bool) or not isinstance(frames, int) or not 0 <= frames <= MAX_FRAMES:
        raise UsageError(f"frames must be an int in 0..{MAX_FRAMES}, got {frames!r}")


def _work_limit(solver: str, time_limit: float | None, evaluations: int | None) -> int | None:
    """Check the limits of a solve; the tree search's work limit (None for other solvers)."""
    if time_limit is None:
        if evaluations is None:
            raise UsageError("time_limit=None (no clock) needs a work limit: evaluations=N")
    elif not _is_seconds(time_limit):
        raise UsageError(
            f"time_limit must be a number of seconds in (0, {MAX_TIME_LIMIT:g}], got {time_limit!r}"
        )
    if evaluations is not None:
        if solver != "tree":
            raise UsageError(f"evaluations is a work limit of the tree search, not of {solver!r}")
        if (
            isinstance(evaluations, bool)
            or not isinstance(evaluations, int)
            or not 1 <= evaluations <= MAX_EVALUATIONS
        ):
            raise UsageError(
                f"evaluations must be an int in 1..{MAX_EVALUATIONS}, got {evaluations!r}"
            )
    elif solver == "tree" and time_limit is not None:
        evaluations = default_evaluations(time_limit)
    return evaluations


def solve_limited(
    problem: ProblemLike,
    solver: SolverName = "tree",
    *,
    time_limit: float | None = DEFAULT_TIME_LIMIT,
    evaluations: int | None = None,
    seed: int = 0,
    waits: bool = True,
    on_improve: Callable[[Progress], None] | None = None,
) -> tuple[Result, int | None, float | None]:
    """:func:`scheduler.solve` under the pipeline's reproducible limits (module docstring).

    Parameters
    ----------
    problem : Problem or CompiledCell
    solver : {"tree", "greedy", "cpsat"}
    time_limit : float or None
        Seconds (> 0). The tree search's default work limit is derived from
        it (:func:`default_evaluations`) and its wall-clock cap is
        :data:`WALL_CAP_FACTOR` times it; other solvers stop at it. None:
        no clock at all, only with ``evaluations``.
    evaluations : int, optional
        The tree search's work limit (1 to :data:`MAX_EVALUATIONS`).
    seed : int
    waits : bool
        Whether schedules may wait at zone borders.
    on_improve : callable, optional
        :func:`scheduler.solve`'s ``progress``.

    Returns
    -------
    (Result, int or None, float)
        The result, the work limit used (None for other solvers) and the
        wall-clock cap, seconds (None: none).

    Raises
    ------
    UsageError
        A bad limit, or ``evaluations`` for a solver other than ``tree``.
    """
    evaluations = _work_limit(solver, time_limit, evaluations)
    cap = (
        None
        if time_limit is None
        else float(time_limit) * (WALL_CAP_FACTOR if evaluations is not None else 1.0)
    )
    options = TreeOptions(max_evaluations=evaluations) if evaluations is not None else None
    result = solve(
        problem,
        solver,
        time_limit=cap,
        seed=seed,
        waits=waits,
        options=options,
        progress=on_improve,
    )
    return result, evaluations, cap


def solve_cell(
    cell: Cell | CompiledCell,
    *,
    solver: SolverName = "tree",
    time_limit: float | None = DEFAULT_TIME_LIMIT,
    evaluations: int | None = None,
    seed: int = 0,
    compile_options: CompileOptions | None = None,
    progress: StepCallback | None = None,
    faults: FaultPlan | None = None,
    faults_from: str | None = None,
) -> SolvedCell:
    """Compile ``cell`` (unless compiled already), solve it and validate the schedule.

    Parameters are those of :func:`run_cell`; ``time_limit=None`` with
    ``evaluations`` runs on the work limit alone (no clock). ``faults``
    (read by :func:`load_faults`, from the file ``faults_from``) are checked
    against the compiled cell before the solve: no fault after any possible
    plan end.

    Returns
    -------
    SolvedCell

    Raises
    ------
    UsageError
        Bad limits or seed; ``evaluations`` with a solver other than ``tree``;
        ``compile_options`` with a compiled cell.
    NoFeasibleSchedule
        A task no arm can do (from the compile), or no schedule found.
    """
    if isinstance(cell, CompiledCell):
        if compile_options is not None:
            raise UsageError("compile_options: the cell is compiled already")
    elif not isinstance(cell, Cell):
        raise UsageError(f"expected a workcell.Cell or CompiledCell, got {type(cell).__name__}")
    evaluations = _work_limit(solver, time_limit, evaluations)  # checked before the compile
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_SEED:
        raise UsageError(f"seed must be an int in 0..{MAX_SEED}, got {seed!r}")
    if isinstance(cell, CompiledCell):
        compiled = cell
    else:
        if progress is not None:
            progress("compile", f"{len(cell.taskset.tasks)} tasks, {len(cell.arms)} arms")
        compiled = compile_cell(cell, options=compile_options)
    if faults:
        check_faults(compiled, faults, source=faults_from)  # the times: before the solve
    if progress is not None:
        limit = f"{evaluations} evaluations, " if evaluations is not None else ""
        clock = "no time limit" if time_limit is None else f"time limit {time_limit:g} s"
        progress("solve", f"{solver}, {limit}{clock}")
    result, evaluations, cap = solve_limited(
        compiled, solver, time_limit=time_limit, evaluations=evaluations, seed=seed
    )
    if result.stats.interrupted:  # Ctrl-C during the search: stop the pipeline here
        raise KeyboardInterrupt
    if result.schedule is None:
        raise NoFeasibleSchedule(
            f"cell {compiled.cell.name!r}: the {solver} solver found no schedule "
            f"({result.status.value} after {result.runtime:.1f} s)"
        )
    validate(compiled, result.schedule)
    return SolvedCell(compiled, result, cap, evaluations)


def _is_seconds(value: object) -> bool:
    return (
        not isinstance(value, bool)
        and isinstance(value, int | float)
        and math.isfinite(value)
        and 0 < value <= MAX_TIME_LIMIT
    )


def run_solved(
    solved: SolvedCell,
    *,
    seed: int = 0,
    faults: FaultsLike = None,
    medium: MediumSpec = "ideal",
    coordination: str = "centralized",
    options: SimOptions | None = None,
    out: str | PathLike[str] | None = None,
    frames: int = 0,
    progress: StepCallback | None = None,
) -> CellRun:
    """Simulate a solved cell's schedule and write the run's files.

    Parameters are those of :func:`run_cell`.

    Returns
    -------
    CellRun
    """
    _check_frames(frames)
    plan = load_faults(faults, solved.compiled)
    where = check_out_dir(out, create=False) if out is not None else None
    if progress is not None:
        progress("simulate", f"{len(plan)} faults, medium {medium!r}")
    sim = simulate(
        solved.compiled,
        solved.schedule,
        seed=seed,
        faults=plan,
        medium=medium,
        coordination=coordination,
        options=options,
    )
    written: tuple[Path, ...] = ()
    if where is not None:
        if progress is not None:
            progress("write", str(where))
        written = write_run(where, solved.compiled, solved.schedule, sim, frames=frames)
    status = RunStatus.TASKS_FAILED if int(sim.metrics.failed_tasks) else RunStatus.OK
    return CellRun(
        solved.compiled,
        solved.result,
        sim,
        written,
        status,
        solved.evaluations,
        solved.time_bound,
    )


def run_cell(
    cell: Cell | CompiledCell,
    *,
    solver: SolverName = "tree",
    time_limit: float = DEFAULT_TIME_LIMIT,
    evaluations: int | None = None,
    seed: int = 0,
    faults: FaultsLike = None,
    medium: MediumSpec = "ideal",
    coordination: str = "centralized",
    options: SimOptions | None = None,
    compile_options: CompileOptions | None = None,
    out: str | PathLike[str] | None = None,
    frames: int = 0,
    progress: StepCallback | None = None,
) -> CellRun:
    """Compile, solve, validate, simulate and (with ``out``) write: the main job.

    Parameters
    ----------
    cell : Cell or CompiledCell
        A compiled cell skips the compile.
    solver : {"tree", "greedy", "cpsat"}
        :func:`scheduler.solve`'s solver.
    time_limit : float
        Seconds (> 0): the tree search's default work limit derives from it
        and its wall-clock cap is :data:`WALL_CAP_FACTOR` times it; the
        other solvers stop at it.
    evaluations : int, optional
        The tree search's work limit, schedules evaluated (1 to
        :data:`MAX_EVALUATIONS`); default :func:`default_evaluations`
        of ``time_limit``, so the plan depends on the seed only.
    seed : int
        Seeds the solver and the simulation (message loss, drawn insertions).
    faults : FaultPlan, records, dicts, a ``.toml``/``.json`` path, or None
        Read and checked before the compile (:func:`load_faults`).
    medium : str or callable
        The medium between the coordinator and the arms (:func:`workcell.simulate`).
    coordination : {"centralized"}
        The coordination policy.
    options : SimOptions, optional
        The simulation's settings.
    compile_options : CompileOptions, optional
        The compile's settings (not with a compiled cell).
    out : str or path-like, optional
        A directory (created if missing, checked before any work) for
        :data:`RUN_FILES`.
    frames : int
        Also write this many motion frames to ``out/frames/`` (0 to :data:`MAX_FRAMES`).
    progress : callable, optional
        ``progress(step, detail)`` as each of :data:`STEPS` begins.

    Returns
    -------
    CellRun
        Its ``status`` says whether tasks failed; a run with failed tasks
        is a result, not an exception.

    Raises
    ------
    UsageError
        Bad arguments (named), before any long work.
    FormatError
        A malformed faults file.
    NoFeasibleSchedule
        A task no arm can do, or no schedule found.
    SafetyViolation
        The simulation's monitor saw a collision or a broken zone invariant.
    """
    _check_frames(frames)
    plan = load_faults(faults, cell)  # the one place faults are read and checked: before compiling
    if out is not None:
        check_out_dir(out, create=False)
    solved = solve_cell(
        cell,
        solver=solver,
        time_limit=time_limit,
        evaluations=evaluations,
        seed=seed,
        compile_options=compile_options,
        progress=progress,
        faults=plan,
        faults_from=faults_source(faults),
    )
    return run_solved(
        solved,
        seed=seed,
        faults=plan,
        medium=medium,
        coordination=coordination,
        options=options,
        out=out,
        frames=frames,
        progress=progress,
    )


def write_run(
    out: str | PathLike[str],
    compiled: CompiledCell,
    schedule: Schedule,
    sim: SimResult,
    *,
    frames: int = 0,
) -> tuple[Path, ...]:
    """Write :data:`RUN_FILES` of one run into ``out`` (and ``frames`` motion frames).

    Parameters
    ----------
    out : str or path-like
        An existing or creatable directory.
    compiled : CompiledCell
    schedule : scheduler.Schedule
        The plan simulated.
    sim : SimResult
    frames : int
        Motion frames to write into ``out/frames/`` (0 to :data:`MAX_FRAMES`).

    Returns
    -------
    tuple of Path
        The files written, in the order of :data:`RUN_FILES`, then the frames.
    """
    import numpy as np

    from workcell.replay import build_replay, write_html
    from workcell.viz.plots import gantt, motion_frames, render_instants, zone_timeline

    _check_frames(frames)
    where = check_out_dir(out)
    problem = compiled.problem
    sim.save(where)
    (where / "schedule.json").write_text(json.dumps(schedule.to_dict(problem), indent=1) + "\n")
    fig = gantt(problem, schedule, sim)
    fig.savefig(where / "gantt.png", dpi=100)
    fig = zone_timeline(sim, title=f"{problem.name}: zone occupancy, executed")
    fig.savefig(where / "zones.png", dpi=100)
    end = float(sim.metrics.executed_makespan)
    if not (math.isfinite(end) and end > 0):
        end = schedule.makespan
    times = np.round(np.linspace(0.0, end, 5)[1:4], 1)
    fig = render_instants(compiled, sim, [0.0, *times.tolist()])
    fig.savefig(where / "instants.png", dpi=90)
    replay = build_replay(sim, compiled)
    replay.save(where)  # replay.json: 'multiarm view DIR' rebuilds the page from it
    write_html(replay, None, where / "replay.html")
    written = [where / n for n in RUN_FILES]
    if frames:
        written += motion_frames(compiled, sim, where / "frames", n_frames=frames)
    return tuple(written)


def failure_candidate(problem: Problem, schedule: Schedule) -> str:
    """The arm whose failure tells most about re-solving (``multiarm demo`` injects it).

    The busiest arm whose every task another arm can take over; the busiest
    arm when none can be spared. Ties go to the first arm.
    """
    import numpy as np

    arms = schedule.arms(problem)
    load = [
        float(np.sum((schedule.end - schedule.start)[arms == a])) for a in range(problem.n_arms)
    ]

    def spare(a: int) -> bool:
        return all(
            any(int(problem.mode_arm[m]) != a for m in problem.task_modes[t])
            for t in range(problem.n_tasks)
        )

    order = sorted(range(problem.n_arms), key=lambda a: (not spare(a), -load[a], a))
    return str(problem.arm_names[order[0]])
