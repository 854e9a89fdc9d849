# mypy: disallow-untyped-defs=False, disallow-incomplete-defs=False, disallow-untyped-calls=False
"""Earliest placement of one task on the arm gaps and resource timelines (numba).

Placement ("query") of a task ``t`` in mode ``m`` on arm ``a``, given a state
of already placed tasks, finds the earliest start ``S >= S0`` such that

* the arm is free: the task fits into a gap of the arm's sequence (or after
  its last task) with the sequence-dependent setup before it and the setup to
  the next task after it (in *chronological* mode only after the last task);
* every exclusive zone, shared-zone movement and tool it needs is free over
  the intervals :mod:`scheduler.timing` defines, given the waits it inserts
  at zone borders (waits mode: each border gets the least wait that lets the
  next part of the path through, while the arm stands in the zones it is in;
  when standing there clashes with another arm's use of such a zone, the
  task either starts later, so that it enters the zone after that use, or
  waits at the border where it enters the zone until the use is over,
  whichever ends first, the later start on a tie; rigid mode: no waits, the
  whole task is delayed) (S2.6, S2.12);
* start zones: an arm stands in its exclusive start zones from 0 until it
  leaves for its first task.

:func:`_commit` records a placement. With a blocking oracle,
:func:`_place_blocking` adds the detour cost of the arms parked at the start
(read from the :class:`~scheduler.kernel.arrays.OracleTable`, unknown costs
listed as misses for Python to answer).

Intervals on a resource never overlap, so they are sorted by end too, and a
binary search finds the first conflict; a piece that starts after the
resource's last end (the common case: most of what a timeline holds is over
before a new task's piece) is free without one. A placement records its
intervals with the prefix sums of its waits (the borders increase, so the
waits before an offset are a prefix of them), as :mod:`scheduler.timing`
computes them. The placement functions take the
bundled tuples of :mod:`scheduler.kernel.arrays`: ``d`` (Arrays), ``st``
(State), ``sc`` (Scratch), ``ot`` (OracleTable), and bind the fields they use
to locals on entry (reading tuple fields inside the hot loops measured 1.5-2x
slower); the innermost helpers take arrays.
"""

from __future__ import annotations

import math

from scheduler.kernel._jit import EPS, INF, NO_REFCOUNT, njit

__all__: list[str] = []

PLACED = 0
NO_PLACE = 1
MISSING = 2


@njit(cache=True, inline="always")
def _setup(kind, table, arm_off, arm_count, slot, mode_of, a, prev, nxt):
    """Setup time of arm ``a`` from task ``prev`` (-1: initial pose) to ``nxt``
    from a :class:`~scheduler.setup.KernelSetup`: a lookup in the compact
    table (kind 1) or travel computed from the packed points (kinds 2, 3)."""
    if kind == 0:
        return 0.0
    mn = mode_of[a, nxt]
    if kind == 1:
        ps = 0 if prev < 0 else 1 + slot[mode_of[a, prev]]
        return table[arm_off[a] + ps * arm_count[a] + slot[mn]]
    M = slot.shape[0]
    A = arm_off.shape[0]
    i = 6 * M + 3 * a if prev < 0 else 3 * M + 3 * mode_of[a, prev]
    j = 3 * mn
    dx = table[j] - table[i]
    dy = table[j + 1] - table[i + 1]
    dz = table[j + 2] - table[i + 2]
    if kind == 3:
        dist = abs(dx) + abs(dy) + abs(dz)
    else:
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    return table[6 * M + 4 * A + a] + dist / table[6 * M + 3 * A + a]


@njit(cache=True, **NO_REFCOUNT)
def _first_conflict(tl_s, tl_e, tl_own, lo, n, x, y, arm):
    """Index of the first interval of [lo, lo+n) overlapping [x, y) owned by
    another arm, or -1. Overlaps below EPS do not count."""
    a = lo
    b = lo + n
    xe = x + EPS
    while a < b:
        mid = (a + b) // 2
        if tl_e[mid] > xe:
            b = mid
        else:
            a = mid + 1
    i = a
    ye = y - EPS
    while i < lo + n and tl_s[i] < ye:
        if tl_own[i] != arm:
            return i
        i += 1
    return -1


