"""The greedy baseline: earliest-finish-time list scheduling (HEFT).

Tasks go in order of upward rank (mean duration plus the longest chain after
them), each placed in the mode that finishes first, at its earliest feasible
time. When list decoding finds no schedule (start zones dead-locking, see
:mod:`scheduler.fallback`), CP-SAT is asked instead, unless
``GreedyOptions(fallback=False)``.

Examples
--------
>>> from scheduler.fjsp import parse_fjsp
>>> p = parse_fjsp("2 2 1\\n2 1 1 3 2 1 4 2 2\\n1 2 1 2 2 1\\n")
>>> solve_greedy(p).objective
5.0
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from multiarm.errors import UsageError
from scheduler.problem import Problem
from scheduler.result import Result, SolveStatus
from scheduler.schedule import validate
from scheduler.start import begin

__all__ = ["GreedyOptions", "solve_greedy"]


@dataclass(frozen=True, slots=True)
class GreedyOptions:
    """Knobs of the greedy solver.

    Attributes
    ----------
    fallback : bool
        Ask CP-SAT (one worker, within the time limit) when list decoding
        finds no schedule (default True).

    Raises
    ------
    UsageError
        A field of the wrong type.
    """

    fallback: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.fallback, bool):
            raise UsageError(f"GreedyOptions.fallback must be a bool, got {self.fallback!r}")


def solve_greedy(
    problem: Problem,
    seed: int = 0,
    *,
    waits: bool = True,
    time_limit: float | None = None,
    options: GreedyOptions | None = None,
) -> Result:
    """Earliest-finish-time list scheduling (see the module docstring).

    Parameters
    ----------
    problem : Problem
    seed : int
        Used only by the CP-SAT fallback.
    waits : bool
        Whether schedules may wait at zone borders.
    time_limit : float or None
        Seconds for the fallback (the list pass itself is one decode).
    options : GreedyOptions or None

    Returns
    -------
    Result
        Status ``optimal`` when the makespan meets the lower bound.
    """
    opt = options or GreedyOptions()
    st = begin(problem, "greedy", seed, waits=waits)
    trivial = st.trivial()
    if trivial is not None:
        return trivial
    p, t0, stats, ev, lb, sol = problem, st.t0, st.stats, st.ev, st.lb, st.first
    stats.evaluations = ev.evaluations
    if sol is None:
        if opt.fallback:
            left = None if time_limit is None else time_limit - (time.perf_counter() - t0)
            from scheduler.fallback import exact_fallback

            res = exact_fallback(p, waits=waits, seed=seed, time_limit=left)
            stats.extra["fallback"] = "cpsat"
            stats.nodes = res.stats.nodes
            runtime = time.perf_counter() - t0
            if res.schedule is not None:
                stats.record(runtime, res.objective)
            return Result(
                res.status,
                res.schedule,
                res.objective,
                max(lb, res.bound)
                if res.schedule is None
                else min(max(lb, res.bound), res.objective),
                runtime,
                "greedy",
                seed,
                stats,
            )
        runtime = time.perf_counter() - t0
        return Result(SolveStatus.UNKNOWN, None, math.inf, lb, runtime, "greedy", seed, stats)
    sched = ev.schedule(sol)
    mk = validate(p, sched)
    runtime = time.perf_counter() - t0
    stats.record(runtime, mk)
    status = SolveStatus.OPTIMAL if mk <= lb + 1e-9 else SolveStatus.FEASIBLE
    return Result(status, sched, mk, min(lb, mk), runtime, "greedy", seed, stats)
