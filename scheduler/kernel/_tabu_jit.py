"""Compiled tabu search on the disjunctive graph of a pure FJSP (no zones or tools).

Setup times, where given (``GraphArrays.stp``), lie on the arcs between
consecutive tasks of an arm and from an arm's initial pose to its first
task; they must obey the triangle inequality with the task between
(:func:`scheduler.tabu.graph_setup` checks it), which keeps every formula
below exact: taking ``v`` out replaces the arcs ``x -> v -> y`` by one
``x -> y`` that is no longer.

On a problem without zones, tools, setup times or a blocking oracle, a
schedule decoded from arm sequences is semi-active: each task starts at the
longest path to it in the disjunctive graph (job arcs plus the arcs between
consecutive tasks of an arm, task release and arm availability as heads).
The makespan is then the longest path, and every quantity the tabu search
needs — heads, tails, the critical tasks, and the exact makespan of moving
one task — follows from the graph in linear time, here compiled by numba.

The move is the *k-insertion* of Mastrolilli and Gambardella (2000): take a
critical task ``v`` out of its arm's sequence (the graph ``G-``), and insert
it, in any of its modes, at any position of the chosen arm's sequence that
keeps the graph acyclic. With heads ``r`` and tails ``q`` of ``G-`` the
longest path through ``v`` inserted between ``x`` and ``y`` is::

    max(release(v), r(job preds) + p, r(x) + p(x)) + p(v, k)
      + max(p + q(job succs), p(y) + q(y))

and the makespan of the new schedule is the larger of that and the longest
path of ``G-`` (every other path of the new graph is one of ``G-``): the
estimate is exact, so every candidate is ranked by its true makespan. The
insertion between ``x`` and ``y`` is acyclic unless ``x`` descends from one
of ``v``'s job successors or ``y`` is an ancestor of one of its job
predecessors (both sets computed once per ``v``).

Heads and tails of ``G-`` are recomputed on one side of ``v`` only: in a
topological order of the whole graph, a task before ``v`` keeps its head and
one after it keeps its tail (:func:`_minus_fast`; :func:`_minus` computes
them from scratch, the reference the tests compare it with).

Each iteration takes the best move that is not tabu (a tabu one when it
beats the best makespan — styles 0 and 2; with styles 1 and 3 a tabu task is
not looked at — or when every move is tabu); ties are broken at
random, or by the shorter path through the moved task, and the best ``top``
moves are compared by their whole schedule's sum of end times (computed
exactly). What a move makes tabu (``style``): 0 the task right after its old
predecessor, 1 the task itself (not moved again; for a number of
iterations that may be a share of the critical tasks), 2 the task right
after its old predecessor or right before its old successor, 3 both 1 and
2. After ``patience`` iterations without a new best, the search restarts
from the best with a few random feasible insertions. Random choices use a
xorshift generator whose state is an array, so runs repeat bit for bit
from the same seed.

``MULTIARM_NO_JIT=1`` runs the same functions as plain Python (the
reference the tests compare the compiled code with).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from scheduler.kernel._jit import jit_enabled, njit


class GraphArrays(NamedTuple):
    """A pure FJSP's fixed arrays (CSR offsets ``*_ptr``/``pp``/``sp``):
    predecessors ``pp``/``pi``, successors ``sp``/``si``, releases ``rel``,
    arm availability ``avail``, and each task's allowed modes as their arm
    ``tm_arm`` and duration ``tm_dur`` (``tm_ptr[t]..tm_ptr[t+1]``), and the
    setup times ``stp[arm, prev + 1, next]`` (row 0: from the initial pose;
    shape ``(0, 1, 1)``: no setups)."""

    pp: Any
    pi: Any
    sp: Any
    si: Any
    rel: Any
    avail: Any
    tm_ptr: Any
    tm_arm: Any
    tm_dur: Any
    stp: Any


class SearchArrays(NamedTuple):
    """The search's state, mutated in place by :func:`tabu_run`: the current
    solution (``choice``, ``seq``, ``seq_n``), the best one (``b_*``), the
    tabu table, the random state ``rs`` and the control arrays ``ctl``/``fctl``."""

    choice: Any
    seq: Any
    seq_n: Any
    b_choice: Any
    b_seq: Any
    b_seq_n: Any
    tabu: Any
    rs: Any
    ctl: Any
    fctl: Any


__all__ = ["GraphArrays", "SearchArrays", "all_moves", "graph_makespan", "tabu_run"]

_EPS = 1e-9


def _xorshift(rs):
    """xorshift64*: the next 53-bit float in [0, 1) from the state ``rs[0]``
    (the product wraps around modulo 2**64)."""
    x = rs[0]
    x ^= x >> np.uint64(12)
    x ^= x << np.uint64(25)
    x ^= x >> np.uint64(27)
    rs[0] = x
    y = x * np.uint64(2685821657736338717)
    return float(y >> np.uint64(11)) / 9007199254740992.0


if jit_enabled():
    _rand = njit(cache=True)(_xorshift)
else:  # pragma: no cover - plain Python: the same wrap-around, without numpy's warning

    def _rand(rs):
        """:func:`_xorshift` with numpy's overflow warning silenced."""
        with np.errstate(over="ignore"):
            return _xorshift(rs)


