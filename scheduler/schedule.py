"""Schedules and the one validator of every constraint.

A :class:`Schedule` says, for every task: its mode (hence its arm), start,
end, the waits inserted at its mode's zone borders, and the blocking (detour)
cost charged to it. :func:`validate` checks every constraint of the problem
and returns the makespan it computes; every solver's tests, the benchmarks
and the simulator compare schedules only through it (DESIGN.md).

Examples
--------
>>> from scheduler.problem import Model
>>> m = Model()
>>> a = m.add_arm("a")
>>> t0, t1 = m.add_task("t0"), m.add_task("t1", predecessors=["t0"])
>>> m.add_mode(t0, a, 2.0); m.add_mode(t1, a, 3.0)
>>> p = m.build()
>>> validate(p, Schedule.from_starts(p, [0, 1], [0.0, 2.0]))
5.0
>>> validate(p, Schedule.from_starts(p, [0, 1], [0.0, 1.0]))
Traceback (most recent call last):
...
multiarm.errors.ScheduleError: task 't1' starts at 1 before its predecessor 't0' ends at 2
"""

from __future__ import annotations

import bisect
import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from multiarm.errors import ScheduleError, UsageError, ValidationError
from multiarm.types import FloatArray, IntArray
from scheduler.problem import Problem, ProblemLike, as_problem

__all__ = [
    "ROW_COLUMNS",
    "Reservation",
    "Schedule",
    "ScheduleError",
    "blocking_required",
    "validate",
]


ReservationRow = tuple[Literal["zone", "move", "tool", "start"], str, str | None, str, float, float]
"""A :class:`Reservation` as a plain tuple (kind, resource, task, arm, start, end)."""


@dataclass(frozen=True, slots=True)
class Reservation:
    """One use of a resource: ``kind`` is ``"zone"`` (exclusive occupancy),
    ``"move"`` (movement in a shared zone), ``"tool"`` or ``"start"`` (an arm
    standing in its start zone until it leaves)."""

    kind: Literal["zone", "move", "tool", "start"]
    resource: str
    task: str | None
    arm: str
    start: float
    end: float


