"""A lower bound from the busiest resources: CP-SAT on a relaxation that keeps them exactly.

The zone-free relaxation (:func:`scheduler.reference.relaxation_bound`)
drops every zone; the one-machine bounds (:func:`scheduler.bounds.resource_bounds`)
look at one resource at a time with the arms left out. On a compiled cell
whose plans wait for a few busy zones (``cell8``: a station's shared zone and
the space-grid blocks in front of it) neither sees how the arms, the modes
and those resources constrain each other. This relaxation keeps, besides
the arms (with travel), releases, precedence and tools, the ``k`` busiest
essential resources (exclusive zones and shared-zone movement) with every
window in them, and lets an arm wait anywhere:

* a task lasts at least its mode (``E >= S + duration``);
* each merged window ``(s, e)`` of a kept resource in the chosen mode is an
  interval of length ``e - s`` that starts no earlier than ``S + s`` and
  ends no later than ``E - (duration - e)``, and the windows of one mode keep
  their order (each starts at least ``s2 - s1`` after the one before); a
  move window in a shared zone is cut at the mode's borders inside it, one
  interval per stretch (an arm that waits there stands still, and another
  may move in the zone meanwhile);
* no two intervals of one kept resource overlap (for shared zones: their
  move windows).

**Valid for every schedule** :func:`scheduler.validate` **accepts.** A real
use of an exclusive zone's window starts at ``S + s`` plus the waits before
it, lasts ``e - s`` plus the waits inside it, and ends ``duration - e`` plus
later waits and detours before the task's end, so its first ``e - s``
seconds are such an interval; a real move between two borders is one
stretch of exactly its length (waits happen only at borders); uses of a resource by different arms never overlap and one arm
does one task at a time; the resources left out and the start zones only
remove schedules. Times map to ``floor(x / unit)`` and every length,
offset, duration, travel and release is rounded down (``floor(a + b) >=
floor(a) + floor(b)``), so the image of every valid schedule is a solution,
and CP-SAT's proven bound (also when it stops early,
:func:`scheduler.cpsat.cpsat_bound`) times the unit bounds the makespan.

Examples
--------
>>> from scheduler.generate import random_problem
>>> from scheduler.bounds import lower_bound
>>> p = random_problem(3, 8, 2, 1, seed=4, zone_fraction=1.0)
>>> b, status = busy_resources_bound(p, None, workers=1)  # no time limit: solved
>>> status, b >= lower_bound(p) - 1e-6
('OPTIMAL', True)
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from multiarm.errors import UsageError
from scheduler.cpsat import (
    add_arm_sequences,
    add_relaxed_tasks,
    cpsat_bound,
    essential_resources,
    resource_windows,
    solve_or_interrupt,
)
from scheduler.problem import Problem

__all__ = ["busiest_resources", "busy_resources_bound", "busy_resources_model"]


def busiest_resources(problem: Problem, k: int) -> list[int]:
    """The ``k`` essential zone resources (exclusive zones, shared-zone movement) with
    the largest one-machine bound (:func:`scheduler.bounds.resource_bounds`), then the
    largest total window length over all modes; tools are kept anyway.

    Parameters
    ----------
    problem : Problem
    k : int

    Returns
    -------
    list of int
        Resource numbers (:meth:`scheduler.timing.Shapes.resource_name`).
    """
    from scheduler.bounds import resource_bounds

    p = problem
    keep = essential_resources(p)
    zones = {r for r in keep if r < 2 * p.n_zones}
    one = {rb.resource: rb.bound for rb in resource_bounds(p)}
    total: dict[int, float] = {}
    for r, modes in resource_windows(p, frozenset(zones)).items():
        total[r] = sum(e - s for ws in modes.values() for s, e in ws)
    ranked = sorted(zones, key=lambda r: (-one.get(r, 0.0), -total.get(r, 0.0), r))
    return ranked[: max(0, k)]


def busy_resources_model(
    problem: Problem, horizon: float, resources: list[int], unit: float, *, travel: bool = True
) -> tuple[Any, dict[str, Any]]:
    """The relaxation of :func:`busy_resources_bound` as a CP-SAT model.

    Parameters
    ----------
    problem : Problem
    horizon : float
        A makespan some valid schedule reaches (seconds).
    resources : list of int
        The zone resources kept (tools are always kept).
    unit : float
        Seconds per model unit (times rounded down).
    travel : bool
        Keep the travel between an arm's tasks (a circuit per arm); False: a
        no-overlap per arm only (travel into a task from anywhere still
        counts at its least), a weaker relaxation but a much smaller model.

    Returns
    -------
    (CpModel, dict)
        Variables ``S``, ``E``, ``X``, ``makespan``, ``scale`` and
        ``windows`` (the number of window intervals).
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
    if travel:
        add_arm_sequences(mdl, p, iv, X, S, E, fl)
    else:
        for a in range(p.n_arms):
            ivs = [iv[int(m)] for m in np.flatnonzero(p.mode_arm == a)]
            if len(ivs) > 1:
                mdl.add_no_overlap(ivs)
    tools: dict[int, list[Any]] = {}
    for m in range(p.n_modes):
        for k in p.mode_tools[m]:
            tools.setdefault(int(k), []).append(iv[m])
    for ivs in tools.values():
        if len(ivs) > 1:
            mdl.add_no_overlap(ivs)
    # the kept resources: one optional interval per merged window of a mode
    per_res: dict[int, list[Any]] = {}
    per_mode: dict[int, list[tuple[float, Any]]] = {}
    n_windows = 0
    Z = p.n_zones
    for r, modes in resource_windows(p, frozenset(resources)).items():
        for m, ws in modes.items():
            t = int(p.mode_task[m])
            d = float(p.mode_duration[m])
            if r >= Z:  # movement: an arm standing at a border inside does not move
                ws = _split(ws, p.shapes[m].borders)
            for s, e in ws:
                y = mdl.new_int_var(0, H, "")
                length = fl(e - s)
                mdl.add(y >= S[t] + fl(s)).only_enforce_if(X[m])
                mdl.add(y + length <= E[t] - fl(d - e)).only_enforce_if(X[m])
                per_res.setdefault(r, []).append(
                    mdl.new_optional_fixed_size_interval_var(y, length, X[m], "")
                )
                per_mode.setdefault(m, []).append((s, y))
                n_windows += 1
    for ivs in per_res.values():
        if len(ivs) > 1:
            mdl.add_no_overlap(ivs)
    for m, ws in per_mode.items():  # a mode's windows keep their order
        ws.sort(key=lambda w: w[0])
        for (s1, y1), (s2, y2) in itertools.pairwise(ws):
            mdl.add(y2 >= y1 + fl(s2 - s1)).only_enforce_if(X[m])
    mdl.add_cumulative(master, [1] * T, p.n_arms)
    mk = mdl.new_int_var(0, H, "makespan")
    mdl.add_max_equality(mk, E)
    mdl.minimize(mk)
    return mdl, {"S": S, "E": E, "X": X, "makespan": mk, "scale": scale, "windows": n_windows}


