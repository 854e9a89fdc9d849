"""The exact reference: an OR-Tools CP-SAT model of the same problem.

Variables and constraints (times scaled to integers, see below):

* per task ``t``: start ``S_t``, end ``E_t``, a literal ``x_m`` per mode with
  ``sum_m x_m = 1``; per mode, a chain of delay points ``P_m,i >= P_m,i-1``
  (``P_m,0 = S_t``), one for each zone border ``i`` a constraint refers to:
  ``P_m,i - S_t`` is the sum of the waits at borders up to ``i`` (when waits
  are allowed; waits at borders nothing refers to are never needed), and
  ``E_t = P_m,last + d_m`` if ``x_m``;
* arms: the optional mode intervals ``[S_t, E_t)`` of an arm never overlap
  (``NoOverlap``; a mode without delay points is a fixed-size interval
  ``[S_t, S_t + d_m)``, which CP-SAT propagates better than a size
  variable), and with setup times a ``Circuit`` over the arm's modes whose
  arcs enforce ``S_t' >= E_t + setup(t, t')`` (and the setup from
  the initial pose after the depot);
* exclusive zones: ``NoOverlap`` over the occupancy intervals
  ``[P_m,i + s, P_m,k + e)`` of every window ``[s, e)`` in the zone, ``i`` the
  borders ``<= s`` and ``k`` those ``< e`` (and ``[0, departure)`` of an arm
  that starts inside it); shared zones: ``NoOverlap`` over the movement
  pieces between borders; tools: ``NoOverlap`` over ``[S_t, E_t)`` of the
  modes holding them (:mod:`scheduler.timing` defines these intervals);
  resources only one arm uses are left out (:func:`shared_resources`);
* releases ``S_t >= r_t``, precedence ``S_t >= E_p``, arm availability;
* a redundant ``Cumulative`` of capacity (number of arms) over the task
  intervals, and ``makespan >= E_t``; minimise the makespan.

Times are multiplied by the smallest power of ten (up to 10^6) that makes
every duration, offset, release, availability and setup an integer; then the
model is exact and CP-SAT's bound is a bound of the problem. Otherwise times
are rounded outwards (starts down, ends up) at a 1e-3 resolution: the
schedules stay valid but the bound falls back to :func:`lower_bound`.
The search is hinted with the earliest-finish-time schedule that also sets
the horizon (``hint=False`` to start cold). Where times are rounded, the hint
is first re-timed in the model's units with its modes and orders
(:func:`repair_hint`: rounded as it is, it is usually no solution), and a run
that finds nothing better returns that schedule; a hint that is a valid
schedule is returned itself when nothing found is shorter. The blocking oracle is not
modelled: when every detour it charges is finite, each mode is padded with
its largest (:func:`oracle_padding`; the schedule stays valid, the bound is
not kept); otherwise the model leaves it out, a relaxation, so CP-SAT's bound
(at an exact scale) is kept and a schedule no parked arm meets is taken as
it is; one that meets a parked arm has its modes and start order decoded
again chronologically with the oracle's detours.
On compiled cells see :mod:`scheduler.reference`.
"""

from __future__ import annotations

import bisect
import collections
import itertools
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from multiarm.types import FloatArray
from scheduler import _ctrl_c
from scheduler.problem import Problem
from scheduler.result import Result, SearchStats, SolveStatus
from scheduler.schedule import Schedule, ScheduleError, validate
from scheduler.start import begin

__all__ = [
    "add_arm_sequences",
    "add_relaxed_tasks",
    "arrival_heads",
    "build_model",
    "cpsat_bound",
    "essential_resources",
    "integer_scale",
    "resource_windows",
    "run_solver",
    "shared_resources",
    "solve_cpsat",
    "solve_or_interrupt",
]


def _integral(values: Any, scale: float) -> bool:
    v = np.asarray(values, dtype=float) * scale
    v = v[np.isfinite(v)]
    return bool(np.all(np.abs(v - np.round(v)) <= 1e-9 * np.maximum(1.0, np.abs(v))))


def _time_values(p: Problem) -> Any:
    """Every number of the problem that is a time (setups included), or None
    when the setups are too many to list."""
    data = [p.mode_duration, p.win_start, p.win_end, p.task_release, p.arm_available]
    setups = []
    if not p._setup.zero:
        for a in range(p.n_arms):
            tasks = np.flatnonzero(p.mode_of[a] >= 0)
            if len(tasks) * (len(tasks) + 1) > 2_000_000:
                return None
            for prev in (-1, *tasks.tolist()):
                setups.append(p.setup_row(a, prev)[tasks])
    return np.concatenate([np.ravel(d) for d in data] + setups)


def integer_scale(problem: Problem) -> tuple[float, bool]:
    """(scale, exact): the power of ten that makes the data integral, if any."""
    allv = _time_values(problem)
    if allv is None:
        return 1000.0, False
    for k in range(7):
        s = 10.0**k
        if _integral(allv, s) and (allv.size == 0 or np.max(np.abs(allv)) * s < 2**40):
            return s, True
    return 1000.0, False


def shared_resources(problem: Problem) -> frozenset[int]:
    """Resources (numbered as in :mod:`scheduler.timing`) that two arms can use.

    A zone, shared zone's movement or tool used only by the modes of one arm
    (and, for an exclusive zone, stood in at the start by no other arm) never
    constrains a schedule: an arm's tasks never overlap, and every window lies
    inside its task. Only the others need a constraint.

    Returns
    -------
    frozenset of int
    """
    p = problem
    arms_of: dict[int, set[int]] = {}
    for m, sh in enumerate(p.shapes.modes):
        a = int(p.mode_arm[m])
        for r, _, _ in (*sh.exclusive, *sh.moves):
            arms_of.setdefault(r, set()).add(a)
        for r in sh.tools:
            arms_of.setdefault(r, set()).add(a)
    for a, zs in enumerate(p.arm_start_zones):
        for z in zs:
            if p.zone_exclusive[z]:
                arms_of.setdefault(int(z), set()).add(a)
    return frozenset(r for r, arms in arms_of.items() if len(arms) > 1)


def resource_windows(
    problem: Problem, resources: frozenset[int]
) -> dict[int, dict[int, list[Any]]]:
    """Per resource of ``resources``: mode -> its merged ``(start, end)`` windows
    (offsets; a tool: the whole mode)."""
    use: dict[int, dict[int, list[Any]]] = {}
    for m, sh in enumerate(problem.shapes.modes):
        for r, s, e in (*sh.exclusive, *sh.moves):
            if r in resources:
                use.setdefault(r, {}).setdefault(m, []).append((s, e))
        for r in sh.tools:
            if r in resources:
                use.setdefault(r, {}).setdefault(m, []).append((0.0, sh.duration))
    return use


