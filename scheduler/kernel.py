"""The hot path: placing tasks on arm and resource timelines (numba).

Everything here works on flat numpy arrays so that numba can compile it;
``MULTIARM_NO_JIT=1`` (or ``NUMBA_DISABLE_JIT=1``) runs the same code as
plain Python, which ``benchmarks/bench_kernel.py`` uses to measure what the
compilation buys.

Placement ("query") of a task ``t`` in mode ``m`` on arm ``a``, given a state
of already placed tasks, finds the earliest start ``S >= S0`` such that

* the arm is free: the task fits into a gap of the arm's sequence (or after
  its last task) with the sequence-dependent setup before it and the setup to
  the next task after it (in *chronological* mode only after the last task);
* every exclusive zone, shared-zone movement and tool it needs is free over
  the intervals :mod:`scheduler.timing` defines, given the waits it inserts
  at zone borders (waits mode: each border gets the least wait that lets the
  next part of the path through, while the arm stands in the zones it is in;
  rigid mode: no waits, the whole task is delayed);
* start zones: an arm stands in its exclusive start zones from 0 until it
  leaves for its first task.

``commit`` records a placement. ``decode`` places a whole list of tasks in
order, with modes fixed or the earliest-finishing mode chosen (which makes
list scheduling with a priority order the earliest-finish-time baseline).

The state of a partial schedule is a handful of arrays (:class:`State`);
timelines are stored flat, each resource in its own slice, sorted by start.
Intervals on a resource never overlap, so they are sorted by end too, and a
binary search finds the first conflict.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from multiarm.types import FloatArray, IntArray

__all__ = ["EPS", "Instance", "State", "jit_enabled"]

EPS = 1e-9
INF = math.inf

_NO_JIT = os.environ.get("MULTIARM_NO_JIT", "") not in ("", "0")

if _NO_JIT:  # pragma: no cover - exercised by the kernel benchmark

    def njit(*args: Any, **kwargs: Any) -> Any:
        if args and callable(args[0]):
            return args[0]
        return lambda f: f

else:
    from numba import njit


def jit_enabled() -> bool:
    """Whether the kernel runs compiled."""
    return not _NO_JIT and os.environ.get("NUMBA_DISABLE_JIT", "") in ("", "0")


# ----------------------------------------------------------------- helpers


@njit(cache=True)
def _setup(kind, dense, mode_of, start_pt, end_pt, home, speed, base, order, a, prev, nxt):
    if kind == 0:
        return 0.0
    if kind == 1:
        return dense[a, prev + 1, nxt]
    mn = mode_of[a, nxt]
    if prev < 0:
        sx, sy, sz = home[a, 0], home[a, 1], home[a, 2]
    else:
        mp = mode_of[a, prev]
        sx, sy, sz = end_pt[mp, 0], end_pt[mp, 1], end_pt[mp, 2]
    dx = start_pt[mn, 0] - sx
    dy = start_pt[mn, 1] - sy
    dz = start_pt[mn, 2] - sz
    if order == 1:
        d = abs(dx) + abs(dy) + abs(dz)
    else:
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
    return base[a] + d / speed[a]


@njit(cache=True)
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


@njit(cache=True)
def _fit(p_res, p_s, p_e, p0, p1, t0, arm, tl_s, tl_e, tl_own, res_lo, res_n):
    """Least t >= t0 such that every piece [t + s, t + e) of p0..p1 is free."""
    t = t0
    while True:
        moved = False
        for i in range(p0, p1):
            r = p_res[i]
            n = res_n[r]
            if n == 0:
                continue
            k = _first_conflict(tl_s, tl_e, tl_own, res_lo[r], n, t + p_s[i], t + p_e[i], arm)
            if k >= 0:
                t = tl_e[k] - p_s[i]
                if not (t < INF):
                    return INF
                moved = True
        if not moved:
            return t


@njit(cache=True)
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
):
    """Earliest start >= S0 with the least waits at borders; fills
    ``waits_out[:k]``; returns (start, end without extra)."""
    seg0 = seg_ptr[m]
    nseg = seg_ptr[m + 1] - seg0
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
            return INF, INF
        S = tau
        taus[0] = tau
        ok = True
        for j in range(1, nseg):
            sj = seg0 + j
            alpha = tau + seg_len[sj - 1]
            need = _fit(
                sp_res,
                sp_s,
                sp_e,
                segp_ptr[sj],
                segp_ptr[sj + 1],
                alpha,
                arm,
                tl_s,
                tl_e,
                tl_own,
                res_lo,
                res_n,
            )
            if not (need < INF):
                return INF, INF
            w = need - alpha
            if w > EPS:
                for q in range(stand_ptr[sj], stand_ptr[sj + 1]):
                    r = st_res[q]
                    if res_n[r] == 0:
                        continue
                    k = _first_conflict(tl_s, tl_e, tl_own, res_lo[r], res_n[r], alpha, need, arm)
                    if k >= 0:
                        shift = tl_e[k] - taus[st_origin[q]]
                        if not (shift < INF):
                            return INF, INF
                        S = S + max(shift, 1e-6)
                        ok = False
                        break
                if not ok:
                    break
                waits_out[j - 1] = w
            else:
                waits_out[j - 1] = 0.0
                need = alpha
            tau = need
            taus[j] = tau
        if ok:
            return S, tau + seg_len[seg0 + nseg - 1]


@njit(cache=True)
def _query(
    t,
    m,
    S0,
    chrono,
    use_waits,
    extra,
    # instance
    mode_arm,
    mode_dur,
    rp_ptr,
    rp_res,
    rp_s,
    rp_e,
    seg_ptr,
    seg_len,
    segp_ptr,
    sp_res,
    sp_s,
    sp_e,
    stand_ptr,
    st_res,
    st_origin,
    tool_ptr,
    tool_res,
    avail,
    arm_lb,
    su_kind,
    su_dense,
    mode_of,
    su_start,
    su_end,
    su_home,
    su_speed,
    su_base,
    su_order,
    # state
    tl_s,
    tl_e,
    tl_own,
    res_lo,
    res_n,
    arm_t,
    arm_lo,
    arm_n,
    t_start,
    t_end,
    # scratch
    waits_out,
    taus,
):
    """Earliest placement of task t in mode m from S0: (start, end, arm slot)."""
    a = mode_arm[m]
    lo = arm_lo[a]
    n = arm_n[a]
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
                su_dense,
                mode_of,
                su_start,
                su_end,
                su_home,
                su_speed,
                su_base,
                su_order,
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
                su_dense,
                mode_of,
                su_start,
                su_end,
                su_home,
                su_speed,
                su_base,
                su_order,
                a,
                t,
                nxt,
            )
            if lb + mode_dur[m] + extra > limit + EPS:
                continue
        S = lb
        while True:
            if use_waits and nb > 0:
                S, end = _fit_waits(
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
                )
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


@njit(cache=True)
def _insert(tl_s, tl_e, tl_own, tl_task, res_lo, res_n, r, s, e, own, task):
    lo = res_lo[r]
    n = res_n[r]
    x = lo
    y = lo + n
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


@njit(cache=True)
def _commit(
    t,
    m,
    S,
    end,
    k,
    waits,
    mode_arm,
    ex_ptr,
    ex_res,
    ex_s,
    ex_e,
    ex_move,
    bd_ptr,
    bd_val,
    tool_ptr,
    tool_res,
    start_ptr,
    start_res,
    su_kind,
    su_dense,
    mode_of,
    su_start,
    su_end,
    su_home,
    su_speed,
    su_base,
    su_order,
    tl_s,
    tl_e,
    tl_own,
    tl_task,
    res_lo,
    res_n,
    arm_t,
    arm_lo,
    arm_n,
    t_start,
    t_end,
    t_mode,
    t_last,
):
    a = mode_arm[m]
    t_start[t] = S
    t_end[t] = end
    t_mode[t] = m
    if t_last[0] < S:
        t_last[0] = S
    lo = arm_lo[a]
    n = arm_n[a]
    for i in range(lo + n, lo + k, -1):
        arm_t[i] = arm_t[i - 1]
    arm_t[lo + k] = t
    arm_n[a] = n + 1
    if k == 0:
        # the arm leaves its start zones for its (new) first task
        dep = S - _setup(
            su_kind,
            su_dense,
            mode_of,
            su_start,
            su_end,
            su_home,
            su_speed,
            su_base,
            su_order,
            a,
            -1,
            t,
        )
        for q in range(start_ptr[a], start_ptr[a + 1]):
            r = start_res[q]
            for i in range(res_lo[r], res_lo[r] + res_n[r]):
                if tl_own[i] == a and tl_s[i] == 0.0 and tl_e[i] > dep:
                    tl_e[i] = max(dep, 0.0)
    b0 = bd_ptr[m]
    nb = bd_ptr[m + 1] - b0
    for i in range(ex_ptr[m], ex_ptr[m + 1]):
        r = ex_res[i]
        s = ex_s[i]
        e = ex_e[i]
        if not ex_move[i]:
            ws = 0.0
            we = 0.0
            for j in range(nb):
                b = bd_val[b0 + j]
                if b <= s:
                    ws += waits[j]
                if b < e:
                    we += waits[j]
            _insert(tl_s, tl_e, tl_own, tl_task, res_lo, res_n, r, S + s + ws, S + e + we, a, t)
        else:
            p0 = s
            wp = 0.0
            for j in range(nb):
                b = bd_val[b0 + j]
                if b <= s:
                    wp += waits[j]
            for j in range(nb + 1):
                if j < nb:
                    b = bd_val[b0 + j]
                    if not (s < b < e) or waits[j] <= 0.0:
                        continue
                    # piece [p0, b) then the wait at b
                    _insert(
                        tl_s, tl_e, tl_own, tl_task, res_lo, res_n, r, S + p0 + wp, S + b + wp, a, t
                    )
                    wp += waits[j]
                    p0 = b
                else:
                    _insert(
                        tl_s, tl_e, tl_own, tl_task, res_lo, res_n, r, S + p0 + wp, S + e + wp, a, t
                    )
    for q in range(tool_ptr[m], tool_ptr[m + 1]):
        _insert(tl_s, tl_e, tl_own, tl_task, res_lo, res_n, tool_res[q], S, end, a, t)


@njit(cache=True)
def _earliest(t, chrono, release, pred_ptr, pred_idx, t_end, t_last):
    S0 = release[t]
    for q in range(pred_ptr[t], pred_ptr[t + 1]):
        e = t_end[pred_idx[q]]
        if e > S0:
            S0 = e
    if chrono and t_last[0] > S0:
        S0 = t_last[0]
    return S0


@dataclass
class State:
    """A partial schedule: flat timelines and the placed tasks (arrays)."""

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
        return State(
            self.tl_s.copy(),
            self.tl_e.copy(),
            self.tl_own.copy(),
            self.tl_task.copy(),
            self.res_n.copy(),
            self.arm_t.copy(),
            self.arm_n.copy(),
            self.t_start.copy(),
            self.t_end.copy(),
            self.t_mode.copy(),
            self.t_last.copy(),
            self.t_waits.copy(),
        )


class Instance:
    """A problem compiled into the kernel's flat arrays (built once per problem)."""

    def __init__(self, problem: Any) -> None:
        from scheduler.setup import MatrixSetup, NoSetup, TravelSetup

        p = problem
        self.problem = p
        A, T, M, Z, K = p.n_arms, p.n_tasks, p.n_modes, p.n_zones, p.n_tools
        R = 2 * Z + K
        self.R = R
        shapes = p.shapes
        i64, f64 = np.int64, np.float64
        self.mode_arm = np.ascontiguousarray(p.mode_arm, dtype=i64)
        self.mode_task = np.ascontiguousarray(p.mode_task, dtype=i64)
        self.mode_dur = np.ascontiguousarray(p.mode_duration, dtype=f64)
        self.release = np.ascontiguousarray(p.task_release, dtype=f64)
        self.avail = np.ascontiguousarray(p.arm_available, dtype=f64)
        self.pred_ptr = np.zeros(T + 1, dtype=i64)
        self.pred_idx = np.array([q for ps in p.task_preds for q in ps], dtype=i64)
        self.pred_ptr[1:] = np.cumsum([len(ps) for ps in p.task_preds])
        self.tm_ptr = np.zeros(T + 1, dtype=i64)
        self.tm_idx = np.array([m for ms in p.task_modes for m in ms], dtype=i64)
        self.tm_ptr[1:] = np.cumsum([len(ms) for ms in p.task_modes])
        # rigid pieces, merged windows, borders, tools
        rp_res, rp_s, rp_e, rp_ptr = [], [], [], [0]
        ex_res, ex_s, ex_e, ex_mv, ex_ptr = [], [], [], [], [0]
        bd_val, bd_ptr = [], [0]
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
            ex_ptr.append(len(ex_res))
            tool_ptr.append(len(tool_res))
            bd_val.extend(sh.borders)
            bd_ptr.append(len(bd_val))
            # segments between breakpoints, with pieces and stands
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
        self.start_ptr = np.zeros(A + 1, dtype=i64)
        starts = []
        for a in range(A):
            zs = [z for z in p.arm_start_zones[a] if p.zone_exclusive[z]]
            starts.extend(zs)
            self.start_ptr[a + 1] = len(starts)
            for z in zs:
                cap[z] += 1
        self.start_res = np.array(starts, dtype=i64)
        arr = lambda x, dt: np.ascontiguousarray(np.array(x, dtype=dt))  # noqa: E731
        self.rp_res, self.rp_s, self.rp_e, self.rp_ptr = (
            arr(rp_res, i64),
            arr(rp_s, f64),
            arr(rp_e, f64),
            arr(rp_ptr, i64),
        )
        self.ex_res, self.ex_s, self.ex_e = arr(ex_res, i64), arr(ex_s, f64), arr(ex_e, f64)
        self.ex_move, self.ex_ptr = arr(ex_mv, np.bool_), arr(ex_ptr, i64)
        self.bd_val, self.bd_ptr = arr(bd_val, f64), arr(bd_ptr, i64)
        self.tool_res, self.tool_ptr = arr(tool_res, i64), arr(tool_ptr, i64)
        self.seg_len, self.seg_ptr = arr(seg_len, f64), arr(seg_ptr, i64)
        self.sp_res, self.sp_s, self.sp_e, self.segp_ptr = (
            arr(sp_res, i64),
            arr(sp_s, f64),
            arr(sp_e, f64),
            arr(segp_ptr, i64),
        )
        self.st_res, self.st_origin, self.stand_ptr = (
            arr(st_res, i64),
            arr(st_origin, i64),
            arr(stand_ptr, i64),
        )
        self.res_lo = np.zeros(R, dtype=i64)
        self.res_lo[1:] = np.cumsum(cap)[:-1]
        self.tl_size = int(cap.sum())
        arm_cap = np.bincount(self.mode_arm, minlength=A).astype(i64)
        self.arm_lo = np.zeros(A, dtype=i64)
        self.arm_lo[1:] = np.cumsum(arm_cap)[:-1]
        self.arm_size = int(arm_cap.sum())
        self.max_borders = int(max((len(shapes[m].borders) for m in range(M)), default=0))
        # setup
        self.mode_of = np.ascontiguousarray(p.mode_of, dtype=i64)
        setup = p.setup
        z2, z1, z0 = np.zeros((1, 1, 1)), np.zeros((1, 3)), np.zeros(1)
        self.su_kind, self.su_dense, self.su_start, self.su_end = 0, z2, z1, z1
        self.su_home, self.su_speed, self.su_base, self.su_order = z1, z0, z0, 2
        self.python_setup = False
        if isinstance(setup, NoSetup):
            pass
        elif isinstance(setup, MatrixSetup):
            self.su_kind, self.su_dense = 1, np.ascontiguousarray(setup.times, dtype=f64)
        elif isinstance(setup, TravelSetup):
            self.su_kind = 2
            self.su_start = np.ascontiguousarray(setup.start, dtype=f64)
            self.su_end = np.ascontiguousarray(setup.end, dtype=f64)
            self.su_home = np.ascontiguousarray(setup.home, dtype=f64)
            self.su_speed = np.ascontiguousarray(np.broadcast_to(setup.speed, (A,)), dtype=f64)
            self.su_base = np.ascontiguousarray(np.broadcast_to(setup.base, (A,)), dtype=f64)
            self.su_order = 1 if setup.metric == "manhattan" else 2
        else:  # any other setup: materialise the dense table once
            dense = np.zeros((A, T + 1, T))
            for a in range(A):
                for prev in range(-1, T):
                    if prev < 0 or p.mode_of[a, prev] >= 0:
                        dense[a, prev + 1] = np.where(p.mode_of[a] >= 0, p.setup_row(a, prev), 0.0)
            self.su_kind, self.su_dense = 1, dense
        self.succ_ptr = np.zeros(T + 1, dtype=i64)
        self.succ_ptr[1:] = np.cumsum([len(s) for s in p.task_succs])
        self.succ_idx = np.array([x for s in p.task_succs for x in s], dtype=i64)
        self.no_lb = np.full(A, -INF)
        self.all_modes = np.ones(M, dtype=np.bool_)
        self.scratch_w = np.zeros(max(self.max_borders, 1))
        self.scratch_tau = np.zeros(max(self.max_borders + 1, 1))

    # -------------------------------------------------------------- state
    def new_state(self) -> State:
        T = self.problem.n_tasks
        st = State(
            tl_s=np.zeros(max(self.tl_size, 1)),
            tl_e=np.zeros(max(self.tl_size, 1)),
            tl_own=np.zeros(max(self.tl_size, 1), dtype=np.int64),
            tl_task=np.full(max(self.tl_size, 1), -1, dtype=np.int64),
            res_n=np.zeros(self.R, dtype=np.int64),
            arm_t=np.zeros(max(self.arm_size, 1), dtype=np.int64),
            arm_n=np.zeros(self.problem.n_arms, dtype=np.int64),
            t_start=np.full(T, np.nan),
            t_end=np.full(T, np.nan),
            t_mode=np.full(T, -1, dtype=np.int64),
            t_last=np.zeros(1),
            t_waits=np.zeros((T, max(self.max_borders, 1))),
        )
        # arms standing in exclusive start zones hold them until they leave
        for a in range(self.problem.n_arms):
            for q in range(self.start_ptr[a], self.start_ptr[a + 1]):
                r = int(self.start_res[q])
                i = int(self.res_lo[r] + st.res_n[r])
                st.tl_s[i], st.tl_e[i], st.tl_own[i] = 0.0, INF, a
                st.res_n[r] += 1
        return st

    def _setup_args(self) -> tuple[Any, ...]:
        return (
            self.su_kind,
            self.su_dense,
            self.mode_of,
            self.su_start,
            self.su_end,
            self.su_home,
            self.su_speed,
            self.su_base,
            self.su_order,
        )

    def earliest(self, st: State, t: int, chrono: bool, release: FloatArray | None = None) -> float:
        """Earliest start of task t from releases, predecessors (and chronology)."""
        rel = self.release if release is None else release
        return float(_earliest(t, chrono, rel, self.pred_ptr, self.pred_idx, st.t_end, st.t_last))

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
        """Earliest placement of task t in mode m from S0: (start, end, slot, waits)."""
        S, end, k = _query(
            t,
            m,
            S0,
            chrono,
            waits,
            extra,
            self.mode_arm,
            self.mode_dur,
            self.rp_ptr,
            self.rp_res,
            self.rp_s,
            self.rp_e,
            self.seg_ptr,
            self.seg_len,
            self.segp_ptr,
            self.sp_res,
            self.sp_s,
            self.sp_e,
            self.stand_ptr,
            self.st_res,
            self.st_origin,
            self.tool_ptr,
            self.tool_res,
            self.avail,
            self.no_lb if arm_lb is None else arm_lb,
            *self._setup_args(),
            st.tl_s,
            st.tl_e,
            st.tl_own,
            self.res_lo,
            st.res_n,
            st.arm_t,
            self.arm_lo,
            st.arm_n,
            st.t_start,
            st.t_end,
            self.scratch_w,
            self.scratch_tau,
        )
        nb = int(self.bd_ptr[m + 1] - self.bd_ptr[m])
        return float(S), float(end), int(k), self.scratch_w[:nb].copy()

    def commit(
        self, st: State, t: int, m: int, S: float, end: float, k: int, waits: FloatArray
    ) -> None:
        """Record a placement returned by :meth:`query`."""
        w = np.zeros(max(self.max_borders, 1))
        w[: len(waits)] = waits
        st.t_waits[t] = w
        _commit(
            t,
            m,
            S,
            end,
            k,
            w,
            self.mode_arm,
            self.ex_ptr,
            self.ex_res,
            self.ex_s,
            self.ex_e,
            self.ex_move,
            self.bd_ptr,
            self.bd_val,
            self.tool_ptr,
            self.tool_res,
            self.start_ptr,
            self.start_res,
            *self._setup_args(),
            st.tl_s,
            st.tl_e,
            st.tl_own,
            st.tl_task,
            self.res_lo,
            st.res_n,
            st.arm_t,
            self.arm_lo,
            st.arm_n,
            st.t_start,
            st.t_end,
            st.t_mode,
            st.t_last,
        )