@njit(cache=True)
def _randint(rs, n):
    """A uniform integer in ``[0, n)``."""
    k = int(_rand(rs) * n)
    return k if k < n else n - 1


@njit(cache=True)
def _links(seq, seq_n, mprev, mnext):
    """Previous and next task on each arm from the sequences."""
    mprev[:] = -1
    mnext[:] = -1
    for a in range(seq.shape[0]):
        for i in range(seq_n[a]):
            t = seq[a, i]
            if i > 0:
                mprev[t] = seq[a, i - 1]
            if i + 1 < seq_n[a]:
                mnext[t] = seq[a, i + 1]


@njit(cache=True)
def _heads_full(pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext, skip, head, order, indeg):
    """Heads (earliest starts) of the graph without task ``skip`` (-1: none) in
    topological order (Kahn's algorithm); returns how many tasks were ordered
    (fewer: a cycle). ``stp`` holds the setup times (empty: none)."""
    T = len(rel)
    hs = stp.shape[0] > 0
    n = 0
    for t in range(T):
        if t == skip:
            continue
        d = 0
        for j in range(pp[t], pp[t + 1]):
            if pi[j] != skip:
                d += 1
        if mprev[t] >= 0:
            d += 1
        indeg[t] = d
        if d == 0:
            order[n] = t
            n += 1
    k = 0
    while k < n:
        t = order[k]
        k += 1
        h = rel[t]
        for j in range(pp[t], pp[t + 1]):
            q = pi[j]
            if q != skip and head[q] + dur[q] > h:
                h = head[q] + dur[q]
        q = mprev[t]
        if q >= 0:
            e = head[q] + dur[q]
            if hs:
                e += stp[arm[t], q + 1, t]
            if e > h:
                h = e
        else:
            e = avail[arm[t]]
            if hs:
                e += stp[arm[t], 0, t]
            if e > h:
                h = e
        head[t] = h
        for j in range(sp[t], sp[t + 1]):
            x = si[j]
            if x == skip:
                continue
            indeg[x] -= 1
            if indeg[x] == 0:
                order[n] = x
                n += 1
        x = mnext[t]
        if x >= 0:
            indeg[x] -= 1
            if indeg[x] == 0:
                order[n] = x
                n += 1
    return n


@njit(cache=True)
def _tails(sp, si, stp, arm, dur, mnext, skip, order, n, tail):
    """Tails (longest path after each end) over the first ``n`` of ``order``."""
    hs = stp.shape[0] > 0
    for k in range(n - 1, -1, -1):
        t = order[k]
        best = 0.0
        for j in range(sp[t], sp[t + 1]):
            x = si[j]
            if x != skip and dur[x] + tail[x] > best:
                best = dur[x] + tail[x]
        x = mnext[t]
        if x >= 0:
            e = dur[x] + tail[x]
            if hs:
                e += stp[arm[t], t + 1, x]
            if e > best:
                best = e
        tail[t] = best