def essential_resources(problem: Problem) -> frozenset[int]:
    """The shared resources (:func:`shared_resources`) without the dominated ones.

    A resource ``r`` is *dominated* by another ``q`` when every mode that
    uses ``r`` also uses ``q``, each of its windows in ``r`` lying inside one
    of its windows in ``q`` (offsets), and ``q`` excludes at least as much as
    ``r`` while waiting (``q`` an exclusive zone or tool, or both movements
    of shared zones). Then, waits included, each use of ``r`` lies inside a
    use of ``q`` by the same task (a window ``[s, e)`` inside ``[s', e')``
    is shifted by no more waits at its start and no fewer at its end), so
    two tasks that meet in ``r`` meet in ``q``: leaving ``r`` out changes no
    constraint. On the compiled cells the space grid's blocks that one arm
    sweeps at once dominate each other: ``supersigma`` keeps 26 of 153
    shared resources, ``scara4`` 16 of 53. An exclusive zone some arm starts
    in is always kept (its start interval is not a window).

    Returns
    -------
    frozenset of int
    """
    p = problem
    shared = shared_resources(p)
    use = resource_windows(p, shared)
    Z = p.n_zones
    starts = {int(z) for zs in p.arm_start_zones for z in zs if p.zone_exclusive[z]}

    def kind(r: int) -> int:  # 0: presence (exclusive zone, tool), 1: movement
        return 1 if Z <= r < 2 * Z else 0

    def inside(ws: list[Any], outer: list[Any]) -> bool:
        return all(any(a2 <= a and b <= b2 for a2, b2 in outer) for a, b in ws)

    def dominated(r: int, q: int) -> bool:
        u, uq = use[r], use[q]
        if kind(q) > kind(r) or len(uq) < len(u):
            return False
        return all(m in uq and inside(ws, uq[m]) for m, ws in u.items())

    dropped: set[int] = set()
    order = sorted(use)
    for r in order:
        if r in starts:
            continue
        for q in order:
            if q == r or q in dropped or not dominated(r, q):
                continue
            if r < q and dominated(q, r):  # the same windows: keep the first
                continue
            dropped.add(r)
            break
    return frozenset(r for r in shared if r not in dropped)


def _rounders(scale: float, exact: bool, rounding: str) -> tuple[Any, Any]:
    """(lo, hi): the roundings of starts and of ends/lengths/gaps to model units."""

    def near(x: float) -> int:
        return round(x * scale)

    def down(x: float) -> int:
        return math.floor(x * scale + 1e-9)

    def up(x: float) -> int:
        return math.ceil(x * scale - 1e-9)

    if exact:
        return near, near
    if rounding == "out":
        return down, up
    return up, down


