"""``multiarm schedule PROBLEM``: solve a problem file or a cell and print the schedule.

The file is read by :func:`workcell.check.load_schedulable` (a problem
``.json`` from ``save_problem``, an FJSPLIB file, or a cell compiled with
:func:`workcell.compile_cell`) and solved by
:func:`workcell.pipeline.solve_limited`, the solve step of
:func:`workcell.run_cell` with the same reproducible limits.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from multiarm.errors import MultiarmError, UsageError
from scheduler import Problem, Result, lower_bound
from scheduler import Progress as SolveProgress
from workcell.cli import args as common
from workcell.cli.output import EXIT_ERROR, EXIT_INTERRUPTED, EXIT_OK, Progress
from workcell.pipeline import MAX_EVALUATIONS, solve_limited

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``schedule``."""
    p.add_argument(
        "problem",
        metavar="PROBLEM",
        help="a problem (.json), an FJSPLIB file, a cell file (.toml) or a built-in cell's name",
    )
    common.add_solver(p)
    common.add_time_limit(p, 10.0)
    common.add_evaluations(p)
    common.add_seed(p, "for the solver")
    p.add_argument(
        "--no-waits",
        action="store_true",
        help="delay whole tasks instead of waiting at zone borders",
    )
    p.add_argument(
        "--out",
        metavar="FILE",
        help="write the schedule: .json (its data) or .csv (one row a task)",
    )
    p.add_argument("--verbose", action="store_true", help="print each improvement as it comes")
    p.add_argument(
        "--rows", type=int, default=50, metavar="N", help="print at most N rows of the schedule"
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar or lines")


def _check_out_file(name: str) -> None:
    """``--out`` checked before any work, so that a solved schedule is never lost."""
    out = Path(name)
    if out.is_dir():
        raise UsageError(f"--out: {str(out)!r} is a directory")
    if out.suffix.lower() not in (".json", ".csv"):
        raise UsageError(f"--out: {str(out)!r} must end in .json or .csv")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"--out: directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK):
        raise UsageError(f"--out: directory {str(parent)!r} is not writable")


def _compiled_note(name: str) -> str:
    """`` (a cell is compiled)`` where ``name`` is a cell (a ``.toml`` file or a
    built-in cell's name, as :func:`workcell.check.load_schedulable` reads it)."""
    from pathlib import Path

    from workcell.cell import EXAMPLES

    path = Path(name)
    cell = path.suffix.lower() == ".toml" or (not path.exists() and name in EXAMPLES)
    return " (a cell is compiled)" if cell else ""


def run(args: argparse.Namespace) -> int:
    """Run ``schedule``; the exit status."""
    from workcell.check import load_schedulable

    if args.out:
        _check_out_file(args.out)
    common.check_time_limit(args.time_limit)
    common.check_count("--rows", args.rows, 0, 10**9)
    if args.evaluations is not None and args.solver != "tree":
        raise UsageError("--evaluations is a work limit of the tree search (--solver tree)")
    common.check_count("--evaluations", args.evaluations, 1, MAX_EVALUATIONS)
    with Progress(2, "schedule", enabled=not args.no_progress) as bar:
        bar.step(f"read {args.problem}{_compiled_note(args.problem)}")
        problem: Problem = load_schedulable(args.problem)
        print(f"{problem!r}; lower bound {lower_bound(problem):.6g}", flush=True)
        bar.step(f"solve ({args.solver}, time limit {args.time_limit:g} s)")
        result = _solve(problem, args)
    print(result.summary())
    if result.stats.interrupted:  # Ctrl-C: the best schedule so far is printed, not written
        print("interrupted: multiarm schedule stopped (Ctrl-C)", file=sys.stderr)
        return EXIT_INTERRUPTED
    plan = result.plan
    if plan is not None and args.rows:
        print(plan.table(max_rows=args.rows))
    if plan is not None and args.out:
        try:
            plan.write(args.out)
        except MultiarmError:
            print(json.dumps(plan.to_dict()))  # keep the result
            raise
        print(f"schedule written to {args.out}")
    return EXIT_OK if result.schedule is not None else EXIT_ERROR


def _solve(problem: Problem, args: argparse.Namespace) -> Result:
    """The solve, printing each improvement with ``--verbose``."""

    def improved(pr: SolveProgress) -> None:
        print(
            f"  {pr.elapsed:9.3f} s  makespan {pr.objective:.6g}  bound {pr.bound:.6g}", flush=True
        )

    result, _evaluations, _cap = solve_limited(
        problem,
        args.solver,
        time_limit=args.time_limit,
        evaluations=args.evaluations,
        seed=args.seed,
        waits=not args.no_waits,
        on_improve=improved if args.verbose else None,
    )
    return result
