"""Re-solving during execution: what a coordinator knows, a new plan back.

:func:`reschedule` is the scheduler's answer to a coordinator whose cell
departed from the plan (SEEDS.md S2.11-S2.12: an arm failed, a part is late,
a detour cost more than planned). It takes what the coordinator knows --
the tasks done and the tasks running (frozen with their times), the tasks
that failed, the arms out of service, the parts that are late -- and returns
a new plan warm-started from the previous one, under a work limit (decoded
schedules), so the same inputs and seed give the same plan whatever the
machine's speed.

Tasks that can never run (no working arm has a mode for them, a part they
need never comes, a predecessor that cannot run, or they failed) are
returned in :attr:`Rescheduled.dropped`; the schedule still lists them (a
schedule covers every task), each after every live task, and a caller never
executes them. How far after is the scheduler's business: the caller tells
dropped tasks by the set, never by their times.

Examples
--------
>>> from scheduler.fjsp import parse_fjsp
>>> from scheduler.solve import solve
>>> p = parse_fjsp("2 2 1\\n2 1 1 3 2 1 4 2 2\\n1 2 1 2 2 1\\n")
>>> plan = solve(p, "greedy").schedule
>>> first = int(plan.start.argmin())
>>> done = {first: FrozenTask(int(plan.mode[first]), float(plan.start[first]),
...                           float(plan.end[first]))}
>>> r = reschedule(p, now=1.0, previous=plan, done=done, arms_out={1})
>>> rest = [t for t in range(p.n_tasks) if t != first]
>>> r.dropped, set(r.schedule.arms(p)[rest].tolist())
(frozenset(), {0})
"""

from __future__ import annotations

import functools
import gc
import math
import time
import weakref
from collections.abc import Callable, Collection, Mapping
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, field
from typing import ParamSpec, TypeVar

import numpy as np
import numpy.typing as npt

from multiarm.errors import UsageError, ValidationError
from scheduler.kernel import Instance, compile_problem
from scheduler.online import CellState, _resolve
from scheduler.problem import Problem
from scheduler.schedule import Schedule, ScheduleError

__all__ = ["FrozenTask", "Rescheduled", "reschedule"]

_FAR = 1e7
"""Seconds: where dropped tasks are put (internal: callers use ``dropped``)."""


@dataclass(frozen=True, slots=True)
class FrozenTask:
    """A task whose arm, start, end and border waits are fixed.

    Attributes
    ----------
    mode : int
    start, end : float
        Seconds.
    waits : tuple of float
        Seconds waited at each of the mode's borders (empty: none).
    """

    mode: int
    start: float
    end: float
    waits: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if not (math.isfinite(self.start) and math.isfinite(self.end) and self.end >= self.start):
            raise ValidationError(
                f"FrozenTask: start {self.start!r} and end {self.end!r} must be finite, "
                "end >= start"
            )
        object.__setattr__(self, "waits", tuple(float(w) for w in self.waits))


@dataclass(frozen=True, slots=True)
class Rescheduled:
    """What :func:`reschedule` returns.

    Attributes
    ----------
    schedule : Schedule or None
        The new plan (every task), or None when no plan was found (then
        ``reason`` says why and the caller keeps its plan).
    dropped : frozenset of int
        Tasks that can never run; never to be executed.
    reason : str
        Why there is no schedule ("" when there is one).
    latency : float
        Wall-clock seconds of the call (a measurement, never used to decide).
    phases : tuple of (str, float)
        Wall-clock seconds of the call's parts (a measurement): ``"state"``
        (what the coordinator knows turned into the decoder's start),
        ``"first"`` (the warm start decoded), ``"search"`` (the local
        search), ``"decodes"`` (the decoding within ``"first"`` and
        ``"search"``), ``"build"`` (the schedule record) and ``"validate"``
        (zero unless ``check``); ``"prepare"`` is the part before the
        scheduler's online search (the dropped tasks and the warm start).
    """

    schedule: Schedule | None
    dropped: frozenset[int] = field(default_factory=frozenset)
    reason: str = ""
    latency: float = 0.0
    phases: tuple[tuple[str, float], ...] = ()

    @property
    def makespan(self) -> float:
        """The new plan's makespan over the tasks that run (nan without a plan)."""
        s = self.schedule
        if s is None:
            return math.nan
        ends = [float(s.end[t]) for t in range(len(s.end)) if t not in self.dropped]
        return max(ends, default=0.0)