def build_model(
    problem: Problem,
    horizon: float,
    *,
    waits: bool = True,
    pad: Any = None,
    unit: float | None = None,
    rounding: str = "out",
    resources: frozenset[int] | None = None,
) -> tuple[Any, dict[str, Any]]:
    """The CP-SAT model and its variables (see the module docstring).

    Parameters
    ----------
    problem : Problem
    horizon : float
        Seconds: no schedule of interest ends later (a known schedule's
        makespan); the model allows some slack beyond it.
    waits : bool
        Whether the arms may wait at zone borders.
    pad : (M,) float or None
        Seconds added at the end of each mode (the tools held through it):
        the largest detour a blocking oracle can charge the mode, so that
        every solution stays valid whatever arms are parked.
    unit : float or None
        The model's time unit in seconds; None: the exact unit of
        :func:`integer_scale` (1 ms, rounded outwards, when there is none).
    rounding : {"out", "in"}
        With a unit that does not divide the data: ``"out"`` rounds every
        start down and every end, length and gap up, so that each solution
        is a valid schedule; ``"in"`` rounds the other way and drops what
        rounds to nothing, so that every valid schedule maps to a solution
        and the model's bound times the unit bounds the problem.
    resources : frozenset of int or None
        The resources to constrain (None: :func:`essential_resources`, which
        changes no constraint; a subset gives a relaxation).

    Returns
    -------
    (CpModel, dict)
        The variables: ``S``, ``E`` (per task), ``X`` (per mode), ``P`` (per
        mode, the delay points by border index), ``makespan``, and ``scale``
        (units per second) and ``exact`` (the unit divides every number).
    """
    from ortools.sat.python import cp_model

    p = problem
    if unit is None:
        scale, exact = integer_scale(p)
    else:
        scale = 1.0 / unit
        allv = _time_values(p)
        exact = allv is not None and _integral(allv, scale)
    lo, hi = _rounders(scale, exact, rounding)
    relax = rounding == "in" and not exact
    shared = essential_resources(p) if resources is None else resources
    shapes = p.shapes
    T = p.n_tasks
    max_refs = max((len(sh.borders) for sh in shapes.modes), default=0)
    H = (
        hi(horizon) + 1
        if exact
        else math.ceil(horizon * scale * 1.02) + 2 * (max_refs + 2) * T + 10
    )
    mdl = cp_model.CpModel()
    arrive = arrival_heads(p)
    S = [mdl.new_int_var(hi(float(p.task_release[t])), H, f"S{t}") for t in range(T)]
    E = [mdl.new_int_var(0, H, f"E{t}") for t in range(T)]
    X: dict[int, Any] = {}
    P: dict[int, dict[int, Any]] = {}
    mode_iv: dict[int, Any] = {}
    res_iv: dict[int, list[Any]] = {}
    # what each interval of res_iv stands for, in the same order: a window
    # (mode, delay index of its start, start offset, index of its end, end
    # offset), a tool held through a mode (mode,) or an arm's start zone (-1 - arm,)
    res_of: dict[int, list[tuple[Any, ...]]] = {}
    master = []
    for t in range(T):
        lits = []
        size_t = mdl.new_int_var(0, H, f"D{t}")
        master.append(mdl.new_interval_var(S[t], size_t, E[t], f"T{t}"))
        for m in p.task_modes[t]:
            x = mdl.new_bool_var(f"x{m}")
            X[m] = x
            lits.append(x)
            sh = shapes[m]
            borders = sh.borders

            def at_or_before(off: float, borders: tuple[float, ...] = borders) -> int:
                return bisect.bisect_right(borders, off) if waits else 0

            def before(off: float, borders: tuple[float, ...] = borders) -> int:
                return bisect.bisect_left(borders, off) if waits else 0

            # (resource, delay index of the start, start offset, index of the end, end offset)
            pieces: list[tuple[int, int, float, int, float]] = []
            for r, s, e in sh.exclusive:
                if r in shared:
                    pieces.append((r, at_or_before(s), s, before(e), e))
            for r, s, e in sh.moves:
                if r in shared:
                    cuts = [b for b in borders if s < b < e] if waits else []
                    for p0, p1 in itertools.pairwise([s, *cuts, e]):
                        i = at_or_before(p0)
                        pieces.append((r, i, p0, i, p1))
            refs = sorted({0} | {i for _, i, _, _, _ in pieces} | {k for *_, k, _ in pieces})
            # the delay before border i: P[i] - S is the sum of the waits at borders
            # 1..i (waits at borders no constraint refers to are never needed)
            pts: dict[int, Any] = {0: S[t]}
            prev = S[t]
            for i in refs[1:]:
                v = mdl.new_int_var(0, H, f"P{m}_{i}")
                mdl.add(v >= prev)
                pts[i] = v
                prev = v
            P[m] = pts
            d = float(sh.duration) + (float(pad[m]) if pad is not None else 0.0)
            a = int(p.mode_arm[m])
            # the initial pose's setup binds only the arm's first task (on the
            # circuit's start arc); every task keeps its arm's shortest way in
            mdl.add(S[t] >= hi(float(arrive[m]))).only_enforce_if(x)
            if len(refs) == 1:
                # no delay point: the mode lasts exactly its duration, and a
                # fixed-size interval propagates best (on FJSP, MK10 at 10 s:
                # 233.7 with the size as E - S, 223.3 fixed; seeds 0, 3, 4)
                dd = hi(d)
                mdl.add(E[t] == S[t] + dd).only_enforce_if(x)
                mdl.add(size_t == dd).only_enforce_if(x)
                mode_iv[m] = mdl.new_optional_fixed_size_interval_var(S[t], dd, x, f"I{m}")
            else:
                mdl.add(E[t] == prev + hi(d)).only_enforce_if(x)
                mdl.add(size_t == E[t] - S[t]).only_enforce_if(x)
                mode_iv[m] = mdl.new_optional_interval_var(S[t], size_t, E[t], x, f"I{m}")
            for r, i, s, k, e in pieces:
                fixed = hi(e) - lo(s)
                if relax and fixed <= 0:  # rounds to nothing: dropped (a relaxation)
                    continue
                if i == k:
                    iv = mdl.new_optional_fixed_size_interval_var(pts[i] + lo(s), fixed, x, "")
                else:
                    size = mdl.new_int_var(max(fixed, 0), H, "")
                    iv = mdl.new_optional_interval_var(pts[i] + lo(s), size, pts[k] + hi(e), x, "")
                res_iv.setdefault(r, []).append(iv)
                res_of.setdefault(r, []).append((m, i, s, k, e))
            for r in sh.tools:
                if r in shared:
                    res_iv.setdefault(r, []).append(mode_iv[m])
                    res_of.setdefault(r, []).append((m,))
        mdl.add_exactly_one(lits)
        for q in p.task_preds[t]:
            mdl.add(S[t] >= E[q])
    # arms
    arcs: dict[tuple[int, int], Any] = {}
    first = add_arm_sequences(mdl, p, mode_iv, X, S, E, hi, arcs)
    # arms standing in exclusive start zones until they leave
    for a in range(p.n_arms):
        zs = [z for z in p.arm_start_zones[a] if p.zone_exclusive[z] and z in shared]
        if not zs:
            continue
        modes = [int(m) for m in np.flatnonzero(p.mode_arm == a)]
        dep = mdl.new_int_var(0, H, f"dep{a}")
        if modes:
            cands = []
            for m in modes:
                t = int(p.mode_task[m])
                e_m = mdl.new_int_var(-H, H, "")
                lit = first.get(m, X[m])  # the arm's first task (any task without setups)
                mdl.add(e_m == S[t] - lo(p.setup_time(a, -1, t))).only_enforce_if(lit)
                mdl.add(e_m == H).only_enforce_if(~lit)
                cands.append(e_m)
            mdl.add_min_equality(dep, cands)
        else:
            mdl.add(dep == H)
        for z in zs:
            res_iv.setdefault(z, []).append(mdl.new_interval_var(0, dep, dep, f"start{a}_{z}"))
            res_of.setdefault(z, []).append((-1 - a,))
    for ivs in res_iv.values():
        if len(ivs) > 1:
            mdl.add_no_overlap(ivs)
    mdl.add_cumulative(master, [1] * T, p.n_arms)
    mk = mdl.new_int_var(0, H, "makespan")
    mdl.add_max_equality(mk, E)
    mdl.minimize(mk)
    return mdl, {
        "S": S,
        "E": E,
        "X": X,
        "P": P,
        "makespan": mk,
        "scale": scale,
        "exact": exact,
        "res_iv": res_iv,
        "res_of": res_of,
        "arcs": arcs,
        "pad": pad,
        "rounding": rounding,
        "horizon_units": H,
    }


def _schedule_of(
    problem: Problem, value: Callable[[Any], int], v: dict[str, Any], pad: Any
) -> Schedule:
    """The schedule of a solution of the model (starts and waits in seconds);
    ``value`` gives a model variable's value (``solver.value``, or a lookup in
    a vector of values by variable index)."""
    p, scale = problem, v["scale"]
    T = p.n_tasks
    modes = np.array([next(m for m in p.task_modes[t] if value(v["X"][m]) == 1) for t in range(T)])
    starts = np.array([value(v["S"][t]) / scale for t in range(T)])
    ws = []
    for t in range(T):
        m = int(modes[t])
        w = np.zeros(len(p.shapes[m].borders))
        pts = v["P"][m]
        prev = value(pts[0])
        for i in sorted(pts)[1:]:
            cur = value(pts[i])
            w[i - 1] = (cur - prev) / scale
            prev = cur
        ws.append(w)
    return Schedule.from_starts(p, modes, starts, ws, None if pad is None else pad[modes])