@njit(cache=True)
def graph_makespan(g, arm, dur, seq, seq_n):
    """The longest path of the graph of arm sequences ``seq`` (-1.0: a cycle)."""
    pp, pi, sp, si, rel, avail = g.pp, g.pi, g.sp, g.si, g.rel, g.avail
    stp = g.stp
    T = len(rel)
    mprev = np.empty(T, dtype=np.int64)
    mnext = np.empty(T, dtype=np.int64)
    _links(seq, seq_n, mprev, mnext)
    head = np.zeros(T)
    order = np.empty(T, dtype=np.int64)
    indeg = np.empty(T, dtype=np.int64)
    n = _heads_full(pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext, -1, head, order, indeg)
    if n < T:
        return -1.0
    c = 0.0
    for t in range(T):
        if head[t] + dur[t] > c:
            c = head[t] + dur[t]
    return c


@njit(cache=True)
def _minus(
    v, pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext, head, tail, order, indeg, desc, anc
):
    """Heads, tails, makespan of G- (v taken out of its arm), and which tasks
    descend from v's job successors (``desc``) or lead to its job
    predecessors (``anc``). ``mprev``/``mnext`` must already bypass v."""
    T = len(rel)
    n = _heads_full(pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext, v, head, order, indeg)
    _tails(sp, si, stp, arm, dur, mnext, v, order, n, tail)
    desc[:] = False
    anc[:] = False
    for j in range(sp[v], sp[v + 1]):
        desc[si[j]] = True
    for j in range(pp[v], pp[v + 1]):
        anc[pi[j]] = True
    cm = 0.0
    for k in range(n):
        t = order[k]
        if not desc[t]:
            for j in range(pp[t], pp[t + 1]):
                if pi[j] != v and desc[pi[j]]:
                    desc[t] = True
                    break
            if not desc[t] and mprev[t] >= 0 and desc[mprev[t]]:
                desc[t] = True
        if head[t] + dur[t] > cm:
            cm = head[t] + dur[t]
    for k in range(n - 1, -1, -1):
        t = order[k]
        if not anc[t]:
            for j in range(sp[t], sp[t + 1]):
                if si[j] != v and anc[si[j]]:
                    anc[t] = True
                    break
            if not anc[t] and mnext[t] >= 0 and anc[mnext[t]]:
                anc[t] = True
    _ = T
    return cm


@njit(cache=True)
def _minus_fast(
    v,
    pp,
    pi,
    sp,
    si,
    rel,
    avail,
    stp,
    arm,
    dur,
    mprev,
    mnext,
    head,
    tail,
    gorder,
    gpos,
    pm,
    h2,
    t2,
    desc,
    anc,
):
    """What :func:`_minus` computes, from the heads, tails and topological
    order ``gorder`` (positions ``gpos``, prefix maxima of the ends ``pm``) of
    the whole graph: a task before v in that order keeps its head, one after
    it its tail, so each is recomputed on one side of v only."""
    n = len(rel)
    hs = stp.shape[0] > 0
    pv = gpos[v]
    h2[:] = head
    t2[:] = tail
    desc[:] = False
    anc[:] = False
    for j in range(sp[v], sp[v + 1]):
        desc[si[j]] = True
    for j in range(pp[v], pp[v + 1]):
        anc[pi[j]] = True
    cm = pm[pv - 1] if pv > 0 else 0.0
    for k in range(pv + 1, n):
        t = gorder[k]
        h = rel[t]
        d = desc[t]
        for j in range(pp[t], pp[t + 1]):
            q = pi[j]
            if q != v:
                if h2[q] + dur[q] > h:
                    h = h2[q] + dur[q]
                if desc[q]:
                    d = True
        q = mprev[t]
        if q >= 0:
            e = h2[q] + dur[q]
            if hs:
                e += stp[arm[t], q + 1, t]
            if e > h:
                h = e
            if desc[q]:
                d = True
        else:
            e = avail[arm[t]]
            if hs:
                e += stp[arm[t], 0, t]
            if e > h:
                h = e
        h2[t] = h
        desc[t] = d
        if h + dur[t] > cm:
            cm = h + dur[t]
    for k in range(pv - 1, -1, -1):
        t = gorder[k]
        b = 0.0
        a = anc[t]
        for j in range(sp[t], sp[t + 1]):
            x = si[j]
            if x != v:
                if dur[x] + t2[x] > b:
                    b = dur[x] + t2[x]
                if anc[x]:
                    a = True
        x = mnext[t]
        if x >= 0:
            e = dur[x] + t2[x]
            if hs:
                e += stp[arm[t], t + 1, x]
            if e > b:
                b = e
            if anc[x]:
                a = True
        t2[t] = b
        anc[t] = a
    return cm


