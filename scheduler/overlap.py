"""How much two tasks of different arms can progress at once, and the bound it gives.

Two tasks on different arms that share a zone, a shared zone's movement or a
tool cannot both progress through the parts of their modes that use it at
the same time. Drawn as a *coordination diagram* (the progress ``u`` of one
mode against the progress ``v`` of the other), every pair of their windows in
one resource is a forbidden open rectangle; a schedule traces a monotone path
through the diagram, waiting (an axis-parallel step) or progressing together
(a diagonal step). The diagonal length of the path is the time both progress
at once, so

    ``max(E1, E2) - min(S1, S2) >= d1 + d2 - cap(m1, m2)``

(and, when one starts ``delta`` after the other, ``>= delta + d1 + d2 -
lead(delta)``) for any schedule in which the two modes run, ``cap`` the
longest diagonal of any monotone path (:func:`overlap_caps`). Waits and detours only lengthen
tasks, so this holds for every schedule :func:`scheduler.validate` accepts.

**How** ``cap`` **is computed (an upper bound, never below the true value).**
The diagram is cut into square cells of side ``step``; a cell is blocked
(the path may not enter it: both arms inside one exclusive zone or holding
one tool) or closed to diagonal steps (also both moving in one shared zone)
only when it lies entirely inside a forbidden rectangle, and the arms may
wait anywhere (the real arms wait only at zone borders: relaxed). Dynamic
programming over staircases of unblocked cells from the first cell to the
last finds the longest chain of diagonal-free cells increasing in both
coordinates; ``cap`` is its length times ``step``. It bounds the diagonal of
any real path: the cells a real path touches are unblocked and form a
staircase, its diagonal in them is at most ``step`` per row and per column
of cells, and cells of a staircase with distinct rows and columns form such
a chain, so by König's theorem (a fractional matching of a bipartite graph
is at most its largest matching) the diagonal is at most ``step`` times the
longest chain. Two modes holding one tool never overlap at all
(``cap = 0``). The same search from every cell of the first row (column)
bounds the overlap when one task starts ``delta`` after the other
(:class:`PairOverlap`): the one ahead has then progressed at most ``delta``.

:func:`overlap_bound` adds the constraint above for every pair of modes to
the zone-free relaxation (arms, travel, releases, precedence, tools; tasks
may take longer than their modes), solved by CP-SAT with times rounded down
(``floor``, which keeps every constraint of a real schedule), so that its
bound is a lower bound of the makespan of the true problem.

Examples
--------
>>> from scheduler import Model, Window
>>> m = Model()
>>> a, b, z = m.add_arm("a"), m.add_arm("b"), m.add_zone("z")
>>> t1, t2 = m.add_task("t1"), m.add_task("t2")
>>> _ = m.add_mode(t1, a, 4.0, windows=[Window(z, 0.0, 4.0)])
>>> _ = m.add_mode(t2, b, 4.0, windows=[Window(z, 2.0, 4.0)])
>>> caps = overlap_caps(m.build(), step=0.1)
>>> round(caps[(0, 1)].cap, 6)  # exactly 2 s (t2 enters z once t1 is done), 2 cells more
2.2
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from multiarm.types import FloatArray
from scheduler.cpsat import (
    add_arm_sequences,
    add_relaxed_tasks,
    cpsat_bound,
    essential_resources,
    resource_windows,
    solve_or_interrupt,
)
from scheduler.kernel.exact_bb import diagram_chain as _chain
from scheduler.problem import Problem

__all__ = ["PairOverlap", "overlap_bound", "overlap_caps", "overlap_model"]


@dataclass(frozen=True, slots=True)
class PairOverlap:
    """How much two modes ``m1``, ``m2`` can progress at once (seconds).

    Attributes
    ----------
    cap : float
        The longest diagonal of the diagram (module docstring).
    step : float
        Cell side of the grid.
    first : (n,) float
        ``first[i]``: an upper bound of ``u0 + D(u0)`` over ``u0 <= (i + 1)
        step``, ``D(u0)`` the longest diagonal of a path from ``(u0, 0)``:
        when ``m2`` starts ``delta`` after ``m1`` (``m1`` has then progressed
        ``u0 <= delta``), the two span at least ``delta + d1 + d2 -
        first[floor(delta / step)]`` (the last entry beyond).
    second : (m,) float
        The same with the roles swapped (``m2`` first).
    """

    cap: float
    step: float
    first: FloatArray
    second: FloatArray


def _pair(
    d1: float,
    d2: float,
    rects: list[tuple[float, float, float, float, bool]],
    step: float,
) -> PairOverlap:
    """The overlap profile of two modes (their diagram's forbidden rectangles)."""
    n, m = max(1, math.ceil(d1 / step - 1e-9)), max(1, math.ceil(d2 / step - 1e-9))
    blocked = np.zeros((n, m), dtype=np.bool_)
    nodiag = np.zeros((n, m), dtype=np.bool_)
    for s1, e1, s2, e2, presence in rects:
        # cells entirely inside the open rectangle, the quotients moved by 1e-6
        # of a cell towards fewer cells (rounding never marks a crossable cell)
        i0, i1 = math.floor(s1 / step + 1e-6) + 1, math.ceil(e1 / step - 1e-6) - 2
        j0, j1 = math.floor(s2 / step + 1e-6) + 1, math.ceil(e2 / step - 1e-6) - 2
        if i0 <= i1 and j0 <= j1:
            nodiag[i0 : i1 + 1, j0 : j1 + 1] = True
            if presence:
                blocked[i0 : i1 + 1, j0 : j1 + 1] = True
    cap = min(float(_chain(blocked, nodiag)[n - 1, m - 1]) * step, d1, d2)
    # chains from each cell to the last one: the same search on the reversed diagram
    back = _chain(
        np.ascontiguousarray(blocked[::-1, ::-1]), np.ascontiguousarray(nodiag[::-1, ::-1])
    )[::-1, ::-1]
    rows = np.maximum(back[:, 0], 0).astype(float)
    cols = np.maximum(back[0, :], 0).astype(float)
    first = np.maximum.accumulate((np.arange(1, n + 1) + rows) * step)
    second = np.maximum.accumulate((np.arange(1, m + 1) + cols) * step)
    return PairOverlap(cap, step, first, second)


def overlap_caps(
    problem: Problem,
    step: float | None = None,
    max_cells: int = 160_000,
    max_pairs: int | None = None,
) -> dict[tuple[int, int], PairOverlap] | None:
    """Per pair of modes ``(m1, m2)``, ``m1 < m2``, of different arms and tasks
    that share a resource: upper bounds (seconds) on the time both can
    progress at once (module docstring), overall and by which starts first.

    Parameters
    ----------
    problem : Problem
    step : float or None
        Cell side (seconds); None: 1/400 of the longest mode. A pair whose
        diagram would have more than ``max_cells`` cells uses a coarser step
        (the cap is then looser, never wrong).
    max_cells : int
    max_pairs : int or None
        None is returned when more pairs than this share a resource.

    Returns
    -------
    dict or None
        :class:`PairOverlap` per pair; pairs that share no resource are left
        out (their cap is the shorter mode's duration).
    """
    p = problem
    if p.n_modes == 0:
        return {}
    longest = float(np.max(p.mode_duration))
    base = step if step is not None else max(longest / 400.0, 1e-6)
    use = resource_windows(p, essential_resources(p))
    Z, Z2 = p.n_zones, 2 * p.n_zones
    by_mode: list[dict[int, list[Any]]] = [{} for _ in range(p.n_modes)]
    for r, modes in use.items():
        for m, ws in modes.items():
            by_mode[m][r] = ws
    users: dict[int, list[int]] = {r: sorted(modes) for r, modes in use.items()}
    pairs: set[tuple[int, int]] = set()
    for ms in users.values():
        for i, m1 in enumerate(ms):
            for m2 in ms[i + 1 :]:
                if p.mode_arm[m1] != p.mode_arm[m2] and p.mode_task[m1] != p.mode_task[m2]:
                    pairs.add((m1, m2))
    if max_pairs is not None and len(pairs) > max_pairs:
        return None
    out: dict[tuple[int, int], PairOverlap] = {}
    for m1, m2 in sorted(pairs):
        d1, d2 = float(p.mode_duration[m1]), float(p.mode_duration[m2])
        w1, w2 = by_mode[m1], by_mode[m2]
        common = [r for r in w1 if r in w2]
        if any(r >= Z2 for r in common):  # one tool: never at once
            out[(m1, m2)] = PairOverlap(0.0, max(d1, d2), np.array([d1]), np.array([d2]))
            continue
        rects = [
            (s1, e1, s2, e2, not Z <= r < Z2)
            for r in common
            for s1, e1 in w1[r]
            for s2, e2 in w2[r]
        ]
        st = max(base, math.sqrt(d1 * d2 / max_cells))
        out[(m1, m2)] = _pair(d1, d2, rects, st)
    return out


def _levels(table: Any, ks: Any, need: int, n_levels: int) -> list[tuple[int, int]]:
    """Thresholds ``(k, table[k])`` worth a constraint: where ``table`` (nonincreasing)
    has dropped by a share of its range, and only where it says more than
    ``need`` and than the start gap itself (``k``)."""
    table = np.minimum.accumulate(table)
    top, bottom = int(table[0]), int(table[-1])
    if n_levels <= 0 or top <= bottom:
        return []
    out: list[tuple[int, int]] = []
    for q in range(n_levels):
        level = top - (top - bottom) * q / n_levels
        k = int(np.flatnonzero(table >= level)[-1])
        low = int(table[k])
        if low + int(ks[k]) > need and (not out or out[-1][0] != k):
            out.append((k, low))
    return out


def add_pair_spans(
    mdl: Any,
    problem: Problem,
    S: list[Any],
    E: list[Any],
    X: dict[int, Any],
    caps: dict[tuple[int, int], PairOverlap],
    scale: float,
    H: int,
    *,
    slack: int = 0,
    profiles: bool = True,
    n_levels: int = 6,
) -> int:
    """Add the pair spans of ``caps`` to a CP-SAT model whose start and end
    variables ``S``, ``E`` are the real times in units of ``1 / scale``
    rounded down (less ``slack`` units at most for the ends); the number of
    pairs constrained."""
    p = problem

    def fl(x: float) -> int:
        return math.floor(x * scale + 1e-9)

    dur = [fl(float(d)) for d in p.mode_duration]
    pairs = 0
    for (m1, m2), po in caps.items():
        t1, t2 = int(p.mode_task[m1]), int(p.mode_task[m2])
        d1, d2 = float(p.mode_duration[m1]), float(p.mode_duration[m2])
        need = fl(d1 + d2 - po.cap) - slack
        if need <= max(dur[m1], dur[m2]):
            continue  # implied by the tasks' own lengths
        before, after, lead1, lead2 = (mdl.new_bool_var("") for _ in range(4))
        mdl.add_bool_or([before, after, lead1, lead2, ~X[m1], ~X[m2]])
        mdl.add(S[t2] >= E[t1]).only_enforce_if(before)
        mdl.add(S[t1] >= E[t2]).only_enforce_if(after)
        hi_e = mdl.new_int_var(0, H, "")
        mdl.add_max_equality(hi_e, [E[t1], E[t2]])
        for lit, (a, b), lead in ((lead1, (t1, t2), po.first), (lead2, (t2, t1), po.second)):
            # ``b`` starts delta >= 0 after ``a``: span >= delta + d1 + d2 - lead(delta)
            mdl.add(S[b] >= S[a]).only_enforce_if(lit)
            mdl.add(hi_e - S[a] >= need).only_enforce_if(lit)
            if not profiles:
                continue
            k_max = math.ceil(len(lead) * po.step * scale) + 1
            ks = np.arange(k_max + 1)
            rows = np.minimum(
                np.floor((ks + 1) / scale / po.step + 1e-9).astype(int), len(lead) - 1
            )
            table = np.floor((d1 + d2 - lead[rows]) * scale + 1e-9).astype(int) - 1 - slack
            # b within k units of a: the pair ends at least table[k] after b starts
            # (table nonincreasing); a few levels as reified thresholds
            levels = _levels(table, ks, need, n_levels)
            for k, low in levels:
                y = mdl.new_bool_var("")
                mdl.add(S[b] - S[a] <= k).only_enforce_if(y)
                mdl.add(S[b] - S[a] >= k + 1).only_enforce_if(~y)
                mdl.add(hi_e - S[b] >= low).only_enforce_if([lit, y])
        pairs += 1
    return pairs


def overlap_model(
    problem: Problem,
    horizon: float,
    caps: dict[tuple[int, int], PairOverlap],
    unit: float,
    *,
    profiles: bool = True,
    n_levels: int = 6,
) -> tuple[Any, dict[str, Any]]:
    """The relaxation of :func:`overlap_bound` as a CP-SAT model.

    Every time ``x`` of a real schedule maps to ``floor(x / unit)``;
    durations, travel, releases and the pair constraints' lengths are rounded
    down, so the image of every valid schedule is a solution (``floor(a + b)
    >= floor(a) + floor(b)``).

    Returns
    -------
    (CpModel, dict)
        Variables ``S``, ``E``, ``X``, ``makespan``, ``scale`` and ``pairs``
        (pair constraints added).
    """
    from ortools.sat.python import cp_model

    p = problem
    scale = 1.0 / unit

    def fl(x: float) -> int:
        return math.floor(x * scale + 1e-9)

    T = p.n_tasks
    H = math.ceil(horizon * scale * 1.02) + 10
    mdl = cp_model.CpModel()
    S, E, X, iv, master = add_relaxed_tasks(mdl, p, fl, H)
    add_arm_sequences(mdl, p, iv, X, S, E, fl)
    # tools are held from start to end, waits included: a no-overlap each
    tools: dict[int, list[Any]] = {}
    for m in range(p.n_modes):
        for k in p.mode_tools[m]:
            tools.setdefault(int(k), []).append(iv[m])
    for ivs in tools.values():
        if len(ivs) > 1:
            mdl.add_no_overlap(ivs)
    pairs = add_pair_spans(mdl, p, S, E, X, caps, scale, H, profiles=profiles, n_levels=n_levels)
    mdl.add_cumulative(master, [1] * T, p.n_arms)
    mk = mdl.new_int_var(0, H, "makespan")
    mdl.add_max_equality(mk, E)
    mdl.minimize(mk)
    return mdl, {"S": S, "E": E, "X": X, "makespan": mk, "scale": scale, "pairs": pairs}


def overlap_bound(
    problem: Problem,
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    unit: float = 0.01,
    workers: int = 2,
    max_deterministic_time: float | None = None,
    step: float | None = None,
    horizon: float | None = None,
    max_pairs: int | None = 20_000,
) -> tuple[float, str]:
    """A lower bound of the makespan: CP-SAT on the overlap relaxation.

    Parameters
    ----------
    problem : Problem
    time_limit : float or None
        Seconds for CP-SAT.
    seed : int
    unit : float
        Time unit of the model (seconds; times rounded down).
    workers : int
    max_deterministic_time : float or None
        CP-SAT's work limit (repeatable where the wall time is not).
    step : float or None
        Cell side of :func:`overlap_caps`.
    horizon : float or None
        A makespan some schedule reaches (None: the earliest-finish-time
        schedule's).
    max_pairs : int or None
        More pairs of modes sharing a resource than this: no model is built
        (``cell8`` has about 95,000; their caps alone take minutes).

    Returns
    -------
    (float, str)
        The bound (seconds; CP-SAT's proven bound even when the run stopped
        before its first solution, ``"UNKNOWN"``; 0 when it proved nothing)
        and CP-SAT's status name (``"OPTIMAL"``: the relaxation is solved,
        its optimum is the bound; ``"SKIPPED"``: too many pairs).
    """
    from ortools.sat.python import cp_model

    p = problem
    if p.n_tasks == 0:
        return 0.0, "OPTIMAL"
    if horizon is None:
        from scheduler.search import Evaluator, priority_order

        sol = Evaluator(p).evaluate(priority_order(p))
        horizon = (
            sol.makespan
            if sol is not None
            else float(np.max(p.task_release) + np.sum(p.mode_duration) + 1.0)
        )
    caps = overlap_caps(p, step, max_pairs=max_pairs)
    if caps is None:
        return 0.0, "SKIPPED"
    mdl, v = overlap_model(p, horizon, caps, unit)
    solver = cp_model.CpSolver()
    if time_limit is not None:
        solver.parameters.max_time_in_seconds = max(0.01, time_limit)
    if max_deterministic_time is not None:
        solver.parameters.max_deterministic_time = max_deterministic_time
    solver.parameters.num_workers = workers
    solver.parameters.random_seed = seed
    code = solve_or_interrupt(solver, mdl)  # Ctrl-C stays Python's
    # a run stopped before its first solution still proved its bound
    return cpsat_bound(solver, code) / v["scale"], solver.status_name(code)