def _hinted_span(
    problem: Problem, hint: Schedule, what: tuple[Any, ...]
) -> tuple[float, float] | None:
    """Seconds: when the hint holds a resource interval of the model (``what``,
    as recorded in ``res_of`` by :func:`build_model`); None when the hint does
    not use it (a mode it did not choose)."""
    m = int(what[0])
    if m < 0:  # an arm's start zone: held from 0, before anyone else
        return (0.0, 0.0)
    t = int(problem.mode_task[m])
    if int(hint.mode[t]) != m:
        return None
    st = float(hint.start[t])
    if len(what) == 1:  # a tool: the whole mode
        return (st, float(hint.end[t]))
    _, i, s, k, e = what
    cw = np.concatenate([[0.0], np.cumsum(hint.waits[t])])
    return (st + float(cw[i]) + float(s), st + float(cw[k]) + float(e))


def _longest_paths(n: int, edges: list[tuple[int, int, int]], lower: list[int]) -> list[int] | None:
    """The least values ``x >= lower`` with ``x[w] >= x[u] + c`` for every edge
    ``(u, w, c)``; None when there are none (a cycle of positive length).

    A topological pass (Kahn's order) when the edges form no cycle, as the
    hint's orders almost always do; else a first-in first-out label-correcting
    pass, which gives up (None) after ``20 * (n + len(edges))`` improvements
    (in the order of creation, task by task, it needed over 50 times that on
    ``cell8``, where the topological pass takes one).

    Examples
    --------
    >>> _longest_paths(3, [(0, 1, 2), (1, 2, 3), (0, 2, 1)], [1, 0, 0])
    [1, 3, 6]
    >>> _longest_paths(2, [(0, 1, 1), (1, 0, 0)], [0, 0]) is None
    True
    """
    out: list[list[tuple[int, int]]] = [[] for _ in range(n)]
    indeg = [0] * n
    for u, w, c in edges:
        out[u].append((w, c))
        indeg[w] += 1
    dist = list(lower)
    ready = collections.deque(i for i in range(n) if indeg[i] == 0)
    done = 0
    while ready:
        u = ready.popleft()
        done += 1
        for w, c in out[u]:
            dist[w] = max(dist[w], dist[u] + c)
            indeg[w] -= 1
            if indeg[w] == 0:
                ready.append(w)
    if done == n:
        return dist
    dist = list(lower)  # a cycle: label-correcting, which detects a positive one
    queue = collections.deque(range(n))
    queued = [True] * n
    budget = 20 * (len(edges) + n)
    while queue:
        u = queue.popleft()
        queued[u] = False
        for w, c in out[u]:
            if dist[u] + c > dist[w]:
                dist[w] = dist[u] + c
                budget -= 1
                if budget < 0:
                    return None
                if not queued[w]:
                    queued[w] = True
                    queue.append(w)
    return dist


def _retimed(problem: Problem, v: dict[str, Any], hint: Schedule) -> dict[int, int] | None:
    """The earliest values, in model units, of the starts, delay points and ends
    of the hint's modes (by model variable index) that keep the hint's order on
    every arm and every resource of the model (:func:`repair_hint`); None when
    that order has no such times under the model's horizon.

    Every constraint between them is a difference ``x >= y + c`` once the modes
    and orders are fixed, so the earliest times are longest paths, found by a
    first-in first-out label-correcting pass from the releases and arrival heads
    (a positive cycle, which only ties between zero-length uses could make, ends
    it after a bounded number of passes).
    """
    p = problem
    lo, hi = _rounders(v["scale"], v["exact"], v["rounding"])
    pad = v["pad"]
    arrive = arrival_heads(p)
    T = p.n_tasks
    var: list[Any] = []
    lower: list[int] = []
    start_of: dict[tuple[int, int], int] = {}  # (task, delay index) -> node
    s_node, e_node = [0] * T, [0] * T
    edges: list[tuple[int, int, int]] = []  # (u, w, c): value[w] >= value[u] + c

    def node(x: Any, least: int = 0) -> int:
        var.append(x)
        lower.append(least)
        return len(var) - 1

    for t in range(T):
        m = int(hint.mode[t])
        pts = v["P"][m]
        s_node[t] = prev = node(v["S"][t], max(hi(float(p.task_release[t])), hi(float(arrive[m]))))
        start_of[(t, 0)] = prev
        for i in sorted(pts)[1:]:
            n = node(pts[i])
            edges.append((prev, n, 0))
            start_of[(t, i)] = prev = n
        d = float(p.shapes[m].duration) + (float(pad[m]) if pad is not None else 0.0)
        e_node[t] = node(v["E"][t])
        edges.append((prev, e_node[t], hi(d)))
        edges += [(e_node[q], s_node[t], 0) for q in p.task_preds[t]]
    arms = hint.arms(p)
    first: dict[int, int] = {}
    for a in range(p.n_arms):
        ts = sorted(np.flatnonzero(arms == a).tolist(), key=lambda t: (hint.start[t], t))
        if not ts:
            continue
        first[a] = ts[0]
        if not p._setup.zero:
            head = float(p.arm_available[a]) + p.setup_time(a, -1, ts[0])
            lower[s_node[ts[0]]] = max(lower[s_node[ts[0]]], hi(head))
        for t, u in itertools.pairwise(ts):
            gap = 0 if p._setup.zero else hi(p.setup_time(a, t, u))
            edges.append((e_node[t], s_node[u], gap))

    def ends(what: tuple[Any, ...]) -> tuple[tuple[int, int], tuple[int, int]] | None:
        """((node, offset) of the start, (node, offset) of the end) of a use;
        None for an arm's start zone (it starts at 0)."""
        m = int(what[0])
        if m < 0:
            return None
        t = int(p.mode_task[m])
        if len(what) == 1:
            return (s_node[t], 0), (e_node[t], 0)
        _, i, s_off, k, e_off = what
        return (start_of[(t, i)], lo(s_off)), (start_of[(t, k)], hi(e_off))

    for whats in v["res_of"].values():
        held = sorted(
            (span, what) for what in whats if (span := _hinted_span(p, hint, what)) is not None
        )
        for (_, wa), (_, wb) in itertools.pairwise(held):
            use_b = ends(wb)
            if use_b is None:
                return None  # a start zone after another use: not the hint's order
            use_a = ends(wa)
            if use_a is None:  # held from 0 until its arm's first task leaves for it
                arm = -1 - int(wa[0])
                if arm not in first:
                    return None
                f = first[arm]
                a_end = (s_node[f], -lo(p.setup_time(arm, -1, f)))
            else:
                a_end = use_a[1]
            b_start = use_b[0]
            edges.append((a_end[0], b_start[0], a_end[1] - b_start[1]))
    dist = _longest_paths(len(var), edges, lower)
    if dist is None:
        return None
    if max(dist, default=0) > v["horizon_units"]:
        return None
    return {int(x.index): int(d) for x, d in zip(var, dist, strict=True)}