def _frozen(x: Any, dtype: type) -> Any:
    """``x`` as a read-only array of ``dtype``: ``x`` itself when it already is
    one that owns its data (or views a read-only array that does), else a copy."""
    if (
        isinstance(x, np.ndarray)
        and x.dtype == dtype
        and not x.flags.writeable
        and (
            x.flags.owndata
            or (
                isinstance(x.base, np.ndarray)
                and x.base.flags.owndata
                and not x.base.flags.writeable
            )
        )
    ):
        return x
    arr: Any = np.array(x, dtype=dtype)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Schedule:
    """A complete schedule (see the module docstring).

    Attributes
    ----------
    mode : (T,) int
    start, end : (T,) float, seconds
    waits : tuple of (k_t,) float
        Per task, the wait at each border of its mode (zeros allowed).
    blocking : (T,) float
        Detour cost charged to each task (seconds).
    """

    mode: IntArray
    start: FloatArray
    end: FloatArray
    waits: tuple[FloatArray, ...]
    blocking: FloatArray
    _arm: IntArray | None = field(default=None, repr=False)
    _problem: Problem | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        for name in ("mode", "start", "end", "blocking"):
            arr = _frozen(getattr(self, name), np.int64 if name == "mode" else np.float64)
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "waits", tuple(_frozen(w, np.float64) for w in self.waits))

    @classmethod
    def from_starts(
        cls,
        problem: Problem,
        modes: Sequence[int] | IntArray,
        starts: Sequence[float] | FloatArray,
        waits: Sequence[Sequence[float] | FloatArray] | None = None,
        blocking: Sequence[float] | FloatArray | None = None,
    ) -> Schedule:
        """A schedule from modes and starts; ends are computed (duration +
        waits + blocking), waits default to none."""
        modes_a = np.asarray(modes, dtype=np.int64)
        T = problem.n_tasks
        w = (
            tuple(np.asarray(x, dtype=float) for x in waits)
            if waits is not None
            else tuple(np.zeros(len(problem.shapes[int(m)].borders)) for m in modes_a)
        )
        b = np.zeros(T) if blocking is None else np.asarray(blocking, dtype=float)
        starts_a = np.asarray(starts, dtype=float)
        ends = (
            np.array(
                [
                    starts_a[t] + problem.shapes[int(modes_a[t])].length(w[t]) + b[t]
                    for t in range(T)
                ]
            )
            if T
            else np.zeros(0)
        )
        return cls(modes_a, starts_a, ends, w, b)

    @classmethod
    def empty(cls) -> Schedule:
        """The schedule of a problem without tasks."""
        return cls(np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), (), np.zeros(0))

    @property
    def n_tasks(self) -> int:
        """The number of tasks."""
        return len(self.mode)

    @property
    def bound_problem(self) -> Problem | None:
        """The problem this schedule is bound to (see :meth:`bind`), or None.

        Schedules returned by :func:`scheduler.solve` and
        :func:`scheduler.online.reschedule` are bound to their problem, so
        that :meth:`to_dataframe` and :meth:`reservations_frame` need no
        argument.
        """
        return self._problem

    def bind(self, problem: Problem) -> Schedule:
        """This schedule bound to ``problem`` (a new record; equal to this one).

        Parameters
        ----------
        problem : Problem
            The problem the schedule is for.

        Returns
        -------
        Schedule

        Raises
        ------
        ValidationError
            The schedule and the problem have different numbers of tasks.

        Examples
        --------
        >>> from scheduler.fjsp import parse_fjsp
        >>> p = parse_fjsp("1 1\\n2 1 1 2 1 1 3\\n")
        >>> s = Schedule.from_starts(p, [0, 1], [0.0, 2.0]).bind(p)
        >>> s.to_dataframe()[["task", "arm", "start", "end", "duration"]].values.tolist()
        [['J1.O1', 'M1', 0.0, 2.0, 2.0], ['J1.O2', 'M1', 2.0, 5.0, 3.0]]
        """
        if self.n_tasks != problem.n_tasks:
            raise ValidationError(
                f"a schedule of {self.n_tasks} tasks cannot be bound to a problem of "
                f"{problem.n_tasks} tasks"
            )
        # the arrays are read-only and owned: shared, not copied again
        bound = copy.copy(self)
        object.__setattr__(bound, "_problem", problem)
        return bound

    def _the_problem(self, problem: Problem | None) -> Problem:
        if problem is not None:
            return problem
        if self._problem is None:
            raise UsageError(
                "this schedule is not bound to a problem: pass the problem, or bind it "
                "with schedule.bind(problem)"
            )
        return self._problem

    @property
    def makespan(self) -> float:
        """Largest end (0 for an empty schedule). Use :func:`validate` to check it."""
        return float(self.end.max()) if len(self.end) else 0.0

    def arms(self, problem: Problem) -> IntArray:
        """(T,) int: the arm of every task."""
        out: IntArray = problem.mode_arm[self.mode]
        return out

    def sequences(self, problem: Problem) -> list[list[int]]:
        """Per arm, its tasks in start order."""
        arms = self.arms(problem)
        seqs: list[list[int]] = [[] for _ in range(problem.n_arms)]
        for t in np.lexsort((np.arange(self.n_tasks), self.start)):
            seqs[int(arms[t])].append(int(t))
        return seqs

    def total_wait(self) -> float:
        """Sum of every wait at zone borders (the conflicts predicted), seconds."""
        return float(sum(float(w.sum()) for w in self.waits))

    def reservations(
        self, problem: Problem, seqs: list[list[int]] | None = None
    ) -> list[Reservation]:
        """Every use of an exclusive zone, shared-zone movement, tool and start zone.

        Parameters
        ----------
        problem : Problem
        seqs : list of list of int or None
            :meth:`sequences`, when already computed.

        Returns
        -------
        list of Reservation
        """
        return [Reservation(*row) for row in self.reservation_rows(problem, seqs)]

    def reservation_rows(
        self, problem: Problem, seqs: list[list[int]] | None = None
    ) -> list[ReservationRow]:
        """:meth:`reservations` as plain tuples ``(kind, resource, task, arm,
        start, end)``, cheaper where thousands are checked (the validator).

        Parameters
        ----------
        problem : Problem
        seqs : list of list of int or None

        Returns
        -------
        list of tuple
        """
        shapes = problem.shapes
        Z = problem.n_zones
        zone_names, tool_names = problem.zone_names, problem.tool_names
        out: list[ReservationRow] = []
        arms = self.arms(problem).tolist()
        mode, start = self.mode.tolist(), self.start.tolist()
        for t in range(self.n_tasks):
            sh = shapes[mode[t]]
            if not (sh.exclusive or sh.moves or sh.tools):
                continue
            arm = problem.arm_names[arms[t]]
            task = problem.task_names[t]
            for r, s, e in sh.intervals(start[t], self.waits[t]):
                kind: Literal["zone", "move"] = "zone" if r < Z else "move"
                out.append((kind, zone_names[r % Z], task, arm, s, e))
            for r in sh.tools:
                out.append(
                    (
                        "tool",
                        tool_names[r - 2 * Z],
                        task,
                        arm,
                        start[t],
                        float(self.end[t]),
                    )
                )
        if not any(problem.arm_start_zones):
            return out
        for a, (z_list, dep) in enumerate(
            zip(problem.arm_start_zones, self.departures(problem, seqs), strict=True)
        ):
            for z in z_list:
                if problem.zone_exclusive[z]:
                    out.append(("start", zone_names[z], None, problem.arm_names[a], 0.0, dep))
        return out

    def departures(self, problem: Problem, seqs: list[list[int]] | None = None) -> list[float]:
        """When each arm leaves its initial pose (inf if it never moves).

        Parameters
        ----------
        problem : Problem
        seqs : list of list of int or None
            :meth:`sequences`, when already computed.
        """
        out = []
        for a, seq in enumerate(self.sequences(problem) if seqs is None else seqs):
            if seq:
                out.append(float(self.start[seq[0]]) - problem.setup_time(a, -1, seq[0]))
            else:
                out.append(math.inf)
        return out

    # ------------------------------------------------------------ export
    def to_dict(self, problem: Problem) -> dict[str, Any]:
        """Plain data with names."""
        arms = self.arms(problem)
        return {
            "format": "multiarm.schedule/1",
            "makespan": self.makespan,
            "tasks": [
                {
                    "task": problem.task_names[t],
                    "arm": problem.arm_names[arms[t]],
                    "start": float(self.start[t]),
                    "end": float(self.end[t]),
                    "waits": [
                        [b, float(w)]
                        for b, w in zip(
                            problem.shapes[int(self.mode[t])].borders,
                            self.waits[t].tolist(),
                            strict=True,
                        )
                        if w > 0
                    ],
                    "blocking": float(self.blocking[t]),
                }
                for t in range(self.n_tasks)
            ],
        }

    @classmethod
    def from_dict(cls, problem: Problem, data: dict[str, Any]) -> Schedule:
        """Inverse of :meth:`to_dict`."""
        T = problem.n_tasks
        idx = {n: i for i, n in enumerate(problem.task_names)}
        arm_idx = {n: i for i, n in enumerate(problem.arm_names)}
        mode = np.full(T, -1, dtype=np.int64)
        start = np.zeros(T)
        end = np.zeros(T)
        blocking = np.zeros(T)
        waits: list[FloatArray] = [np.zeros(0)] * T
        for row in data["tasks"]:
            t = idx[row["task"]]
            m = int(problem.mode_of[arm_idx[row["arm"]], t])
            if m < 0:
                raise ValidationError(f"arm {row['arm']!r} cannot do task {row['task']!r}")
            mode[t], start[t], end[t] = m, row["start"], row["end"]
            blocking[t] = row.get("blocking", 0.0)
            borders = problem.shapes[m].borders
            w = np.zeros(len(borders))
            for b, x in row.get("waits", []):
                if b not in borders:
                    raise ValidationError(f"task {row['task']!r}: {b} is not a border of its mode")
                w[borders.index(b)] = x
            waits[t] = w
        if (mode < 0).any():
            missing = problem.task_names[int(np.argmax(mode < 0))]
            raise ValidationError(f"the schedule data lacks task {missing!r}")
        return cls(mode, start, end, tuple(waits), blocking)

    def rows(self, problem: Problem | None = None) -> list[dict[str, Any]]:
        """One tidy record per task, in task order.

        Parameters
        ----------
        problem : Problem or None
            Needed only when the schedule is not bound to its problem.

        Returns
        -------
        list of dict
            Keys ``task``, ``arm`` (names), ``mode`` (mode id), ``start``,
            ``end``, ``duration`` (the mode's, seconds), ``wait`` (total wait
            at zone borders) and ``detour`` (blocking cost charged); ``end =
            start + duration + wait + detour``.

        Raises
        ------
        UsageError
            No problem given and none bound.
        """
        p = self._the_problem(problem)
        arms = self.arms(p)
        return [
            {
                "task": p.task_names[t],
                "arm": p.arm_names[int(arms[t])],
                "mode": int(self.mode[t]),
                "start": float(self.start[t]),
                "end": float(self.end[t]),
                "duration": float(p.mode_duration[int(self.mode[t])]),
                "wait": float(self.waits[t].sum()),
                "detour": float(self.blocking[t]),
            }
            for t in range(self.n_tasks)
        ]

    def to_dataframe(self, problem: Problem | None = None) -> Any:
        """A pandas DataFrame of :meth:`rows` (one row per task).

        Parameters
        ----------
        problem : Problem or None
            Needed only when the schedule is not bound to its problem.

        Returns
        -------
        pandas.DataFrame
            Columns ``task, arm, mode, start, end, duration, wait, detour``.

        Raises
        ------
        UsageError
            No problem given and none bound, or pandas missing.
        """
        pd = _pandas()
        return pd.DataFrame(self.rows(problem), columns=list(ROW_COLUMNS))

    def reservations_frame(self, problem: Problem | None = None) -> Any:
        """A pandas DataFrame of :meth:`reservations`, in start order.

        Returns
        -------
        pandas.DataFrame
            Columns ``kind`` (``zone``, ``move``, ``tool``, ``start``),
            ``resource``, ``task`` (None for an arm standing in its start
            zone), ``arm``, ``start``, ``end``.

        Raises
        ------
        UsageError
            No problem given and none bound, or pandas missing.
        """
        pd = _pandas()
        res = sorted(self.reservations(self._the_problem(problem)), key=lambda r: (r.start, r.arm))
        return pd.DataFrame(
            [
                {
                    "kind": r.kind,
                    "resource": r.resource,
                    "task": r.task,
                    "arm": r.arm,
                    "start": r.start,
                    "end": r.end,
                }
                for r in res
            ],
            columns=["kind", "resource", "task", "arm", "start", "end"],
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Schedule):
            return NotImplemented
        return (
            np.array_equal(self.mode, other.mode)
            and np.array_equal(self.start, other.start)
            and np.array_equal(self.end, other.end)
            and np.array_equal(self.blocking, other.blocking)
            and len(self.waits) == len(other.waits)
            and all(np.array_equal(a, b) for a, b in zip(self.waits, other.waits, strict=True))
        )

    __hash__ = None  # type: ignore[assignment]


