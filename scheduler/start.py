"""What every solver does first: its clock, the trivial case, the first schedule and the bound.

:func:`begin` starts a solver's clock, builds the :class:`~scheduler.search.Evaluator`,
decodes the earliest-finish-time (HEFT) list -- the greedy's answer, the tree
search's first incumbent and CP-SAT's hint and horizon -- and computes the
lower bound (:func:`scheduler.bounds.lower_bound`), timing it in
``stats.phases["bound"]``. A problem without tasks needs none of it:
:meth:`SolverStart.trivial` is then the (optimal, empty) result.

Examples
--------
>>> from scheduler.fjsp import parse_fjsp
>>> p = parse_fjsp("2 2 1\\n2 1 1 3 2 1 4 2 2\\n1 2 1 2 2 1\\n")
>>> s = begin(p, "greedy", seed=0)
>>> s.trivial() is None, s.first.makespan >= s.lb
(True, True)
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from scheduler.bounds import lower_bound
from scheduler.problem import Problem
from scheduler.result import Result, SearchStats
from scheduler.search import Evaluator, Solution, priority_order

__all__ = ["SolverStart", "begin"]


@dataclass
class SolverStart:
    """A solver's state after :func:`begin`.

    Attributes
    ----------
    problem : Problem
    solver : str
    seed : int
    t0 : float
        ``time.perf_counter()`` when the solver's clock started.
    stats : SearchStats
        The run's statistics (the bound's time already in ``phases``).
    ev : Evaluator
        The decoder of the problem (waits as asked).
    first : Solution or None
        The HEFT list decoded (None: it cannot be placed, or no tasks).
    lb : float
        The lower bound (0 without tasks).
    """

    problem: Problem
    solver: str
    seed: int
    t0: float
    stats: SearchStats
    ev: Evaluator
    first: Solution | None
    lb: float

    def elapsed(self) -> float:
        """Seconds since the solver's clock started.

        Returns
        -------
        float
        """
        return time.perf_counter() - self.t0

    def trivial(self) -> Result | None:
        """The (optimal, empty) result of a problem without tasks, else None.

        Returns
        -------
        Result or None
        """
        if self.problem.n_tasks:
            return None
        return Result.empty(self.solver, self.seed, self.elapsed(), self.stats)


def begin(
    problem: Problem,
    solver: str,
    seed: int,
    *,
    waits: bool = True,
    record_first: bool = False,
) -> SolverStart:
    """Start a solver (module docstring): clock, evaluator, first schedule, bound.

    Parameters
    ----------
    problem : Problem
    solver : str
        The solver's name (for results).
    seed : int
    waits : bool
        Whether schedules may wait at zone borders.
    record_first : bool
        Record the first schedule as the run's first incumbent in ``stats``
        (solvers whose answer it can be).

    Returns
    -------
    SolverStart
    """
    t0 = time.perf_counter()
    stats = SearchStats()
    ev = Evaluator(problem, waits=waits)
    first: Solution | None = None
    lb = 0.0
    if problem.n_tasks:
        first = ev.evaluate(priority_order(problem))
        if first is not None and record_first:
            stats.record(time.perf_counter() - t0, first.makespan)
        ph = time.perf_counter()
        lb = lower_bound(problem)
        stats.phases["bound"] = time.perf_counter() - ph
    return SolverStart(problem, solver, seed, t0, stats, ev, first, lb)