@dataclass(frozen=True, slots=True)
class _Static:
    """What every call on one problem reuses (computed once per problem)."""

    topo: tuple[int, ...]
    """The tasks in topological order."""
    task_arm: npt.NDArray[np.bool_]
    """(T, A): whether a task has a mode on an arm."""
    fastest: tuple[tuple[int, ...], ...]
    """Per task, its modes fastest first (ties: smaller id)."""
    mode_arm: npt.NDArray[np.int64]
    span: float
    """Seconds between two dropped tasks' positions."""


_STATIC: weakref.WeakKeyDictionary[Instance, _Static] = weakref.WeakKeyDictionary()


def _static(p: Problem) -> _Static:
    """The problem's :class:`_Static` (cached on its compiled instance)."""
    inst = compile_problem(p)
    got = _STATIC.get(inst)
    if got is None:
        dur = p.mode_duration
        task_arm = np.zeros((p.n_tasks, p.n_arms), dtype=np.bool_)
        task_arm[
            np.asarray(p.mode_task, dtype=np.int64), np.asarray(p.mode_arm, dtype=np.int64)
        ] = True
        got = _Static(
            tuple(p.topological_order),
            task_arm,
            tuple(
                tuple(sorted((int(m) for m in ms), key=lambda m: (float(dur[m]), m)))
                for ms in p.task_modes
            ),
            np.asarray(p.mode_arm, dtype=np.int64),
            2.0 * float(np.sum(dur)) + 1e4,
        )
        _STATIC[inst] = got
    return got


def _dropped(
    p: Problem,
    frozen: Collection[int],
    failed: Collection[int],
    arms_out: AbstractSet[int],
    parts_late: Mapping[int, float],
) -> set[int]:
    """Tasks that can never run (frozen tasks never are): the failed ones,
    those whose part never comes or whose every arm is out, and every task
    after one of them (its successors, transitively)."""
    st = _static(p)
    seeds = [int(t) for t in failed]
    seeds += [int(t) for t, r in parts_late.items() if math.isinf(r)]
    if arms_out:
        working = np.ones(p.n_arms, dtype=np.bool_)
        working[[int(a) for a in arms_out]] = False
        seeds += np.flatnonzero(~(st.task_arm & working).any(axis=1)).tolist()
    out: set[int] = set()
    while seeds:
        t = seeds.pop()
        if t in out or t in frozen:
            continue
        out.add(t)
        seeds.extend(p.task_succs[t])
    return out


_P = ParamSpec("_P")
_R = TypeVar("_R")


