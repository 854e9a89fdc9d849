"""A :class:`~scheduler.problem.Problem` compiled into the kernel's flat arrays.

:class:`Arrays` holds every per-problem array the numba code reads, bundled in
one typed tuple (numba compiles functions of named tuples of arrays);
:class:`State` is a partial schedule, :class:`Scratch` the work buffers of one
query and :class:`OracleTable` the answered blocking-oracle costs.
:class:`Instance` wraps them for Python callers; :func:`compile_problem` builds it
once per problem and caches it here (by identity, until the problem is collected), so the
problem module never imports the kernel.

Timelines are flat: resource ``r`` (exclusive zone ``z``: ``r = z``; moves in
shared zone ``z``: ``r = Z + z``; tool ``k``: ``r = 2 Z + k``, see
:mod:`scheduler.timing`) owns the slice ``res_lo[r] : res_lo[r] + res_n[r]``
of ``tl_s``/``tl_e``/``tl_own``/``tl_task``, sorted by start. Arm ``a``'s
tasks are ``arm_t[arm_lo[a] : arm_lo[a] + arm_n[a]]``, sorted by start.
"""

from __future__ import annotations

import bisect
import weakref
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from multiarm.errors import UsageError, ValidationError
from multiarm.types import BoolArray, FloatArray, IntArray
from scheduler.kernel._jit import INF
from scheduler.kernel.place import _commit, _commit_all, _earliest, _oracle_put, _query
from scheduler.setup import KernelSetup

if TYPE_CHECKING:
    from scheduler.problem import Problem

__all__ = [
    "Arrays",
    "Ctx",
    "Instance",
    "OracleTable",
    "Scratch",
    "State",
    "compile_problem",
]


def _a(x: Any, dtype: Any) -> Any:
    """A C-contiguous, writeable array of ``dtype`` (one numba type per field)."""
    return np.require(np.asarray(x, dtype=dtype), dtype=dtype, requirements=["C", "W"])


class Arrays(NamedTuple):
    """Every array of a compiled problem (read-only for the kernel).

    Counts: A arms, T tasks, M modes, R = 2 Z + K resources. ``*_ptr`` arrays
    are CSR offsets into the matching value arrays.

    Attributes
    ----------
    mode_arm, mode_task : (M,) int64
    mode_dur : (M,) float64, seconds
    mode_of : (A, T) int64, the mode of (arm, task) or -1
    release : (T,) float64, seconds
    avail : (A,) float64, seconds: when each arm becomes available
    pred_ptr, pred_idx, succ_ptr, succ_idx : int64, predecessors and successors
    tm_ptr, tm_idx : int64, the modes of each task
    rp_ptr, rp_res, rp_s, rp_e : rigid pieces of each mode (no waits):
        resource and offsets from the start
    seg_ptr, seg_len : each mode's segments between borders, lengths
    segp_ptr, sp_res, sp_s, sp_e : each segment's pieces, offsets from its start
    stand_ptr, st_res, st_origin : resources held while waiting at a border
        and the segment where holding them began
    tool_ptr, tool_res : each mode's tools
    ex_ptr, ex_res, ex_s, ex_e, ex_move : each mode's merged windows
    ex_b0, ex_b1 : per window, how many of its mode's borders are ``<= s``
        and ``< e`` (the waits before it start and end are prefix sums)
    bd_ptr, bd_val : each mode's borders (offsets, seconds)
    start_ptr, start_res : each arm's exclusive start zones
    res_lo : (R,) int64, each resource's slice of the timelines
    arm_lo : (A,) int64, each arm's slice of ``arm_t``
    no_lb : (A,) float64, -inf (no per-arm lower bound)
    all_modes : (M,) bool, True
    su : KernelSetup, the setup times (:meth:`scheduler.setup.Setup.kernel_data`)
    """

    mode_arm: IntArray
    mode_task: IntArray
    mode_dur: FloatArray
    mode_of: IntArray
    release: FloatArray
    avail: FloatArray
    pred_ptr: IntArray
    pred_idx: IntArray
    succ_ptr: IntArray
    succ_idx: IntArray
    tm_ptr: IntArray
    tm_idx: IntArray
    rp_ptr: IntArray
    rp_res: IntArray
    rp_s: FloatArray
    rp_e: FloatArray
    seg_ptr: IntArray
    seg_len: FloatArray
    segp_ptr: IntArray
    sp_res: IntArray
    sp_s: FloatArray
    sp_e: FloatArray
    stand_ptr: IntArray
    st_res: IntArray
    st_origin: IntArray
    tool_ptr: IntArray
    tool_res: IntArray
    ex_ptr: IntArray
    ex_res: IntArray
    ex_s: FloatArray
    ex_e: FloatArray
    ex_move: BoolArray
    ex_b0: IntArray
    ex_b1: IntArray
    bd_ptr: IntArray
    bd_val: FloatArray
    start_ptr: IntArray
    start_res: IntArray
    res_lo: IntArray
    arm_lo: IntArray
    no_lb: FloatArray
    all_modes: BoolArray
    su: KernelSetup