def repair_hint(
    mdl: Any, problem: Problem, v: dict[str, Any], hint: Schedule, time_limit: float
) -> list[int] | None:
    """A solution of the model ``mdl`` (built by :func:`build_model`) with the
    hint's modes and its order on every arm and resource, as a value per model
    variable; None when there is none, or none is found within ``time_limit``
    seconds.

    Rounded outwards to a unit that does not divide the data, a schedule is
    usually no solution of the model: each window grows by up to a unit, so
    two windows that touch in the schedule overlap by a unit or two (on the
    built-in cells CP-SAT then starts from nothing and, with 2 workers, finds
    no schedule in 10 s). Here the hint is re-timed in the model's units
    (:func:`_retimed`: the earliest starts, delay points and ends with its
    modes and orders), and a copy of the model with those values, the modes
    and the circuits' arcs along each arm's order fixed is solved for the
    rest of the variables (intervals' sizes, start-zone departures, the
    makespan): propagation only.
    """
    from ortools.sat.python import cp_model

    p = problem
    times = _retimed(p, v, hint)
    if times is None:
        return None
    rep = mdl.clone()
    rep.clear_hints()
    for t in range(p.n_tasks):
        for m in p.task_modes[t]:
            rep.add(rep.get_bool_var_from_proto_index(v["X"][m].index) == int(m == hint.mode[t]))
    for i, value in times.items():
        rep.add(rep.get_int_var_from_proto_index(i) == value)
    arms = hint.arms(p)
    for a in range(p.n_arms):
        ts = sorted(np.flatnonzero(arms == a).tolist(), key=lambda t: (hint.start[t], t))
        # the circuit's arcs along that order (with setups; else there are none)
        ms = [-1 - a, *(int(hint.mode[t]) for t in ts), -1 - a]
        for key in itertools.pairwise(ms) if len(ms) > 2 else [(-1 - a, -1 - a)]:
            lit = v["arcs"].get(key)
            if lit is not None:
                rep.add(rep.get_bool_var_from_proto_index(lit.index) == 1)
    solver = cp_model.CpSolver()
    solver.parameters.max_time_in_seconds = max(0.01, time_limit)
    solver.parameters.num_workers = 1
    code = solver.solve(rep)
    if code not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        return None
    return list(solver.response_proto.solution)


def _add_hint(mdl: Any, problem: Problem, v: dict[str, Any], hint: Schedule) -> None:
    """Hint the model with a schedule (rounded to the model's unit)."""
    p, scale = problem, v["scale"]
    for t in range(p.n_tasks):
        mh = int(hint.mode[t])
        st = float(hint.start[t])
        mdl.add_hint(v["S"][t], round(st * scale))
        for m in p.task_modes[t]:
            mdl.add_hint(v["X"][m], int(m == mh))
        cw = np.concatenate([[0.0], np.cumsum(hint.waits[t])]) if len(hint.waits[t]) else [0.0]
        for i, var in v["P"][mh].items():
            if i:
                mdl.add_hint(var, round((st + float(cw[i])) * scale))


def oracle_padding(problem: Problem, max_queries: int = 200_000) -> Any:
    """(M,) float: per mode, the sum over the other arms of the largest finite
    detour the blocking oracle charges at any of their poses; None when there
    is no oracle, an answer is infinite, or asking would take more than
    ``max_queries`` calls."""
    p = problem
    oracle = p.blocking
    if oracle is None:
        return None
    poses = [[-1, *np.flatnonzero(p.mode_of[b] >= 0).tolist()] for b in range(p.n_arms)]
    if p.n_modes * sum(len(x) for x in poses) > max_queries:
        return None
    pad = np.zeros(p.n_modes)
    for m in range(p.n_modes):
        a = int(p.mode_arm[m])
        for b in range(p.n_arms):
            if b == a:
                continue
            worst = 0.0
            for pose in poses[b]:
                c = float(oracle.cost(m, b, pose))
                if not (c >= 0.0) or math.isinf(c):
                    return None
                worst = max(worst, c)
            pad[m] += worst
    return pad


def run_solver(solver: Any, model: Any, callback: Any = None) -> tuple[Any, bool]:
    """``solver.solve(model)`` that leaves Ctrl-C to Python: ``(status, interrupted)``.

    CP-SAT catches SIGINT itself by default (``catch_sigint_signal``) and
    ends its search as if the time limit had come: the KeyboardInterrupt
    never reaches Python, and a sweep or a tree search racing CP-SAT goes
    on after Ctrl-C. Here CP-SAT leaves the signal to Python's handler. On
    the main thread the search runs in a helper thread while this one waits
    (signals are handled on the main thread only): at Ctrl-C it stops the
    search (``stop_search``), waits for it to end and returns
    ``interrupted=True`` with the status CP-SAT reached. On another thread
    (the tree search's racing CP-SAT) the main thread gets the
    KeyboardInterrupt and stops this search itself; ``interrupted`` is False.
    A Ctrl-C noted by the solve's handler (:mod:`scheduler._ctrl_c`) stops the
    search too when its KeyboardInterrupt was lost on the way.

    Parameters
    ----------
    solver : ortools.sat.python.cp_model.CpSolver
    model : ortools.sat.python.cp_model.CpModel
    callback : CpSolverSolutionCallback, optional

    Returns
    -------
    (CpSolverStatus, bool)
        CP-SAT's status, and whether Ctrl-C stopped the search.
    """
    import threading

    solver.parameters.catch_sigint_signal = False

    def solve() -> Any:
        return solver.solve(model, callback) if callback is not None else solver.solve(model)

    if threading.current_thread() is not threading.main_thread():
        return solve(), False
    with _ctrl_c.guard() as ctrl_c:
        return _run_beside(solver, solve, ctrl_c)