def _collector_held(f: Callable[_P, _R]) -> Callable[_P, _R]:
    """``f`` with Python's cyclic garbage collector held off while it runs
    (and enabled again afterwards if it was)."""

    @functools.wraps(f)
    def held(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        enabled = gc.isenabled()
        gc.disable()
        try:
            return f(*args, **kwargs)
        finally:
            if enabled:
                gc.enable()

    return held


@_collector_held
def reschedule(
    problem: Problem,
    *,
    now: float,
    previous: Schedule,
    done: Mapping[int, FrozenTask] | None = None,
    running: Mapping[int, FrozenTask] | None = None,
    failed: Collection[int] = (),
    arms_out: Collection[int] = (),
    parts_late: Mapping[int, float] | None = None,
    evaluations: int = 200,
    time_limit: float = 1e6,
    seed: int = 0,
    check: bool = False,
) -> Rescheduled:
    """A new plan from what the coordinator knows (module docstring).

    The call is latency-critical: Python's cyclic garbage collector is held
    off while it runs (a full collection of a long simulation's garbage can
    take a second) and runs again afterwards as before.

    Parameters
    ----------
    problem : Problem
    now : float
        Seconds: no task that is not frozen starts earlier.
    previous : Schedule
        The plan followed so far (the warm start: its order and modes where
        still possible; a dropped arm's tasks move to a working arm's
        fastest mode).
    done, running : mapping of int -> FrozenTask
        Tasks finished, and tasks running or committed to their arm (their
        predecessors frozen too): kept exactly.
    failed : collection of int
        Tasks that failed (dropped, with every task after them).
    arms_out : collection of int
        Arms out of service: they get no new task.
    parts_late : mapping of int -> float
        Per task, when its late part comes (seconds; ``inf``: never).
    evaluations : int
        Work limit: decoded schedules of the search (then one, the warm
        start decoded, if the first answer puts a live task after a dropped
        one).
    time_limit : float
        Seconds of wall clock (large by default: the work limit decides).
    seed : int
    check : bool
        Check the new plan with :func:`scheduler.validate` before returning
        it (off by default: the decoder places every task feasibly by
        construction, and on a large compiled cell the check costs more than
        the rest of the call; the tests check the plans).

    Returns
    -------
    Rescheduled

    Raises
    ------
    UsageError
        A task index or arm index out of range.
    """
    t_in = time.perf_counter()
    p = problem
    done = dict(done or {})
    running = dict(running or {})
    late = dict(parts_late or {})
    for t in (*done, *running, *failed, *late):
        if not 0 <= int(t) < p.n_tasks:
            raise UsageError(f"reschedule: task {t!r} is not a task of the problem")
    for a in arms_out:
        if not 0 <= int(a) < p.n_arms:
            raise UsageError(f"reschedule: arm {a!r} is not an arm of the problem")
    frozen: dict[int | str, tuple[int, float, float, list[float]]] = {
        t: (f.mode, f.start, f.end, list(f.waits)) for t, f in (*done.items(), *running.items())
    }
    out = set(arms_out)
    dead = _dropped(p, frozen.keys(), set(failed), out, late)  # type: ignore[arg-type]
    releases: dict[int | str, float] = {t: r for t, r in late.items() if math.isfinite(r)}
    # warm start: tasks planned on an arm out move to a working arm's
    # fastest mode; the dropped tasks come last, each at its own time far
    # after the rest, so the plan's makespan is theirs whatever the live
    # tasks do, and the search can never gain by pushing a live task after them
    st = _static(p)
    T = p.n_tasks
    mode = np.array(previous.mode, dtype=np.int64)
    start = np.array(previous.start, dtype=float)
    live = np.ones(T, dtype=np.bool_)
    live[[int(t) for t in frozen]] = False
    dead_mask = np.zeros(T, dtype=np.bool_)
    dead_mask[list(dead)] = True
    arm_out = np.zeros(p.n_arms, dtype=np.bool_)
    arm_out[[int(a) for a in out]] = True
    for t in np.flatnonzero(live & (dead_mask | arm_out[st.mode_arm[mode]])).tolist():
        # a dropped task: its fastest mode; else its fastest mode on a working arm
        m = next(m for m in st.fastest[t] if dead_mask[t] or not arm_out[st.mode_arm[m]])
        mode[t] = m
    span = st.span
    for k, t in enumerate(x for x in st.topo if x in dead):
        releases[t] = start[t] = _FAR + k * span
    if dead:
        # an arm out keeps the modes of the tasks only it could do (they
        # stay planned after the live tasks and are dropped)
        state = CellState(
            time=now, done=frozen, releases=releases, arm_busy_until={a: _FAR for a in out}
        )
    else:
        state = CellState(time=now, done=frozen, releases=releases, failed_arms=set(out))
    t0 = time.perf_counter()
    new: Schedule | None = None
    err = ""
    phases: dict[str, float] = {"prepare": t0 - t_in}
    for limit in (evaluations, 1):
        try:
            res = _resolve(
                p,
                state,
                (start, mode),
                time_limit=time_limit,
                seed=seed,
                max_evaluations=limit,
                check=check,
            )
            for part, v in res.stats.phases.items():
                phases[part] = phases.get(part, 0.0) + v
            new = res.schedule
            err = "" if new is not None else f"no schedule ({res.status.value})"
        except (ScheduleError, UsageError) as exc:
            new, err = None, str(exc)
        if new is not None and bool(np.any((new.start >= _FAR) & ~dead_mask)):
            # a task that can run was put after the ones that cannot: take
            # the warm start decoded instead (every task in plan order)
            new, err = None, "a task that can run was planned after the dropped ones"
            continue
        break
    return Rescheduled(
        new, frozenset(dead), err, time.perf_counter() - t_in, tuple(sorted(phases.items()))
    )