# ------------------------------------------------------------ whole passes


@njit(cache=True)
def _decode(
    order,
    fixed,
    allowed,
    arm_lb,
    chrono,
    use_waits,
    tm_ptr,
    tm_idx,
    release,
    pred_ptr,
    pred_idx,
    mode_arm,
    mode_dur,
    rp_ptr,
    rp_res,
    rp_s,
    rp_e,
    seg_ptr,
    seg_len,
    segp_ptr,
    sp_res,
    sp_s,
    sp_e,
    stand_ptr,
    st_res,
    st_origin,
    tool_ptr,
    tool_res,
    avail,
    ex_ptr,
    ex_res,
    ex_s,
    ex_e,
    ex_move,
    bd_ptr,
    bd_val,
    start_ptr,
    start_res,
    su_kind,
    su_dense,
    mode_of,
    su_start,
    su_end,
    su_home,
    su_speed,
    su_base,
    su_order,
    tl_s,
    tl_e,
    tl_own,
    tl_task,
    res_lo,
    res_n,
    arm_t,
    arm_lo,
    arm_n,
    t_start,
    t_end,
    t_mode,
    t_last,
    t_waits,
    waits_out,
    taus,
    best_w,
):
    """Place ``order`` one task after another; ``fixed[t] >= 0`` forces a mode,
    -1 picks the earliest-finishing one (ties: less waiting, lower mode id).
    A task that cannot be placed yet (a predecessor still to come, or a zone
    held by an arm that has not left its start zone) is deferred and retried
    after the others, in order. Returns 0, or -(placed + 1) when the rest
    cannot be placed at all."""
    nbmax = t_waits.shape[1]
    pending = order.copy()
    n = len(pending)
    placed = 0
    while n > 0:
        kept = 0
        for idx in range(n):
            t = pending[idx]
            ready = True
            for q in range(pred_ptr[t], pred_ptr[t + 1]):
                if t_mode[pred_idx[q]] < 0:
                    ready = False
                    break
            bm = -1
            if ready:
                S0 = _earliest(t, chrono, release, pred_ptr, pred_idx, t_end, t_last)
                best = INF
                bS = INF
                bk = -1
                bw = INF
                for mi in range(tm_ptr[t], tm_ptr[t + 1]):
                    m = tm_idx[mi]
                    if (fixed[t] >= 0 and m != fixed[t]) or not allowed[m]:
                        continue
                    S, end, k = _query(
                        t,
                        m,
                        S0,
                        chrono,
                        use_waits,
                        0.0,
                        mode_arm,
                        mode_dur,
                        rp_ptr,
                        rp_res,
                        rp_s,
                        rp_e,
                        seg_ptr,
                        seg_len,
                        segp_ptr,
                        sp_res,
                        sp_s,
                        sp_e,
                        stand_ptr,
                        st_res,
                        st_origin,
                        tool_ptr,
                        tool_res,
                        avail,
                        arm_lb,
                        su_kind,
                        su_dense,
                        mode_of,
                        su_start,
                        su_end,
                        su_home,
                        su_speed,
                        su_base,
                        su_order,
                        tl_s,
                        tl_e,
                        tl_own,
                        res_lo,
                        res_n,
                        arm_t,
                        arm_lo,
                        arm_n,
                        t_start,
                        t_end,
                        waits_out,
                        taus,
                    )
                    if not (end < INF):
                        continue
                    nb = bd_ptr[m + 1] - bd_ptr[m]
                    wsum = 0.0
                    if use_waits:
                        for j in range(nb):
                            wsum += waits_out[j]
                    if end < best - EPS or (end <= best + EPS and wsum < bw - EPS):
                        best = end
                        bS = S
                        bk = k
                        bm = m
                        bw = wsum
                        for j in range(nbmax):
                            best_w[j] = waits_out[j] if (use_waits and j < nb) else 0.0
            if bm < 0:
                pending[kept] = t
                kept += 1
                continue
            for j in range(nbmax):
                t_waits[t, j] = best_w[j]
            _commit(
                t,
                bm,
                bS,
                best,
                bk,
                best_w,
                mode_arm,
                ex_ptr,
                ex_res,
                ex_s,
                ex_e,
                ex_move,
                bd_ptr,
                bd_val,
                tool_ptr,
                tool_res,
                start_ptr,
                start_res,
                su_kind,
                su_dense,
                mode_of,
                su_start,
                su_end,
                su_home,
                su_speed,
                su_base,
                su_order,
                tl_s,
                tl_e,
                tl_own,
                tl_task,
                res_lo,
                res_n,
                arm_t,
                arm_lo,
                arm_n,
                t_start,
                t_end,
                t_mode,
                t_last,
            )
            placed += 1
        if kept == n:
            return -(placed + 1)
        n = kept
    return 0


