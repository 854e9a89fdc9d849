"""Tabu search on arm sequences: the tree search's main improvement phase.

A solution here is a mode per task and, per arm, the order of its tasks.
:func:`~scheduler.kernel.seq_decode` turns it into a schedule: tasks go in
order of earliest possible start once their predecessors and the previous
task on their arm are placed, each at its earliest feasible time (zones,
tools and waits at zone borders resolved there, as everywhere).

Every iteration looks at the critical chain of the current schedule (the
tasks that explain its makespan, :func:`critical_chain`) and evaluates
moves on it:

* **swap** two consecutive tasks of the chain that follow each other on one
  arm (the critical arcs of the classical job-shop neighbourhoods);
* **reassign** a critical task to another arm that can do it, inserted where
  its current start falls in that arm's sequence (or one place either side).

Moves are ranked by an estimate of the makespan through the moved task from
the current schedule's heads and tails (zones ignored), and only the best few
are decoded exactly.

It takes the best move that is not tabu — undoing a recent swap, or giving a
task back to an arm it just left — unless that move beats the best schedule
so far (aspiration), even when it is worse than the current one. After a run
without improvement it restarts from the best schedule with a random kick.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from multiarm.types import FloatArray, IntArray
from scheduler.kernel import State, compiled, seq_decode
from scheduler.problem import Problem
from scheduler.search import Budget, Evaluator, Solution

__all__ = ["critical_chain", "tabu_search"]

_TOL = 1e-6


def _sequences(p: Problem, st: State, tasks: IntArray) -> tuple[IntArray, IntArray]:
    """Per arm, the given tasks in start order (as a padded (A, T) array)."""
    A, T = p.n_arms, p.n_tasks
    seq = np.full((A, max(T, 1)), -1, dtype=np.int64)
    seq_n = np.zeros(A, dtype=np.int64)
    arms = p.mode_arm[st.t_mode[tasks]]
    order = np.lexsort((tasks, st.t_start[tasks]))
    for i in order:
        a = int(arms[i])
        seq[a, seq_n[a]] = tasks[i]
        seq_n[a] += 1
    return seq, seq_n


def critical_chain(
    p: Problem, st: State, rng: np.random.Generator | None = None
) -> list[tuple[int, str, int]]:
    """The chain explaining the makespan, last task first: ``(task, reason, by)``
    with reason ``"pred"``, ``"arm"``, ``"resource"`` or ``"release"``."""
    T = p.n_tasks
    if T == 0:
        return []
    start, end, mode = st.t_start, st.t_end, st.t_mode
    arm = p.mode_arm[mode]
    inst = compiled(p)
    prev = np.full(T, -1, dtype=np.int64)
    for a in range(p.n_arms):
        n = int(st.arm_n[a])
        lo = int(inst.arm_lo[a])
        ts = st.arm_t[lo : lo + n]
        prev[ts[1:]] = ts[:-1]
    shapes = p.shapes
    has_resources = bool(p.n_windows or p.n_tools)

    def blockers(t: int) -> list[int]:
        """Tasks whose interval on a resource ends exactly where one of t's starts."""
        m = int(mode[t])
        sh = shapes[m]
        if not (sh.exclusive or sh.moves or sh.tools):
            return []
        w = st.t_waits[t, : len(sh.borders)]
        starts = [(r, s) for r, s, _ in sh.intervals(float(start[t]), w)]
        starts += [(r, float(start[t])) for r in sh.tools]
        out = []
        for r, s in starts:
            lo = int(inst.res_lo[r])
            n = int(st.res_n[r])
            ends = st.tl_e[lo : lo + n]
            k = int(np.searchsorted(ends, s - _TOL))
            while k < n and ends[k] <= s + _TOL:
                x = int(st.tl_task[lo + k])
                if x >= 0 and x != t and arm[x] != arm[t]:
                    out.append(x)
                k += 1
        return out

    chain: list[tuple[int, str, int]] = []
    t = int(np.argmax(end))
    seen: set[int] = set()
    while t not in seen:
        seen.add(t)
        S = float(start[t])
        reasons: list[tuple[str, int]] = []
        q = int(prev[t])
        if q >= 0 and abs(float(end[q]) + p.setup_time(int(arm[t]), q, t) - S) <= _TOL:
            reasons.append(("arm", q))
        for q in p.task_preds[t]:
            if abs(float(end[q]) - S) <= _TOL:
                reasons.append(("pred", q))
        if has_resources:
            reasons.extend(("resource", x) for x in blockers(t))
        if not reasons:
            chain.append((t, "release", -1))
            break
        pick = (
            reasons[int(rng.integers(len(reasons)))]
            if (rng is not None and len(reasons) > 1)
            else reasons[0]
        )
        chain.append((t, pick[0], pick[1]))
        t = pick[1]
    return chain


