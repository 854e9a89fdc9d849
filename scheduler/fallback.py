"""The exact fallback of the heuristics: when list decoding finds no schedule.

List decoding can dead-lock where a schedule exists: two arms that start in
exclusive zones, each of whose first task enters the other's start zone,
each wait for the other to leave first (no list order places either). The
heuristics then hand the problem to CP-SAT (one worker), which models the
start zones exactly (and, with a blocking oracle, pads each mode with the
largest detour the oracle can charge it, so its solutions stay valid).
``unknown`` is left for a search that ran out of its budget.

Examples
--------
>>> from scheduler import Model, Window
>>> m = Model()
>>> _ = m.add_zone("ZA"), m.add_zone("ZB")
>>> _ = m.add_arm("A", start_zones=["ZA"]), m.add_arm("B", start_zones=["ZB"])
>>> _ = m.add_task("ta"), m.add_mode("ta", "A", 2.0, windows=[Window("ZB", 0.5, 1.5)])
>>> _ = m.add_task("tb"), m.add_mode("tb", "B", 2.0, windows=[Window("ZA", 0.5, 1.5)])
>>> r = exact_fallback(m.build(), waits=True, seed=0, time_limit=None)
>>> r.status.value, r.objective
('optimal', 2.0)
"""

from __future__ import annotations

from scheduler.problem import Problem
from scheduler.result import Result

__all__ = ["DTIME_PER_EVALUATION", "exact_fallback"]

DTIME_PER_EVALUATION = 1e-3
"""CP-SAT deterministic time granted per decode of a heuristic's work limit."""


def exact_fallback(
    problem: Problem,
    *,
    waits: bool,
    seed: int,
    time_limit: float | None,
    max_evaluations: int | None = None,
) -> Result:
    """Solve ``problem`` with CP-SAT on one worker within what is left of a budget.

    Parameters
    ----------
    problem : Problem
    waits : bool
        Whether schedules may wait at zone borders.
    seed : int
    time_limit : float or None
        Seconds left (None: no wall-clock limit).
    max_evaluations : int or None
        The heuristic's work limit: converted to CP-SAT deterministic time
        (:data:`DTIME_PER_EVALUATION` each, at least 1), so that a
        work-limited run stays repeatable.

    Returns
    -------
    Result
        CP-SAT's result (its schedule validated).
    """
    from scheduler.cpsat import solve_cpsat

    dtime = None
    if max_evaluations is not None:
        dtime = max(1.0, DTIME_PER_EVALUATION * max_evaluations)
    limit = None if time_limit is None else max(0.05, time_limit)
    return solve_cpsat(problem, limit, seed, waits=waits, workers=1, max_deterministic_time=dtime)
