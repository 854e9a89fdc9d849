"""``simulate``: execute a schedule in the simulated cell and return the result.

The run puts together the event kernel (:mod:`workcell.sim.events.loop`), a
medium (:mod:`workcell.sim.comms.medium`, or one of :mod:`workcell.sim.comms`
by name), the coordinator (:mod:`workcell.sim.coordination.centralized`), one S2.3
controller per arm (:mod:`workcell.sim.control.controller`), the faults
(:mod:`workcell.sim.harness.faults`) and the independent safety monitor
(:mod:`workcell.sim.harness.monitor`), and returns a :class:`SimResult`.

Examples
--------
>>> from workcell import load_example, compile_cell
>>> from scheduler import solve
>>> cc = compile_cell(load_example("supersigma"))
>>> plan = solve(cc.problem, "greedy", seed=0).schedule
>>> result = simulate(cc, plan)
>>> set(result.tasks_frame()["status"])
{'done'}
>>> result.metrics.executed_makespan >= plan.makespan  # geometric stops (S2.12) cost time
True
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from multiarm.errors import InternalError, UsageError, ValidationError
from multiarm.types import FloatArray
from scheduler import Plan, Problem, Schedule, validate
from workcell.arms.profiles import StepperDrive
from workcell.cell import Cell
from workcell.compile import CompiledCell, compile_cell
from workcell.sim.comms.media import make_medium
from workcell.sim.comms.medium import Medium
from workcell.sim.control.controller import ArmController, Ticker
from workcell.sim.control.force import free_thresholds, insert_searches
from workcell.sim.coordination.centralized import FAR, Coordinator, Network
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Metrics, Trace
from workcell.sim.harness.faults import (
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    Fault,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
    as_plan,
)
from workcell.sim.harness.monitor import LiveMonitor, SafetyMonitor
from workcell.sim.harness.options import CONTROL_TIME, COORDINATION_POLICIES, SimOptions
from workcell.sim.protocol.records import MotionLog, TaskRecord

__all__ = ["CONTROL_TIME", "SimOptions", "SimResult", "check_control_bound", "simulate"]

MediumSpec = str | Callable[[EventLoop, int], Medium]


def check_control_bound(n_arms: int, period: float, control_time: float = CONTROL_TIME) -> int:
    """The S2.2 centralized-control bound: ``arms <= period / control_time``.

    Parameters
    ----------
    n_arms : int
    period : float
        Sampling period, seconds.
    control_time : float
        Per-arm control time per period, seconds.

    Returns
    -------
    int
        The largest number of arms one processor can control.

    Raises
    ------
    UsageError
        When ``n_arms`` exceeds the bound (the message gives the numbers).

    Examples
    --------
    >>> check_control_bound(8, 1e-3)
    8
    >>> check_control_bound(9, 1e-3)
    Traceback (most recent call last):
    ...
    multiarm.errors.UsageError: centralized control (S2.2): 9 arms exceed sampling period / per-arm control time = 0.001 s / 0.000125 s = 8 arms
    """
    if not (period > 0 and math.isfinite(period)):
        raise UsageError(f"sampling period must be > 0 seconds, got {period!r}")
    if not (control_time > 0 and math.isfinite(control_time)):
        raise UsageError(f"per-arm control time must be > 0 seconds, got {control_time!r}")
    bound = math.floor(period / control_time + 1e-9)
    if n_arms > bound:
        raise UsageError(
            f"centralized control (S2.2): {n_arms} arms exceed sampling period / per-arm "
            f"control time = {period:g} s / {control_time:g} s = {bound} arms"
        )
    return bound


def _medium(spec: MediumSpec, kernel: EventLoop, stations: int) -> Medium:
    if callable(spec):
        m = spec(kernel, stations)
        if not isinstance(m, Medium):
            raise UsageError(f"medium factory returned {m!r}, not a Medium")
        return m
    if not isinstance(spec, str):
        raise UsageError(f"medium must be a name or a callable, got {spec!r}")
    out: Medium = make_medium(spec, kernel, stations)
    return out


@dataclass(frozen=True, slots=True, repr=False)
class SimResult:
    """What :func:`simulate` returns (a frozen record).

    Attributes
    ----------
    problem : scheduler.Problem
    schedule : scheduler.Schedule
        The plan given.
    plan : scheduler.Plan
        The last plan the coordinator followed (after any re-solve), bound
        to its problem (the type of ``scheduler.Result.plan``).
    executed : scheduler.Schedule or None
        What ran, when every task completed (else None).
    seed : int
    trace : Trace
    metrics : Metrics
    monitor : LiveMonitor or None
        The live safety monitor of the run (its counters), None when off.
    arm_logs : tuple of MotionLog
        Each arm's published motion and task records
        (:class:`~workcell.sim.protocol.records.MotionLog`), in arm order.
    """

    problem: Problem
    schedule: Schedule
    plan: Plan
    executed: Schedule | None
    seed: int
    trace: Trace
    metrics: Metrics
    monitor: LiveMonitor | None = None
    _tasks: tuple[dict[str, Any], ...] = ()
    _reservations: tuple[dict[str, Any], ...] = ()
    arm_logs: tuple[MotionLog, ...] = ()

    def joints(self, times: Sequence[float] | FloatArray) -> dict[str, FloatArray]:
        """Each arm's actual joints at ``times`` (seconds) as run: arm name ->
        (N, dof) float (for rendering the cell at chosen instants)."""
        t = np.asarray(times, dtype=float).reshape(-1)
        return {c.name: SafetyMonitor.joints(c, t) for c in self.arm_logs}

    def tasks_frame(self) -> Any:
        """One row per task: task, arm, mode, planned_start, planned_end,
        start, end, status ("done" | "failed"), cause (text) and cause_kind
        (its category, one of :data:`~workcell.sim.coordination.centralized.CAUSE_KINDS`;
        "" for a task done)."""
        import pandas as pd

        cols = [
            "task",
            "arm",
            "mode",
            "planned_start",
            "planned_end",
            "start",
            "end",
            "status",
            "cause",
            "cause_kind",
        ]
        return pd.DataFrame(self._tasks, columns=cols)

    def reservations_frame(self) -> Any:
        """Executed resource use: kind ("zone" | "move" | "tool"), resource,
        arm, task, start, end."""
        import pandas as pd

        return pd.DataFrame(
            self._reservations, columns=["kind", "resource", "task", "arm", "start", "end"]
        )

    def save(self, directory: str | PathLike[str]) -> Path:
        """Write trace.json, metrics.json and tasks.csv into ``directory`` (created)."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.trace.to_json(d / "trace.json")
        self.metrics.to_json(d / "metrics.json")
        self.tasks_frame().to_csv(d / "tasks.csv", index=False)
        return d

    def __repr__(self) -> str:
        m = self.metrics
        return (
            f"SimResult({self.problem.name!r}: planned {m.planned_makespan:.6g} s, executed "
            f"{m.executed_makespan:.6g} s, {m.done_tasks} done, {m.failed_tasks} failed)"
        )


