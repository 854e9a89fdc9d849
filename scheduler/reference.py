"""The exact reference on compiled cells: CP-SAT on a compact no-wait model, and a bound.

The general model of :mod:`scheduler.cpsat` gives every zone window its own
interval, so that an arm may wait at any zone border. On a compiled cell
(52-152 zones, most of them space-grid blocks, about 50 borders per mode)
that is thousands of optional intervals of variable size, and CP-SAT finds
no schedule of even ``supersigma`` in a minute. This module answers two
narrower questions exactly instead:

* **The no-wait optimum** (:func:`nowait_model`): the best schedule in which
  no arm waits at a zone border (it may still wait before a task). Then every
  window lies at a fixed offset from its task's start, and two modes ``m1``
  (task ``t1``) and ``m2`` (task ``t2``) of different arms that share a zone,
  a shared zone's movement or a tool conflict exactly when ``S[t2] - S[t1]``
  lies in a union of open intervals ``(s1 - e2, e1 - s2)``, one per pair of
  their windows in one resource. One constraint per pair of modes, enforced by
  both modes' literals, keeps the difference in the complement (CP-SAT's
  linear-in-domain constraint). Arms are a ``NoOverlap`` and, with setups, a
  ``Circuit`` whose arcs carry the travel time; a redundant ``Cumulative`` of
  capacity (number of arms) helps the bound. Resources only one arm uses are
  left out, and so are resources dominated by another
  (:func:`scheduler.cpsat.essential_resources`).
  Schedules without waits are schedules of the problem, so this optimum is an
  *upper reference* of the true optimum (waits allowed); it is the true
  optimum of the same problem solved with ``waits=False``.
* **A bound of the true problem** (:func:`relaxation_bound`): CP-SAT's bound on
  the problem without zones (arms, travel, releases, precedence, tools all
  kept): every valid schedule, waits and detours included, is a solution of
  it. The reference's bound is the larger of this and
  :func:`scheduler.bounds.lower_bound`.

Times: the model's unit is the exact unit of the data
(:func:`scheduler.cpsat.integer_scale`: 1 ms on compiled cells) unless a
coarser ``unit`` is asked for, which is rounded *outwards* (window and task
ends, durations, travel and releases up, window starts down), so every
solution is still a valid schedule; only the exact unit gives a proof.

Blocking oracle (parked arms, S2.6): neither model asks it. The no-wait
model's schedule is checked by :func:`scheduler.validate` with the oracle:
when no parked arm is in its way (the detours charged are all zero), it is a
schedule of the problem and the proof stands; otherwise its modes and start
order are decoded again with the detours charged, and the result is only
feasible. The zone-free bound stays a bound (detours only lengthen tasks).

Examples
--------
>>> from scheduler.generate import random_problem
>>> p = random_problem(2, 6, 2, 1, seed=1)
>>> r = solve_reference(p, time_limit=10, seed=0)
>>> r.status, r.makespan >= r.bound
('optimal', True)
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from multiarm.errors import ScheduleError, UsageError
from scheduler.bounds import lower_bound
from scheduler.cpsat import (
    _rounders,
    _time_values,
    arrival_heads,
    cpsat_bound,
    essential_resources,
    integer_scale,
    solve_or_interrupt,
)
from scheduler.overlap import overlap_bound
from scheduler.problem import Problem
from scheduler.resource_bound import busy_resources_bound
from scheduler.schedule import Schedule, validate
from scheduler.search import Evaluator, priority_order

__all__ = [
    "FINE_TASKS",
    "LARGE",
    "Reference",
    "best_bound",
    "nowait_model",
    "relaxation_bound",
    "solve_reference",
]

LARGE = 20_000
"""Pairs of modes beyond which CP-SAT's presolve is skipped (``cell8``: 95,131;
its presolve alone took more than 30 s of a 60 s budget)."""

FINE_TASKS = 20
"""Up to this many tasks, :func:`solve_reference` runs the zone-free
relaxation at the no-wait model's unit (1 ms without an exact unit) rather
than 10 ms: on ``parking`` (5 tasks) its bound is then 19.32 s instead of
19.31 s, and meets the tree's plan within the 10 ms tolerance (a proof)."""


