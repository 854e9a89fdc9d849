"""Online re-solving: a new plan from the cell's current state.

When reality departs from the plan (a part arrives late, an arm faults, a
detour takes longer), the coordinator calls :func:`reschedule` with a
:class:`CellState`: the current time, the tasks finished or running (a
frozen prefix: their arm, start, end and waits are kept as they are), the
parts that arrived (new release times), arms that failed (they get no new
task) and arms that are busy until some time. The result is a complete
schedule consistent with the frozen prefix, in which every other task starts
no earlier than now.

The search starts from the previous schedule (same order and modes where
still possible: a warm start), decodes it on top of the frozen prefix, and
improves it with the tree search's local search until the time limit — by
default a few milliseconds, what a real cell can afford.

Examples
--------
>>> from scheduler.fjsp import parse_fjsp
>>> from scheduler.solve import solve
>>> p = parse_fjsp("2 2 1\\n2 1 1 3 2 1 4 2 2\\n1 2 1 2 2 1\\n")
>>> plan = solve(p, "greedy").schedule
>>> first = int(plan.start.argmin())
>>> state = CellState(time=1.0, done={first: (int(plan.mode[first]), float(plan.start[first]),
...                                          float(plan.end[first]))}, failed_arms={"M2"})
>>> r = reschedule(p, state, plan, time_limit=0.05)
>>> set(r.schedule.arms(p)[[t for t in range(p.n_tasks) if t != first]].tolist())
{0}
"""

from __future__ import annotations

import math
import time
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from multiarm.errors import UsageError
from multiarm.types import FloatArray, IntArray
from scheduler.kernel import compile_problem
from scheduler.kernel.api import keyed_order
from scheduler.problem import Problem
from scheduler.result import Result, SearchStats, SolveStatus
from scheduler.schedule import Schedule, validate
from scheduler.search import Evaluator, Solution, local_search, rank_upward

__all__ = ["CellState", "reschedule"]

_POST_COST: weakref.WeakKeyDictionary[Any, float] = weakref.WeakKeyDictionary()
"""Per compiled instance: seconds the last calls spent building and validating
the new schedule (the part of the time limit kept back from the search)."""

TaskRef = int | str
ArmRef = int | str


@dataclass
class CellState:
    """What the cell looks like now.

    Attributes
    ----------
    time : float
        Now (seconds, the schedule's clock).
    done : mapping task -> (mode, start, end) or (mode, start, end, waits)
        Finished tasks and tasks running now (with the end expected); kept
        exactly. ``mode`` is the mode id (``problem.mode_of[arm, task]``).
    releases : mapping task -> float
        New release times of late parts (their expected arrival). They only
        postpone: a task keeps the problem's release if that is later (to
        use an early arrival, rebuild the problem with the new release).
    failed_arms : set of arms
        Arms that take no new task.
    arm_busy_until : mapping arm -> float
        Arms that cannot start a new task before a time (e.g. being
        repaired, or finishing an unplanned move).
    """

    time: float
    done: Mapping[TaskRef, tuple[int, float, float] | tuple[int, float, float, list[float]]] = (
        field(default_factory=dict)
    )
    releases: Mapping[TaskRef, float] = field(default_factory=dict)
    failed_arms: set[ArmRef] = field(default_factory=set)
    arm_busy_until: Mapping[ArmRef, float] = field(default_factory=dict)


class _TimedEvaluator(Evaluator):
    """An :class:`Evaluator` that adds up the wall time of its resumed
    decodes (a measurement for :attr:`SearchStats.phases`, never used to decide)."""

    decode_time = 0.0

    def evaluate_resume(
        self, order: np.ndarray, modes: np.ndarray | None = None
    ) -> Solution | None:
        t = time.perf_counter()
        try:
            return super().evaluate_resume(order, modes)
        finally:
            self.decode_time += time.perf_counter() - t


def _ref(names: tuple[str, ...], ref: int | str, what: str) -> int:
    """The id of a task or arm given by name or id."""
    if isinstance(ref, str):
        try:
            return names.index(ref)
        except ValueError:
            raise UsageError(f"unknown {what} {ref!r}") from None
    if not 0 <= int(ref) < len(names):
        raise UsageError(f"{what} id {ref} out of range")
    return int(ref)