class _Seq:
    """A sequence solution and its decoded state."""

    __slots__ = ("key", "modes", "order", "seq", "seq_n", "state")

    def __init__(
        self, modes: IntArray, seq: IntArray, seq_n: IntArray, state: State, order: IntArray
    ) -> None:
        self.modes = modes
        self.seq = seq
        self.seq_n = seq_n
        self.state = state
        self.order = order
        self.key = (float(state.t_end.max()), float(state.t_end.sum()))


def _tails(p: Problem, s: _Seq, dur: FloatArray) -> FloatArray:
    """Per task, the longest chain of arm and job successors after its end
    (the tail of the disjunctive graph of the current schedule; zones ignored)."""
    st = s.state
    T = p.n_tasks
    tail = np.zeros(T)
    nxt = np.full(T, -1, dtype=np.int64)
    for a in range(p.n_arms):
        n = int(s.seq_n[a])
        ts = s.seq[a, :n]
        nxt[ts[:-1]] = ts[1:]
    for t in np.argsort(-st.t_start, kind="stable").tolist():
        best = 0.0
        for q in p.task_succs[t]:
            v = float(dur[q] + tail[q])
            if v > best:
                best = v
        q = int(nxt[t])
        if q >= 0:
            a = int(p.mode_arm[s.modes[t]])
            v = p.setup_time(a, t, q) + float(dur[q] + tail[q])
            if v > best:
                best = v
        tail[t] = best
    return tail


