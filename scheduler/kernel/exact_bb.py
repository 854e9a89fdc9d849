"""Compiled pieces of the exact branch and bound (:func:`scheduler.exact.prove`).

A simple temporal network (STN) kept as arrays: time points, edges
``x[v] >= x[u] + w`` in per-source linked lists, earliest times ``dist``
(longest paths from the origin, point 0). An edge is added with
:func:`stn_add` (incremental label correcting from its head; a positive
cycle, i.e. an infeasible branch, shows as the edge's own tail growing) and
edges are removed last-in first-out with :func:`stn_pop`. :func:`conflict`
finds the pair of orders to branch on and :func:`node_bound` the node's lower
bound (see :mod:`scheduler.exact` for why each is exact).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from scheduler.kernel._jit import njit

__all__ = [
    "arm_bound",
    "conflict",
    "diagram_bound",
    "diagram_chain",
    "jackson_bound",
    "node_bound",
    "select_pairs",
    "stn_add",
    "stn_pop",
    "stn_tails",
]

_EPS = 1e-9


@njit(cache=True)  # type: ignore[untyped-decorator]
def stn_add(
    head: Any,
    nxt: Any,
    src: Any,
    dst: Any,
    wt: Any,
    ne: Any,
    dist: Any,
    queue: Any,
    queued: Any,
    u: int,
    v: int,
    w: float,
) -> bool:  # pragma: no cover - compiled
    """Add ``x[v] >= x[u] + w`` (edge number ``ne[0]``); False on a positive cycle.

    The edge stays in either case (pop it with :func:`stn_pop`). First-in
    first-out label correcting from ``v`` (``queue`` holds ``len(dist) + 1``
    points, ``queued`` all False on entry and on return): the network had no
    positive cycle before, so any new one runs through the new edge and
    shows as ``x[u]`` growing; without one, every point is queued at most
    ``len(dist)`` times, so the count limit is only a safety net (hitting it
    also reports a cycle).
    """
    e = ne[0]
    src[e] = u
    dst[e] = v
    wt[e] = w
    nxt[e] = head[u]
    head[u] = e
    ne[0] = e + 1
    if dist[u] + w <= dist[v] + _EPS:
        return True
    n = len(dist)
    cap = len(queue)
    dist[v] = dist[u] + w
    lo = 0
    size = 1
    queue[0] = v
    queued[v] = True
    count = 0
    limit = n * n + 100
    ok = True
    while size > 0:
        x = queue[lo]
        lo = (lo + 1) % cap
        size -= 1
        queued[x] = False
        if not ok:
            continue  # drain, so that queued is all False again
        dx = dist[x]
        f = head[x]
        while f >= 0:
            y = dst[f]
            if dx + wt[f] > dist[y] + _EPS:
                if y == u:
                    ok = False
                    break
                dist[y] = dx + wt[f]
                if not queued[y]:
                    queue[(lo + size) % cap] = y
                    size += 1
                    queued[y] = True
                    count += 1
                    if count > limit:
                        ok = False
                        break
            f = nxt[f]
    return ok


@njit(cache=True)  # type: ignore[untyped-decorator]
def stn_pop(head: Any, nxt: Any, src: Any, ne: Any, keep: int) -> None:  # pragma: no cover
    """Remove the edges added after the first ``keep`` (last in, first out)."""
    e = ne[0] - 1
    while e >= keep:
        head[src[e]] = nxt[e]
        e -= 1
    ne[0] = keep


@njit(cache=True)  # type: ignore[untyped-decorator]
def conflict(
    dist: Any,
    t_start: Any,
    t_end: Any,
    t_arm: Any,
    setup: Any,
    i_lo: Any,
    i_task: Any,
    i_ps: Any,
    i_os: Any,
    i_pe: Any,
    i_oe: Any,
    out: Any,
) -> int:  # pragma: no cover - compiled
    """The conflict to branch on at the earliest times ``dist``; 0 when none.

    Tasks ``t`` (start point ``t_start[t]``, end point ``t_end[t]``, arm
    ``t_arm[t]``; ``setup[t, t']`` the travel between them, ``inf`` across
    arms) conflict when both orders are violated; intervals (grouped by
    resource: group ``g`` is ``i_lo[g]:i_lo[g+1]``, each from point
    ``i_ps`` plus ``i_os`` to point ``i_pe`` plus ``i_oe``) of tasks of
    different arms conflict when they overlap. The one picked is the
    earliest (smallest start of the pair's later interval, then the largest
    overlap). ``out`` receives ``u1, v1, u2, v2`` and ``w1, w2`` at
    ``out[4:6]``: branch 1 adds ``x[v1] >= x[u1] + w1``, branch 2 the other.
    Returns 1 when a conflict was found.
    """
    found = 0
    best_key = np.inf
    best_ov = -1.0
    T = len(t_start)
    for x in range(T):
        for y in range(x + 1, T):
            if t_arm[x] != t_arm[y]:
                continue
            sx = dist[t_start[x]]
            ex = dist[t_end[x]]
            sy = dist[t_start[y]]
            ey = dist[t_end[y]]
            a = ex + setup[x, y]
            b = ey + setup[y, x]
            if sy < a - _EPS and sx < b - _EPS:
                key = max(sx, sy)
                ov = min(a - sy, b - sx)
                if key < best_key - _EPS or (key < best_key + _EPS and ov > best_ov):
                    best_key = key
                    best_ov = ov
                    found = 1
                    out[0] = t_end[x]
                    out[1] = t_start[y]
                    out[4] = setup[x, y]
                    out[2] = t_end[y]
                    out[3] = t_start[x]
                    out[5] = setup[y, x]
    G = len(i_lo) - 1
    for g in range(G):
        for i in range(i_lo[g], i_lo[g + 1]):
            s1 = dist[i_ps[i]] + i_os[i]
            e1 = dist[i_pe[i]] + i_oe[i]
            for j in range(i + 1, i_lo[g + 1]):
                if t_arm[i_task[i]] == t_arm[i_task[j]]:
                    continue
                s2 = dist[i_ps[j]] + i_os[j]
                e2 = dist[i_pe[j]] + i_oe[j]
                if s1 < e2 - _EPS and s2 < e1 - _EPS:
                    key = max(s1, s2)
                    ov = min(e1, e2) - key
                    if key < best_key - _EPS or (key < best_key + _EPS and ov > best_ov):
                        best_key = key
                        best_ov = ov
                        found = 1
                        out[0] = i_pe[i]
                        out[1] = i_ps[j]
                        out[4] = i_oe[i] - i_os[j]
                        out[2] = i_pe[j]
                        out[3] = i_ps[i]
                        out[5] = i_oe[j] - i_os[i]
    return found


@njit(cache=True)  # type: ignore[untyped-decorator]
def stn_tails(
    head: Any, nxt: Any, dst: Any, wt: Any, t_end: Any, tail: Any
) -> None:  # pragma: no cover - compiled
    """Longest paths to the end: ``tail[u]`` is the longest path of the network
    from point ``u`` to any task's end point (0 at an end point; ``-inf`` when
    no end point is reachable).

    Every completion of the node satisfies every edge, so its makespan is at
    least ``x[u] + tail[u]``. The network has no positive cycle (the caller
    only asks on feasible nodes), so the passes (Bellman-Ford, points taken
    from the last: a task's own chain settles in one pass) end after at most
    ``len(tail)`` of them.
    """
    n = len(tail)
    for u in range(n):
        tail[u] = -np.inf
    for t in range(len(t_end)):
        tail[t_end[t]] = 0.0
    for _ in range(n + 1):
        changed = False
        for u in range(n - 1, -1, -1):
            best = tail[u]
            f = head[u]
            while f >= 0:
                tv = tail[dst[f]]
                if tv > -np.inf and wt[f] + tv > best + _EPS:
                    best = wt[f] + tv
                f = nxt[f]
            if best > tail[u]:
                tail[u] = best
                changed = True
        if not changed:
            break


@njit(cache=True)  # type: ignore[untyped-decorator]
def jackson_bound(
    head: Any, length: Any, tail: Any, n: int, order: Any
) -> float:  # pragma: no cover - compiled
    """The preemptive one-machine bound of the first ``n`` items (Jackson's
    preemptive schedule, Carlier): ``max over subsets J of min head(J) +
    sum length(J) + min tail(J)``.

    For a subset ``J`` with least head ``a`` and least tail ``b``, every item
    with ``head >= a`` and ``tail >= b`` may be added (the sum only grows), so
    the maximum is taken over the ``n * n`` pairs ``(a, b)`` of a head and a
    tail of the items. ``order`` is scratch (``n`` ints).
    """
    if n == 0:
        return 0.0
    idx = np.argsort(-tail[:n])  # by decreasing tail
    for k in range(n):
        order[k] = idx[k]
    best = 0.0
    for i in range(n):
        a = head[i]
        total = 0.0
        for k in range(n):
            j = order[k]
            if head[j] >= a:
                total += length[j]
                best = max(best, a + total + tail[j])
    return best


@njit(cache=True)  # type: ignore[untyped-decorator]
def _one_machine(
    head: Any, length: Any, tail: Any, extra: Any, n: int
) -> float:  # pragma: no cover
    """``max_k head_k + sum_{head_j >= head_k} (length_j + extra_j) - max extra_j
    + min tail_j`` over the first ``n`` items: a one-machine bound (each
    item's ``extra``, a least travel before it, counted for all but one)."""
    if n == 0:
        return 0.0
    order = np.argsort(head[:n])
    best = 0.0
    total = 0.0
    mt = np.inf
    mx = 0.0
    for k in range(n - 1, -1, -1):
        i = order[k]
        total += length[i] + extra[i]
        mt = min(mt, tail[i])
        mx = max(mx, extra[i])
        best = max(best, head[i] + total - mx + mt)
    return best


@njit(cache=True)  # type: ignore[untyped-decorator]
def arm_bound(
    th: Any,
    t_arm: Any,
    t_dur: Any,
    t_tail: Any,
    t_setin: Any,
    cap: Any,
    n_arms: int,
    h: Any,
    ln: Any,
    tl: Any,
    ex: Any,
) -> float:  # pragma: no cover - compiled
    """Arm bounds of the tasks with ``t_arm >= 0`` (earliest starts ``th``).

    Per arm, the one-machine bound (nominal durations, least travel into each
    task counted for all but one). Per pair of arms ``A, B`` and threshold
    ``h``: the tasks ``X`` of ``A`` and ``Y`` of ``B`` that start at ``h`` or
    later all progress inside ``[h, C - q)`` (``q`` their least tail), ``A``
    for ``sum X`` and ``B`` for ``sum Y``, both at once for at most
    ``sum cap[x, y]`` (the overlap caps of :mod:`scheduler.overlap`), so
    ``C >= h + sum X + sum Y - sum cap + q``.
    """
    T = len(th)
    best = 0.0
    for a in range(n_arms):
        n = 0
        for t in range(T):
            if t_arm[t] == a:
                h[n] = th[t]
                ln[n] = t_dur[t]
                tl[n] = t_tail[t]
                ex[n] = t_setin[t]
                n += 1
        best = max(best, float(_one_machine(h, ln, tl, ex, n)))
    order = np.argsort(th)
    seen = np.zeros(T, dtype=np.bool_)
    for a in range(n_arms):
        for b in range(a + 1, n_arms):
            sa = 0.0
            sb = 0.0
            ca = 0.0
            cb = 0.0
            xa = 0.0
            xb = 0.0
            caps = 0.0
            qmin = np.inf
            seen[:] = False
            for k in range(T - 1, -1, -1):
                x = order[k]
                if t_arm[x] != a and t_arm[x] != b:
                    continue
                for y in range(T):
                    if seen[y] and t_arm[y] != t_arm[x]:
                        caps += cap[x, y]
                seen[x] = True
                if t_arm[x] == a:
                    sa += t_dur[x]
                    ca += t_setin[x]
                    xa = max(xa, t_setin[x])
                else:
                    sb += t_dur[x]
                    cb += t_setin[x]
                    xb = max(xb, t_setin[x])
                qmin = min(qmin, t_tail[x])
                span = max(sa + ca - xa, sb + cb - xb, sa + sb - caps)
                best = max(best, th[x] + span + qmin)
    return best


@njit(cache=True)  # type: ignore[untyped-decorator]
def node_bound(
    dist: Any,
    t_start: Any,
    t_end: Any,
    t_arm: Any,
    t_dur: Any,
    t_tail: Any,
    t_setin: Any,
    n_arms: int,
    cap: Any,
    th: Any,
    i_lo: Any,
    i_task: Any,
    i_ps: Any,
    i_os: Any,
    i_len: Any,
    i_tail: Any,
    h: Any,
    ln: Any,
    tl: Any,
    ex: Any,
    e_head: Any,
    e_nxt: Any,
    e_dst: Any,
    e_wt: Any,
    i_pe: Any,
    i_oe: Any,
    tail_pt: Any,
    tt: Any,
    scratch: Any,
    cut: float = np.inf,
    deep: bool = True,
) -> float:  # pragma: no cover - compiled
    """A lower bound of every completion of the node (see :mod:`scheduler.exact`).

    The largest of: each task's earliest end plus its tail; per arm, the
    one-machine bound of its tasks (earliest starts, nominal durations, least
    travel into each, tails); per resource group, the one-machine bound of
    its intervals (earliest starts, nominal lengths, the rest of the task
    after the interval plus the task's tail).

    Tails are the larger of the static ones (least durations of the
    successors) and the network's longest paths to the end (:func:`stn_tails`
    on the edges ``e_head, e_nxt, e_dst, e_wt``: precedence, the arm
    sequences and orders fixed so far, with nominal steps), into ``tail_pt``
    (one per point) and ``tt`` (one per task). Each resource group's bound is
    Jackson's preemptive bound (:func:`jackson_bound`) over all its
    intervals, of every arm (``scratch``: ints, one per interval).

    The cheap bounds come first (static tails, the suffix one-machine bound
    per resource): when they reach ``cut`` (the node is pruned anyway), or
    without ``deep``, the network's tails and the preemptive bounds are not
    computed.
    """
    T = len(t_start)
    best = 0.0
    for t in range(T):
        best = max(best, dist[t_end[t]] + t_tail[t])
        th[t] = dist[t_start[t]]
    best = max(
        best, float(arm_bound(th, t_arm, t_dur, t_tail, t_setin, cap, n_arms, h, ln, tl, ex))
    )
    G = len(i_lo) - 1
    for g in range(G):
        if best >= cut:
            return best
        n = 0
        for i in range(i_lo[g], i_lo[g + 1]):
            h[n] = dist[i_ps[i]] + i_os[i]
            ln[n] = i_len[i]
            tl[n] = i_tail[i] + t_tail[i_task[i]]
            ex[n] = 0.0
            n += 1
        best = max(best, float(_one_machine(h, ln, tl, ex, n)))
    if best >= cut or not deep:
        return best
    stn_tails(e_head, e_nxt, e_dst, e_wt, t_end, tail_pt)
    for t in range(T):
        tt[t] = max(t_tail[t], tail_pt[t_end[t]])
        best = max(best, dist[t_end[t]] + tt[t])
    best = max(best, float(arm_bound(th, t_arm, t_dur, tt, t_setin, cap, n_arms, h, ln, tl, ex)))
    for g in range(G):
        if best >= cut:
            return best
        n = 0
        for i in range(i_lo[g], i_lo[g + 1]):
            h[n] = dist[i_ps[i]] + i_os[i]
            ln[n] = i_len[i]
            tl[n] = max(i_tail[i] + t_tail[i_task[i]], tail_pt[i_pe[i]] - i_oe[i])
            n += 1
        best = max(best, float(jackson_bound(h, ln, tl, n, scratch)))
    return best


@njit(cache=True)  # type: ignore[untyped-decorator]
def _mark(
    flags: Any, s1: float, e1: float, s2: float, e2: float, step: float
) -> None:  # pragma: no cover - compiled
    """Set the cells lying entirely inside the open rectangle (as :mod:`scheduler.overlap`).

    Cell ``i`` is ``[i step, (i + 1) step]``: inside ``(s, e)`` when ``i >
    s / step`` and ``i < e / step - 1``. The quotients are moved by 1e-6 of
    a cell towards marking fewer cells, so that rounding (an ``e / step`` a
    hair above the whole number it really is) never marks a cell that a
    real path may cross: fewer marked cells only lower the bound."""
    n, m = flags.shape
    i0 = max(int(np.floor(s1 / step + 1e-6)) + 1, 0)
    i1 = min(int(np.ceil(e1 / step - 1e-6)) - 2, n - 1)
    j0 = max(int(np.floor(s2 / step + 1e-6)) + 1, 0)
    j1 = min(int(np.ceil(e2 / step - 1e-6)) - 2, m - 1)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            flags[i, j] = True


@njit(cache=True)  # type: ignore[untyped-decorator]
def diagram_chain(blocked: Any, nodiag: Any) -> Any:  # pragma: no cover - compiled
    """Per cell, the longest chain of diagonal-free cells, rows and columns
    increasing, along a staircase of unblocked cells from the first cell to
    it (-1: unreachable).

    State per cell: whether the chain already holds a cell of this row
    (``r``) and of this column (``c``), as ``2 r + c``; a cell joins the
    chain only from state 0. (The overlap caps of :mod:`scheduler.overlap` and
    :func:`diagram_bound` share it; it lives here so that numba's cache of
    :func:`diagram_bound`, checked against this file only, is never stale.)"""
    n, m = blocked.shape
    table = np.full((n, m), -1, np.int64)
    prev = np.full((m, 4), -1, np.int64)
    for i in range(n):
        cur = np.full((m, 4), -1, np.int64)
        for j in range(m):
            if blocked[i, j]:
                continue
            if i == 0 and j == 0:
                cur[0, 0] = 0
            for s in range(4):
                if i > 0 and prev[j, s] > cur[j, s & 1]:  # from below-left row: new row
                    cur[j, s & 1] = prev[j, s]
                if j > 0 and cur[j - 1, s] > cur[j, s & 2]:  # new column
                    cur[j, s & 2] = cur[j - 1, s]
                if i > 0 and j > 0 and prev[j - 1, s] > cur[j, 0]:  # through the corner
                    cur[j, 0] = prev[j - 1, s]
            if not nodiag[i, j] and cur[j, 0] >= 0 and cur[j, 0] + 1 > cur[j, 3]:
                cur[j, 3] = cur[j, 0] + 1
            for s in range(4):
                table[i, j] = max(table[i, j], cur[j, s])
        prev = cur
    return table


@njit(cache=True)  # type: ignore[untyped-decorator]
def diagram_bound(
    la: float,
    lb: float,
    a_res: Any,
    a_s: Any,
    a_e: Any,
    b_res: Any,
    b_s: Any,
    b_e: Any,
    presence: Any,
    p_dir: Any,
    p_end: Any,
    p_start: Any,
    a_at: Any,
    a_head: Any,
    b_at: Any,
    b_head: Any,
    step: float,
    cut: float,
    max_cells: float = 160_000.0,
) -> float:  # pragma: no cover - compiled
    """A lower bound of the makespan from the coordination diagram of two arms'
    whole sequences (-1: no path, the sequences are infeasible).

    Arm A's progress axis has length ``la`` (its tasks and travel end to end),
    B's ``lb``; windows ``(res, s, e)`` are offsets on those axes. Two windows
    in one resource forbid their open rectangle (blocked when
    ``presence[res]``: an exclusive zone or a tool; else closed to diagonal
    steps: movement in a shared zone). A precedence ``k`` with ``p_dir[k] ==
    0`` (a task of A before one of B) forbids ``u < p_end[k]`` together with
    ``v > p_start[k]`` (axes swapped when ``p_dir[k] == 1``). A schedule is a
    monotone path from ``(0, 0)`` to ``(la, lb)`` taking ``la + lb - D`` time
    at least, ``D`` its diagonal, and the longest chain of
    :func:`diagram_chain` times ``step`` bounds ``D``
    (:mod:`scheduler.overlap`'s argument). Heads: A's task starting at
    progress ``a_at[k]`` starts no earlier than ``a_head[k]``; when the path
    crosses ``u = a_at[k]`` at ``v`` in cell row ``j``, the time is at least
    ``max(a_head[k], a_at[k], j step)`` and what is left takes at least
    ``la - a_at[k] + lb - (j + 1) step`` less the chain from that cell to the
    end; the least over ``j`` bounds the makespan (B's heads likewise).
    Returns as soon as the bound reaches ``cut``. The cell side is raised so
    that the grid has at most ``max_cells`` cells (any side gives a bound).
    """
    step = max(step, np.sqrt(la * lb / max_cells))
    n = max(1, int(np.ceil(la / step - 1e-9)))
    m = max(1, int(np.ceil(lb / step - 1e-9)))
    blocked = np.zeros((n, m), dtype=np.bool_)
    nodiag = np.zeros((n, m), dtype=np.bool_)
    for i in range(len(a_res)):
        for j in range(len(b_res)):
            if a_res[i] != b_res[j]:
                continue
            if presence[a_res[i]]:
                _mark(blocked, a_s[i], a_e[i], b_s[j], b_e[j], step)
            _mark(nodiag, a_s[i], a_e[i], b_s[j], b_e[j], step)
    for k in range(len(p_dir)):
        if p_dir[k] == 0:
            _mark(blocked, -2.0 * step, p_end[k], p_start[k], lb + 2.0 * step, step)
        else:
            _mark(blocked, p_start[k], la + 2.0 * step, -2.0 * step, p_end[k], step)
    if blocked[0, 0] or blocked[n - 1, m - 1]:
        return -1.0
    table = diagram_chain(blocked, nodiag)
    if table[n - 1, m - 1] < 0:
        return -1.0
    best = la + lb - min(float(table[n - 1, m - 1]) * step, la, lb)
    if len(a_at) + len(b_at) == 0 or best >= cut:
        return best
    back = diagram_chain(
        np.ascontiguousarray(blocked[::-1, ::-1]), np.ascontiguousarray(nodiag[::-1, ::-1])
    )[::-1, ::-1]
    for k in range(len(a_at)):
        i = min(max(int(np.floor(a_at[k] / step)), 0), n - 1)
        low = np.inf
        for j in range(m):
            if back[i, j] < 0:
                continue
            rest = la - a_at[k] + lb - (j + 1) * step - back[i, j] * step
            low = min(low, max(a_head[k], a_at[k], j * step) + max(rest, 0.0))
        if low < np.inf:
            best = max(best, low)
    for k in range(len(b_at)):
        j = min(max(int(np.floor(b_at[k] / step)), 0), m - 1)
        low = np.inf
        for i in range(n):
            if back[i, j] < 0:
                continue
            rest = lb - b_at[k] + la - (i + 1) * step - back[i, j] * step
            low = min(low, max(b_head[k], b_at[k], i * step) + max(rest, 0.0))
        if low < np.inf:
            best = max(best, low)
    return best


@njit(cache=True)  # type: ignore[untyped-decorator]
def select_pairs(
    head: Any,
    nxt: Any,
    src: Any,
    dst: Any,
    wt: Any,
    ne: Any,
    dist: Any,
    queue: Any,
    queued: Any,
    t_arm: Any,
    t_tail: Any,
    i_lo: Any,
    i_task: Any,
    i_ps: Any,
    i_os: Any,
    i_pe: Any,
    i_oe: Any,
    i_len: Any,
    i_tail: Any,
    tail_pt: Any,
    ub: float,
    sel: Any,
    out_i: Any,
    out_j: Any,
    out_n: Any,
    max_rounds: int,
) -> bool:  # pragma: no cover - compiled
    """Immediate selection on every resource group (Carlier and Pinson's pair
    rule), to a fixed point; False when the node has no completion shorter
    than ``ub``.

    Intervals ``i`` and ``j`` of tasks of different arms in one group never
    overlap. If ``i`` came first, ``j`` would start no earlier than ``i``'s
    earliest end ``ee_i`` (its earliest start plus its nominal length, or its
    end point's earliest time if later), last at least its nominal length
    and be followed by at least its tail (the larger of the rest of its task
    plus the task's static tail and ``tail_pt`` of its end point less the
    end's offset: the network's longest path to a task's end, from
    :func:`stn_tails` at this node or an ancestor, or ``-inf``), so every such completion ends at ``ee_i + len_j +
    tail_j`` or later. When that reaches ``ub``, every completion shorter
    than ``ub`` puts ``j`` first: the edge ``x[ps_i] + os_i >= x[pe_j] +
    oe_j`` is added (:func:`stn_add`) and ``sel[j, i]`` set, and the pair
    recorded in ``out_i, out_j`` (their number in ``out_n[0]``, also when
    False is returned: the caller clears ``sel`` there when it leaves the
    node). When both orders reach ``ub``, or an edge closes a
    positive cycle, no completion is shorter than ``ub``. Earliest times only
    grow, so the rule is applied again until nothing changes (at most
    ``max_rounds`` passes; stopping earlier only adds fewer orders).
    """
    k = 0
    G = len(i_lo) - 1
    for _ in range(max_rounds):
        added = 0
        for g in range(G):
            for i in range(i_lo[g], i_lo[g + 1]):
                ti = i_task[i]
                ee_i = max(dist[i_ps[i]] + i_os[i] + i_len[i], dist[i_pe[i]] + i_oe[i])
                q_i = max(i_tail[i] + t_tail[ti], tail_pt[i_pe[i]] - i_oe[i])
                for j in range(i + 1, i_lo[g + 1]):
                    tj = i_task[j]
                    if t_arm[ti] == t_arm[tj] or sel[i, j] or sel[j, i]:
                        continue
                    ee_j = max(dist[i_ps[j]] + i_os[j] + i_len[j], dist[i_pe[j]] + i_oe[j])
                    q_j = max(i_tail[j] + t_tail[tj], tail_pt[i_pe[j]] - i_oe[j])
                    no_ij = ee_i + i_len[j] + q_j >= ub  # i first: too long
                    no_ji = ee_j + i_len[i] + q_i >= ub
                    if no_ij and no_ji:
                        out_n[0] = k
                        return False
                    if no_ij:  # j first
                        a, b = j, i
                    elif no_ji:
                        a, b = i, j
                    else:
                        continue
                    if ne[0] >= len(src):
                        raise RuntimeError("edge store full")
                    sel[a, b] = True
                    out_i[k] = a
                    out_j[k] = b
                    k += 1
                    added += 1
                    if not stn_add(
                        head, nxt, src, dst, wt, ne, dist, queue, queued,
                        i_pe[a], i_ps[b], i_oe[a] - i_os[b],
                    ):  # fmt: skip
                        out_n[0] = k
                        return False
                    ee_i = max(dist[i_ps[i]] + i_os[i] + i_len[i], dist[i_pe[i]] + i_oe[i])
        if added == 0:
            break
    out_n[0] = k
    return True