class State(NamedTuple):
    """A partial schedule: flat timelines and the placed tasks (arrays, mutated in place).

    Attributes
    ----------
    tl_s, tl_e : float64, interval starts and ends on the resource timelines
    tl_own, tl_task : int64, the arm and task of each interval
    res_n : (R,) int64, intervals per resource
    arm_t : int64, each arm's tasks in start order; ``arm_n`` (A,) how many
    t_start, t_end : (T,) float64, NaN while unplaced
    t_mode : (T,) int64, -1 while unplaced
    t_last : (1,) float64, the latest start so far (chronological decoding)
    t_waits : (T, max borders) float64, the waits at each task's borders
    """

    tl_s: FloatArray
    tl_e: FloatArray
    tl_own: IntArray
    tl_task: IntArray
    res_n: IntArray
    arm_t: IntArray
    arm_n: IntArray
    t_start: FloatArray
    t_end: FloatArray
    t_mode: IntArray
    t_last: FloatArray
    t_waits: FloatArray

    def copy(self) -> State:
        """An independent copy (every array copied).

        Returns
        -------
        State
        """
        return State._make(np.array(x, copy=True) for x in self)


class Ctx(NamedTuple):
    """What one decode may change: overridden releases, per-arm lower bounds,
    allowed modes, and the flags (chronological, waits at borders, blocking oracle).

    Attributes
    ----------
    release : (T,) float64, seconds
    arm_lb : (A,) float64, seconds (-inf: none)
    allowed : (M,) bool
    chrono, waits, blocking : bool
    """

    release: FloatArray
    arm_lb: FloatArray
    allowed: BoolArray
    chrono: bool
    waits: bool
    blocking: bool


class Scratch(NamedTuple):
    """Work buffers of one instance: waits of the last query (``w``), segment
    starts (``tau``), the best waits so far (``best_w``), the earliest start
    of each segment (``floor``), the waits of another placement of the same
    query (``w2``), the prefix sums of the waits a placement records
    (``cw``), all float64."""

    w: FloatArray
    tau: FloatArray
    best_w: FloatArray
    floor: FloatArray
    w2: FloatArray
    cw: FloatArray


class OracleTable(NamedTuple):
    """Answered blocking-oracle costs, read by the compiled decoders.

    A hash table (open addressing, linear probing, at most half full): the
    answer for mode ``m`` with an arm parked at pose column ``c`` is stored
    under key ``m * (M + A) + c``, where ``c = mode_of[b, task]`` when arm
    ``b`` is parked at the end pose of ``task`` and ``c = M + b`` at its
    initial pose. Memory grows with the answers, not with M x A x T. A
    decoder that needs unknown costs lists them in ``miss[:miss_n[0]]`` as
    (mode, column) rows and returns; Python asks the oracle, stores the
    answers and decodes again.

    Attributes
    ----------
    keys : (S,) int64, -1 where empty; S a power of two
    vals : (S,) float64, seconds (inf: no detour)
    fill : (1,) int64, how many keys are stored
    miss : (cap, 2) int64
    miss_n : (1,) int64
    """

    keys: IntArray
    vals: FloatArray
    fill: IntArray
    miss: IntArray
    miss_n: IntArray


