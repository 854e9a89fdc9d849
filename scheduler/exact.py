"""Exact branch and bound over modes and orderings (the tree search's proof phase).

For small problems the tree search can prove optimality. This module
enumerates, depth first:

1. a mode for every task (in topological order, shortest first), pruning
   with the longest path of the tasks chosen so far plus their tails;
2. then, while two tasks conflict (on an arm, an exclusive zone, a shared
   zone's movement or a tool) at their earliest times, the two orders of
   that pair.

Every task is a chain of time points (its start, one after each wait at a
zone border, its end); constraints are differences between time points, so
the earliest times of a node are longest paths from a time origin (a simple
temporal network), updated incrementally when a branch adds an edge. A
positive cycle means the branch is infeasible. When no conflict is left, the
earliest times form a valid schedule whose makespan is the node's bound, so
the search is complete: every schedule orders each conflicting pair one way
or the other, and the earliest times of those orders are no later.

Conditions (checked by :func:`applicable`): no blocking oracle (its cost
depends on which arms are parked, not a difference constraint; an oracle
that charges nothing anywhere can be dropped first, see
:func:`oracle_binding` and :func:`without_idle_oracle`), no arm
starting inside an exclusive zone, and setup times that obey the triangle
inequality (``setup(p, q) <= setup(p, r) + duration(r) + setup(r, q)``,
true of travel times), so that an arm's pairwise orders imply its sequence.

:func:`prove` (the exact method for compiled cells)
----------------------------------------------------
The same search, made to prove the optimum of the built-in cells (see
docs/scheduler.md, "The exact reference on compiled cells"). Each rule below
keeps the optimum of the true problem (waits at zone borders allowed, as
:func:`scheduler.validate` allows them), so a finished search is a proof:

* **Reductions.** An idle blocking oracle is dropped (:func:`without_idle_oracle`:
  no schedule changes). Dominated resources are left out
  (:func:`scheduler.cpsat.essential_resources`: each of their uses lies
  inside a use of a kept resource by the same task, waits included). Only
  *relevant* borders get a time point (:func:`relevant_borders`): a wait at
  any other border ``b`` is moved to the next relevant border, or dropped
  after the last one; no kept window starts between them, a kept window
  ending between them ends earlier, one spanning both is unchanged, no kept
  movement window has ``b`` strictly inside it (else ``b`` would be
  relevant), and the task ends no later, so the moved schedule is valid and
  no longer.
* **Modes** are fixed task by task (the incumbent's first). Bound: the
  longest path of the chosen tasks plus their tails (least durations of
  their successors), and the arm bounds below on the chosen tasks.
* **Arm sequences** are fixed arm by arm (the incumbent's order first); each
  consecutive pair adds ``start >= end + travel``, which with the triangle
  inequality orders every pair of the arm's tasks. Every schedule has one
  sequence per arm, so enumerating them all loses nothing. When a task
  ``y`` is placed next, every task ``z`` of the arm not yet placed gets
  ``start(z) >= end(y) + travel(y, z)`` at once (every completion puts ``z``
  after ``y``, and the triangle inequality bounds the travel in between), so
  a prefix pushes the rest of the arm's work, and all that waits for it,
  later; a precedence the prefix breaks shows as a positive cycle at once.
  At a complete sequence these edges are implied by the consecutive ones.
  Measured on ``supersigma``: 2.3 times fewer nodes to the proof.
* **Pairwise orders** of intervals of different arms in one kept resource
  that overlap at the earliest times (the earliest conflict first), as in
  :func:`branch_and_bound`; with no conflict left, the earliest times are a
  valid schedule (validated before it is kept).
* **Immediate selection** (Carlier and Pinson's pair rule) at every node of
  the pairwise orders, once a schedule is known
  (:func:`scheduler.kernel.exact_bb.select_pairs`): intervals ``i`` and
  ``j`` of different arms in one kept resource never overlap; if ``i`` came
  first, ``j`` would start at ``i``'s earliest end or later, last at least
  its nominal length and be followed by at least its tail (the rest of its
  task and the task's static tail, or the network's longest path from its
  end point, see below), so every such completion ends at ``ee_i + len_j +
  tail_j`` or later. When that is at least the best makespan less 1e-9 s,
  no completion that could improve on it puts ``i`` first, and ``j before
  i`` is added as an edge (the same edge its branch would add). Both orders
  excluded, or a positive cycle, cut the node. Earliest times only grow, so
  the rule runs to a fixed point. It removes only completions the pruning
  rule below would cut anyway, so the search stays complete for schedules
  better than the best, and a bound of a node (or of a kept leaf) with such
  edges bounds every completion better than the best: :attr:`Proof.bound`
  is capped at the best makespan, so it stays a bound of the optimum.
  The network's tails are taken once at the first node of a pairwise-order
  search and kept below it (edges only lengthen paths, so they stay tails).
  Measured on ``supersigma`` (docs/scheduler.md): 526,027 nodes to the
  proof against 772,041 without it, about the same wall time, the optimum
  found in about half the time; tried at the arm-sequence level too, it
  added ~500 orders per node (every pair of windows of two tasks) and
  halved the node rate, so it runs only below that level.
* **Node bounds** (each a lower bound of every completion, waits included,
  since a wait only lengthens what it is in): the earliest end of every task
  plus its tail; per arm, the one-machine bound of its tasks (a later start
  plus all durations and least travel into all but one of them plus the
  least tail); per kept resource, the same over its intervals (their
  nominal lengths, the rest of the task after them plus its tail; the
  preemptive bound below); per pair
  of arms and threshold ``h``, the tasks of both starting at ``h`` or later
  progress ``sum X`` and ``sum Y`` and both at once for at most the sum of
  their pairwise overlap caps (:mod:`scheduler.overlap`, an upper bound of
  the time two modes progress together), so the span after ``h`` is at least
  ``sum X + sum Y - sum caps``.
* **Tails from the network.** A node's edges (precedence with nominal task
  steps, the arm sequences and the orders fixed so far) hold in every
  completion, so the makespan is at least ``x[u] + L(u)``, ``L(u)`` the
  longest path from point ``u`` to any task's end
  (:func:`scheduler.kernel.exact_bb.stn_tails`; waits only lengthen a
  path). Every tail above (of a task, an arm's task, an interval: ``L`` of
  its closing point less its offset) is the larger of the static one and
  this one, so a task followed on its arm by others carries their work.
* **Every arm in a resource at once** (Jackson's preemptive bound, Carlier):
  the intervals of one kept resource never overlap in time, whichever arms
  they belong to (one arm's are sequential, other arms' are excluded by the
  resource: an exclusive zone, a shared zone's movement, a tool), each lasts
  at least its nominal length, starts no earlier than its head (earliest
  time) and is followed by at least its tail. So for every subset ``J`` of
  them the makespan is at least ``min head(J) + sum length(J) + min
  tail(J)``; :func:`scheduler.kernel.exact_bb.jackson_bound` takes the
  largest over all subsets (for least head ``a`` and least tail ``b``, every
  interval with head ``>= a`` and tail ``>= b`` may join, so ``n * n``
  candidates suffice). This is where three or four arms taking turns in one
  zone or use one tool (``scara4``'s blocks and its screwdriver) show, which the pair bounds
  below miss. Both are taken at the sequence level (the pairwise-order
  nodes keep the cheaper bounds: a weaker bound cuts less, never wrongly).
* **Coordination-diagram bound** once every arm's sequence is fixed, per
  pair of arms (:func:`scheduler.kernel.exact_bb.diagram_bound`): the two
  sequences laid end to end (tasks and travel) are the axes, every pair of
  their windows in one resource a forbidden rectangle (and each precedence
  between the two arms a forbidden quadrant), and the longest chain of
  :func:`scheduler.kernel.exact_bb.diagram_chain` bounds the diagonal of every monotone
  path with the overlap caps' König argument; releases and other arms are
  left out (a relaxation), the earliest starts enter as heads. A coarse grid
  is tried first: every cell side gives a bound. A cell is marked only when
  it lies inside a rectangle with 1e-6 of a cell to spare: the end of the
  diagram is often a corner of a rectangle (both arms' last windows end
  with their tasks), and ``e / step`` a hair above its whole value once
  marked the last cell and cut the optimal leaf (regression test in
  ``tests/scheduler/test_exact_bounds.py``).
* **Order.** A first pass fixes modes and sequences and keeps, on a heap
  by bound, every leaf whose node bound is below the incumbent; a leaf's
  diagram bound (costlier) is taken when the leaf first comes to the top,
  and the leaf goes back when that raises it above the next one. Each time
  the heap has doubled (16, 32, ... leaves) the best leaf is searched at
  once (the network saved and restored around it), for an incumbent that
  cuts the rest of the pass; a leaf is dropped only when a bound of its own
  reaches the incumbent, so nothing is lost. The second pass searches the
  leaves left by increasing bound, so when it stops early every schedule
  better than the best found lies in a leaf not yet finished, whose bound
  is at least the current one: :attr:`Proof.bound` is then a lower bound of
  the optimum (else the problem's :func:`scheduler.lower_bound` or
  ``lower``).
* **Pruning** cuts a node whose bound is at least the best makespan less
  1e-9 s: the optimum is proven to 1e-9 s.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np

from scheduler.problem import Problem
from scheduler.schedule import Schedule

__all__ = [
    "ExactResult",
    "Proof",
    "applicable",
    "branch_and_bound",
    "oracle_binding",
    "prove",
    "relevant_borders",
    "without_idle_oracle",
    "zone_free",
]

_EPS = 1e-9


def oracle_binding(problem: Problem, max_queries: int = 1_000_000) -> bool | None:
    """Whether the blocking oracle can ever charge a detour (S2.6).

    Asks the oracle every question a schedule can raise: each mode ``m``
    against each other arm ``b`` parked at its initial pose (``-1``) or at
    the end pose of any task ``b`` can do. When every answer is 0, no
    schedule is ever charged a detour nor refused a start, so the problem
    with the oracle and without it have the same valid schedules with the
    same makespans: exact methods may drop it (:func:`without_idle_oracle`).

    Parameters
    ----------
    problem : Problem
    max_queries : int
        Give up (return None) when more questions than this would be asked.

    Returns
    -------
    bool or None
        False: no oracle, or it never charges; True: some answer is
        positive or infinite; None: not checked (too many questions).

    Examples
    --------
    >>> from scheduler.generate import random_problem
    >>> oracle_binding(random_problem(2, 6, 2, 1, seed=1))
    False
    >>> oracle_binding(random_problem(2, 6, 2, 1, seed=1, blocking=True))
    True
    """
    p = problem
    oracle = p.blocking
    if oracle is None:
        return False
    poses = [[-1, *np.flatnonzero(p.mode_of[b] >= 0).tolist()] for b in range(p.n_arms)]
    asked = sum(
        len(poses[b]) for m in range(p.n_modes) for b in range(p.n_arms) if b != p.mode_arm[m]
    )
    if asked > max_queries:
        return None
    for m in range(p.n_modes):
        a = int(p.mode_arm[m])
        for b in range(p.n_arms):
            if b == a:
                continue
            for pose in poses[b]:
                if float(oracle.cost(m, b, pose)) != 0.0:
                    return True
    return False


def without_idle_oracle(problem: Problem, max_queries: int = 1_000_000) -> Problem:
    """The problem without its blocking oracle when that oracle never charges
    (:func:`oracle_binding` is False); else the problem itself, unchanged.

    Dropping an oracle that answers 0 to every question changes no
    constraint, so an optimum or a bound of the result is one of ``problem``.
    """
    if problem.blocking is not None and oracle_binding(problem, max_queries) is False:
        return replace(problem, blocking=None)
    return problem


def zone_free(problem: Problem) -> Problem:
    """The problem without its zones: a relaxation whose optimum bounds the true one.

    Every window, every arm's start zones and the blocking oracle are
    dropped; arms, tasks, modes and their durations, tools, travel, releases,
    precedence and arm availability stay. Every schedule
    :func:`scheduler.validate` accepts for ``problem`` keeps its modes, arm
    sequences, travel, tools and precedence, and its tasks last at least
    their modes (waits at borders and detours only lengthen them): once each
    task is shortened back to its mode, it is a schedule of the result no
    longer than before. So the optimum of the result (or any lower bound of
    it) is a lower bound of ``problem``'s. Where a plan of ``problem``
    meets it, the plan is optimal: the S2.6 parking scene, whose best plan
    sends an arm around a parked one and is no longer than the plan with
    no zone at all (the tree search proves it this way).

    The exact search applies to the result (:func:`applicable`) whenever
    its setup times obey the triangle inequality.

    Parameters
    ----------
    problem : Problem

    Returns
    -------
    Problem
        A new problem with the same arms, tasks and modes, named
        ``"<name> (zone-free)"``.

    Examples
    --------
    >>> from scheduler.generate import random_problem
    >>> p = random_problem(2, 6, 2, 1, seed=1, blocking=True)
    >>> q = zone_free(p)
    >>> q.n_windows, q.blocking, q.n_tasks == p.n_tasks
    (0, None, True)
    >>> from scheduler import solve
    >>> prove(q).makespan <= solve(p, "tree", time_limit=1, seed=0).objective
    True
    """
    p = problem
    none = np.zeros(0, dtype=np.int64)
    return replace(
        p,
        win_mode=none,
        win_zone=none.copy(),
        win_start=np.zeros(0),
        win_end=np.zeros(0),
        win_move=np.zeros(0, dtype=bool),
        arm_start_zones=tuple(() for _ in range(p.n_arms)),
        blocking=None,
        name=f"{p.name} (zone-free)",
    )


def applicable(problem: Problem, max_tasks: int = 12) -> tuple[bool, str]:
    """Whether the exact search can prove optimality here, and why not."""
    p = problem
    if p.n_tasks > max_tasks:
        return False, f"more than {max_tasks} tasks"
    if p.blocking is not None:
        return False, "a blocking oracle is set"
    if any(p.zone_exclusive[z] for zs in p.arm_start_zones for z in zs):
        return False, "an arm starts inside an exclusive zone"
    if not p._setup.is_metric():
        return False, "setup times break the triangle inequality"
    return True, ""


@dataclass
class ExactResult:
    schedule: Schedule | None
    makespan: float
    complete: bool
    nodes: int
    pruned: int


class _Net:
    """Incremental longest paths on a difference-constraint network."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.out: list[list[tuple[int, float]]] = [[] for _ in range(n)]
        self.dist = [0.0] * n

    def add(self, u: int, v: int, w: float) -> bool:
        """Add ``x[v] >= x[u] + w``; False on a positive cycle (edge stays)."""
        self.out[u].append((v, w))
        if self.dist[u] + w <= self.dist[v] + _EPS:
            return True
        self.dist[v] = self.dist[u] + w
        stack = [v]
        count = 0
        limit = 4 * self.n * self.n + 100
        while stack:
            x = stack.pop()
            dx = self.dist[x]
            for y, wy in self.out[x]:
                if dx + wy > self.dist[y] + _EPS:
                    if y == u:
                        return False
                    self.dist[y] = dx + wy
                    stack.append(y)
                    count += 1
                    if count > limit:
                        return False
        return True

    def pop(self, k: int, u_list: list[int]) -> None:
        for u in reversed(u_list[-k:]):
            self.out[u].pop()


