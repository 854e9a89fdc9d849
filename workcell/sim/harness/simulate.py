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

import functools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from multiarm.errors import InternalError, UsageError
from scheduler import Problem, Schedule, validate
from scheduler.kernel import warm_up
from workcell.cell import Cell
from workcell.compile import CompiledCell, compile_cell
from workcell.sim.comms.link import Link
from workcell.sim.comms.media import make_medium
from workcell.sim.comms.medium import Medium
from workcell.sim.control.controller import ArmController, Ticker
from workcell.sim.control.force import free_thresholds, insert_searches
from workcell.sim.coordination.policy import POLICIES, make_policy
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
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
    check_fault_names,
)
from workcell.sim.harness.monitor_live import LiveMonitor
from workcell.sim.harness.options import CONTROL_TIME, COORDINATION_POLICIES, SimOptions
from workcell.sim.harness.result import SimResult, build_result
from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.messages import LateNotice

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
    coordination : {"centralized", "distributed"}
        The coordination policy (:data:`~workcell.sim.harness.options.COORDINATION_POLICIES`):
        ``"centralized"`` is the S2.7 coordinator, ``"distributed"`` one peer
        per arm and no coordinator
        (:mod:`workcell.sim.coordination.distributed`).
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
    check_fault_names(fplan, cc.cell)  # the checks of workcell.faultcheck.check_faults
    POLICIES[coordination]
    seed = int(seed)
    thresholds = free_thresholds(options.force_threshold, p.arm_names)
    searches = (
        insert_searches(
            cc, seed, sigma=options.insertion_sigma, tolerance=options.insertion_tolerance
        )
        if options.insertion == "drawn"
        else {}
    )

    if resolve and coordination == "centralized" and len(fplan):
        # a fault may make the coordinator re-solve: the scheduler's compiled
        # code loaded now, so the first re-solve's latency is its own
        warm_up()
    kernel = EventLoop()
    trace = Trace()
    A = p.n_arms
    med = _medium(medium, kernel, A + 1)
    loss = next((f for f in fplan if isinstance(f, MessageLoss)), None)
    rng = np.random.default_rng(seed)
    names = ["coordinator", *p.arm_names]
    net = Link(kernel, med, trace, names, loss, rng)
    # every frame between an arm and the coordinator goes on its arm's
    # stream of the channel, in order (a policy whose peers share the arms'
    # stations takes a controller's messages to station 0 at that station)
    channel = ControlChannel(A, net)
    period = float(tick) if tick is not None else 1e-3
    ticker = Ticker(kernel, period) if tick is not None else None
    arms: list[ArmController] = []
    for a, (arm, q0) in enumerate(zip(cc.cell.arms, cc.cell.start, strict=True)):
        ctl = ArmController(
            kernel,
            a,
            arm,
            q0,
            channel.send,
            channel,
            trace,
            period,
            ticker,
            thresholds[arm.name],
            searches=searches,
            names=(p.task_names, p.zone_names, p.tool_names),
            geometry=options.geometry_guard,
        )
        arms.append(ctl)

        net.receivers[a + 1] = functools.partial(channel.at_station, a)
    coord = make_policy(
        coordination,
        cc,
        schedule,
        kernel,
        net,
        trace,
        channel,
        seed=seed,
        resolve_budget=options.resolve_budget,
        resolve_evaluations=resolve_evaluations,
        zone_checks=options.zone_protocol,
        geometry=options.geometry_guard,
        resolving=resolve,
        detours=options.detours,
        detour_checks=options.detour_checks,
        guard_answer=options.guard_answer,
    )
    arm_index = {n: i for i, n in enumerate(p.arm_names)}
    arrivals = cc.cell.taskset.expected_arrivals()
    late: dict[float, list[LateNotice]] = {}
    for f in fplan:
        if isinstance(f, LatePart):
            expected = float(arrivals.get(f.part, 0.0))
            tasks = tuple(
                t
                for t, task in enumerate(cc.cell.taskset.tasks)
                if f.part in cc.cell.taskset.gating_parts(task.id)
            )
            late.setdefault(expected, []).append(LateNotice(tasks, expected + f.delay, f.part))
    told: set[float] = set()
    for f in fplan:
        if isinstance(f, ArmFailure):
            kernel.schedule(f.at, coord.arm_failed, arm_index[f.arm], absolute=True)
        elif isinstance(f, Crash):
            kernel.schedule(
                f.at, _crash, arms[arm_index[f.arm]], trace, f.recovery, f.force, absolute=True
            )
        elif isinstance(f, LostSync):
            kernel.schedule(
                f.at, _lost_sync, arms[arm_index[f.arm]], trace, f.axis, f.steps, absolute=True
            )
        elif isinstance(f, EmergencyStop):
            kernel.schedule(f.at, coord.emergency_stop, f.duration, absolute=True)
        elif isinstance(f, ActivateZones):
            kernel.schedule(f.at, coord.activate, f.zones, absolute=True)
        elif isinstance(f, LatePart):
            # the parts late at one expected time are told together (at the
            # place of the first of them among the faults)
            expected = float(arrivals.get(f.part, 0.0))
            if expected in told:
                continue
            told.add(expected)
            if expected <= kernel.now:  # known before the first trajectories go out
                coord.parts_late(late[expected])
            else:
                kernel.schedule(expected, coord.parts_late, late[expected], absolute=True)
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
    result = build_result(
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


def _crash(arm: ArmController, trace: Trace, recovery: float, force: float) -> None:
    threshold = float(arm.sensor.thresholds[2])
    outcome = arm.sense_crash(force, recovery)
    detail = {
        "stop": f"crash: reflex-arc stop (S1.2): {force:g} N above the {threshold:g} N threshold",
        "below": f"crash of {force:g} N not above the {threshold:g} N threshold in force"
        + (" (pushing, S1.7)" if arm.pushing else "")
        + ": not sensed, no stop",
        "standing": "crash while standing: no effect",
    }[outcome]
    trace.add(
        arm.kernel.now,
        "fault",
        arm=arm.name,
        delay=recovery if outcome == "stop" else 0.0,
        detail=detail,
    )


def _lost_sync(arm: ArmController, trace: Trace, axis: int, steps: int) -> None:
    err = arm.lose_sync(axis, steps)
    trace.add(
        arm.kernel.now,
        "fault",
        arm=arm.name,
        detail=f"axis {axis} lost {steps} steps ({err * 1e3:.4g} mm): tracked position wrong "
        "until homed (S1.6)",
    )
