"""Lower bounds on the makespan of a problem.

Every bound here is valid for any schedule :func:`~scheduler.validate`
accepts (waits and detours only make tasks longer), and each is cheap next to
a solve. :func:`lower_bound` is their maximum; :func:`lower_bounds` returns
the parts.

* **Critical path** with releases and arm availability: along every chain of
  predecessors, each task takes at least its shortest mode.
* **Load** (LP relaxation): assign tasks fractionally to arms, each mode
  costing its duration plus the smallest setup that can precede it; the best
  fractional makespan ``C`` with ``available[a] + load[a] <= C`` bounds the
  real one. Arms of different speeds are handled exactly by the LP.
* **Capability subsets**: tasks that only arms of a set ``E`` can do need at
  least ``(sum of available times + sum of their shortest modes) / |E|``.
* **Unary resources** (exclusive zones, movement in shared zones, tools):
  for the tasks that use the resource in every mode, the best over head
  thresholds ``h`` of ``h + sum of lengths + smallest tail``, where a head is
  the earliest the resource can be reached and a tail the least time from
  leaving it to the end of the schedule.

Examples
--------
>>> from scheduler.problem import Model
>>> m = Model()
>>> a, b = m.add_arm("a"), m.add_arm("b")
>>> for i in range(4):
...     t = m.add_task(f"t{i}")
...     m.add_mode(t, a, 3.0); m.add_mode(t, b, 3.0)
>>> lower_bound(m.build())
6.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from multiarm.types import FloatArray
from scheduler.problem import Problem

__all__ = ["LowerBounds", "lower_bound", "lower_bounds"]


@dataclass(frozen=True, slots=True)
class LowerBounds:
    """The parts of the lower bound (seconds) and their maximum ``value``."""

    value: float
    critical_path: float
    load: float
    capability: float
    resources: float
    resource_name: str = ""


def _min_incoming_setup(p: Problem) -> FloatArray:
    """(M,): for each mode, the smallest setup that can precede it on its arm."""
    out = np.zeros(p.n_modes)
    if p._setup.zero:
        return out
    for a in range(p.n_arms):
        modes = np.flatnonzero(p.mode_arm == a)
        if len(modes) == 0:
            continue
        best = p._setup.min_incoming(a)[p.mode_task[modes]]
        out[modes] = np.where(np.isfinite(best), best, 0.0)
    return out


def heads_and_tails(p: Problem) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(earliest start, shortest duration, tail) per task.

    The earliest start respects releases, predecessors (at their shortest)
    and the earliest available capable arm; the tail is the shortest time
    from a task's end to the end of every chain after it.
    """
    mind = p.min_duration()
    avail = np.full(p.n_tasks, np.inf)
    np.minimum.at(avail, p.mode_task, p.arm_available[p.mode_arm])
    order = p.topological_order
    est = np.maximum(p.task_release, avail)
    for t in order:
        for s in p.task_succs[t]:
            est[s] = max(est[s], est[t] + mind[t])
    tail = np.zeros(p.n_tasks)
    for t in reversed(order):
        for s in p.task_succs[t]:
            tail[t] = max(tail[t], mind[s] + tail[s])
    return est, mind, tail


def _resource_rows(
    p: Problem, est: FloatArray, tail: FloatArray
) -> tuple[list[int], list[int], list[float], list[float]]:
    """Per resource, its row of the load LP: (row, mode, length) entries and
    the room ``-(head + tail)``: every mode's use of the resource (merged
    windows; a tool: the whole mode) lies in ``[head, C - tail]``, the
    smallest head and tail over the modes that use it."""
    shapes = p.shapes
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    room: list[float] = []
    per_res: dict[int, list[tuple[int, float, float, float]]] = {}
    for m in range(p.n_modes):
        sh = shapes[m]
        t = int(p.mode_task[m])
        parts: dict[int, list[tuple[float, float]]] = {}
        for r, s, e in (*sh.exclusive, *sh.moves):
            parts.setdefault(r, []).append((s, e))
        for r in sh.tools:
            parts.setdefault(r, []).append((0.0, sh.duration))
        for r, ivs in parts.items():
            length = sum(e - s for s, e in ivs)
            head = float(est[t]) + min(s for s, _ in ivs)
            after = sh.duration - max(e for _, e in ivs) + float(tail[t])
            per_res.setdefault(r, []).append((m, length, head, after))
    for i, uses in enumerate(per_res.values()):
        for m, length, _, _ in uses:
            rows.append(i)
            cols.append(m)
            vals.append(length)
        room.append(-(min(u[2] for u in uses) + min(u[3] for u in uses)))
    return rows, cols, vals, room


