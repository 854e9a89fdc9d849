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

for any schedule in which the two modes run, ``cap`` the longest diagonal of
any monotone path (:func:`overlap_caps`). Waits and detours only lengthen
tasks, so this holds for every schedule :func:`scheduler.validate` accepts.

**How** ``cap`` **is computed (an upper bound, never below the true value).**
The diagram is cut into square cells of side ``step``; a cell is blocked only
when it lies entirely inside a forbidden rectangle, and the path may wait
anywhere (the real arms wait only at zone borders, and an exclusive zone
cannot be crossed while the other arm waits in it: both relaxed). A longest
chain of free cells increasing in both coordinates, times ``step``, is
computed by dynamic programming. It bounds the diagonal of any path through
the real diagram: the path's diagonal in each free cell is at most ``step``
per column and per row of cells, and the cells of a monotone path with
distinct rows and columns form such a chain, so by König's theorem (a
fractional matching of a bipartite graph is at most its largest matching)
the diagonal is at most ``step`` times the longest chain. Two modes holding
one tool never overlap at all (``cap = 0``).

:func:`overlap_bound` adds the constraint above for every pair of modes to
the zone-free relaxation (arms, travel, releases, precedence; tasks may take
longer than their modes), solved by CP-SAT with times rounded down
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
>>> caps = overlap_caps(m.build(), step=0.5)
>>> caps is not None and caps[(0, 1)] <= 2.5
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from scheduler.cpsat import essential_resources, resource_windows
from scheduler.problem import Problem

__all__ = ["overlap_bound", "overlap_caps", "overlap_model"]


def _cap(
    d1: float, d2: float, rects: list[tuple[float, float, float, float]], step: float
) -> float:
    """Longest chain of free cells (seconds) in the diagram of two modes."""
    n, m = max(1, math.ceil(d1 / step - 1e-9)), max(1, math.ceil(d2 / step - 1e-9))
    free = np.ones((n, m), dtype=bool)
    for s1, e1, s2, e2 in rects:
        i0, i1 = math.floor(s1 / step) + 1, math.ceil(e1 / step) - 2
        j0, j1 = math.floor(s2 / step) + 1, math.ceil(e2 / step) - 2
        if i0 <= i1 and j0 <= j1:
            free[i0 : i1 + 1, j0 : j1 + 1] = False
    f = np.zeros(m + 1)
    for i in range(n):  # f[j]: the longest chain in rows < i and columns < j
        g = f.copy()
        g[1:] = np.maximum(f[1:], f[:-1] + free[i])
        f = np.maximum.accumulate(g)
    return min(float(f[-1]) * step, d1, d2)


def overlap_caps(
    problem: Problem,
    step: float | None = None,
    max_cells: int = 160_000,
    max_pairs: int | None = None,
) -> dict[tuple[int, int], float] | None:
    """Per pair of modes ``(m1, m2)``, ``m1 < m2``, of different arms and tasks
    that share a resource: an upper bound (seconds) on the time both can
    progress at once (module docstring).

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
        Pairs that share no resource are left out (their cap is the shorter
        mode's duration).
    """
    p = problem
    if p.n_modes == 0:
        return {}
    longest = float(np.max(p.mode_duration))
    base = step if step is not None else max(longest / 400.0, 1e-6)
    use = resource_windows(p, essential_resources(p))
    Z2 = 2 * p.n_zones
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
    out: dict[tuple[int, int], float] = {}
    for m1, m2 in sorted(pairs):
        d1, d2 = float(p.mode_duration[m1]), float(p.mode_duration[m2])
        w1, w2 = by_mode[m1], by_mode[m2]
        common = [r for r in w1 if r in w2]
        if any(r >= Z2 for r in common):  # one tool: never at once
            out[(m1, m2)] = 0.0
            continue
        rects = [(s1, e1, s2, e2) for r in common for s1, e1 in w1[r] for s2, e2 in w2[r]]
        st = max(base, math.sqrt(d1 * d2 / max_cells))
        out[(m1, m2)] = _cap(d1, d2, rects, st)
    return out


def overlap_model(
    problem: Problem,
    horizon: float,
    caps: dict[tuple[int, int], float],
    unit: float,
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
    dur = [fl(float(d)) for d in p.mode_duration]
    mdl = cp_model.CpModel()
    S = [mdl.new_int_var(fl(float(p.task_release[t])), H, f"S{t}") for t in range(T)]
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
            a = int(p.mode_arm[m])
            first = fl(float(p.arm_available[a]) + p.setup_time(a, -1, t))
            mdl.add(S[t] >= first).only_enforce_if(x)
            iv[m] = mdl.new_optional_interval_var(S[t], size, E[t], x, f"I{m}")
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
            for i, m in enumerate(modes, start=1):
                t = int(p.mode_task[m])
                arcs.append((0, i, mdl.new_bool_var("")))
                arcs.append((i, 0, mdl.new_bool_var("")))
                arcs.append((i, i, ~X[m]))
                for j, m2 in enumerate(modes, start=1):
                    if m2 == m:
                        continue
                    t2 = int(p.mode_task[m2])
                    lit = mdl.new_bool_var("")
                    arcs.append((i, j, lit))
                    mdl.add(S[t2] >= E[t] + fl(p.setup_time(a, t, t2))).only_enforce_if(lit)
            arcs.append((0, 0, mdl.new_bool_var("")))
            mdl.add_circuit(arcs)
    pairs = 0
    for (m1, m2), cap in caps.items():
        t1, t2 = int(p.mode_task[m1]), int(p.mode_task[m2])
        need = fl(float(p.mode_duration[m1]) + float(p.mode_duration[m2]) - cap)
        if need <= max(dur[m1], dur[m2]):
            continue  # implied by the tasks' own lengths
        before, after, spread = (mdl.new_bool_var("") for _ in range(3))
        mdl.add_bool_or([before, after, spread, ~X[m1], ~X[m2]])
        mdl.add(S[t2] >= E[t1]).only_enforce_if(before)
        mdl.add(S[t1] >= E[t2]).only_enforce_if(after)
        lo_s, hi_e = mdl.new_int_var(0, H, ""), mdl.new_int_var(0, H, "")
        mdl.add_min_equality(lo_s, [S[t1], S[t2]])
        mdl.add_max_equality(hi_e, [E[t1], E[t2]])
        mdl.add(hi_e - lo_s >= need).only_enforce_if(spread)
        pairs += 1
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
        The bound (seconds; 0 when CP-SAT found no bound) and CP-SAT's status
        name (``"OPTIMAL"``: the relaxation is solved, its optimum is the
        bound; ``"SKIPPED"``: too many pairs).
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
    code = solver.solve(mdl)
    if code in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        return float(solver.best_objective_bound) / v["scale"], solver.status_name(code)
    return 0.0, solver.status_name(code)