@dataclass(frozen=True, slots=True)
class Reference:
    """What :func:`solve_reference` found.

    Attributes
    ----------
    status : str
        ``"optimal"``: the schedule is proven best among schedules without
        waits at zone borders (and it is valid with the blocking oracle);
        ``"feasible"``: a valid schedule, no proof; ``"unknown"``: none.
    schedule : Schedule or None
        Valid (:func:`scheduler.validate`).
    makespan : float
        Its makespan (inf without one).
    nowait_bound : float
        CP-SAT's bound of the no-wait model (seconds; a bound of the problem
        solved with ``waits=False``; 0 when the unit is not exact).
    bound : float
        A lower bound of the true problem (waits and detours allowed):
        the zone-free relaxation's bound or :func:`scheduler.bounds.lower_bound`.
    unit : float
        The model's time unit (seconds).
    exact_unit : bool
        Whether the unit divides every number of the problem.
    oracle_clean : bool
        Whether the model's schedule met no parked arm (no detour needed).
    seconds : float
        Wall time of the no-wait solve (model building included).
    build_seconds : float
        Of which building the model and its hint.
    deterministic_time : float
        CP-SAT's deterministic time of the no-wait solve.
    pairs : int
        Pairs of modes constrained by a difference domain.
    zone_free_bound : float
        The zone-free relaxation's bound (seconds; 0 when not run).
    overlap_bound : float
        The overlap relaxation's bound (:func:`scheduler.overlap.overlap_bound`,
        seconds; 0 when not run or skipped).
    """

    status: str
    schedule: Schedule | None
    makespan: float
    nowait_bound: float
    bound: float
    unit: float
    exact_unit: bool
    oracle_clean: bool
    seconds: float
    build_seconds: float
    deterministic_time: float
    pairs: int
    zone_free_bound: float = 0.0
    overlap_bound: float = 0.0

    @property
    def gap(self) -> float:
        """``makespan / bound - 1`` (inf without a schedule)."""
        return self.makespan / self.bound - 1.0 if self.bound > 0 else math.inf


def _resource_windows(problem: Problem, shared: frozenset[int]) -> list[dict[int, list[Any]]]:
    """Per mode: resource -> its (start, end) windows (tools: the whole task)."""
    out = []
    for sh in problem.shapes.modes:
        res: dict[int, list[Any]] = {}
        for r, s, e in (*sh.exclusive, *sh.moves):
            if r in shared:
                res.setdefault(r, []).append((s, e))
        for r in sh.tools:
            if r in shared:
                res.setdefault(r, []).append((0.0, sh.duration))
        out.append(res)
    return out


def _forbidden(
    w1: dict[int, list[Any]], w2: dict[int, list[Any]], scale: float, rounding: str
) -> list[tuple[int, int]]:
    """Closed integer ranges of ``k = S2 - S1`` (model units) to forbid.

    In seconds, the two modes' windows meet exactly when ``S2 - S1`` lies in
    one of the open intervals ``(s1 - e2, e1 - s2)`` (merged first).
    ``"out"``: starts are ``k`` units exactly, so ``k`` is forbidden when
    ``k * unit`` lies in one; ``"in"``: a start ``S`` maps to ``floor(S /
    unit)``, so the difference ``k`` covers ``((k - 1) unit, (k + 1) unit)``,
    and ``k`` is forbidden only when that lies inside one."""
    raw = []
    for r, iv1 in w1.items():
        iv2 = w2.get(r)
        if not iv2:
            continue
        for s1, e1 in iv1:
            for s2, e2 in iv2:
                raw.append((s1 - e2, e1 - s2))
    raw.sort()
    merged: list[list[float]] = []
    for a, b in raw:
        if merged and a < merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    out: list[tuple[int, int]] = []
    for a, b in merged:
        if rounding == "out":
            k0, k1 = math.floor(a * scale + 1e-9) + 1, math.ceil(b * scale - 1e-9) - 1
        else:
            k0, k1 = math.ceil(a * scale + 1e-9) + 1, math.floor(b * scale - 1e-9) - 1
        if k0 <= k1:
            if out and k0 <= out[-1][1] + 1:
                out[-1] = (out[-1][0], max(out[-1][1], k1))
            else:
                out.append((k0, k1))
    return out