ROW_COLUMNS = ("task", "arm", "mode", "start", "end", "duration", "wait", "detour")
"""The columns of :meth:`Schedule.rows` and :meth:`Schedule.to_dataframe`."""


def _pandas() -> Any:
    try:
        import pandas as pd
    except ImportError as exc:  # pragma: no cover - pandas is in the analysis extra
        raise UsageError("data frames need pandas (pip install pandas)") from exc
    return pd


# --------------------------------------------------------------- validation


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def park_table(
    problem: Problem, schedule: Schedule, seqs: list[list[int]], arm: int
) -> tuple[list[int], list[float], list[float], list[float]]:
    """What :func:`parked_pose` reads of one arm: its tasks in start order,
    when it leaves for each (start minus the travel), when each ends, and the
    running maximum of those ends."""
    prev = -1
    departs: list[float] = []
    ends: list[float] = []
    reach: list[float] = []
    for t in seqs[arm]:
        depart = float(schedule.start[t]) - problem.setup_time(arm, prev, t)
        departs.append(depart)
        ends.append(float(schedule.end[t]))
        reach.append(max(reach[-1], ends[-1]) if reach else ends[-1])
        prev = t
    return seqs[arm], departs, ends, reach


def parked_pose(
    problem: Problem,
    schedule: Schedule,
    seqs: list[list[int]],
    arm: int,
    time: float,
    table: tuple[list[int], list[float], list[float], list[float]] | None = None,
) -> int | None:
    """Where ``arm`` stands parked at ``time``: the task whose end pose it holds
    (-1: its initial pose), or None when it is working or travelling.

    ``table`` is :func:`park_table` of the arm, when already computed. Walking
    the arm's tasks in order, the first one that ends after ``time`` decides
    (a task never ends before it departs); found by bisection on the running
    maximum of the ends.
    """
    tasks, departs, ends, reach = (
        park_table(problem, schedule, seqs, arm) if table is None else table
    )
    i = bisect.bisect_right(reach, time)
    prev = tasks[i - 1] if i > 0 else -1
    if i == len(tasks):
        return prev
    if time < departs[i]:
        return prev if time >= (ends[i - 1] if i > 0 else 0.0) else None
    return None


