# mypy: disallow-untyped-defs=False, disallow-incomplete-defs=False, disallow-untyped-calls=False
"""List decoding that resumes from a saved prefix (the local search's decoder).

A local-search move changes a list from some position on; every task before
it is placed exactly as before. :func:`decode_resume` decodes a list in
*chunks* of ``every`` positions and saves the partial schedule (the whole
:class:`~scheduler.kernel.arrays.State`) at each chunk boundary into a
:class:`Snaps` buffer; a later list that agrees with it (same tasks, same
modes) up to some position starts from the last boundary before it, so only
the changed suffix is placed again.

Chunked decoding is list decoding (:func:`scheduler.kernel.decode`) with one
difference: a task that cannot be placed yet (a zone held for good by an arm
still in its start zone, a parked arm with no detour) is retried at the end
of its chunk, then carried into the next chunk, rather than at the end of
the whole list. A boundary crossed with a task carried gets no snapshot.
Decoding the same list twice gives the same schedule, whichever snapshot it
started from.

Examples
--------
>>> import numpy as np
>>> from scheduler.generate import random_problem
>>> from scheduler.kernel import compile_problem, decode
>>> p = random_problem(3, 20, 2, 1, seed=0)
>>> inst = compile_problem(p)
>>> order = np.asarray(p.topological_order, dtype=np.int64)
>>> free = np.full(p.n_tasks, -1, dtype=np.int64)
>>> snaps = new_snaps(inst, len(order), every=5)
>>> code, st = decode_resume(inst, order, free, snaps, snaps, -1, every=5)
>>> code, bool(np.array_equal(st.t_start, decode(inst, order, free)[1].t_start))
(0, True)
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from multiarm.errors import UsageError
from multiarm.types import BoolArray, FloatArray, IntArray
from scheduler.kernel._jit import NO_REFCOUNT, njit
from scheduler.kernel.arrays import Ctx, Instance, State
from scheduler.kernel.passes import RESUME, _decode

__all__ = [
    "ResumeWork",
    "Snaps",
    "chunk_size",
    "copy_rows",
    "decode_resume",
    "new_flags",
    "new_snaps",
    "new_work",
    "restore",
    "resume_chrono",
]


class Snaps(NamedTuple):
    """Saved partial schedules: row ``k`` of each field is the
    :class:`~scheduler.kernel.arrays.State` field after the first ``k * every``
    positions of a list; ``ok[k]`` says whether row ``k`` holds one."""

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
    ok: BoolArray


def chunk_size(n: int) -> int:
    """The chunk length used for a list of ``n`` tasks (about ``sqrt(n)``).

    Parameters
    ----------
    n : int

    Returns
    -------
    int

    Examples
    --------
    >>> chunk_size(200)
    15
    """
    return max(4, math.isqrt(max(n, 1)) + 1)


def new_snaps(inst: Instance, n: int, every: int) -> Snaps:
    """An empty snapshot buffer for lists of ``n`` tasks in chunks of ``every``.

    Parameters
    ----------
    inst : Instance
    n : int
    every : int

    Returns
    -------
    Snaps
    """
    rows = n // max(every, 1) + 1
    st = inst.new_state()
    fields: list[Any] = [np.zeros((rows, *np.shape(x)), dtype=np.asarray(x).dtype) for x in st]
    fields.append(np.zeros(rows, dtype=np.bool_))
    return Snaps._make(fields)


@njit(cache=True)
def _save(st, sn, k):
    sn.tl_s[k] = st.tl_s
    sn.tl_e[k] = st.tl_e
    sn.tl_own[k] = st.tl_own
    sn.tl_task[k] = st.tl_task
    sn.res_n[k] = st.res_n
    sn.arm_t[k] = st.arm_t
    sn.arm_n[k] = st.arm_n
    sn.t_start[k] = st.t_start
    sn.t_end[k] = st.t_end
    sn.t_mode[k] = st.t_mode
    sn.t_last[k] = st.t_last
    sn.t_waits[k] = st.t_waits
    sn.ok[k] = True


@njit(cache=True)
def _load(sn, k, st):
    st.tl_s[:] = sn.tl_s[k]
    st.tl_e[:] = sn.tl_e[k]
    st.tl_own[:] = sn.tl_own[k]
    st.tl_task[:] = sn.tl_task[k]
    st.res_n[:] = sn.res_n[k]
    st.arm_t[:] = sn.arm_t[k]
    st.arm_n[:] = sn.arm_n[k]
    st.t_start[:] = sn.t_start[k]
    st.t_end[:] = sn.t_end[k]
    st.t_mode[:] = sn.t_mode[k]
    st.t_last[:] = sn.t_last[k]
    st.t_waits[:] = sn.t_waits[k]


@njit(cache=True)
def _copy_rows(src, dst, lo, hi):
    """Rows ``lo:hi`` of every field of ``src`` into ``dst``."""
    for k in range(lo, hi):
        dst.tl_s[k] = src.tl_s[k]
        dst.tl_e[k] = src.tl_e[k]
        dst.tl_own[k] = src.tl_own[k]
        dst.tl_task[k] = src.tl_task[k]
        dst.res_n[k] = src.res_n[k]
        dst.arm_t[k] = src.arm_t[k]
        dst.arm_n[k] = src.arm_n[k]
        dst.t_start[k] = src.t_start[k]
        dst.t_end[k] = src.t_end[k]
        dst.t_mode[k] = src.t_mode[k]
        dst.t_last[k] = src.t_last[k]
        dst.t_waits[k] = src.t_waits[k]
        dst.ok[k] = src.ok[k]


@njit(cache=True)
def _decode_chunks(
    d, st, cx, sc, ot, order, fixed, every, src, k_from, out, buf, outer, inner, states
):
    """Decode ``order`` in chunks (module docstring), from row ``k_from`` of
    ``src`` (-1: from ``st`` as given, saved as row 0), saving each boundary
    into ``out``. Without ``states`` only the flags ``out.ok`` are written
    and ``st`` already holds boundary ``k_from`` (:func:`restore`).
    ``outer`` = (next position, mid-chunk, carried, chunk length, started)
    and ``inner`` (the chunk's :func:`_decode` cursor) let a call stopped for
    missing oracle answers resume. Returns 0, -1 (some task could not be
    placed) or RESUME."""
    n_order = order.shape[0]
    if outer[4] == 0:
        outer[4] = 1
        if k_from >= 0:
            if states:
                _load(src, k_from, st)
            outer[0] = k_from * every
        else:
            if states:
                _save(st, out, 0)
            else:
                out.ok[0] = True
            outer[0] = 0
    while True:
        if outer[1] == 0:
            pos = outer[0]
            carry = outer[2]
            if pos >= n_order:
                return 0 if carry == 0 else -1
            m = min(every, n_order - pos)
            for i in range(m):
                buf[carry + i] = order[pos + i]
            inner[0] = carry + m
            inner[1] = 0
            inner[2] = 0
            inner[3] = 0
            outer[3] = carry + m
            outer[0] = pos + m
            outer[1] = 1
        code = _decode(d, st, cx, sc, ot, buf, fixed, inner)
        if code == RESUME:
            return RESUME
        outer[1] = 0
        if code == 0:
            outer[2] = 0
        else:
            outer[2] = outer[3] - (-(code + 1))
        pos = outer[0]
        if pos % every == 0:
            k = pos // every
            if outer[2] == 0:
                if states:
                    _save(st, out, k)
                else:
                    out.ok[k] = True
            else:
                out.ok[k] = False


def new_flags(inst: Instance, n: int, every: int) -> Snaps:
    """A snapshot buffer that holds only the flags (``ok``), no states:
    chronological decoding restores a boundary from the anchor's complete
    state instead (:func:`restore`).

    Parameters
    ----------
    inst : Instance
    n : int
    every : int

    Returns
    -------
    Snaps
        Every field but ``ok`` has no columns.
    """
    rows = n // max(every, 1) + 1
    fields: list[Any] = [
        np.zeros((rows, *(0 for _ in np.shape(x))), dtype=np.asarray(x).dtype)
        for x in inst.layout()
    ]
    fields.append(np.zeros(rows, dtype=np.bool_))
    return Snaps._make(fields)


@njit(cache=True, **NO_REFCOUNT)
def _restore(d, root, fin, keep, st, has):
    """``st`` := ``root`` plus the intervals of the tasks ``keep`` marks in
    ``fin`` (:func:`restore`); ``has`` (A,) bool is work space. Every field
    ``st`` is read by is written (it may hold anything before)."""
    A = d.arm_lo.shape[0]
    T = fin.t_start.shape[0]
    nb = fin.t_waits.shape[1]
    for a in range(A):
        has[a] = False
    last = root.t_last[0]
    for t in range(T):
        if keep[t]:
            st.t_start[t] = fin.t_start[t]
            st.t_end[t] = fin.t_end[t]
            st.t_mode[t] = fin.t_mode[t]
            for j in range(nb):
                st.t_waits[t, j] = fin.t_waits[t, j]
            has[d.mode_arm[fin.t_mode[t]]] = True
            if root.t_mode[t] < 0 and fin.t_start[t] > last:
                last = fin.t_start[t]
        else:
            st.t_start[t] = np.nan
            st.t_end[t] = np.nan
            st.t_mode[t] = -1
            for j in range(nb):
                st.t_waits[t, j] = 0.0
    st.t_last[0] = last
    for a in range(A):
        lo = d.arm_lo[a]
        n = 0
        for i in range(lo, lo + fin.arm_n[a]):
            x = fin.arm_t[i]
            if keep[x]:
                st.arm_t[lo + n] = x
                n += 1
        st.arm_n[a] = n
    for r in range(d.res_lo.shape[0]):
        lo = d.res_lo[r]
        n = 0
        j = lo
        for i in range(lo, lo + fin.res_n[r]):
            x = fin.tl_task[i]
            e = fin.tl_e[i]
            if x >= 0:
                if not keep[x]:
                    continue
            else:
                # a start zone: left where the arm's first task left it, or as
                # in the root while the arm has none (chronological decoding
                # moves it once, for the arm's first task)
                while root.tl_task[j] >= 0:
                    j += 1
                if not has[fin.tl_own[i]]:
                    e = root.tl_e[j]
                j += 1
            st.tl_s[lo + n] = fin.tl_s[i]
            st.tl_e[lo + n] = e
            st.tl_own[lo + n] = fin.tl_own[i]
            st.tl_task[lo + n] = x
            n += 1
        st.res_n[r] = n


@njit(cache=True, **NO_REFCOUNT)
def _first_change(order, fixed, ao, am):
    """The first position where ``order`` or its modes (``fixed``) differ
    from the anchor's (``ao``, ``am``); ``len(order)`` if none."""
    n = order.shape[0]
    for i in range(n):
        t = order[i]
        if t != ao[i] or fixed[t] != am[t]:
            return i
    return n


@njit(cache=True)
def _copy_state(src, dst):
    dst.tl_s[:] = src.tl_s
    dst.tl_e[:] = src.tl_e
    dst.tl_own[:] = src.tl_own
    dst.tl_task[:] = src.tl_task
    dst.res_n[:] = src.res_n
    dst.arm_t[:] = src.arm_t
    dst.arm_n[:] = src.arm_n
    dst.t_start[:] = src.t_start
    dst.t_end[:] = src.t_end
    dst.t_mode[:] = src.t_mode
    dst.t_last[:] = src.t_last
    dst.t_waits[:] = src.t_waits


@njit(cache=True)
def _resume_chrono(
    d, st, cx, sc, ot, root, fin, ao, am, order, fixed, every, src, out, work, buf, outer, inner
):
    """:func:`resume_chrono`, compiled: on the first entry (``outer[4] == 0``)
    the boundary to start from (``work.k[0]``: 1 if there is an anchor, in;
    the boundary, out) and ``st`` restored there; then :func:`_decode_chunks`
    (called again after missing oracle answers: it goes on where it stopped)."""
    if outer[4] == 0:
        k = -1
        if work.k[0] == 1:
            k = _first_change(order, fixed, ao, am) // every
            while k > 0 and not src.ok[k]:
                k -= 1
        if k >= 0:
            keep = work.keep
            for t in range(keep.shape[0]):
                keep[t] = root.t_mode[t] >= 0
            for i in range(k * every):
                keep[ao[i]] = True
            _restore(d, root, fin, keep, st, work.has)
        else:
            _copy_state(root, st)
        work.k[0] = k
    return _decode_chunks(
        d, st, cx, sc, ot, order, fixed, every, src, work.k[0], out, buf, outer, inner, False
    )


class ResumeWork(NamedTuple):
    """Work space of :func:`resume_chrono` (one per list length).

    Attributes
    ----------
    keep : (T,) bool
    has : (A,) bool
    k : (1,) int64, the boundary started from
    buf : (n + 1,) int64
    outer, inner : (5,) and (4,) int64, where a stopped pass resumes
    """

    keep: BoolArray
    has: BoolArray
    k: IntArray
    buf: IntArray
    outer: IntArray
    inner: IntArray


def new_work(inst: Instance, n: int) -> ResumeWork:
    """The work space of :func:`resume_chrono` for lists of ``n`` tasks.

    Parameters
    ----------
    inst : Instance
    n : int

    Returns
    -------
    ResumeWork
    """
    i64 = np.int64
    return ResumeWork(
        np.zeros(inst.n_tasks, dtype=np.bool_),
        np.zeros(inst.n_arms, dtype=np.bool_),
        np.zeros(1, dtype=i64),
        np.empty(n + 1, dtype=i64),
        np.zeros(5, dtype=i64),
        np.zeros(4, dtype=i64),
    )


def resume_chrono(
    inst: Instance,
    ctx: Ctx,
    root: State,
    anchor: tuple[State, IntArray, IntArray] | None,
    order: IntArray,
    fixed: IntArray,
    src: Snaps,
    out: Snaps,
    every: int,
    state: State,
    work: ResumeWork,
) -> tuple[int, int]:
    """Chronological chunked decoding of ``order`` that resumes from the
    anchor's complete state: the boundary before the first position where
    ``order`` or its modes differ from the anchor's, restored as
    :func:`restore` restores it, then :func:`decode_resume` from there (the
    same schedule as that pair of calls, in one compiled call).

    Parameters
    ----------
    inst : Instance
    ctx : Ctx
        Chronological (:meth:`Instance.ctx`).
    root : State
        The state every list is decoded from.
    anchor : (State, order, modes) or None
        The anchor's complete state, list and modes (None: decode from ``root``).
    order : (n,) int
    fixed : (T,) int
        The mode of each task (-1: chosen).
    src : Snaps
        The anchor's flags (:func:`new_flags`): which boundaries carried no task.
    out : Snaps
        Receives the flags of the boundaries after the one started from.
    every : int
    state : State
        Overwritten with the result (what it held before does not matter).
    work : ResumeWork
        Of this list length (:func:`new_work`).

    Returns
    -------
    code : int
        0 on success, -1 when some task could not be placed.
    k_from : int
        The boundary started from (-1: ``root``).
    """
    work.outer[:] = 0
    work.inner[:] = 0
    if anchor is None:
        work.k[0] = 0
        fin, ao, am = root, order, fixed
    else:
        work.k[0] = 1
        fin, ao, am = anchor
    while True:
        code = int(
            _resume_chrono(
                inst.data,
                state,
                ctx,
                inst.scratch,
                inst.oracle,
                root,
                fin,
                ao,
                am,
                order,
                fixed,
                int(every),
                src,
                out,
                work,
                work.buf,
                work.outer,
                work.inner,
            )
        )
        if code != RESUME:
            return code, int(work.k[0])
        inst.answer_misses()


def restore(
    inst: Instance, root: State, final: State, order: IntArray, upto: int, state: State
) -> State:
    """The state of a chronological list decode after its first ``upto``
    positions, from its complete state: what a snapshot would hold.

    Chronological decoding appends every task to its arm and inserts its
    intervals into the timelines in start order (equal starts keep their
    order), so the state after a prefix of the list is the complete state
    less the intervals and arm slots of the later tasks; the one value a
    later task changes in place, the end of its arm's start-zone interval
    (its first task leaves the start zone), comes from ``root`` while the
    arm has no task in the prefix. ``upto`` must be a boundary where no task
    was carried over (a snapshot's ``ok``).

    Parameters
    ----------
    inst : Instance
    root : State
        The state the decode started from (tasks placed before the list).
    final : State
        The complete state of decoding ``order`` from ``root``, chronologically.
    order : (n,) int
    upto : int
        Positions kept.
    state : State
        Overwritten with the result (every field an array of ``root``'s
        shape; what it held before does not matter).

    Returns
    -------
    State
        ``state``.
    """
    keep = root.t_mode >= 0
    keep[np.asarray(order[:upto], dtype=np.int64)] = True
    _restore(inst.data, root, final, keep, state, np.zeros(inst.n_arms, dtype=np.bool_))
    return state


def copy_rows(src: Snaps, dst: Snaps, lo: int, hi: int) -> None:
    """Copy rows ``lo:hi`` (snapshots and their flags) from ``src`` to ``dst``.

    Parameters
    ----------
    src, dst : Snaps
    lo, hi : int
    """
    _copy_rows(src, dst, int(lo), int(hi))


def decode_resume(
    inst: Instance,
    order: IntArray,
    fixed: IntArray,
    src: Snaps,
    out: Snaps,
    k_from: int,
    *,
    every: int,
    state: State | None = None,
    chrono: bool = False,
    waits: bool = True,
    blocking: bool | None = None,
    release: FloatArray | None = None,
    allowed: Any = None,
    arm_lb: FloatArray | None = None,
    states: bool = True,
    ctx: Ctx | None = None,
) -> tuple[int, State]:
    """Decode ``order`` in chunks, resuming from snapshot ``k_from`` of ``src``.

    Parameters
    ----------
    inst : Instance
    order : (n,) int
        Task ids (the whole list, from position 0).
    fixed : (T,) int
        ``fixed[t] >= 0`` forces a mode; -1 chooses (as :func:`~scheduler.kernel.decode`).
    src : Snaps
        Snapshots of a list that agrees with ``order`` on its first
        ``k_from * every`` positions (tasks and modes).
    out : Snaps
        Receives the snapshots at the boundaries after ``k_from`` (row 0 too
        when ``k_from`` is -1); may be ``src`` itself.
    k_from : int
        The snapshot to start from; -1: from ``state`` (or the empty schedule).
    every : int
        Chunk length (the one the snapshots were taken with).
    state : State or None
        Mutated into the result; when ``k_from >= 0`` its contents are replaced
        by the snapshot (default: a new state).
    chrono, waits, blocking, release, allowed, arm_lb
        As for :func:`~scheduler.kernel.decode`.
    states : bool
        Whether the snapshots hold states (saved and loaded here). False:
        ``src`` and ``out`` hold only the flags (:func:`new_flags`), and when
        ``k_from >= 0`` ``state`` already holds boundary ``k_from``
        (:func:`restore`, chronological decoding only).
    ctx : Ctx or None
        The options bundled once (:meth:`Instance.ctx`) for a caller that
        decodes many lists with the same ones; then ``chrono``, ``waits``,
        ``blocking``, ``release``, ``allowed`` and ``arm_lb`` are not read.

    Returns
    -------
    code : int
        0 on success, -1 when some task could not be placed.
    state : State

    Raises
    ------
    UsageError
        Blocking asked of a problem without an oracle.
    """
    if not states and k_from >= 0 and state is None:
        raise UsageError("decode_resume: without saved states, pass the restored state")
    st = inst.new_state() if state is None else state
    cx = ctx
    if cx is None:
        has = inst.problem.blocking is not None
        if blocking and not has:
            raise UsageError(f"problem {inst.problem.name!r} has no blocking oracle")
        cx = inst.ctx(
            chrono=chrono,
            waits=waits,
            blocking=has if blocking is None else bool(blocking),
            release=release,
            allowed=allowed,
            arm_lb=arm_lb,
        )
    order = np.ascontiguousarray(order, dtype=np.int64)
    fx = np.ascontiguousarray(fixed, dtype=np.int64)
    buf = np.empty(len(order) + 1, dtype=np.int64)
    outer = np.zeros(5, dtype=np.int64)
    inner = np.zeros(4, dtype=np.int64)
    while True:
        code = int(
            _decode_chunks(
                inst.data,
                st,
                cx,
                inst.scratch,
                inst.oracle,
                order,
                fx,
                int(every),
                src,
                int(k_from),
                out,
                buf,
                outer,
                inner,
                states,
            )
        )
        if code != RESUME:
            return code, st
        inst.answer_misses()