def tabu_search(
    ev: Evaluator,
    start: Solution,
    deadline: float,
    rng: np.random.Generator,
    *,
    on_improve: Callable[[Solution], None] | None = None,
    lower: float = 0.0,
    max_evaluations: int | None = None,
    max_moves: int = 80,
    exact_moves: int = 8,
    patience: int = 400,
    window: int = 1,
    kick: int = 4,
    random_moves: int = 4,
) -> Solution:
    """Improve ``start`` until ``deadline`` or ``max_evaluations`` decodes."""
    p = ev.problem
    inst = ev.inst
    if ev.blocking or start.state is None:
        return start
    base = ev.base if ev.base is not None else inst.new_state()
    todo = np.flatnonzero(base.t_mode < 0)
    if len(todo) == 0:
        return start
    frozen = ev.frozen
    allowed = ev.allowed
    budget = Budget(ev, deadline, max_evaluations)
    out_of_budget = budget.spent

    def decode(modes: IntArray, seq: IntArray, seq_n: IntArray) -> _Seq | None:
        ev.evaluations += 1
        ok, st, order = seq_decode(
            inst,
            seq,
            seq_n,
            modes,
            waits=ev.waits,
            state=base.copy(),
            release=ev.release,
            arm_lb=ev.arm_lb,
        )
        return _Seq(modes, seq, seq_n, st, order) if ok else None

    seq, seq_n = _sequences(p, start.state, todo)
    cur = decode(start.state.t_mode.copy(), seq, seq_n)
    if cur is None:
        return start
    best = cur
    tabu: dict[tuple[str, int, int], int] = {}
    tenure0 = 8 + int(math.sqrt(len(todo)))
    it = 0
    stall = 0

    def to_solution(s: _Seq) -> Solution:
        return Solution(s.order.copy(), s.modes.copy(), s.key[0], s.key[1], s.state)

    while budget.room_for_iteration() and best.key[0] > lower + 1e-9:
        tp = time.perf_counter()
        it += 1
        chain = critical_chain(p, cur.state, rng)
        pos = np.zeros(p.n_tasks, dtype=np.int64)
        for a in range(p.n_arms):
            pos[cur.seq[a, : cur.seq_n[a]]] = np.arange(cur.seq_n[a])
        moves: list[tuple[str, int, int, int]] = []  # (kind, task, arg1, arg2)
        for t, reason, by in chain:
            if t in frozen:
                continue
            if reason == "arm" and by not in frozen:
                moves.append(("swap", by, t, 0))
            for m in p.task_modes[t]:
                if m == cur.modes[t] or (allowed is not None and not allowed[m]):
                    continue
                a2 = int(p.mode_arm[m])
                n2 = int(cur.seq_n[a2])
                seq2 = cur.seq[a2, :n2]
                at = (
                    int(np.searchsorted(cur.state.t_start[seq2], cur.state.t_start[t])) if n2 else 0
                )
                for k in range(at - window, at + window + 1):
                    if 0 <= k <= n2:
                        moves.append(("move", t, m, k))
        if not moves:
            break
        if len(moves) > max_moves:
            idx = rng.choice(len(moves), size=max_moves, replace=False)
            moves = [moves[i] for i in idx]
        # rank by an estimate from heads and tails; decode only the most promising
        st = cur.state
        dur = st.t_end - st.t_start
        tail = _tails(p, cur, dur)
        estimates = []
        for mv in moves:
            kind, t, x, y = mv
            if kind == "swap":
                u, v = t, x
                a = int(p.mode_arm[cur.modes[v]])
                i = int(pos[u])
                pre = int(cur.seq[a, i - 1]) if i > 0 else -1
                post = int(cur.seq[a, i + 2]) if i + 2 < cur.seq_n[a] else -1
                ready = st.t_end[pre] + p.setup_time(a, pre, v) if pre >= 0 else st.t_start[u]
                rv = max([ready, *(st.t_end[q] for q in p.task_preds[v] if q != u)])
                ev_ = rv + dur[v]
                ru = max([ev_ + p.setup_time(a, v, u), *(st.t_end[q] for q in p.task_preds[u])])
                eu = ru + dur[u]
                qu = max([0.0, *(dur[q] + tail[q] for q in p.task_succs[u])])
                if post >= 0:
                    qu = max(qu, p.setup_time(a, u, post) + dur[post] + tail[post])
                qv = max(
                    [
                        dur[u] + qu + p.setup_time(a, v, u),
                        *(dur[q] + tail[q] for q in p.task_succs[v]),
                    ]
                )
                est = max(rv + dur[v] + qv, eu + qu)
            else:
                m2, k = x, y
                a2 = int(p.mode_arm[m2])
                n2 = int(cur.seq_n[a2])
                pre = int(cur.seq[a2, k - 1]) if k > 0 else -1
                post = int(cur.seq[a2, k]) if k < n2 else -1
                r = max([float(p.task_release[t]), *(st.t_end[q] for q in p.task_preds[t])])
                if pre >= 0:
                    r = max(r, st.t_end[pre] + p.setup_time(a2, pre, t))
                d2 = float(p.mode_duration[m2])
                q_ = max([0.0, *(dur[q] + tail[q] for q in p.task_succs[t])])
                if post >= 0:
                    q_ = max(q_, p.setup_time(a2, t, post) + dur[post] + tail[post])
                est = r + d2 + q_
            estimates.append((est, rng.random(), mv))
        estimates.sort(key=lambda e: (e[0], e[1]))
        budget.prep = time.perf_counter() - tp
        if random_moves and len(estimates) > exact_moves:
            # a few moves past the top of the ranking, at random
            rest = estimates[exact_moves - random_moves :]
            picks = rng.choice(len(rest), size=min(random_moves, len(rest)), replace=False)
            estimates = estimates[: exact_moves - random_moves] + [rest[i] for i in sorted(picks)]
        choice: tuple[_Seq, tuple[str, int, int, int]] | None = None
        tried = 0
        for _est, _r, mv in estimates:
            if out_of_budget() or tried >= exact_moves:
                break
            kind, t, x, y = mv
            if kind == "swap":
                attr = ("pair", x, t)
            else:
                attr = ("arm", t, int(p.mode_arm[x]))
            if tabu.get(attr, 0) > it and _est >= best.key[0] - 1e-9:
                continue  # tabu, and not even estimated to beat the best
            tried += 1
            if kind == "swap":
                u, v = t, x  # u right before v on one arm
                a = int(p.mode_arm[cur.modes[v]])
                seq = cur.seq.copy()
                i = int(pos[u])
                seq[a, i], seq[a, i + 1] = v, u
                cand = decode(cur.modes, seq, cur.seq_n)
            else:
                m2, k = x, y
                a1 = int(p.mode_arm[cur.modes[t]])
                a2 = int(p.mode_arm[m2])
                seq = cur.seq.copy()
                seq_n = cur.seq_n.copy()
                i = int(pos[t])
                n1 = int(seq_n[a1])
                seq[a1, i : n1 - 1] = cur.seq[a1, i + 1 : n1]
                seq[a1, n1 - 1] = -1
                seq_n[a1] -= 1
                n2 = int(seq_n[a2])
                seq[a2, k + 1 : n2 + 1] = cur.seq[a2, k:n2]
                seq[a2, k] = t
                seq_n[a2] += 1
                modes = cur.modes.copy()
                modes[t] = m2
                cand = decode(modes, seq, seq_n)
            if cand is None:
                continue
            if tabu.get(attr, 0) > it and cand.key[0] >= best.key[0] - 1e-9:
                continue
            if choice is None or cand.key < choice[0].key:
                choice = (cand, mv)
        if choice is None:
            stall += 1
        else:
            cand, (kind, t, x, _y) = choice
            tenure = tenure0 + int(rng.integers(0, tenure0 // 2 + 1))
            if kind == "swap":
                tabu[("pair", t, x)] = it + tenure  # forbid putting them back
            else:
                tabu[("arm", t, int(p.mode_arm[cur.modes[t]]))] = it + tenure  # forbid going back
            cur = cand
            if cur.key < best.key:
                improved = cur.key[0] < best.key[0] - 1e-9
                best = cur
                stall = 0 if improved else stall + 1
                if improved and on_improve is not None:
                    on_improve(to_solution(best))
            else:
                stall += 1
        if stall >= patience:
            # restart from the best with a few random reassignments and swaps
            stall = 0
            tabu.clear()
            cur = _kick(best, p, rng, decode, allowed, frozen, kick) or best
    return to_solution(best)


def _kick(
    s: _Seq,
    p: Problem,
    rng: np.random.Generator,
    decode: Callable[..., _Seq | None],
    allowed: np.ndarray | None,
    frozen: frozenset[int],
    strength: int,
) -> _Seq | None:
    """A random perturbation: about ``strength`` adjacent swaps and reassignments."""
    seq, seq_n, modes = s.seq.copy(), s.seq_n.copy(), s.modes.copy()
    for _ in range(strength + int(rng.integers(0, strength + 1))):
        a = int(rng.integers(p.n_arms))
        n = int(seq_n[a])
        if n < 2:
            continue
        i = int(rng.integers(n - 1))
        t = int(seq[a, i])
        if t in frozen or seq[a, i + 1] in frozen:
            continue
        alts = [m for m in p.task_modes[t] if m != modes[t] and (allowed is None or allowed[m])]
        if alts and rng.random() < 0.5:
            m2 = alts[int(rng.integers(len(alts)))]
            a2 = int(p.mode_arm[m2])
            seq[a, i : n - 1] = seq[a, i + 1 : n].copy()
            seq[a, n - 1] = -1
            seq_n[a] -= 1
            n2 = int(seq_n[a2])
            k = int(rng.integers(n2 + 1))
            seq[a2, k + 1 : n2 + 1] = seq[a2, k:n2].copy()
            seq[a2, k] = t
            seq_n[a2] += 1
            modes[t] = m2
        else:
            seq[a, i], seq[a, i + 1] = seq[a, i + 1], seq[a, i]
    return decode(modes, seq, seq_n)