def _run_beside(solver: Any, solve: Callable[[], Any], ctrl_c: _ctrl_c.CtrlC) -> tuple[Any, bool]:
    """:func:`run_solver` on the main thread: the search in a helper thread."""
    import threading

    box: dict[str, Any] = {}
    done = threading.Event()

    def run() -> None:
        try:
            box["code"] = solve()
        except BaseException as exc:  # handed to the caller below
            box["error"] = exc
        finally:
            done.set()

    worker = threading.Thread(target=run, name="cpsat-solve", daemon=True)
    interrupted = False
    try:
        # in one piece: a KeyboardInterrupt inside Thread.start may come after
        # the thread exists but before it has its ident (scheduler._ctrl_c)
        with _ctrl_c.deferred():
            worker.start()
    except KeyboardInterrupt:
        if worker.ident is None:  # it never started: nothing to stop
            raise
        interrupted = True
    # wait on an Event, not on Thread.join(timeout): a KeyboardInterrupt inside
    # join can mark a thread still running as stopped (Python 3.11, bpo-45274),
    # and the result would be read before the search ended. After Ctrl-C, ask
    # again until it ends (a stop asked before the search began is not kept).
    # A first Ctrl-C is only noted here (raised inside Condition.wait while it
    # takes its lock back, a KeyboardInterrupt breaks the lock: scheduler._ctrl_c)
    with _ctrl_c.deferred(reraise=False):
        while not done.is_set():
            try:
                interrupted = interrupted or ctrl_c.hit  # noted even if its exception was lost
                if interrupted:
                    solver.stop_search()
                done.wait(0.05)
            except KeyboardInterrupt:
                interrupted = True
    # a Ctrl-C noted after the last look above (the search had just ended) is
    # only pending in the block: it still counts
    interrupted = interrupted or ctrl_c.hit
    if "error" in box:
        raise box["error"]
    return box["code"], interrupted


def solve_or_interrupt(solver: Any, model: Any) -> Any:
    """:func:`run_solver` for a search with nothing to keep: KeyboardInterrupt
    after Ctrl-C (the search stopped), else CP-SAT's status."""
    code, interrupted = run_solver(solver, model)
    if interrupted:
        raise KeyboardInterrupt
    return code


def solve_cpsat(
    problem: Problem,
    time_limit: float | None,
    seed: int,
    *,
    waits: bool = True,
    workers: int = 2,
    hint: Any = True,
    log: bool = False,
    max_deterministic_time: float | None = None,
    on_solver: Any = None,
    callback: bool = True,
    unit: float | None = None,
    on_bound: Callable[[float], None] | None = None,
) -> Result:
    """Solve with CP-SAT (see the module docstring).

    ``hint``: a Schedule to start from (e.g. the previous plan when
    re-solving, or another solver's plan); ``True`` (default) hints the
    earliest-finish-time schedule that also sets the horizon — without it
    CP-SAT often finds no first solution on problems with setup circuits;
    ``False`` hints nothing. A hint that is a valid schedule of the problem
    is the result (``stats.extra["from_hint"]``) when nothing CP-SAT finds
    is shorter: rounded outwards, CP-SAT's schedules can be longer than the
    plan it started from. ``unit``: the model's time unit in seconds
    (None: exact, see :func:`build_model`); a unit that does not divide the
    data rounds outwards, so the schedules stay valid but the model's bound
    is not kept. ``on_bound``: called (in CP-SAT's thread) with every
    improved lower bound CP-SAT proves, in seconds, while it searches; only
    when that bound is one of the problem (an exact unit, no oracle padding,
    a valid schedule under the horizon), else never."""
    from ortools.sat.python import cp_model

    st = begin(problem, "cpsat", seed, waits=waits)
    trivial = st.trivial()
    if trivial is not None:
        return trivial
    p, t0, stats, ev, lb, first = problem, st.t0, st.stats, st.ev, st.lb, st.first
    horizon = (
        first.makespan
        if first is not None
        else float(
            np.max(p.task_release)
            + np.sum([max(p.mode_duration[m] for m in ms) for ms in p.task_modes]) * 2
            + 1e6
        )
    )
    if isinstance(hint, Schedule):
        horizon = max(horizon, hint.makespan) if first is not None else hint.makespan
    anchored = first is not None or isinstance(hint, Schedule)
    pad = oracle_padding(p)
    if pad is not None:  # every task padded with its largest detour: a serial bound
        horizon = float(
            np.max(p.task_release)
            + np.sum([max(p.mode_duration[m] + pad[m] for m in ms) for ms in p.task_modes])
            + float(np.max(p.arm_available))
        ) * 2 + (first.makespan if first is not None else 1e6)
    mdl, v = build_model(p, horizon, waits=waits, pad=pad, unit=unit)
    scale = v["scale"]
    # without padding, the model ignores the blocking oracle: a relaxation, so
    # its bound (at an exact unit) still bounds the problem
    exact = v["exact"] and pad is None
    if hint is True:
        # with an oracle, the greedy schedule's detours only lengthen tasks: it
        # is still a solution of the relaxed model
        hint = ev.schedule(first) if first is not None else None
    repaired: list[int] | None = None
    if isinstance(hint, Schedule) and not v["exact"]:
        # rounded outwards, the hint is usually no solution of the model: re-timed
        # in the model's units with its modes and orders, it is (repair_hint)
        # the fill is propagation only (0.7 s on cell8 with the re-timing): a work-limited
        # run (no wall-clock limit) gets a generous cap, so that whether the repair
        # succeeds does not depend on the machine's speed (repeatable runs)
        left = 60.0 if time_limit is None else max(0.01, time_limit - (time.perf_counter() - t0))
        repaired = repair_hint(mdl, p, v, hint, left)
        stats.extra["hint_repaired"] = repaired is not None
    if repaired is not None:
        for i, value in enumerate(repaired):
            mdl.add_hint(mdl.get_int_var_from_proto_index(i), value)
    elif hint is not None and hint is not False:
        _add_hint(mdl, p, v, hint)
    stats.phases["model"] = time.perf_counter() - t0
    solver = cp_model.CpSolver()
    if time_limit is not None:
        solver.parameters.max_time_in_seconds = max(0.01, time_limit - (time.perf_counter() - t0))
    solver.parameters.num_workers = workers
    solver.parameters.random_seed = seed
    solver.parameters.log_search_progress = log
    if max_deterministic_time is not None:
        solver.parameters.max_deterministic_time = max_deterministic_time

    class _Progress(cp_model.CpSolverSolutionCallback):
        def on_solution_callback(self) -> None:
            stats.record(time.perf_counter() - t0, self.objective_value / scale)

    if on_bound is not None and exact and anchored:
        # the objective is an integer: a bound a hair below one (float noise) is that integer
        solver.best_bound_callback = lambda b: on_bound(math.floor(b + 1e-6) / scale)
    if on_solver is not None:  # e.g. to keep it for stop_search() from another thread
        on_solver(solver)
    # the per-solution callback takes the GIL: a run racing Python code in
    # another thread goes without it (measured 0.55 s vs 0.87 s to optimal)
    code, interrupted = run_solver(solver, mdl, _Progress() if callback else None)
    runtime = time.perf_counter() - t0
    if interrupted:
        stats.interrupted = True  # Ctrl-C: the best schedule found so far, if any
    stats.nodes = int(solver.num_branches)
    stats.extra["conflicts"] = int(solver.num_conflicts)
    stats.extra["scale"] = scale
    stats.extra["deterministic_time"] = float(solver.deterministic_time)
    # CP-SAT's bound holds even when the run stopped without a solution, as
    # long as some valid schedule fits under the horizon, or the model has a
    # solution (the optimum is then one of the model's solutions)
    anchored = anchored or code in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    bound = max(lb, cpsat_bound(solver, code) / scale if exact and anchored else lb)
    if code == cp_model.INFEASIBLE:
        return Result(
            SolveStatus.INFEASIBLE if exact else SolveStatus.UNKNOWN,
            None,
            math.inf,
            lb,
            runtime,
            "cpsat",
            seed,
            stats,
        )
    # the hint itself, where it is a valid schedule: the result is never longer
    # (rounded outwards, CP-SAT's best, or the repaired hint, can be longer than
    # the plan it started from: scara4 hinted with a 126.54 s plan at 1 ms
    # returned 126.69 s)
    hinted = _valid_makespan(p, hint)
    # no solution found, but the repaired hint is one of the model (CP-SAT checks a
    # complete hint; on cell8 its presolve alone outlasts 10 s): that schedule
    from_hint = code not in (cp_model.OPTIMAL, cp_model.FEASIBLE) and repaired is not None
    stats.extra["from_hint"] = from_hint
    if code not in (cp_model.OPTIMAL, cp_model.FEASIBLE) and not from_hint:
        if hinted < math.inf:
            return _hint_result(hint, hinted, bound, runtime, seed, stats)
        return Result(SolveStatus.UNKNOWN, None, math.inf, bound, runtime, "cpsat", seed, stats)
    T = p.n_tasks
    sched: Schedule | None = None
    if from_hint:
        assert repaired is not None
        values = repaired
        cand = _schedule_of(p, lambda x: int(values[x.index]), v, pad)
    else:
        cand = _schedule_of(p, solver.value, v, pad)
    try:
        # with an oracle and no padding, valid only if no parked arm is in the way
        validate(p, cand)
        sched = cand
    except ScheduleError as exc:  # a parked arm in the way, or a non-metric setup corner
        stats.extra["redecoded"] = str(exc)
    if sched is None:
        # decode the order and modes again (with the detours the oracle charges)
        order = np.lexsort((np.arange(T), cand.start)).astype(np.int64)
        sol = ev.evaluate(order, cand.mode.astype(np.int64))
        if sol is not None:
            sched = ev.schedule(sol)
        if sched is None:
            if hinted < math.inf:
                stats.extra["from_hint"] = True
                return _hint_result(hint, hinted, bound, runtime, seed, stats)
            return Result(SolveStatus.UNKNOWN, None, math.inf, bound, runtime, "cpsat", seed, stats)
    mk = validate(p, sched)
    if hinted < mk - 1e-9:
        stats.extra["from_hint"] = True
        return _hint_result(hint, hinted, bound, runtime, seed, stats)
    if from_hint:  # the only solution: found when the model was built
        stats.record(stats.phases["model"], mk)
    optimal = (
        code == cp_model.OPTIMAL
        and exact
        and abs(mk - solver.objective_value / scale) <= 1e-6 * max(1, mk)
    )
    status = SolveStatus.OPTIMAL if optimal or mk <= bound + 1e-9 else SolveStatus.FEASIBLE
    if optimal:
        bound = mk
    return Result(status, sched, mk, min(bound, mk), runtime, "cpsat", seed, stats)