@njit(cache=True)
def _expand(
    cand_t,
    cand_m,
    arm_lb,
    chrono,
    use_waits,
    release,
    pred_ptr,
    pred_idx,
    mode_arm,
    mode_dur,
    rp_ptr,
    rp_res,
    rp_s,
    rp_e,
    seg_ptr,
    seg_len,
    segp_ptr,
    sp_res,
    sp_s,
    sp_e,
    stand_ptr,
    st_res,
    st_origin,
    tool_ptr,
    tool_res,
    avail,
    bd_ptr,
    su_kind,
    su_dense,
    mode_of,
    su_start,
    su_end,
    su_home,
    su_speed,
    su_base,
    su_order,
    tl_s,
    tl_e,
    tl_own,
    res_lo,
    res_n,
    arm_t,
    arm_lo,
    arm_n,
    t_start,
    t_end,
    t_last,
    waits_out,
    taus,
    out_S,
    out_end,
    out_k,
    out_w,
    out_waits,
):
    """Query many (task, mode) candidates against one state (read-only)."""
    nbmax = out_waits.shape[1]
    for i in range(len(cand_t)):
        t = cand_t[i]
        m = cand_m[i]
        S0 = _earliest(t, chrono, release, pred_ptr, pred_idx, t_end, t_last)
        S, end, k = _query(
            t,
            m,
            S0,
            chrono,
            use_waits,
            0.0,
            mode_arm,
            mode_dur,
            rp_ptr,
            rp_res,
            rp_s,
            rp_e,
            seg_ptr,
            seg_len,
            segp_ptr,
            sp_res,
            sp_s,
            sp_e,
            stand_ptr,
            st_res,
            st_origin,
            tool_ptr,
            tool_res,
            avail,
            arm_lb,
            su_kind,
            su_dense,
            mode_of,
            su_start,
            su_end,
            su_home,
            su_speed,
            su_base,
            su_order,
            tl_s,
            tl_e,
            tl_own,
            res_lo,
            res_n,
            arm_t,
            arm_lo,
            arm_n,
            t_start,
            t_end,
            waits_out,
            taus,
        )
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