def nowait_model(
    problem: Problem,
    horizon: float,
    *,
    unit: float | None = None,
    zones: bool = True,
    rounding: str = "out",
) -> tuple[Any, dict[str, Any]]:
    """The no-wait CP-SAT model (module docstring) and its variables.

    Parameters
    ----------
    problem : Problem
    horizon : float
        Seconds: no schedule of interest ends later.
    unit : float or None
        Time unit (seconds); None: the exact unit of the data. A unit that
        does not divide the data is rounded outwards.
    zones : bool
        False leaves out every zone and start zone (tools kept): the
        zone-free relaxation of :func:`relaxation_bound`.
    rounding : {"out", "in"}
        When the unit does not divide the data. ``"out"``: a start of ``k``
        units is ``k * unit`` seconds; durations, travel and releases round
        up, so every solution is a valid schedule without waits. ``"in"``:
        a start ``S`` maps to ``floor(S / unit)``; durations, travel and
        releases round down and the forbidden differences shrink by a unit
        at each side, so every schedule without waits maps to a solution
        and the model's bound times the unit bounds the no-wait optimum.

    Returns
    -------
    (CpModel, dict)
        Variables ``S``, ``E`` (per task), ``X`` (per mode), ``makespan``;
        ``scale`` (units per second), ``exact`` and ``pairs``.
    """
    from ortools.sat.python import cp_model

    p = problem
    if unit is None:
        scale, exact = integer_scale(p)
    else:
        if not (math.isfinite(unit) and unit > 0):
            raise UsageError(f"unit must be finite and > 0 seconds, got {unit!r}")
        scale = 1.0 / unit
        allv = _time_values(p)
        exact = allv is not None and bool(
            np.all(np.abs(allv * scale - np.round(allv * scale)) <= 1e-9 * np.maximum(1, allv))
        )
    if rounding not in ("out", "in"):
        raise UsageError(f"rounding must be 'out' or 'in', got {rounding!r}")
    lo, hi = _rounders(scale, exact, rounding)
    T, M = p.n_tasks, p.n_modes
    H = hi(horizon) + 1 if exact else math.ceil(horizon * scale * 1.02) + 4 * T + 10
    dur = [hi(float(d)) for d in p.mode_duration]
    arrive = arrival_heads(p)
    mdl = cp_model.CpModel()
    S = [mdl.new_int_var(hi(float(p.task_release[t])), H, f"S{t}") for t in range(T)]
    E = [mdl.new_int_var(0, H, f"E{t}") for t in range(T)]
    X: dict[int, Any] = {}
    iv: dict[int, Any] = {}
    arc_lits: dict[int, dict[tuple[int, int], Any]] = {}
    master = []
    sizes = []
    for t in range(T):
        size = mdl.new_int_var(0, H, f"D{t}")
        sizes.append(size)
        master.append(mdl.new_interval_var(S[t], size, E[t], f"T{t}"))
        lits = []
        for m in p.task_modes[t]:
            x = mdl.new_bool_var(f"x{m}")
            X[m] = x
            lits.append(x)
            mdl.add(size == dur[m]).only_enforce_if(x)
            # the initial pose's setup binds the first task only (start arc below)
            mdl.add(S[t] >= hi(float(arrive[m]))).only_enforce_if(x)
            iv[m] = mdl.new_optional_fixed_size_interval_var(S[t], dur[m], x, f"I{m}")
        mdl.add_exactly_one(lits)
        for q in p.task_preds[t]:
            mdl.add(S[t] >= E[q])
    for a in range(p.n_arms):
        modes = [int(m) for m in np.flatnonzero(p.mode_arm == a)]
        if not modes:
            continue
        mdl.add_no_overlap([iv[m] for m in modes])
        if not p._setup.zero:
            arcs = []
            arc_lits[a] = {}
            avail = float(p.arm_available[a])
            for i, m in enumerate(modes, start=1):
                t = int(p.mode_task[m])
                go = mdl.new_bool_var("")
                head = avail + p.setup_time(a, -1, t)
                if math.isfinite(head):
                    mdl.add(S[t] >= hi(head)).only_enforce_if(go)
                else:
                    mdl.add(go == 0)
                arcs.append((0, i, go))
                arcs.append((i, 0, mdl.new_bool_var("")))
                arcs.append((i, i, ~X[m]))
                arc_lits[a][(-1, m)] = arcs[-3][2]
                arc_lits[a][(m, -1)] = arcs[-2][2]
                for j, m2 in enumerate(modes, start=1):
                    if m2 == m:
                        continue
                    t2 = int(p.mode_task[m2])
                    lit = mdl.new_bool_var("")
                    arcs.append((i, j, lit))
                    arc_lits[a][(m, m2)] = lit
                    mdl.add(S[t2] >= E[t] + hi(p.setup_time(a, t, t2))).only_enforce_if(lit)
            arcs.append((0, 0, mdl.new_bool_var("")))
            arc_lits[a][(-1, -1)] = arcs[-1][2]
            mdl.add_circuit(arcs)
    shared = essential_resources(p)
    if not zones:
        shared = frozenset(r for r in shared if r >= 2 * p.n_zones)  # tools only
    wins = _resource_windows(p, shared)
    pairs = 0
    users: dict[int, list[int]] = {}
    for m in range(M):
        for r in wins[m]:
            users.setdefault(r, []).append(m)
    seen: set[tuple[int, int]] = set()
    pair_bad: list[tuple[int, int, list[tuple[int, int]]]] = []
    # (arm, its start modes' travel, other mode, offset of its first window in the zone)
    leave: list[tuple[int, dict[int, int], int, int]] = []
    for ms in users.values():
        for i, m1 in enumerate(ms):
            for m2 in ms[i + 1 :]:
                if (m1, m2) in seen:
                    continue
                seen.add((m1, m2))
                t1, t2 = int(p.mode_task[m1]), int(p.mode_task[m2])
                if t1 == t2 or p.mode_arm[m1] == p.mode_arm[m2]:
                    continue
                bad = _forbidden(wins[m1], wins[m2], scale, "out" if exact else rounding)
                if not bad:
                    continue
                allowed = []
                cur = -H - 1
                for a, b in bad:
                    if a > cur:
                        allowed.append((cur, a - 1))
                    cur = b + 1
                allowed.append((cur, H + 1))
                dom = cp_model.Domain.from_intervals([list(x) for x in allowed])
                mdl.add_linear_expression_in_domain(S[t2] - S[t1], dom).only_enforce_if(
                    [X[m1], X[m2]]
                )
                pair_bad.append((m1, m2, bad))
                pairs += 1
    # arms standing in exclusive start zones until they leave
    if zones:
        for a in range(p.n_arms):
            zs = [z for z in p.arm_start_zones[a] if p.zone_exclusive[z] and z in shared]
            if not zs:
                continue
            modes = [int(m) for m in np.flatnonzero(p.mode_arm == a)]
            dep = mdl.new_int_var(-H, H, f"dep{a}")
            cands: list[Any] = []
            for m in modes:
                t = int(p.mode_task[m])
                e_m = mdl.new_int_var(-H, H, "")
                lit = arc_lits[a][(-1, m)] if a in arc_lits else X[m]  # the arm's first task
                mdl.add(e_m == S[t] - lo(p.setup_time(a, -1, t))).only_enforce_if(lit)
                mdl.add(e_m == H).only_enforce_if(~lit)
                cands.append(e_m)
            mdl.add_min_equality(dep, cands or [H])
            for m in range(M):
                if p.mode_arm[m] == a:
                    continue
                for z in zs:
                    firsts = [s for s, _ in wins[m].get(int(z), [])]
                    if firsts:
                        t = int(p.mode_task[m])
                        mdl.add(S[t] + lo(min(firsts)) >= dep).only_enforce_if(X[m])
                        travel = {m1: lo(p.setup_time(a, -1, int(p.mode_task[m1]))) for m1 in modes}
                        leave.append((a, travel, m, lo(min(firsts))))
    mdl.add_cumulative(master, [1] * T, p.n_arms)
    mk = mdl.new_int_var(0, H, "makespan")
    mdl.add_max_equality(mk, E)
    mdl.minimize(mk)
    return mdl, {
        "S": S,
        "E": E,
        "D": sizes,
        "X": X,
        "arcs": arc_lits,
        "dur": dur,
        "makespan": mk,
        "scale": scale,
        "exact": exact,
        "pairs": pairs,
        "pair_bad": pair_bad,
        "leave": leave,
        "lo": lo,
        "hi": hi,
    }