def _task(p: Problem, ref: TaskRef) -> int:
    return _ref(p.task_names, ref, "task")


def _arm(p: Problem, ref: ArmRef) -> int:
    return _ref(p.arm_names, ref, "arm")


def reschedule(
    problem: Problem,
    state: CellState,
    previous: Schedule | None = None,
    *,
    time_limit: float = 0.015,
    seed: int = 0,
    waits: bool = True,
    max_evaluations: int | None = None,
    check: bool = True,
) -> Result:
    """A new schedule from ``state``, warm-started from ``previous``.

    ``time_limit`` covers the whole call, building and validating the new
    schedule included; the search also stops after ``max_evaluations``
    decoded schedules (a work limit alone makes the result depend on the
    seed only). The first valid schedule (the warm start decoded) comes
    first, whatever the limit.

    With ``check`` (the default) the new schedule is checked with
    :func:`scheduler.validate` before it is returned; ``check=False`` skips
    that check (the decoder places every task feasibly by construction; on
    large compiled cells the check costs more than the search), and the
    objective is then the decoded makespan.

    ``Result.stats.phases`` holds the wall seconds of the call's parts (a
    measurement only): ``"state"`` (the frozen prefix and the decoder set
    up), ``"first"`` (the warm start decoded), ``"search"`` (the local
    search), ``"decodes"`` (the part of ``"first"`` and ``"search"`` spent
    decoding), ``"build"`` (the schedule record) and ``"validate"``.

    Raises
    ------
    UsageError
        Unknown tasks or arms in the state, or a frozen task whose
        predecessor is not frozen.
    """
    return _resolve(
        problem,
        state,
        None if previous is None else (previous.start, previous.mode),
        time_limit=time_limit,
        seed=seed,
        waits=waits,
        max_evaluations=max_evaluations,
        check=check,
    )


