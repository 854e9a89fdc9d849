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
  its current start falls in that arm's sequence (or one place either side),
  and, with setup times, also at the place within ``travel_window`` places
  of that one where it adds the least travel
  (:func:`scheduler.kernel.critical.cheapest_slot`).

Moves are ranked by an estimate of the makespan through the moved task from
the current schedule's heads and tails (zones ignored), and only the best few
are decoded exactly.

It takes the best move that is not tabu — undoing a recent swap, or giving a
task back to an arm it just left — unless that move beats the best schedule
so far (aspiration), even when it is worse than the current one. After a run
without improvement it restarts from the best schedule with a random kick.

On a pure FJSP (:func:`pure_fjsp`: no zone windows, start zones, tools or
blocking oracle, setup times only where they obey the triangle inequality
(:func:`graph_setup`), and not a re-solve) the decoded schedule is the
longest-path schedule of the disjunctive graph (setups on its arm arcs), and :func:`graph_tabu`
runs instead: a compiled search (:mod:`scheduler.kernel._tabu_jit`) with the
k-insertion neighbourhood of Mastrolilli and Gambardella, each move's
makespan computed exactly, rotating through the tabu settings of
:data:`GRAPH_CONFIGS`; its best schedules are decoded by
:func:`~scheduler.kernel.seq_decode`, which must agree on the makespan.
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from multiarm.errors import InternalError
from multiarm.types import FloatArray, IntArray
from scheduler.kernel import State, compile_problem, seq_decode
from scheduler.kernel._tabu_jit import GraphArrays, SearchArrays, graph_makespan, tabu_run
from scheduler.kernel.critical import cheapest_slot
from scheduler.problem import Problem
from scheduler.search import Budget, Evaluator, Solution
from scheduler.setup import NoSetup

__all__ = [
    "GRAPH_CONFIGS",
    "GRAPH_SETUP_MAX_TASKS",
    "GraphConfig",
    "critical_chain",
    "graph_setup",
    "graph_tabu",
    "pure_fjsp",
    "tabu_search",
    "warm_up_graph",
]

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
    inst = compile_problem(p)
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
    travel_window: int = 8,
) -> Solution:
    """Improve ``start`` until ``deadline`` or ``max_evaluations`` decodes.

    ``travel_window``: with setup times, a reassigned task is also offered
    the slot of its new arm's sequence, within this many places of where it
    starts now, that adds the least travel (0: off).

    On a pure FJSP (:func:`pure_fjsp`) the compiled search on the
    disjunctive graph runs instead (:func:`graph_tabu`; one iteration counts
    as one evaluation), with the same stopping rules.
    """
    p = ev.problem
    inst = ev.inst
    if ev.blocking or start.state is None:
        return start
    if pure_fjsp(ev):
        return graph_tabu(
            ev,
            start,
            deadline,
            rng,
            on_improve=on_improve,
            lower=lower,
            max_evaluations=max_evaluations,
        )
    base = ev.base if ev.base is not None else inst.new_state()
    todo = np.flatnonzero(base.t_mode < 0)
    if len(todo) == 0:
        return start
    travel = travel_window > 0 and not isinstance(p.setup, NoSetup)
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
                if travel and n2:
                    # and where it adds the least travel, near where it starts now
                    k = cheapest_slot(inst, a2, t, seq2, at - travel_window, at + travel_window)
                    if abs(k - at) > window:
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


def pure_fjsp(ev: Evaluator) -> bool:
    """Whether the evaluator's problem is an FJSP the graph search handles:
    no zone windows, start zones, tools or blocking oracle, setup times that
    :func:`graph_setup` accepts (none, or obeying the triangle inequality),
    and no re-solve base state or frozen tasks (releases, arm availability,
    ``arm_lb`` and allowed modes are handled)."""
    p = ev.problem
    return (
        not ev.blocking
        and ev.base is None
        and not ev.frozen
        and p.n_windows == 0
        and p.n_tools == 0
        and not any(p.arm_start_zones)
        and graph_setup(p) is not None
    )


GRAPH_SETUP_MAX_TASKS = 600
"""The largest problem with setup times the graph search takes (it reads a
dense ``(A, T + 1, T)`` table and checks the triangle inequality in
``O(A T^3)``)."""