def branch_and_bound(
    problem: Problem,
    upper: float = math.inf,
    deadline: float = math.inf,
    waits: bool = True,
    max_nodes: int | None = None,
    stop: Any = None,
) -> ExactResult:
    """Search for a schedule shorter than ``upper``; ``complete`` is True when
    the search finished (then the best found, or none, is optimal). It stops
    early at ``deadline``, after ``max_nodes`` nodes, or once ``stop`` (a
    ``threading.Event``) is set."""
    p = problem
    T = p.n_tasks
    shapes = p.shapes
    tails = np.zeros(T)
    mind = p.min_duration()
    order = list(p.topological_order)
    for t in reversed(order):
        for s in p.task_succs[t]:
            tails[t] = max(tails[t], mind[s] + tails[s])
    # time points: 0 = origin; per task, points allocated when its mode is chosen
    max_pts = 1 + sum(max(len(shapes[m].borders) for m in p.task_modes[t]) + 2 for t in range(T))
    net = _Net(max_pts)
    edges_src: list[int] = []
    base = [0] * T
    mode_of = [-1] * T
    best_mk = [upper]
    best_sched: list[Schedule | None] = [None]
    stats = {"nodes": 0, "pruned": 0, "timeout": False}

    def add(u: int, v: int, w: float) -> bool:
        edges_src.append(u)
        return net.add(u, v, w)

    def undo(k: int, saved: list[float]) -> None:
        net.pop(k, edges_src)
        del edges_src[len(edges_src) - k :]
        net.dist = saved

    def end_pt(t: int) -> int:
        return base[t] + len(shapes[mode_of[t]].borders) + 1

    def bound() -> float:
        b = 0.0
        for t in range(T):
            if mode_of[t] >= 0:
                b = max(b, net.dist[end_pt(t)] + tails[t])
        return b

    def intervals(t: int) -> list[tuple[int, int, float, int, float]]:
        """(resource, start point, offset, end point, offset) of task t."""
        sh = shapes[mode_of[t]]
        P = [0.0, *sh.borders, sh.duration]
        b0 = base[t]

        def at(x: float, closing: bool) -> tuple[int, float]:
            # time point and offset of nominal offset x (closing: reached
            # before the wait at x; opening: after it)
            for j in range(len(P) - 1, -1, -1):
                if P[j] < x if closing else P[j] <= x:
                    return b0 + j, x - P[j]
            return b0, x

        out = []
        for r, s, e in sh.exclusive:
            ps, os_ = at(s, False)
            pe, oe = at(e, True)
            out.append((r, ps, os_, pe, oe))
        for r, s, e in sh.moves:
            for j in range(len(P) - 1):
                a0, a1 = P[j], P[j + 1]
                if s < a1 and e > a0:
                    out.append((r, b0 + j, max(s, a0) - a0, b0 + j, min(e, a1) - a0))
        for r in sh.tools:
            out.append((r, b0, 0.0, end_pt(t), 0.0))
        return out

    def find_conflict() -> tuple[tuple[int, int, float], tuple[int, int, float]] | None:
        """A pair of orders to branch on: ((u, v, w) for 'x first'), ((u, v, w) for 'y first')."""
        d = net.dist
        arms: dict[int, list[int]] = {}
        for t in range(T):
            arms.setdefault(int(p.mode_arm[mode_of[t]]), []).append(t)
        best_c = None
        best_overlap = -1.0
        for a, ts in arms.items():
            for i1 in range(len(ts)):
                for i2 in range(i1 + 1, len(ts)):
                    x, y = ts[i1], ts[i2]
                    sx, ex, sy, ey = d[base[x]], d[end_pt(x)], d[base[y]], d[end_pt(y)]
                    su_xy = p.setup_time(a, x, y)
                    su_yx = p.setup_time(a, y, x)
                    if sy < ex + su_xy - _EPS and sx < ey + su_yx - _EPS:
                        ov = min(ex + su_xy - sy, ey + su_yx - sx)
                        if ov > best_overlap:
                            best_overlap = ov
                            best_c = ((end_pt(x), base[y], su_xy), (end_pt(y), base[x], su_yx))
        by_res: dict[int, list[tuple[int, int, float, int, float]]] = {}
        for t in range(T):
            for r, ps, os_, pe, oe in intervals(t):
                by_res.setdefault(r, []).append((t, ps, os_, pe, oe))
        for items in by_res.values():
            for i1 in range(len(items)):
                for i2 in range(i1 + 1, len(items)):
                    x, psx, osx, pex, oex = items[i1]
                    y, psy, osy, pey, oey = items[i2]
                    if x == y or p.mode_arm[mode_of[x]] == p.mode_arm[mode_of[y]]:
                        continue
                    s1, e1 = d[psx] + osx, d[pex] + oex
                    s2, e2 = d[psy] + osy, d[pey] + oey
                    if s1 < e2 - _EPS and s2 < e1 - _EPS:
                        ov = min(e1, e2) - max(s1, s2)
                        if ov > best_overlap:
                            best_overlap = ov
                            best_c = ((pex, psy, oex - osy), (pey, psx, oey - osx))
        return best_c

    def record() -> None:
        d = net.dist
        mk = max(d[end_pt(t)] for t in range(T)) if T else 0.0
        if mk < best_mk[0] - _EPS:
            modes = [mode_of[t] for t in range(T)]
            starts = [d[base[t]] for t in range(T)]
            ws = []
            for t in range(T):
                sh = shapes[mode_of[t]]
                P = [0.0, *sh.borders, sh.duration]
                ws.append(
                    [
                        d[base[t] + j] - d[base[t] + j - 1] - (P[j] - P[j - 1])
                        for j in range(1, len(P) - 1)
                    ]
                )
                ws[-1] = [max(0.0, w) for w in ws[-1]]
            best_mk[0] = mk
            best_sched[0] = Schedule.from_starts(p, modes, starts, ws)

    node_limit = math.inf if max_nodes is None else max_nodes

    def exhausted() -> bool:
        if (
            time.perf_counter() > deadline
            or stats["nodes"] >= node_limit
            or (stop is not None and stop.is_set())
        ):
            stats["timeout"] = True
        return bool(stats["timeout"])

    def disjunctive() -> None:
        if exhausted():
            return
        stats["nodes"] += 1
        if bound() >= best_mk[0] - _EPS:
            stats["pruned"] += 1
            return
        c = find_conflict()
        if c is None:
            record()
            return
        for u, v, w in c:
            saved = list(net.dist)
            ok = add(u, v, w)
            if ok:
                disjunctive()
            undo(1, saved)
            if stats["timeout"]:
                return

    next_pt = [1]

    def choose(i: int) -> None:
        if exhausted():
            return
        if i == len(order):
            disjunctive()
            return
        t = order[i]
        for m in sorted(p.task_modes[t], key=lambda m: p.mode_duration[m]):
            stats["nodes"] += 1
            sh = shapes[m]
            P = [0.0, *sh.borders, sh.duration]
            base[t] = next_pt[0]
            mode_of[t] = m
            a = int(p.mode_arm[m])
            saved = list(net.dist)
            first = base[t]
            new_edges = [
                (
                    0,
                    first,
                    max(
                        float(p.task_release[t]), float(p.arm_available[a]) + p.setup_time(a, -1, t)
                    ),
                )
            ]
            for j in range(1, len(P)):
                new_edges.append((first + j - 1, first + j, P[j] - P[j - 1]))
                if not waits or j == len(P) - 1:
                    new_edges.append((first + j, first + j - 1, -(P[j] - P[j - 1])))
            for q in p.task_preds[t]:
                new_edges.append((end_pt(q), first, 0.0))
            ok = True
            for u, v, w in new_edges:  # add them all, so that undo pops exactly these
                ok = add(u, v, w) and ok
            k = len(new_edges)
            next_pt[0] += len(P)
            if ok and bound() < best_mk[0] - _EPS:
                choose(i + 1)
            else:
                stats["pruned"] += 1
            next_pt[0] -= len(P)
            undo(k, saved)
            mode_of[t] = -1
            if stats["timeout"]:
                return

    choose(0)
    return ExactResult(
        best_sched[0], best_mk[0], not stats["timeout"], int(stats["nodes"]), int(stats["pruned"])
    )


