"""Compiling a cell into the scheduler's problem: the one boundary (DESIGN.md step 2).

For every (task, arm) pair :func:`compile_cell` decides whether the arm can
do the task and, if so, builds the **mode**:

1. capabilities and tool mounts: an arm lacking what the task needs has no
   mode for it;
2. the task's motion program (:func:`workcell.program.expand_task`) is
   solved by the arm's inverse kinematics pose by pose, each solution
   started from the previous one (straight-line moves are subdivided so the
   joint path follows the line); an unreachable pose or a joint limit means
   no mode (the reason is kept);
3. the joint path is timed with the arm's drives (S1.5 stepper profiles for
   gantry axes, servo profiles otherwise; per-axis or synchronised as the
   program says, S1.9) plus the step dwells: the mode's duration, nominal or
   worst case (:attr:`Cell.plan_with`); with ``park="home"`` (the default)
   the mode is the round trip from the arm's start joints to the task and
   back, so every motion is swept and travel setups are zero;
4. the arm's collision shapes are swept along the timed path through the
   zones (:func:`workcell.geometry.zone_windows`, conservative by the cell's
   padding): each zone touched gives an ``occupy`` window and, in a shared
   zone, the ``move`` windows in which the arm moves there; the task's tool is
   held throughout. Only zones active at the start (SDL ``active``) get
   windows: the others constrain nothing until activated (S2.5).

Across tasks it carries over every ordering the task set states: explicit
and part prerequisites, producers before consumers, part groups (S2.11),
and flag synchronisation (S1.9) as whole-task precedence (the setter ends
before the waiter starts: safe, and exact when flags are set at a task's
end, as in the built-in cells); release times from the part-arrival model;
start zones from the arms' initial poses; sequence-dependent travel times
(:class:`JointTravelSetup`, exact under the same drive profiles, computed
a row at a time on demand and cached); and a blocking oracle
(:class:`workcell.oracle.CellOracle`) for arms parked in another's way.

The settings are one :class:`~workcell.compiled.CompileOptions` record; the
result is one frozen :class:`CompiledCell` (the problem, the modes'
trajectories, the rejected pairs, the oracle and the options applied).
Nothing is kept anywhere else: keep the CompiledCell.

Examples
--------
>>> from workcell.cell import load_example
>>> cc = compile_cell(load_example("supersigma"))
>>> cc.problem.n_arms, cc.problem.n_tasks
(2, 10)
>>> cc.options.grid  # the space grid's block side used, metres (0: off)
0.3
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from multiarm.errors import NoFeasibleSchedule, Unreachable, UsageError, ValidationError
from multiarm.types import BoolArray, FloatArray, JointVector
from scheduler import MatrixSetup, Model, Problem, Setup, Window
from scheduler.setup import BoundSetup
from scheduler.view import ProblemView
from tasklib.model import Task
from workcell.arms import DriveArm, JointTrajectory, Segment
from workcell.arms.trajectory import Interpolation, move_segment
from workcell.cell import Cell
from workcell.compiled import CompiledMode, CompileOptions
from workcell.geometry import sample_trajectory, static_occupancy, zone_contacts, zone_windows
from workcell.geometry.reach import (
    arm_capsules,
    capsules_box,
    shared_blocks,
    windows_from_flags,
)
from workcell.oracle import CellOracle
from workcell.program import Program, expand_task

__all__ = [
    "CompileOptions",
    "CompiledCell",
    "CompiledMode",
    "JointTravelSetup",
    "compile_cell",
    "compile_cell_detailed",
    "compile_details",
]


@dataclass(frozen=True, eq=False, slots=True)
class CompiledCell:
    """A compiled cell: the problem plus the per-mode detail behind it.

    ``scheduler.solve`` and ``scheduler.validate`` accept it in place of its
    :attr:`problem`; ``workcell.simulate`` and the plots need it (a bare
    Problem does not carry the trajectories).

    Attributes
    ----------
    cell : Cell
    problem : scheduler.Problem
    modes : tuple of CompiledMode
        Indexed like ``problem``'s modes.
    rejected : mapping of (task, arm) -> str
        Why an arm has no mode for a task (read-only).
    oracle : CellOracle
        The blocking oracle (also ``problem.blocking``).
    options : CompileOptions
        The options applied, with the cell's own choices filled in
        (``grid`` is the block side used, 0 when the grid was off;
        ``plan_with`` is set).
    seconds : float
        Wall time of the compile.
    """

    cell: Cell
    problem: Problem
    modes: tuple[CompiledMode, ...]
    rejected: Mapping[tuple[str, str], str]
    oracle: CellOracle
    options: CompileOptions
    seconds: float = 0.0

    def mode(self, task: str, arm: str) -> CompiledMode:
        """The compiled mode of ``task`` on ``arm``."""
        p = self.problem
        try:
            t, a = p.task_names.index(task), p.arm_names.index(arm)
        except ValueError:
            raise ValidationError(f"no task {task!r} or arm {arm!r} in {p.name!r}") from None
        m = int(p.mode_of[a, t])
        if m < 0:
            why = self.rejected.get((task, arm), "no mode")
            raise ValidationError(f"arm {arm!r} has no mode for task {task!r}: {why}")
        return self.modes[m]


def compile_details(problem: object) -> CompiledCell:
    """Deprecated: keep the :class:`CompiledCell` that :func:`compile_cell` returns.

    Given a CompiledCell, returns it; given a Problem, raises: no registry of
    compiled problems is kept.

    Raises
    ------
    UsageError
        Anything but a CompiledCell.
    """
    warnings.warn(
        "workcell.compile_details is deprecated: workcell.compile_cell returns the "
        "CompiledCell; keep it",
        DeprecationWarning,
        stacklevel=2,
    )
    if isinstance(problem, CompiledCell):
        return problem
    name = getattr(problem, "name", type(problem).__name__)
    raise UsageError(
        f"compile_details({name!r}): no registry of compiled problems is kept; keep the "
        "CompiledCell that workcell.compile_cell returns (its .problem is the Problem)"
    )


# ------------------------------------------------------------ one mode


def _lacks(task: Task, arm: DriveArm) -> str | None:
    missing = sorted(task.required_capabilities - arm.capabilities)
    if missing:
        return f"lacks capability {', '.join(repr(m) for m in missing)}"
    if task.tool is not None and task.tool not in arm.tools:
        return f"cannot mount tool {task.tool!r}"
    return None


def _line(a: FloatArray, b: FloatArray, step: float) -> list[FloatArray]:
    """Poses along the straight line from ``a`` to ``b`` (excluded, included),
    orientation of ``b``, at most ``step`` metres apart."""
    dist = float(np.linalg.norm(b[:3, 3] - a[:3, 3]))
    n = max(1, int(np.ceil(dist / step)))
    out = []
    for k in range(1, n + 1):
        t = b.copy()
        t[:3, 3] = a[:3, 3] + (b[:3, 3] - a[:3, 3]) * (k / n)
        out.append(t)
    return out


def _mode(
    program: Program,
    arm: DriveArm,
    q0: JointVector,
    park: JointVector | None = None,
    approach_from: JointVector | None = None,
    step: float = 0.02,
) -> tuple[JointTrajectory, list[float], JointVector]:
    """Time ``program`` on ``arm`` from joint vector ``q0`` (then back to
    ``park`` if given); with ``approach_from``, the trajectory starts there
    with a joint move to ``q0``.

    Returns the trajectory, each program segment's start offset, and the end
    joints. Raises Unreachable (naming the step) when a pose cannot be reached.
    """
    segments: list[Segment] = []
    offsets: list[float] = []
    q = np.asarray(q0, dtype=float)
    pose = arm.fk(q[None])[0]
    t = 0.0
    if approach_from is not None:
        come = move_segment(
            arm.drives, np.asarray(approach_from, dtype=float), q, arm.interpolation
        )
        if come is not None:
            segments.append(come)
            t += come.duration
            # a stepper ends on whole steps, within half a step of ``q0``: the
            # program goes on from there (starting it at ``q0`` made the
            # trajectory jump by up to half a wrist step, 0.3 mm of the hand)
            q = come.q1
    for seg in program.segments:
        offsets.append(t)
        if seg.kind == "dwell":
            segments.append(Segment(q, q, seg.duration))
            t += seg.duration
            continue
        target = seg.target
        if target is None:  # pragma: no cover - a move always has a target
            continue
        poses = _line(pose, target, step) if seg.interpolation == "linear" else [target]
        interp: Interpolation = "sync" if seg.interpolation == "linear" else arm.interpolation
        for p in poses:
            try:
                q_goal = arm.ik(p, q)
            except Unreachable as exc:
                raise Unreachable(f"step {seg.step} ({seg.label}): {exc}") from None
            piece = move_segment(arm.drives, q, q_goal, interp, seg.speed)
            if piece is not None:
                segments.append(piece)
                t += piece.duration
                q = piece.q1
        pose = target
    offsets.append(t)
    if park is not None:
        back = move_segment(arm.drives, q, park, arm.interpolation)
        if back is not None:
            segments.append(back)
            q = back.q1
    if not segments:
        segments.append(Segment(q, q, 0.0))
    return JointTrajectory.build(segments), offsets, q


# --------------------------------------------------------------- compile


def _releases(cell: Cell) -> dict[str, float]:
    ts = cell.taskset
    if cell.releases == "none":
        return {}
    if cell.releases == "expected":
        arrive = ts.expected_arrivals()
    else:
        arrive = {a.part: a.time for a in ts.sample_arrivals(cell.seed)}
    out: dict[str, float] = {}
    for task in ts.tasks:
        gating = ts.gating_parts(task.id)
        if gating:
            out[task.id] = max(arrive[p] for p in gating)
    return out


def _resolve(cell: Cell, options: CompileOptions | None = None) -> CompileOptions:
    """``options`` (default :class:`CompileOptions`) with the cell's own
    choices filled in where a field is None: the grid block side from
    ``cell.grid`` (0 when off or with fewer than two arms) and ``plan_with``."""
    if options is None:
        options = CompileOptions()
    elif not isinstance(options, CompileOptions):
        raise UsageError(
            f"compile_cell: options must be a workcell.CompileOptions, got {type(options).__name__}"
        )
    grid = cell.grid if options.grid is None else float(options.grid)
    if len(cell.arms) < 2:
        grid = 0.0
    return replace(options, grid=float(grid), plan_with=options.plan_with or cell.plan_with)


def compile_cell(
    cell: Cell,
    *,
    options: CompileOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> CompiledCell:
    """Compile ``cell`` into a :class:`CompiledCell` (module docstring).

    Parameters
    ----------
    cell : Cell
    options : CompileOptions, optional
        Defaults: the cell's own choices (its ``[compile]`` table) and the
        module defaults.
    progress : callable, optional
        Called as ``progress(done, total)`` after each task (kept out of the
        options, which are plain values).

    Returns
    -------
    CompiledCell
        ``.problem`` is the :class:`scheduler.Problem`, with a
        :class:`JointTravelSetup` of travel times and the cell's blocking
        oracle; ``.modes`` the modes' trajectories.

    Raises
    ------
    NoFeasibleSchedule
        A task no arm can do: the message names it and why each arm failed.
    UsageError
        ``options`` is not a CompileOptions.
    """
    if not isinstance(cell, Cell):
        raise UsageError(f"compile_cell: expected a workcell.Cell, got {type(cell).__name__}")
    opts = _resolve(cell, options)
    return _compile(cell, opts, progress)


def compile_cell_detailed(
    cell: Cell,
    *,
    plan_with: Literal["nominal", "worst"] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> CompiledCell:
    """Deprecated alias: ``compile_cell(cell, options=CompileOptions(plan_with=...))``."""
    warnings.warn(
        "workcell.compile_cell_detailed is deprecated: workcell.compile_cell returns the "
        "CompiledCell (plan_with is a CompileOptions field)",
        DeprecationWarning,
        stacklevel=2,
    )
    return compile_cell(cell, options=CompileOptions(plan_with=plan_with), progress=progress)


def _compile(
    cell: Cell, opts: CompileOptions, progress: Callable[[int, int], None] | None
) -> CompiledCell:
    t0 = time.perf_counter()
    plan = opts.plan_with or cell.plan_with
    ts = cell.taskset
    zm = cell.zone_map
    shared = ~zm.exclusive_mask()
    active = zm.active_mask()
    tool_names = sorted({t.tool for t in ts.tasks if t.tool is not None})
    releases = _releases(cell)
    group_of: dict[str, int] = {}
    for g, grp in enumerate(ts.groups):
        for tid in grp.tasks:
            group_of[tid] = g
    preds = ts.precedence()
    for setter, waiter, _flag in ts.flag_edges():
        preds[waiter] = tuple(dict.fromkeys((*preds.get(waiter, ()), setter)))
    modes: list[tuple[tuple[int, int], CompiledMode]] = []
    rejected: dict[tuple[str, str], str] = {}
    motions: dict[tuple[Any, ...], _Motion | str] = {}
    for ti, task in enumerate(ts.tasks):
        program = expand_task(task, ts.trajectories, plan)
        reasons = []
        for ai, (arm, q0) in enumerate(zip(cell.arms, cell.start, strict=True)):
            why = _lacks(task, arm)
            if why is None:
                # Tasks repeated for several products (the same moves and
                # dwells) time and sweep alike on one arm: done once.
                key = (ai, _program_key(program))
                got = motions.get(key)
                if got is None:
                    try:
                        got = _motion(program, arm, q0, cell, shared, active, opts.linear_step)
                    except Unreachable as exc:
                        got = str(exc)
                    except ValidationError as exc:  # name the cell file, the arm and the task
                        raise ValidationError(
                            f"{cell.source or repr(cell.name)}: arms.{arm.name}: "
                            f"task {task.id!r}: {exc}"
                        ) from None
                    motions[key] = got
                if isinstance(got, str):
                    why = got
                else:
                    modes.append(((ti, ai), _compiled_mode(task, program, arm, got)))
                    continue
            rejected[(task.id, arm.name)] = why
            reasons.append(f"{arm.name}: {why}")
        if not any(key[0] == ti for key, _ in modes):
            raise NoFeasibleSchedule(
                f"cell {cell.name!r}: no arm can do task {task.id!r} ({'; '.join(reasons)})"
            )
        if progress is not None:
            progress(ti + 1, len(ts.tasks))
    modes, pair_zones = _pair_windows(cell, modes, float(opts.grid or 0.0), opts.grid_padding)
    m = _model(cell, releases, group_of, preds, tool_names, active, modes, pair_zones)
    oracle = CellOracle(
        cell,
        budget=opts.detour_budget,
        max_checks=opts.detour_max_checks,
        seed=opts.detour_seed,
        grid=opts.contact_padding,
        detours=opts.detours,
    )
    problem, ordered = _build(m, cell, modes, oracle)
    if cell.park == "home":
        # Every arm rests at its start joints between tasks: a mode that would
        # hit another arm resting there can never be sure to run; drop it, so
        # that running the tasks one at a time is always a valid schedule.
        table = oracle.table()
        drop = set()
        for mi in range(problem.n_modes):
            hit = [b for b in range(problem.n_arms) if math.isinf(table[mi, b, 0])]
            if hit:
                t, a = int(problem.mode_task[mi]), int(problem.mode_arm[mi])
                drop.add((t, a))
                names = ", ".join(repr(cell.arms[b].name) for b in hit)
                rejected[(ts.tasks[t].id, cell.arms[a].name)] = (
                    f"would hit arm {names} resting at its start joints"
                )
        if drop:
            modes = [x for x in modes if x[0] not in drop]
            for ti, task in enumerate(ts.tasks):
                if not any(key[0] == ti for key, _ in modes):
                    why_all = "; ".join(
                        f"{arm.name}: {rejected.get((task.id, arm.name), '?')}" for arm in cell.arms
                    )
                    raise NoFeasibleSchedule(
                        f"cell {cell.name!r}: no arm can do task {task.id!r} ({why_all})"
                    )
            m = _model(cell, releases, group_of, preds, tool_names, active, modes, pair_zones)
            problem, ordered = _build(m, cell, modes, oracle)
    return CompiledCell(
        cell,
        problem,
        ordered,
        MappingProxyType(rejected),
        oracle,
        opts,
        time.perf_counter() - t0,
    )


def _model(
    cell: Cell,
    releases: dict[str, float],
    group_of: dict[str, int],
    preds: dict[str, tuple[str, ...]],
    tool_names: list[str],
    active: Any,
    modes: list[tuple[tuple[int, int], CompiledMode]],
    pair_zones: tuple[str, ...] = (),
) -> Model:
    ts, zm = cell.taskset, cell.zone_map
    m = Model(cell.name)
    for z in range(zm.n_zones):
        m.add_zone(zm.zone_names()[z], "exclusive" if bool(zm.exclusive_mask()[z]) else "shared")
    for name in pair_zones:
        m.add_zone(name, "exclusive")
    for k in tool_names:
        m.add_tool(k)
    for arm, q in zip(cell.arms, cell.start, strict=True):
        zones_in = [z for z in static_occupancy(arm, q, zm) if bool(active[zm.zone_id(z)])]
        m.add_arm(arm.name, capabilities=sorted(arm.capabilities), start_zones=zones_in)
    for task in ts.tasks:
        m.add_task(task.id, release=releases.get(task.id, 0.0), group=group_of.get(task.id, -1))
    for task in ts.tasks:
        m.add_predecessors(task.id, preds.get(task.id, ()))
    for (_t, _a), cm in modes:
        m.add_mode(cm.task, cm.arm, cm.duration, windows=cm.windows, tools=cm.tools)
    m.set_setup(JointTravelSetup(cell, modes))
    return m


def _pair_windows(
    cell: Cell,
    modes: list[tuple[tuple[int, int], CompiledMode]],
    grid: float,
    grid_padding: float,
) -> tuple[list[tuple[tuple[int, int], CompiledMode]], tuple[str, ...]]:
    """Add the space-grid zones' windows to the modes (:mod:`workcell.geometry.reach`).

    The space two or more arms can reach is cut into blocks of
    ``grid`` metres (0: no grid); every block that modes of two or more arms
    touch becomes an exclusive zone, with each mode's occupancy windows from
    the zone sweep. Two arms can then never be where they could meet at the
    same time. Returns the modes with their new windows and the zones used.
    """
    if grid <= 0 or len(cell.arms) < 2:
        return modes, ()
    # The blocks are coarse, so the sweep against them samples more coarsely
    # too: the guarantee holds for any padding (windows grow by it).
    pad = max(cell.padding, grid_padding)
    samples: list[tuple[FloatArray, FloatArray]] = []
    boxes: list[list[FloatArray]] = [[] for _ in cell.arms]
    seen: set[int] = set()
    for (_t, a), cm in modes:
        arm = cell.arms[a]
        try:
            t, q = sample_trajectory(arm, cm.trajectory, pad)  # shared by modes of one motion
        except ValidationError as exc:  # name the cell file and the arm
            where = cell.source or repr(cell.name)
            raise ValidationError(f"{where}: arms.{arm.name}: compile.grid: {exc}") from None
        samples.append((t, q))
        if id(q) not in seen:
            seen.add(id(q))
            boxes[a].append(capsules_box(*arm_capsules(arm, q), pad))
    for a, (arm, q0) in enumerate(zip(cell.arms, cell.start, strict=True)):
        boxes[a].append(capsules_box(*arm_capsules(arm, np.asarray(q0, dtype=float)), pad))
    reach = [
        np.stack([np.min([b[0] for b in bs], 0), np.max([b[1] for b in bs], 0)]) for bs in boxes
    ]
    try:
        blocks = shared_blocks(reach, grid)
    except ValidationError as exc:  # name the cell file's field (or the cell)
        raise ValidationError(f"{cell.source or repr(cell.name)}: compile.grid: {exc}") from None
    if blocks.n_zones == 0:
        return modes, ()
    names = blocks.zone_names()
    spans: list[list[tuple[int, float, float]]] = []
    users: list[set[int]] = [set() for _ in range(blocks.n_zones)]
    contacts: dict[int, BoolArray] = {}
    for i, ((_t, a), cm) in enumerate(modes):
        t, q = samples[i]
        flags = contacts.get(id(q))
        if flags is None:
            flags = contacts[id(q)] = zone_contacts(cell.arms[a], q, blocks, pad)
        dur = cm.duration
        mine: list[tuple[int, float, float]] = []
        for z in np.flatnonzero(flags.any(axis=0)):
            for s, e in windows_from_flags(t, flags[:, z]):
                s, e = max(0.0, s), min(dur, e)
                if e > s:
                    mine.append((int(z), s, e))
                    users[int(z)].add(a)
        spans.append(mine)
    keep = {z for z in range(blocks.n_zones) if len(users[z]) >= 2}
    out = []
    for i, (key, cm) in enumerate(modes):
        extra = tuple(Window(names[z], s, e, "occupy") for z, s, e in spans[i] if z in keep)
        out.append((key, replace(cm, windows=cm.windows + extra) if extra else cm))
    return out, tuple(names[z] for z in sorted(keep))


def _build(
    m: Model,
    cell: Cell,
    modes: list[tuple[tuple[int, int], CompiledMode]],
    oracle: CellOracle,
) -> tuple[Problem, tuple[CompiledMode, ...]]:
    m.set_blocking(oracle)
    problem = m.build()
    # the Model orders modes by (task, arm): the same order as ``modes``
    ordered = tuple(cm for _, cm in sorted(modes, key=lambda x: x[0]))
    oracle.bind(problem, ordered)
    return problem, ordered


def _program_key(program: Program) -> tuple[Any, ...]:
    """What a program's motion depends on: its segments (flags and the task
    name left out), the targets by value."""
    return tuple(
        (
            s.kind,
            None if s.target is None else np.asarray(s.target, dtype=float).tobytes(),
            s.interpolation,
            s.speed,
            s.duration,
            s.label,
            s.step,
        )
        for s in program.segments
    )


@dataclass(frozen=True, slots=True)
class _Motion:
    """A program timed and swept on one arm: the parts of a compiled mode
    that do not depend on the task's name, tool or flags."""

    trajectory: JointTrajectory
    offsets: tuple[float, ...]
    q_start: JointVector
    q_end: JointVector
    windows: tuple[Window, ...]


