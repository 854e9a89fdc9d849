# mypy: disallow-untyped-defs=False, disallow-incomplete-defs=False, disallow-untyped-calls=False
"""The critical chain of a complete kernel state, compiled.

The chain explains a schedule's makespan, last task first: each task could
not start (or pass a zone border) earlier because of another one, for a
reason

* ``PRED`` -- a predecessor ended exactly at its start;
* ``ARM`` -- the previous task on its arm ended exactly one setup before;
* ``RESOURCE`` -- a task of another arm released a zone (exclusive, or the
  moves of a shared zone) or a tool exactly where one of its intervals on
  that resource starts;
* ``RELEASE`` -- none of these: the chain starts here.

It reads only the state's timelines (the intervals each task holds on each
resource), never the problem's Python objects, so its cost does not grow
with the number of zone windows of a mode (a compiled cell's space grid
gives modes thousands). The local search
(:func:`scheduler.search.neighbours`) builds its moves on it.

Examples
--------
>>> import numpy as np
>>> from scheduler.generate import random_problem
>>> from scheduler.kernel import compile_problem, decode
>>> p = random_problem(3, 12, 2, 1, seed=0)
>>> inst = compile_problem(p)
>>> _code, st = decode(inst, np.arange(p.n_tasks), np.full(p.n_tasks, -1))
>>> chain = critical_chain(inst, st)
>>> chain[0][0] == int(np.argmax(st.t_end)), chain[-1][1]
(True, 'release')
"""

from __future__ import annotations

import numpy as np

from multiarm.types import IntArray
from scheduler.kernel._jit import njit
from scheduler.kernel.arrays import Instance, State
from scheduler.kernel.place import _setup

__all__ = [
    "ARM",
    "PRED",
    "REASONS",
    "RELEASE",
    "RESOURCE",
    "Reasons",
    "cheapest_slot",
    "critical_chain",
    "task_reasons",
]

PRED, ARM, RESOURCE, RELEASE = 0, 1, 2, 3
REASONS = ("pred", "arm", "resource", "release")
"""Reason codes as the names :func:`critical_chain` returns."""

TOL = 1e-6
"""Two times closer than this (seconds) meet."""


@njit(cache=True)
def _index(st, n_res, res_lo, T):
    """Per task, its intervals on the timelines (CSR over tasks): resource and slot."""
    count = np.zeros(T + 1, dtype=np.int64)
    for r in range(n_res):
        lo = res_lo[r]
        for k in range(st.res_n[r]):
            x = st.tl_task[lo + k]
            if x >= 0:
                count[x + 1] += 1
    for t in range(T):
        count[t + 1] += count[t]
    fill = count[:-1].copy()
    own_r = np.empty(count[T], dtype=np.int64)
    own_k = np.empty(count[T], dtype=np.int64)
    for r in range(n_res):
        lo = res_lo[r]
        for k in range(st.res_n[r]):
            x = st.tl_task[lo + k]
            if x >= 0:
                own_r[fill[x]] = r
                own_k[fill[x]] = lo + k
                fill[x] += 1
    return count, own_r, own_k


@njit(cache=True)
def _prev_on_arm(st, arm_lo, n_arms, T):
    """Per task, the task before it on its arm (-1: the first)."""
    prev = np.full(T, -1, dtype=np.int64)
    for a in range(n_arms):
        lo = arm_lo[a]
        for i in range(1, st.arm_n[a]):
            prev[st.arm_t[lo + i]] = st.arm_t[lo + i - 1]
    return prev


@njit(cache=True)
def _sorted_ends(st, n_res, res_lo):
    """Per resource, whether its intervals' ends are in order too (then the
    ones meeting a start are found by bisection)."""
    out = np.ones(n_res, dtype=np.bool_)
    for r in range(n_res):
        lo = res_lo[r]
        for k in range(lo + 1, lo + st.res_n[r]):
            if st.tl_e[k] < st.tl_e[k - 1]:
                out[r] = False
                break
    return out