def _grid_starts(problem: Problem, v: dict[str, Any], hint: Schedule) -> list[int]:
    """``hint``'s modes and order timed again in model units: each start the
    least that meets every constraint towards the others (repeated until
    nothing moves, at most 100 passes), so that the hint is a solution."""
    p = problem
    T = p.n_tasks
    hi, dur = v["hi"], v["dur"]
    mode = [int(m) for m in hint.mode]
    rank = np.argsort(np.lexsort((np.arange(T), hint.start)))
    S = [max(hi(float(hint.start[t])), hi(float(p.task_release[t]))) for t in range(T)]
    arm_seq: dict[int, list[int]] = {}
    for t in sorted(range(T), key=lambda t: rank[t]):
        arm_seq.setdefault(int(p.mode_arm[mode[t]]), []).append(t)
    pairs: dict[int, list[tuple[int, int, list[tuple[int, int]]]]] = {}
    chosen = set(mode)
    for m1, m2, bad in v["pair_bad"]:
        if m1 in chosen and m2 in chosen:
            t1, t2 = int(p.mode_task[m1]), int(p.mode_task[m2])
            if rank[t1] < rank[t2]:  # place t2 against t1: S2 - S1 outside bad
                pairs.setdefault(t2, []).append((t1, 1, bad))
            else:  # place t1 against t2: S1 - S2 outside -bad
                pairs.setdefault(t1, []).append((t2, -1, bad))
    for _ in range(100):
        moved = False
        for t in sorted(range(T), key=lambda t: rank[t]):
            m = mode[t]
            a = int(p.mode_arm[m])
            need = S[t]
            for q in p.task_preds[t]:
                need = max(need, S[q] + dur[mode[q]])
            seq = arm_seq[a]
            i = seq.index(t)
            if i == 0:
                need = max(need, hi(float(p.arm_available[a]) + p.setup_time(a, -1, t)))
            else:
                q = seq[i - 1]
                need = max(need, S[q] + dur[mode[q]] + hi(p.setup_time(a, q, t)))
            for arm, travel, m2, off in v["leave"]:
                if m2 == m and arm_seq.get(arm):
                    first = arm_seq[arm][0]
                    need = max(need, S[first] - travel[mode[first]] - off)
            while True:  # the least start outside every forbidden difference
                bump = need
                for q, sign, bad in pairs.get(t, ()):
                    for x, y in bad:
                        lo_k, hi_k = (x, y) if sign > 0 else (-y, -x)
                        if lo_k <= need - S[q] <= hi_k:
                            bump = max(bump, S[q] + hi_k + 1)
                if bump == need:
                    break
                need = bump
            if need != S[t]:
                S[t] = need
                moved = True
        if not moved:
            break
    return S


