"""``multiarm demo``: the main job on the built-in cells.

Each cell is compiled once, solved by every solver
(:func:`workcell.pipeline.solve_limited`), and the tree search's plan is
run twice through :func:`workcell.pipeline.run_solved` (the simulate and
write steps of :func:`workcell.run_cell`): as planned, then with one arm
failing at 40 % of it (:func:`workcell.pipeline.failure_candidate`), so
that the coordinator re-solves. Exit status 1 when a run stopped, 3 when a
run as planned has failed tasks (the failures of the injected fault are the
point of the second run and do not count).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from multiarm import MultiarmError, __version__
from multiarm.errors import UsageError
from scheduler import lower_bound
from scheduler.solve import SolverName
from workcell.cell import EXAMPLES, Cell, load_example
from workcell.cli import args as common
from workcell.cli.output import EXIT_ERROR, EXIT_FAILURES, EXIT_OK, Progress, print_table
from workcell.compile import compile_cell
from workcell.detours import compare_detours
from workcell.pipeline import (
    CellRun,
    SolvedCell,
    StepCallback,
    failure_candidate,
    run_solved,
    solve_limited,
)
from workcell.sim.harness.options import SimOptions
from workcell.summary import ArmUsage, ZoneUsage, arm_usage, run_summary, side_by_side, zone_usage

__all__ = ["STEPS_PER_CELL", "add_arguments", "run"]

SOLVERS: tuple[SolverName, ...] = ("greedy", "tree", "cpsat")
STEPS_PER_CELL = 8
"""compile, three solves, then simulate and write twice."""
SECONDS_PER_CELL = 10.0
"""A rough allowance for one cell besides its solves (compile, two runs, their plots), seconds."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``demo``."""
    common.add_time_limit(p, 2.0, "per solver and cell")
    p.add_argument("--out", default="out", metavar="DIR", help="where plots, traces and metrics go")
    p.add_argument(
        "--cells",
        nargs="+",
        metavar="NAME",
        help=f"only these built-in cells ({', '.join(EXAMPLES)})",
    )
    common.add_seed(p)
    common.add_network(p)
    p.add_argument(
        "--no-monitor", action="store_true", help="run without the independent safety monitor"
    )
    p.add_argument(
        "--allow-failures",
        action="store_true",
        help="exit 0 even when a run as planned has failed tasks (default: exit status 3)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar or lines")


def run(args: argparse.Namespace) -> int:
    """Run ``demo``; the exit status."""
    names = list(dict.fromkeys(args.cells or EXAMPLES))
    unknown = [n for n in names if n not in EXAMPLES]
    if unknown:
        raise UsageError(
            f"--cells: unknown built-in cell {unknown[0]!r} (known: {', '.join(EXAMPLES)})"
        )
    args.solver = "tree"
    common.check_sim(args)
    out = common.out_dir(args.out)
    print(f"multiarm {__version__}: the built-in cells, compiled, scheduled and simulated\n")
    steps = len(names) * STEPS_PER_CELL
    about = len(names) * (len(SOLVERS) * args.time_limit + SECONDS_PER_CELL)
    print(
        f"{len(names)} cells x {STEPS_PER_CELL} steps = {steps} steps (compile; solve with "
        f"{', '.join(SOLVERS)}; simulate and write twice), about {math.ceil(about / 10) * 10:.0f} s\n"
    )
    cells = [load_example(name) for name in names]
    print_table(
        [c.summary() for c in cells], ["name", "arms", "arm types", "tasks", "zones", "tools"]
    )
    rows = []
    stopped = failed = False
    with Progress(steps, "demo", enabled=not args.no_progress) as bar:
        for cell in cells:
            row, runs = _demo_cell(cell, args, out / cell.name, bar)
            rows.append(row)
            stopped = stopped or len(runs) < 2
            failed = failed or ("nominal" in runs and not runs["nominal"].ok)
    print("\n== planned vs executed (the tree search's plan; then one arm failing at 40 % of it)")
    print_table(rows, list(rows[0]))
    print(f"\nplots, traces and metrics written to {out}/<cell>/{{nominal,arm_failure}}/")
    if stopped:
        print("status: runs stopped", file=sys.stderr)
        print("error: some runs stopped (see above)", file=sys.stderr)
        return EXIT_ERROR
    if failed and not args.allow_failures:
        print("status: tasks failed in a run as planned (see 'failed')")
        return EXIT_FAILURES
    print("status: ok, every run as planned did every task")
    return EXIT_OK