def _compiled(cell: Cell | CompiledCell | Problem) -> CompiledCell:
    if isinstance(cell, CompiledCell):
        return cell
    if isinstance(cell, Cell):
        return compile_cell(cell)
    if isinstance(cell, Problem):
        raise UsageError(
            f"simulate: got the bare Problem {cell.name!r}; pass the CompiledCell that "
            "workcell.compile_cell returned (it carries the trajectories)"
        )
    raise UsageError(f"simulate: cell must be a Cell or a CompiledCell, got {type(cell).__name__}")


def _check_faults(plan: FaultPlan, cc: CompiledCell) -> None:
    p = cc.problem
    arms = p.arm_names
    parts = set(cc.cell.taskset.expected_arrivals()) | {x.id for x in cc.cell.taskset.parts}
    sdl = set(cc.cell.zone_map.zone_names())  # the arm-pair zones are never activated
    for i, f in enumerate(plan):
        where = f"faults[{i}] ({f.kind})"
        if isinstance(f, ArmFailure | Crash | LostSync) and f.arm not in arms:
            raise ValidationError(f"{where}.arm: unknown arm {f.arm!r} (arms: {', '.join(arms)})")
        if isinstance(f, LostSync):
            arm = cc.cell.arm(f.arm)
            if f.axis >= arm.dof:
                raise ValidationError(
                    f"{where}.axis: arm {f.arm!r} has {arm.dof} axes, no axis {f.axis}"
                )
            if not isinstance(arm.drives[f.axis], StepperDrive):
                raise ValidationError(
                    f"{where}.axis: axis {f.axis} of arm {f.arm!r} is a servo joint; only "
                    "stepper axes lose synchronism (S1.6)"
                )
        if isinstance(f, LatePart) and f.part not in parts:
            raise ValidationError(
                f"{where}.part: unknown part {f.part!r} (parts: {', '.join(sorted(parts))})"
            )
        if isinstance(f, ActivateZones):
            for z in f.zones:
                if z not in sdl:
                    raise ValidationError(
                        f"{where}.zones: unknown zone {z!r} (zones of the cell's zone map: "
                        f"{', '.join(sorted(sdl))})"
                    )
    if sum(isinstance(f, MessageLoss) for f in plan) > 1:
        raise ValidationError("faults: at most one message_loss record")