@njit(cache=True)
def _reasons(d, st, t, prev, ptr, own_r, own_k, ordered, tol, out_kind, out_by):
    """Every reason why ``t`` starts when it does (module docstring); their count.
    ``ordered`` (:func:`_sorted_ends`) lets the scan of a timeline start at
    the first end that can meet (the same reasons, in the same order)."""
    n = 0
    S = st.t_start[t]
    m = st.t_mode[t]
    a = d.mode_arm[m]
    for q in range(d.pred_ptr[t], d.pred_ptr[t + 1]):
        x = d.pred_idx[q]
        if abs(st.t_end[x] - S) <= tol:
            out_kind[n] = 0
            out_by[n] = x
            n += 1
    x = prev[t]
    if x >= 0:
        su = d.su
        setup = _setup(
            su.kind, su.table, su.arm_off, su.arm_count, su.mode_slot, d.mode_of, a, x, t
        )
        if abs(st.t_end[x] + setup - S) <= tol:
            out_kind[n] = 1
            out_by[n] = x
            n += 1
    for i in range(ptr[t], ptr[t + 1]):
        r = own_r[i]
        s = st.tl_s[own_k[i]]
        lo = d.res_lo[r]
        hi = lo + st.res_n[r]
        first = lo
        if ordered[r]:
            # the first end >= s - tol (the scan below skips the earlier ones):
            # at or before t's own interval (it ends after s), so a few steps
            # back from it find the first one, as a bisection would
            first = own_k[i]
            while first > lo and st.tl_e[first - 1] >= s - tol:
                first -= 1
        # the scan stops at the first end past the start
        for k in range(first, hi):
            e = st.tl_e[k]
            if e > s + tol:
                break
            if e >= s - tol:
                y = st.tl_task[k]
                if y >= 0 and y != t and d.mode_arm[st.t_mode[y]] != a:
                    out_kind[n] = 2
                    out_by[n] = y
                    n += 1
    return n


@njit(cache=True)
def _reason_space(st, own_k):
    """Buffers (kinds, tasks) for :func:`_reasons`: room for every reason of any task."""
    T = st.t_start.shape[0]
    cap = T + 1 + own_k.shape[0] + st.tl_task.shape[0]
    return np.empty(cap, dtype=np.int64), np.empty(cap, dtype=np.int64)


@njit(cache=True)
def _chain(d, st, u, tol):
    """The chain from the task that ends last (module docstring): tasks,
    reason codes and the tasks they wait for, as arrays of the chain's length.
    ``u`` (T,) uniform draws pick among several reasons (zeros: the first)."""
    T = st.t_start.shape[0]
    n_res = d.res_lo.shape[0]
    ptr, own_r, own_k = _index(st, n_res, d.res_lo, T)
    prev = _prev_on_arm(st, d.arm_lo, d.arm_lo.shape[0], T)
    ordered = _sorted_ends(st, n_res, d.res_lo)
    kind, by = _reason_space(st, own_k)
    return _chain_from(d, st, u, tol, ptr, own_r, own_k, prev, ordered, kind, by)


@njit(cache=True)
def _chain_from(d, st, u, tol, ptr, own_r, own_k, prev, ordered, kind, by):
    """:func:`_chain` with the state's index (:func:`_index`,
    :func:`_prev_on_arm`, :func:`_sorted_ends`) and the reason buffers given."""
    T = st.t_start.shape[0]
    c_t = np.empty(T, dtype=np.int64)
    c_kind = np.empty(T, dtype=np.int64)
    c_by = np.empty(T, dtype=np.int64)
    seen = np.zeros(T, dtype=np.bool_)
    t = 0
    for i in range(T):
        if st.t_end[i] > st.t_end[t]:
            t = i
    n = 0
    while not seen[t]:
        seen[t] = True
        k = _reasons(d, st, t, prev, ptr, own_r, own_k, ordered, tol, kind, by)
        c_t[n] = t
        if k == 0:
            c_kind[n] = 3
            c_by[n] = -1
            n += 1
            break
        j = 0
        if k > 1:
            j = min(int(u[n] * k), k - 1)
        c_kind[n] = kind[j]
        c_by[n] = by[j]
        n += 1
        t = by[j]
    return c_t[:n], c_kind[:n], c_by[:n]


def critical_chain(
    inst: Instance, st: State, rng: np.random.Generator | None = None, tol: float = TOL
) -> list[tuple[int, str, int]]:
    """The chain that explains the makespan of a complete state, last task first.

    Parameters
    ----------
    inst : Instance
    st : State
        Every task placed.
    rng : numpy.random.Generator or None
        Picks among several reasons at random; None: the first (predecessors,
        then the arm, then resources in resource order).
    tol : float
        Seconds within which two times meet.

    Returns
    -------
    list of (task, reason, by)
        ``reason`` is ``"pred"``, ``"arm"``, ``"resource"`` or ``"release"``
        (where the chain starts; ``by = -1``).
    """
    T = len(st.t_start)
    if T == 0:
        return []
    u = rng.random(T) if rng is not None else np.zeros(T)
    ts, kinds, bys = _chain(inst.data, st, u, float(tol))
    return [
        (int(t), REASONS[int(k)], int(b))
        for t, k, b in zip(ts.tolist(), kinds.tolist(), bys.tolist(), strict=True)
    ]