@dataclass(frozen=True, slots=True)
class Proof:
    """The result of :func:`prove`.

    Attributes
    ----------
    schedule : Schedule or None
        The best schedule found (the incumbent given, if nothing better).
    makespan : float
        Its makespan (``inf`` when none).
    bound : float
        A lower bound of the optimum of the true problem: ``makespan`` when
        ``proven``, else the root node's bound (or the ``lower`` given).
    proven : bool
        The search finished: ``makespan`` is the optimum (none below it by
        more than 1e-9 s; with no schedule, none below ``upper``).
    nodes : int
        Search nodes visited (the deterministic work measure).
    pruned : int
        Nodes cut by their bound or an infeasible order.
    seconds : float
        Wall time.
    reason : str
        Why it stopped: ``"proven"``, ``"time"``, ``"nodes"``, ``"stopped"``,
        ``"leaves"`` (more kept leaves than ``max_leaves``), or why the method
        does not apply (then nothing was searched).
    counts : tuple of (str, int)
        Work by level: mode assignments completed, arm-sequence leaves reached
        (``sequences``), kept for the second pass (``kept``) and searched;
        with ``workers > 1``, summed over the parts, and ``parts``: how many.
    """

    schedule: Schedule | None
    makespan: float
    bound: float
    proven: bool
    nodes: int
    pruned: int
    seconds: float
    reason: str
    counts: tuple[tuple[str, int], ...] = ()


