# mypy: disallow-untyped-defs=False, disallow-incomplete-defs=False, disallow-untyped-calls=False
"""Whole passes of the kernel (numba): list decoding, batched queries, sequence decoding.

* :func:`_decode` places a list of tasks one after another, modes fixed or
  the earliest-finishing one chosen (list scheduling: with a priority order it
  is the earliest-finish-time baseline, S1.5). With a blocking oracle it is
  chronological and charges detours; unknown oracle answers make it stop
  (``MISSING``) and resume, after Python has asked the oracle, at the task
  where it stopped.
* :func:`_expand` queries many (task, mode) candidates against one state
  (read-only); :func:`_expand_blocking` does the same with the oracle.
* :func:`_seq_decode` decodes fixed arm sequences with fixed modes.

The Python-facing wrappers live in :mod:`scheduler.kernel.api`, schedules are
built in :mod:`scheduler.kernel.build`.
"""

from __future__ import annotations

import numpy as np

from scheduler.kernel._jit import EPS, INF, NO_REFCOUNT, njit
from scheduler.kernel.place import (
    MISSING,
    PLACED,
    _commit,
    _earliest,
    _place_blocking,
    _query,
)

__all__: list[str] = []

RESUME = 1
"""Return code of :func:`_decode`: oracle answers are missing, call again."""


@njit(cache=True, **NO_REFCOUNT)
def _decode(d, st, cx, sc, ot, pending, fixed, cursor):
    """Place ``pending[:cursor[0]]`` one task after another; ``fixed[t] >= 0``
    forces a mode, -1 picks the earliest-finishing one (ties: less waiting
    (plus detour), lower mode id). A task that cannot be placed yet (a
    predecessor still to come, a zone held by an arm that has not left its
    start zone, a parked arm in the way) is deferred and retried after the
    others, in order. ``cursor`` = (n, index, kept, placed) is where the
    pass is, so that a call stopped for missing oracle answers resumes.
    Returns 0, ``-(placed + 1)`` when the rest cannot be placed at all, or
    RESUME."""
    nbmax = st.t_waits.shape[1]
    n = cursor[0]
    idx = cursor[1]
    kept = cursor[2]
    placed = cursor[3]
    best_w = sc.best_w
    waits_out = sc.w
    use_waits = cx.waits
    blocking = cx.blocking
    chrono = cx.chrono
    release = cx.release
    allowed = cx.allowed
    arm_lb = cx.arm_lb
    pred_ptr = d.pred_ptr
    pred_idx = d.pred_idx
    tm_ptr = d.tm_ptr
    tm_idx = d.tm_idx
    bd_ptr = d.bd_ptr
    t_mode = st.t_mode
    t_waits = st.t_waits
    while n > 0:
        while idx < n:
            t = pending[idx]
            ready = True
            for q in range(pred_ptr[t], pred_ptr[t + 1]):
                if t_mode[pred_idx[q]] < 0:
                    ready = False
                    break
            bm = -1
            best = INF
            bS = INF
            bk = -1
            bw = INF
            if ready:
                S0 = _earliest(d, st, t, chrono, release)
                missed = False
                for mi in range(tm_ptr[t], tm_ptr[t + 1]):
                    m = tm_idx[mi]
                    if (fixed[t] >= 0 and m != fixed[t]) or not allowed[m]:
                        continue
                    nb = bd_ptr[m + 1] - bd_ptr[m]
                    if blocking:
                        status, S, end, k, c = _place_blocking(
                            d, st, sc, ot, t, m, S0, use_waits, arm_lb
                        )
                        if status == MISSING:
                            missed = True
                            continue
                        if status != PLACED:
                            continue
                        wsum = 0.0
                        for j in range(nb):
                            wsum += waits_out[j]
                        wsum += c
                        better = end < best or (end == best and wsum < bw)
                    else:
                        S, end, k = _query(d, st, sc, t, m, S0, chrono, use_waits, 0.0, arm_lb)
                        if not (end < INF):
                            continue
                        wsum = 0.0
                        if use_waits:
                            for j in range(nb):
                                wsum += waits_out[j]
                        better = end < best - EPS or (end <= best + EPS and wsum < bw - EPS)
                    if better:
                        best = end
                        bS = S
                        bk = k
                        bm = m
                        bw = wsum
                        for j in range(nbmax):
                            best_w[j] = waits_out[j] if (use_waits and j < nb) else 0.0
                if missed:
                    cursor[0] = n
                    cursor[1] = idx
                    cursor[2] = kept
                    cursor[3] = placed
                    return RESUME
            idx += 1
            if bm < 0:
                pending[kept] = t
                kept += 1
                continue
            for j in range(nbmax):
                t_waits[t, j] = best_w[j]
            _commit(d, st, t, bm, bS, best, bk, best_w, sc.cw)
            placed += 1
        if kept == n:
            return -(placed + 1)
        n = kept
        idx = 0
        kept = 0
    return 0