class Reasons:
    """:func:`task_reasons` for many tasks of one complete state: the state's
    index of intervals is built once (a call then costs only the task's own
    intervals, where :func:`task_reasons` reads the whole state).

    Parameters
    ----------
    inst : Instance
    st : State
        Every task placed; not changed while this is used.
    tol : float
    """

    def __init__(self, inst: Instance, st: State, tol: float = TOL) -> None:
        T = len(st.t_start)
        d = inst.data
        self._d = d
        self._st = st
        self._tol = float(tol)
        self._ptr, self._own_r, self._own_k = _index(st, d.res_lo.shape[0], d.res_lo, T)
        self._prev = _prev_on_arm(st, d.arm_lo, d.arm_lo.shape[0], T)
        self._ordered = _sorted_ends(st, d.res_lo.shape[0], d.res_lo)
        cap = T + 1 + len(self._own_k) + len(st.tl_task)
        self._kind: IntArray = np.empty(cap, dtype=np.int64)
        self._by: IntArray = np.empty(cap, dtype=np.int64)

    def __call__(self, t: int) -> list[tuple[str, int]]:
        """Every reason why task ``t`` starts when it does: (reason, by)."""
        n = int(
            _reasons(
                self._d,
                self._st,
                int(t),
                self._prev,
                self._ptr,
                self._own_r,
                self._own_k,
                self._ordered,
                self._tol,
                self._kind,
                self._by,
            )
        )
        return [(REASONS[int(self._kind[i])], int(self._by[i])) for i in range(n)]


def task_reasons(inst: Instance, st: State, t: int, tol: float = TOL) -> list[tuple[str, int]]:
    """Every reason why task ``t`` of a complete state starts when it does.

    Parameters
    ----------
    inst : Instance
    st : State
    t : int
    tol : float

    Returns
    -------
    list of (reason, by)
    """
    T = len(st.t_start)
    d = inst.data
    ptr, own_r, own_k = _index(st, d.res_lo.shape[0], d.res_lo, T)
    prev = _prev_on_arm(st, d.arm_lo, d.arm_lo.shape[0], T)
    ordered = _sorted_ends(st, d.res_lo.shape[0], d.res_lo)
    cap = T + 1 + len(own_k) + len(st.tl_task)
    kind: IntArray = np.empty(cap, dtype=np.int64)
    by: IntArray = np.empty(cap, dtype=np.int64)
    n = int(_reasons(d, st, int(t), prev, ptr, own_r, own_k, ordered, float(tol), kind, by))
    return [(REASONS[int(kind[i])], int(by[i])) for i in range(n)]


@njit(cache=True)
def _cheapest_slot(d, a, t, seq, lo, hi):
    """:func:`cheapest_slot`, compiled."""
    su = d.su
    n = seq.shape[0]
    if lo < 0:
        lo = 0
    if hi > n:
        hi = n
    best_k = lo
    best = np.inf
    for k in range(lo, hi + 1):
        pre = seq[k - 1] if k > 0 else -1
        add = _setup(
            su.kind, su.table, su.arm_off, su.arm_count, su.mode_slot, d.mode_of, a, pre, t
        )
        if k < n:
            post = seq[k]
            add += _setup(
                su.kind, su.table, su.arm_off, su.arm_count, su.mode_slot, d.mode_of, a, t, post
            )
            add -= _setup(
                su.kind, su.table, su.arm_off, su.arm_count, su.mode_slot, d.mode_of, a, pre, post
            )
        if add < best - 1e-12:
            best_k = k
            best = add
    return best_k


def cheapest_slot(inst: Instance, arm: int, t: int, seq: IntArray, lo: int, hi: int) -> int:
    """Where inserting task ``t`` into arm ``arm``'s sequence adds the least travel.

    Parameters
    ----------
    inst : Instance
    arm : int
    t : int
        A task ``arm`` can do, not in ``seq``.
    seq : (n,) int
        The arm's tasks in order.
    lo, hi : int
        The places tried (``k``: before ``seq[k]``; ``n``: at the end),
        clipped to ``0..n``.

    Returns
    -------
    int
        The first place of least added setup time (setup into ``t``, plus
        out of it into the next task, minus the setup it replaces).
    """
    return int(_cheapest_slot(inst.data, int(arm), int(t), seq, int(lo), int(hi)))
