"""What every solver returns: status, schedule, objective, bound, statistics."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from multiarm.errors import UsageError
from scheduler.plan import Plan
from scheduler.schedule import Schedule

__all__ = ["Progress", "Result", "SearchStats", "SolveStatus"]


@dataclass(frozen=True, slots=True)
class Progress:
    """One improvement of a running solve, handed to ``solve(..., progress=f)``.

    Attributes
    ----------
    elapsed : float
        Seconds since the solver's clock started.
    objective : float
        The incumbent's makespan (inf before the first schedule).
    bound : float
        The best lower bound known to the caller's solve.
    solver : str
    """

    elapsed: float
    objective: float
    bound: float
    solver: str


_LISTENER: list[Callable[[float, float], None] | None] = [None]
"""The progress listener of the running :func:`scheduler.solve` (set there)."""


class SolveStatus(StrEnum):
    """How a solve ended. A time limit that expires is a status, not an error."""

    OPTIMAL = "optimal"
    """The schedule is proven optimal (objective equals the bound)."""
    FEASIBLE = "feasible"
    """A valid schedule, not proven optimal."""
    INFEASIBLE = "infeasible"
    """Proven to have no valid schedule."""
    UNKNOWN = "unknown"
    """No schedule found and nothing proven within the limits."""


@dataclass
class SearchStats:
    """Search statistics (counts, and times in seconds from the solve's start)."""

    nodes: int = 0
    """Search-tree nodes expanded (beam and exact search)."""
    pruned: int = 0
    """Nodes cut by bounds, dominance or duplicates."""
    evaluations: int = 0
    """Complete schedules decoded (local search, restarts)."""
    first_time: float = math.nan
    """When the first valid schedule was found."""
    best_time: float = math.nan
    """When the best schedule was found."""
    first_objective: float = math.inf
    improvements: list[tuple[float, float]] = field(default_factory=list)
    """(time, objective) each time the incumbent improved."""
    phases: dict[str, float] = field(default_factory=dict)
    """Seconds spent per phase."""
    extra: dict[str, Any] = field(default_factory=dict)
    interrupted: bool = False
    """True when Ctrl-C (KeyboardInterrupt) stopped the search: the result
    holds the best schedule found until then."""
    listener: Callable[[float, float], None] | None = field(
        default_factory=lambda: _LISTENER[0], repr=False, compare=False
    )
    """Called with (time, objective) at every improvement (set by ``solve``)."""

    def record(self, t: float, objective: float) -> None:
        """Note an improved incumbent found ``t`` seconds in, and tell the listener.

        Parameters
        ----------
        t : float
            Seconds since the solve started.
        objective : float
            The new incumbent's makespan.
        """
        if self.listener is not None:
            self.listener(t, objective)
        if math.isnan(self.first_time):
            self.first_time = t
            self.first_objective = objective
        self.best_time = t
        self.improvements.append((t, objective))


@dataclass(frozen=True)
class Result:
    """The outcome of :func:`scheduler.solve`.

    Attributes
    ----------
    status : SolveStatus
    schedule : Schedule or None
        Validated by :func:`scheduler.validate` before being returned.
    objective : float
        The schedule's makespan (inf without a schedule).
    bound : float
        The best proven lower bound on the optimum.
    runtime : float
        Wall-clock seconds.
    solver : str
    seed : int
    stats : SearchStats
    """

    status: SolveStatus
    schedule: Schedule | None
    objective: float
    bound: float
    runtime: float
    solver: str
    seed: int
    stats: SearchStats

    @property
    def plan(self) -> Plan | None:
        """The schedule with its problem (None without a schedule).

        Raises
        ------
        UsageError
            The schedule is not bound to its problem (results of
            :func:`scheduler.solve` and :func:`scheduler.online.reschedule`
            always are).
        """
        if self.schedule is None:
            return None
        if self.schedule.bound_problem is None:
            raise UsageError("this result's schedule is not bound to its problem")
        return Plan(self.schedule.bound_problem, self.schedule)

    @property
    def gap(self) -> float:
        """``(objective - bound) / objective`` (0 when optimal, inf without a schedule)."""
        if self.schedule is None or not math.isfinite(self.objective):
            return math.inf
        if self.objective <= 0:
            return 0.0
        return max(0.0, (self.objective - self.bound) / self.objective)

    @classmethod
    def empty(cls, solver: str, seed: int, runtime: float, stats: SearchStats) -> Result:
        """The (optimal, empty) result of a problem without tasks."""
        return cls(SolveStatus.OPTIMAL, Schedule.empty(), 0.0, 0.0, runtime, solver, seed, stats)

    def to_dataframe(self) -> Any:
        """One row of the result: solver, status, objective, bound, gap, runtime, seed, counts.

        Returns
        -------
        pandas.DataFrame
            A single row (the schedule's rows come from ``Schedule.to_dataframe``).

        Raises
        ------
        UsageError
            pandas is not installed.
        """
        try:
            import pandas as pd
        except ImportError as exc:  # pragma: no cover - pandas is in the test extras
            raise UsageError("Result.to_dataframe needs pandas (pip install pandas)") from exc
        return pd.DataFrame(
            [
                {
                    "solver": self.solver,
                    "status": self.status.value,
                    "objective": self.objective,
                    "bound": self.bound,
                    "gap": self.gap,
                    "runtime": self.runtime,
                    "seed": self.seed,
                    "nodes": self.stats.nodes,
                    "evaluations": self.stats.evaluations,
                    "interrupted": self.stats.interrupted,
                }
            ]
        )

    def summary(self) -> str:
        """One line for logs."""
        return (
            f"{self.solver}: {self.status.value}, makespan {self.objective:.6g}, bound {self.bound:.6g}, "
            f"gap {100 * self.gap:.2f}%, {self.runtime:.3f}s, {self.stats.nodes} nodes, "
            f"{self.stats.evaluations} evaluations"
        )