@njit(cache=True)
def _worse(a0, a1, a2, b0, b1, b2):
    """Whether key (a0, a1, a2) is worse than (b0, b1, b2) (ties within EPS)."""
    if a0 > b0 + _EPS:
        return True
    if a0 < b0 - _EPS:
        return False
    if a1 > b1 + _EPS:
        return True
    if a1 < b1 - _EPS:
        return False
    return a2 > b2


@njit(cache=True)
def _unlink(v, mprev, mnext):
    a, b = mprev[v], mnext[v]
    if a >= 0:
        mnext[a] = b
    if b >= 0:
        mprev[b] = a


@njit(cache=True)
def _relink(v, mprev, mnext):
    a, b = mprev[v], mnext[v]
    if a >= 0:
        mnext[a] = v
    if b >= 0:
        mprev[b] = v


@njit(cache=True)
def _apply(v, c, k, i, tm_ptr, tm_arm, tm_dur, choice, arm, dur, seq, seq_n):
    """Move v to mode choice ``c`` on arm ``k`` at position ``i`` of k's
    sequence without v."""
    a0 = arm[v]
    n0 = seq_n[a0]
    j = 0
    for x in range(n0):
        if seq[a0, x] != v:
            seq[a0, j] = seq[a0, x]
            j += 1
    seq[a0, n0 - 1] = -1
    seq_n[a0] = n0 - 1
    nk = seq_n[k]
    for x in range(nk, i, -1):
        seq[k, x] = seq[k, x - 1]
    seq[k, i] = v
    seq_n[k] = nk + 1
    choice[v] = c
    arm[v] = tm_arm[tm_ptr[v] + c]
    dur[v] = tm_dur[tm_ptr[v] + c]