@njit(cache=True, **NO_REFCOUNT)
def _fit(p_res, p_s, p_e, p0, p1, t0, arm, tl_s, tl_e, tl_own, res_lo, res_n):
    """Least t >= t0 such that every piece [t + s, t + e) of p0..p1 is free."""
    t = t0
    while True:
        moved = False
        for i in range(p0, p1):
            r = p_res[i]
            n = res_n[r]
            # nothing held, or everything held ends by the piece's start (the
            # ends are in order): the common case, without the bisection
            if n == 0 or tl_e[res_lo[r] + n - 1] <= t + p_s[i] + EPS:
                continue
            k = _first_conflict(tl_s, tl_e, tl_own, res_lo[r], n, t + p_s[i], t + p_e[i], arm)
            if k >= 0:
                t = tl_e[k] - p_s[i]
                if not (t < INF):
                    return INF
                moved = True
        if not moved:
            return t


@njit(cache=True, **NO_REFCOUNT)
def _fit_waits(
    m,
    S0,
    arm,
    seg_ptr,
    seg_len,
    segp_ptr,
    sp_res,
    sp_s,
    sp_e,
    stand_ptr,
    st_res,
    st_origin,
    tl_s,
    tl_e,
    tl_own,
    res_lo,
    res_n,
    waits_out,
    taus,
    floors,
    entry,
):
    """Earliest start >= S0 with the least waits at borders; fills
    ``waits_out[:borders]``; returns (start, end without extra, whether a
    wait moved to an entry border).

    A wait at a border holds the zones the arm stands in. When that
    clashes with another arm's use of such a zone, the task starts later,
    so that it enters the zone after that use; or, with ``entry``, the arm
    waits instead at the border where it entered the zone, until that use is
    over (the segment's *floor*, ``floors``; a zone held from the task's
    start still makes it start later)."""
    seg0 = seg_ptr[m]
    nseg = seg_ptr[m + 1] - seg0
    for j in range(nseg):
        floors[j] = -INF
    moved = False
    S = S0
    while True:
        tau = _fit(
            sp_res,
            sp_s,
            sp_e,
            segp_ptr[seg0],
            segp_ptr[seg0 + 1],
            S,
            arm,
            tl_s,
            tl_e,
            tl_own,
            res_lo,
            res_n,
        )
        if not (tau < INF):
            return INF, INF, moved
        S = tau
        taus[0] = tau
        later = False
        j = 1
        while j < nseg:
            sj = seg0 + j
            alpha = taus[j - 1] + seg_len[sj - 1]
            need = _fit(
                sp_res,
                sp_s,
                sp_e,
                segp_ptr[sj],
                segp_ptr[sj + 1],
                max(alpha, floors[j]),
                arm,
                tl_s,
                tl_e,
                tl_own,
                res_lo,
                res_n,
            )
            if not (need < INF):
                return INF, INF, moved
            w = need - alpha
            if w > EPS:
                back = -1
                for q in range(stand_ptr[sj], stand_ptr[sj + 1]):
                    r = st_res[q]
                    if res_n[r] == 0:
                        continue
                    k = _first_conflict(tl_s, tl_e, tl_own, res_lo[r], res_n[r], alpha, need, arm)
                    if k >= 0:
                        o = st_origin[q]
                        if o == 0 or not entry:
                            shift = tl_e[k] - taus[o]
                            if not (shift < INF):
                                return INF, INF, moved
                            S = S + max(shift, 1e-6)
                            later = True
                        else:
                            if not (tl_e[k] < INF):
                                return INF, INF, moved
                            floors[o] = max(floors[o], tl_e[k])
                            back = o
                            moved = True
                        break
                if later:
                    break
                if back > 0:
                    j = back  # wait at the border before segment ``back`` instead
                    continue
                waits_out[j - 1] = w
            else:
                waits_out[j - 1] = 0.0
                need = alpha
            taus[j] = need
            j += 1
        if not later:
            return S, taus[nseg - 1] + seg_len[seg0 + nseg - 1], moved