_SETUP_CACHE: OrderedDict[int, tuple[Problem, FloatArray | None]] = OrderedDict()


def graph_setup(p: Problem) -> FloatArray | None:
    """The setup times as the graph search reads them, or None where it cannot.

    With setups the disjunctive graph gets the setup time on each arc
    between consecutive tasks of an arm (and from the arm's initial pose to
    its first task). The k-insertion's makespan stays exact when the setups
    obey the triangle inequality with the task between:
    ``s(x, y) <= s(x, v) + p(v) + s(v, y)`` (every path of the graph with
    ``v`` taken out is then no longer than one through ``v`` put back), the
    condition :meth:`scheduler.setup.BoundSetup.is_metric` checks.

    Parameters
    ----------
    p : Problem

    Returns
    -------
    ndarray or None
        ``stp[arm, prev + 1, next]`` (row 0: from the initial pose; only the
        entries between tasks the arm can do are filled), shape ``(0, 1, 1)``
        without setups; None when a setup breaks the triangle inequality or
        the problem has more than :data:`GRAPH_SETUP_MAX_TASKS` tasks.
    """
    if isinstance(p.setup, NoSetup):
        return np.zeros((0, 1, 1))
    key = id(p)
    hit = _SETUP_CACHE.get(key)
    if hit is not None and hit[0] is p:
        return hit[1]
    out: FloatArray | None = None
    T, A = p.n_tasks, p.n_arms
    if T <= GRAPH_SETUP_MAX_TASKS:
        out = np.zeros((A, T + 1, T))
        for a in range(A):
            modes = np.flatnonzero(p.mode_arm == a)
            if len(modes) == 0:
                continue
            tasks = p.mode_task[modes]
            dur = p.mode_duration[modes]
            rows = np.array([p.setup_row(a, int(q))[tasks] for q in (-1, *tasks.tolist())])
            out[a, 0, tasks] = rows[0]
            out[a, (tasks + 1)[:, None], tasks[None, :]] = rows[1:]
            S = rows[1:].copy()
            np.fill_diagonal(S, 0.0)
            home = rows[0]
            bad = False
            for k in range(len(tasks)):
                via = S[k][None, :] + dur[k]
                if np.any(S[:, k : k + 1] + via + 1e-9 < S) or np.any(
                    home > home[k] + via[0] + 1e-9
                ):
                    bad = True
                    break
            if bad:
                out = None
                break
    _SETUP_CACHE[key] = (p, out)
    while len(_SETUP_CACHE) > 8:
        _SETUP_CACHE.popitem(last=False)
    return out


@dataclass(frozen=True)
class GraphConfig:
    """One setting of the compiled graph search (:func:`graph_tabu` rotates several)."""

    style: int = 1
    """What a move makes tabu: 0 the task right after its old predecessor,
    1 the task itself (it is not moved again), 2 the task right after its old
    predecessor or right before its old successor, 3 both 1 and 2."""
    tenure: int = -5
    """Iterations a move stays tabu (at least); negative: ``-tenure / 10``
    times the number of critical tasks at that moment."""
    tenure_span: int = 10
    """Random extra tenure: ``U{0..tenure_span}`` (negative tenure: in tenths
    of the base)."""
    top: int = 16
    """Moves (best by their exact makespan) whose whole schedule is computed
    to break ties by the sum of end times (1: ties broken at random)."""
    rank: int = 2
    """Tie-break before that: 0 the shorter path through the moved task,
    2 random, 3 the path through the task first."""


GRAPH_CONFIGS = (
    GraphConfig(1, -5, 10, 16, 2),
    GraphConfig(3, -3, 10, 1, 0),
    GraphConfig(2, 5, 5, 1, 0),
    GraphConfig(1, -10, 5, 16, 2),
)
"""The configurations :func:`graph_tabu` rotates through by default."""