def _valid_makespan(problem: Problem, hint: Any) -> float:
    """The makespan of ``hint`` where it is a valid schedule of ``problem``, else inf."""
    if not isinstance(hint, Schedule):
        return math.inf
    try:
        return validate(problem, hint)
    except ScheduleError:
        return math.inf


def _hint_result(
    hint: Schedule, makespan: float, bound: float, runtime: float, seed: int, stats: SearchStats
) -> Result:
    """The hint as the result: no solution CP-SAT found is shorter. The hint
    was the incumbent from the start, so it is the one improvement kept (the
    listener heard CP-SAT's longer ones as they came)."""
    stats.improvements[:] = [(0.0, makespan)]
    stats.first_time = stats.best_time = 0.0
    stats.first_objective = makespan
    status = SolveStatus.OPTIMAL if makespan <= bound + 1e-9 else SolveStatus.FEASIBLE
    return Result(status, hint, makespan, min(bound, makespan), runtime, "cpsat", seed, stats)


def cpsat_bound(solver: Any, code: Any) -> int:
    """CP-SAT's proven lower bound of a minimised integer objective, in model units.

    Valid whether or not a solution was found: a run stopped by its limit
    (``UNKNOWN``: no solution yet, or ``FEASIBLE``) still proved that no
    solution is below ``best_objective_bound``. Rounded down (an integer
    objective is at least the ceiling, the floor is the safe side of any
    floating-point noise); 0 when the model is infeasible, invalid, or the
    bound is not finite.

    Parameters
    ----------
    solver : ortools.sat.python.cp_model.CpSolver
        After ``solve``.
    code : CpSolverStatus
        The status ``solve`` returned.

    Returns
    -------
    int
        At most the optimum of the model (``>= 0``).

    Examples
    --------
    >>> from ortools.sat.python import cp_model
    >>> m = cp_model.CpModel()
    >>> x = m.new_int_var(3, 10, "x")
    >>> m.minimize(x)
    >>> s = cp_model.CpSolver()
    >>> cpsat_bound(s, s.solve(m))
    3
    """
    from ortools.sat.python import cp_model

    if code not in (cp_model.OPTIMAL, cp_model.FEASIBLE, cp_model.UNKNOWN):
        return 0
    b = float(solver.best_objective_bound)
    if not math.isfinite(b) or b <= 0:
        return 0
    return math.floor(b + 1e-9)