def relevant_borders(problem: Problem, m: int, resources: frozenset[int]) -> tuple[float, ...]:
    """The borders of mode ``m`` where a wait can matter: a window of a resource
    in ``resources`` starts there, or it lies strictly inside such a movement
    window. A wait at any other border can be moved to the next relevant one
    (or dropped after the last) without lengthening any use of those
    resources, the task or the schedule (see :mod:`scheduler.exact`)."""
    sh = problem.shapes[m]
    keep: set[float] = set()
    for r, s, _ in (*sh.exclusive, *sh.moves):
        if r not in resources:
            continue
        if 0.0 < s < sh.duration:
            keep.add(s)
    for r, s, e in sh.moves:
        if r in resources:
            keep.update(b for b in sh.borders if s < b < e)
    return tuple(b for b in sh.borders if b in keep)


class _ModeData:
    """Per mode: time points (start, relevant borders, end) and the intervals of
    the essential resources, as offsets from those points."""

    def __init__(self, problem: Problem, m: int, resources: frozenset[int], waits: bool) -> None:
        sh = problem.shapes[m]
        self.borders = relevant_borders(problem, m, resources) if waits else ()
        P = [0.0, *self.borders, sh.duration]
        self.P = P
        self.n_pts = len(P)
        self.duration = sh.duration
        self.border_index = [sh.borders.index(b) for b in self.borders]

        def closing(x: float) -> tuple[int, float]:  # last point strictly before x (end)
            j = max(k for k in range(len(P) - 1) if P[k] < x or k == 0)
            return j, x - P[j]

        def opening(x: float) -> tuple[int, float]:  # last point at or before x (start)
            j = max(k for k in range(len(P) - 1) if P[k] <= x)
            return j, x - P[j]

        iv: list[tuple[int, int, float, int, float, float, float]] = []
        for r, s, e in sh.exclusive:
            if r in resources:
                j0, o0 = opening(s)
                j1, o1 = closing(e)
                iv.append((r, j0, o0, j1, o1, e - s, sh.duration - e))
        for r, s, e in sh.moves:
            if r in resources:
                cuts = [s, *(b for b in self.borders if s < b < e), e]
                for a0, a1 in itertools.pairwise(cuts):
                    j0, o0 = opening(a0)
                    j1, o1 = closing(a1)
                    iv.append((r, j0, o0, j1, o1, a1 - a0, sh.duration - a1))
        for r in sh.tools:
            if r in resources:
                iv.append((r, 0, 0.0, len(P) - 1, 0.0, sh.duration, 0.0))
        self.intervals = iv