@njit(cache=True, **NO_REFCOUNT)
def _expand(d, st, cx, sc, cand_t, cand_m, out_S, out_end, out_k, out_w, out_waits):
    """Query many (task, mode) candidates against one state (read-only)."""
    nbmax = out_waits.shape[1]
    use_waits = cx.waits
    chrono = cx.chrono
    release = cx.release
    arm_lb = cx.arm_lb
    bd_ptr = d.bd_ptr
    waits_out = sc.w
    for i in range(len(cand_t)):
        t = cand_t[i]
        m = cand_m[i]
        S0 = _earliest(d, st, t, chrono, release)
        S, end, k = _query(d, st, sc, t, m, S0, chrono, use_waits, 0.0, arm_lb)
        out_S[i] = S
        out_end[i] = end
        out_k[i] = k
        nb = bd_ptr[m + 1] - bd_ptr[m]
        wsum = 0.0
        for j in range(nbmax):
            v = waits_out[j] if (use_waits and j < nb and end < INF) else 0.0
            out_waits[i, j] = v
            wsum += v
        out_w[i] = wsum


@njit(cache=True, **NO_REFCOUNT)
def _expand_blocking(
    d, st, cx, sc, ot, cand_t, cand_m, out_S, out_end, out_k, out_w, out_waits, out_c
):
    """:func:`_expand` with the oracle's detours (chronological). Returns
    RESUME when answers are missing (listed in ``ot.miss``), else 0."""
    nbmax = out_waits.shape[1]
    use_waits = cx.waits
    missed = False
    for i in range(len(cand_t)):
        t = cand_t[i]
        m = cand_m[i]
        S0 = _earliest(d, st, t, True, cx.release)
        status, S, end, k, c = _place_blocking(d, st, sc, ot, t, m, S0, use_waits, cx.arm_lb)
        if status == MISSING:
            missed = True
            continue
        out_S[i] = S
        out_end[i] = end
        out_k[i] = k
        out_c[i] = c
        nb = d.bd_ptr[m + 1] - d.bd_ptr[m]
        wsum = 0.0
        for j in range(nbmax):
            v = sc.w[j] if (j < nb and status == PLACED) else 0.0
            out_waits[i, j] = v
            wsum += v
        out_w[i] = wsum
    if missed:
        return RESUME
    return 0


@njit(cache=True, **NO_REFCOUNT)
def _place_one(d, st, sc, ot, t, m, S0, use_waits, arm_lb, out):
    """One blocking placement; ``out`` = (start, end, slot, cost); returns the status."""
    status, S, end, k, c = _place_blocking(d, st, sc, ot, t, m, S0, use_waits, arm_lb)
    out[0] = S
    out[1] = end
    out[2] = k
    out[3] = c
    return status


@njit(cache=True)
def _heap_push(keys, vals, size, key, val):
    i = size
    keys[i] = key
    vals[i] = val
    while i > 0:
        parent = (i - 1) // 2
        if keys[parent] < keys[i] or (keys[parent] == keys[i] and vals[parent] <= vals[i]):
            break
        keys[parent], keys[i] = keys[i], keys[parent]
        vals[parent], vals[i] = vals[i], vals[parent]
        i = parent
    return size + 1


@njit(cache=True)
def _heap_pop(keys, vals, size):
    val = vals[0]
    size -= 1
    keys[0] = keys[size]
    vals[0] = vals[size]
    i = 0
    while True:
        lft = 2 * i + 1
        rgt = lft + 1
        small = i
        if lft < size and (
            keys[lft] < keys[small] or (keys[lft] == keys[small] and vals[lft] < vals[small])
        ):
            small = lft
        if rgt < size and (
            keys[rgt] < keys[small] or (keys[rgt] == keys[small] and vals[rgt] < vals[small])
        ):
            small = rgt
        if small == i:
            break
        keys[small], keys[i] = keys[i], keys[small]
        vals[small], vals[i] = vals[i], vals[small]
        i = small
    return val, size