def _oracle_table(size: int, miss: IntArray, miss_n: IntArray) -> OracleTable:
    return OracleTable(
        np.full(size, -1, dtype=np.int64), np.zeros(size), np.zeros(1, dtype=np.int64), miss, miss_n
    )


def _compile(p: Problem) -> tuple[Arrays, int, int, int]:
    """The arrays of ``p``, the timeline and arm-slot sizes and the most borders of a mode."""
    A, T, M, Z, K = p.n_arms, p.n_tasks, p.n_modes, p.n_zones, p.n_tools
    R = 2 * Z + K
    shapes = p.shapes
    i64, f64 = np.int64, np.float64

    def csr(rows: Any) -> tuple[IntArray, IntArray]:
        rows = list(rows)
        ptr = np.zeros(len(rows) + 1, dtype=i64)
        ptr[1:] = np.cumsum([len(r) for r in rows])
        return ptr, _a([x for r in rows for x in r], i64)

    pred_ptr, pred_idx = csr(p.task_preds)
    succ_ptr, succ_idx = csr(p.task_succs)
    tm_ptr, tm_idx = csr(p.task_modes)
    rp_res, rp_s, rp_e, rp_ptr = [], [], [], [0]
    ex_res, ex_s, ex_e, ex_mv, ex_ptr = [], [], [], [], [0]
    ex_b0: list[int] = []
    ex_b1: list[int] = []
    bd_val: list[float] = []
    bd_ptr = [0]
    tool_res, tool_ptr = [], [0]
    seg_len, seg_ptr = [], [0]
    sp_res, sp_s, sp_e, segp_ptr = [], [], [], [0]
    st_res, st_origin, stand_ptr = [], [], [0]
    cap = np.zeros(R, dtype=i64)
    per_task_cap = np.zeros((T, R), dtype=i64)
    for m in range(M):
        sh = shapes[m]
        d = sh.duration
        for r, s, e in sh.exclusive:
            rp_res.append(r)
            rp_s.append(s)
            rp_e.append(e)
            ex_res.append(r)
            ex_s.append(s)
            ex_e.append(e)
            ex_mv.append(False)
        for r, s, e in sh.moves:
            rp_res.append(r)
            rp_s.append(s)
            rp_e.append(e)
            ex_res.append(r)
            ex_s.append(s)
            ex_e.append(e)
            ex_mv.append(True)
        for r in sh.tools:
            rp_res.append(r)
            rp_s.append(0.0)
            rp_e.append(d)
            tool_res.append(r)
        rp_ptr.append(len(rp_res))
        # borders increase: those <= s (and < e) are a prefix of them
        for q in range(ex_ptr[-1], len(ex_res)):
            ex_b0.append(bisect.bisect_right(sh.borders, ex_s[q]))
            ex_b1.append(bisect.bisect_left(sh.borders, ex_e[q]))
        ex_ptr.append(len(ex_res))
        tool_ptr.append(len(tool_res))
        bd_val.extend(sh.borders)
        bd_ptr.append(len(bd_val))
        # segments between borders, with their pieces and what is held while waiting
        P = [0.0, *sh.borders, d]
        for j in range(len(P) - 1):
            a0, a1 = P[j], P[j + 1]
            seg_len.append(a1 - a0)
            for r, s, e in (*sh.exclusive, *sh.moves):
                if s < a1 and e > a0:
                    sp_res.append(r)
                    sp_s.append(max(s, a0) - a0)
                    sp_e.append(min(e, a1) - a0)
            for r in sh.tools:
                sp_res.append(r)
                sp_s.append(0.0)
                sp_e.append(a1 - a0)
            segp_ptr.append(len(sp_res))
            if j > 0:
                for r, s, e in sh.exclusive:
                    if s < a0 < e:
                        st_res.append(r)
                        st_origin.append(P.index(s) if s in P else 0)
                for r in sh.tools:
                    st_res.append(r)
                    st_origin.append(0)
            stand_ptr.append(len(st_res))
        seg_ptr.append(len(seg_len))
        # how many intervals this mode can add per resource
        t = int(p.mode_task[m])
        counts = np.zeros(R, dtype=i64)
        for r, _s, _e in sh.exclusive:
            counts[r] += 1
        for r, s, e in sh.moves:
            counts[r] += 1 + sum(1 for b in sh.borders if s < b < e)
        for r in sh.tools:
            counts[r] += 1
        per_task_cap[t] = np.maximum(per_task_cap[t], counts)
    cap += per_task_cap.sum(axis=0)
    start_ptr = np.zeros(A + 1, dtype=i64)
    starts: list[int] = []
    for a in range(A):
        zs = [z for z in p.arm_start_zones[a] if p.zone_exclusive[z]]
        starts.extend(zs)
        start_ptr[a + 1] = len(starts)
        for z in zs:
            cap[z] += 1
    res_lo = np.zeros(R, dtype=i64)
    res_lo[1:] = np.cumsum(cap)[:-1]
    arm_cap = np.bincount(np.asarray(p.mode_arm, dtype=i64), minlength=A).astype(i64)
    arm_lo = np.zeros(A, dtype=i64)
    arm_lo[1:] = np.cumsum(arm_cap)[:-1]
    max_borders = int(max((len(shapes[m].borders) for m in range(M)), default=0))
    arrays = Arrays(
        mode_arm=_a(p.mode_arm, i64),
        mode_task=_a(p.mode_task, i64),
        mode_dur=_a(p.mode_duration, f64),
        mode_of=_a(p.mode_of, i64),
        release=_a(p.task_release, f64),
        avail=_a(p.arm_available, f64),
        pred_ptr=pred_ptr,
        pred_idx=pred_idx,
        succ_ptr=succ_ptr,
        succ_idx=succ_idx,
        tm_ptr=tm_ptr,
        tm_idx=tm_idx,
        rp_ptr=_a(rp_ptr, i64),
        rp_res=_a(rp_res, i64),
        rp_s=_a(rp_s, f64),
        rp_e=_a(rp_e, f64),
        seg_ptr=_a(seg_ptr, i64),
        seg_len=_a(seg_len, f64),
        segp_ptr=_a(segp_ptr, i64),
        sp_res=_a(sp_res, i64),
        sp_s=_a(sp_s, f64),
        sp_e=_a(sp_e, f64),
        stand_ptr=_a(stand_ptr, i64),
        st_res=_a(st_res, i64),
        st_origin=_a(st_origin, i64),
        tool_ptr=_a(tool_ptr, i64),
        tool_res=_a(tool_res, i64),
        ex_ptr=_a(ex_ptr, i64),
        ex_res=_a(ex_res, i64),
        ex_s=_a(ex_s, f64),
        ex_e=_a(ex_e, f64),
        ex_move=_a(ex_mv, np.bool_),
        ex_b0=_a(ex_b0, i64),
        ex_b1=_a(ex_b1, i64),
        bd_ptr=_a(bd_ptr, i64),
        bd_val=_a(bd_val, f64),
        start_ptr=start_ptr,
        start_res=_a(starts, i64),
        res_lo=res_lo,
        arm_lo=arm_lo,
        no_lb=np.full(A, -INF),
        all_modes=np.ones(M, dtype=np.bool_),
        su=p.setup.kernel_data(p),
    )
    return arrays, int(cap.sum()), int(arm_cap.sum()), max_borders