def _add_hint(mdl: Any, problem: Problem, v: dict[str, Any], hint: Schedule) -> None:
    """Hint every start, mode, end and travel arc of ``hint`` (rounded to the unit).

    A complete hint lets CP-SAT take it as its first solution when it is one
    (on ``cell8``, an incomplete hint left it without any in a minute)."""
    p = problem
    starts = _grid_starts(p, v, hint)
    ends = []
    for t in range(p.n_tasks):
        m = int(hint.mode[t])
        mdl.add_hint(v["S"][t], starts[t])
        mdl.add_hint(v["D"][t], v["dur"][m])
        mdl.add_hint(v["E"][t], starts[t] + v["dur"][m])
        ends.append(starts[t] + v["dur"][m])
        for m2 in p.task_modes[t]:
            mdl.add_hint(v["X"][m2], int(m2 == m))
    mdl.add_hint(v["makespan"], max(ends, default=0))
    for a, lits in v["arcs"].items():
        seq = sorted(
            (int(hint.mode[t]) for t in range(p.n_tasks) if p.mode_arm[int(hint.mode[t])] == a),
            key=lambda m: (starts[int(p.mode_task[m])], m),
        )
        used = set(zip([-1, *seq], [*seq, -1], strict=True)) if seq else {(-1, -1)}
        for key, lit in lits.items():
            mdl.add_hint(lit, int(key in used))


