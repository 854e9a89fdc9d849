"""scheduler: the multi-arm task scheduler (SEEDS.md S2.10-S2.12).

* :class:`Model` builds an immutable, validated :class:`Problem` (arms,
  tasks, modes with zone windows and tools, setup times, an optional
  blocking oracle); :func:`read_fjsp` reads FJSP benchmark files.
* :func:`solve` runs a solver (``"tree"``, ``"greedy"``, ``"cpsat"``) and
  returns a :class:`Result`; :func:`validate` checks any :class:`Schedule`
  against every constraint and returns its makespan; :func:`lower_bound`
  bounds the optimum.
* :func:`reschedule` re-solves during execution from what a coordinator
  knows (tasks done, running, failed; arms out; parts late).
"""

from scheduler.bounds import LowerBounds, lower_bound, lower_bounds
from scheduler.fjsp import parse_fjsp, read_fjsp
from scheduler.greedy import GreedyOptions
from scheduler.io import (
    detect_format,
    load_problem,
    load_schedule,
    problem_from_dict,
    save_problem,
    schedule_from_dict,
)
from scheduler.plan import Plan
from scheduler.problem import BlockingOracle, HasProblem, Model, Problem, ProblemLike, Window
from scheduler.reschedule import FrozenTask, Rescheduled, reschedule
from scheduler.result import Progress, Result, SearchStats, SolveStatus
from scheduler.schedule import Reservation, Schedule, ScheduleError, validate
from scheduler.setup import FunctionSetup, MatrixSetup, NoSetup, Setup, TravelSetup
from scheduler.solve import REGISTRY, SOLVERS, CpSatOptions, SolverName, solve
from scheduler.tree import TreeOptions

__all__ = [
    "REGISTRY",
    "SOLVERS",
    "BlockingOracle",
    "CpSatOptions",
    "FrozenTask",
    "FunctionSetup",
    "GreedyOptions",
    "HasProblem",
    "LowerBounds",
    "MatrixSetup",
    "Model",
    "NoSetup",
    "Plan",
    "Problem",
    "ProblemLike",
    "Progress",
    "Rescheduled",
    "Reservation",
    "Result",
    "Schedule",
    "ScheduleError",
    "SearchStats",
    "Setup",
    "SolveStatus",
    "SolverName",
    "TravelSetup",
    "TreeOptions",
    "Window",
    "detect_format",
    "load_problem",
    "load_schedule",
    "lower_bound",
    "lower_bounds",
    "parse_fjsp",
    "problem_from_dict",
    "read_fjsp",
    "reschedule",
    "save_problem",
    "schedule_from_dict",
    "solve",
    "validate",
]