@njit(cache=True, nogil=True)
def tabu_run(g, state, iters, tenure_lo, tenure_span, patience, kick, style, rank, top):
    """Run up to ``iters`` iterations of the tabu search (see the module docstring).

    ``g`` is the problem (:class:`GraphArrays`), ``state`` the search
    (:class:`SearchArrays`, mutated). The current solution is ``choice`` (per task, the index of its mode among
    ``tm_ptr[t]..tm_ptr[t+1]``), ``seq``/``seq_n`` (the arms' sequences); the
    best one ``b_*``. ``ctl`` holds (iteration, iterations since the best
    improved, improvements found in this call); ``fctl`` (best makespan,
    current makespan, lower bound to stop at). ``tabu[v, x]`` is the
    iteration until which v may not follow x, or precede it with style 2-3
    (``x = T + arm``: be first or last on the arm; ``x = T + A``: be moved at
    all, styles 1 and 3). ``tenure_lo < 0`` makes the tenure
    ``-tenure_lo / 10`` times the number of critical tasks plus a random
    share ``tenure_span / 10`` of that. Returns the iterations run.
    """
    pp, pi, sp, si, rel, avail = g.pp, g.pi, g.sp, g.si, g.rel, g.avail
    stp = g.stp
    hs = stp.shape[0] > 0
    tm_ptr, tm_arm, tm_dur = g.tm_ptr, g.tm_arm, g.tm_dur
    choice, seq, seq_n = state.choice, state.seq, state.seq_n
    b_choice, b_seq, b_seq_n = state.b_choice, state.b_seq, state.b_seq_n
    tabu, rs, ctl, fctl = state.tabu, state.rs, state.ctl, state.fctl
    T = len(rel)
    A = seq.shape[0]
    arm = np.empty(T, dtype=np.int64)
    dur = np.empty(T)
    for t in range(T):
        arm[t] = tm_arm[tm_ptr[t] + choice[t]]
        dur[t] = tm_dur[tm_ptr[t] + choice[t]]
    mprev = np.empty(T, dtype=np.int64)
    mnext = np.empty(T, dtype=np.int64)
    head = np.zeros(T)
    tail = np.zeros(T)
    h2 = np.zeros(T)
    t2 = np.zeros(T)
    order = np.empty(T, dtype=np.int64)
    indeg = np.empty(T, dtype=np.int64)
    desc = np.zeros(T, dtype=np.bool_)
    anc = np.zeros(T, dtype=np.bool_)
    crit = np.empty(T, dtype=np.int64)
    sk = np.empty(T, dtype=np.int64)
    gpos = np.empty(T, dtype=np.int64)
    pm = np.empty(T)
    order2 = np.empty(T, dtype=np.int64)
    K = max(1, top)
    ck0 = np.empty(K)
    ck1 = np.empty(K)
    ck2 = np.empty(K)
    cmk = np.empty(K)
    cv = np.empty(K, dtype=np.int64)
    cc = np.empty(K, dtype=np.int64)
    ckk = np.empty(K, dtype=np.int64)
    ci_ = np.empty(K, dtype=np.int64)
    done = 0
    while done < iters:
        if fctl[0] <= fctl[2] + _EPS:
            break
        it = ctl[0] + 1
        ctl[0] = it
        done += 1
        _links(seq, seq_n, mprev, mnext)
        n = _heads_full(
            pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext, -1, head, order, indeg
        )
        _tails(sp, si, stp, arm, dur, mnext, -1, order, n, tail)
        cmax = 0.0
        for k in range(n):
            t = order[k]
            gpos[t] = k
            if head[t] + dur[t] > cmax:
                cmax = head[t] + dur[t]
            pm[k] = cmax
        fctl[1] = cmax
        nc = 0
        for t in range(T):
            if head[t] + dur[t] + tail[t] >= cmax - _EPS and tm_ptr[t + 1] > tm_ptr[t]:
                crit[nc] = t
                nc += 1
        nc0 = nc
        # the best moves by (makespan, path through v, random), kept in a small buffer
        cnt = 0
        best_mk = fctl[0]
        for pas in range(2):
            if pas == 1 and (cnt > 0 or nc == 0):
                break  # else every move is tabu: the best of them (pass 1)
            for ci in range(nc):
                v = crit[ci]
                if pas == 0 and (style == 1 or style == 3) and tabu[v, T + A] > it:
                    continue  # a tabu task (aspiration is not looked for)
                a0 = arm[v]
                p0 = mprev[v]
                _unlink(v, mprev, mnext)
                cm = _minus_fast(
                    v, pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext,
                    head, tail, order, gpos, pm, h2, t2, desc, anc,
                )  # fmt: skip
                rj = rel[v]
                for j in range(pp[v], pp[v + 1]):
                    q = pi[j]
                    if h2[q] + dur[q] > rj:
                        rj = h2[q] + dur[q]
                qj = 0.0
                for j in range(sp[v], sp[v + 1]):
                    q = si[j]
                    if dur[q] + t2[q] > qj:
                        qj = dur[q] + t2[q]
                for c in range(tm_ptr[v + 1] - tm_ptr[v]):
                    k = tm_arm[tm_ptr[v] + c]
                    pv = tm_dur[tm_ptr[v] + c]
                    nk = 0
                    for x in range(seq_n[k]):
                        y = seq[k, x]
                        if y != v:
                            sk[nk] = y
                            nk += 1
                    for i in range(nk + 1):
                        pre = sk[i - 1] if i > 0 else -1
                        post = sk[i] if i < nk else -1
                        if pre >= 0 and desc[pre]:
                            break  # every later position follows a successor too
                        if post >= 0 and anc[post]:
                            continue
                        if k == a0 and pre == p0:
                            continue  # where it is now
                        r = rj
                        if pre >= 0:
                            e = h2[pre] + dur[pre]
                            if hs:
                                e += stp[k, pre + 1, v]
                        else:
                            e = avail[k]
                            if hs:
                                e += stp[k, 0, v]
                        if e > r:
                            r = e
                        q = qj
                        if post >= 0:
                            e = dur[post] + t2[post]
                            if hs:
                                e += stp[k, v + 1, post]
                            if e > q:
                                q = e
                        est = r + pv + q
                        mk = est if est > cm else cm
                        if style == 0:
                            key = pre if pre >= 0 else T + k
                            is_tabu = tabu[v, key] > it
                        elif style == 1:
                            is_tabu = False
                        else:
                            key = pre if pre >= 0 else T + k
                            key2 = post if post >= 0 else T + k
                            is_tabu = tabu[v, key] > it or tabu[v, key2] > it
                        if pas == 0 and is_tabu and mk >= best_mk - _EPS:
                            continue
                        rnd = _rand(rs)
                        k0, k1 = mk, est
                        if rank == 1:
                            k1 = -est
                        elif rank == 2:
                            k1 = 0.0
                        elif rank == 3:
                            k0, k1 = est, mk
                        if cnt < K:
                            slot = cnt
                            cnt += 1
                        else:
                            slot = 0  # the worst in the buffer, if worse than this move
                            for z in range(1, K):
                                if _worse(ck0[z], ck1[z], ck2[z], ck0[slot], ck1[slot], ck2[slot]):
                                    slot = z
                            if not _worse(ck0[slot], ck1[slot], ck2[slot], k0, k1, rnd):
                                continue
                        ck0[slot], ck1[slot], ck2[slot], cmk[slot] = k0, k1, rnd, mk
                        cv[slot], cc[slot], ckk[slot], ci_[slot] = v, c, k, i
                _relink(v, mprev, mnext)
        bv = -1
        bmk = np.inf
        if cnt > 0:
            b = 0
            if K > 1 and cnt > 1:
                # rank the buffer by the exact (makespan, sum of ends)
                bs0, bs1, bs2 = np.inf, np.inf, np.inf
                for z in range(cnt):
                    v = cv[z]
                    c_old = choice[v]
                    a_old = arm[v]
                    i_old = 0
                    for x in range(seq_n[a_old]):
                        if seq[a_old, x] == v:
                            i_old = x
                    _apply(
                        v,
                        cc[z],
                        ckk[z],
                        ci_[z],
                        tm_ptr,
                        tm_arm,
                        tm_dur,
                        choice,
                        arm,
                        dur,
                        seq,
                        seq_n,
                    )
                    _links(seq, seq_n, mprev, mnext)
                    _heads_full(
                        pp,
                        pi,
                        sp,
                        si,
                        rel,
                        avail,
                        stp,
                        arm,
                        dur,
                        mprev,
                        mnext,
                        -1,
                        h2,
                        order2,
                        indeg,
                    )
                    c1 = 0.0
                    s1 = 0.0
                    for t in range(T):
                        e = h2[t] + dur[t]
                        s1 += e
                        if e > c1:
                            c1 = e
                    _apply(
                        v, c_old, a_old, i_old, tm_ptr, tm_arm, tm_dur, choice, arm, dur, seq, seq_n
                    )
                    if _worse(bs0, bs1, bs2, c1, s1, ck2[z]):
                        bs0, bs1, bs2 = c1, s1, ck2[z]
                        b = z
                _links(seq, seq_n, mprev, mnext)
            else:
                for z in range(1, cnt):
                    if _worse(ck0[b], ck1[b], ck2[b], ck0[z], ck1[z], ck2[z]):
                        b = z
            bv, bc, bk, bi, bmk = cv[b], cc[b], ckk[b], ci_[b], cmk[b]
        improved = False
        if bv >= 0:
            v = bv
            p0 = mprev[v]
            if tenure_lo < 0:
                # adaptive: a share of the critical tasks (in tenths)
                lo_ = max(2, (-tenure_lo * nc0) // 10)
                ten = it + lo_ + _randint(rs, lo_ * tenure_span // 10 + 1)
            else:
                ten = it + tenure_lo + _randint(rs, tenure_span + 1)
            if style == 1 or style == 3:
                tabu[v, T + A] = ten
            if style != 1:
                key = p0 if p0 >= 0 else T + arm[v]
                tabu[v, key] = ten
                if style >= 2:
                    n0 = mnext[v]
                    key = n0 if n0 >= 0 else T + arm[v]
                    tabu[v, key] = ten
            _apply(v, bc, bk, bi, tm_ptr, tm_arm, tm_dur, choice, arm, dur, seq, seq_n)
            fctl[1] = bmk
            if bmk < fctl[0] - _EPS:
                improved = True
                fctl[0] = bmk
                b_choice[:] = choice
                b_seq[:, :] = seq
                b_seq_n[:] = seq_n
                ctl[1] = 0
                ctl[2] += 1
        if not improved:
            ctl[1] += 1
        if ctl[1] >= patience:
            # restart from the best with a few random feasible insertions
            ctl[1] = 0
            tabu[:, :] = 0
            choice[:] = b_choice
            seq[:, :] = b_seq
            seq_n[:] = b_seq_n
            for t in range(T):
                arm[t] = tm_arm[tm_ptr[t] + choice[t]]
                dur[t] = tm_dur[tm_ptr[t] + choice[t]]
            _links(seq, seq_n, mprev, mnext)
            for _ in range(kick):
                v = _randint(rs, T)
                if tm_ptr[v + 1] == tm_ptr[v]:
                    continue
                _unlink(v, mprev, mnext)
                _minus(
                    v,
                    pp,
                    pi,
                    sp,
                    si,
                    rel,
                    avail,
                    stp,
                    arm,
                    dur,
                    mprev,
                    mnext,
                    h2,
                    t2,
                    order,
                    indeg,
                    desc,
                    anc,
                )
                _relink(v, mprev, mnext)
                c = _randint(rs, tm_ptr[v + 1] - tm_ptr[v])
                k = tm_arm[tm_ptr[v] + c]
                nk = 0
                for x in range(seq_n[k]):
                    y = seq[k, x]
                    if y != v:
                        sk[nk] = y
                        nk += 1
                lo = 0
                hi = nk
                for i in range(nk + 1):
                    pre = sk[i - 1] if i > 0 else -1
                    post = sk[i] if i < nk else -1
                    if pre >= 0 and desc[pre]:
                        hi = i - 1
                        break
                    if post >= 0 and anc[post]:
                        lo = i + 1
                if lo > hi:
                    continue
                i = lo + _randint(rs, hi - lo + 1)
                _apply(v, c, k, i, tm_ptr, tm_arm, tm_dur, choice, arm, dur, seq, seq_n)
                _links(seq, seq_n, mprev, mnext)
    _ = A
    return done


@njit(cache=True)
def all_moves(g, choice, seq, seq_n, fast):
    """Every k-insertion of a critical task that keeps the graph acyclic, with
    its exact makespan: rows ``(task, mode choice, arm, position, makespan)``
    (position in the arm's sequence without the task). The neighbourhood the
    search ranks, for tests against brute force; ``fast`` computes the graph
    without the task as the search does (:func:`_minus_fast`), else from
    scratch (:func:`_minus`)."""
    pp, pi, sp, si, rel, avail = g.pp, g.pi, g.sp, g.si, g.rel, g.avail
    stp = g.stp
    hs = stp.shape[0] > 0
    tm_ptr, tm_arm, tm_dur = g.tm_ptr, g.tm_arm, g.tm_dur
    T = len(rel)
    arm = np.empty(T, dtype=np.int64)
    dur = np.empty(T)
    for t in range(T):
        arm[t] = tm_arm[tm_ptr[t] + choice[t]]
        dur[t] = tm_dur[tm_ptr[t] + choice[t]]
    mprev = np.empty(T, dtype=np.int64)
    mnext = np.empty(T, dtype=np.int64)
    head = np.zeros(T)
    tail = np.zeros(T)
    h2 = np.zeros(T)
    t2 = np.zeros(T)
    order = np.empty(T, dtype=np.int64)
    indeg = np.empty(T, dtype=np.int64)
    desc = np.zeros(T, dtype=np.bool_)
    anc = np.zeros(T, dtype=np.bool_)
    sk = np.empty(T, dtype=np.int64)
    gpos = np.empty(T, dtype=np.int64)
    pm = np.empty(T)
    order2 = np.empty(T, dtype=np.int64)
    _links(seq, seq_n, mprev, mnext)
    n = _heads_full(pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext, -1, head, order, indeg)
    _tails(sp, si, stp, arm, dur, mnext, -1, order, n, tail)
    cmax = 0.0
    for k in range(n):
        t = order[k]
        gpos[t] = k
        if head[t] + dur[t] > cmax:
            cmax = head[t] + dur[t]
        pm[k] = cmax
    rows = []
    for v in range(T):
        if head[v] + dur[v] + tail[v] < cmax - _EPS:
            continue
        a0 = arm[v]
        p0 = mprev[v]
        _unlink(v, mprev, mnext)
        if fast:
            cm = _minus_fast(
                v, pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext,
                head, tail, order, gpos, pm, h2, t2, desc, anc,
            )  # fmt: skip
        else:
            cm = _minus(
                v, pp, pi, sp, si, rel, avail, stp, arm, dur, mprev, mnext,
                h2, t2, order2, indeg, desc, anc,
            )  # fmt: skip
        rj = rel[v]
        for j in range(pp[v], pp[v + 1]):
            q = pi[j]
            if h2[q] + dur[q] > rj:
                rj = h2[q] + dur[q]
        qj = 0.0
        for j in range(sp[v], sp[v + 1]):
            q = si[j]
            if dur[q] + t2[q] > qj:
                qj = dur[q] + t2[q]
        for c in range(tm_ptr[v + 1] - tm_ptr[v]):
            k = tm_arm[tm_ptr[v] + c]
            pv = tm_dur[tm_ptr[v] + c]
            nk = 0
            for x in range(seq_n[k]):
                y = seq[k, x]
                if y != v:
                    sk[nk] = y
                    nk += 1
            for i in range(nk + 1):
                pre = sk[i - 1] if i > 0 else -1
                post = sk[i] if i < nk else -1
                if pre >= 0 and desc[pre]:
                    break
                if post >= 0 and anc[post]:
                    continue
                if k == a0 and pre == p0:
                    continue
                r = rj
                if pre >= 0:
                    e = h2[pre] + dur[pre]
                    if hs:
                        e += stp[k, pre + 1, v]
                else:
                    e = avail[k]
                    if hs:
                        e += stp[k, 0, v]
                if e > r:
                    r = e
                q = qj
                if post >= 0:
                    e = dur[post] + t2[post]
                    if hs:
                        e += stp[k, v + 1, post]
                    if e > q:
                        q = e
                est = r + pv + q
                rows.append((float(v), float(c), float(k), float(i), max(est, cm)))
        _relink(v, mprev, mnext)
    out = np.empty((len(rows), 5))
    for j in range(len(rows)):
        out[j, 0], out[j, 1], out[j, 2], out[j, 3], out[j, 4] = rows[j]
    return out
