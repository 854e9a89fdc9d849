"""The exact reference: an OR-Tools CP-SAT model of the same problem.

Variables and constraints (times scaled to integers, see below):

* per task ``t``: start ``S_t``, end ``E_t``, a literal ``x_m`` per mode with
  ``sum_m x_m = 1``; per mode, a wait ``w_mj >= 0`` at each zone border ``j``
  (when waits are allowed) and ``E_t = S_t + d_m + sum_j w_mj`` if ``x_m``;
* arms: the optional mode intervals ``[S_t, E_t)`` of an arm never overlap —
  ``NoOverlap`` without setup times, otherwise a ``Circuit`` over the arm's
  modes whose arcs enforce ``S_t' >= E_t + setup(t, t')`` (and the setup from
  the initial pose after the depot);
* exclusive zones: ``NoOverlap`` over the occupancy intervals
  ``[S_t + s + W<=(s), S_t + e + W<(e))`` of every window in the zone (and
  ``[0, departure)`` of an arm that starts inside it); shared zones:
  ``NoOverlap`` over the movement pieces between borders; tools:
  ``NoOverlap`` over ``[S_t, E_t)`` of the modes holding them
  (:mod:`scheduler.timing` defines these intervals);
* releases ``S_t >= r_t``, precedence ``S_t >= E_p``, arm availability;
* a redundant ``Cumulative`` of capacity (number of arms) over the task
  intervals, and ``makespan >= E_t``; minimise the makespan.

Times are multiplied by the smallest power of ten (up to 10^6) that makes
every duration, offset, release, availability and setup an integer; then the
model is exact and CP-SAT's bound is a bound of the problem. Otherwise times
are rounded outwards (starts down, ends up) at a 1e-3 resolution: the
schedules stay valid but the bound falls back to :func:`lower_bound`.
The search is hinted with the earliest-finish-time schedule that also sets
the horizon (``hint=False`` to start cold). The blocking oracle is not
modelled: with one, the solution's modes and
start order are decoded again chronologically with the oracle's detours, and
CP-SAT's bound (of a relaxation) is kept.
"""

from __future__ import annotations

import itertools
import math
import time
from typing import Any

import numpy as np

from scheduler.problem import Problem
from scheduler.result import Result, SolveStatus
from scheduler.schedule import Schedule, ScheduleError, validate
from scheduler.start import begin

__all__ = ["build_model", "integer_scale", "solve_cpsat"]


def _integral(values: Any, scale: float) -> bool:
    v = np.asarray(values, dtype=float) * scale
    v = v[np.isfinite(v)]
    return bool(np.all(np.abs(v - np.round(v)) <= 1e-9 * np.maximum(1.0, np.abs(v))))


def integer_scale(problem: Problem) -> tuple[float, bool]:
    """(scale, exact): the power of ten that makes the data integral, if any."""
    p = problem
    data = [p.mode_duration, p.win_start, p.win_end, p.task_release, p.arm_available]
    setups = []
    if not p._setup.zero:
        for a in range(p.n_arms):
            tasks = np.flatnonzero(p.mode_of[a] >= 0)
            if len(tasks) * (len(tasks) + 1) > 2_000_000:
                return 1000.0, False
            for prev in (-1, *tasks.tolist()):
                setups.append(p.setup_row(a, prev)[tasks])
    allv = (
        np.concatenate([np.ravel(d) for d in data] + setups)
        if setups or any(len(d) for d in data)
        else np.zeros(0)
    )
    for k in range(7):
        s = 10.0**k
        if _integral(allv, s) and (allv.size == 0 or np.max(np.abs(allv)) * s < 2**40):
            return s, True
    return 1000.0, False


