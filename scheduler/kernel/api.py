"""The kernel's Python entry points: decoding lists and sequences, batched
queries, blocking placements, and the one-time compile (:func:`warm_up`).

Each call bundles the per-call options in a :class:`~scheduler.kernel.arrays.Ctx`
and runs a compiled pass of :mod:`scheduler.kernel.passes`. With a blocking
oracle the compiled pass reads the answered costs from the instance's
:class:`~scheduler.kernel.arrays.OracleTable`; when some are unknown it
stops, the oracle is asked here (:meth:`Instance.answer_misses`) and the
pass resumes where it stopped, so the oracle is asked once per
(mode, arm, pose) for the problem's lifetime.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from multiarm.errors import UsageError
from multiarm.types import BoolArray, FloatArray, IntArray
from scheduler.kernel._jit import jit_enabled
from scheduler.kernel.arrays import Instance, State, compile_problem
from scheduler.kernel.critical import _chain, cheapest_slot, critical_chain
from scheduler.kernel.moves_jit import _neighbour_moves, chrono_extend, neighbour_moves
from scheduler.kernel.passes import (
    RESUME,
    _decode,
    _expand,
    _expand_blocking,
    _keyed_order,
    _place_one,
    _seq_decode,
)
from scheduler.kernel.place import MISSING, PLACED
from scheduler.kernel.resume import (
    _decode_chunks,
    _resume_chrono,
    chunk_size,
    copy_rows,
    decode_resume,
    new_flags,
    new_snaps,
    new_work,
    restore,
    resume_chrono,
)
from scheduler.problem import Model, Window

__all__ = [
    "COMPILE_NOTE",
    "decode",
    "expand",
    "expand_blocking",
    "keyed_order",
    "place_blocking",
    "seq_decode",
    "warm_up",
]

log = logging.getLogger("scheduler.kernel")


def _blocking(inst: Instance, blocking: bool | None) -> bool:
    """Whether to charge the oracle: ``None`` means whenever the problem has one."""
    has = inst.problem.blocking is not None
    if blocking and not has:
        raise UsageError(f"problem {inst.problem.name!r} has no blocking oracle")
    return has if blocking is None else bool(blocking)


def decode(
    inst: Instance,
    order: IntArray,
    fixed: IntArray,
    *,
    chrono: bool = False,
    waits: bool = True,
    state: State | None = None,
    release: FloatArray | None = None,
    allowed: Any = None,
    arm_lb: FloatArray | None = None,
    blocking: bool | None = None,
) -> tuple[int, State]:
    """Place the tasks of ``order`` one after another on top of ``state``.

    A task goes in its fixed mode, or in the mode that finishes first
    (ties: less waiting, then the lower mode id), at its earliest feasible
    start; a task that cannot be placed yet is retried after the others.

    Parameters
    ----------
    inst : Instance
    order : (n,) int
        Task ids.
    fixed : (T,) int
        ``fixed[t] >= 0`` forces mode ``fixed[t]``; -1 chooses.
    chrono : bool
        Chronological: no task starts before an earlier one of the list.
    waits : bool
        Waits at zone borders allowed.
    state : State or None
        The partial schedule to extend (mutated); default: empty.
    release : (T,) float or None
        Overridden release times, seconds.
    allowed : (M,) bool or None
        Modes that may be used.
    arm_lb : (A,) float or None
        Per arm, a time before which it cannot start, seconds.
    blocking : bool or None
        Charge the blocking oracle's detours (chronological decoding); None:
        whenever the problem has an oracle.

    Returns
    -------
    code : int
        0 on success, ``-(placed + 1)`` when the remaining tasks cannot be
        placed at all (a zone held for good, a parked arm with no detour).
    state : State

    Raises
    ------
    ValidationError
        The blocking oracle answered a negative or NaN cost.
    UsageError
        Blocking asked of a problem without an oracle.
    """
    st = inst.new_state() if state is None else state
    cx = inst.ctx(
        chrono=chrono,
        waits=waits,
        blocking=_blocking(inst, blocking),
        release=release,
        allowed=allowed,
        arm_lb=arm_lb,
    )
    pending = np.array(order, dtype=np.int64)
    fx = np.ascontiguousarray(fixed, dtype=np.int64)
    cursor = np.array([len(pending), 0, 0, 0], dtype=np.int64)
    while True:
        code = int(_decode(inst.data, st, cx, inst.scratch, inst.oracle, pending, fx, cursor))
        if code != RESUME:
            return code, st
        inst.answer_misses()


def keyed_order(inst: Instance, todo: BoolArray, key: FloatArray) -> IntArray:
    """The tasks ``todo`` marks in a topological order, the smallest ``key``
    first among the ready ones (ties: the smaller id); predecessors outside
    ``todo`` count as done.

    Parameters
    ----------
    inst : Instance
    todo : (T,) bool
    key : (T,) float

    Returns
    -------
    (n,) int
        Every task ``todo`` marks (fewer only if the precedence has a cycle).
    """
    out = np.empty(inst.n_tasks, dtype=np.int64)
    n = int(
        _keyed_order(
            inst.data,
            np.ascontiguousarray(todo, dtype=np.bool_),
            np.ascontiguousarray(key, dtype=np.float64),
            out,
        )
    )
    return out[:n]


def expand(
    inst: Instance,
    st: State,
    cand_t: IntArray,
    cand_m: IntArray,
    *,
    chrono: bool = False,
    waits: bool = True,
    release: FloatArray | None = None,
    arm_lb: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray, IntArray, FloatArray, FloatArray]:
    """Query candidates (task, mode) against ``st`` (read-only), without an oracle.

    Parameters
    ----------
    inst : Instance
    st : State
    cand_t, cand_m : (n,) int
        Tasks and modes.
    chrono, waits : bool
    release : (T,) float or None
    arm_lb : (A,) float or None

    Returns
    -------
    start, end : (n,) float
        Seconds (inf: cannot be placed).
    slot : (n,) int
    total_wait : (n,) float
    waits : (n, max borders) float
    """
    n = len(cand_t)
    out_S, out_end, out_w = np.zeros(n), np.zeros(n), np.zeros(n)
    out_k = np.zeros(n, dtype=np.int64)
    out_waits = np.zeros((n, max(inst.max_borders, 1)))
    cx = inst.ctx(chrono=chrono, waits=waits, release=release, arm_lb=arm_lb)
    _expand(
        inst.data,
        st,
        cx,
        inst.scratch,
        np.ascontiguousarray(cand_t, dtype=np.int64),
        np.ascontiguousarray(cand_m, dtype=np.int64),
        out_S,
        out_end,
        out_k,
        out_w,
        out_waits,
    )
    return out_S, out_end, out_k, out_w, out_waits


def expand_blocking(
    inst: Instance,
    st: State,
    cand_t: IntArray,
    cand_m: IntArray,
    *,
    waits: bool = True,
    release: FloatArray | None = None,
    arm_lb: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray, IntArray, FloatArray, FloatArray, FloatArray]:
    """:func:`expand` with the blocking oracle's detours (chronological).

    Parameters
    ----------
    inst : Instance
        Of a problem with a blocking oracle.
    st : State
    cand_t, cand_m : (n,) int
    waits : bool
    release : (T,) float or None
    arm_lb : (A,) float or None

    Returns
    -------
    start, end : (n,) float
        Seconds (inf: cannot be placed); ``end`` includes the detour.
    slot : (n,) int
    total_wait : (n,) float
    waits : (n, max borders) float
    detour : (n,) float
        The cost charged, seconds.

    Raises
    ------
    ValidationError
        The blocking oracle answered a negative or NaN cost.
    UsageError
        Blocking asked of a problem without an oracle.
    """
    n = len(cand_t)
    out_S, out_end, out_w, out_c = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    out_k = np.zeros(n, dtype=np.int64)
    out_waits = np.zeros((n, max(inst.max_borders, 1)))
    cx = inst.ctx(waits=waits, blocking=_blocking(inst, True), release=release, arm_lb=arm_lb)
    ct = np.ascontiguousarray(cand_t, dtype=np.int64)
    cm = np.ascontiguousarray(cand_m, dtype=np.int64)
    while True:
        code = _expand_blocking(
            inst.data,
            st,
            cx,
            inst.scratch,
            inst.oracle,
            ct,
            cm,
            out_S,
            out_end,
            out_k,
            out_w,
            out_waits,
            out_c,
        )
        if code != RESUME:
            return out_S, out_end, out_k, out_w, out_waits, out_c
        inst.answer_misses()


def place_blocking(
    inst: Instance,
    st: State,
    t: int,
    m: int,
    S0: float,
    *,
    waits: bool = True,
    arm_lb: FloatArray | None = None,
) -> tuple[float, float, int, FloatArray, float]:
    """Chronological placement of task ``t`` in mode ``m`` from ``S0`` with the
    blocking oracle's detour cost (it grows with the start to a fixpoint).

    Parameters
    ----------
    inst : Instance
        Of a problem with a blocking oracle.
    st : State
    t, m : int
    S0 : float
        Seconds.
    waits : bool
    arm_lb : (A,) float or None

    Returns
    -------
    start, end : float
        Seconds (inf: cannot be placed); ``end`` includes the detour.
    slot : int
    waits : (borders of m,) float
    detour : float
        Seconds.

    Raises
    ------
    ValidationError
        The blocking oracle answered a negative or NaN cost.
    UsageError
        Blocking asked of a problem without an oracle.
    """
    cx = inst.ctx(waits=waits, blocking=_blocking(inst, True), arm_lb=arm_lb)
    out = np.zeros(4)
    while True:
        status = _place_one(
            inst.data, st, inst.scratch, inst.oracle, t, m, S0, cx.waits, cx.arm_lb, out
        )
        if status != MISSING:
            break
        inst.answer_misses()
    nb = int(inst.data.bd_ptr[m + 1] - inst.data.bd_ptr[m])
    w = inst.scratch.w[:nb].copy()
    if status != PLACED:
        return math.inf, math.inf, -1, w, float(out[3])
    return float(out[0]), float(out[1]), int(out[2]), w, float(out[3])


def seq_decode(
    inst: Instance,
    seq: IntArray,
    seq_n: IntArray,
    modes: IntArray,
    *,
    waits: bool = True,
    state: State | None = None,
    release: FloatArray | None = None,
    arm_lb: FloatArray | None = None,
) -> tuple[bool, State, IntArray]:
    """Decode fixed arm sequences with fixed modes on top of ``state``.

    Tasks whose predecessors and previous task on the arm are placed go in
    order of earliest possible start, each at its earliest feasible time
    after its arm's previous task.

    Parameters
    ----------
    inst : Instance
    seq : (A, n) int
        ``seq[a, :seq_n[a]]``: arm ``a``'s tasks in order.
    seq_n : (A,) int
    modes : (T,) int
        Every task's mode.
    waits : bool
    state : State or None
    release : (T,) float or None
    arm_lb : (A,) float or None

    Returns
    -------
    complete : bool
        False: the sequences contradict the precedence, or a start zone is
        held for good.
    state : State
    order : (placed,) int
        The processing order of the newly placed tasks.
    """
    st = inst.new_state() if state is None else state
    todo = int((st.t_mode < 0).sum())
    order = np.full(inst.n_tasks, -1, dtype=np.int64)
    cx = inst.ctx(waits=waits, release=release, arm_lb=arm_lb)
    placed = _seq_decode(
        inst.data,
        st,
        cx,
        inst.scratch,
        np.ascontiguousarray(seq, dtype=np.int64),
        np.ascontiguousarray(seq_n, dtype=np.int64),
        np.ascontiguousarray(modes, dtype=np.int64),
        order,
    )
    return placed == todo, st, order[:placed]


# --------------------------------------------------------------- warm-up


class _Parked:
    """A tiny oracle for the warm-up: a detour of 1 s behind any parked arm."""

    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        return 1.0


_WARM = False


COMPILE_NOTE = (
    "compiling the scheduler kernel, once per machine "
    "(about a minute; numba caches it on disk for later runs)..."
)
"""What :func:`warm_up` announces before a compile that is not cached yet."""


def _cached_on_disk() -> bool:
    """Whether numba's on-disk cache already holds the kernel's entry points."""
    for fn in (
        _decode,
        _expand,
        _expand_blocking,
        _place_one,
        _seq_decode,
        _chain,
        _decode_chunks,
        _resume_chrono,
        _keyed_order,
        _neighbour_moves,
    ):
        cache = getattr(fn, "_cache", None)
        path = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
        if path is None or not os.path.exists(path):
            return False
    return True


def warm_up(announce: Callable[[str], None] | None = None) -> float:
    """Compile (or load from numba's on-disk cache) every kernel entry point.

    Call it before starting a solver's clock: the first compile takes about
    a minute once per machine (55-65 s measured on 2 shared cores, 2026-12;
    cached on disk afterwards), loading takes about a second per process;
    later calls return at once.

    Parameters
    ----------
    announce : callable or None
        Receives :data:`COMPILE_NOTE` before a compile that is not cached
        yet; default: an INFO message on the ``scheduler.kernel`` logger
        (the ``multiarm`` command shows it on stderr).

    Returns
    -------
    float
        Seconds spent (0.0 when already warm or running as plain Python).

    Examples
    --------
    >>> seconds = warm_up()
    >>> warm_up()
    0.0
    """
    global _WARM
    if _WARM or not jit_enabled():
        _WARM = True
        return 0.0
    t0 = time.perf_counter()
    if not _cached_on_disk():
        if announce is None:
            log.info(COMPILE_NOTE)
        else:
            announce(COMPILE_NOTE)
    m = Model()
    m.add_zone("E")
    m.add_zone("S", "shared")
    m.add_tool("k")
    m.add_arm("a", start_zones=["E"])
    m.add_arm("b")
    m.add_task("x")
    m.add_task("y", predecessors=["x"])
    m.add_mode("x", "a", 2.0, windows=[Window("E", 0.5, 1.5), Window("S", 1.0, 2.0, "move")])
    m.add_mode("x", "b", 3.0, tools=["k"])
    m.add_mode("y", "b", 2.0, windows=[Window("E", 0.5, 1.0)], tools=["k"])
    plain = m.build()
    m.set_blocking(_Parked())
    parked = m.build()
    for p in (plain, parked):
        inst = compile_problem(p)
        order = np.arange(p.n_tasks, dtype=np.int64)
        free = np.full(p.n_tasks, -1, dtype=np.int64)
        _code, st = decode(inst, order, free)
        decode(inst, order, free, chrono=True, waits=False, allowed=np.ones(p.n_modes, bool))
        expand(inst, inst.new_state(), order, np.asarray(p.mode_of[1], dtype=np.int64))
        # the beam search's modes are a writable array: another compile
        expand(inst, inst.new_state(), order, np.array(p.mode_of[1], dtype=np.int64))
        seq = np.zeros((p.n_arms, p.n_tasks), dtype=np.int64)
        seq_decode(inst, seq, np.zeros(p.n_arms, dtype=np.int64), st.t_mode)
        st2 = inst.new_state()
        S, end, k, w = inst.query(st2, 0, 0, inst.earliest(st2, 0, False))
        inst.commit(st2, 0, 0, S, end, k, w)
        # a re-solve's frozen prefix, committed in one call
        inst.commit_all(
            inst.new_state(),
            np.zeros(1, dtype=np.int64),
            np.zeros(1, dtype=np.int64),
            np.array([S]),
            np.array([end]),
            np.zeros((1, max(inst.max_borders, 1))),
        )
        if p.blocking is not None:
            expand_blocking(inst, st2, np.array([1]), np.array([2]))
            place_blocking(inst, st2, 1, 2, end)
        every = chunk_size(len(order))
        snaps = new_snaps(inst, len(order), every)
        _code, st3 = decode_resume(inst, order, free, snaps, snaps, -1, every=every)
        decode_resume(inst, order, free, snaps, snaps, 0, every=every)
        copy_rows(snaps, new_snaps(inst, len(order), every), 0, 1)
        # chronological resumes: flags only, a boundary restored from the complete state
        flags = new_flags(inst, len(order), every)
        _code, fin = decode_resume(
            inst, order, free, flags, flags, -1, every=every, chrono=True, states=False
        )
        root = inst.new_state()
        back = restore(inst, root, fin, order, 0, inst.new_state())
        decode_resume(
            inst, order, free, flags, flags, 0, every=every, state=back, chrono=True, states=False
        )
        # the same in one compiled call (the local search's chronological decoder)
        cx = inst.ctx(chrono=True, blocking=p.blocking is not None)
        work = new_work(inst, len(order))
        resume_chrono(inst, cx, root, None, order, free, flags, flags, every, back, work)
        resume_chrono(
            inst, cx, root, (fin, order, free), order, free, flags, flags, every, back, work
        )
        keyed_order(inst, np.ones(p.n_tasks, dtype=np.bool_), np.zeros(p.n_tasks))
        critical_chain(inst, st3)
        rng = np.random.default_rng(0)
        pos = np.arange(len(order), dtype=np.int64)
        for chrono in (False, True):  # the local search's moves
            neighbour_moves(inst, st3, order, st3.t_mode.copy(), rng, chrono=chrono)
        one = np.zeros(1, dtype=np.int64)
        chrono_extend(inst, st3, order, pos, (one, one + 3, one - 1), rng)
        cheapest_slot(inst, 0, 0, np.zeros(0, dtype=np.int64), 0, 0)  # the tabu search's
    _WARM = True
    spent = time.perf_counter() - t0
    log.debug("scheduler kernel ready in %.1f s", spent)
    return spent