@njit(cache=True, **NO_REFCOUNT)
def _query(d, st, sc, t, m, S0, chrono, use_waits, extra, arm_lb):
    """Earliest placement of task t in mode m from S0: (start, end, arm slot);
    the waits are left in ``sc.w``."""
    su = d.su
    su_kind = su.kind
    su_table = su.table
    su_off = su.arm_off
    su_count = su.arm_count
    su_slot = su.mode_slot
    seg_ptr = d.seg_ptr
    seg_len = d.seg_len
    segp_ptr = d.segp_ptr
    sp_res = d.sp_res
    sp_s = d.sp_s
    sp_e = d.sp_e
    stand_ptr = d.stand_ptr
    st_res = d.st_res
    st_origin = d.st_origin
    taus = sc.tau
    mode_of = d.mode_of
    mode_dur = d.mode_dur
    avail = d.avail
    rp_ptr = d.rp_ptr
    rp_res = d.rp_res
    rp_s = d.rp_s
    rp_e = d.rp_e
    tool_ptr = d.tool_ptr
    tool_res = d.tool_res
    res_lo = d.res_lo
    arm_t = st.arm_t
    t_start = st.t_start
    t_end = st.t_end
    tl_s = st.tl_s
    tl_e = st.tl_e
    tl_own = st.tl_own
    res_n = st.res_n
    waits_out = sc.w
    floors = sc.floor
    other_w = sc.w2
    a = d.mode_arm[m]
    lo = d.arm_lo[a]
    n = st.arm_n[a]
    k0 = 0
    if chrono:
        k0 = n
    else:
        # first slot whose next task starts at or after S0
        x = lo
        y = lo + n
        while x < y:
            mid = (x + y) // 2
            if t_start[arm_t[mid]] >= S0:
                y = mid
            else:
                x = mid + 1
        k0 = x - lo
    nb = seg_ptr[m + 1] - seg_ptr[m] - 1
    for k in range(k0, n + 1):
        if k > 0:
            prev = arm_t[lo + k - 1]
            ready = t_end[prev]
        else:
            prev = -1
            ready = avail[a]
        lb = max(
            S0,
            ready
            + _setup(
                su_kind,
                su_table,
                su_off,
                su_count,
                su_slot,
                mode_of,
                a,
                prev,
                t,
            ),
        )
        if arm_lb[a] > lb:
            lb = arm_lb[a]
        nxt = -1
        limit = INF
        if k < n:
            nxt = arm_t[lo + k]
            limit = t_start[nxt] - _setup(
                su_kind,
                su_table,
                su_off,
                su_count,
                su_slot,
                mode_of,
                a,
                t,
                nxt,
            )
            if lb + mode_dur[m] + extra > limit + EPS:
                continue
        S = lb
        while True:
            if use_waits and nb > 0:
                # the entry-border rule; where it moved a wait, the plain
                # later start too, and the earlier end of the two (a tie: the
                # later start, which stands less)
                S_in = S
                S, end, moved = _fit_waits(
                    m,
                    S,
                    a,
                    seg_ptr,
                    seg_len,
                    segp_ptr,
                    sp_res,
                    sp_s,
                    sp_e,
                    stand_ptr,
                    st_res,
                    st_origin,
                    tl_s,
                    tl_e,
                    tl_own,
                    res_lo,
                    res_n,
                    waits_out,
                    taus,
                    floors,
                    True,
                )
                if moved:
                    for j in range(nb):
                        other_w[j] = waits_out[j]
                    S2, end2, _m = _fit_waits(
                        m,
                        S_in,
                        a,
                        seg_ptr,
                        seg_len,
                        segp_ptr,
                        sp_res,
                        sp_s,
                        sp_e,
                        stand_ptr,
                        st_res,
                        st_origin,
                        tl_s,
                        tl_e,
                        tl_own,
                        res_lo,
                        res_n,
                        waits_out,
                        taus,
                        floors,
                        False,
                    )
                    if end < end2 - EPS:
                        for j in range(nb):
                            waits_out[j] = other_w[j]
                    else:
                        S, end = S2, end2
            else:
                S = _fit(
                    rp_res,
                    rp_s,
                    rp_e,
                    rp_ptr[m],
                    rp_ptr[m + 1],
                    S,
                    a,
                    tl_s,
                    tl_e,
                    tl_own,
                    res_lo,
                    res_n,
                )
                end = S + mode_dur[m]
                for j in range(nb):
                    waits_out[j] = 0.0
            if not (S < INF):
                return INF, INF, -1
            if extra <= 0.0:
                break
            # the tools are held through the detour too
            moved = False
            for q in range(tool_ptr[m], tool_ptr[m + 1]):
                r = tool_res[q]
                if res_n[r] == 0:
                    continue
                c = _first_conflict(tl_s, tl_e, tl_own, res_lo[r], res_n[r], end, end + extra, a)
                if c >= 0:
                    S = S + max(tl_e[c] - end, 1e-6)
                    moved = True
                    break
            if not moved:
                break
        end = end + extra
        if nxt >= 0 and end > limit + EPS:
            continue
        return S, end, k
    return INF, INF, -1


