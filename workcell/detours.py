"""What OMPL detours buy a plan (SEEDS.md S2.6 geometric deadlock, S2.12).

An arm parked in another's way is a *geometric deadlock* (S2.6): the arm
allowed to move cannot follow its path. The coordinator may then answer
"continue with an alternative trajectory" (S2.12), and the compile prices
that answer ahead: the blocking oracle plans an OMPL detour around the
parked arm and charges its extra time (:mod:`workcell.oracle`). Compiled
with ``CompileOptions(detours=False)`` the same contact costs infinity, so a
plan must wait until the parked arm has left.

:func:`compare_detours` solves a cell both ways with the same solver, seed
and work limit and returns a :class:`DetourComparison`: the two makespans
(validated) and the detours the better plan takes. On the built-in cell
``parking`` the tree plan sends one arm around the other and ends earlier
than any plan found without detours (docs/workcell.md, "The parking cell").

Examples
--------
>>> from workcell import load_example
>>> c = compare_detours(load_example("parking"))
>>> c.detours >= 1 and c.makespan < c.makespan_without
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from multiarm.errors import UsageError
from scheduler import CpSatOptions, Schedule, SolverName, TreeOptions, solve, validate
from scheduler.schedule import blocking_required
from workcell.cell import Cell
from workcell.compile import CompiledCell, compile_cell

__all__ = ["DetourComparison", "compare_detours", "plan_detours"]

EVALUATIONS = 2000
"""Default work limit of the tree search (decoded schedules): the makespans
then depend on the seed only, not on the machine."""


@dataclass(frozen=True, slots=True)
class DetourComparison:
    """One cell solved with and without OMPL detours.

    Attributes
    ----------
    cell : str
    solver : str
    makespan : float
        Seconds, the plan compiled with detours (``inf`` when none was found).
    makespan_without : float
        Seconds, the plan compiled with ``detours=False`` (``inf`` when none).
    detours : int
        OMPL detours the plan with detours takes (paths around a parked arm).
    detour_tasks : tuple of str
        The tasks that take them.
    detour_seconds : float
        Extra seconds those detours cost the plan (the oracle's charge).
    """

    cell: str
    solver: str
    makespan: float
    makespan_without: float
    detours: int
    detour_tasks: tuple[str, ...]
    detour_seconds: float

    @property
    def saved(self) -> float:
        """Seconds the detours save (``makespan_without - makespan``; ``inf``
        when no plan without detours was found)."""
        return self.makespan_without - self.makespan

    def line(self) -> str:
        """One line for reports and the demo."""
        head = f"{self.cell}: detours ({self.solver})"
        if not math.isfinite(self.makespan):
            return f"{head}: no plan found"
        plural = "" if self.detours == 1 else "s"
        took = (
            f"{self.detours} OMPL detour{plural} around a parked arm "
            f"({', '.join(self.detour_tasks)}, +{self.detour_seconds:.2f} s)"
            if self.detours
            else "no detour"
        )
        if not math.isfinite(self.makespan_without):
            without = "without detours no plan was found"
        elif self.saved > 0:
            without = (
                f"without detours {self.makespan_without:.1f} s: the detours save "
                f"{self.saved:.1f} s ({self.saved / self.makespan_without:.0%})"
            )
        else:
            without = f"without detours {self.makespan_without:.1f} s"
        return f"{head}: {took}, makespan {self.makespan:.1f} s; {without}"


def plan_detours(compiled: CompiledCell, schedule: Schedule) -> dict[str, int]:
    """The OMPL detours a schedule takes: task name -> number of detour paths.

    A task is sent around an arm parked in its way when the blocking oracle
    charges it for that arm at its start (:func:`scheduler.schedule.blocking_required`);
    each run of contacts along its path is one detour path
    (:meth:`workcell.oracle.CellOracle.detours`).
    """
    p = compiled.problem
    seqs = schedule.sequences(p)
    out: dict[str, int] = {}
    for t in range(p.n_tasks):
        if float(schedule.blocking[t]) <= 0.0:
            continue
        _, who = blocking_required(p, schedule, t, seqs)
        m = int(schedule.mode[t])
        n = sum(len(compiled.oracle.detours(m, b, pose)) for b, pose in who)
        if n:
            out[p.task_names[t]] = n
    return out


def _solve(
    compiled: CompiledCell,
    solver: SolverName,
    evaluations: int,
    time_limit: float | None,
    seed: int,
) -> Schedule | None:
    if solver == "tree":
        result = solve(
            compiled,
            "tree",
            time_limit=time_limit,
            seed=seed,
            options=TreeOptions(max_evaluations=evaluations),
        )
    elif solver == "cpsat":
        result = solve(
            compiled,
            "cpsat",
            time_limit=time_limit if time_limit is not None else 10.0,
            seed=seed,
            options=CpSatOptions(workers=1),
        )
    else:
        result = solve(compiled, solver, time_limit=time_limit, seed=seed)
    return result.schedule


def compare_detours(
    cell: Cell,
    *,
    compiled: CompiledCell | None = None,
    solver: SolverName = "tree",
    evaluations: int = EVALUATIONS,
    time_limit: float | None = None,
    seed: int = 0,
) -> DetourComparison:
    """Solve ``cell`` with and without OMPL detours and compare the plans.

    Parameters
    ----------
    cell : Cell
    compiled : CompiledCell, optional
        ``cell`` already compiled with detours on (reused; the cell is
        compiled once more with ``detours=False``, the other options kept).
    solver : {"tree", "greedy", "cpsat"}
        The same solver, seed and limits for both.
    evaluations : int
        The tree search's work limit (decoded schedules): with no
        ``time_limit`` the result depends on the seed only.
    time_limit : float, optional
        Seconds per solve (CP-SAT: 10 s when not given; it runs on one
        worker).
    seed : int

    Returns
    -------
    DetourComparison

    Raises
    ------
    UsageError
        ``compiled`` is not ``cell`` compiled with detours on, or a bad solver.
    """
    if solver not in ("tree", "greedy", "cpsat"):
        raise UsageError(f"compare_detours: unknown solver {solver!r} (tree, greedy or cpsat)")
    if compiled is None:
        compiled = compile_cell(cell)
    elif compiled.cell is not cell or not compiled.options.detours:
        raise UsageError(
            "compare_detours: compiled must be this cell compiled with detours on "
            "(CompileOptions(detours=True), the default)"
        )
    without = compile_cell(cell, options=replace(compiled.options, detours=False))
    plan = _solve(compiled, solver, evaluations, time_limit, seed)
    other = _solve(without, solver, evaluations, time_limit, seed)
    mk = validate(compiled, plan) if plan is not None else math.inf
    mk_without = validate(without, other) if other is not None else math.inf
    taken = plan_detours(compiled, plan) if plan is not None else {}
    extra = (
        float(sum(float(plan.blocking[compiled.problem.task_names.index(t)]) for t in taken))
        if plan is not None
        else 0.0
    )
    return DetourComparison(
        cell.name,
        solver,
        float(mk),
        float(mk_without),
        int(sum(taken.values())),
        tuple(taken),
        extra,
    )