def _inst_args(inst: Instance) -> tuple[Any, ...]:
    return (
        inst.mode_arm,
        inst.mode_dur,
        inst.rp_ptr,
        inst.rp_res,
        inst.rp_s,
        inst.rp_e,
        inst.seg_ptr,
        inst.seg_len,
        inst.segp_ptr,
        inst.sp_res,
        inst.sp_s,
        inst.sp_e,
        inst.stand_ptr,
        inst.st_res,
        inst.st_origin,
        inst.tool_ptr,
        inst.tool_res,
        inst.avail,
        inst.ex_ptr,
        inst.ex_res,
        inst.ex_s,
        inst.ex_e,
        inst.ex_move,
        inst.bd_ptr,
        inst.bd_val,
        inst.start_ptr,
        inst.start_res,
        *inst._setup_args(),
    )


def _state_args(inst: Instance, st: State) -> tuple[Any, ...]:
    return (
        st.tl_s,
        st.tl_e,
        st.tl_own,
        st.tl_task,
        inst.res_lo,
        st.res_n,
        st.arm_t,
        inst.arm_lo,
        st.arm_n,
        st.t_start,
        st.t_end,
        st.t_mode,
        st.t_last,
        st.t_waits,
    )


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
) -> tuple[int, State]:
    """Place ``order`` (see :func:`_decode`) on top of ``state`` (default: empty);
    ``release`` overrides release times, ``allowed`` masks modes (M,) and
    ``arm_lb`` gives each arm a time it cannot start before. Returns (code,
    state): code 0 on success, ``-(placed + 1)`` when the remaining tasks
    cannot be placed at all (a zone held for good)."""
    st = inst.new_state() if state is None else state
    best_w = np.zeros(max(inst.max_borders, 1))
    code = _decode(
        np.ascontiguousarray(order, dtype=np.int64),
        np.ascontiguousarray(fixed, dtype=np.int64),
        inst.all_modes if allowed is None else allowed,
        inst.no_lb if arm_lb is None else arm_lb,
        chrono,
        waits,
        inst.tm_ptr,
        inst.tm_idx,
        inst.release if release is None else release,
        inst.pred_ptr,
        inst.pred_idx,
        *_inst_args(inst),
        *_state_args(inst, st),
        inst.scratch_w,
        inst.scratch_tau,
        best_w,
    )
    return int(code), st


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
    """Query candidates (task, mode) against ``st``: (start, end, slot, total wait, waits)."""
    n = len(cand_t)
    out_S, out_end, out_w = np.zeros(n), np.zeros(n), np.zeros(n)
    out_k = np.zeros(n, dtype=np.int64)
    out_waits = np.zeros((n, max(inst.max_borders, 1)))
    _expand(
        np.ascontiguousarray(cand_t, dtype=np.int64),
        np.ascontiguousarray(cand_m, dtype=np.int64),
        inst.no_lb if arm_lb is None else arm_lb,
        chrono,
        waits,
        inst.release if release is None else release,
        inst.pred_ptr,
        inst.pred_idx,
        inst.mode_arm,
        inst.mode_dur,
        inst.rp_ptr,
        inst.rp_res,
        inst.rp_s,
        inst.rp_e,
        inst.seg_ptr,
        inst.seg_len,
        inst.segp_ptr,
        inst.sp_res,
        inst.sp_s,
        inst.sp_e,
        inst.stand_ptr,
        inst.st_res,
        inst.st_origin,
        inst.tool_ptr,
        inst.tool_res,
        inst.avail,
        inst.bd_ptr,
        *inst._setup_args(),
        st.tl_s,
        st.tl_e,
        st.tl_own,
        inst.res_lo,
        st.res_n,
        st.arm_t,
        inst.arm_lo,
        st.arm_n,
        st.t_start,
        st.t_end,
        st.t_last,
        inst.scratch_w,
        inst.scratch_tau,
        out_S,
        out_end,
        out_k,
        out_w,
        out_waits,
    )
    return out_S, out_end, out_k, out_w, out_waits