class Instance:
    """A problem compiled for the kernel; get it with :func:`compile_problem`.

    Parameters
    ----------
    problem : Problem

    Attributes
    ----------
    data : Arrays
        The compiled arrays (``arm_lo``, ``res_lo`` are also attributes).
    max_borders : int
        The most borders (wait points) of any mode.
    oracle : OracleTable
        Answered blocking-oracle costs (grows as answers come).

    Examples
    --------
    >>> from scheduler.generate import random_problem
    >>> p = random_problem(2, 5, 1, 0, seed=0)
    >>> inst = compile_problem(p)
    >>> inst is compile_problem(p), inst.data.mode_dur.shape == (p.n_modes,)
    (True, True)
    """

    def __init__(self, problem: Problem) -> None:
        self._problem = weakref.ref(problem)
        self.data, self.tl_size, self.arm_size, self.max_borders = _compile(problem)
        self.R = len(self.data.res_lo)
        self.arm_lo = self.data.arm_lo
        self.res_lo = self.data.res_lo
        self.n_tasks = problem.n_tasks
        self.n_arms = problem.n_arms
        nb = max(self.max_borders, 1)
        self.scratch = Scratch(
            np.zeros(nb),
            np.zeros(nb + 1),
            np.zeros(nb),
            np.zeros(nb + 1),
            np.zeros(nb),
            np.zeros(nb + 1),
        )
        self._empty: State | None = None
        A = problem.n_arms
        self._width = problem.n_modes + A
        per_task = int(np.diff(self.data.tm_ptr).max(initial=1))
        self.oracle = _oracle_table(
            64,
            np.zeros((max(per_task, 1) * max(A, 1), 2), dtype=np.int64),
            np.zeros(1, dtype=np.int64),
        )
        table = getattr(problem.blocking, "table", None)
        if callable(table):
            self.prefill_blocking(table())

    @property
    def problem(self) -> Problem:
        """The problem compiled (held weakly: the cache must not keep it alive).

        Raises
        ------
        UsageError
            The problem no longer exists.
        """
        p = self._problem()
        if p is None:
            raise UsageError("the problem of this compiled instance no longer exists")
        return p

    # ----------------------------------------------------------- oracle
    def _store(self, modes: IntArray, cols: IntArray, costs: FloatArray) -> None:
        """Store answers, growing the table to stay at most half full."""
        o = self.oracle
        need = int(o.fill[0]) + len(modes)
        if 2 * need > len(o.keys):
            size = len(o.keys)
            while 2 * need > size:
                size *= 2
            old = o.keys >= 0
            grown = _oracle_table(size, o.miss, o.miss_n)
            _oracle_put(grown.keys, grown.vals, grown.fill, o.keys[old], o.vals[old])
            self.oracle = o = grown
        keys = np.asarray(modes, dtype=np.int64) * self._width + np.asarray(cols, dtype=np.int64)
        _oracle_put(o.keys, o.vals, o.fill, keys, np.asarray(costs, dtype=np.float64))

    def known_blocking(self) -> int:
        """How many blocking-oracle answers are stored.

        Returns
        -------
        int
        """
        return int(self.oracle.fill[0])

    def pose_column(self, arm: int, pose_task: int) -> int:
        """Column of :attr:`oracle` for ``arm`` parked at the end of ``pose_task`` (-1: initial pose).

        Parameters
        ----------
        arm, pose_task : int

        Returns
        -------
        int
        """
        if pose_task < 0:
            return int(self.data.mode_arm.shape[0] + arm)
        return int(self.data.mode_of[arm, pose_task])

    def prefill_blocking(self, costs: Any) -> int:
        """Store known blocking-oracle answers so the oracle is never asked for them.

        Parameters
        ----------
        costs : (M, A, T + 1) array of float, seconds
            ``costs[m, b, pose + 1]`` as :meth:`BlockingOracle.cost`
            ``(m, b, pose)`` returns (``pose = -1``: initial pose; column 0);
            NaN where unknown. Entries for poses an arm cannot take are ignored.

        Returns
        -------
        int
            How many answers were stored.

        Raises
        ------
        UsageError
            The problem has no blocking oracle.
        ValidationError
            Wrong shape, or a negative answer.
        """
        p = self.problem
        if p.blocking is None:
            raise UsageError(f"problem {p.name!r} has no blocking oracle to pre-fill")
        c = np.asarray(costs, dtype=float)
        M, A, T = p.n_modes, p.n_arms, p.n_tasks
        if c.shape != (M, A, T + 1):
            raise ValidationError(
                f"blocking pre-fill of problem {p.name!r}: expected shape {(M, A, T + 1)}, got {c.shape}"
            )
        if np.any(c < 0):
            m, b, q = np.argwhere(c < 0)[0]
            raise ValidationError(
                f"blocking pre-fill of problem {p.name!r}: negative cost {c[m, b, q]} "
                f"for mode {m}, arm {b}, pose {q - 1}"
            )
        cols = np.concatenate([M + np.arange(A)[:, None], self.data.mode_of], axis=1)  # (A, T + 1)
        known = ~np.isnan(c) & (cols[None, :, :] >= 0)
        m_idx, b_idx, q_idx = np.nonzero(known)
        self._store(m_idx, cols[b_idx, q_idx], c[known])
        return len(m_idx)

    def answer_misses(self) -> int:
        """Ask the problem's oracle the costs a decoder listed as missing.

        Returns
        -------
        int
            How many were asked.

        Raises
        ------
        ValidationError
            The oracle answered a negative or NaN cost.
        """
        p = self.problem
        oracle = p.blocking
        o = self.oracle
        n = int(o.miss_n[0])
        if oracle is None or n == 0:
            return 0
        M = p.n_modes
        asked = 0
        got_m, got_c, got_v = [], [], []
        seen = set()
        for m, col in o.miss[:n].tolist():
            if (m, col) in seen:
                continue
            seen.add((m, col))
            if col >= M:
                arm, pose = col - M, -1
            else:
                arm, pose = int(p.mode_arm[col]), int(p.mode_task[col])
            c = float(oracle.cost(m, arm, pose))
            if not c >= 0.0:
                raise ValidationError(
                    f"blocking oracle of problem {p.name!r} returned {c} for mode {m}, "
                    f"arm {p.arm_names[arm]!r}, pose {pose}: expected a cost >= 0 or inf"
                )
            got_m.append(m)
            got_c.append(col)
            got_v.append(c)
            asked += 1
        o.miss_n[0] = 0
        self._store(np.array(got_m), np.array(got_c), np.array(got_v, dtype=float))
        return asked

    # ------------------------------------------------------------ state
    def new_state(self) -> State:
        """An empty partial schedule (arms standing in their exclusive start zones).

        Returns
        -------
        State
        """
        if self._empty is None:
            self._empty = self._build_empty()
        return self._empty.copy()

    def layout(self) -> State:
        """The empty partial schedule itself, shared: for the shapes and
        dtypes of a state's fields (never mutate it; :meth:`new_state` gives
        a copy to work on).

        Returns
        -------
        State
        """
        if self._empty is None:
            self._empty = self._build_empty()
        return self._empty

    def _build_empty(self) -> State:
        """The empty partial schedule (built once; :meth:`new_state` copies it)."""
        T, A = self.n_tasks, self.n_arms
        n = max(self.tl_size, 1)
        st = State(
            tl_s=np.zeros(n),
            tl_e=np.zeros(n),
            tl_own=np.zeros(n, dtype=np.int64),
            tl_task=np.full(n, -1, dtype=np.int64),
            res_n=np.zeros(self.R, dtype=np.int64),
            arm_t=np.zeros(max(self.arm_size, 1), dtype=np.int64),
            arm_n=np.zeros(A, dtype=np.int64),
            t_start=np.full(T, np.nan),
            t_end=np.full(T, np.nan),
            t_mode=np.full(T, -1, dtype=np.int64),
            t_last=np.zeros(1),
            t_waits=np.zeros((T, max(self.max_borders, 1))),
        )
        d = self.data
        for a in range(A):
            for q in range(int(d.start_ptr[a]), int(d.start_ptr[a + 1])):
                r = int(d.start_res[q])
                i = int(d.res_lo[r] + st.res_n[r])
                st.tl_s[i], st.tl_e[i], st.tl_own[i] = 0.0, INF, a
                st.res_n[r] += 1
        return st

    def ctx(
        self,
        *,
        chrono: bool = False,
        waits: bool = True,
        blocking: bool = False,
        release: FloatArray | None = None,
        allowed: Any = None,
        arm_lb: FloatArray | None = None,
    ) -> Ctx:
        """The per-call options bundled for the kernel (defaults: the problem's).

        Parameters
        ----------
        chrono, waits, blocking : bool
        release : (T,) float or None
        allowed : (M,) bool or None
        arm_lb : (A,) float or None

        Returns
        -------
        Ctx
        """
        d = self.data
        return Ctx(
            d.release if release is None else _a(release, np.float64),
            d.no_lb if arm_lb is None else _a(arm_lb, np.float64),
            d.all_modes if allowed is None else _a(allowed, np.bool_),
            bool(chrono or blocking),
            bool(waits),
            bool(blocking),
        )

    # ------------------------------------------------ single placements
    def earliest(self, st: State, t: int, chrono: bool, release: FloatArray | None = None) -> float:
        """Earliest start of task ``t`` from releases, predecessors (and chronology).

        Parameters
        ----------
        st : State
        t : int
        chrono : bool
            No earlier than the latest start so far.
        release : (T,) float or None
            Overridden release times.

        Returns
        -------
        float
            Seconds.
        """
        rel = self.data.release if release is None else _a(release, np.float64)
        return float(_earliest(self.data, st, t, chrono, rel))

    def query(
        self,
        st: State,
        t: int,
        m: int,
        S0: float,
        *,
        chrono: bool = False,
        waits: bool = True,
        extra: float = 0.0,
        arm_lb: FloatArray | None = None,
    ) -> tuple[float, float, int, FloatArray]:
        """Earliest placement of task ``t`` in mode ``m`` from ``S0``.

        Parameters
        ----------
        st : State
        t, m : int
        S0 : float
            Seconds.
        chrono : bool
            Only after the arm's last task.
        waits : bool
            Waits at borders allowed.
        extra : float
            Seconds added to the end (a detour), tools held through it.
        arm_lb : (A,) float or None

        Returns
        -------
        start, end : float
            ``inf`` when it cannot be placed.
        slot : int
            Position in the arm's sequence (-1: none).
        waits : (borders of m,) float
        """
        d = self.data
        lb = d.no_lb if arm_lb is None else _a(arm_lb, np.float64)
        S, end, k = _query(d, st, self.scratch, t, m, S0, chrono, waits, extra, lb)
        nb = int(d.bd_ptr[m + 1] - d.bd_ptr[m])
        return float(S), float(end), int(k), self.scratch.w[:nb].copy()

    def commit(
        self, st: State, t: int, m: int, S: float, end: float, k: int, waits: FloatArray
    ) -> None:
        """Record a placement returned by :meth:`query` (mutates ``st``).

        Parameters
        ----------
        st : State
        t, m : int
        S, end : float
            Seconds.
        k : int
            Slot in the arm's sequence.
        waits : (borders of m,) float
        """
        w = np.zeros(max(self.max_borders, 1))
        w[: len(waits)] = waits
        st.t_waits[t] = w
        _commit(self.data, st, t, m, S, end, k, w, self.scratch.cw)

    def commit_all(
        self,
        st: State,
        tasks: IntArray,
        modes: IntArray,
        starts: FloatArray,
        ends: FloatArray,
        waits: FloatArray,
    ) -> None:
        """Record placements in the given order, each task after its arm's
        tasks so far (:meth:`commit` at the arm's next slot, in one compiled
        call; mutates ``st``).

        Parameters
        ----------
        st : State
        tasks, modes : (n,) int
        starts, ends : (n,) float
            Seconds.
        waits : (n, max borders) float
            Row ``i``: the waits at the borders of ``modes[i]``, then zeros.
        """
        _commit_all(
            self.data,
            st,
            _a(tasks, np.int64),
            _a(modes, np.int64),
            _a(starts, np.float64),
            _a(ends, np.float64),
            _a(waits, np.float64),
            self.scratch.cw,
        )


_CACHE: dict[int, Instance] = {}
"""Compiled instances by ``id(problem)``; an entry leaves when its problem is
collected (keyed by identity: two equal problems are still two instances)."""


def compile_problem(problem: Problem) -> Instance:
    """The kernel's compiled :class:`Instance` of ``problem``, built once and cached.

    *Compiling* here turns a scheduling :class:`~scheduler.problem.Problem`
    into the kernel's flat arrays; ``workcell.compile_cell`` (a cell into a
    Problem) is the other compile of the package. Formerly ``compiled``.

    Parameters
    ----------
    problem : Problem

    Returns
    -------
    Instance

    Examples
    --------
    >>> from scheduler.generate import random_problem
    >>> p = random_problem(2, 4, 1, 0, seed=1)
    >>> compile_problem(p).n_tasks == p.n_tasks
    True
    """
    key = id(problem)
    inst = _CACHE.get(key)
    if inst is None or inst._problem() is not problem:
        inst = Instance(problem)
        _CACHE[key] = inst
        weakref.finalize(problem, _CACHE.pop, key, None)
    return inst