def _solver(seconds: float | None, seed: int, workers: int, dtime: float | None, log: bool) -> Any:
    from ortools.sat.python import cp_model

    solver = cp_model.CpSolver()
    if seconds is not None:
        solver.parameters.max_time_in_seconds = max(0.01, seconds)
    if dtime is not None:
        solver.parameters.max_deterministic_time = dtime
    solver.parameters.num_workers = workers
    solver.parameters.random_seed = seed
    solver.parameters.log_search_progress = log
    return solver


def _horizon(problem: Problem, hint: Schedule | None) -> tuple[float, Schedule | None]:
    """A makespan that a schedule without waits reaches, and that schedule: the
    earliest-finish-time list, or ``hint``'s order and modes decoded without
    waits when that is shorter."""
    ev = Evaluator(problem, waits=False)
    cands = [ev.evaluate(priority_order(problem))]
    if hint is not None:
        order = np.lexsort((np.arange(problem.n_tasks), hint.start)).astype(np.int64)
        cands.append(ev.evaluate(order, hint.mode.astype(np.int64)))
    found = [c for c in cands if c is not None]
    if found:
        best = min(found, key=lambda c: c.makespan)
        return best.makespan, ev.schedule(best)
    return float(
        np.max(problem.task_release)
        + float(np.max(problem.arm_available))
        + 2 * np.sum([max(problem.mode_duration[m] for m in ms) for ms in problem.task_modes])
        + 1e3
    ), None


def _bound_of(
    problem: Problem,
    horizon: float,
    unit: float | None,
    zones: bool,
    seconds: float | None,
    seed: int,
    workers: int,
    dtime: float | None,
) -> tuple[float, str]:
    """The inward model's bound (seconds) and CP-SAT's status name."""

    mdl, v = nowait_model(problem, horizon, unit=unit, zones=zones, rounding="in")
    solver = _solver(seconds, seed, workers, dtime, False)
    code = solve_or_interrupt(solver, mdl)  # Ctrl-C stays Python's
    return cpsat_bound(solver, code) / v["scale"], solver.status_name(code)


def relaxation_bound(
    problem: Problem,
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    unit: float | None = None,
    workers: int = 2,
    max_deterministic_time: float | None = None,
) -> float:
    """A lower bound of the makespan (seconds): the zone-free relaxation's CP-SAT bound.

    Every valid schedule (waits at borders and detours included) keeps its
    arms' sequences, travel, releases, precedence and tools, so it is a
    schedule of the problem without zones; CP-SAT's bound of that problem,
    modelled with inward rounding (:func:`nowait_model`, ``rounding="in"``),
    bounds it.

    Parameters
    ----------
    problem : Problem
    time_limit : float or None
        Seconds for CP-SAT.
    seed : int
    unit : float or None
        Time unit (seconds); None: the exact unit of the data, or 1 ms.
    workers : int
    max_deterministic_time : float or None

    Returns
    -------
    float
        At least :func:`scheduler.bounds.lower_bound`.

    Examples
    --------
    >>> from scheduler.generate import random_problem
    >>> p = random_problem(2, 6, 2, 1, seed=1)
    >>> relaxation_bound(p, 5) >= lower_bound(p)
    True
    """
    p = problem
    lb = lower_bound(p)
    if p.n_tasks == 0:
        return 0.0
    horizon, _ = _horizon(p, None)
    b, _ = _bound_of(p, horizon, unit, False, time_limit, seed, workers, max_deterministic_time)
    return max(lb, b)