@njit(cache=True)
def _seq_decode(d, st, cx, sc, seq, seq_n, modes, order_out):
    """Decode fixed arm sequences ``seq[a, :seq_n[a]]`` with fixed ``modes``:
    tasks whose predecessors and previous task on the arm are placed go in
    order of earliest possible start, each at its earliest feasible time
    after its arm's previous task (zones, tools, waits as in ``_query``).
    Returns the number of tasks placed (fewer than T: the sequences contradict
    the precedence, or a start zone is held for good)."""
    release = cx.release
    arm_lb = cx.arm_lb
    use_waits = cx.waits
    mode_arm = d.mode_arm
    avail = d.avail
    pred_ptr = d.pred_ptr
    pred_idx = d.pred_idx
    t_end = st.t_end
    t_mode = st.t_mode
    t_waits = st.t_waits
    succ_ptr = d.succ_ptr
    succ_idx = d.succ_idx
    bd_ptr = d.bd_ptr
    start_ptr = d.start_ptr
    waits_out = sc.w
    T = len(release)
    A = seq.shape[0]
    nbmax = st.t_waits.shape[1]
    best_w = sc.best_w
    pos = np.zeros(T, dtype=np.int64)
    indeg = np.zeros(T, dtype=np.int64)
    for t in range(T):
        for q in range(pred_ptr[t], pred_ptr[t + 1]):
            if t_mode[pred_idx[q]] < 0:  # tasks of a base state are already placed
                indeg[t] += 1
    for a in range(A):
        for i in range(seq_n[a]):
            t = seq[a, i]
            pos[t] = i
            if i > 0:
                indeg[t] += 1
    keys = np.empty(T)
    vals = np.empty(T, dtype=np.int64)
    size = 0
    for t in range(T):
        if indeg[t] == 0 and t_mode[t] < 0:
            a = mode_arm[modes[t]]
            est = max(release[t], avail[a], arm_lb[a])
            size = _heap_push(keys, vals, size, est, t)
    placed = 0
    blocked = np.empty(T, dtype=np.int64)  # waiting for an arm to leave its start zone
    blocked_key = np.empty(T)
    nblocked = 0
    while size > 0:
        t, size = _heap_pop(keys, vals, size)
        m = modes[t]
        a = mode_arm[m]
        S0 = _earliest(d, st, t, False, release)
        S, end, k = _query(d, st, sc, t, m, S0, True, use_waits, 0.0, arm_lb)
        if not (end < INF):
            blocked[nblocked] = t
            blocked_key[nblocked] = S0
            nblocked += 1
            continue
        if k == 0 and start_ptr[a + 1] > start_ptr[a]:
            # the arm leaves its start zones: what waited for them may go now
            for i in range(nblocked):
                size = _heap_push(keys, vals, size, blocked_key[i], blocked[i])
            nblocked = 0
        nb = bd_ptr[m + 1] - bd_ptr[m]
        for j in range(nbmax):
            best_w[j] = waits_out[j] if (use_waits and j < nb) else 0.0
            t_waits[t, j] = best_w[j]
        _commit(d, st, t, m, S, end, k, best_w, sc.cw)
        order_out[placed] = t
        placed += 1
        for q in range(succ_ptr[t], succ_ptr[t + 1]):
            s = succ_idx[q]
            indeg[s] -= 1
            if indeg[s] == 0:
                sa = mode_arm[modes[s]]
                est = max(release[s], avail[sa], arm_lb[sa])
                for r in range(pred_ptr[s], pred_ptr[s + 1]):
                    if t_end[pred_idx[r]] > est:
                        est = t_end[pred_idx[r]]
                if pos[s] > 0:
                    prv = seq[sa, pos[s] - 1]
                    if t_end[prv] > est:
                        est = t_end[prv]
                size = _heap_push(keys, vals, size, est, s)
        i = pos[t] + 1
        if i < seq_n[a]:
            s = seq[a, i]
            indeg[s] -= 1
            if indeg[s] == 0:
                est = max(release[s], t_end[t])
                for r in range(pred_ptr[s], pred_ptr[s + 1]):
                    if t_end[pred_idx[r]] > est:
                        est = t_end[pred_idx[r]]
                size = _heap_push(keys, vals, size, est, s)
    return placed


@njit(cache=True)
def _keyed_order(d, todo, key, out):
    """The tasks ``todo`` marks in a topological order (predecessors outside
    ``todo`` count as done), the one with the smallest ``key`` first among
    those ready (ties: the smaller id), into ``out``; returns how many."""
    T = todo.shape[0]
    missing = np.zeros(T, dtype=np.int64)
    keys = np.empty(T)
    vals = np.empty(T, dtype=np.int64)
    size = 0
    for t in range(T):
        if not todo[t]:
            continue
        for q in range(d.pred_ptr[t], d.pred_ptr[t + 1]):
            if todo[d.pred_idx[q]]:
                missing[t] += 1
        if missing[t] == 0:
            size = _heap_push(keys, vals, size, key[t], t)
    n = 0
    while size > 0:
        t, size = _heap_pop(keys, vals, size)
        out[n] = t
        n += 1
        for q in range(d.succ_ptr[t], d.succ_ptr[t + 1]):
            s = d.succ_idx[q]
            if todo[s]:
                missing[s] -= 1
                if missing[s] == 0:
                    size = _heap_push(keys, vals, size, key[s], s)
    return n