@njit(cache=True, inline="always")
def _insert(tl_s, tl_e, tl_own, tl_task, res_lo, res_n, r, s, e, own, task):
    """Insert interval [s, e) of ``own``/``task`` into resource r's timeline, sorted by start."""
    lo = res_lo[r]
    n = res_n[r]
    x = lo
    y = lo + n
    if n > 0 and tl_s[y - 1] <= s:
        x = y  # after every interval (chronological decoding's common case)
    while x < y:
        mid = (x + y) // 2
        if tl_s[mid] <= s:
            x = mid + 1
        else:
            y = mid
    for i in range(lo + n, x, -1):
        tl_s[i] = tl_s[i - 1]
        tl_e[i] = tl_e[i - 1]
        tl_own[i] = tl_own[i - 1]
        tl_task[i] = tl_task[i - 1]
    tl_s[x] = s
    tl_e[x] = e
    tl_own[x] = own
    tl_task[x] = task
    res_n[r] = n + 1


@njit(cache=True, **NO_REFCOUNT)
def _commit(d, st, t, m, S, end, k, waits, cw):
    """Record task t in mode m at [S, end), slot k of its arm, with ``waits``
    (``cw``: a buffer for their prefix sums, one more than the most borders)."""
    res_lo = d.res_lo
    res_n = st.res_n
    tl_s = st.tl_s
    tl_e = st.tl_e
    tl_own = st.tl_own
    tl_task = st.tl_task
    bd_val = d.bd_val
    ex_res = d.ex_res
    ex_s = d.ex_s
    ex_e = d.ex_e
    ex_move = d.ex_move
    ex_b0 = d.ex_b0
    ex_b1 = d.ex_b1
    a = d.mode_arm[m]
    st.t_start[t] = S
    st.t_end[t] = end
    st.t_mode[t] = m
    if st.t_last[0] < S:
        st.t_last[0] = S
    lo = d.arm_lo[a]
    n = st.arm_n[a]
    arm_t = st.arm_t
    for i in range(lo + n, lo + k, -1):
        arm_t[i] = arm_t[i - 1]
    arm_t[lo + k] = t
    st.arm_n[a] = n + 1
    if k == 0:
        # the arm leaves its start zones for its (new) first task
        su = d.su
        dep = S - _setup(
            su.kind, su.table, su.arm_off, su.arm_count, su.mode_slot, d.mode_of, a, -1, t
        )
        for q in range(d.start_ptr[a], d.start_ptr[a + 1]):
            r = d.start_res[q]
            for i in range(res_lo[r], res_lo[r] + res_n[r]):
                if tl_own[i] == a and tl_s[i] == 0.0 and tl_e[i] > dep:
                    tl_e[i] = max(dep, 0.0)
    b0 = d.bd_ptr[m]
    nb = d.bd_ptr[m + 1] - b0
    # cw[j]: the waits at the first j borders, added in border order (the
    # borders increase, so the waits before an offset are such a prefix:
    # W<=(s) = cw[ex_b0], W<(e) = cw[ex_b1], as scheduler.timing sums them)
    cw[0] = 0.0
    for j in range(nb):
        cw[j + 1] = cw[j] + waits[j]
    for i in range(d.ex_ptr[m], d.ex_ptr[m + 1]):
        r = ex_res[i]
        s = ex_s[i]
        e = ex_e[i]
        j0 = ex_b0[i]
        j1 = ex_b1[i]
        if not ex_move[i]:
            _insert(
                tl_s, tl_e, tl_own, tl_task, res_lo, res_n, r, S + s + cw[j0], S + e + cw[j1], a, t
            )
        else:
            # the pieces between the borders inside it where the arm waits,
            # each shifted by the waits before it
            p0 = s
            for j in range(j0, j1):
                if waits[j] <= 0.0:
                    continue
                b = bd_val[b0 + j]
                _insert(
                    tl_s,
                    tl_e,
                    tl_own,
                    tl_task,
                    res_lo,
                    res_n,
                    r,
                    S + p0 + cw[j],
                    S + b + cw[j],
                    a,
                    t,
                )
                p0 = b
            _insert(
                tl_s, tl_e, tl_own, tl_task, res_lo, res_n, r, S + p0 + cw[j1], S + e + cw[j1], a, t
            )
    for q in range(d.tool_ptr[m], d.tool_ptr[m + 1]):
        _insert(tl_s, tl_e, tl_own, tl_task, res_lo, res_n, d.tool_res[q], S, end, a, t)