def blocking_required(
    problem: Problem,
    schedule: Schedule,
    task: int,
    seqs: list[list[int]] | None = None,
    cache: dict[tuple[int, int, int], float] | None = None,
    tables: list[tuple[list[int], list[float], list[float], list[float]]] | None = None,
) -> tuple[float, list[tuple[int, int]]]:
    """The detour cost the blocking oracle charges ``task`` in ``schedule``:
    (total, [(parked arm, pose task), ...] that block it). ``tables``: every
    arm's :func:`park_table`, when already computed."""
    oracle = problem.blocking
    if oracle is None:
        return 0.0, []
    if seqs is None:
        seqs = schedule.sequences(problem)
    m = int(schedule.mode[task])
    a = int(problem.mode_arm[m])
    S = float(schedule.start[task])
    total = 0.0
    who = []
    for b in range(problem.n_arms):
        if b == a:
            continue
        pose = parked_pose(problem, schedule, seqs, b, S, None if tables is None else tables[b])
        if pose is None:
            continue
        key = (m, b, pose)
        if cache is not None and key in cache:
            c = cache[key]
        else:
            c = float(oracle.cost(m, b, pose))
            if cache is not None:
                cache[key] = c
        if c != 0.0:
            total += c
            who.append((b, pose))
    return total, who