def _motion(
    program: Program,
    arm: DriveArm,
    q0: JointVector,
    cell: Cell,
    shared: Any,
    active: Any,
    step: float,
) -> _Motion:
    # With park="last" the task starts at its first pose and the travel there
    # is the setup. With park="home" the task is the whole round trip from
    # the arm's start joints and back, so every motion is swept for zones
    # (the setups between tasks are then zero).
    first = next((s.target for s in program.segments if s.target is not None), None)
    q_first = arm.ik(first, q0) if first is not None else np.asarray(q0, dtype=float)
    home = np.asarray(q0, dtype=float) if cell.park == "home" else None
    traj, offsets, q_end = _mode(program, arm, q_first, home, approach_from=home, step=step)
    if home is not None:
        q_first = home
    zw = zone_windows(arm, traj, cell.zone_map, padding=cell.padding)
    windows: list[Window] = []
    dur = traj.duration
    for w in zw.windows:
        if not bool(active[w.zone_id]):
            continue
        kinds = [("occupy", w.occupied)]
        if bool(shared[w.zone_id]):
            kinds.append(("move", w.moving))
        for kind, spans in kinds:
            for s, e in spans:
                s, e = max(0.0, float(s)), min(dur, float(e))
                if e > s:
                    windows.append(Window(w.zone, s, e, kind))  # type: ignore[arg-type]
    return _Motion(traj, tuple(offsets), q_first, q_end, tuple(windows))


