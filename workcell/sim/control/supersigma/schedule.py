"""A cell's schedule run as a SUPERSIGMA task program (S1.1, S1.3, S1.9).

The central control unit can run the scheduler's plan instead of a
hand-written program: :func:`run_schedule` builds one task *box* per arm of a
:class:`~workcell.sim.control.supersigma.programs.SigmaCell` and runs them on the CCU
(S1.9: boxes synchronised by flags). Each box takes its arm's tasks in start
order. A task

* waits for its planned start (``WAIT TIME``: parts arrive, the plan holds)
  and for its predecessors' "done" flags;
* then runs through its planned duration, moving its arm's x axis (moves of
  at most 30,000 steps back and forth inside the rails, each sized so that
  the controller's own profile, S1.5, ends it on time; the CCU waits on the
  status lines between moves, S1.3);
* at the planned instant it *enters* a resource window (an exclusive zone,
  movement in a shared zone, a tool), stops there until the previous user of
  that resource has set its "left" flag -- the arm held at the zone border
  (S2.6) -- and at the planned instant it *leaves* one, sets its own.

Every wait is for an event planned no later than the waiting point, and each
box meets its events in planned order (leaving before entering at the same
instant), so the boxes never wait on each other in a cycle. The executed
makespan is the planned one plus the bus and CCU latencies (a command holds
the bus 100 us; the CCU polls every millisecond) and the waits they cause at
zone borders; the run also measures the bus load and the CCU's idle share of
a real schedule, next to the S1.10 programs.

Examples
--------
>>> from scheduler import solve
>>> from scheduler.generate import random_problem
>>> problem = random_problem(2, 8, 2, 1, seed=0)
>>> plan = solve(problem, solver="greedy", time_limit=2.0, seed=0).schedule
>>> run = run_schedule(problem, plan)
>>> run.report.lost, bool(run.makespan >= plan.makespan - 1e-9)
(0, True)
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from multiarm.errors import InternalError, ValidationError
from multiarm.types import FloatArray
from workcell.sim.comms.microbus import StepProfile, move_time
from workcell.sim.control.supersigma.ccu import CCU, Box, RunReport
from workcell.sim.control.supersigma.programs import SigmaCell
from workcell.sim.events.loop import ProcessGenerator

if TYPE_CHECKING:
    from scheduler import Problem, Schedule

__all__ = ["Handover", "ScheduleRun", "run_schedule", "steps_for"]

MAX_STEPS = 30_000
"""Longest single move a task program sends (inside the default rails)."""


def steps_for(duration: float, profile: StepProfile | None = None) -> int:
    """The step count whose move lasts ``duration`` seconds (at most), for
    moves of up to :data:`MAX_STEPS`.

    Parameters
    ----------
    duration : float
        Seconds, >= 0.
    profile : StepProfile, optional
        Speed profile.

    Returns
    -------
    int
        Steps (0 for a duration shorter than one step at the low speed).

    Examples
    --------
    >>> n = steps_for(0.5)
    >>> move_time(n) <= 0.5 < move_time(n + 1)
    True
    """
    lo, hi = 0, MAX_STEPS
    if move_time(hi, profile) <= duration:
        return hi
    while hi - lo > 1:  # move_time grows with the step count
        mid = (lo + hi) // 2
        if move_time(mid, profile) <= duration:
            lo = mid
        else:
            hi = mid
    return lo


@dataclass(frozen=True, slots=True)
class Handover:
    """A resource passed from one task to the next (executed instants).

    Parameters
    ----------
    resource : str
        Zone or tool.
    left_by, entered_by : str
        The previous and the next task.
    left, entered : float
        When the previous task left and when the next one went in, seconds.
    """

    resource: str
    left_by: str
    entered_by: str
    left: float
    entered: float


@dataclass(frozen=True, slots=True)
class ScheduleRun:
    """What a schedule did under the CCU.

    Parameters
    ----------
    report : RunReport
        Bus counts, seconds, CCU idle share.
    start, end : (T,) float ndarray
        Executed start and end of every task, seconds.
    planned_makespan : float
        The schedule's makespan, seconds.
    handovers : tuple of Handover
        Every resource passed from one task to another, with the executed
        instants.
    """

    report: RunReport
    start: FloatArray
    end: FloatArray
    planned_makespan: float
    handovers: tuple[Handover, ...] = ()

    @property
    def makespan(self) -> float:
        """Executed makespan, seconds."""
        return float(self.end.max()) if self.end.size else 0.0


def _handovers(
    problem: Problem, schedule: Schedule
) -> tuple[
    list[list[tuple[float, int]]], list[list[tuple[float, int]]], list[tuple[str, int, int]]
]:
    """Per task, the (offset, window) pairs where it enters a resource
    window whose previous user is another task, and where it leaves a window
    that another task enters next; offsets in seconds from its planned
    start; and per hand-over (resource, previous task, next task)."""
    index = {name: i for i, name in enumerate(problem.task_names)}
    by_resource: dict[tuple[str, str], list[tuple[float, float, int]]] = {}
    for r in schedule.reservations(problem):
        if r.task is None:
            continue
        kind = "zone" if r.kind in ("zone", "move") else r.kind
        by_resource.setdefault((kind, r.resource), []).append((r.start, r.end, index[r.task]))
    enters: list[list[tuple[float, int]]] = [[] for _ in range(problem.n_tasks)]
    leaves: list[list[tuple[float, int]]] = [[] for _ in range(problem.n_tasks)]
    meta: list[tuple[str, int, int]] = []
    for (_, resource), windows in by_resource.items():
        windows.sort()
        for (_, prev_end, prev), (cur_start, _, cur) in itertools.pairwise(windows):
            if prev == cur:
                continue
            wid = len(meta)
            meta.append((resource, prev, cur))
            leaves[prev].append((prev_end - float(schedule.start[prev]), wid))
            enters[cur].append((cur_start - float(schedule.start[cur]), wid))
    return enters, leaves, meta


def run_schedule(
    problem: Problem,
    schedule: Schedule,
    *,
    statement_time: float = 1e-3,
    profile: StepProfile | None = None,
) -> ScheduleRun:
    """Run ``schedule`` as a task program on a SUPERSIGMA CCU (see the module
    docstring).

    Parameters
    ----------
    problem : scheduler.Problem
        The problem (1..25 arms).
    schedule : scheduler.Schedule
        A schedule of it.
    statement_time : float, optional
        CCU processor time per statement, seconds.
    profile : StepProfile, optional
        Stepper profile of every axis.

    Returns
    -------
    ScheduleRun
        Bus counts and executed task times.

    Raises
    ------
    ValidationError
        For more than 25 arms or a schedule of another size.
    """
    if schedule.n_tasks != problem.n_tasks:
        raise ValidationError(
            f"run_schedule: schedule has {schedule.n_tasks} tasks, problem "
            f"{problem.name!r} has {problem.n_tasks}"
        )
    if not 1 <= problem.n_arms <= 25:
        raise ValidationError(
            f"run_schedule: {problem.n_arms} arms; a MICROBUS serves at most 25 "
            "(6 controllers each on 256 addresses)"
        )
    cell = SigmaCell(problem.n_arms, statement_time=statement_time, profile=profile)
    prof = cell.profile
    enters, leaves, meta = _handovers(problem, schedule)
    left_at = np.full(len(meta), math.nan)
    entered_at = np.full(len(meta), math.nan)
    names = problem.task_names
    start = np.full(problem.n_tasks, math.nan)
    end = np.full(problem.n_tasks, math.nan)
    longest = move_time(MAX_STEPS, prof)

    def arm_box(arm: int, tasks: list[int]) -> Box:
        motor = cell.motors[arm][0]

        def run_for(ccu: CCU, seconds: float) -> ProcessGenerator:
            left = seconds
            while left > 0:
                n = MAX_STEPS if left >= longest else steps_for(left, prof)
                if n == 0:
                    break
                direction = -1 if motor.position > 0 else 1
                yield from ccu.move(motor.address, direction * n)
                yield from ccu.wait(motor.address)
                left -= move_time(n, prof)

        def box(ccu: CCU) -> ProcessGenerator:
            for t in tasks:
                yield from ccu.wait_until(float(schedule.start[t]))
                for p in problem.task_preds[t]:
                    yield from ccu.wait_flag(f"done:{names[p]}", consume=False)
                start[t] = ccu.kernel.now
                duration = float(schedule.end[t] - schedule.start[t])
                # (offset, 0 = leave first, 1 = enter, window)
                events = sorted(
                    [(min(max(o, 0.0), duration), 0, w) for o, w in leaves[t]]
                    + [(min(max(o, 0.0), duration), 1, w) for o, w in enters[t]]
                )
                at = 0.0
                for offset, enter, w in events:
                    yield from run_for(ccu, offset - at)
                    at = max(at, offset)
                    if enter:  # stop at the border until the previous user has left
                        yield from ccu.wait_flag(f"left:{w}", consume=False)
                        entered_at[w] = ccu.kernel.now
                    else:
                        left_at[w] = ccu.kernel.now
                        yield from ccu.set_flag(f"left:{w}")
                yield from run_for(ccu, duration - at)
                end[t] = ccu.kernel.now
                yield from ccu.set_flag(f"done:{names[t]}")

        return box

    boxes = {
        problem.arm_names[a]: arm_box(a, seq)
        for a, seq in enumerate(schedule.sequences(problem))
        if seq
    }
    horizon = 10.0 * float(schedule.makespan) + 60.0
    report = cell.ccu.run(boxes, until=horizon)
    if np.isnan(end).any():  # pragma: no cover - the waits cannot form a cycle
        stuck = [names[t] for t in np.flatnonzero(np.isnan(end))]
        raise InternalError(f"run_schedule: tasks {stuck} not done by {horizon:.1f} s")
    handovers = tuple(
        Handover(resource, names[a], names[b], float(left_at[i]), float(entered_at[i]))
        for i, (resource, a, b) in enumerate(meta)
    )
    return ScheduleRun(report, start, end, float(schedule.makespan), handovers)