def _load_lp(p: Problem, extra: FloatArray, est: FloatArray, tail: FloatArray) -> float:
    from scipy.optimize import linprog
    from scipy.sparse import coo_matrix

    M, T, A = p.n_modes, p.n_tasks, p.n_arms
    cost = p.mode_duration + extra
    # variables: x_0..x_{M-1}, C
    c = np.zeros(M + 1)
    c[M] = 1.0
    eq = coo_matrix((np.ones(M), (p.mode_task, np.arange(M))), shape=(T, M + 1))
    rr, rc, rv, room = _resource_rows(p, est, tail)
    R = len(room)
    rows = np.concatenate(
        [p.mode_arm, np.arange(A), A + np.asarray(rr, dtype=int), A + np.arange(R)]
    )
    cols = np.concatenate([np.arange(M), np.full(A, M), np.asarray(rc, dtype=int), np.full(R, M)])
    vals = np.concatenate([cost, -np.ones(A), np.asarray(rv, dtype=float), -np.ones(R)])
    ub = coo_matrix((vals, (rows, cols)), shape=(A + R, M + 1))
    res = linprog(
        c,
        A_ub=ub.tocsr(),
        b_ub=np.concatenate([-p.arm_available, np.asarray(room, dtype=float)]),
        A_eq=eq.tocsr(),
        b_eq=np.ones(T),
        bounds=[(0, 1)] * M + [(0, None)],
        method="highs",
    )
    if res.status != 0:  # pragma: no cover - the LP is always feasible and bounded
        return 0.0
    # HiGHS returns a primal within its tolerance: step down by it to stay valid
    return float(res.fun) * (1 - 1e-9) - 1e-9


def _capability(p: Problem, extra: FloatArray) -> float:
    cost = p.mode_duration + extra
    sets: dict[frozenset[int], float] = {}
    task_best = np.full(p.n_tasks, np.inf)
    np.minimum.at(task_best, p.mode_task, cost)
    task_sets = [frozenset(int(p.mode_arm[m]) for m in ms) for ms in p.task_modes]
    candidates = (
        set(task_sets) | {frozenset([a]) for a in range(p.n_arms)} | {frozenset(range(p.n_arms))}
    )
    for e in candidates:
        work = sum(task_best[t] for t, s in enumerate(task_sets) if s <= e)
        if work > 0:
            sets[e] = (work + float(sum(p.arm_available[a] for a in e))) / len(e)
    return max(sets.values(), default=0.0)


def _resources(p: Problem, est: FloatArray, tail: FloatArray) -> tuple[float, str]:
    shapes = p.shapes
    Z = p.n_zones
    per_res: dict[int, list[tuple[float, float, float]]] = {}
    for t in range(p.n_tasks):
        usage: dict[int, list[tuple[float, float, float]]] = {}
        for m in p.task_modes[t]:
            sh = shapes[m]
            parts: dict[int, list[tuple[float, float]]] = {}
            for r, s, e in (*sh.exclusive, *sh.moves):
                parts.setdefault(r, []).append((s, e))
            for r in sh.tools:
                parts.setdefault(r, []).append((0.0, sh.duration))
            for r, ivs in parts.items():
                length = sum(e - s for s, e in ivs)
                head = min(s for s, _ in ivs)
                after = sh.duration - max(e for _, e in ivs)
                usage.setdefault(r, []).append((length, head, after))
        n_modes = len(p.task_modes[t])
        for r, uses in usage.items():
            if len(uses) == n_modes:  # every mode needs the resource
                per_res.setdefault(r, []).append(
                    (
                        min(u[0] for u in uses),
                        est[t] + min(u[1] for u in uses),
                        min(u[2] for u in uses) + tail[t],
                    )
                )
    best, best_name = 0.0, ""
    for r, jobs in per_res.items():
        jobs.sort(key=lambda j: j[1])
        heads = [j[1] for j in jobs]
        total, min_tail = 0.0, math.inf
        bound = 0.0
        for i in range(len(jobs) - 1, -1, -1):
            total += jobs[i][0]
            min_tail = min(min_tail, jobs[i][2])
            bound = max(bound, heads[i] + total + min_tail)
        if bound > best:
            best = bound
            kind, name = shapes.resource_name(r)
            best_name = f"{kind} {name}"
    _ = Z
    return best, best_name


def lower_bounds(problem: Problem) -> LowerBounds:
    """Every lower bound on the makespan (see the module docstring)."""
    p = problem
    if p.n_tasks == 0:
        return LowerBounds(0.0, 0.0, 0.0, 0.0, 0.0)
    est, mind, tail = heads_and_tails(p)
    cp = float(np.max(est + mind + tail))
    extra = _min_incoming_setup(p)
    load = _load_lp(p, extra, est, tail)
    cap = _capability(p, extra)
    res, name = _resources(p, est, tail)
    value = max(cp, load, cap, res, 0.0)
    return LowerBounds(float(value), float(cp), float(load), float(cap), float(res), name)


def lower_bound(problem: Problem) -> float:
    """The best lower bound on the makespan of ``problem`` (seconds)."""
    return lower_bounds(problem).value