def best_bound(
    problem: Problem,
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    workers: int = 2,
    max_deterministic_time: float | None = None,
) -> float:
    """The best lower bound of the makespan we can prove (seconds).

    The largest of :func:`scheduler.bounds.lower_bound` (no solver),
    :func:`relaxation_bound` (zone-free),
    :func:`scheduler.overlap.overlap_bound` (pair spans) and
    :func:`scheduler.resource_bound.busy_resources_bound` (the busiest zones
    kept, waits anywhere), each relaxation given ``time_limit`` seconds (or
    ``max_deterministic_time``) of CP-SAT. All four are bounds of the true
    problem: waits at borders and detours included.

    Examples
    --------
    >>> from scheduler.generate import random_problem
    >>> p = random_problem(2, 6, 2, 1, seed=1)
    >>> best_bound(p, 2, workers=1) >= lower_bound(p)
    True
    """
    p = problem
    lb = lower_bound(p)
    if p.n_tasks == 0:
        return 0.0
    zf = relaxation_bound(
        p, time_limit, seed, workers=workers, max_deterministic_time=max_deterministic_time
    )
    ob, _ = overlap_bound(
        p, time_limit, seed, workers=workers, max_deterministic_time=max_deterministic_time
    )
    rb, _ = busy_resources_bound(
        p, time_limit, seed, workers=workers, max_deterministic_time=max_deterministic_time
    )
    return max(lb, zf, ob, rb)


