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
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from scheduler.problem import Problem
from scheduler.schedule import Schedule

__all__ = [
    "ExactResult",
    "applicable",
    "branch_and_bound",
    "oracle_binding",
    "without_idle_oracle",
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
