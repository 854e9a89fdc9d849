# mypy: disallow-untyped-defs=False, disallow-incomplete-defs=False, disallow-untyped-calls=False
"""The local search's moves around a critical chain, compiled (numba).

:func:`scheduler.search.neighbours` explains a decoded schedule's makespan
by its critical chain (:mod:`scheduler.kernel.critical`), continued through
the list when decoding is chronological (a task held back only by the task
before it in the list: reason ``LIST``), and proposes moves on it:

* ``MODE`` -- a task of the chain (or the task that held it on a zone or
  tool) in another allowed mode;
* ``BEFORE`` -- a task moved just before the task that held it up (arm,
  resource or list), where precedence allows;
* ``AFTER`` -- that task moved just after it, where precedence allows.

Everything runs on arrays: the state, the list and its positions, the
current modes, a mask of frozen tasks and of allowed modes. The random
choices (which reason of several, the shuffle of the moves) are drawn from
the caller's :class:`numpy.random.Generator` in the same order and with the
same calls as the reference written in Python (``tests/scheduler/
moves_reference.py``), so a seed gives the same moves either way.

Examples
--------
>>> import numpy as np
>>> from scheduler.generate import random_problem
>>> from scheduler.kernel import compile_problem, decode
>>> p = random_problem(3, 12, 2, 1, seed=0)
>>> inst = compile_problem(p)
>>> order = np.arange(p.n_tasks)
>>> _code, st = decode(inst, order, np.full(p.n_tasks, -1))
>>> kind, a, b = neighbour_moves(inst, st, order, st.t_mode.copy(),
...                              np.random.default_rng(0))
>>> len(kind) == len(a) == len(b) and set(kind.tolist()) <= {MODE, BEFORE, AFTER}
True
"""

from __future__ import annotations

import numpy as np

from multiarm.types import BoolArray, FloatArray, IntArray
from scheduler import _ctrl_c
from scheduler.kernel._jit import njit
from scheduler.kernel.arrays import Instance, State
from scheduler.kernel.critical import (
    TOL,
    _chain_from,
    _index,
    _prev_on_arm,
    _reason_space,
    _reasons,
    _sorted_ends,
)

__all__ = ["AFTER", "BEFORE", "LIST", "MODE", "chrono_extend", "neighbour_moves"]

LIST = 4
"""Reason code of a chain link held back by the list (after the codes of
:mod:`scheduler.kernel.critical`: pred 0, arm 1, resource 2, release 3)."""

MODE, BEFORE, AFTER = 0, 1, 2
"""Move kinds: ``(MODE, t, m)``, ``(BEFORE, t, x)`` (t just before x),
``(AFTER, x, t)`` (x just after t)."""


@njit(cache=True)
def _extend(d, st, order, pos, release, c_t, c_kind, c_by, rng, links, tol):
    """The chain ``c_*`` continued through the list (module docstring):
    where it ends at a release of a task that starts later than its release,
    held by the task before it in the list starting at the same time, that
    link becomes ``LIST`` and the chain goes on from there with that task's
    own reasons (several: one drawn with ``rng.integers``)."""
    ptr = np.zeros(1, dtype=np.int64)
    own_r = np.zeros(0, dtype=np.int64)
    own_k = np.zeros(0, dtype=np.int64)
    prev = np.zeros(0, dtype=np.int64)
    ordered = np.zeros(0, dtype=np.bool_)
    kind = np.zeros(0, dtype=np.int64)
    by = np.zeros(0, dtype=np.int64)
    return _extend_from(
        d,
        st,
        order,
        pos,
        release,
        c_t,
        c_kind,
        c_by,
        rng,
        links,
        tol,
        False,
        ptr,
        own_r,
        own_k,
        prev,
        ordered,
        kind,
        by,
    )


