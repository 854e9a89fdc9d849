"""Sequence-dependent setup (travel) times between an arm's tasks.

Travel from one task's end pose to the next task's start pose on the same arm
is a setup time that depends on the pair (DESIGN.md data flow, step 2). A
:class:`Setup` describes it; the problem *binds* it (:meth:`Setup.bind`) into
a :class:`BoundSetup` that answers ``time(arm, prev, next)`` and whole rows
``row(arm, prev)`` (every next task at once, cached), ``prev = -1`` meaning
the arm's initial pose.

* :class:`NoSetup`: zero everywhere (FJSP).
* :class:`MatrixSetup`: a dense ``(A, T + 1, T)`` array (row 0 = from the
  initial pose).
* :class:`TravelSetup`: distances between mode end and start points divided
  by the arm's speed, plus a fixed time per move — computed on demand.
* :class:`FunctionSetup`: any Python callable, cached per row.

:meth:`Setup.kernel_data` hands the placement kernel (:mod:`scheduler.kernel`)
what it needs as a :class:`KernelSetup`: a compact table of the pairs each
arm can actually take (from its initial pose or one of its tasks to one of
its tasks), never a dense ``(A, T + 1, T)`` table.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Mapping
from typing import Any, Literal, NamedTuple

import numpy as np

from multiarm.errors import UsageError, ValidationError
from multiarm.types import FloatArray, IntArray
from scheduler.view import ProblemView

__all__ = [
    "BoundSetup",
    "FunctionSetup",
    "KernelSetup",
    "MatrixSetup",
    "NoSetup",
    "Setup",
    "TravelSetup",
    "setup_from_dict",
]


class KernelSetup(NamedTuple):
    """Setup times as the placement kernel reads them: a compact table.

    For each arm ``a``, a block of ``arm_count[a] + 1`` rows (from its
    initial pose, then from the end of each of its modes, in mode order) of
    ``arm_count[a]`` entries (to the start of each of its modes): only pairs
    the arm can take, never a dense ``(A, T + 1, T)`` table.

    Travel setups are packed instead (kinds 2 and 3): ``table`` holds the
    mode start points (M, 3), end points (M, 3), home points (A, 3), speeds
    (A,) and fixed times (A,), flattened, and the kernel computes each travel
    time as :class:`TravelSetup` does.

    Attributes
    ----------
    kind : int
        0: no setup (nothing read); 1: the table; 2, 3: travel, Euclidean or
        Manhattan.
    table : (sum of arm_count * (arm_count + 1),) float, seconds
    arm_off : (A,) int
        Where arm ``a``'s block starts.
    arm_count : (A,) int
        How many modes arm ``a`` has.
    mode_slot : (M,) int
        Each mode's rank among its arm's modes.
    """

    kind: int
    table: FloatArray
    arm_off: IntArray
    arm_count: IntArray
    mode_slot: IntArray


def _layout(problem: ProblemView) -> tuple[IntArray, IntArray, IntArray, list[IntArray]]:
    """Per arm: block offsets, mode counts, each mode's slot, and the arm's modes."""
    A, M = problem.n_arms, problem.n_modes
    mode_arm = np.asarray(problem.mode_arm, dtype=np.int64)
    count = np.bincount(mode_arm, minlength=A).astype(np.int64)
    off = np.zeros(A, dtype=np.int64)
    off[1:] = np.cumsum(count * (count + 1))[:-1]
    slot = np.zeros(M, dtype=np.int64)
    modes = [np.flatnonzero(mode_arm == a) for a in range(A)]
    for a in range(A):
        slot[modes[a]] = np.arange(len(modes[a]))
    return off, count, slot, modes


def _table_setup(
    problem: ProblemView, block: Callable[[int, IntArray], FloatArray] | None
) -> KernelSetup:
    """A :class:`KernelSetup` whose arm blocks come from ``block(arm, modes)``,
    shape (len(modes) + 1, len(modes)); ``None``: no setup (kind 0)."""
    off, count, slot, modes = _layout(problem)
    if block is None:
        return KernelSetup(0, np.zeros(1), off, count, slot)
    table = np.zeros(max(int((count * (count + 1)).sum()), 1))
    for a, ms in enumerate(modes):
        n = len(ms)
        if n:
            table[off[a] : off[a] + (n + 1) * n] = np.asarray(block(a, ms), dtype=float).ravel()
    return KernelSetup(1, table, off, count, slot)


class BoundSetup:
    """Setup times bound to one problem, with a cache of rows."""

    def __init__(
        self,
        problem: ProblemView,
        row_fn: Callable[[int, int], FloatArray],
        zero: bool = False,
        cache_rows: int = 8192,
        min_in_fn: Callable[[int], FloatArray] | None = None,
        time_fn: Callable[[int, int, int], float] | None = None,
    ) -> None:
        self.problem = problem
        self._time_fn = time_fn
        self._row_fn = row_fn
        self.zero = zero
        self._zeros = np.zeros(problem.n_tasks)
        self._zeros.setflags(write=False)
        self._cache: OrderedDict[tuple[int, int], FloatArray] = OrderedDict()
        self._limit = cache_rows
        self._min_in_fn = min_in_fn

    def min_incoming(self, arm: int) -> FloatArray:
        """(T,): for each task, the least setup of ``arm`` into it from its
        initial pose or from any other task it can do (inf where it cannot)."""
        p = self.problem
        if self.zero:
            return np.zeros(p.n_tasks)
        if self._min_in_fn is not None:
            return self._min_in_fn(arm)
        tasks = np.flatnonzero(p.mode_of[arm] >= 0)
        best = np.full(p.n_tasks, np.inf)
        best[tasks] = self._row_fn(arm, -1)[tasks]
        for prev in tasks.tolist():
            row = np.array(self._row_fn(arm, prev), dtype=float)[tasks]
            row[tasks == prev] = np.inf
            best[tasks] = np.minimum(best[tasks], row)
        return best

    def row(self, arm: int, prev: int) -> FloatArray:
        """(T,) float: setup of ``arm`` from task ``prev`` (-1: initial pose) to
        every task (inf where the arm cannot do it); cached."""
        if self.zero:
            return self._zeros
        key = (arm, prev)
        r = self._cache.get(key)
        if r is None:
            r = np.asarray(self._row_fn(arm, prev), dtype=float)
            r.setflags(write=False)
            self._cache[key] = r
            if len(self._cache) > self._limit:
                self._cache.popitem(last=False)
        out: FloatArray = r
        return out

    def time(self, arm: int, prev: int, nxt: int) -> float:
        """Setup of ``arm`` from task ``prev`` (-1: initial pose) to task ``nxt``, seconds."""
        if self.zero:
            return 0.0
        if self._time_fn is not None:
            return self._time_fn(arm, prev, nxt)
        return float(self.row(arm, prev)[nxt])

    def check(self) -> None:
        """Validate every row the arms can use: finite and >= 0."""
        p = self.problem
        if self.zero:
            return
        for a in range(p.n_arms):
            tasks = p.mode_task[p.mode_arm == a]
            if len(tasks) == 0:
                continue
            for prev in (-1, *tasks.tolist()):
                r = self.row(a, prev)[tasks]
                bad = ~np.isfinite(r) | (r < 0)
                if bad.any():
                    t = int(tasks[np.argmax(bad)])
                    src = "its initial pose" if prev < 0 else f"task {p.task_names[prev]!r}"
                    raise ValidationError(
                        f"setup time of arm {p.arm_names[a]!r} from {src} to task "
                        f"{p.task_names[t]!r} must be finite and >= 0, got {float(r[np.argmax(bad)])}"
                    )
            if len(tasks) > 400:  # checking every row of big problems costs more than it saves
                break

    def is_metric(self, tol: float = 1e-9) -> bool:
        """Whether ``setup(p, q) <= setup(p, r) + duration(r) + setup(r, q)`` for
        every arm and task triple (initial pose included). Travel times obey
        it; the exact search relies on it. O(A T^3): small problems only."""
        p = self.problem
        if self.zero:
            return True
        for a in range(p.n_arms):
            modes = np.flatnonzero(p.mode_arm == a)
            tasks = p.mode_task[modes]
            n = len(tasks)
            if n < 2:
                continue
            dur = p.mode_duration[modes]
            S = np.array([self.row(a, int(q))[tasks] for q in tasks])  # S[i, j]: t_i -> t_j
            init = self.row(a, -1)[tasks]
            via = (
                S[:, :, None] + dur[None, :, None] + S[None, :, :]
            )  # via[i, k, j]: t_i -> t_k -> t_j
            i, k, j = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
            distinct = (i != k) & (k != j) & (i != j)
            if np.any((S[:, None, :] > via + tol) & distinct):
                return False
            via0 = init[:, None] + dur[:, None] + S  # via0[k, j]: home -> t_k -> t_j
            if np.any((init[None, :] > via0 + tol) & ~np.eye(n, dtype=bool)):
                return False
        return True


class Setup:
    """Base class of setup-time models."""

    def bind(self, problem: ProblemView) -> BoundSetup:
        """The setup times of ``problem``, looked up and cached per row.

        Raises
        ------
        UsageError
            A subclass that does not say how (it must override this method).
        """
        raise UsageError(f"{type(self).__name__} does not implement Setup.bind")

    def kernel_data(self, problem: ProblemView) -> KernelSetup:
        """The setup times of ``problem`` for the placement kernel.

        This default reads the problem's cached rows (:meth:`BoundSetup.row`)
        into the compact table: for each arm, from its initial pose and from
        each task it can do, to each task it can do.

        Parameters
        ----------
        problem : ProblemView
            The problem this setup belongs to.

        Returns
        -------
        KernelSetup
        """
        tasks_of = np.asarray(problem.mode_task)

        def block(a: int, modes: IntArray) -> FloatArray:
            tasks = tasks_of[modes]
            rows = [problem.setup_row(a, int(prev))[tasks] for prev in (-1, *tasks.tolist())]
            return np.array(rows, dtype=float)

        return _table_setup(problem, block)

    def to_dict(self) -> dict[str, Any]:
        """Plain data for :func:`setup_from_dict` (JSON-ready).

        Raises
        ------
        UsageError
            A setup that cannot be written as data.
        """
        raise UsageError(f"{type(self).__name__} cannot be written as data")


class NoSetup(Setup):
    """No setup time (e.g. FJSP)."""

    def bind(self, problem: ProblemView) -> BoundSetup:
        return BoundSetup(problem, lambda a, p: np.zeros(problem.n_tasks), zero=True)

    def kernel_data(self, problem: ProblemView) -> KernelSetup:
        """No setup: kind 0, nothing stored (see :meth:`Setup.kernel_data`)."""
        return _table_setup(problem, None)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "none"}


class MatrixSetup(Setup):
    """Setup times from a dense array ``times[arm, prev + 1, next]``, shape (A, T + 1, T)."""

    def __init__(self, times: Any) -> None:
        self.times = np.array(times, dtype=float)
        if self.times.ndim != 3 or self.times.shape[1] != self.times.shape[2] + 1:
            raise ValidationError(
                f"setup matrix must have shape (A, T + 1, T), got {self.times.shape}"
            )

    def bind(self, problem: ProblemView) -> BoundSetup:
        A, T = problem.n_arms, problem.n_tasks
        if self.times.shape != (A, T + 1, T):
            raise ValidationError(
                f"setup matrix must have shape {(A, T + 1, T)}, got {self.times.shape}"
            )
        return BoundSetup(problem, lambda a, p: self.times[a, p + 1])

    def kernel_data(self, problem: ProblemView) -> KernelSetup:
        """The matrix entries the arms can use (see :meth:`Setup.kernel_data`)."""
        tasks_of = np.asarray(problem.mode_task)

        def block(a: int, modes: IntArray) -> FloatArray:
            tasks = tasks_of[modes]
            out: FloatArray = self.times[a][np.concatenate([[0], tasks + 1])][:, tasks]
            return out

        return _table_setup(problem, block)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "matrix", "times": self.times.tolist()}


class TravelSetup(Setup):
    """Travel time = ``base[a] + distance(end of prev, start of next) / speed[a]``.

    Parameters
    ----------
    start, end : (M, 3) float, metres
        Where each mode starts and ends (tool point, cell frame).
    home : (A, 3) float, metres
        Each arm's initial pose (``prev = -1``).
    speed : (A,) float, m/s
    base : (A,) float, seconds
        Fixed time of every move (acceleration, settling).
    metric : {"euclidean", "manhattan"}
        Straight-line (interpolated) or per-axis (Cartesian) travel (S1.9).
    """

    def __init__(
        self,
        start: Any,
        end: Any,
        home: Any,
        speed: Any = 1.0,
        base: Any = 0.0,
        metric: Literal["euclidean", "manhattan"] = "euclidean",
    ) -> None:
        self.start = np.asarray(start, dtype=float)
        self.end = np.asarray(end, dtype=float)
        self.home = np.asarray(home, dtype=float)
        self.speed = np.atleast_1d(np.asarray(speed, dtype=float))
        self.base = np.atleast_1d(np.asarray(base, dtype=float))
        if metric not in ("euclidean", "manhattan"):
            raise ValidationError(f"metric must be 'euclidean' or 'manhattan', not {metric!r}")
        self.metric = metric

    def bind(self, problem: ProblemView) -> BoundSetup:
        A, M = problem.n_arms, problem.n_modes
        if self.start.shape != (M, 3) or self.end.shape != (M, 3):
            raise ValidationError(f"travel setup needs (M, 3) = {(M, 3)} start and end points")
        if self.home.shape != (A, 3):
            raise ValidationError(f"travel setup needs (A, 3) = {(A, 3)} home points")
        speed = np.broadcast_to(self.speed, (A,)) if self.speed.size in (1, A) else None
        base = np.broadcast_to(self.base, (A,)) if self.base.size in (1, A) else None
        if speed is None or base is None:
            raise ValidationError("travel setup speed and base must be scalars or one per arm")
        if np.any(~np.isfinite(speed) | (speed <= 0)):
            raise ValidationError("travel setup speeds must be finite and > 0")
        mode_of = problem.mode_of
        order = 1 if self.metric == "manhattan" else 2

        def row(a: int, prev: int) -> FloatArray:
            src = self.home[a] if prev < 0 else self.end[mode_of[a, prev]]
            modes = mode_of[a]
            pts = self.start[np.where(modes >= 0, modes, 0)]
            d = np.linalg.norm(pts - src, ord=order, axis=1)
            out: FloatArray = base[a] + d / speed[a]
            out[modes < 0] = math.inf
            return out

        def min_in(a: int) -> FloatArray:
            modes = np.flatnonzero(problem.mode_arm == a)
            best = np.full(problem.n_tasks, math.inf)
            if len(modes) == 0:
                return best
            dst = self.start[modes]  # (n, 3)
            src = np.vstack([self.home[a][None, :], self.end[modes]])  # (n + 1, 3)
            from scipy.spatial.distance import cdist

            d = cdist(dst, src, "cityblock" if order == 1 else "euclidean")  # (n, n + 1)
            d[np.arange(len(modes)), np.arange(len(modes)) + 1] = math.inf  # not from itself
            best[problem.mode_task[modes]] = base[a] + d.min(axis=1) / speed[a]
            return best

        start, end, home = self.start, self.end, self.home

        def one(a: int, prev: int, nxt: int) -> float:
            m = mode_of[a, nxt]
            if m < 0:
                return math.inf
            src = home[a] if prev < 0 else end[mode_of[a, prev]]
            dst = start[m]
            if order == 1:
                d = abs(dst[0] - src[0]) + abs(dst[1] - src[1]) + abs(dst[2] - src[2])
            else:
                d = math.sqrt(
                    (dst[0] - src[0]) ** 2 + (dst[1] - src[1]) ** 2 + (dst[2] - src[2]) ** 2
                )
            return float(base[a] + d / speed[a])

        return BoundSetup(problem, row, min_in_fn=min_in, time_fn=one)

    def kernel_data(self, problem: ProblemView) -> KernelSetup:
        """The points, speeds and fixed times packed for the kernel, which
        computes each travel time as :meth:`bind` does (kind 2 Euclidean, 3
        Manhattan; see :class:`KernelSetup`): no table to build or to read
        from memory."""
        A = problem.n_arms
        off, count, slot, _modes = _layout(problem)
        packed = np.concatenate(
            [
                self.start.ravel(),
                self.end.ravel(),
                self.home.ravel(),
                np.broadcast_to(self.speed, (A,)),
                np.broadcast_to(self.base, (A,)),
            ]
        ).astype(float)
        return KernelSetup(3 if self.metric == "manhattan" else 2, packed, off, count, slot)

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": "travel",
            "start": self.start.tolist(),
            "end": self.end.tolist(),
            "home": self.home.tolist(),
            "speed": self.speed.tolist(),
            "base": self.base.tolist(),
            "metric": self.metric,
        }


class FunctionSetup(Setup):
    """Setup times from ``fn(arm, prev, next) -> float`` (``prev = -1``: initial pose),
    computed on demand and cached a row at a time."""

    def __init__(self, fn: Callable[[int, int, int], float]) -> None:
        self.fn = fn

    def bind(self, problem: ProblemView) -> BoundSetup:
        mode_of = problem.mode_of

        def row(a: int, prev: int) -> FloatArray:
            out = np.full(problem.n_tasks, math.inf)
            for t in np.flatnonzero(mode_of[a] >= 0):
                out[t] = float(self.fn(a, prev, int(t)))
            return out

        return BoundSetup(problem, row)

    def to_dict(self) -> dict[str, Any]:
        raise UsageError("a FunctionSetup is code and cannot be written; use a MatrixSetup")


def setup_from_dict(data: Mapping[str, Any]) -> Setup:
    """Inverse of ``Setup.to_dict``."""
    kind = data.get("kind")
    if kind == "none":
        return NoSetup()
    if kind == "matrix":
        return MatrixSetup(data["times"])
    if kind == "travel":
        return TravelSetup(
            data["start"],
            data["end"],
            data["home"],
            data["speed"],
            data["base"],
            data.get("metric", "euclidean"),
        )
    raise ValidationError(f"unknown setup kind {kind!r}")