@njit(cache=True)
def _commit_all(d, st, ts, ms, ss, es, ws, cw):
    """Record tasks ``ts`` in modes ``ms`` at ``[ss, es)`` with waits ``ws``
    (rows), in this order, each after its arm's tasks so far."""
    for i in range(len(ts)):
        t = ts[i]
        m = ms[i]
        st.t_waits[t, :] = ws[i]
        _commit(d, st, t, m, ss[i], es[i], st.arm_n[d.mode_arm[m]], ws[i], cw)


@njit(cache=True, **NO_REFCOUNT)
def _earliest(d, st, t, chrono, release):
    """Earliest start of t: release, predecessors' ends (and the latest start if chronological)."""
    pred_idx = d.pred_idx
    t_end = st.t_end
    S0 = release[t]
    for q in range(d.pred_ptr[t], d.pred_ptr[t + 1]):
        e = t_end[pred_idx[q]]
        if e > S0:
            S0 = e
    if chrono and st.t_last[0] > S0:
        S0 = st.t_last[0]
    return S0


@njit(cache=True, **NO_REFCOUNT)
def _oracle_get(keys, vals, key):
    """The answer stored under ``key`` (open addressing, linear probing), NaN if none."""
    mask = keys.shape[0] - 1
    i = key & mask
    while True:
        k = keys[i]
        if k == key:
            return vals[i]
        if k < 0:
            return math.nan
        i = (i + 1) & mask


@njit(cache=True, **NO_REFCOUNT)
def _oracle_put(keys, vals, fill, new_keys, new_vals):
    """Store answers (the table must have room: at most half full afterwards)."""
    mask = keys.shape[0] - 1
    for q in range(new_keys.shape[0]):
        key = new_keys[q]
        i = key & mask
        while keys[i] >= 0 and keys[i] != key:
            i = (i + 1) & mask
        if keys[i] < 0:
            fill[0] += 1
        keys[i] = key
        vals[i] = new_vals[q]


@njit(cache=True, **NO_REFCOUNT)
def _blocking_cost(d, st, ot, m, S):
    """Detour cost of mode m starting at S: the sum over the other arms parked
    at S (initial pose, or the end of their last task) of the oracle's cost.
    NaN when some answers are unknown (listed in ``ot.miss``)."""
    arm_lo = d.arm_lo
    mode_of = d.mode_of
    arm_n = st.arm_n
    arm_t = st.arm_t
    t_end = st.t_end
    keys = ot.keys
    vals = ot.vals
    a = d.mode_arm[m]
    A = arm_lo.shape[0]
    M = d.mode_arm.shape[0]
    row = m * (M + A)
    total = 0.0
    missing = False
    for b in range(A):
        if b == a:
            continue
        n = arm_n[b]
        if n == 0:
            col = M + b
        else:
            last = arm_t[arm_lo[b] + n - 1]
            if t_end[last] > S + EPS:
                continue  # working (or travelling) at S
            col = mode_of[b, last]
        c = _oracle_get(keys, vals, row + col)
        if c != c:
            i = ot.miss_n[0]
            if i < ot.miss.shape[0]:
                ot.miss[i, 0] = m
                ot.miss[i, 1] = col
                ot.miss_n[0] = i + 1
            missing = True
        else:
            total += c
    if missing:
        return math.nan
    return total


@njit(cache=True, **NO_REFCOUNT)
def _place_blocking(d, st, sc, ot, t, m, S0, use_waits, arm_lb):
    """Chronological placement with the oracle's detour cost.

    Returns (status, start, end, slot, cost): status PLACED, NO_PLACE (no
    start, or a parked arm in the way with no detour) or MISSING (unknown
    oracle answers listed). A later start can only see more arms parked, so
    the cost grows to a fixpoint."""
    c = 0.0
    while True:
        S, end, k = _query(d, st, sc, t, m, S0, True, use_waits, c, arm_lb)
        if not (S < INF):
            return NO_PLACE, INF, INF, -1, 0.0
        c2 = _blocking_cost(d, st, ot, m, S)
        if c2 != c2:
            return MISSING, INF, INF, -1, 0.0
        if not (c2 < INF):
            return NO_PLACE, INF, INF, -1, c2
        if c2 <= c + 1e-12:
            return PLACED, S, end, k, c
        c = c2