@njit(cache=True)
def _extend_from(
    d,
    st,
    order,
    pos,
    release,
    c_t,
    c_kind,
    c_by,
    rng,
    links,
    tol,
    built,
    ptr,
    own_r,
    own_k,
    prev,
    ordered,
    kind,
    by,
):
    """:func:`_extend`; with ``built`` the state's index and the reason
    buffers are given (else built at the first link through the list)."""
    T = st.t_start.shape[0]
    n0 = c_t.shape[0]
    cap = n0 + T + 1
    o_t = np.empty(cap, dtype=np.int64)
    o_kind = np.empty(cap, dtype=np.int64)
    o_by = np.empty(cap, dtype=np.int64)
    seen = np.zeros(T, dtype=np.bool_)
    for i in range(n0):
        o_t[i] = c_t[i]
        o_kind[i] = c_kind[i]
        o_by[i] = c_by[i]
        seen[c_t[i]] = True
    n = n0
    while n > 0 and o_kind[n - 1] == 3 and links > 0:
        t = o_t[n - 1]
        S = st.t_start[t]
        i = pos[t]
        if i <= 0 or release[t] + tol >= S:
            break
        x = order[i - 1]
        if abs(st.t_start[x] - S) > tol or seen[x]:
            break
        o_kind[n - 1] = LIST
        o_by[n - 1] = x
        links -= 1
        u = x
        exhausted = True
        while links > 0:
            seen[u] = True
            if not built:
                ptr, own_r, own_k = _index(st, d.res_lo.shape[0], d.res_lo, T)
                prev = _prev_on_arm(st, d.arm_lo, d.arm_lo.shape[0], T)
                ordered = _sorted_ends(st, d.res_lo.shape[0], d.res_lo)
                kind = np.empty(T + 1 + own_k.shape[0] + st.tl_task.shape[0], dtype=np.int64)
                by = np.empty(kind.shape[0], dtype=np.int64)
                built = True
            k = _reasons(d, st, u, prev, ptr, own_r, own_k, ordered, tol, kind, by)
            if k == 0:
                o_t[n] = u
                o_kind[n] = 3
                o_by[n] = -1
                n += 1
                exhausted = False
                break
            j = 0
            if k > 1:
                j = rng.integers(0, k)
            o_t[n] = u
            o_kind[n] = kind[j]
            o_by[n] = by[j]
            n += 1
            links -= 1
            if seen[by[j]]:
                exhausted = False
                break
            u = by[j]
        if exhausted:
            break
    return o_t[:n], o_kind[:n], o_by[:n]


@njit(cache=True)
def _moves(d, c_t, c_kind, c_by, pos, modes, frozen, allowed, rng):
    """The moves on the chain (module docstring), shuffled with
    ``rng.permutation``: kinds and their two operands."""
    n = c_t.shape[0]
    cap = 0
    for i in range(n):
        t = c_t[i]
        cap += d.tm_ptr[t + 1] - d.tm_ptr[t] + 2
        b = c_by[i]
        if b >= 0:
            cap += d.tm_ptr[b + 1] - d.tm_ptr[b]
    kind = np.empty(cap, dtype=np.int64)
    a1 = np.empty(cap, dtype=np.int64)
    a2 = np.empty(cap, dtype=np.int64)
    k = 0
    for i in range(n):
        t = c_t[i]
        if frozen[t]:
            continue
        for q in range(d.tm_ptr[t], d.tm_ptr[t + 1]):
            m = d.tm_idx[q]
            if m != modes[t] and allowed[m]:
                kind[k] = MODE
                a1[k] = t
                a2[k] = m
                k += 1
        r = c_kind[i]
        b = c_by[i]
        if (r == 1 or r == 2 or r == LIST) and b >= 0 and not frozen[b]:
            # t just before b: it comes after b now and its predecessors all before b
            it = pos[t]
            jb = pos[b]
            ok = it > jb
            if ok:
                for q in range(d.pred_ptr[t], d.pred_ptr[t + 1]):
                    if pos[d.pred_idx[q]] >= jb:
                        ok = False
                        break
            if ok:
                kind[k] = BEFORE
                a1[k] = t
                a2[k] = b
                k += 1
            # b just after t: it comes before t now and its successors all after t
            ok = jb < it
            if ok:
                for q in range(d.succ_ptr[b], d.succ_ptr[b + 1]):
                    if pos[d.succ_idx[q]] <= it:
                        ok = False
                        break
            if ok:
                kind[k] = AFTER
                a1[k] = b
                a2[k] = t
                k += 1
            if r == 2:
                # or let the blocker go elsewhere
                for q in range(d.tm_ptr[b], d.tm_ptr[b + 1]):
                    m = d.tm_idx[q]
                    if m != modes[b] and allowed[m]:
                        kind[k] = MODE
                        a1[k] = b
                        a2[k] = m
                        k += 1
    idx = rng.permutation(k)
    return kind[idx], a1[idx], a2[idx]


