"""One run of a sweep: build the problem, solve it through the scheduler, record the row."""

from __future__ import annotations

import math
import time
import traceback
from typing import Any

from scheduler import REGISTRY, Problem, Result, lower_bound, solve, validate
from scheduler.kernel import warm_up
from workcell.experiments.grid import Run, SolverConfig
from workcell.experiments.instances import benchmark_function, build_problem
from workcell.experiments.rows import benchmark_row, error_row, result_row

__all__ = ["run_one"]


def _solve(problem: Problem, config: SolverConfig, seed: int, waits: bool = True) -> Result:
    """Solve through :func:`scheduler.solve` with the configuration's typed options.

    Every option of a sweep file is a field of the solver's options class
    (:data:`scheduler.REGISTRY`), work limits included (``max_evaluations``,
    CP-SAT's ``max_deterministic_time``), so no run bypasses the one solve.
    ``waits`` is a generated instance's ``waits`` field (every solver of
    that instance alike).
    """
    options = REGISTRY[config.solver].options(**dict(config.options))
    return solve(
        problem,
        config.solver,  # type: ignore[arg-type]
        time_limit=config.time_limit,
        seed=seed,
        options=options,
        waits=waits,
    )


def run_one(run: Run) -> dict[str, Any]:
    """Execute one run and return its results row; never raises for the run's own failures.

    The problem is built (cached per process), solved, and the schedule
    checked by :func:`scheduler.validate`, whose makespan is recorded; any
    exception is recorded as status ``"error"`` with its type and message.
    The scheduler's compiled kernel is loaded before the solver's clock
    starts (the seconds it took, once per process, go to ``warmup_time``).

    A ``benchmark`` run calls its measurement function with
    ``seed=run.seed`` and the instance's parameters; what it returns (one
    dict, or a list of dicts: rows of a table) is recorded as JSON in the
    ``metrics`` column, with status ``"measured"``.

    Parameters
    ----------
    run : Run

    Returns
    -------
    dict
        One row (:data:`workcell.experiments.rows.COLUMNS`).
    """
    t0 = time.perf_counter()
    started = time.time()
    try:
        if run.instance.kind == "benchmark":
            fn = benchmark_function(run.instance)
            t0 = time.perf_counter()
            measured = fn(seed=run.seed, **dict(run.instance.params))
            return benchmark_row(run, measured, wall_time=time.perf_counter() - t0, started=started)
        problem = build_problem(run.instance)
        build = time.perf_counter() - t0
        warmup = _warm_up()
        waits = bool(dict(run.instance.params).get("waits", True))
        result = _solve(problem, run.config, run.seed, waits)
        if result.stats.interrupted:  # Ctrl-C cut the search short: not a result to keep
            raise KeyboardInterrupt
        makespan = validate(problem, result.schedule) if result.schedule is not None else math.inf
        return result_row(
            run,
            problem,
            result,
            makespan,
            lower_bound(problem),
            build_time=build,
            wall_time=time.perf_counter() - t0,
            started=started,
            warmup_time=warmup,
        )
    except Exception as exc:  # recorded, never lost: the sweep goes on
        return error_row(
            run,
            exc,
            "".join(traceback.format_exception(exc)[-3:]),
            wall_time=time.perf_counter() - t0,
            started=started,
        )


def _warm_up() -> float:
    """Load the scheduler's compiled kernel before a solver's clock starts (seconds taken)."""
    return float(warm_up(announce=lambda _msg: None))
