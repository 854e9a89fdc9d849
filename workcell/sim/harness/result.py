"""What :func:`~workcell.sim.harness.simulate.simulate` returns: :class:`SimResult`,
built from the coordinator's task states and the arms' published records."""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from multiarm.errors import InternalError
from multiarm.types import FloatArray
from scheduler import Plan, Problem, Schedule
from workcell.compile import CompiledCell
from workcell.sim.comms.link import Link
from workcell.sim.control.controller import ArmController, Ticker
from workcell.sim.coordination.policy import CoordinationPolicy
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Metrics, Trace
from workcell.sim.harness.monitor import SafetyMonitor
from workcell.sim.harness.monitor_live import LiveMonitor
from workcell.sim.protocol.records import MotionLog, TaskRecord

__all__ = ["SimResult", "build_result"]


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
    safety : LiveMonitor or None
        The live safety monitor of the run (its counters: samples, wakes, FCL
        checks), None when ``SimOptions(monitor=False)``. ``monitor`` is the
        option's word; the result's was ``monitor`` too and still reads, with
        a DeprecationWarning, for one release.
    arm_logs : tuple of MotionLog
        Each arm's published motion and task records
        (:class:`~workcell.sim.protocol.records.MotionLog`), in arm order.
    compiled : CompiledCell or None
        The compiled cell that ran (what :meth:`to_html` draws).
    """

    problem: Problem
    schedule: Schedule
    plan: Plan
    executed: Schedule | None
    seed: int
    trace: Trace
    metrics: Metrics
    safety: LiveMonitor | None = None
    _tasks: tuple[dict[str, Any], ...] = ()
    _reservations: tuple[dict[str, Any], ...] = ()
    arm_logs: tuple[MotionLog, ...] = ()
    compiled: CompiledCell | None = None

    @property
    def monitor(self) -> LiveMonitor | None:
        """Deprecated name of :attr:`safety` (``monitor`` is the option's word)."""
        warnings.warn(
            "SimResult.monitor is deprecated: read SimResult.safety "
            "(SimOptions.monitor is the switch, SimResult.safety the live monitor's counters)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.safety

    def to_html(self, path: str | PathLike[str], **options: Any) -> Path:
        """Write the 3D replay of this run as one self-contained HTML file.

        The cell in 3D with the arms posed over time, zones coloured by state,
        a time slider with play and pause, a Gantt strip in sync and the
        faults marked; it works offline (:mod:`workcell.replay`).

        Parameters
        ----------
        path : str or path-like
            The HTML file to write.
        **options
            Passed to :func:`workcell.replay.write_html` (``rate``,
            ``max_frames``, ``geometry``, ``title``).

        Returns
        -------
        Path
            The file written.
        """
        from workcell.replay import write_html

        return write_html(self, self.compiled, path, **options)

    def joints(self, times: Sequence[float] | FloatArray) -> dict[str, FloatArray]:
        """Each arm's actual joints at ``times`` (seconds) as run: arm name ->
        (N, dof) float (for rendering the cell at chosen instants)."""
        t = np.asarray(times, dtype=float).reshape(-1)
        return {c.name: SafetyMonitor.joints(c, t) for c in self.arm_logs}

    def tasks_frame(self) -> Any:
        """One row per task: task, arm, mode, planned_start, planned_end,
        start, end, status ("done" | "failed"), cause (text), cause_kind
        (its category, one of :data:`~workcell.sim.coordination.centralized.CAUSE_KINDS`;
        "" for a task done) and plan: the plan its planned times come from
        (0: the schedule given, ``k``: the plan of the ``k``-th re-solve; the
        last one that planned the task to run). A failed task that had
        started (interrupted by its arm's failure, or an insertion that
        failed) keeps its start. A task that never started has no start and
        no end: they are missing (NaN, pandas' missing value, in the frame;
        an empty cell in ``tasks.csv``; see :meth:`save`)."""
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
            "plan",
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
        """Write trace.json, metrics.json and tasks.csv into ``directory`` (created).

        No file holds NaN: a value that does not exist (the start and end of
        a task that never started, the executed makespan when no task was
        done, a latency percentile without re-solves) is an empty cell in
        ``tasks.csv`` and ``null`` in ``metrics.json``.
        """
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        self.trace.to_json(d / "trace.json")
        self.metrics.to_json(d / "metrics.json")
        self.tasks_frame().to_csv(d / "tasks.csv", index=False, na_rep="")
        return d

    def __repr__(self) -> str:
        m = self.metrics
        ran = m.done_tasks > 0 and math.isfinite(m.executed_makespan)
        executed = f"{m.executed_makespan:.6g} s" if ran else "nothing (no task done)"
        return (
            f"SimResult({self.problem.name!r}: planned {m.planned_makespan:.6g} s, executed "
            f"{executed}, {m.done_tasks} done, {m.failed_tasks} failed)"
        )


def build_result(
    cc: CompiledCell,
    schedule: Schedule,
    coord: CoordinationPolicy,
    arms: list[ArmController],
    trace: Trace,
    kernel: EventLoop,
    net: Link,
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
    started: dict[int, tuple[int, TaskRecord]] = {}
    for c in arms:
        for t, log in c.log.tasks.items():
            if coord.status[t] == "done" and log.finished:
                logs[t] = (c.index, log)
            elif t not in started or log.start > started[t][1].start:
                started[t] = (c.index, log)
    tasks: list[dict[str, Any]] = []
    for t in range(T):
        k = coord.plan_of[t]
        planned = coord.plans[k]
        row: dict[str, Any] = {
            "task": p.task_names[t],
            "planned_start": float(planned.start[t]),
            "planned_end": float(planned.end[t]),
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
            m = int(planned.mode[t])
            a = int(p.mode_arm[m])
            # a task interrupted (or that ran and failed) keeps its start
            begun = started.get(t)
            start = float(begun[1].start) if begun is not None else math.nan
            end = float(begun[1].end) if begun is not None and begun[1].finished else math.nan
            row.update(arm=p.arm_names[a], mode=m, start=start, end=end, status="failed")
            row["cause_kind"], row["cause"] = _cause(coord, t, strict)
            if coord.status[t] != "failed":
                # found only now, at the end of the run (the coordinator logged
                # the tasks it failed when it failed them)
                trace.add(
                    t_end,
                    "task_failed",
                    arm=p.arm_names[a],
                    task=p.task_names[t],
                    detail=row["cause"],
                )
        row["plan"] = k
        tasks.append(row)
    trace.sort()
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
    for e in trace.select(("zone_enter", "zone_leave")):
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
        sleeps=trace.count("sleep"),
        wakes=trace.count("wake"),
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
        Plan(p, coord.plan),
        executed,
        seed,
        trace,
        metrics,
        live,
        tuple(tasks),
        tuple(res),
        tuple(c.log for c in arms),
        cc,
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


def _cause(coord: CoordinationPolicy, t: int, strict: bool = False) -> tuple[str, str]:
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
    if t in coord.dropped:
        return "predecessor", "planned after a task that cannot run"
    held = {v.index: list(coord.geo_held.get(v.index, [])) for v in coord.book if v.held}
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
    ctl = coord.book[a]
    doing = f"task {p.task_names[ctl.leg.task]!r}" if ctl.leg is not None else "no trajectory"
    text = (
        f"stall: arm {p.arm_names[a]!r} stood still with work left ({doing}, task "
        f"{p.task_names[t]!r} {coord.status[t]}), no stop in force and no event pending"
    )
    if strict:
        raise InternalError(f"simulate: {text} (please report)")
    return "stall", text