@njit(cache=True)
def _neighbour_moves(d, st, order, modes, frozen, allowed, release, chrono, rng, tol):
    """:func:`neighbour_moves`, compiled: the chain (``rng.random(T)`` picks
    among reasons), its continuation through the list, the shuffled moves."""
    T = st.t_start.shape[0]
    u = rng.random(T)
    # the state's index, built once for the chain and its continuation
    n_res = d.res_lo.shape[0]
    ptr, own_r, own_k = _index(st, n_res, d.res_lo, T)
    prev = _prev_on_arm(st, d.arm_lo, d.arm_lo.shape[0], T)
    ordered = _sorted_ends(st, n_res, d.res_lo)
    kind, by = _reason_space(st, own_k)
    c_t, c_kind, c_by = _chain_from(d, st, u, tol, ptr, own_r, own_k, prev, ordered, kind, by)
    pos = np.full(T, -1, dtype=np.int64)
    for i in range(order.shape[0]):
        pos[order[i]] = i
    if chrono:
        c_t, c_kind, c_by = _extend_from(
            d,
            st,
            order,
            pos,
            release,
            c_t,
            c_kind,
            c_by,
            rng,
            T,
            tol,
            True,
            ptr,
            own_r,
            own_k,
            prev,
            ordered,
            kind,
            by,
        )
    return _moves(d, c_t, c_kind, c_by, pos, modes, frozen, allowed, rng)


def chrono_extend(
    inst: Instance,
    st: State,
    order: IntArray,
    pos: IntArray,
    chain: tuple[IntArray, IntArray, IntArray],
    rng: np.random.Generator,
    *,
    release: FloatArray | None = None,
    max_links: int | None = None,
    tol: float = TOL,
) -> tuple[IntArray, IntArray, IntArray]:
    """A critical chain continued through the list (chronological decoding).

    Parameters
    ----------
    inst : Instance
    st : State
        Every task of ``order`` placed.
    order : (n,) int
        The list decoded.
    pos : (T,) int
        Each task's position in ``order`` (-1: not in it).
    chain : (tasks, reason codes, by)
        The chain as arrays, last task first (``critical.PRED`` ... ``RELEASE``).
    rng : numpy.random.Generator
        Picks among several reasons.
    release : (T,) float or None
        The release times decoded with (default: the problem's).
    max_links : int or None
        The most links added (default: the number of tasks).
    tol : float

    Returns
    -------
    (tasks, reason codes, by)
        The chain, its last ``RELEASE`` link turned ``LIST`` where the list
        held that task, and continued.
    """
    d = inst.data
    rel = d.release if release is None else np.ascontiguousarray(release, dtype=np.float64)
    c_t, c_kind, c_by = (np.ascontiguousarray(x, dtype=np.int64) for x in chain)
    links = len(st.t_start) if max_links is None else int(max_links)
    with _ctrl_c.atomic():  # see neighbour_moves
        out: tuple[IntArray, IntArray, IntArray] = _extend(
            d,
            st,
            np.ascontiguousarray(order, dtype=np.int64),
            np.ascontiguousarray(pos, dtype=np.int64),
            rel,
            c_t,
            c_kind,
            c_by,
            rng,
            links,
            float(tol),
        )
    return out


def neighbour_moves(
    inst: Instance,
    st: State,
    order: IntArray,
    modes: IntArray,
    rng: np.random.Generator,
    *,
    chrono: bool = False,
    frozen: BoolArray | None = None,
    allowed: BoolArray | None = None,
    release: FloatArray | None = None,
    tol: float = TOL,
) -> tuple[IntArray, IntArray, IntArray]:
    """The shuffled moves around the critical chain of a decoded list.

    Parameters
    ----------
    inst : Instance
    st : State
        ``order`` decoded (every task placed).
    order : (n,) int
        The list.
    modes : (T,) int
        The current mode of each task.
    rng : numpy.random.Generator
        Draws ``random(T)``, then ``integers`` per choice among reasons on
        the continued chain, then one ``permutation``.
    chrono : bool
        Continue the chain through the list (chronological decoding).
    frozen : (T,) bool or None
        Tasks never moved (default: none).
    allowed : (M,) bool or None
        Modes that may be used (default: all).
    release : (T,) float or None
        The release times decoded with (default: the problem's).
    tol : float

    Returns
    -------
    kind, a, b : (k,) int
        ``(MODE, t, m)``, ``(BEFORE, t, x)`` or ``(AFTER, x, t)`` per move.
    """
    d = inst.data
    T = len(st.t_start)
    fr = np.zeros(T, dtype=np.bool_) if frozen is None else frozen
    # the call unpickles constants in Python for its Generator: a Ctrl-C
    # must not be raised in there (scheduler._ctrl_c.atomic)
    with _ctrl_c.atomic():
        out: tuple[IntArray, IntArray, IntArray] = _neighbour_moves(
            d,
            st,
            np.ascontiguousarray(order, dtype=np.int64),
            np.ascontiguousarray(modes, dtype=np.int64),
            fr,
            d.all_modes if allowed is None else allowed,
            d.release if release is None else release,
            bool(chrono),
            rng,
            float(tol),
        )
    return out
