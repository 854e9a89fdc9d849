"""One interface for every solver: ``solve(problem, solver, time_limit, seed)``.

Solvers are registered in :data:`REGISTRY` (name -> options class and entry
point); each takes its typed, frozen options (:class:`~scheduler.tree.TreeOptions`,
:class:`~scheduler.greedy.GreedyOptions`, :class:`CpSatOptions`). The old
keyword options (``workers=``, ``hint=``, ``log=`` for CP-SAT; ``start=``
for the tree) are still accepted.

Examples
--------
>>> from scheduler.fjsp import parse_fjsp
>>> p = parse_fjsp("2 2 1\\n2 1 1 3 2 1 4 2 2\\n1 2 1 2 2 1\\n")
>>> r = solve(p, "tree", time_limit=5, seed=0)
>>> r.status.value, r.objective
('optimal', 5.0)
>>> solve(p, "greedy").objective >= r.objective
True
>>> seen = []
>>> _ = solve(p, "greedy", progress=seen.append)
>>> seen[0].solver, seen[0].objective
('greedy', 5.0)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, Literal

import numpy as np

from multiarm.errors import UsageError
from scheduler import _ctrl_c
from scheduler import result as _result
from scheduler.greedy import GreedyOptions, solve_greedy
from scheduler.problem import Problem, ProblemLike, as_problem
from scheduler.result import Progress, Result, SearchStats, SolveStatus
from scheduler.tree import TreeOptions

__all__ = [
    "REGISTRY",
    "SOLVERS",
    "CpSatOptions",
    "SolverName",
    "SolverSpec",
    "bind_result",
    "solve",
    "solve_greedy",
]

SolverName = Literal["tree", "greedy", "cpsat"]
SOLVERS: tuple[str, ...] = ("tree", "greedy", "cpsat")
MAX_SEED = 2**31 - 1


@dataclass(frozen=True, slots=True)
class CpSatOptions:
    """Knobs of the CP-SAT solver.

    Attributes
    ----------
    workers : int
        CP-SAT search workers (>= 1).
    hint : bool or Schedule
        ``True``: hint the earliest-finish-time schedule; ``False``: none; a
        Schedule: start from it.
    log : bool
        CP-SAT's search log on stdout.
    max_deterministic_time : float or None
        A work limit in CP-SAT's deterministic time units (> 0): with
        ``workers=1`` the result then depends on the seed only, whatever
        the machine's load.

    Raises
    ------
    UsageError
        A field out of range.
    """

    workers: int = 2
    hint: Any = True
    log: bool = False
    max_deterministic_time: float | None = None

    def __post_init__(self) -> None:
        if isinstance(self.workers, bool) or not isinstance(self.workers, int) or self.workers < 1:
            raise UsageError(f"CpSatOptions.workers must be an int >= 1, got {self.workers!r}")
        if not isinstance(self.log, bool):
            raise UsageError(f"CpSatOptions.log must be a bool, got {self.log!r}")
        dt = self.max_deterministic_time
        if dt is not None and (
            isinstance(dt, bool)
            or not isinstance(dt, int | float)
            or not (math.isfinite(dt) and dt > 0)
        ):
            raise UsageError(
                f"CpSatOptions.max_deterministic_time must be finite and > 0, or None, got {dt!r}"
            )


def _run_tree(
    p: Problem, tl: float | None, seed: int, waits: bool, opt: Any, extra: dict[str, Any]
) -> Result:
    from scheduler.tree import solve_tree

    return solve_tree(p, tl, seed, waits=waits, options=opt, **extra)


def _run_greedy(
    p: Problem, tl: float | None, seed: int, waits: bool, opt: Any, extra: dict[str, Any]
) -> Result:
    return solve_greedy(p, seed, waits=waits, time_limit=tl, options=opt)


def _run_cpsat(
    p: Problem, tl: float | None, seed: int, waits: bool, opt: Any, extra: dict[str, Any]
) -> Result:
    from scheduler.cpsat import solve_cpsat

    o = opt or CpSatOptions()
    return solve_cpsat(
        p,
        tl,
        seed,
        waits=waits,
        workers=o.workers,
        hint=o.hint,
        log=o.log,
        max_deterministic_time=o.max_deterministic_time,
    )


@dataclass(frozen=True, slots=True)
class SolverSpec:
    """A registered solver.

    Attributes
    ----------
    options : type
        Its frozen options dataclass.
    run : callable
        ``run(problem, time_limit, seed, waits, options, extra) -> Result``.
    extra : tuple of str
        Keyword arguments that are not options (e.g. the tree's ``start``).
    """

    options: type
    run: Callable[[Problem, float | None, int, bool, Any, dict[str, Any]], Result]
    extra: tuple[str, ...] = ()


REGISTRY: dict[str, SolverSpec] = {
    "tree": SolverSpec(TreeOptions, _run_tree, ("start",)),
    "greedy": SolverSpec(GreedyOptions, _run_greedy),
    "cpsat": SolverSpec(CpSatOptions, _run_cpsat),
}


def bind_result(result: Result, problem: Problem) -> Result:
    """``result`` with its schedule bound to ``problem`` (see :meth:`Schedule.bind`).

    Parameters
    ----------
    result : Result
    problem : Problem

    Returns
    -------
    Result
        The same result; its schedule (when there is one) carries its problem.
    """
    if result.schedule is None or result.schedule.bound_problem is problem:
        return result
    from dataclasses import replace

    return replace(result, schedule=result.schedule.bind(problem))


def _warm_up() -> None:
    """Compile the kernel before any solver's clock starts (when the kernel offers it)."""
    from scheduler import kernel

    warm = getattr(kernel, "warm_up", None)
    if warm is not None:
        warm()


def solve(
    problem: ProblemLike,
    solver: SolverName = "tree",
    time_limit: float | None = 10.0,
    seed: int = 0,
    *,
    waits: bool = True,
    options: object = None,
    progress: Callable[[Progress], None] | None = None,
    **legacy: object,
) -> Result:
    """Solve ``problem`` and return a :class:`~scheduler.result.Result`.

    Parameters
    ----------
    problem : Problem or object with a ``.problem`` Problem
        A :class:`Problem`, or anything carrying one as ``.problem`` (a
        ``workcell.CompiledCell``: its problem is solved).
    solver : {"tree", "greedy", "cpsat"}
        ``tree`` (default): the anytime tree search with pruning and local
        improvement; ``greedy``: the earliest-finish-time list-scheduling
        baseline; ``cpsat``: the exact OR-Tools CP-SAT model. When list
        decoding finds no schedule, ``tree`` and ``greedy`` ask CP-SAT
        (:mod:`scheduler.fallback`).
    time_limit : float or None
        Seconds, finite and > 0; ``None`` means no limit.
    seed : int
        In 0..2**31-1. Every random choice derives from it.
    waits : bool
        Whether schedules may insert waits at zone borders (S2.6).
    options : TreeOptions, GreedyOptions, CpSatOptions or None
        The solver's typed options (defaults when None).
    progress : callable or None
        Called with a :class:`~scheduler.result.Progress` at every improved
        incumbent.
    **legacy
        The former keyword options: ``start=Solution`` (tree); ``workers``,
        ``hint``, ``log`` (cpsat).

    Returns
    -------
    Result
        Its schedule, when there is one, has passed :func:`validate`. After
        Ctrl-C, the best found so far with ``stats.interrupted = True``.

    Raises
    ------
    UsageError
        An unknown solver or option, options of another solver, a time limit
        that is not finite and > 0, or a seed outside 0..2**31-1.
    """
    problem = as_problem(problem, "solve")
    if time_limit is not None:
        if isinstance(time_limit, bool) or not isinstance(time_limit, int | float | np.number):
            raise UsageError(f"time_limit must be a number of seconds or None, got {time_limit!r}")
        if not (math.isfinite(float(time_limit)) and time_limit > 0):
            raise UsageError(
                f"time_limit must be finite and > 0 seconds, or None for no limit, "
                f"got {time_limit!r}"
            )
        time_limit = float(time_limit)
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool):
        raise UsageError(f"seed must be an int, got {seed!r}")
    if not 0 <= int(seed) <= MAX_SEED:
        raise UsageError(f"seed must be in 0..{MAX_SEED}, got {seed!r}")
    seed = int(seed)
    spec = REGISTRY.get(solver)
    if spec is None:
        raise UsageError(f"unknown solver {solver!r} (known: {', '.join(SOLVERS)})")
    extra = {k: legacy.pop(k) for k in spec.extra if k in legacy}
    names = {f.name for f in fields(spec.options)}
    bad = set(legacy) - names
    if bad:
        allowed = sorted(names | set(spec.extra) | {"options"})
        raise UsageError(
            f"solver {solver!r} has no option {sorted(bad)[0]!r} (it takes: {', '.join(allowed)})"
        )
    if options is not None and not isinstance(options, spec.options):
        raise UsageError(
            f"solver {solver!r} takes options={spec.options.__name__}(...), "
            f"got {type(options).__name__}"
        )
    if legacy:
        from dataclasses import replace

        options = replace(options or spec.options(), **legacy)  # type: ignore[type-var]
    t0 = time.perf_counter()
    # Ctrl-C is noted for the whole solve, so that one whose KeyboardInterrupt
    # is lost on the way still ends the search (scheduler._ctrl_c)
    with _ctrl_c.guard() as ctrl_c:
        try:
            # a KeyboardInterrupt inside numba's compiler can break its state
            # for the rest of the process: a Ctrl-C there is raised after it
            with _ctrl_c.deferred():
                _warm_up()
            listener = None
            if progress is not None:
                from scheduler.bounds import lower_bound

                lb = lower_bound(problem)

                def listener(t: float, objective: float) -> None:
                    progress(Progress(t, objective, min(lb, objective), solver))

            _result._LISTENER[0] = listener
            res = bind_result(spec.run(problem, time_limit, seed, waits, options, extra), problem)
            if ctrl_c.hit:
                # a Ctrl-C came during the solve and its exception was lost or
                # only noted (a finaliser, a deferred block that had just ended):
                # the caller must still see it
                res.stats.interrupted = True
            return res
        except KeyboardInterrupt:
            # solvers that keep a best schedule return it themselves; here nothing was kept
            stats = SearchStats(interrupted=True)
            from scheduler.bounds import lower_bound

            return Result(
                SolveStatus.UNKNOWN,
                None,
                math.inf,
                lower_bound(problem),
                time.perf_counter() - t0,
                solver,
                seed,
                stats,
            )
        finally:
            _result._LISTENER[0] = None
