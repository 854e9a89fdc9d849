"""Lower bounds on the makespan of a problem.

Every bound here is valid for any schedule :func:`~scheduler.validate`
accepts (waits and detours only make tasks longer), and each is cheap next to
a solve. :func:`lower_bound` is their maximum; :func:`lower_bounds` returns
the parts.

* **Critical path** with releases, arm availability and travel: a mode of a
  task on arm ``a`` starts no earlier than ``available[a]`` plus the least
  setup of ``a`` into the task (:func:`mode_heads`), and along every chain of
  predecessors each task takes at least its shortest mode.
* **Load** (LP relaxation): assign tasks fractionally to arms, each mode
  costing its duration plus the smallest setup that can precede it; the best
  fractional makespan ``C`` with ``available[a] + load[a] <= C`` bounds the
  real one. Arms of different speeds are handled exactly by the LP. Every
  exclusive zone, shared-zone movement and tool is a row of the same LP:
  each mode loads it with its merged windows (a tool: the whole mode), and
  all its uses lie between its earliest head and its smallest tail.
* **Capability subsets**: tasks that only arms of a set ``E`` can do need at
  least ``(sum of available times + sum of their shortest modes) / |E|``.
* **Unary resources** (exclusive zones, movement in shared zones, tools):
  for the tasks that use the resource in every mode, a job of their least
  occupation with a head (the earliest the resource can be reached, travel
  included) and a tail (the least time from leaving it to the end of the
  schedule). ``resources`` is the best over head thresholds ``h`` of
  ``h + sum of lengths + smallest tail``; ``one_machine`` the preemptive
  one-machine bound of the same jobs (:func:`jackson_preemptive`, the best
  such sum over every subset: Carlier 1982), which also sees a few jobs with
  long tails among many short ones (:func:`resource_bounds` lists them all).

Valid for every schedule :func:`~scheduler.validate` accepts: waits at
borders and detours only lengthen tasks and uses, every arm is available
before its first task and travels into each, two arms never hold one
resource at once and one arm never does two tasks at once.

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

__all__ = [
    "LowerBounds",
    "ResourceBound",
    "jackson_preemptive",
    "lower_bound",
    "lower_bounds",
    "min_incoming_setup",
    "mode_heads",
    "resource_bounds",
]


@dataclass(frozen=True, slots=True)
class LowerBounds:
    """The parts of the lower bound (seconds) and their maximum ``value``.

    ``resource_name`` and ``one_machine_name`` name the resource (``"zone z1"``,
    ``"move z3"``, ``"tool t0"``) that gives ``resources`` (head-body-tail) and
    ``one_machine`` (the preemptive one-machine bound).
    """

    value: float
    critical_path: float
    load: float
    capability: float
    resources: float
    resource_name: str = ""
    one_machine: float = 0.0
    one_machine_name: str = ""


def min_incoming_setup(p: Problem) -> FloatArray:
    """(M,): for each mode, the smallest setup that can precede it on its arm.

    The least over the arm's initial pose and every other task the arm can
    do (0 where none is finite): a bound on the travel into the mode in
    every valid schedule, whether setups obey the triangle inequality or not.
    """
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
    p: Problem,
    uses: list[dict[int, tuple[float, float, float]]],
    est_mode: FloatArray,
    tail: FloatArray,
) -> tuple[list[int], list[int], list[float], list[float]]:
    """Per resource, its row of the load LP: (row, mode, length) entries and
    the room ``-(head + tail)``: every mode's use of the resource (merged
    windows; a tool: the whole mode) lies in ``[head, C - tail]``, the
    smallest head and tail over the modes that use it (``uses``: :func:`_uses`
    of every mode)."""
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    room: list[float] = []
    per_res: dict[int, list[tuple[int, float, float, float]]] = {}
    for m, mode_uses in enumerate(uses):
        t = int(p.mode_task[m])
        for r, (length, first, after) in mode_uses.items():
            per_res.setdefault(r, []).append(
                (m, length, float(est_mode[m]) + first, after + float(tail[t]))
            )
    for i, res_uses in enumerate(per_res.values()):
        for m, length, _, _ in res_uses:
            rows.append(i)
            cols.append(m)
            vals.append(length)
        room.append(-(min(u[2] for u in res_uses) + min(u[3] for u in res_uses)))
    return rows, cols, vals, room


def _load_lp(
    p: Problem,
    uses: list[dict[int, tuple[float, float, float]]],
    extra: FloatArray,
    est_mode: FloatArray,
    tail: FloatArray,
) -> float:
    from scipy.optimize import linprog
    from scipy.sparse import coo_matrix

    M, T, A = p.n_modes, p.n_tasks, p.n_arms
    cost = p.mode_duration + extra
    # variables: x_0..x_{M-1}, C
    c = np.zeros(M + 1)
    c[M] = 1.0
    eq = coo_matrix((np.ones(M), (p.mode_task, np.arange(M))), shape=(T, M + 1))
    rr, rc, rv, room = _resource_rows(p, uses, est_mode, tail)
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


def _uses(p: Problem, m: int) -> dict[int, tuple[float, float, float]]:
    """Per resource mode ``m`` uses: (least occupation, offset of the first use, time
    from the end of the last use to the end of the mode). Exclusive zones and
    shared-zone movement: the merged windows (waits at borders inside a
    window only lengthen it); tools: the whole mode."""
    sh = p.shapes[m]
    parts: dict[int, list[tuple[float, float]]] = {}
    for r, s, e in (*sh.exclusive, *sh.moves):
        parts.setdefault(r, []).append((s, e))
    for r in sh.tools:
        parts.setdefault(r, []).append((0.0, sh.duration))
    return {
        r: (
            sum(e - s for s, e in ivs),
            min(s for s, _ in ivs),
            sh.duration - max(e for _, e in ivs),
        )
        for r, ivs in parts.items()
    }


def _resource_jobs(
    p: Problem,
    uses: list[dict[int, tuple[float, float, float]]],
    est_mode: FloatArray,
    tail: FloatArray,
) -> dict[int, list[tuple[float, float, float]]]:
    """Per resource, one job ``(length, head, tail)`` per task that uses it in every
    mode: the least occupation over its modes, the earliest the resource can be
    reached (the mode's earliest start plus the offset of its first use) and
    the least time from leaving it to the end of the schedule (the rest of
    the mode plus the task's tail)."""
    per_res: dict[int, list[tuple[float, float, float]]] = {}
    for t in range(p.n_tasks):
        modes = p.task_modes[t]
        usage: dict[int, list[tuple[float, float, float]]] = {}
        for m in modes:
            start = float(est_mode[m])
            for r, (length, first, after) in uses[m].items():
                usage.setdefault(r, []).append((length, start + first, after + float(tail[t])))
        for r, us in usage.items():
            if len(us) == len(modes):  # every mode needs the resource
                per_res.setdefault(r, []).append(
                    (min(u[0] for u in us), min(u[1] for u in us), min(u[2] for u in us))
                )
    return per_res


def _head_body_tail(jobs: list[tuple[float, float, float]]) -> float:
    """The best over head thresholds ``h`` of ``h`` + the lengths of the jobs with a
    head of at least ``h`` + their smallest tail."""
    jobs = sorted(jobs, key=lambda j: j[1])
    total, min_tail, bound = 0.0, math.inf, 0.0
    for i in range(len(jobs) - 1, -1, -1):
        total += jobs[i][0]
        min_tail = min(min_tail, jobs[i][2])
        bound = max(bound, jobs[i][1] + total + min_tail)
    return bound


def jackson_preemptive(jobs: list[tuple[float, float, float]]) -> float:
    """The preemptive one-machine bound of jobs ``(length, head, tail)``.

    Jackson's preemptive schedule (at every moment, of the released jobs the
    one with the largest tail runs, and a newly released job with a larger
    tail interrupts it) has the least ``max(end + tail)`` of every
    preemptive schedule, and that value equals
    ``max over subsets J of (min head in J + sum of lengths in J + min tail in J)``
    (Carlier 1982). A schedule that never interrupts is one of the preemptive
    ones, so the value bounds every one-machine schedule of the jobs.

    Parameters
    ----------
    jobs : list of (length, head, tail)

    Returns
    -------
    float
        0 without jobs.

    Examples
    --------
    >>> jackson_preemptive([(3.0, 0.0, 10.0), (1.0, 1.0, 0.0), (1.0, 1.0, 0.0)])
    13.0
    """
    import heapq

    order = sorted(range(len(jobs)), key=lambda j: jobs[j][1])
    heap: list[tuple[float, int]] = []
    left = [j[0] for j in jobs]
    now, i, best, n = 0.0, 0, 0.0, len(jobs)
    while i < n or heap:
        if not heap:
            now = max(now, jobs[order[i]][1])
        while i < n and jobs[order[i]][1] <= now:
            j = order[i]
            heapq.heappush(heap, (-jobs[j][2], j))
            i += 1
        _, j = heap[0]
        nxt = jobs[order[i]][1] if i < n else math.inf
        if now + left[j] <= nxt:  # it ends before the next release
            now += left[j]
            left[j] = 0.0
            heapq.heappop(heap)
            best = max(best, now + jobs[j][2])
        else:  # the next release may interrupt it
            left[j] -= nxt - now
            now = nxt
    return best


@dataclass(frozen=True, slots=True)
class ResourceBound:
    """The work every schedule puts on one resource and the bounds it gives.

    Attributes
    ----------
    resource : int
        The resource number (:meth:`scheduler.timing.Shapes.resource_name`).
    kind : str
        ``"zone"`` (exclusive), ``"move"`` (movement in a shared zone) or ``"tool"``.
    name : str
    tasks : int
        Tasks that use it in every mode.
    work : float
        The sum of their least occupations (seconds).
    simple : float
        The head-body-tail bound (the best head threshold).
    bound : float
        The preemptive one-machine bound (:func:`jackson_preemptive`) with
        heads and tails that count travel into each mode.
    """

    resource: int
    kind: str
    name: str
    tasks: int
    work: float
    simple: float
    bound: float


def resource_bounds(problem: Problem) -> tuple[ResourceBound, ...]:
    """The one-machine bound of every exclusive zone, shared-zone movement and tool.

    For the tasks that use a resource in every mode, each a job of its least
    occupation (merged window lengths; a tool: the whole mode), its head (the
    earliest a mode can start, :func:`mode_heads`, plus the offset of its
    first use) and its tail (the rest of the mode plus the task's tail). Valid
    for every schedule :func:`scheduler.validate` accepts: no two arms use the
    resource at once, one arm does one task at a time, a use lasts at least
    its windows (waits at borders inside it and detours only lengthen it) and
    lies between its head and the makespan less its tail.

    Parameters
    ----------
    problem : Problem

    Returns
    -------
    tuple of ResourceBound
        One per resource some task needs in every mode, in resource order.

    Examples
    --------
    Two tasks hold zone ``z`` for their first 2 s and run 5 s more, a third holds
    it for 1 s: whichever of the first two enters second ends at 9 at the
    earliest, which the head-body-tail bound (5) does not see.

    >>> from scheduler.problem import Model, Window
    >>> m = Model()
    >>> z = m.add_zone("z")
    >>> for arm, d, e in [("a", 7.0, 2.0), ("b", 7.0, 2.0), ("c", 1.0, 1.0)]:
    ...     _ = m.add_arm(arm); t = m.add_task(f"t{arm}")
    ...     _ = m.add_mode(t, arm, d, windows=[Window(z, 0.0, e)])
    >>> [(r.name, r.work, r.simple, r.bound) for r in resource_bounds(m.build())]
    [('z', 5.0, 5.0, 9.0)]
    """
    p = problem
    if p.n_tasks == 0:
        return ()
    est_mode, _, tail = mode_heads(p)
    return _resource_bounds(p, [_uses(p, m) for m in range(p.n_modes)], est_mode, tail)


def _resource_bounds(
    p: Problem,
    uses: list[dict[int, tuple[float, float, float]]],
    est_mode: FloatArray,
    tail: FloatArray,
) -> tuple[ResourceBound, ...]:
    out = []
    for r, jobs in sorted(_resource_jobs(p, uses, est_mode, tail).items()):
        kind, name = p.shapes.resource_name(r)
        out.append(
            ResourceBound(
                r,
                kind,
                name,
                len(jobs),
                float(sum(j[0] for j in jobs)),
                _head_body_tail(jobs),
                jackson_preemptive(jobs),
            )
        )
    return tuple(out)


def mode_heads(
    p: Problem, setup_in: FloatArray | None = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(earliest start per mode, earliest start per task, tail per task).

    A mode of task ``t`` on arm ``a`` starts no earlier than the task's
    release, the earliest end of each predecessor (its earliest start plus its
    shortest mode, over its modes) and ``available[a]`` plus the least setup
    of ``a`` into ``t`` (from its initial pose or any task ``a`` can do): in
    every valid schedule ``a`` is available before its first task and
    travels into each. A task's earliest start is the least over its modes;
    its tail is the shortest time from its end to the end of every chain of
    successors after it (each at its shortest mode).

    Parameters
    ----------
    p : Problem
    setup_in : (M,) float array or None
        The least setup into each mode, when already computed.

    Returns
    -------
    tuple of three float arrays
        Shapes (M,), (T,), (T,).
    """
    if setup_in is None:
        setup_in = min_incoming_setup(p)
    arrive = p.arm_available[p.mode_arm] + setup_in
    dur = p.mode_duration
    est_mode = np.zeros(p.n_modes)
    est = np.zeros(p.n_tasks)
    ect = np.zeros(p.n_tasks)
    release = p.task_release.tolist()
    for t in p.topological_order:
        base = release[t]
        for q in p.task_preds[t]:
            base = max(base, ect[q])
        ms = list(p.task_modes[t])
        est_mode[ms] = np.maximum(base, arrive[ms])
        est[t] = est_mode[ms].min()
        ect[t] = (est_mode[ms] + dur[ms]).min()
    _, mind, tail = heads_and_tails(p)
    del mind
    return est_mode, est, tail


def lower_bounds(problem: Problem) -> LowerBounds:
    """Every lower bound on the makespan (see the module docstring)."""
    p = problem
    if p.n_tasks == 0:
        return LowerBounds(0.0, 0.0, 0.0, 0.0, 0.0)
    extra = min_incoming_setup(p)
    est_mode, _, tail = mode_heads(p, extra)
    ect = np.full(p.n_tasks, np.inf)
    np.minimum.at(ect, p.mode_task, est_mode + p.mode_duration)
    cp = float(np.max(ect + tail))
    uses = [_uses(p, m) for m in range(p.n_modes)]
    load = _load_lp(p, uses, extra, est_mode, tail)
    cap = _capability(p, extra)
    res, name, om, om_name = 0.0, "", 0.0, ""
    for rb in _resource_bounds(p, uses, est_mode, tail):
        if rb.simple > res:
            res, name = rb.simple, f"{rb.kind} {rb.name}"
        if rb.bound > om:
            om, om_name = rb.bound, f"{rb.kind} {rb.name}"
    value = max(cp, load, cap, res, om, 0.0)
    return LowerBounds(
        float(value), float(cp), float(load), float(cap), float(res), name, float(om), om_name
    )


def lower_bound(problem: Problem) -> float:
    """The best lower bound on the makespan of ``problem`` (seconds)."""
    return lower_bounds(problem).value