class _Graph:
    """The flat arrays of a pure FJSP's disjunctive graph (see :mod:`scheduler.kernel._tabu_jit`)."""

    def __init__(self, ev: Evaluator) -> None:
        p = ev.problem
        T = p.n_tasks
        self.p = p
        self.pp = np.zeros(T + 1, dtype=np.int64)
        self.sp = np.zeros(T + 1, dtype=np.int64)
        self.pp[1:] = np.cumsum([len(x) for x in p.task_preds])
        self.sp[1:] = np.cumsum([len(x) for x in p.task_succs])
        self.pi = np.array([q for x in p.task_preds for q in x], dtype=np.int64)
        self.si = np.array([q for x in p.task_succs for q in x], dtype=np.int64)
        rel = p.task_release if ev.release is None else ev.release
        self.rel = np.ascontiguousarray(rel, dtype=np.float64)
        avail = np.asarray(p.arm_available, dtype=np.float64)
        if ev.arm_lb is not None:
            avail = np.maximum(avail, ev.arm_lb)
        self.avail = np.ascontiguousarray(avail)
        modes = [
            [m for m in p.task_modes[t] if ev.allowed is None or ev.allowed[m]] for t in range(T)
        ]
        self.tm_ptr = np.zeros(T + 1, dtype=np.int64)
        self.tm_ptr[1:] = np.cumsum([len(x) for x in modes])
        self.tm_mode = np.array([m for x in modes for m in x], dtype=np.int64)
        self.tm_arm = np.ascontiguousarray(p.mode_arm[self.tm_mode], dtype=np.int64)
        self.tm_dur = np.ascontiguousarray(p.mode_duration[self.tm_mode], dtype=np.float64)
        stp = graph_setup(p)
        if stp is None:
            raise InternalError(f"the graph search cannot read the setups of {p.name!r}")
        self.arrays = GraphArrays(
            self.pp,
            self.pi,
            self.sp,
            self.si,
            self.rel,
            self.avail,
            self.tm_ptr,
            self.tm_arm,
            self.tm_dur,
            stp,
        )
        """The same arrays bundled for the compiled search."""

    def choice_of(self, modes: IntArray) -> IntArray:
        """Per task, the index of its mode among its allowed modes."""
        out = np.zeros(self.p.n_tasks, dtype=np.int64)
        for t in range(self.p.n_tasks):
            lo, hi = int(self.tm_ptr[t]), int(self.tm_ptr[t + 1])
            hit = np.flatnonzero(self.tm_mode[lo:hi] == modes[t])
            if len(hit) == 0:
                raise InternalError(f"task {self.p.task_names[t]!r} is in a mode not allowed")
            out[t] = hit[0]
        return out

    def modes_of(self, choice: IntArray) -> IntArray:
        """Mode ids from per-task choices."""
        out: IntArray = self.tm_mode[self.tm_ptr[:-1] + choice]
        return out

    def makespan(self, choice: IntArray, seq: IntArray, seq_n: IntArray) -> float:
        """The longest path of the graph (-1.0: the sequences make a cycle)."""
        idx = self.tm_ptr[:-1] + choice
        return float(graph_makespan(self.arrays, self.tm_arm[idx], self.tm_dur[idx], seq, seq_n))