def add_arm_sequences(
    mdl: Any,
    p: Problem,
    intervals: dict[int, Any],
    X: dict[int, Any] | Any,
    S: Any,
    E: Any,
    to_units: Callable[[float], int],
    arcs_out: dict[tuple[int, int], Any] | None = None,
) -> dict[int, Any]:
    """Each arm does one mode at a time, with its setups (travel) between them.

    A no-overlap of the arm's mode ``intervals``, and, when the problem has
    setups, a circuit over the arm's modes whose arcs enforce
    ``S[t2] >= E[t] + setup(a, t, t2)`` and, on the start arc into the arm's
    first mode, ``S[t] >= available[a] + setup(a, -1, t)`` (``to_units``
    rounds into model units: outward for a bound-safe model, inward for a
    relaxation). The initial pose's setup binds the first mode only: setups
    need not obey the triangle inequality (a task may move the arm closer to
    the next one), so it is no bound on a later task's start
    (:func:`arrival_heads` is). Shared by the CP-SAT model and the
    relaxations.

    ``arcs_out``, when given, receives the circuits' arc literals: ``(m, m2)``
    "mode ``m2`` follows ``m`` on their arm", ``(-1 - a, m)`` "``m`` is arm
    ``a``'s first", ``(m, -1 - a)`` "its last", ``(-1 - a, -1 - a)`` "arm ``a``
    does nothing".

    Returns
    -------
    dict
        Mode -> the literal "this mode is its arm's first" (empty without
        setups: then every chosen mode's start is bounded by
        ``available[a]`` alone).
    """
    first: dict[int, Any] = {}
    arcs_out = {} if arcs_out is None else arcs_out
    for a in range(p.n_arms):
        modes = [int(m) for m in np.flatnonzero(p.mode_arm == a)]
        if not modes:
            continue
        mdl.add_no_overlap([intervals[m] for m in modes])  # redundant with setups
        if p._setup.zero:
            continue
        arcs = []
        avail = float(p.arm_available[a])
        for i, m in enumerate(modes, start=1):
            t = int(p.mode_task[m])
            go = mdl.new_bool_var("")
            first[m] = go
            arcs_out[(-1 - a, m)] = go
            arcs.append((0, i, go))
            head = avail + p.setup_time(a, -1, t)
            if math.isfinite(head):
                mdl.add(S[t] >= to_units(head)).only_enforce_if(go)
            else:
                mdl.add(go == 0)
            last = arcs_out[(m, -1 - a)] = mdl.new_bool_var("")
            arcs.append((i, 0, last))
            arcs.append((i, i, ~X[m]))
            for j, m2 in enumerate(modes, start=1):
                if m2 == m:
                    continue
                t2 = int(p.mode_task[m2])
                lit = arcs_out[(m, m2)] = mdl.new_bool_var("")
                arcs.append((i, j, lit))
                mdl.add(S[t2] >= E[t] + to_units(p.setup_time(a, t, t2))).only_enforce_if(lit)
        idle = arcs_out[(-1 - a, -1 - a)] = mdl.new_bool_var("")
        arcs.append((0, 0, idle))
        mdl.add_circuit(arcs)
    return first


def add_relaxed_tasks(
    mdl: Any, p: Problem, to_units: Callable[[float], int], H: int
) -> tuple[list[Any], list[Any], dict[int, Any], dict[int, Any], list[Any]]:
    """The tasks of a relaxation: each may last longer than its modes.

    One interval ``[S_t, E_t)`` per task, at least its chosen mode's
    duration long (an arm may wait anywhere inside it), starting no earlier
    than its release and :func:`arrival_heads`, after its predecessors'
    ends; one optional interval per mode. ``to_units`` rounds down (every
    valid schedule's image is a solution). Shared by the overlap and the
    busy-resources relaxations.

    Returns
    -------
    tuple
        ``S``, ``E`` (per task), ``X`` (mode -> literal), the mode intervals
        (mode -> interval) and the task intervals.
    """
    T = p.n_tasks
    dur = [to_units(float(d)) for d in p.mode_duration]
    arrive = arrival_heads(p)
    S = [mdl.new_int_var(to_units(float(p.task_release[t])), H, f"S{t}") for t in range(T)]
    E = [mdl.new_int_var(0, H, f"E{t}") for t in range(T)]
    X: dict[int, Any] = {}
    iv: dict[int, Any] = {}
    master = []
    for t in range(T):
        size = mdl.new_int_var(0, H, f"D{t}")
        master.append(mdl.new_interval_var(S[t], size, E[t], f"T{t}"))
        lits = []
        for m in p.task_modes[t]:
            x = mdl.new_bool_var(f"x{m}")
            X[m] = x
            lits.append(x)
            mdl.add(size >= dur[m]).only_enforce_if(x)
            mdl.add(S[t] >= to_units(float(arrive[m]))).only_enforce_if(x)
            iv[m] = mdl.new_optional_interval_var(S[t], size, E[t], x, f"I{m}")
        mdl.add_exactly_one(lits)
        for q in p.task_preds[t]:
            mdl.add(S[t] >= E[q])
    return S, E, X, iv, master


def arrival_heads(p: Problem) -> FloatArray:
    """(M,): the earliest a mode can start on its arm's account, seconds.

    ``available[a]`` plus the shortest way of ``a`` into the task: from its
    initial pose straight or through other tasks of ``a`` (each at its
    shortest mode on ``a``, with the setups between). Valid for every mode
    of every valid schedule, setups obeying the triangle inequality or not;
    where they obey it, it is ``available[a] + setup(a, -1, t)``.
    """
    out: FloatArray = p.arm_available[p.mode_arm].astype(float)
    if p._setup.zero:
        return out
    for a in range(p.n_arms):
        modes = np.flatnonzero(p.mode_arm == a)
        if len(modes) == 0:
            continue
        tasks = np.unique(p.mode_task[modes])
        dmin = np.full(p.n_tasks, np.inf)
        np.minimum.at(dmin, p.mode_task[modes], p.mode_duration[modes])
        dist = np.full(p.n_tasks, np.inf)
        dist[tasks] = np.asarray(p.setup_row(a, -1), dtype=float)[tasks]
        left = np.zeros(p.n_tasks, dtype=bool)
        left[tasks] = True
        while left.any():  # Dijkstra, dense: the tasks of one arm
            u = int(np.flatnonzero(left)[np.argmin(dist[left])])
            left[u] = False
            if not np.isfinite(dist[u]):
                break
            via = dist[u] + dmin[u] + np.asarray(p.setup_row(a, u), dtype=float)
            dist[left] = np.minimum(dist[left], via[left])
        head = dist[p.mode_task[modes]]
        out[modes] += np.where(np.isfinite(head), head, 0.0)
    return out