def validate(problem: ProblemLike, schedule: Schedule, tol: float = 1e-6) -> float:
    """Check every constraint of ``problem`` on ``schedule``; return the makespan.

    Checks: one mode of the right task per task; finite times; ends equal
    start + duration + waits + charged blocking; non-negative waits, one per
    border; releases; arm availability and the setup before every task, in
    each arm's start order; precedence; exclusive zones never held by two arms
    at once (start zones included); never two arms moving in one shared zone;
    tools held by one task at a time; blocking: every task charged at least
    the detour its parked neighbours force, and none starting while a parked
    arm is in its way for good. Intervals are half-open: touching is fine.

    Parameters
    ----------
    problem : Problem or object with a ``.problem`` Problem
        A :class:`Problem`, or anything carrying one as ``.problem`` (a
        ``workcell.CompiledCell``).
    schedule : Schedule
    tol : float
        Absolute tolerance on times, seconds.

    Returns
    -------
    float
        The makespan (largest end), or 0 for a problem without tasks.

    Raises
    ------
    ScheduleError
        Naming the first violated constraint, its tasks, arms and times.
    """
    p = as_problem(problem, "validate")
    T = p.n_tasks
    s = schedule
    if (
        len(s.mode) != T
        or len(s.start) != T
        or len(s.end) != T
        or len(s.waits) != T
        or len(s.blocking) != T
    ):
        raise ScheduleError(f"the schedule covers {len(s.mode)} tasks, the problem has {T}")
    names = p.task_names
    # plain Python floats and ints: indexing numpy arrays one element at a time is slow
    mode, start, end, blk = s.mode.tolist(), s.start.tolist(), s.end.tolist(), s.blocking.tolist()
    mode_task, release, shapes = p.mode_task.tolist(), p.task_release.tolist(), p.shapes
    for t in range(T):
        m = mode[t]
        if not (0 <= m < p.n_modes) or mode_task[m] != t:
            raise ScheduleError(
                f"task {names[t]!r} is given mode {m}, which is not one of its modes"
            )
        if not (math.isfinite(start[t]) and math.isfinite(end[t])):
            raise ScheduleError(f"task {names[t]!r} has a non-finite start or end")
        sh = shapes[m]
        w = s.waits[t]
        if len(w) != len(sh.borders):
            raise ScheduleError(
                f"task {names[t]!r} gives {len(w)} waits for {len(sh.borders)} borders"
            )
        if len(w) and any(not math.isfinite(x) or x < -tol for x in w.tolist()):
            raise ScheduleError(f"task {names[t]!r} has a negative or non-finite wait")
        if not (math.isfinite(blk[t]) and blk[t] >= -tol):
            raise ScheduleError(f"task {names[t]!r} has a negative or non-finite blocking cost")
        expect = start[t] + sh.length(w) + blk[t]
        if abs(end[t] - expect) > tol:
            raise ScheduleError(
                f"task {names[t]!r} ends at {_fmt(end[t])}, but start + duration + waits + blocking "
                f"= {_fmt(expect)}"
            )
        if start[t] < release[t] - tol:
            raise ScheduleError(
                f"task {names[t]!r} starts at {_fmt(start[t])} before its release {_fmt(release[t])}"
            )
        for q in p.task_preds[t]:
            if start[t] < end[q] - tol:
                raise ScheduleError(
                    f"task {names[t]!r} starts at {_fmt(start[t])} before its predecessor "
                    f"{names[q]!r} ends at {_fmt(end[q])}"
                )
    seqs = s.sequences(p)
    for a, seq in enumerate(seqs):
        prev, ready = -1, float(p.arm_available[a])
        for t in seq:
            need = ready + p.setup_time(a, prev, t)
            if start[t] < need - tol:
                what = "becomes available" if prev < 0 else f"finishes {names[prev]!r}"
                raise ScheduleError(
                    f"arm {p.arm_names[a]!r} starts task {names[t]!r} at {_fmt(start[t])}, but it "
                    f"{what} and travels until {_fmt(need)}"
                )
            prev, ready = t, end[t]
    # zones and tools
    res = s.reservation_rows(p, seqs)
    groups: dict[tuple[str, str], list[ReservationRow]] = {}
    for r in res:
        if r[0] == "move" or r[0] == "tool":
            groups.setdefault((r[0], r[1]), []).append(r)
        else:  # exclusive occupancy and start zones share the zone
            groups.setdefault(("zone", r[1]), []).append(r)
    for (kind, name), items in groups.items():
        items.sort(key=lambda r: r[4])
        for i, (_k1, _n1, task1, arm1, s1, e1) in enumerate(items):
            for _k2, _n2, task2, arm2, s2, e2 in items[i + 1 :]:
                if s2 >= e1 - tol:
                    break
                if arm2 == arm1 or e2 <= s2 + tol or e1 <= s1 + tol:
                    continue
                what = {
                    "zone": "inside exclusive zone",
                    "move": "moving in shared zone",
                    "tool": "holding tool",
                }[kind]
                who1 = f"task {task1!r}" if task1 else "standing (start zone)"
                who2 = f"task {task2!r}" if task2 else "standing (start zone)"
                raise ScheduleError(
                    f"arms {arm1!r} ({who1}) and {arm2!r} ({who2}) are both {what} {name!r} "
                    f"during [{_fmt(s2)}, {_fmt(min(e1, e2))})"
                )
    if p.blocking is not None:
        cache: dict[tuple[int, int, int], float] = {}
        tables = [park_table(p, s, seqs, b) for b in range(p.n_arms)]
        for t in range(T):
            need, who = blocking_required(p, s, t, seqs, cache, tables)
            if math.isinf(need):
                b, pose = next(
                    (b, pose) for b, pose in who if math.isinf(cache[(int(s.mode[t]), b, pose)])
                )
                where = "its initial pose" if pose < 0 else f"the end pose of {names[pose]!r}"
                raise ScheduleError(
                    f"task {names[t]!r} starts at {_fmt(s.start[t])} while arm {p.arm_names[b]!r} is "
                    f"parked at {where}, in its way with no detour"
                )
            if s.blocking[t] < need - tol:
                raise ScheduleError(
                    f"task {names[t]!r} is charged {_fmt(s.blocking[t])} s of detour, but the arms parked "
                    f"in its way force {_fmt(need)} s"
                )
    return float(s.end.max()) if T else 0.0