def simulate(
    cell: Cell | CompiledCell,
    schedule: Schedule,
    *,
    seed: int = 0,
    faults: FaultPlan | Sequence[Fault] | Sequence[Mapping[str, Any]] | None = None,
    medium: MediumSpec = "ideal",
    coordination: str = "centralized",
    options: SimOptions | None = None,
) -> SimResult:
    """Execute ``schedule`` in the simulated cell (S2.3-S2.7, S2.12).

    Parameters
    ----------
    cell : Cell or CompiledCell
        A Cell is compiled first (:func:`workcell.compile_cell`).
    schedule : scheduler.Schedule
        A schedule of the cell's problem (checked with :func:`scheduler.validate`).
    seed : int
        Seeds every random draw (message loss, drawn insertions); the same
        seed gives the same trace bit for bit.
    faults : FaultPlan, list of fault records or of dicts, optional
    medium : str or callable
        A medium name (``"ideal"``, ``"fixed"`` and the names of
        :mod:`workcell.sim.comms`) or ``factory(kernel, stations) -> Medium``.
        Station 0 is the coordinator, station ``i`` the ``i``-th arm.
    coordination : {"centralized"}
        The coordination policy (:data:`~workcell.sim.harness.options.COORDINATION_POLICIES`):
        ``"centralized"`` is the S2.7 coordinator.
    options : SimOptions, optional
        Re-solving, sampling period, monitor, insertion and force settings,
        ablations (:class:`~workcell.sim.harness.options.SimOptions`); default
        ``SimOptions()``.

    Returns
    -------
    SimResult

    Raises
    ------
    UsageError
        Bad arguments (named), or too many arms for centralized control at
        ``options.tick`` (S2.2).
    ValidationError
        Bad fault records (index and field named).
    ScheduleError
        A schedule that violates the problem.
    SafetyViolation
        The monitor saw a collision or a broken zone invariant.
    InternalError
        With ``options.strict``: the run stalled (a bug of the simulator).
    """
    wall0 = time.perf_counter()
    if options is None:
        options = SimOptions()
    elif not isinstance(options, SimOptions):
        raise UsageError(f"simulate: options must be a SimOptions, got {type(options).__name__}")
    if coordination not in COORDINATION_POLICIES:
        raise UsageError(
            f"simulate: unknown coordination policy {coordination!r} (known: "
            f"{', '.join(COORDINATION_POLICIES)})"
        )
    cc = _compiled(cell)
    p = cc.problem
    if not isinstance(schedule, Schedule):
        raise UsageError(
            f"simulate: schedule must be a scheduler.Schedule, got {type(schedule).__name__}"
        )
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise UsageError(f"simulate: seed must be an integer >= 0, got {seed!r}")
    resolve = options.resolve
    monitor = options.monitor
    monitor_period = options.monitor_period
    tick = options.tick
    strict = options.strict
    resolve_evaluations = options.resolve_evaluations
    if resolve_evaluations is None:
        resolve_evaluations = max(5, 2000 // max(1, p.n_tasks))
    if tick is not None:
        check_control_bound(p.n_arms, float(tick), options.control_time)
    if len(schedule.mode) != p.n_tasks:
        raise UsageError(
            f"simulate: the schedule covers {len(schedule.mode)} tasks, cell {p.name!r} has "
            f"{p.n_tasks}"
        )
    if options.zone_protocol:
        validate(p, schedule)
    fplan = as_plan(faults)
    _check_faults(fplan, cc)
    seed = int(seed)
    thresholds = free_thresholds(options.force_threshold, p.arm_names)
    searches = (
        insert_searches(
            cc, seed, sigma=options.insertion_sigma, tolerance=options.insertion_tolerance
        )
        if options.insertion == "drawn"
        else {}
    )

    kernel = EventLoop()
    trace = Trace()
    A = p.n_arms
    med = _medium(medium, kernel, A + 1)
    loss = next((f for f in fplan if isinstance(f, MessageLoss)), None)
    rng = np.random.default_rng(seed)
    names = ["coordinator", *p.arm_names]
    net = Network(kernel, med, trace, names, loss, rng)
    period = float(tick) if tick is not None else 1e-3
    ticker = Ticker(kernel, period) if tick is not None else None
    arms: list[ArmController] = []
    for a, (arm, q0) in enumerate(zip(cc.cell.arms, cc.cell.start, strict=True)):
        ctl = ArmController(
            kernel, a, arm, q0, net.send, trace, period, ticker, thresholds[arm.name]
        )
        ctl.searches = searches
        ctl.task_names = p.task_names
        ctl.zone_names = p.zone_names
        ctl.tool_names = p.tool_names
        arms.append(ctl)

        def rx(frame: Any, ctl: ArmController = ctl) -> None:
            ctl.receive(frame.kind, frame.payload[0])

        net.receivers[a + 1] = rx
    if ticker is not None:
        ticker.arms = arms
    coord = Coordinator(
        cc,
        schedule,
        kernel,
        net,
        trace,
        arms,
        seed=seed,
        resolve_budget=options.resolve_budget,
        resolve_evaluations=resolve_evaluations,
        zone_checks=options.zone_protocol,
        geometry=options.geometry_guard,
        resolving=resolve,
    )
    arm_index = {n: i for i, n in enumerate(p.arm_names)}
    arrivals = cc.cell.taskset.expected_arrivals()
    for f in fplan:
        if isinstance(f, ArmFailure):
            kernel.schedule(f.at, coord.arm_failed, arm_index[f.arm], absolute=True)
        elif isinstance(f, Crash):
            kernel.schedule(
                f.at, _crash, coord, arm_index[f.arm], f.recovery, f.force, absolute=True
            )
        elif isinstance(f, LostSync):
            kernel.schedule(
                f.at, _lost_sync, coord, arm_index[f.arm], f.axis, f.steps, absolute=True
            )
        elif isinstance(f, EmergencyStop):
            kernel.schedule(f.at, coord.emergency_stop, f.duration, absolute=True)
        elif isinstance(f, ActivateZones):
            kernel.schedule(f.at, coord.activate, f.zones, absolute=True)
        elif isinstance(f, LatePart):
            expected = float(arrivals.get(f.part, 0.0))
            tasks = [
                t
                for t, task in enumerate(cc.cell.taskset.tasks)
                if f.part in cc.cell.taskset.gating_parts(task.id)
            ]
            if expected <= kernel.now:  # known before the first trajectories go out
                coord.part_late(tasks, expected + f.delay, f.part)
            else:
                kernel.schedule(
                    expected, coord.part_late, tasks, expected + f.delay, f.part, absolute=True
                )
    live: LiveMonitor | None = None
    if monitor is True or monitor == "live":
        live = LiveMonitor(cc, kernel, [c.log for c in arms], trace, monitor_period)
        live.start()
    coord.start()
    horizon = (
        10.0 * max(schedule.makespan, 1.0)
        + 1e4
        + sum(f.duration for f in fplan if isinstance(f, EmergencyStop))
        + sum(f.delay for f in fplan if isinstance(f, LatePart) and math.isfinite(f.delay))
    )
    kernel.run(until=None if False else horizon)
    if kernel.peek() < math.inf and kernel.peek() <= horizon:  # pragma: no cover
        raise InternalError("simulate: events left after the run")
    t_end = max((c.log.end_time() for c in arms), default=0.0)
    for c in arms:
        c.finish()
    result = _result(
        cc,
        schedule,
        coord,
        arms,
        trace,
        kernel,
        net,
        ticker,
        seed,
        monitor == "post",
        monitor_period,
        wall0,
        t_end,
        strict,
        live,
    )
    return result


def _crash(coord: Coordinator, a: int, recovery: float, force: float) -> None:
    arm = coord.arms[a]
    threshold = float(arm.sensor.thresholds[2])
    outcome = arm.sense_crash(force, recovery)
    detail = {
        "stop": f"crash: reflex-arc stop (S1.2): {force:g} N above the {threshold:g} N threshold",
        "below": f"crash of {force:g} N not above the {threshold:g} N threshold in force"
        + (" (pushing, S1.7)" if arm.pushing else "")
        + ": not sensed, no stop",
        "standing": "crash while standing: no effect",
    }[outcome]
    coord.trace.add(
        coord.kernel.now,
        "fault",
        arm=arm.name,
        delay=recovery if outcome == "stop" else 0.0,
        detail=detail,
    )


def _lost_sync(coord: Coordinator, a: int, axis: int, steps: int) -> None:
    arm = coord.arms[a]
    err = arm.lose_sync(axis, steps)
    coord.trace.add(
        coord.kernel.now,
        "fault",
        arm=arm.name,
        detail=f"axis {axis} lost {steps} steps ({err * 1e3:.4g} mm): tracked position wrong "
        "until homed (S1.6)",
    )


def _result(
    cc: CompiledCell,
    schedule: Schedule,
    coord: Coordinator,
    arms: list[ArmController],
    trace: Trace,
    kernel: EventLoop,
    net: Network,
    ticker: Ticker | None,
    seed: int,
    monitor: bool,
    monitor_period: float,
    wall0: float,
    t_end: float,
    strict: bool = False,
    live: LiveMonitor | None = None,
) -> SimResult:
    p = cc.problem
    T = p.n_tasks
    logs: dict[int, tuple[int, TaskRecord]] = {}
    for c in arms:
        for t, log in c.log.tasks.items():
            if coord.status[t] == "done" and log.finished:
                logs[t] = (c.index, log)
    trace.sort()
    tasks: list[dict[str, Any]] = []
    plan = coord.plan
    for t in range(T):
        m_plan = int(schedule.mode[t])
        row: dict[str, Any] = {
            "task": p.task_names[t],
            "planned_start": float(schedule.start[t]),
            "planned_end": float(schedule.end[t]),
        }
        if t in logs:
            a, log = logs[t]
            row.update(
                arm=p.arm_names[a],
                mode=int(log.mode),
                start=float(log.start),
                end=float(log.end),
                status="done",
                cause="",
                cause_kind="",
            )
        else:
            m = int(plan.mode[t])
            a = int(p.mode_arm[m])
            row.update(arm=p.arm_names[a], mode=m, start=math.nan, end=math.nan, status="failed")
            row["cause_kind"], row["cause"] = _cause(coord, t, strict)
            trace.add(
                kernel.now,
                "task_failed",
                arm=p.arm_names[a],
                task=p.task_names[t],
                detail=row["cause"],
            )
        del m_plan
        tasks.append(row)
    # executed schedule
    executed: Schedule | None = None
    if len(logs) == T:
        modes = np.array([int(logs[t][1].mode) for t in range(T)], dtype=np.int64)
        starts = np.array([float(logs[t][1].start) for t in range(T)])
        ends = np.array([float(logs[t][1].end) for t in range(T)])
        waits = []
        blocking = np.zeros(T)
        for t in range(T):
            w = np.zeros(len(p.shapes[int(modes[t])].borders))
            for j, x in logs[t][1].waits:
                w[j] += x
            waits.append(w)
            blocking[t] = max(0.0, ends[t] - starts[t] - p.shapes[int(modes[t])].length(w))
        executed = Schedule(modes, starts, ends, tuple(waits), blocking)
    # reservations executed
    res: list[dict[str, Any]] = []
    open_: dict[tuple[str, str, str, str], float] = {}
    for e in trace:
        if e.kind == "zone_enter":
            kind = {"zone": "zone", "move": "move", "tool": "tool"}[e.detail]
            open_[(kind, e.zone, e.task, e.arm)] = e.time
        elif e.kind == "zone_leave":
            kind = {"zone": "zone", "move": "move", "tool": "tool"}[e.detail]
            s = open_.pop((kind, e.zone, e.task, e.arm), None)
            if s is not None:
                res.append(
                    {
                        "kind": kind,
                        "resource": e.zone,
                        "task": e.task,
                        "arm": e.arm,
                        "start": s,
                        "end": e.time,
                    }
                )
    done_ends = [float(logs[t][1].end) for t in logs]
    executed_mk = max(done_ends) if done_ends else math.nan
    # busy: time on a leg (travelling, working, or stopped on the way),
    # counted within [0, executed makespan] only, so a share in [0, 1]
    span = executed_mk if done_ends else 0.0
    busy = {n: 0.0 for n in p.arm_names}
    for c in arms:
        busy[c.name] = sum(
            max(0.0, min(r.end, span) - max(r.start, 0.0))
            for r in c.log.records
            if r.leg is not None
        )
    metrics = Metrics(
        planned_makespan=float(schedule.makespan),
        executed_makespan=executed_mk,
        utilisation={n: (v / span if span > 0 else 0.0) for n, v in busy.items()},
        zone_wait=_merge([c.zone_wait for c in arms]),
        border_wait=float(sum(c.border_wait for c in arms)),
        sleeps=sum(1 for e in trace if e.kind == "sleep"),
        wakes=sum(1 for e in trace if e.kind == "wake"),
        detours=coord.detours,
        resolves=coord.resolves,
        resolve_latency=np.array(coord.resolve_latency, dtype=float),
        resolve_budget=coord.resolve_budget,
        message_delay=np.array(net.delays, dtype=float),
        messages=net.sent,
        retransmissions=net.retransmissions,
        stale_frames=net.stale,
        failed_tasks=sum(1 for r in tasks if r["status"] == "failed"),
        done_tasks=sum(1 for r in tasks if r["status"] == "done"),
        ticks=ticker.ticks if ticker is not None else 0,
        events=kernel.events_run,
    )
    if monitor:
        SafetyMonitor(cc, monitor_period).check([c.log for c in arms], max(t_end, 0.0), trace)
    metrics.wall_seconds = time.perf_counter() - wall0
    return SimResult(
        p,
        schedule,
        Plan(p, plan),
        executed,
        seed,
        trace,
        metrics,
        live,
        tuple(tasks),
        tuple(res),
        tuple(c.log for c in arms),
    )


def _merge(dicts: list[dict[str, float]]) -> dict[str, float]:
    out: dict[str, float] = {}
    for d in dicts:
        for k, v in d.items():
            out[k] = out.get(k, 0.0) + v
    return dict(sorted(out.items()))


def _cycle(graph: dict[int, list[int]]) -> list[int]:
    """A cycle of the wait-for ``graph`` (arm -> arms it waits for), [] if none."""
    for root in sorted(graph):
        path: list[int] = []
        on: dict[int, int] = {}
        x: int | None = root
        while x is not None and x not in on:
            on[x] = len(path)
            path.append(x)
            nxt = graph.get(x, [])
            x = min(nxt) if nxt else None
        if x is not None:
            return [*path[on[x] :], x]
    return []


def _cause(coord: Coordinator, t: int, strict: bool = False) -> tuple[str, str]:
    """(category, text) of the failed task ``t`` (categories:
    :data:`~workcell.sim.coordination.centralized.CAUSE_KINDS`)."""
    p = coord.p
    if coord.cause[t]:
        return coord.cause_kind[t] or "predecessor", coord.cause[t]
    # the predecessors not done (a done task's predecessors are all done)
    seen: set[int] = set()
    stack = [t]
    while stack:
        x = stack.pop()
        for q in p.task_preds[x]:
            if q in seen or coord.status[q] == "done":
                continue
            seen.add(q)
            if coord.cause[q]:
                return "predecessor", f"predecessor {p.task_names[q]!r} failed: {coord.cause[q]}"
            stack.append(q)

    def no_arm(x: int) -> bool:
        return all(int(p.mode_arm[m]) in coord.failed_arms for m in p.task_modes[x])

    if no_arm(t):
        return "arm_failed", "no working arm can do it (every capable arm failed)"
    for q in sorted(seen):
        if no_arm(q):
            return (
                "predecessor",
                f"predecessor {p.task_names[q]!r} cannot run: every arm able to do it failed",
            )
    for q in sorted(seen):
        b = int(p.mode_arm[int(coord.plan.mode[q])])
        if b in coord.failed_arms:
            return (
                "predecessor",
                f"predecessor {p.task_names[q]!r} cannot run: its arm {p.arm_names[b]!r} failed"
                + ("" if coord.resolving else " (re-solving off)"),
            )
    a = int(p.mode_arm[int(coord.plan.mode[t])])
    if a in coord.failed_arms:
        if not coord.resolving:
            return (
                "arm_out",
                f"arm {p.arm_names[a]!r} failed (re-solving off: its tasks are not reassigned)",
            )
        return "arm_failed", f"arm {p.arm_names[a]!r} failed and no working arm could take the task"
    if float(coord.plan.start[t]) >= FAR:
        return "predecessor", "planned after a task that cannot run"
    held = {
        c.index: list(coord.geo_held.get(c.index, [])) for c in coord.arms if "geometry" in c.stops
    }
    if a in held or _cycle(held):
        cycle = _cycle(held)
        names = p.arm_names
        if cycle:
            waits = " -> ".join(repr(names[x]) for x in cycle)
        else:
            waits = "; ".join(
                f"{names[x]!r} waits for {', '.join(repr(names[y]) for y in ys)}"
                for x, ys in sorted(held.items())
            )
        return "deadlock", f"unresolved geometric deadlock (S2.6), wait-for: {waits}"
    # nothing explains it: an arm had work, no stop in force and no event
    # pending -- a stall of the simulator itself
    ctl = coord.arms[a]
    doing = f"task {p.task_names[ctl.leg.task]!r}" if ctl.leg is not None else "no trajectory"
    text = (
        f"stall: arm {p.arm_names[a]!r} stood still with work left ({doing}, task "
        f"{p.task_names[t]!r} {coord.status[t]}), no stop in force and no event pending"
    )
    if strict:
        raise InternalError(f"simulate: {text} (please report)")
    return "stall", text