def _demo_cell(
    cell: Cell, args: argparse.Namespace, out: Path, bar: Progress
) -> tuple[dict[str, object], dict[str, CellRun]]:
    """One cell of the demo: its summary row, and its runs that completed."""
    print(f"\n== {cell.name}: {cell.description}")
    bar.step(f"{cell.name}: compile")
    cc = compile_cell(cell)
    p = cc.problem
    print(
        f"compiled in {cc.seconds:.1f} s: {p.n_tasks} tasks, {p.n_modes} modes "
        f"({len(cc.rejected)} (task, arm) pairs have none), {p.n_windows} zone windows; "
        f"lower bound {lower_bound(p):.1f} s"
    )
    rows, solved = [], {}
    for solver in SOLVERS:
        bar.step(f"{cell.name}: solve ({solver})")
        r, evaluations, cap = solve_limited(cc, solver, time_limit=args.time_limit, seed=args.seed)
        if r.schedule is not None:
            solved[solver] = SolvedCell(cc, r, cap, evaluations)
        rows.append(
            {
                "solver": solver,
                "status": r.status.value,
                "makespan (s)": f"{r.objective:.1f}" if r.schedule is not None else "none",
                "bound (s)": f"{r.bound:.1f}",
                "time (s)": f"{r.runtime:.1f}",
            }
        )
    print_table(rows, ["solver", "status", "makespan (s)", "bound (s)", "time (s)"])
    if cell.park == "last":  # arms wait where they worked: what OMPL detours buy (S2.6)
        print(compare_detours(cell, compiled=cc, seed=args.seed).line())
    if not solved:
        raise MultiarmError(f"cell {cell.name!r}: no solver found a schedule")
    best = min(solved.values(), key=lambda s: s.result.objective)
    sched = best.schedule
    print(f"\nbest schedule ({best.result.solver}, {best.result.objective:.1f} s) per arm:")
    print_table([a.row() for a in arm_usage(cc, sched)], ArmUsage.COLUMNS)
    print("per zone:")
    print_table([z.row() for z in zone_usage(p, sched)], ZoneUsage.COLUMNS)
    plan = solved.get("tree", best)  # the tree search's plan (the best when it found none)
    arm = failure_candidate(p, plan.schedule)
    at = round(0.4 * plan.schedule.makespan, 3)
    runs: dict[str, CellRun] = {}
    why: dict[str, str] = {}
    failure = [{"kind": "arm_failure", "arm": arm, "at": at}]
    for label, faults in (("nominal", None), ("arm_failure", failure)):
        try:
            runs[label] = run_solved(
                plan,
                seed=args.seed,
                faults=faults,
                medium=args.network,
                options=SimOptions(monitor=not args.no_monitor),
                out=out / label,
                progress=_steps(bar, f"{cell.name}, {label}"),
            )
        except MultiarmError as exc:  # e.g. the safety monitor: loud, and the demo goes on
            why[label] = str(exc)
            print(f"error: {cell.name}, {label} run: {exc}", file=sys.stderr)
    _print_runs(plan, arm, at, runs, why)
    return _summary_row(plan, arm, at, runs), runs


def _steps(bar: Progress, name: str) -> StepCallback:
    """A pipeline progress callback that shows each step on ``bar``."""

    def show(step: str, detail: str) -> None:
        bar.step(f"{name}: {step}")

    return show


def _print_runs(
    plan: SolvedCell, arm: str, at: float, runs: dict[str, CellRun], why: dict[str, str]
) -> None:
    """Planned, executed, and executed with the fault, side by side."""
    fault_col = f"{arm} fails at {at:g} s"
    print(
        f"\nsimulated the {plan.result.solver} plan, then with arm {arm!r} failing at {at:g} s"
        + "".join(f"; the {label} run stopped: {text}" for label, text in why.items())
        + ":"
    )
    columns = {
        col: run_summary(plan.compiled, plan.schedule, runs[label].sim)
        for label, col in (("nominal", "executed"), ("arm_failure", fault_col))
        if label in runs
    }
    if columns:
        print_table(side_by_side(columns), ["metric", "planned", *columns])


def _summary_row(
    plan: SolvedCell, arm: str, at: float, runs: dict[str, CellRun]
) -> dict[str, object]:
    """The cell's row of the closing table ("stopped" for a run that did not end)."""

    def figure(label: str, field: str) -> str:
        if label not in runs:
            return "stopped"
        m = runs[label].sim.metrics
        if field == "makespan":
            end = float(m.executed_makespan)
            return f"{end:.1f}" if math.isfinite(end) else "none"
        if field == "failed":
            return str(int(m.failed_tasks))
        if field == "resolves":
            return str(m.resolves)
        lat = np.asarray(m.resolve_latency, dtype=float)
        return f"{float(np.percentile(lat, 99)) * 1e3:.2f}" if lat.size else "-"

    p = plan.problem
    return {
        "cell": plan.compiled.cell.name,
        "arms": p.n_arms,
        "tasks": p.n_tasks,
        "planned (s)": f"{plan.schedule.makespan:.1f}",
        "executed (s)": figure("nominal", "makespan"),
        "failed": figure("nominal", "failed"),
        "arm failing": f"{arm} at {at:.1f} s",
        "executed, fault (s)": figure("arm_failure", "makespan"),
        "re-solves": figure("arm_failure", "resolves"),
        "re-solve p99 (ms)": figure("arm_failure", "p99"),
        "failed, fault": figure("arm_failure", "failed"),
    }