def _compiled_mode(task: Task, program: Program, arm: DriveArm, mo: _Motion) -> CompiledMode:
    sets = tuple((f, mo.offsets[i]) for f, i in program.flags_set)
    waits = tuple((f, mo.offsets[i]) for f, i in program.flags_waited)
    tools = (task.tool,) if task.tool is not None else ()
    return CompiledMode(
        task.id, arm.name, mo.trajectory, mo.q_start, mo.q_end, mo.windows, tools, sets, waits
    )


class JointTravelSetup(Setup):
    """Travel times of a compiled cell: each arm's exact move time (its drives'
    own profiles, the slowest joint setting the time) from one task's end
    joints to the next task's start joints (``prev = -1``: its start joints),
    a row at a time, vectorised over the next tasks, and cached by the problem.

    Written to JSON as the equivalent dense :class:`scheduler.MatrixSetup`.
    """

    def __init__(self, cell: Cell, modes: list[tuple[tuple[int, int], CompiledMode]]) -> None:
        self.arms = cell.arms
        self.start = cell.start
        self.q_start: dict[int, dict[int, JointVector]] = {a: {} for a in range(len(cell.arms))}
        self.q_end: dict[int, dict[int, JointVector]] = {a: {} for a in range(len(cell.arms))}
        for (t, a), cm in modes:
            self.q_start[a][t] = cm.q_start
            self.q_end[a][t] = cm.q_end

    def _row(self, n_tasks: int, a: int, prev: int) -> FloatArray:
        out = np.full(n_tasks, math.inf)
        targets = self.q_start[a]
        q0 = self.start[a] if prev < 0 else self.q_end[a].get(prev)
        if q0 is None or not targets:
            return out
        tasks = np.fromiter(targets, dtype=np.int64)
        q1 = np.stack([targets[t] for t in tasks.tolist()])
        out[tasks] = self.arms[a].move_times(np.broadcast_to(q0, q1.shape), q1)
        return out

    def bind(self, problem: ProblemView) -> BoundSetup:
        return BoundSetup(problem, lambda a, prev: self._row(problem.n_tasks, a, prev))

    def to_dict(self) -> dict[str, Any]:
        n_arms = len(self.arms)
        n_tasks = 1 + max((t for d in self.q_start.values() for t in d), default=-1)
        times = np.stack(
            [
                np.stack([self._row(n_tasks, a, prev) for prev in range(-1, n_tasks)])
                for a in range(n_arms)
            ]
        )
        return MatrixSetup(np.where(np.isfinite(times), times, 0.0)).to_dict()