def solve_reference(
    problem: Problem,
    time_limit: float | None = 60.0,
    seed: int = 0,
    *,
    hint: Schedule | None = None,
    workers: int = 2,
    max_deterministic_time: float | None = None,
    unit: float | None = None,
    bound_time: float | None = 10.0,
    bound_deterministic_time: float | None = None,
    tolerance: float = 0.01,
    log: bool = False,
) -> Reference:
    """Solve the no-wait model and bound the true problem (module docstring).

    Four CP-SAT runs: the no-wait model rounded outwards (its schedule), the
    same rounded inwards (a bound of the no-wait optimum, when the unit is
    not exact), the zone-free relaxation and the overlap relaxation
    (:func:`scheduler.overlap.overlap_bound`; bounds of the true problem),
    the last three ``bound_time`` seconds each. Without an exact unit the
    relaxations round inwards at 10 ms (zone-free; the model's unit up to
    :data:`FINE_TASKS` tasks) and 50 ms (overlap).

    Parameters
    ----------
    problem : Problem
    time_limit : float or None
        Seconds for the no-wait solve.
    seed : int
    hint : Schedule or None
        A valid schedule to start from (e.g. the tree search's); its
        waits are ignored.
    workers : int
        CP-SAT workers.
    max_deterministic_time : float or None
        CP-SAT's work limit for each solve (repeatable where the wall
        time is not).
    unit : float or None
        Time unit (seconds); None: the exact unit of the data, or 1 ms.
    bound_time : float or None
        Seconds for each bounding run (0: none; the bounds are then
        :func:`scheduler.bounds.lower_bound`).
    bound_deterministic_time : float or None
        CP-SAT's work limit for each bounding run (the bounds then depend
        little on the machine's load).
    tolerance : float
        Seconds: with a unit that does not divide the data, the no-wait
        optimum counts as proven when the outward model is solved to
        optimality and its schedule is at most this much above the inward
        model's bound.
    log : bool
        CP-SAT's log of the no-wait solve on stdout.

    Returns
    -------
    Reference
    """
    from ortools.sat.python import cp_model

    p = problem
    t0 = time.perf_counter()
    if p.n_tasks == 0:
        return Reference(
            "optimal", Schedule.empty(), 0.0, 0.0, 0.0, 1.0, True, True, 0.0, 0.0, 0.0, 0
        )
    horizon, start = _horizon(p, hint)
    mdl, v = nowait_model(p, horizon, unit=unit)
    scale = v["scale"]
    if start is not None:
        _add_hint(mdl, p, v, start)
    build = time.perf_counter() - t0
    solver = _solver(
        None if time_limit is None else time_limit - (time.perf_counter() - t0),
        seed,
        workers,
        max_deterministic_time,
        log,
    )
    if v["pairs"] > LARGE:  # presolve alone would take the whole budget
        solver.parameters.cp_model_presolve = False
    code = solve_or_interrupt(solver, mdl)  # Ctrl-C stays Python's
    seconds = time.perf_counter() - t0
    dtime = float(solver.deterministic_time)
    ok = code in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    lb = lower_bound(p)
    bounding = bound_time is None or bound_time > 0
    bdt = max_deterministic_time if bound_deterministic_time is None else bound_deterministic_time
    if v["exact"]:
        nw_bound = cpsat_bound(solver, code) / scale
    elif bounding:
        nw_bound, _ = _bound_of(p, horizon, 1 / scale, True, bound_time, seed, workers, bdt)
    else:
        nw_bound = 0.0
    bound = lb
    zf = ob = 0.0
    if bounding:
        fine = v["exact"] or p.n_tasks <= FINE_TASKS
        zf_unit = 1 / scale if fine else max(1 / scale, 0.01)
        zf, _ = _bound_of(p, horizon, zf_unit, False, bound_time, seed, workers, bdt)
        ob, _ = overlap_bound(
            p,
            bound_time,
            seed,
            unit=1 / scale if v["exact"] else max(1 / scale, 0.05),
            workers=workers,
            max_deterministic_time=bdt,
            horizon=horizon,
        )
        bound = max(lb, zf, ob)
    nw_bound = max(nw_bound, bound)
    if not ok:
        return Reference(
            "unknown", None, math.inf, nw_bound, bound, 1 / scale, v["exact"], False, seconds,
            build, dtime, v["pairs"], zf, ob,
        )  # fmt: skip
    T = p.n_tasks
    modes = np.array(
        [next(m for m in p.task_modes[t] if solver.boolean_value(v["X"][m])) for t in range(T)]
    )
    starts = np.array([solver.value(v["S"][t]) / scale for t in range(T)])
    sched: Schedule | None = Schedule.from_starts(p, modes, starts)
    clean = True
    try:
        assert sched is not None
        validate(p, sched)
    except ScheduleError:  # a parked arm in the way: decode the same order with detours
        clean = False
        ev = Evaluator(p, waits=False)
        sol = ev.evaluate(np.lexsort((np.arange(T), starts)).astype(np.int64), modes)
        sched = ev.schedule(sol) if sol is not None else None
    if sched is None:
        return Reference(
            "unknown", None, math.inf, nw_bound, bound, 1 / scale, v["exact"], False, seconds,
            build, dtime, v["pairs"], zf, ob,
        )  # fmt: skip
    mk = validate(p, sched)
    if v["exact"]:
        proven = code == cp_model.OPTIMAL and abs(
            mk - solver.objective_value / scale
        ) <= 1e-6 * max(1.0, mk)
    else:  # the outward optimum against the inward bound
        proven = code == cp_model.OPTIMAL and mk - nw_bound <= tolerance
    proven = proven and clean
    return Reference(
        "optimal" if proven else "feasible",
        sched,
        mk,
        nw_bound,
        min(bound, mk),
        1 / scale,
        v["exact"],
        clean,
        seconds,
        build,
        dtime,
        v["pairs"],
        zf,
        ob,
    )