def prove(
    problem: Problem,
    time_limit: float | None = None,
    max_nodes: int | None = None,
    *,
    incumbent: Schedule | None = None,
    upper: float = math.inf,
    lower: float = 0.0,
    waits: bool = True,
    progress: Any = None,
    progress_every: float = 10.0,
    stop: Any = None,
    cap_step: float | None = None,
    modes: Sequence[int] | None = None,
    sequences: bool = True,
    diagram_step: float | None = None,
    max_leaves: int = 2_000_000,
    plain_nodes: int = 100_000,
    select: bool = True,
    stop_at_first: bool = False,
    domains: Mapping[int, Sequence[int]] | None = None,
    workers: int = 1,
) -> Proof:
    """Prove the optimum by branch and bound (the exact method for compiled cells).

    The problem is first reduced without changing its optimum (see the module
    docstring): an idle blocking oracle is dropped (:func:`without_idle_oracle`),
    dominated resources are left out
    (:func:`scheduler.cpsat.essential_resources`) and only the borders where
    a wait can matter get a time point (:func:`relevant_borders`). The search
    then fixes a mode per task, then orders conflicting pairs (tasks of one
    arm, intervals of different arms in one resource), pruning a node whose
    bound (:func:`scheduler.kernel.exact_bb.node_bound`) reaches the best
    makespan so far.

    Parameters
    ----------
    problem : Problem
    time_limit : float or None
        Wall-clock limit, seconds (None: none).
    max_nodes : int or None
        Deterministic work limit: stop after this many nodes.
    incumbent : Schedule or None
        A valid schedule to start from (e.g. the tree search's plan): only
        better ones are searched for, and its modes and start order are
        tried first. It is validated here.
    upper : float
        Search only for schedules shorter than this.
    lower : float
        A known lower bound of the optimum (e.g. :func:`scheduler.reference.best_bound`):
        the search stops as soon as a schedule meets it, and the bound reported
        is at least it.
    waits : bool
        Whether arms may wait at zone borders (as :func:`scheduler.validate` allows).
    progress : callable or None
        Called with a one-line status every ``progress_every`` seconds.
    stop : threading.Event or None
        Stop early once set.
    select : bool
        Immediate selection in the pairwise-order search (see the module
        docstring); False only to measure what it buys.
    stop_at_first : bool
        Stop at the first schedule shorter than ``upper`` (reason
        ``"found"``): the search then only answers whether one exists. A
        result with ``proven`` and no schedule says none does.
    domains : mapping of int to sequence of int, or None
        Modes the search may give some tasks (task -> its allowed modes;
        the others keep all theirs): the search and its proof are then of
        the schedules in which those tasks take those modes. With
        ``modes``, only the modes in both count.
    workers : int
        Processes searching at once (default 1: this one). With more, the
        mode assignments are split into parts by the modes of the first
        tasks (in topological order) that have a choice, about four parts a
        worker, and forked processes prove them, at most ``workers`` at a
        time, each from the same ``incumbent`` and ``upper`` (so each part's
        work, and the schedule returned, do not depend on which part ends
        first; ``max_nodes`` and ``plain_nodes`` are shared out evenly,
        ``time_limit`` is one wall clock for all). The problem is proven when every part is; the
        bound is the least of the parts' bounds (a part not searched counts
        with the root bound). One process where the split gives a single
        part, ``fork`` is missing, or this is a daemon process (e.g. a Dask
        worker). ``progress`` then reports each part as it ends, and
        ``stop`` is read between parts' results (the parts are stopped).

    Returns
    -------
    Proof

    Examples
    --------
    >>> from scheduler import solve, validate
    >>> from scheduler.generate import random_problem
    >>> p = random_problem(2, 6, 2, 1, seed=1)
    >>> res = prove(p, time_limit=60)
    >>> res.proven, validate(p, res.schedule) == res.makespan
    (True, True)
    >>> res.makespan <= solve(p, "tree", time_limit=1, seed=0).objective
    True
    """
    from scheduler.cpsat import essential_resources
    from scheduler.kernel import exact_bb as kb
    from scheduler.overlap import overlap_caps
    from scheduler.schedule import validate

    t0 = time.perf_counter()
    deadline = math.inf if time_limit is None else t0 + time_limit
    if workers > 1 and applicable(without_idle_oracle(problem), max_tasks=10**9)[0]:
        split = _parts(problem, modes, domains, 4 * workers, incumbent)
        if split and _may_fork():
            return _prove_parts(
                problem,
                split,
                workers,
                t0,
                time_limit,
                max_nodes,
                progress,
                stop,
                lower,
                dict(
                    incumbent=incumbent,
                    upper=upper,
                    lower=lower,
                    waits=waits,
                    cap_step=cap_step,
                    modes=modes,
                    sequences=sequences,
                    diagram_step=diagram_step,
                    max_leaves=max_leaves,
                    plain_nodes=plain_nodes,
                    select=select,
                    stop_at_first=stop_at_first,
                ),
            )
    if sequences and plain_nodes > 0:
        # first the search without the sequence level, on a small budget: it
        # proves problems with few conflicts at once and gives an incumbent
        again = partial(
            prove,
            problem,
            upper=upper,
            lower=lower,
            waits=waits,
            progress=progress,
            progress_every=progress_every,
            stop=stop,
            cap_step=cap_step,
            modes=modes,
            select=select,
            stop_at_first=stop_at_first,
            domains=domains,
        )
        first = again(
            None if time_limit is None else time_limit / 4,
            plain_nodes if max_nodes is None else min(plain_nodes, max_nodes // 4),
            incumbent=incumbent,
            sequences=False,
        )
        if first.proven or first.reason not in ("time", "nodes"):
            return replace(first, seconds=time.perf_counter() - t0)
        rest = again(
            None if time_limit is None else max(0.0, time_limit - first.seconds),
            None if max_nodes is None else max(0, max_nodes - first.nodes),
            incumbent=first.schedule if first.schedule is not None else incumbent,
            sequences=True,
            diagram_step=diagram_step,
            max_leaves=max_leaves,
            plain_nodes=0,
        )
        return replace(
            rest,
            nodes=first.nodes + rest.nodes,
            pruned=first.pruned + rest.pruned,
            seconds=time.perf_counter() - t0,
            bound=max(first.bound, rest.bound) if not rest.proven else rest.bound,
        )
    p = without_idle_oracle(problem)
    ok, why = applicable(p, max_tasks=10**9)
    if not ok:
        return Proof(None, math.inf, lower, False, 0, 0, 0.0, why)
    T = p.n_tasks
    best_mk = upper
    best_sched: Schedule | None = None
    inc_start = np.zeros(T)
    inc_mode = [-1] * T
    if incumbent is not None:
        mk = validate(problem, incumbent)
        inc_start = np.asarray(incumbent.start, dtype=float)
        inc_mode = [int(m) for m in incumbent.mode]
        if mk < best_mk:
            best_mk, best_sched = mk, incumbent
    if T == 0:
        return Proof(Schedule.from_starts(p, [], []), 0.0, 0.0, True, 0, 0, 0.0, "proven")
    resources = essential_resources(p)
    shape = [_ModeData(p, m, resources, waits) for m in range(p.n_modes)]
    mind = p.min_duration()
    tails = np.zeros(T)
    for t in reversed(p.topological_order):
        for s in p.task_succs[t]:
            tails[t] = max(tails[t], mind[s] + tails[s])
    # the overlap caps (an upper bound on the time two modes of different arms
    # progress at once); pairs sharing no resource: the shorter duration
    mode_cap = np.zeros((p.n_modes, p.n_modes))
    for m1 in range(p.n_modes):
        for m2 in range(p.n_modes):
            if p.mode_arm[m1] != p.mode_arm[m2]:
                mode_cap[m1, m2] = min(p.mode_duration[m1], p.mode_duration[m2])
    caps = overlap_caps(p, step=cap_step)
    for (m1, m2), po in (caps or {}).items():
        mode_cap[m1, m2] = mode_cap[m2, m1] = min(mode_cap[m1, m2], po.cap)
    scratch = [np.zeros(T + 1) for _ in range(4)]
    base = np.zeros(T, dtype=np.int64)
    n_pts = 1
    for t in range(T):
        base[t] = n_pts
        n_pts += max(shape[m].n_pts for m in p.task_modes[t])
    n_iv = sum(max(len(shape[m].intervals) for m in p.task_modes[t]) for t in range(T))
    # every branch adds one edge per pair of intervals or tasks, at most once on a path
    max_edges = 4 * n_pts + 2 * len(p.task_preds) + sum(map(len, p.task_preds))
    # branches, immediate selections, and the arm-prefix edges (each task after
    # each one placed before it on its arm)
    max_edges += 2 * n_iv * n_iv + 2 * T * T + 64
    head = np.full(n_pts, -1, dtype=np.int64)
    nxt = np.zeros(max_edges, dtype=np.int64)
    src = np.zeros(max_edges, dtype=np.int64)
    dst = np.zeros(max_edges, dtype=np.int64)
    wt = np.zeros(max_edges)
    ne = np.zeros(1, dtype=np.int64)
    dist = np.zeros(n_pts)
    tail_pt = np.zeros(n_pts)
    sel_tail = np.zeros(n_pts)  # the tails immediate selection uses (see ``selected``)
    queue = np.zeros(n_pts + 1, dtype=np.int64)
    queued = np.zeros(n_pts, dtype=np.bool_)
    mode_of = [-1] * T
    stats = {
        "nodes": 0,
        "pruned": 0,
        "assignments": 0,
        "diagrams": 0,
        "diagram_calls": 0,
        "kept": 0,
        "searched": 0,
        "selected": 0,
    }
    reason = [""]
    last_report = [t0]
    node_limit = math.inf if max_nodes is None else max_nodes

    def add(u: int, v: int, w: float) -> bool:
        if ne[0] >= len(src):
            raise RuntimeError("edge store full")  # pragma: no cover - sized above
        return bool(kb.stn_add(head, nxt, src, dst, wt, ne, dist, queue, queued, u, v, w))

    def attempt(edges: Callable[[], bool], then: Callable[[], None]) -> bool:
        """One branch: add its edges (``edges`` returns False when the branch is
        infeasible or cut), run ``then`` on the new node if not, then remove
        the edges and restore the earliest times. False once the search stops."""
        saved = dist.copy()
        keep = int(ne[0])
        if edges():
            then()
        else:
            stats["pruned"] += 1
        kb.stn_pop(head, nxt, src, ne, keep)
        dist[:] = saved
        return not reason[0]

    def exhausted() -> bool:
        if reason[0]:
            return True
        now = time.perf_counter()
        if now > deadline:
            reason[0] = "time"
        elif stats["nodes"] >= node_limit:
            reason[0] = "nodes"
        elif stop is not None and stop.is_set():
            reason[0] = "stopped"
        elif best_mk <= lower + _EPS:
            reason[0] = "met the lower bound"
        elif stop_at_first and best_mk < upper:
            reason[0] = "found"
        if progress is not None and now - last_report[0] >= progress_every:
            last_report[0] = now
            progress(
                f"exact: {now - t0:.0f} s, {stats['nodes']:,} nodes, "
                f"{stats['pruned']:,} pruned, {stats['assignments']:,} mode assignments, "
                f"{stats['diagrams']:,} sequences, {len(leaves):,} kept, "
                f"{stats['searched']:,} searched, "
                f"best {best_mk:.3f}"
            )
        return bool(reason[0])

    def end_pt(t: int) -> int:
        return int(base[t]) + shape[mode_of[t]].n_pts - 1

    # ---- phase 2 arrays (filled when every mode is fixed)
    def phase2_arrays() -> dict[str, Any]:
        t_start = base.copy()
        t_end = np.array([end_pt(t) for t in range(T)], dtype=np.int64)
        t_arm = np.array([int(p.mode_arm[mode_of[t]]) for t in range(T)], dtype=np.int64)
        t_dur = np.array([shape[mode_of[t]].duration for t in range(T)])
        setup = np.full((T, T), np.inf)
        for x in range(T):
            for y in range(T):
                if x != y and t_arm[x] == t_arm[y]:
                    setup[x, y] = p.setup_time(int(t_arm[x]), x, y)
        t_setin = np.zeros(T)
        for t in range(T):
            ins = [setup[x, t] for x in range(T) if x != t and t_arm[x] == t_arm[t]]
            t_setin[t] = min(ins) if ins else 0.0
        rows: list[tuple[int, int, int, float, int, float, float, float]] = []
        for t in range(T):
            md = shape[mode_of[t]]
            for r, j0, o0, j1, o1, ln, tl in md.intervals:
                rows.append((r, t, int(base[t]) + j0, o0, int(base[t]) + j1, o1, ln, tl))
        rows.sort(key=lambda x: (x[0], x[2], x[1]))
        lo = [0]
        for k in range(1, len(rows)):
            if rows[k][0] != rows[k - 1][0]:
                lo.append(k)
        lo.append(len(rows))
        n = max(len(rows), T) + 1
        return {
            "t_start": t_start,
            "t_end": t_end,
            "t_arm": t_arm,
            "t_dur": t_dur,
            "t_tail": tails.copy(),
            "t_setin": t_setin,
            "cap": np.array(
                [[mode_cap[mode_of[x], mode_of[y]] for y in range(T)] for x in range(T)]
            ),
            "th": np.zeros(T),
            "setup": setup,
            "i_lo": np.array(lo if rows else [0], dtype=np.int64),
            "i_task": np.array([x[1] for x in rows], dtype=np.int64),
            "i_ps": np.array([x[2] for x in rows], dtype=np.int64),
            "i_os": np.array([x[3] for x in rows]),
            "i_pe": np.array([x[4] for x in rows], dtype=np.int64),
            "i_oe": np.array([x[5] for x in rows]),
            "i_len": np.array([x[6] for x in rows]),
            "i_tail": np.array([x[7] for x in rows]),
            "h": np.zeros(n),
            "ln": np.zeros(n),
            "tl": np.zeros(n),
            "ex": np.zeros(n),
            "out": np.zeros(6),
            "tt": np.zeros(T),
            "order": np.zeros(n, dtype=np.int64),
            "sel": np.zeros((len(rows), len(rows)), dtype=np.bool_),
            "si": np.zeros(len(rows) * len(rows) + 1, dtype=np.int64),
            "sj": np.zeros(len(rows) * len(rows) + 1, dtype=np.int64),
            "sn": np.zeros(1, dtype=np.int64),
        }

    def bound2(a: dict[str, Any], cut: float = math.inf, deep: bool = True) -> float:
        """The node bound; it may stop early once at ``cut`` or above. Without
        ``deep``, the cheap bounds only (the pairwise orders' nodes: there the
        network tails and preemptive bounds were measured to cut too little
        for their cost on ``supersigma``)."""
        return float(
            kb.node_bound(
                dist, a["t_start"], a["t_end"], a["t_arm"], a["t_dur"], a["t_tail"],
                a["t_setin"], p.n_arms, a["cap"], a["th"], a["i_lo"], a["i_task"], a["i_ps"], a["i_os"],
                a["i_len"], a["i_tail"], a["h"], a["ln"], a["tl"], a["ex"], head, nxt, dst, wt,
                a["i_pe"], a["i_oe"], tail_pt, a["tt"], a["order"], cut, deep,
            )
        )  # fmt: skip

    def record() -> None:
        nonlocal best_mk, best_sched
        mk = max(float(dist[end_pt(t)]) for t in range(T))
        if mk >= best_mk - _EPS:
            return
        starts = [float(dist[base[t]]) for t in range(T)]
        ws = []
        for t in range(T):
            md = shape[mode_of[t]]
            w = np.zeros(len(p.shapes[mode_of[t]].borders))
            for j in range(1, md.n_pts - 1):
                gap = dist[base[t] + j] - dist[base[t] + j - 1] - (md.P[j] - md.P[j - 1])
                w[md.border_index[j - 1]] = max(0.0, float(gap))
            ws.append(w)
        sched = Schedule.from_starts(p, list(mode_of), starts, ws)
        best_mk = validate(problem, sched)
        best_sched = sched

    def selected(a: dict[str, Any], fresh: bool) -> tuple[bool, Any]:
        """Immediate selection at the node (:func:`scheduler.kernel.exact_bb.select_pairs`,
        against the incumbent): whether the node may still hold a better
        schedule, and the pairs it ordered (their marks to clear on leaving).
        The network's tails are taken at the first node of a pairwise-order
        search (``fresh``) and kept for the nodes below it: edges only
        lengthen paths, so an ancestor's tails are still tails there."""
        if not select:
            return True, None
        if fresh:  # also with no schedule yet: one may be found below
            kb.stn_tails(head, nxt, dst, wt, a["t_end"], sel_tail)
        if not math.isfinite(best_mk):
            return True, None
        ok = bool(
            kb.select_pairs(
                head, nxt, src, dst, wt, ne, dist, queue, queued, a["t_arm"], a["t_tail"],
                a["i_lo"], a["i_task"], a["i_ps"], a["i_os"], a["i_pe"], a["i_oe"], a["i_len"],
                a["i_tail"], sel_tail, best_mk - _EPS, a["sel"], a["si"], a["sj"], a["sn"], 64,
            )
        )  # fmt: skip
        n = int(a["sn"][0])
        stats["selected"] += n
        return ok, (a["si"][:n].copy(), a["sj"][:n].copy()) if n else None

    def disjunctive(a: dict[str, Any], floor: float = 0.0, fresh: bool = True) -> None:
        if exhausted():
            return
        stats["nodes"] += 1
        if floor >= best_mk - _EPS or bound2(a, best_mk - _EPS, False) >= best_mk - _EPS:
            stats["pruned"] += 1
            return
        ok, marks = selected(a, fresh)
        try:
            if not ok or (marks is not None and bound2(a, best_mk - _EPS, False) >= best_mk - _EPS):
                stats["pruned"] += 1
                return
            branch(a, floor)
        finally:
            if marks is not None:
                a["sel"][marks] = False

    def branch(a: dict[str, Any], floor: float) -> None:
        """Record the node's schedule when no conflict is left, else branch on one."""
        out = a["out"]
        if not kb.conflict(
            dist, a["t_start"], a["t_end"], a["t_arm"], a["setup"], a["i_lo"], a["i_task"],
            a["i_ps"], a["i_os"], a["i_pe"], a["i_oe"], out,
        ):  # fmt: skip
            record()
            return
        b1 = (int(out[0]), int(out[1]), float(out[4]))
        b2 = (int(out[2]), int(out[3]), float(out[5]))
        # the incumbent's order first: the branch whose later point comes later there
        tx = int(np.searchsorted(base, b1[0], side="right")) - 1
        ty = int(np.searchsorted(base, b1[1], side="right")) - 1
        if inc_start[ty] < inc_start[tx]:
            b1, b2 = b2, b1
        for u, v, w in (b1, b2):
            if not attempt(partial(add, u, v, w), partial(disjunctive, a, floor, False)):
                return

    order = list(p.topological_order)

    def bound1(i: int) -> float:
        b = 0.0
        t_arm = np.full(T, -1, dtype=np.int64)
        th = np.zeros(T)
        t_dur = np.zeros(T)
        cap = np.zeros((T, T))
        done = order[:i]
        for t in done:
            b = max(b, float(dist[end_pt(t)]) + tails[t])
            t_arm[t] = int(p.mode_arm[mode_of[t]])
            th[t] = dist[base[t]]
            t_dur[t] = shape[mode_of[t]].duration
        for x in done:
            for y in done:
                cap[x, y] = mode_cap[mode_of[x], mode_of[y]]
        # unassigned tasks are on no arm (-1) and left out
        ab = kb.arm_bound(th, t_arm, t_dur, tails, np.zeros(T), cap, p.n_arms, *scratch)
        return max(b, float(ab))

    presence = np.array(
        [r < p.n_zones or r >= 2 * p.n_zones for r in range(2 * p.n_zones + p.n_tools)],
        dtype=np.bool_,
    )
    nominal = []  # per mode: (res, s, e) arrays of its intervals, offsets from its start
    for md in shape:
        rows_ = [(r, md.P[j0] + o0, md.P[j1] + o1) for r, j0, o0, j1, o1, _, _ in md.intervals]
        nominal.append(
            (
                np.array([x[0] for x in rows_], dtype=np.int64),
                np.array([x[1] for x in rows_]),
                np.array([x[2] for x in rows_]),
            )
        )
    loads = [0.0] * p.n_arms
    for t in range(T):
        for m in p.task_modes[t]:
            loads[int(p.mode_arm[m])] += float(p.mode_duration[m]) / len(p.task_modes[t])
    step = diagram_step if diagram_step is not None else max(max(loads) / 400.0, 1e-6)

    def laid_out(arm: int, seq: list[int]) -> tuple[float, dict[int, float], list[Any]]:
        """The arm's progress axis: its tasks and travel end to end."""
        off = p.setup_time(arm, -1, seq[0]) if seq else 0.0
        at: dict[int, float] = {}
        parts = []
        prev = -1
        for t in seq:
            if prev >= 0:
                off += p.setup_time(arm, prev, t)
            at[t] = off
            r, s0, e0 = nominal[mode_of[t]]
            parts.append((r, s0 + off, e0 + off))
            off += shape[mode_of[t]].duration
            prev = t
        return off, at, parts

    def diagram_bound(seqs: list[list[int]]) -> float:
        """The largest coordination-diagram bound over pairs of arms (-1: infeasible)."""
        outs = [laid_out(arm, seq) for arm, seq in enumerate(seqs)]
        best = 0.0
        for x in range(p.n_arms):
            for y in range(x + 1, p.n_arms):
                if not seqs[x] or not seqs[y]:
                    continue
                la, at_a, pa = outs[x]
                lb, at_b, pb = outs[y]
                pd, pe, ps = [], [], []
                for t in seqs[y]:
                    for q in p.task_preds[t]:
                        if q in at_a:
                            pd.append(0)
                            pe.append(at_a[q] + shape[mode_of[q]].duration)
                            ps.append(at_b[t])
                for t in seqs[x]:
                    for q in p.task_preds[t]:
                        if q in at_b:
                            pd.append(1)
                            pe.append(at_b[q] + shape[mode_of[q]].duration)
                            ps.append(at_a[t])
                heads = [
                    (
                        np.array([at[t] for t in sq]),
                        np.array([float(dist[base[t]]) for t in sq]),
                    )
                    for at, sq in ((at_a, seqs[x]), (at_b, seqs[y]))
                ]
                args = (
                    la, lb,
                    np.concatenate([r for r, _, _ in pa]), np.concatenate([s for _, s, _ in pa]),
                    np.concatenate([e for _, _, e in pa]), np.concatenate([r for r, _, _ in pb]),
                    np.concatenate([s for _, s, _ in pb]), np.concatenate([e for _, _, e in pb]),
                    presence, np.array(pd, dtype=np.int64), np.array(pe, dtype=float),
                    np.array(ps, dtype=float), heads[0][0], heads[0][1], heads[1][0],
                    heads[1][1],
                )  # fmt: skip
                # a coarse grid first (any cell side gives a bound), the fine one if needed
                low = kb.diagram_bound(*args, 4.0 * step, best_mk - _EPS)
                if 0 <= low < best_mk - _EPS:
                    low = kb.diagram_bound(*args, step, best_mk - _EPS)
                if low < 0:
                    return -1.0
                best = max(best, float(low))
        return best

    def sequence(a: dict[str, Any], arms: list[list[int]], k: int, seq: list[int]) -> None:
        """Fix each arm's task sequence (arm ``k`` is being built as ``seq``;
        the arms before it are in ``done_seqs``)."""
        if exhausted():
            return
        stats["nodes"] += 1
        here = bound2(a, best_mk - _EPS)
        if here >= best_mk - _EPS:
            stats["pruned"] += 1
            return
        if len(seq) == len(arms[k]):
            done_seqs.append(list(seq))
            if k + 1 < p.n_arms:
                sequence(a, arms, k + 1, [])
            else:
                stats["diagrams"] += 1
                if not math.isfinite(best_mk):  # no schedule yet: search this leaf now
                    floor = diagram_bound(done_seqs)
                    stats["diagram_calls"] += 1
                    if floor < 0 or floor >= best_mk - _EPS:
                        stats["pruned"] += 1
                    else:
                        stats["searched"] += 1
                        disjunctive(a, max(floor, here))
                else:  # kept with the node's bound; its diagram bound when it comes up
                    seqs = [list(q) for q in done_seqs]
                    stats["kept"] += 1
                    heapq.heappush(leaves, (here, stats["kept"], tuple(mode_of), seqs, False))
                    if len(leaves) >= probe[0]:
                        probe_best_leaf()
            done_seqs.pop()
            return
        rest = sorted(set(arms[k]) - set(seq), key=lambda t: (inc_start[t], t))

        def after(y: int) -> bool:
            """``y`` next on arm ``k``: after the last task, and every other task
            of the arm not yet placed after ``y``, each with its travel."""
            ok = True
            if seq:
                ok = add(
                    int(a["t_end"][seq[-1]]), int(a["t_start"][y]), p.setup_time(k, seq[-1], y)
                )
            for z in rest:  # every completion puts z after y (triangle inequality)
                if z != y:
                    ok = add(int(a["t_end"][y]), int(a["t_start"][z]), p.setup_time(k, y, z)) and ok
            return ok

        def deeper(y: int) -> None:
            seq.append(y)
            sequence(a, arms, k, seq)
            seq.pop()

        for y in rest:
            if not attempt(partial(after, y), partial(deeper, y)):
                return

    done_seqs: list[list[int]] = []

    def place(t: int, m: int) -> bool:
        """Add the time points' edges of task ``t`` in mode ``m`` (``mode_of[t] == m``)."""
        md = shape[m]
        arm = int(p.mode_arm[m])
        first = int(base[t])
        release = max(
            float(p.task_release[t]), float(p.arm_available[arm]) + p.setup_time(arm, -1, t)
        )
        ok = add(0, first, release)
        for j in range(1, md.n_pts):
            step = md.P[j] - md.P[j - 1]
            ok = add(first + j - 1, first + j, step) and ok
            if j == md.n_pts - 1:  # no wait at the end: the task ends on time
                ok = add(first + j, first + j - 1, -step) and ok
        for q in p.task_preds[t]:
            ok = add(end_pt(q), first, 0.0) and ok
        return ok

    # (floor, number, modes, sequences, diagram bound taken) of every leaf of the
    # first pass not cut by its bound
    leaves: list[tuple[float, int, tuple[int, ...], list[list[int]], bool]] = []

    def search_leaf() -> float | None:
        """Take the kept leaf of least floor off the heap and search it; its
        diagram bound is taken the first time it comes up, and the leaf goes
        back when that raises it above the next one. Returns the floor of the
        leaf searched, or None (none searched: infeasible, cut or put back)."""
        floor, k, ms, seqs, diagram = heapq.heappop(leaves)
        kb.stn_pop(head, nxt, src, ne, 0)
        dist[:] = 0.0
        ok = True
        for t in order:
            mode_of[t] = ms[t]
            ok = place(t, ms[t]) and ok
        for arm, sq in enumerate(seqs):
            for x, y in itertools.pairwise(sq):
                ok = add(end_pt(x), int(base[y]), p.setup_time(arm, x, y)) and ok
        if ok and not diagram:
            low = diagram_bound(seqs)
            stats["diagram_calls"] += 1
            ok = 0 <= low < best_mk - _EPS
            if ok and low > floor and leaves and low > leaves[0][0]:
                heapq.heappush(leaves, (low, k, ms, seqs, True))
                return None
            floor = max(floor, low)
        if not ok:
            stats["pruned"] += 1
            return None
        a = arrays.get(ms)  # the last assignment's, if the same
        if a is None:
            arrays.clear()
            a = arrays[ms] = phase2_arrays()
        stats["searched"] += 1
        disjunctive(a, floor)
        return floor

    arrays: dict[tuple[int, ...], dict[str, Any]] = {}

    probe = [16]

    def probe_best_leaf() -> None:
        """In the first pass, once the heap holds ``probe`` leaves (doubled each
        time): search its best leaf now, for a better incumbent that cuts the
        rest of the pass (the network is saved around it and restored)."""
        probe[0] *= 2
        n = int(ne[0])
        saved = (head.copy(), nxt[:n].copy(), src[:n].copy(), dst[:n].copy(), wt[:n].copy())
        saved_dist, saved_modes = dist.copy(), list(mode_of)
        while leaves and not exhausted():
            if leaves[0][0] >= best_mk - _EPS:
                leaves.clear()  # every kept leaf is cut by the new incumbent
                break
            if search_leaf() is not None:
                break
        head[:] = saved[0]
        nxt[:n], src[:n], dst[:n], wt[:n] = saved[1:]
        ne[0] = n
        dist[:] = saved_dist
        mode_of[:] = saved_modes

    def choose(i: int) -> None:
        if exhausted():
            return
        if i == T:
            stats["assignments"] += 1
            a = phase2_arrays()
            if sequences:
                arms = [[t for t in range(T) if a["t_arm"][t] == arm] for arm in range(p.n_arms)]
                sequence(a, arms, 0, [])
                if len(leaves) > max_leaves:
                    reason[0] = "leaves"
            else:
                disjunctive(a)
            return
        t = order[i]
        allowed = p.task_modes[t] if modes is None else (int(modes[t]),)
        if domains is not None and t in domains:
            allowed = tuple(m for m in allowed if m in domains[t])
        cands = sorted(allowed, key=lambda m: (m != inc_mode[t], p.mode_duration[m]))

        def placed(m: int) -> bool:  # task t in mode m, and the node's bound under the best
            return place(t, m) and bound1(i + 1) < best_mk - _EPS

        for m in cands:
            stats["nodes"] += 1
            mode_of[t] = m
            go_on = attempt(partial(placed, m), partial(choose, i + 1))
            mode_of[t] = -1
            if not go_on:
                return

    choose(0)
    floor_now = -math.inf  # the floor of the leaf searched when the second pass stopped
    if sequences and not reason[0]:
        # second pass: the leaves by increasing floor; every schedule better than
        # the best lies in a leaf not yet searched, whose floor is at least the
        # current one
        while leaves and not exhausted() and leaves[0][0] < best_mk - _EPS:
            searched = search_leaf()
            if searched is not None:
                floor_now = searched
    proven = not reason[0] or reason[0] == "met the lower bound"
    root = max(lower, float(lower_bound_of(p)))
    bound = best_mk if proven else min(best_mk, max(root, floor_now))
    return Proof(
        best_sched,
        best_mk,
        bound,
        proven,
        int(stats["nodes"]),
        int(stats["pruned"]),
        time.perf_counter() - t0,
        "proven" if proven else reason[0],
        (
            ("assignments", int(stats["assignments"])),
            ("sequences", int(stats["diagrams"])),
            ("kept", int(stats["kept"])),
            ("diagrams", int(stats["diagram_calls"])),
            ("searched", int(stats["searched"])),
            ("selected", int(stats["selected"])),
        ),
    )


def _parts(
    problem: Problem,
    modes: Sequence[int] | None,
    domains: Mapping[int, Sequence[int]] | None,
    want: int,
    incumbent: Schedule | None,
) -> list[dict[int, tuple[int, ...]]]:
    """The parts of :func:`prove`'s split (``workers > 1``): the first tasks in
    topological order that have a choice of modes, until their combinations
    number at least ``want``, each combination a part (those tasks' modes
    fixed, with ``domains`` kept for the others), the incumbent's first; []
    when there is no choice to split."""
    allowed: dict[int, tuple[int, ...]] = {}
    for t in range(problem.n_tasks):
        ms = tuple(problem.task_modes[t]) if modes is None else (int(modes[t]),)
        if domains is not None and t in domains:
            ms = tuple(m for m in ms if m in domains[t])
        allowed[t] = ms
    chosen: list[int] = []
    count = 1
    for t in problem.topological_order:
        if count >= want:
            break
        if len(allowed[t]) >= 2:
            chosen.append(t)
            count *= len(allowed[t])
    if count < 2:
        return []
    base = {int(t): tuple(int(m) for m in ms) for t, ms in (domains or {}).items()}
    parts = [
        {**base, **{t: (int(m),) for t, m in zip(chosen, combo, strict=True)}}
        for combo in itertools.product(*(allowed[t] for t in chosen))
    ]
    if incumbent is not None:
        mine = tuple(int(incumbent.mode[t]) for t in chosen)
        parts.sort(key=lambda d: tuple(d[t][0] for t in chosen) != mine)
    return parts


def _may_fork() -> bool:
    """Whether :func:`prove` may fork its parts' processes (``fork`` exists and
    this process is no daemon, which may not have children)."""
    import multiprocessing

    return (
        "fork" in multiprocessing.get_all_start_methods()
        and not multiprocessing.current_process().daemon
    )


def _prove_part(conn: Any, problem: Problem, kwargs: dict[str, Any]) -> None:
    """A forked process of :func:`prove`'s split: prove one part, send the result back."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    try:
        res = prove(problem, **kwargs)
        s = res.schedule
        conn.send(
            (
                "ok",
                res.makespan,
                res.bound,
                res.proven,
                res.nodes,
                res.pruned,
                res.reason,
                res.counts,
                None
                if s is None
                else (s.mode, s.start, s.end, [w.copy() for w in s.waits], s.blocking),
            )
        )
    except Exception as exc:  # reported by the parent as an InternalError
        conn.send(("error", repr(exc)))
    finally:
        conn.close()


def _prove_parts(
    problem: Problem,
    parts: list[dict[int, tuple[int, ...]]],
    workers: int,
    t0: float,
    time_limit: float | None,
    max_nodes: int | None,
    progress: Any,
    stop: Any,
    lower: float,
    kwargs: dict[str, Any],
) -> Proof:
    """:func:`prove` with ``workers`` processes over ``parts`` (see its ``workers``)."""
    import multiprocessing
    from multiprocessing.connection import wait

    from multiarm.errors import InternalError

    ctx = multiprocessing.get_context("fork")
    deadline = math.inf if time_limit is None else t0 + time_limit
    per_part = None if max_nodes is None else max(1, max_nodes // len(parts))
    root = max(lower, float(lower_bound_of(problem)))
    results: dict[int, tuple[Any, ...]] = {}
    running: dict[Any, tuple[Any, int]] = {}
    nxt = 0
    reason = ""
    try:
        while nxt < len(parts) or running:
            while not reason and len(running) < workers and nxt < len(parts):
                left = deadline - time.perf_counter()
                if left <= 0:
                    reason = "time"
                    break
                here, there = ctx.Pipe(duplex=False)
                args = {
                    **kwargs,
                    "time_limit": None if time_limit is None else left,
                    "max_nodes": per_part,
                    "plain_nodes": -(-int(kwargs.get("plain_nodes", 0)) // len(parts)),
                    "domains": parts[nxt],
                }
                proc = ctx.Process(target=_prove_part, args=(there, problem, args), daemon=True)
                proc.start()
                there.close()
                running[here] = (proc, nxt)
                nxt += 1
            if not running:
                break
            ready: list[Any] = wait(list(running), timeout=0.2)
            for conn in ready:
                proc, k = running.pop(conn)
                try:
                    got = tuple(conn.recv())
                except EOFError:
                    got = ("error", f"the process of part {k + 1} ended without a result")
                conn.close()
                proc.join(timeout=5.0)
                if got[0] == "error":
                    raise InternalError(f"prove: part {k + 1} of {len(parts)} failed: {got[1]}")
                results[k] = got
                if got[6] in ("met the lower bound", "found"):
                    reason = got[6]  # the whole search is answered: end the rest
                if progress is not None:
                    progress(
                        f"exact: part {k + 1} of {len(parts)} {got[6]} after"
                        f" {time.perf_counter() - t0:.0f} s, {len(results)} done"
                    )
            if stop is not None and stop.is_set() and not reason:
                reason = "stopped"
            if reason:
                for proc, _k in running.values():
                    proc.terminate()
                for conn, (proc, _k) in list(running.items()):
                    proc.join(timeout=5.0)
                    conn.close()
                running.clear()
    finally:
        for conn, (proc, _k) in running.items():  # an exception (or Ctrl-C) on the way
            proc.terminate()
            proc.join(timeout=5.0)
            conn.close()
    best_mk = float(kwargs.get("upper", math.inf))  # as the one-process search starts
    best_sched: Schedule | None = None
    if kwargs.get("incumbent") is not None:
        from scheduler.schedule import validate

        mk = validate(problem, kwargs["incumbent"])
        if mk < best_mk:
            best_mk, best_sched = mk, kwargs["incumbent"]
    nodes = pruned = 0
    counts: dict[str, int] = {}
    bound = math.inf
    why = ""
    for k in range(len(parts)):  # in part order: the same schedule whichever ended first
        if k not in results:
            bound = min(bound, root)  # not searched, or stopped before its result
            why = why or reason or "time"
            continue
        _ok, mk, b, proven, n, pr, r, cnt, sched = results[k]
        nodes += n
        pruned += pr
        for key, v in cnt:
            counts[key] = counts.get(key, 0) + v
        if sched is not None and mk < best_mk - 1e-12:
            best_mk = mk
            best_sched = Schedule(sched[0], sched[1], sched[2], tuple(sched[3]), sched[4])
        if not proven:
            bound = min(bound, b)
            why = why or r
    met = best_mk <= lower + _EPS
    proven = met or not why
    if reason == "found":
        proven = False
        why = "found"
    seconds = time.perf_counter() - t0
    return Proof(
        best_sched,
        best_mk,
        best_mk if proven else min(best_mk, max(root, bound)),
        proven,
        nodes,
        pruned,
        seconds,
        ("met the lower bound" if met else "proven") if proven else why,
        (*counts.items(), ("parts", len(parts))),
    )


def lower_bound_of(problem: Problem) -> float:
    """:func:`scheduler.lower_bound` (imported late: it imports this module's users)."""
    from scheduler.bounds import lower_bound

    return float(lower_bound(problem))