def to_schedule(inst: Instance, st: State) -> Any:
    """The :class:`~scheduler.schedule.Schedule` of a complete state (blocking
    cost = whatever the end exceeds start + duration + waits by)."""
    from scheduler.schedule import Schedule

    p = inst.problem
    shapes = p.shapes
    T = p.n_tasks
    waits = []
    blocking = np.zeros(T)
    for t in range(T):
        m = int(st.t_mode[t])
        sh = shapes[m]
        w = st.t_waits[t, : len(sh.borders)].copy()
        waits.append(w)
        blocking[t] = max(0.0, float(st.t_end[t]) - float(st.t_start[t]) - sh.length(w))
        if blocking[t] <= 1e-12 * max(1.0, abs(float(st.t_end[t]))):
            blocking[t] = 0.0
    return Schedule(st.t_mode.copy(), st.t_start.copy(), st.t_end.copy(), tuple(waits), blocking)


# -------------------------------------------------- sequence decoding


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
def _seq_decode(
    seq,
    seq_n,
    modes,
    use_waits,
    release,
    pred_ptr,
    pred_idx,
    succ_ptr,
    succ_idx,
    mode_arm,
    mode_dur,
    rp_ptr,
    rp_res,
    rp_s,
    rp_e,
    seg_ptr,
    seg_len,
    segp_ptr,
    sp_res,
    sp_s,
    sp_e,
    stand_ptr,
    st_res,
    st_origin,
    tool_ptr,
    tool_res,
    avail,
    arm_lb,
    ex_ptr,
    ex_res,
    ex_s,
    ex_e,
    ex_move,
    bd_ptr,
    bd_val,
    start_ptr,
    start_res,
    su_kind,
    su_dense,
    mode_of,
    su_start,
    su_end,
    su_home,
    su_speed,
    su_base,
    su_order,
    tl_s,
    tl_e,
    tl_own,
    tl_task,
    res_lo,
    res_n,
    arm_t,
    arm_lo,
    arm_n,
    t_start,
    t_end,
    t_mode,
    t_last,
    t_waits,
    waits_out,
    taus,
    best_w,
    order_out,
):
    """Decode fixed arm sequences ``seq[a, :seq_n[a]]`` with fixed ``modes``:
    tasks whose predecessors and previous task on the arm are placed go in
    order of earliest possible start, each at its earliest feasible time
    after its arm's previous task (zones, tools, waits as in ``_query``).
    Returns the number of tasks placed (fewer than T: the sequences contradict
    the precedence, or a start zone is held for good)."""
    T = len(release)
    A = seq.shape[0]
    nbmax = t_waits.shape[1]
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
        S0 = _earliest(t, False, release, pred_ptr, pred_idx, t_end, t_last)
        S, end, k = _query(
            t,
            m,
            S0,
            True,
            use_waits,
            0.0,
            mode_arm,
            mode_dur,
            rp_ptr,
            rp_res,
            rp_s,
            rp_e,
            seg_ptr,
            seg_len,
            segp_ptr,
            sp_res,
            sp_s,
            sp_e,
            stand_ptr,
            st_res,
            st_origin,
            tool_ptr,
            tool_res,
            avail,
            arm_lb,
            su_kind,
            su_dense,
            mode_of,
            su_start,
            su_end,
            su_home,
            su_speed,
            su_base,
            su_order,
            tl_s,
            tl_e,
            tl_own,
            res_lo,
            res_n,
            arm_t,
            arm_lo,
            arm_n,
            t_start,
            t_end,
            waits_out,
            taus,
        )
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
        _commit(
            t,
            m,
            S,
            end,
            k,
            best_w,
            mode_arm,
            ex_ptr,
            ex_res,
            ex_s,
            ex_e,
            ex_move,
            bd_ptr,
            bd_val,
            tool_ptr,
            tool_res,
            start_ptr,
            start_res,
            su_kind,
            su_dense,
            mode_of,
            su_start,
            su_end,
            su_home,
            su_speed,
            su_base,
            su_order,
            tl_s,
            tl_e,
            tl_own,
            tl_task,
            res_lo,
            res_n,
            arm_t,
            arm_lo,
            arm_n,
            t_start,
            t_end,
            t_mode,
            t_last,
        )
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
    """Decode arm sequences (see :func:`_seq_decode`) on top of ``state``:
    (complete, state, processing order of the newly placed tasks)."""
    st = inst.new_state() if state is None else state
    T = inst.problem.n_tasks
    todo = int((st.t_mode < 0).sum())
    succ = inst.succ_ptr, inst.succ_idx
    order = np.full(T, -1, dtype=np.int64)
    best_w = np.zeros(max(inst.max_borders, 1))
    placed = _seq_decode(
        seq,
        seq_n,
        modes,
        waits,
        inst.release if release is None else release,
        inst.pred_ptr,
        inst.pred_idx,
        *succ,
        inst.mode_arm,
        inst.mode_dur,
        inst.rp_ptr,
        inst.rp_res,
        inst.rp_s,
        inst.rp_e,
        inst.seg_ptr,
        inst.seg_len,
        inst.segp_ptr,
        inst.sp_res,
        inst.sp_s,
        inst.sp_e,
        inst.stand_ptr,
        inst.st_res,
        inst.st_origin,
        inst.tool_ptr,
        inst.tool_res,
        inst.avail,
        inst.no_lb if arm_lb is None else arm_lb,
        inst.ex_ptr,
        inst.ex_res,
        inst.ex_s,
        inst.ex_e,
        inst.ex_move,
        inst.bd_ptr,
        inst.bd_val,
        inst.start_ptr,
        inst.start_res,
        *inst._setup_args(),
        st.tl_s,
        st.tl_e,
        st.tl_own,
        st.tl_task,
        inst.res_lo,
        st.res_n,
        st.arm_t,
        inst.arm_lo,
        st.arm_n,
        st.t_start,
        st.t_end,
        st.t_mode,
        st.t_last,
        st.t_waits,
        inst.scratch_w,
        inst.scratch_tau,
        best_w,
        order,
    )
    return placed == todo, st, order[:placed]
