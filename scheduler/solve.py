"""One interface for every solver: ``solve(problem, solver, time_limit, seed)``.

Examples
--------
>>> from scheduler.fjsp import parse_fjsp
>>> p = parse_fjsp("2 2 1\\n2 1 1 3 2 1 4 2 2\\n1 2 1 2 2 1\\n")
>>> r = solve(p, "tree", time_limit=5, seed=0)
>>> r.status.value, r.objective
('optimal', 5.0)
>>> solve(p, "greedy").objective >= r.objective
True
"""

from __future__ import annotations

import math
import time
from typing import Literal

import numpy as np

from multiarm.errors import UsageError
from scheduler.bounds import lower_bound
from scheduler.problem import Problem
from scheduler.result import Result, SearchStats, SolveStatus
from scheduler.schedule import validate
from scheduler.search import Evaluator, priority_order

__all__ = ["SOLVERS", "SolverName", "solve", "solve_greedy"]

SolverName = Literal["tree", "greedy", "cpsat"]
SOLVERS: tuple[str, ...] = ("tree", "greedy", "cpsat")


def solve_greedy(problem: Problem, seed: int = 0, *, waits: bool = True) -> Result:
    """Earliest-finish-time list scheduling (HEFT): tasks in order of upward
    rank (mean duration plus the longest chain after them), each placed in
    the mode that finishes first, at its earliest feasible time."""
    t0 = time.perf_counter()
    p = problem
    stats = SearchStats()
    lb = lower_bound(p)
    if p.n_tasks == 0:
        return Result.empty("greedy", seed, time.perf_counter() - t0, stats)
    ev = Evaluator(p, waits=waits)
    sol = ev.evaluate(priority_order(p))
    stats.evaluations = ev.evaluations
    runtime = time.perf_counter() - t0
    if sol is None:
        return Result(SolveStatus.UNKNOWN, None, math.inf, lb, runtime, "greedy", seed, stats)
    sched = ev.schedule(sol)
    mk = validate(p, sched)
    stats.record(runtime, mk)
    status = SolveStatus.OPTIMAL if mk <= lb + 1e-9 else SolveStatus.FEASIBLE
    return Result(status, sched, mk, min(lb, mk), runtime, "greedy", seed, stats)


def solve(
    problem: Problem,
    solver: SolverName = "tree",
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    waits: bool = True,
    **options: object,
) -> Result:
    """Solve ``problem`` and return a :class:`~scheduler.result.Result`.

    Parameters
    ----------
    problem : Problem
    solver : {"tree", "greedy", "cpsat"}
        ``tree`` (default): the anytime tree search with pruning and local
        improvement; ``greedy``: the earliest-finish-time list-scheduling
        baseline; ``cpsat``: the exact OR-Tools CP-SAT model.
    time_limit : float or None
        Seconds; ``None`` means no limit (the tree search then runs its
        exact phase to the end on small problems).
    seed : int
        Every random choice derives from it: the same seed gives the same
        schedule (for ``cpsat``, with the same number of workers and no time
        limit cutting the search).
    waits : bool
        Whether schedules may insert waits at zone borders (S2.6).
    **options
        Solver-specific: ``tree`` takes ``options=TreeOptions(...)`` and
        ``start=Solution``; ``cpsat`` takes ``workers``, ``hint``, ``log``.

    Returns
    -------
    Result
        Its schedule, when there is one, has passed :func:`validate`.

    Raises
    ------
    UsageError
        An unknown solver name or option, or a negative time limit.
    """
    if time_limit is not None and not (time_limit >= 0):
        raise UsageError(f"time_limit must be >= 0 seconds or None, got {time_limit!r}")
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool):
        raise UsageError(f"seed must be an int, got {seed!r}")
    seed = int(seed)
    if solver == "tree":
        from scheduler.tree import solve_tree

        allowed = {"options", "start"}
        _check(options, allowed, solver)
        return solve_tree(problem, time_limit, seed, waits=waits, **options)  # type: ignore[arg-type]
    if solver == "greedy":
        _check(options, set(), solver)
        return solve_greedy(problem, seed, waits=waits)
    if solver == "cpsat":
        from scheduler.cpsat import solve_cpsat

        _check(options, {"workers", "hint", "log"}, solver)
        return solve_cpsat(problem, time_limit, seed, waits=waits, **options)  # type: ignore[arg-type]
    raise UsageError(f"unknown solver {solver!r} (known: {', '.join(SOLVERS)})")


def _check(options: dict[str, object], allowed: set[str], solver: str) -> None:
    bad = set(options) - allowed
    if bad:
        raise UsageError(
            f"solver {solver!r} has no option {sorted(bad)[0]!r} (it takes: {', '.join(sorted(allowed)) or 'none'})"
        )