def _split(
    windows: list[tuple[float, float]], borders: tuple[float, ...]
) -> list[tuple[float, float]]:
    """Cut windows at the borders strictly inside them (where an arm may wait).

    >>> _split([(0.0, 4.0), (5.0, 6.0)], (2.0, 5.0))
    [(0.0, 2.0), (2.0, 4.0), (5.0, 6.0)]
    """
    out = []
    for s, e in windows:
        cuts = [b for b in borders if s < b < e]
        out += list(itertools.pairwise([s, *cuts, e]))
    return out


def busy_resources_bound(
    problem: Problem,
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    k: int = 6,
    unit: float = 0.01,
    workers: int = 2,
    max_deterministic_time: float | None = None,
    horizon: float | None = None,
    travel: bool = True,
) -> tuple[float, str]:
    """A lower bound of the makespan: CP-SAT on the relaxation keeping the ``k`` busiest
    zone resources (module docstring).

    Parameters
    ----------
    problem : Problem
    time_limit : float or None
        Seconds for CP-SAT.
    seed : int
    k : int
        Zone resources kept (:func:`busiest_resources`); tools are always kept.
    unit : float
        Time unit of the model (seconds; times rounded down).
    workers : int
    max_deterministic_time : float or None
        CP-SAT's work limit (repeatable where the wall time is not).
    horizon : float or None
        A makespan some valid schedule reaches (None: the earliest-finish-time
        schedule's).
    travel : bool
        Keep the travel between an arm's tasks (:func:`busy_resources_model`).

    Returns
    -------
    (float, str)
        The bound (seconds; 0 when CP-SAT proved nothing) and CP-SAT's status
        name (``"OPTIMAL"``: the relaxation is solved).

    Raises
    ------
    UsageError
        ``k`` is not an integer ``>= 0`` or ``unit`` not a number ``> 0``.
    """
    from ortools.sat.python import cp_model

    p = problem
    if isinstance(k, bool) or not isinstance(k, int) or k < 0:
        raise UsageError(f"busy_resources_bound: k must be an integer >= 0, got {k!r}")
    if not (isinstance(unit, int | float) and math.isfinite(unit) and unit > 0):
        raise UsageError(f"busy_resources_bound: unit must be a number > 0 (seconds), got {unit!r}")
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
    mdl, v = busy_resources_model(p, horizon, busiest_resources(p, k), unit, travel=travel)
    solver = cp_model.CpSolver()
    if time_limit is not None:
        solver.parameters.max_time_in_seconds = max(0.01, time_limit)
    if max_deterministic_time is not None:
        solver.parameters.max_deterministic_time = max_deterministic_time
    solver.parameters.num_workers = workers
    solver.parameters.random_seed = seed
    code = solve_or_interrupt(solver, mdl)  # Ctrl-C stays Python's
    return cpsat_bound(solver, code) / v["scale"], solver.status_name(code)
