"""``multiarm simulate CELL``: compile, schedule and simulate one cell (:func:`workcell.run_cell`).

Prints planned against executed figures (:func:`workcell.summary.run_summary`),
writes the run's files to ``--out`` (:data:`workcell.pipeline.RUN_FILES`)
and ends with a status line; failed tasks give exit status 3 unless
``--allow-failures``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from multiarm.errors import MultiarmError, UsageError
from scheduler import Problem, Schedule
from workcell.cli import args as common
from workcell.cli.output import EXIT_FAILURES, EXIT_OK, Progress, print_table, status_line
from workcell.pipeline import (
    MAX_FRAMES,
    RUN_FILES,
    CellRun,
    load_cell_or_example,
    load_faults,
    run_cell,
)
from workcell.sim.harness.options import SimOptions
from workcell.summary import run_summary

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``simulate``."""
    p.add_argument("cell", metavar="CELL", help="a cell file (.toml) or a built-in cell's name")
    common.add_solver(p)
    common.add_time_limit(p, 5.0)
    common.add_evaluations(p)
    common.add_seed(p)
    p.add_argument(
        "--faults", metavar="FILE", help="fault records to inject (.toml [[faults]] or .json list)"
    )
    common.add_network(p)
    p.add_argument(
        "--tick",
        type=float,
        metavar="SECONDS",
        help="model every controller tick of this period, at most 1 s (default: event level)",
    )
    p.add_argument(
        "--insertion",
        choices=["planned", "drawn"],
        default="planned",
        help="force-guided insertions: the planned tries, or tries drawn at run time (S1.7)",
    )
    p.add_argument("--out", metavar="DIR", help="output directory (default: ./out/CELLNAME)")
    p.add_argument(
        "--frames",
        type=int,
        default=0,
        metavar="N",
        help=f"also write N motion frames (at most {MAX_FRAMES})",
    )
    p.add_argument(
        "--no-monitor", action="store_true", help="run without the independent safety monitor"
    )
    p.add_argument(
        "--central-unit",
        action="store_true",
        help="also run the plan as a task program on the SUPERSIGMA central unit over MICROBUS (S1)",
    )
    p.add_argument(
        "--allow-failures",
        action="store_true",
        help="exit 0 even when tasks failed (default: exit status 3)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar or lines")


def run(args: argparse.Namespace) -> int:
    """Run ``simulate``; the exit status."""
    common.check_sim(args)
    cell = load_cell_or_example(args.cell)
    try:
        # read and checked against the cell (names) now; run_cell reads the file
        # again and checks the times against the compiled cell before the solve
        if args.faults:
            load_faults(args.faults, cell)
    except MultiarmError as exc:
        raise UsageError(f"--faults: {exc}") from None
    out = common.out_dir(args.out or str(Path("out") / cell.name))
    options = SimOptions(tick=args.tick, monitor=not args.no_monitor, insertion=args.insertion)
    with Progress(4, cell.name, enabled=not args.no_progress) as bar:
        result = run_cell(
            cell,
            solver=args.solver,
            time_limit=args.time_limit,
            evaluations=args.evaluations,
            seed=args.seed,
            faults=args.faults,
            medium=args.network,
            options=options,
            out=out,
            frames=args.frames,
            progress=lambda step, detail: bar.step(f"{step} ({detail})"),
        )
    _print_run(result, args, out)
    if args.central_unit:
        _print_central_unit(result.compiled.problem, result.sim.schedule)
    print(
        f"\nwrote {len(result.written)} files to {out}/: "
        + ", ".join(p.name for p in result.written[: len(RUN_FILES)])
    )
    print(status_line(result.failed_tasks, result.compiled.problem.n_tasks))
    if result.ok or args.allow_failures:
        return EXIT_OK
    print(
        f"error: {result.failed_tasks} tasks failed (exit status {EXIT_FAILURES}; "
        "--allow-failures accepts it)",
        file=sys.stderr,
    )
    return EXIT_FAILURES


def _print_run(result: CellRun, args: argparse.Namespace, out: Path) -> None:
    problem = result.compiled.problem
    print(
        f"{result.compiled.cell.name}: {problem.n_arms} arms, {problem.n_tasks} tasks; "
        f"compiled in {result.compiled.seconds:.1f} s; {result.result.summary()}"
    )
    if result.time_bound:
        fix = "raise --time-limit or lower --evaluations" if args.solver == "tree" else "use tree"
        print(
            f"note: the clock, not a work limit, stopped the {args.solver} solver before it proved "
            f"its plan optimal: the plan may differ from run to run ({fix})"
        )
    print(
        f"simulated (seed {args.seed}, medium {args.network!r}, "
        f"{'event level' if args.tick is None else f'tick {args.tick:g} s'}, "
        f"{'faults from ' + args.faults if args.faults else 'no faults'}): "
        f"{len(result.sim.trace)} trace events\n"
    )
    rows = run_summary(result.compiled, result.result.schedule or result.sim.schedule, result.sim)
    print_table(
        [{"metric": r.metric, "planned": r.planned, "executed": r.executed} for r in rows],
        ["metric", "planned", "executed"],
    )


def _print_central_unit(problem: Problem, schedule: Schedule) -> None:
    """The plan as a SUPERSIGMA task program: one box per arm on the CCU (S1.1, S1.9)."""
    from workcell.sim.control.supersigma.schedule import run_schedule

    run_ = run_schedule(problem, schedule)
    rep = run_.report
    print("\nunder the SUPERSIGMA central unit and MICROBUS (S1):")
    print_table(
        [
            {
                "planned (s)": f"{run_.planned_makespan:.2f}",
                "executed (s)": f"{run_.makespan:.2f}",
                "commands": rep.commands,
                "commands/s": f"{rep.rate:.2f}",
                "saturation": f"{100 * rep.saturation:.3f} %",
                "CCU idle": f"{100 * rep.idle_share:.1f} %",
                "lost": rep.lost,
            }
        ],
        ["planned (s)", "executed (s)", "commands", "commands/s", "saturation", "CCU idle", "lost"],
    )