def _resolve(
    problem: Problem,
    state: CellState,
    warm: tuple[FloatArray, IntArray] | None,
    *,
    time_limit: float = 0.015,
    seed: int = 0,
    waits: bool = True,
    max_evaluations: int | None = None,
    check: bool = True,
) -> Result:
    """:func:`reschedule` with the warm start given as (starts, modes) arrays
    (``scheduler.reschedule`` builds them without a schedule record)."""
    t0 = time.perf_counter()
    p = problem
    inst = compile_problem(p)
    now = float(state.time)
    frozen: dict[int, tuple[int, float, float, np.ndarray]] = {}
    for ref, entry in state.done.items():
        t = _task(p, ref)
        m, s, e = int(entry[0]), float(entry[1]), float(entry[2])
        if not (0 <= m < p.n_modes) or int(p.mode_task[m]) != t:
            raise UsageError(f"task {p.task_names[t]!r}: mode {m} is not one of its modes")
        w = (
            np.asarray(entry[3], dtype=float)
            if len(entry) > 3
            else np.zeros(len(p.shapes[m].borders))
        )
        frozen[t] = (m, s, e, w)
    for t in frozen:
        for q in p.task_preds[t]:
            if q not in frozen:
                raise UsageError(
                    f"task {p.task_names[t]!r} is done or running but its predecessor {p.task_names[q]!r} is not"
                )
    release = np.maximum(np.asarray(p.task_release, dtype=float), now)
    for ref, r in state.releases.items():
        t = _task(p, ref)
        release[t] = max(release[t], float(r))  # a late part postpones; it never advances a task
    allowed = np.ones(p.n_modes, dtype=np.bool_)
    for ref in state.failed_arms:
        allowed[p.mode_arm == _arm(p, ref)] = False
    arm_lb = np.full(p.n_arms, now)
    for ref, until in state.arm_busy_until.items():
        a = _arm(p, ref)
        arm_lb[a] = max(arm_lb[a], float(until))
    # the frozen prefix, committed in start order
    # (exactly where it was: each after its arm's frozen tasks so far)
    base = inst.new_state()
    if frozen:
        ts = sorted(frozen, key=lambda t: (frozen[t][1], t))
        fw = np.zeros((len(ts), max(inst.max_borders, 1)))
        for i, t in enumerate(ts):
            w = frozen[t][3]
            fw[i, : len(w)] = w
        inst.commit_all(
            base,
            np.array(ts, dtype=np.int64),
            np.array([frozen[t][0] for t in ts], dtype=np.int64),
            np.array([frozen[t][1] for t in ts], dtype=np.float64),
            np.array([frozen[t][2] for t in ts], dtype=np.float64),
            fw,
        )
    todo = np.ones(p.n_tasks, dtype=np.bool_)
    todo[list(frozen)] = False
    remaining = np.flatnonzero(todo)
    ev = _TimedEvaluator(
        p,
        waits=waits,
        base=base,
        release=release,
        allowed=allowed,
        arm_lb=arm_lb,
        frozen=frozenset(frozen),
    )
    stats = SearchStats()
    t_state = time.perf_counter()
    # warm start: the previous order (by start) and modes where still allowed
    modes = np.full(p.n_tasks, -1, dtype=np.int64)
    if warm is not None:
        first = np.asarray(warm[0], dtype=float)  # earlier start first
        prev = np.asarray(warm[1], dtype=np.int64)[remaining]
        modes[remaining] = np.where(allowed[prev], prev, -1)
    else:
        first = -rank_upward(p)  # larger rank first
    for t, (m, *_rest) in frozen.items():
        modes[t] = m
    order = keyed_order(inst, todo, first)
    sol = ev.evaluate_resume(order, modes)
    if sol is None:  # a previous mode cannot be placed any more: let every task choose
        free = modes.copy()
        free[remaining] = -1
        sol = ev.evaluate_resume(order, free)
    if sol is not None:
        ev.anchor(sol)  # the local search resumes from its prefix
    t_first = time.perf_counter()
    # a cheap bound (the LP of lower_bound would eat the latency budget)
    mind = p.min_duration()
    lb = max(
        max((frozen[t][2] for t in frozen), default=0.0),
        float(np.max(release[remaining] + mind[remaining], initial=0.0)),
    )
    if sol is None:
        stats.evaluations = ev.evaluations
        stats.phases.update(state=t_state - t0, first=t_first - t_state, decodes=ev.decode_time)
        return Result(
            SolveStatus.UNKNOWN,
            None,
            math.inf,
            lb,
            time.perf_counter() - t0,
            "reschedule",
            seed,
            stats,
        )
    stats.record(time.perf_counter() - t0, sol.makespan)
    rng = np.random.default_rng(seed)
    # the limit covers the whole call: keep time to build and validate the
    # schedule. The reserve is the larger of a static estimate and what that
    # step took in the last calls on this problem (slower on a loaded machine)
    reserve = max(2e-4 + 1e-5 * p.n_tasks, 1.25 * _POST_COST.get(inst, 0.0))
    deadline = t0 + time_limit - reserve
    if len(remaining) and time.perf_counter() < deadline:
        # within a few milliseconds the list local search does better than the
        # tabu search here (measured over 60 failure events at 8 x 200: mean
        # makespan 314.1 against 315.4)
        sol = local_search(
            ev,
            sol,
            deadline,
            rng,
            lower=lb,
            max_evaluations=max_evaluations,
            on_improve=lambda s: stats.record(time.perf_counter() - t0, s.makespan),
        )
    tp = time.perf_counter()
    sched = ev.schedule(sol)
    stats.evaluations = ev.evaluations
    sched = sched.bind(p)
    tv = time.perf_counter()
    mk = validate(p, sched) if check else float(sol.makespan)
    te = time.perf_counter()
    took = te - tp
    stats.phases.update(
        state=t_state - t0,
        first=t_first - t_state,
        search=tp - t_first,
        decodes=ev.decode_time,
        build=tv - tp,
        validate=te - tv if check else 0.0,
    )
    # a running estimate that follows a slowdown at once and a speed-up gently
    _POST_COST[inst] = max(took, 0.8 * _POST_COST.get(inst, took) + 0.2 * took)
    return Result(
        SolveStatus.FEASIBLE if mk > lb + 1e-9 else SolveStatus.OPTIMAL,
        sched,
        mk,
        min(lb, mk),
        time.perf_counter() - t0,
        "reschedule",
        seed,
        stats,
    )