def graph_tabu(
    ev: Evaluator,
    start: Solution,
    deadline: float,
    rng: np.random.Generator,
    *,
    on_improve: Callable[[Solution], None] | None = None,
    lower: float = 0.0,
    max_evaluations: int | None = None,
    configs: tuple[GraphConfig, ...] | None = None,
    episode: int = 3000,
    patience: int = 6000,
    kick: int = 3,
    chunk: int = 32,
) -> Solution:
    """The compiled tabu search of a pure FJSP (:mod:`scheduler.kernel._tabu_jit`).

    k-insertion moves of critical tasks ranked by their exact makespan; the
    best schedule is decoded by :func:`~scheduler.kernel.seq_decode` at the
    end (and at each improvement reported to ``on_improve``). Iterations run
    in chunks of ``chunk`` between checks of the deadline, the work limit
    (one iteration = one evaluation) and a stop request.

    Parameters
    ----------
    ev : Evaluator
        Of a problem :func:`pure_fjsp` accepts.
    start : Solution
        A decoded solution (with its state).
    deadline : float
        ``time.perf_counter()`` value to stop at.
    rng : numpy.random.Generator
        Seeds the compiled search's own generator.
    on_improve : callable or None
        Called with the new best after each compiled call that improved it.
    lower : float
        Stop at this makespan (a lower bound).
    max_evaluations : int or None
        Iterations at most.
    configs : tuple of GraphConfig or None
        The settings to rotate through (default :data:`GRAPH_CONFIGS`).
    episode : int
        Iterations per setting; each new one starts from the best schedule
        with a kick.
    patience : int
        Iterations without a new best before restarting from the best.
    kick : int
        Random insertions at a restart.
    chunk : int
        Iterations per compiled call at first (doubled while a call takes
        under 4 ms; the search's course does not depend on it).

    Returns
    -------
    Solution
        The best solution found (``start`` when nothing better).
    """
    p = ev.problem
    inst = ev.inst
    T = p.n_tasks
    if start.state is None or T == 0:
        return start
    g = _Graph(ev)
    todo = np.arange(T, dtype=np.int64)
    seq, seq_n = _sequences(p, start.state, todo)
    choice = g.choice_of(start.state.t_mode)
    cmax0 = g.makespan(choice, seq, seq_n)
    if abs(cmax0 - start.makespan) > 1e-6:
        raise InternalError(
            f"graph makespan {cmax0} differs from the decoded {start.makespan} on {p.name!r}"
        )
    b_choice, b_seq, b_seq_n = choice.copy(), seq.copy(), seq_n.copy()
    tabu = np.zeros((T, T + p.n_arms + 1), dtype=np.int64)
    rs = np.array([int(rng.integers(1, 2**63 - 1))], dtype=np.uint64)
    ctl = np.zeros(3, dtype=np.int64)
    fctl = np.array([cmax0, cmax0, float(lower)])
    state = SearchArrays(choice, seq, seq_n, b_choice, b_seq, b_seq_n, tabu, rs, ctl, fctl)
    cfgs = configs if configs else GRAPH_CONFIGS
    k_cfg = 0
    in_episode = 0
    limit = math.inf if max_evaluations is None else ev.evaluations + max_evaluations

    def decoded(ch: IntArray, sq: IntArray, sn: IntArray) -> Solution:
        modes = g.modes_of(ch)
        ok, st, order = seq_decode(
            inst, sq, sn, modes, waits=ev.waits, release=ev.release, arm_lb=ev.arm_lb
        )
        if not ok:
            raise InternalError(f"graph search sequences do not decode on {p.name!r}")
        mk = float(st.t_end.max())
        if abs(mk - fctl[0]) > 1e-6:
            raise InternalError(f"graph makespan {fctl[0]} but decoded {mk} on {p.name!r}")
        return Solution(order.copy(), st.t_mode.copy(), mk, float(st.t_end.sum()), st)

    stop = ev.stop
    while (
        time.perf_counter() < deadline
        and ev.evaluations < limit
        and fctl[0] > lower + 1e-9
        and not (stop is not None and stop.is_set())
    ):
        if in_episode >= episode:
            # next configuration, from the best with a kick
            k_cfg = (k_cfg + 1) % len(cfgs)
            in_episode = 0
            ctl[1] = patience
        cf = cfgs[k_cfg]
        n = int(min(chunk, limit - ev.evaluations, max(1, episode - in_episode)))
        ctl[2] = 0
        tc = time.perf_counter()
        done = tabu_run(
            g.arrays,
            state,
            n,
            cf.tenure,
            cf.tenure_span,
            patience,
            kick,
            cf.style,
            cf.rank,
            cf.top,
        )
        in_episode += int(done)
        ev.evaluations += int(done)
        if time.perf_counter() - tc < 0.004 and done == n:
            chunk = min(2 * chunk, 4096)  # fewer calls where iterations are cheap
        if done == 0:
            break
        if ctl[2] and on_improve is not None:
            on_improve(decoded(b_choice, b_seq, b_seq_n))
    if fctl[0] >= start.makespan - 1e-9:
        return start
    return decoded(b_choice, b_seq, b_seq_n)


_WARM = False


def warm_up_graph() -> None:
    """Compile (or load from numba's on-disk cache) the graph search, once per process.

    The first compile takes several seconds once per machine; solvers call
    this before starting their clock.
    """
    global _WARM
    if _WARM:
        return
    from scheduler.fjsp import parse_fjsp

    p = parse_fjsp("2 2 1\n2 2 1 2 2 3 1 1 1\n1 2 1 2 2 1\n", name="warm-up")
    ev = Evaluator(p)
    sol = ev.evaluate(np.arange(p.n_tasks, dtype=np.int64))
    if sol is not None:
        graph_tabu(ev, sol, math.inf, np.random.default_rng(0), max_evaluations=2)
    _WARM = True