def build_model(
    problem: Problem, horizon: float, *, waits: bool = True, pad: Any = None
) -> tuple[Any, dict[str, Any]]:
    """The CP-SAT model and its variables (see the module docstring).

    ``pad`` : (M,) float or None, seconds added at the end of each mode (the
    tools held through it): the largest detour a blocking oracle can charge
    the mode, so that every solution stays valid whatever arms are parked.
    """
    from ortools.sat.python import cp_model

    p = problem
    scale, exact = integer_scale(p)

    def lo(x: float) -> int:
        return math.floor(x * scale + 1e-9)

    def hi(x: float) -> int:
        return math.ceil(x * scale - 1e-9)

    H = hi(horizon) + 1
    mdl = cp_model.CpModel()
    T = p.n_tasks
    S = [mdl.new_int_var(hi(float(p.task_release[t])), H, f"S{t}") for t in range(T)]
    E = [mdl.new_int_var(0, H, f"E{t}") for t in range(T)]
    X: dict[int, Any] = {}
    W: dict[int, list[Any]] = {}
    mode_iv: dict[int, Any] = {}
    res_iv: dict[int, list[Any]] = {}
    master = []
    shapes = p.shapes
    for t in range(T):
        lits = []
        size_t = mdl.new_int_var(0, H, f"D{t}")
        master.append(mdl.new_interval_var(S[t], size_t, E[t], f"T{t}"))
        for m in p.task_modes[t]:
            x = mdl.new_bool_var(f"x{m}")
            X[m] = x
            lits.append(x)
            sh = shapes[m]
            nb = len(sh.borders)
            ws = [mdl.new_int_var(0, H, f"w{m}_{j}") for j in range(nb)] if (waits and nb) else []
            W[m] = ws
            d = hi(sh.duration + (float(pad[m]) if pad is not None else 0.0))
            total = d + sum(ws)
            mdl.add(size_t == total).only_enforce_if(x)
            mdl.add(E[t] == S[t] + total).only_enforce_if(x)
            a = int(p.mode_arm[m])
            mdl.add(S[t] >= hi(float(p.arm_available[a]) + p.setup_time(a, -1, t))).only_enforce_if(
                x
            )
            mode_iv[m] = mdl.new_optional_interval_var(S[t], size_t, E[t], x, f"I{m}")
            bidx = {b: j for j, b in enumerate(sh.borders)}

            def shift(
                off: float,
                inclusive: bool,
                sh: Any = sh,
                ws: list[Any] = ws,
                bidx: dict[float, int] = bidx,
            ) -> Any:
                return (
                    sum(ws[bidx[b]] for b in sh.borders if (b < off or (inclusive and b == off)))
                    if ws
                    else 0
                )

            for r, s, e in sh.exclusive:
                st = mdl.new_int_var(0, H, f"zs{m}_{r}_{s}")
                en = mdl.new_int_var(0, H, f"ze{m}_{r}_{s}")
                mdl.add(st == S[t] + lo(s) + shift(s, True)).only_enforce_if(x)
                mdl.add(en == S[t] + hi(e) + shift(e, False)).only_enforce_if(x)
                res_iv.setdefault(r, []).append(
                    mdl.new_optional_interval_var(st, mdl.new_int_var(0, H, ""), en, x, f"Z{m}_{r}")
                )
            for r, s, e in sh.moves:
                cuts = [b for b in sh.borders if s < b < e] if ws else []
                pts = [s, *cuts, e]
                for p0, p1 in itertools.pairwise(pts):
                    st = mdl.new_int_var(0, H, "")
                    mdl.add(st == S[t] + lo(p0) + shift(p0, True)).only_enforce_if(x)
                    size = hi(p1) - lo(p0)
                    res_iv.setdefault(r, []).append(
                        mdl.new_optional_interval_var(
                            st, size, mdl.new_int_var(0, H, ""), x, f"M{m}_{r}"
                        )
                    )
            for r in sh.tools:
                res_iv.setdefault(r, []).append(mode_iv[m])
        mdl.add_exactly_one(lits)
        for q in p.task_preds[t]:
            mdl.add(S[t] >= E[q])
    # arms
    for a in range(p.n_arms):
        modes = [int(m) for m in np.flatnonzero(p.mode_arm == a)]
        if not modes:
            continue
        if p._setup.zero:
            mdl.add_no_overlap([mode_iv[m] for m in modes])
        else:
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
                    mdl.add(S[t2] >= E[t] + hi(p.setup_time(a, t, t2))).only_enforce_if(lit)
            arcs.append((0, 0, mdl.new_bool_var("")))
            mdl.add_circuit(arcs)
    # arms standing in exclusive start zones until they leave
    for a in range(p.n_arms):
        zs = [z for z in p.arm_start_zones[a] if p.zone_exclusive[z]]
        if not zs:
            continue
        modes = [int(m) for m in np.flatnonzero(p.mode_arm == a)]
        dep = mdl.new_int_var(0, H, f"dep{a}")
        if modes:
            cands = []
            for m in modes:
                t = int(p.mode_task[m])
                e_m = mdl.new_int_var(-H, H, "")
                mdl.add(e_m == S[t] - hi(p.setup_time(a, -1, t))).only_enforce_if(X[m])
                mdl.add(e_m == H).only_enforce_if(~X[m])
                cands.append(e_m)
            mdl.add_min_equality(dep, cands)
        else:
            mdl.add(dep == H)
        for z in zs:
            res_iv.setdefault(z, []).append(mdl.new_interval_var(0, dep, dep, f"start{a}_{z}"))
    for ivs in res_iv.values():
        if len(ivs) > 1:
            mdl.add_no_overlap(ivs)
    mdl.add_cumulative(master, [1] * T, p.n_arms)
    mk = mdl.new_int_var(0, H, "makespan")
    mdl.add_max_equality(mk, E)
    mdl.minimize(mk)
    return mdl, {"S": S, "E": E, "X": X, "W": W, "makespan": mk, "scale": scale, "exact": exact}


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
) -> Result:
    """Solve with CP-SAT (see the module docstring).

    ``hint``: a Schedule to start from (e.g. the previous plan when
    re-solving); ``True`` (default) hints the earliest-finish-time schedule
    that also sets the horizon — without it CP-SAT often finds no first
    solution on problems with setup circuits; ``False`` hints nothing."""
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
    pad = oracle_padding(p)
    if pad is not None:  # every task padded with its largest detour: a serial bound
        horizon = float(
            np.max(p.task_release)
            + np.sum([max(p.mode_duration[m] + pad[m] for m in ms) for ms in p.task_modes])
            + float(np.max(p.arm_available))
        ) * 2 + (first.makespan if first is not None else 1e6)
    mdl, v = build_model(p, horizon, waits=waits, pad=pad)
    scale, exact = v["scale"], v["exact"] and p.blocking is None
    if hint is True:
        # with an oracle, the greedy schedule's detours only lengthen tasks: it
        # is still a solution of the relaxed model
        hint = ev.schedule(first) if first is not None else None
    if hint is not None and hint is not False:
        for t in range(p.n_tasks):
            mdl.add_hint(v["S"][t], round(float(hint.start[t]) * scale))
            for m in p.task_modes[t]:
                mdl.add_hint(v["X"][m], int(m == int(hint.mode[t])))
            for j, w in enumerate(v["W"][int(hint.mode[t])]):
                mdl.add_hint(w, round(float(hint.waits[t][j]) * scale))
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

    if on_solver is not None:  # e.g. to keep it for stop_search() from another thread
        on_solver(solver)
    # the per-solution callback takes the GIL: a run racing Python code in
    # another thread goes without it (measured 0.55 s vs 0.87 s to optimal)
    code = solver.solve(mdl, _Progress()) if callback else solver.solve(mdl)
    runtime = time.perf_counter() - t0
    stats.nodes = int(solver.num_branches)
    stats.extra["conflicts"] = int(solver.num_conflicts)
    stats.extra["scale"] = scale
    bound = max(
        lb,
        solver.best_objective_bound / scale
        if exact and code in (cp_model.OPTIMAL, cp_model.FEASIBLE)
        else lb,
    )
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
    if code not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        return Result(SolveStatus.UNKNOWN, None, math.inf, lb, runtime, "cpsat", seed, stats)
    T = p.n_tasks
    modes = np.array(
        [next(m for m in p.task_modes[t] if solver.boolean_value(v["X"][m])) for t in range(T)]
    )
    starts = np.array([solver.value(v["S"][t]) / scale for t in range(T)])
    sched: Schedule | None = None
    if p.blocking is None or pad is not None:
        ws = [
            np.array([solver.value(w) / scale for w in v["W"][int(modes[t])]])
            if v["W"][int(modes[t])]
            else np.zeros(len(p.shapes[int(modes[t])].borders))
            for t in range(T)
        ]
        cand = Schedule.from_starts(
            p, modes, starts, ws, None if pad is None else pad[modes].astype(float)
        )
        try:
            validate(p, cand)
            sched = cand
        except ScheduleError as exc:  # rounding (inexact scale) or a non-metric setup corner
            stats.extra["redecoded"] = str(exc)
    if sched is None or p.blocking is not None:
        # with an oracle: decode the order and modes again with the detours actually charged
        order = np.lexsort((np.arange(T), starts)).astype(np.int64)
        sol = ev.evaluate(order, modes.astype(np.int64))
        if sol is not None:
            again = ev.schedule(sol)
            if sched is None or validate(p, again) < validate(p, sched):
                sched = again
        if sched is None:
            return Result(SolveStatus.UNKNOWN, None, math.inf, bound, runtime, "cpsat", seed, stats)
    mk = validate(p, sched)
    optimal = (
        code == cp_model.OPTIMAL
        and exact
        and abs(mk - solver.objective_value / scale) <= 1e-6 * max(1, mk)
    )
    status = SolveStatus.OPTIMAL if optimal or mk <= bound + 1e-9 else SolveStatus.FEASIBLE
    if optimal:
        bound = mk
    return Result(status, sched, mk, min(bound, mk), runtime, "cpsat", seed, stats)
