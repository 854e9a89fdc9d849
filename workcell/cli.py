"""The ``multiarm`` console command: a thin layer over the library.

It parses arguments, calls the library and prints; errors of ours are printed
as one line (``file:line:col: message``) with exit status 1, never as a
traceback.

Sub-commands:

``demo``
    The main job on the built-in cells: compile each, schedule it with every
    solver, validate, print per-arm and per-zone summaries, simulate the tree
    search's plan, then again with one arm failing at 40 % of it (a re-solve);
    a summary table, and plots, traces and metrics written to ``./out``.
``simulate CELL``
    Compile, schedule and simulate one cell (a cell file or a built-in cell's
    name), optionally with faults (``--faults FILE``) and a network medium
    (``--network``); print planned vs executed; write plots, ``trace.json``,
    ``metrics.json`` and ``tasks.csv`` to ``--out``.
``check FILE...``
    Parse and validate files (:mod:`workcell.check`): problem JSON,
    schedules (validated against ``--problem``) and FJSPLIB instances are
    recognised by content; then by extension ``.tdl`` (trajectories),
    ``.sdl`` (zones), ``.json`` and ``.toml`` (a task set when it holds a
    ``tasks`` list, else a cell file, compiled and explained: per arm the
    tasks it can do and why not the others, zones and tools with their users,
    warnings); a built-in cell's name is explained too. ``--json`` prints one
    machine-readable report.
``schedule PROBLEM``
    Solve a scheduling problem (``.json`` written by ``save_problem``, an
    FJSPLIB file, a cell file, or a built-in cell's name) and print the
    result and the schedule as a table; ``--verbose`` prints improvements as
    they come; ``--out`` writes the schedule as JSON or CSV by extension.
``bench``
    Run the benchmark scripts (``--quick`` for a smoke run).
``sweep FILE``
    Run a sweep file (:mod:`workcell.experiments`) in a local process pool,
    or on a Dask cluster with ``--dask-address ADDRESS``; resumes an
    interrupted sweep.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from multiarm import MultiarmError, __version__
from multiarm.errors import UsageError

__all__ = ["main"]


def _print_table(rows: list[dict[str, Any]], columns: Sequence[str]) -> None:
    table = [[str(r[c]) for c in columns] for r in rows]
    widths = [max(len(c), *(len(row[i]) for row in table)) for i, c in enumerate(columns)]
    print("  ".join(c.ljust(w) for c, w in zip(columns, widths, strict=True)))
    print("  ".join("-" * w for w in widths))
    for row in table:
        print("  ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)))


def cmd_demo(args: argparse.Namespace) -> int:
    """The main job on the built-in cells: compile, schedule with every solver,
    simulate the tree search's plan, then again with one arm failing."""
    from workcell.cell import EXAMPLES, load_example

    names = list(dict.fromkeys(args.cells or EXAMPLES))
    unknown = [n for n in names if n not in EXAMPLES]
    if unknown:
        raise UsageError(
            f"--cells: unknown built-in cell {unknown[0]!r} (known: {', '.join(EXAMPLES)})"
        )
    _check_sim_args(args)
    out = _out_dir(args.out)
    print(f"multiarm {__version__}: the built-in cells, compiled, scheduled and simulated\n")
    cells = [load_example(name) for name in names]
    _print_table(
        [c.summary() for c in cells], ["name", "arms", "arm types", "tasks", "zones", "tools"]
    )
    rows = []
    complete = True
    for cell in cells:
        row, ok = _demo_cell(cell, args, out / cell.name)
        rows.append(row)
        complete = complete and ok
    print("\n== planned vs executed (the tree search's plan; then one arm failing at 40 % of it)")
    _print_table(rows, list(rows[0]))
    print(f"\nplots, traces and metrics written to {out}/<cell>/{{nominal,arm_failure}}/")
    if not complete:
        print("error: some runs stopped (see above)", file=sys.stderr)
        return 1
    return 0


def _demo_cell(cell: Any, args: argparse.Namespace, out: Path) -> tuple[dict[str, Any], bool]:
    """One cell of the demo: its summary row, and whether both runs completed."""
    import time

    from scheduler import lower_bound, solve, validate
    from workcell.sim.options import SimOptions
    from workcell.sim.run import simulate

    print(f"\n== {cell.name}: {cell.description}")
    t0 = time.perf_counter()
    cc = _compile_with_bar(cell)
    p = cc.problem
    print(
        f"compiled in {time.perf_counter() - t0:.1f} s: {p.n_tasks} tasks, {p.n_modes} modes "
        f"({len(cc.rejected)} (task, arm) pairs have none), {p.n_windows} zone windows; "
        f"lower bound {lower_bound(p):.1f} s"
    )
    rows = []
    best = None
    plans = {}
    for solver in ("greedy", "tree", "cpsat"):
        r = solve(p, solver, time_limit=args.time_limit, seed=args.seed)
        ok = r.schedule is not None
        mk = validate(p, r.schedule) if r.schedule is not None else math.inf
        if r.schedule is not None:
            plans[solver] = r.schedule
            if best is None or mk < best[0]:
                best = (mk, r.schedule, solver)
        rows.append(
            {
                "solver": solver,
                "status": r.status.value,
                "makespan (s)": f"{mk:.1f}" if ok else "none",
                "bound (s)": f"{r.bound:.1f}",
                "time (s)": f"{r.runtime:.1f}",
            }
        )
    _print_table(rows, ["solver", "status", "makespan (s)", "bound (s)", "time (s)"])
    if best is None:
        raise MultiarmError(f"cell {cell.name!r}: no solver found a schedule")
    mk, sched, solver = best
    print(f"\nbest schedule ({solver}, {mk:.1f} s) per arm:")
    arm_rows = []
    arm_of = sched.arms(p)
    for a, name in enumerate(p.arm_names):
        tasks = [t for t in range(p.n_tasks) if int(arm_of[t]) == a]
        busy = sum(float(sched.end[t] - sched.start[t]) for t in tasks)
        arm_rows.append(
            {
                "arm": name,
                "type": cell.arms[a].kind,
                "tasks": len(tasks),
                "busy (s)": f"{busy:.1f}",
                "utilisation": f"{busy / mk:.0%}" if mk > 0 else "-",
            }
        )
    _print_table(arm_rows, ["arm", "type", "tasks", "busy (s)", "utilisation"])
    print("per zone:")
    zone_rows = []
    reservations = sched.reservations(p)
    grid = [name for name in p.zone_names if name.startswith("grid_")]
    for z, name in enumerate(p.zone_names):
        if name.startswith("grid_"):
            continue
        exclusive = bool(p.zone_exclusive[z])
        kind = "zone" if exclusive else "move"
        res = [r for r in reservations if r.kind == kind and r.resource == name]
        held = sum(r.end - r.start for r in res)
        zone_rows.append(
            {
                "zone": name,
                "policy": "exclusive" if exclusive else "shared",
                "uses": len(res),
                "occupied or moved in (s)": f"{held:.1f}",
            }
        )
    if grid:  # the compile's space-grid blocks (workcell.geometry.reach), summed
        res = [r for r in reservations if r.kind == "zone" and r.resource.startswith("grid_")]
        zone_rows.append(
            {
                "zone": f"space grid ({len(grid)} blocks)",
                "policy": "exclusive",
                "uses": len(res),
                "occupied or moved in (s)": f"{sum(r.end - r.start for r in res):.1f}",
            }
        )
    _print_table(zone_rows, ["zone", "policy", "uses", "occupied or moved in (s)"])
    # simulate the tree search's plan (the best plan when the tree found none)
    plan_by = "tree" if "tree" in plans else solver
    plan = plans[plan_by]
    arm = _failing_arm(p, plan)
    at = round(0.4 * plan.makespan, 3)
    runs: dict[str, tuple[Any, float]] = {}
    stopped: dict[str, str] = {}
    bar = _progress(2, f"{cell.name}: simulate")
    try:
        for label, faults in (
            ("nominal", None),
            ("arm_failure", [{"kind": "arm_failure", "arm": arm, "at": at}]),
        ):
            from workcell.sim.faults import FaultPlan

            plan_faults = FaultPlan.from_dicts(faults) if faults else None
            t1 = time.perf_counter()
            try:
                result = simulate(
                    cc,
                    plan,
                    seed=args.seed,
                    faults=plan_faults,
                    medium=args.network,
                    options=SimOptions(monitor=not args.no_monitor),
                )
            except MultiarmError as exc:  # e.g. the safety monitor: loud, and the demo goes on
                stopped[label] = str(exc)
                print(f"error: {cell.name}, {label} run: {exc}", file=sys.stderr)
            else:
                wall = time.perf_counter() - t1
                _write_run(_out_dir(str(out / label)), cc, plan, result)
                runs[label] = (result, wall)
            bar.update(1)
    finally:
        bar.close()
    fault_col = f"{arm} fails at {at:g} s"
    print(
        f"\nsimulated the {plan_by} plan, then with arm {arm!r} failing at {at:g} s"
        + "".join(f"; the {label} run stopped: {why}" for label, why in stopped.items())
        + ":"
    )
    merged: dict[str, dict[str, Any]] = {}
    for label, col in (("nominal", "executed"), ("arm_failure", fault_col)):
        if label not in runs:
            continue
        for row in _sim_rows(p, plan, runs[label][0]):
            entry = merged.setdefault(
                row["metric"],
                {"metric": row["metric"], "planned": row["planned"], "executed": "", fault_col: ""},
            )
            entry[col] = row["executed"]
    if merged:
        table = [r for r in merged.values() if not r["metric"].startswith("  waits in")]
        waits = [r for r in merged.values() if r["metric"].startswith("  waits in")]
        at_waits = next(i for i, r in enumerate(table) if r["metric"] == "zone waits (s)") + 1
        table[at_waits:at_waits] = waits
        _print_table(table, ["metric", "planned", "executed", fault_col])

    def figure(label: str, field: str) -> str:
        if label not in runs:
            return "stopped"
        m = runs[label][0].metrics
        if field == "makespan":
            return f"{float(m.executed_makespan):.1f}"
        if field == "failed":
            return str(_count(m.failed_tasks))
        if field == "resolves":
            return str(m.resolves)
        return _ms(m.resolve_latency, 99)

    return {
        "cell": cell.name,
        "arms": p.n_arms,
        "tasks": p.n_tasks,
        "planned (s)": f"{plan.makespan:.1f}",
        "executed (s)": figure("nominal", "makespan"),
        "failed": figure("nominal", "failed"),
        "arm failing": f"{arm} at {at:.1f} s",
        "executed, fault (s)": figure("arm_failure", "makespan"),
        "re-solves": figure("arm_failure", "resolves"),
        "re-solve p99 (ms)": figure("arm_failure", "p99"),
        "failed, fault": figure("arm_failure", "failed"),
    }, not stopped


def cmd_check(args: argparse.Namespace) -> int:
    """Validate each file and explain cells (:mod:`workcell.check`)."""
    from workcell.check import check_files

    return check_files(args.files, args.problem, as_json=args.json)


def cmd_schedule(args: argparse.Namespace) -> int:
    """Solve a problem file or a cell and print (and optionally write) the schedule."""
    import json

    from scheduler import Progress, lower_bound, solve

    if args.out:  # checked before any work, so a solved schedule is never lost
        out = Path(args.out)
        if out.is_dir():
            raise UsageError(f"--out: {str(out)!r} is a directory")
        if out.suffix.lower() not in (".json", ".csv"):
            raise UsageError(f"--out: {str(out)!r} must end in .json or .csv")
        parent = out.parent if str(out.parent) else Path(".")
        if not parent.is_dir():
            raise UsageError(f"--out: directory {str(parent)!r} does not exist")
        if not os.access(parent, os.W_OK):
            raise UsageError(f"--out: directory {str(parent)!r} is not writable")
    if not (math.isfinite(args.time_limit) and args.time_limit > 0):
        raise UsageError(
            f"--time-limit must be a finite number of seconds > 0, got {args.time_limit}"
        )
    if args.rows < 0:
        raise UsageError(f"--rows must be >= 0, got {args.rows}")
    from workcell.check import load_schedulable

    problem = load_schedulable(args.problem)
    print(f"{problem!r}; lower bound {lower_bound(problem):.6g}")

    def improved(pr: Progress) -> None:
        print(
            f"  {pr.elapsed:9.3f} s  makespan {pr.objective:.6g}  bound {pr.bound:.6g}", flush=True
        )

    result = solve(
        problem,
        args.solver,
        time_limit=args.time_limit,
        seed=args.seed,
        waits=not args.no_waits,
        progress=improved if args.verbose else None,
    )
    print(result.summary())
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
    return 0 if result.schedule is not None else 1


# ------------------------------------------------------------ simulate and the demo's runs


def _progress(total: int, desc: str) -> Any:
    """A progress bar on stderr (hidden when stderr is not a terminal)."""
    from tqdm import tqdm  # type: ignore[import-untyped,unused-ignore]

    return tqdm(total=total, desc=desc, file=sys.stderr, disable=None, leave=False, unit="step")


def _media() -> tuple[str, ...]:
    """The medium names ``--network`` accepts (``workcell.sim.network.MEDIA``)."""
    from workcell.sim import network

    names: tuple[str, ...] = getattr(network, "MEDIA", ("ideal", "fixed"))
    return names


def _check_sim_args(args: argparse.Namespace) -> None:
    """Every check that needs no long work: numbers, the medium's name, the tick."""
    if not (math.isfinite(args.time_limit) and args.time_limit > 0):
        raise UsageError(
            f"--time-limit must be a finite number of seconds > 0, got {args.time_limit}"
        )
    if args.network not in _media():
        raise UsageError(
            f"--network: unknown medium {args.network!r} (known: {', '.join(_media())})"
        )
    tick = getattr(args, "tick", None)
    if tick is not None and not (math.isfinite(tick) and tick > 0):
        raise UsageError(f"--tick must be a finite number of seconds > 0, got {tick}")
    frames = getattr(args, "frames", 0)
    if frames < 0:
        raise UsageError(f"--frames must be >= 0, got {frames}")
    evaluations = getattr(args, "evaluations", None)
    if evaluations is not None:
        if args.solver != "tree":
            raise UsageError("--evaluations is a work limit of the tree search (--solver tree)")
        if evaluations < 1:
            raise UsageError(f"--evaluations must be >= 1, got {evaluations}")


def _out_dir(name: str) -> Path:
    """``name`` as an existing, writable directory (created if missing), checked early."""
    out = Path(name)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out: {str(out)!r} is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"--out: cannot create directory {str(out)!r}: {exc.strerror}") from None
    if not os.access(out, os.W_OK):
        raise UsageError(f"--out: directory {str(out)!r} is not writable")
    return out


def _load_cell_arg(name: str) -> Any:
    """A cell from a cell file (``.toml``) or a built-in cell's name."""
    from workcell.cell import EXAMPLES, load_cell, load_example

    path = Path(name)
    if path.is_file():
        if path.suffix.lower() != ".toml":
            raise UsageError(f"{name}: a cell file is a .toml file")
        return load_cell(path)
    if name in EXAMPLES:
        return load_example(name)
    raise UsageError(
        f"unknown cell {name!r}: no such file, and no built-in cell of that name "
        f"(known: {', '.join(EXAMPLES)})"
    )


def _load_faults(name: str) -> Any:
    """A fault plan from a ``.toml`` (``[[faults]]`` tables) or ``.json`` file
    (a list of records, or ``{"faults": [...]}``), via ``FaultPlan.from_dicts``."""
    from multiarm.errors import FormatError
    from multiarm.text import parse_json, parse_toml
    from workcell.sim.faults import FaultPlan

    path = Path(name)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise UsageError(f"--faults: cannot read {name!r}: {why}") from None
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise UsageError(f"--faults: {name}: expected a .toml or .json file")
    parse = parse_toml if suffix == ".toml" else parse_json
    try:
        data: Any = parse(text, name, FormatError, "faults file")
    except FormatError as exc:
        raise UsageError(f"--faults: {exc}") from None
    if isinstance(data, dict):
        if set(data) != {"faults"} or not isinstance(data["faults"], list):
            raise UsageError(f"--faults: {name}: expected a list of fault records under 'faults'")
        data = data["faults"]
    if not isinstance(data, list):
        raise UsageError(f"--faults: {name}: expected a list of fault records")
    try:
        return FaultPlan.from_dicts(data)
    except MultiarmError as exc:
        raise UsageError(f"--faults: {name}: {exc}") from None


def _compile_with_bar(cell: Any) -> Any:
    from workcell.compile import compile_cell

    bar = _progress(len(cell.taskset.tasks), f"{cell.name}: compile")
    try:
        return compile_cell(cell, progress=lambda done, _total: bar.update(1))
    finally:
        bar.close()


def _ms(values: Any, q: float) -> str:
    import numpy as np

    arr = np.asarray(values, dtype=float)
    return f"{float(np.percentile(arr, q)) * 1e3:.2f}" if arr.size else "-"


def _count(x: Any) -> int:
    return int(x) if isinstance(x, int | float) else len(x)


def _sim_rows(problem: Any, schedule: Any, result: Any) -> list[dict[str, Any]]:
    """The summary table of one run: metric, planned, executed."""
    import numpy as np

    m = result.metrics
    arms = schedule.arms(problem)
    planned_mk = float(m.planned_makespan)
    rows: list[dict[str, Any]] = [
        {
            "metric": "makespan (s)",
            "planned": f"{planned_mk:.2f}",
            "executed": f"{float(m.executed_makespan):.2f}",
        }
    ]
    for a, name in enumerate(problem.arm_names):
        busy = float(np.sum((schedule.end - schedule.start)[arms == a]))
        rows.append(
            {
                "metric": f"utilisation {name}",
                "planned": f"{busy / planned_mk:.0%}" if planned_mk > 0 else "-",
                "executed": f"{float(m.utilisation.get(name, 0.0)):.0%}",
            }
        )
    waits = {z: float(w) for z, w in m.zone_wait.items()}
    rows.append(
        {
            "metric": "zone waits (s)",
            "planned": f"{schedule.total_wait():.2f}",
            "executed": f"{m.border_wait:.2f}",
        }
    )
    for z, w in sorted(waits.items(), key=lambda kv: -kv[1])[:3]:
        if w >= 0.005:  # shown to the hundredth
            rows.append({"metric": f"  waits in {z} (s)", "planned": "", "executed": f"{w:.2f}"})
    delays = np.asarray(m.message_delay, dtype=float)
    rows += [
        {"metric": "sleeps / wakes", "planned": "", "executed": f"{m.sleeps} / {m.wakes}"},
        {"metric": "detours", "planned": "", "executed": str(m.detours)},
        {"metric": "re-solves", "planned": "", "executed": str(m.resolves)},
        {
            "metric": "re-solve latency p50 / p99 (ms)",
            "planned": "",
            "executed": f"{_ms(m.resolve_latency, 50)} / {_ms(m.resolve_latency, 99)}",
        },
        {
            "metric": "re-solves over budget",
            "planned": "",
            "executed": f"{int(np.sum(np.asarray(m.resolve_latency) > m.resolve_budget))}"
            f" (budget {m.resolve_budget * 1e3:g} ms)",
        },
        {
            "metric": "messages; delay mean / p99 (ms)",
            "planned": "",
            "executed": (
                f"{m.messages}; {float(delays.mean()) * 1e3:.3f} / {_ms(delays, 99)}"
                if delays.size
                else f"{m.messages}; -"
            ),
        },
        {"metric": "failed tasks", "planned": "", "executed": str(_count(m.failed_tasks))},
    ]
    return rows


def _write_run(out: Path, compiled: Any, schedule: Any, result: Any, frames: int = 0) -> list[Path]:
    """trace.json, metrics.json, tasks.csv, schedule.json and the plots of one run."""
    import json

    import numpy as np

    from workcell.viz.plots import gantt, motion_frames, render_instants, zone_timeline

    problem = compiled.problem
    result.save(out)
    (out / "schedule.json").write_text(json.dumps(schedule.to_dict(problem), indent=1) + "\n")
    fig = gantt(problem, schedule, result)
    fig.savefig(out / "gantt.png", dpi=100)
    fig = zone_timeline(result, title=f"{problem.name}: zone occupancy, executed")
    fig.savefig(out / "zones.png", dpi=100)
    end = float(result.metrics.executed_makespan)
    if not (math.isfinite(end) and end > 0):
        end = schedule.makespan
    times = np.round(np.linspace(0.0, end, 5)[1:4], 1)
    fig = render_instants(compiled, result, [0.0, *times.tolist()])
    fig.savefig(out / "instants.png", dpi=90)
    written = [
        out / n
        for n in (
            "trace.json",
            "metrics.json",
            "tasks.csv",
            "schedule.json",
            "gantt.png",
            "zones.png",
            "instants.png",
        )
    ]
    if frames:
        written += motion_frames(compiled, result, out / "frames", n_frames=frames)
    return written


def cmd_simulate(args: argparse.Namespace) -> int:
    """Compile, schedule and simulate one cell; print the summary, write the outputs."""
    from workcell.faultcheck import check_faults

    _check_sim_args(args)
    cell = _load_cell_arg(args.cell)
    faults = _load_faults(args.faults) if args.faults else None
    check_faults(cell, faults, source=args.faults)  # names: before the compile
    out = _out_dir(args.out or str(Path("out") / cell.name))
    from scheduler import solve, validate
    from workcell.sim.options import SimOptions
    from workcell.sim.run import simulate

    bar = _progress(4, cell.name)
    try:
        bar.set_postfix_str("compile")
        compiled = _compile_with_bar(cell)
        problem = compiled.problem
        check_faults(compiled, faults, source=args.faults)  # times: before the solve
        bar.update(1)
        bar.set_postfix_str(f"schedule ({args.solver}, {args.time_limit:g} s)")
        options = None
        if args.evaluations is not None:
            from scheduler.tree import TreeOptions

            options = TreeOptions(max_evaluations=args.evaluations)
        r = solve(problem, args.solver, time_limit=args.time_limit, seed=args.seed, options=options)
        bar.update(1)
        if r.schedule is None:
            print(r.summary())
            raise MultiarmError(f"cell {cell.name!r}: the {args.solver} solver found no schedule")
        validate(problem, r.schedule)
        bar.set_postfix_str("simulate")
        result = simulate(
            compiled,
            r.schedule,
            seed=args.seed,
            faults=faults,
            medium=args.network,
            options=SimOptions(
                tick=args.tick, monitor=not args.no_monitor, insertion=args.insertion
            ),
        )
        bar.update(1)
        bar.set_postfix_str("plots")
        written = _write_run(out, compiled, r.schedule, result, args.frames)
        bar.update(1)
    finally:
        bar.close()
    print(
        f"{cell.name}: {problem.n_arms} arms, {problem.n_tasks} tasks; "
        f"compiled in {compiled.seconds:.1f} s; {r.summary()}"
    )
    print(
        f"simulated (seed {args.seed}, medium {args.network!r}, "
        f"{'event level' if args.tick is None else f'tick {args.tick:g} s'}, "
        f"{'faults from ' + args.faults if args.faults else 'no faults'}): "
        f"{len(result.trace)} trace events\n"
    )
    _print_table(_sim_rows(problem, r.schedule, result), ["metric", "planned", "executed"])
    if args.central_unit:
        _print_central_unit(problem, r.schedule)
    print(f"\nwrote {len(written)} files to {out}/: " + ", ".join(p.name for p in written[:7]))
    return 0


def _print_central_unit(problem: Any, schedule: Any) -> None:
    """The plan as a SUPERSIGMA task program: one box per arm on the CCU (S1.1, S1.9)."""
    from workcell.sim.supersigma.schedule import run_schedule

    run = run_schedule(problem, schedule)
    rep = run.report
    print("\nunder the SUPERSIGMA central unit and MICROBUS (S1):")
    _print_table(
        [
            {
                "planned (s)": f"{run.planned_makespan:.2f}",
                "executed (s)": f"{run.makespan:.2f}",
                "commands": rep.commands,
                "commands/s": f"{rep.rate:.2f}",
                "saturation": f"{100 * rep.saturation:.3f} %",
                "CCU idle": f"{100 * rep.idle_share:.1f} %",
                "lost": rep.lost,
            }
        ],
        ["planned (s)", "executed (s)", "commands", "commands/s", "saturation", "CCU idle", "lost"],
    )


def _failing_arm(problem: Any, schedule: Any) -> str:
    """The arm whose failure the demo injects: the busiest one whose tasks
    another arm can all take over (the busiest arm if none can be spared)."""
    import numpy as np

    arms = schedule.arms(problem)
    load = [
        float(np.sum((schedule.end - schedule.start)[arms == a])) for a in range(problem.n_arms)
    ]

    def spare(a: int) -> bool:
        return all(
            any(int(problem.mode_arm[m]) != a for m in problem.task_modes[t])
            for t in range(problem.n_tasks)
        )

    order = sorted(range(problem.n_arms), key=lambda a: (not spare(a), -load[a], a))
    return str(problem.arm_names[order[0]])


def cmd_bench(args: argparse.Namespace) -> int:
    """Run the benchmark scripts (they live beside the package, in ``benchmarks/``)."""
    import runpy
    import sys as _sys

    _sys.argv = ["benchmarks", *(["--quick"] if args.quick else [])]
    try:
        runpy.run_module("benchmarks", run_name="__main__")
    except ImportError:
        raise MultiarmError(
            "the benchmarks/ folder is not importable: run from the project's root"
        ) from None
    return 0


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run a sweep file locally or on a Dask cluster; results go to Parquet."""
    from workcell.experiments import check_dask_address, load_sweep, run_sweep

    if args.dask_address:
        check_dask_address(args.dask_address)
    sweep = load_sweep(args.file)
    where = (
        f"on {args.dask_address}"
        if args.dask_address
        else f"{args.workers or sweep.workers or os.cpu_count()} processes"
    )
    print(f"sweep {sweep.name!r}: {len(sweep.runs())} runs, {where}", flush=True)
    try:
        outcome = run_sweep(
            sweep,
            dask_address=args.dask_address,
            workers=args.workers,
            out=args.out,
            progress=not args.no_progress,
            retry_failed=args.retry_failed,
        )
    except KeyboardInterrupt:
        print(
            "interrupted: finished runs are saved; run the same command to resume", file=sys.stderr
        )
        return 130
    print(
        f"{outcome.ran} runs in {outcome.wall_time:.1f} s ({outcome.runs_per_minute:.1f} runs/min), "
        f"{outcome.skipped} already done, {outcome.failed} failed; results: {outcome.out}"
    )
    return 1 if outcome.failed else 0


def cmd_campaign(args: argparse.Namespace) -> int:
    """Run a seeded fault campaign (or replay one episode); print the findings."""
    from workcell import campaign

    if args.replay is not None:
        seed, index = campaign.parse_replay(args.replay)
        print(campaign.describe(campaign.replay(args.cells[0], seed, index)))
        return 0
    outcome = campaign.run_campaign(
        args.cells,
        args.episodes,
        args.seed,
        workers=args.workers,
        dask_address=args.dask_address,
        out=args.out,
        progress=not args.no_progress,
    )
    print(outcome.report())
    if outcome.out is not None:
        print(f"episodes: {outcome.out / 'episodes.parquet'} (and .csv)")
    return 1 if outcome.findings or outcome.errors else 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for documentation and tests)."""
    parser = argparse.ArgumentParser(
        prog="multiarm",
        description="Schedule and coordinate several robot arms in one assembly cell.",
    )
    parser.add_argument("--version", action="version", version=f"multiarm {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser(
        "demo",
        help="the main job on the built-in cells: compile, schedule, simulate, one arm failing",
    )
    p.add_argument(
        "--time-limit", type=float, default=2.0, metavar="SECONDS", help="per solver and cell"
    )
    p.add_argument("--out", default="out", metavar="DIR", help="where plots, traces and metrics go")
    p.add_argument("--cells", nargs="+", metavar="NAME", help="only these built-in cells")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--network", default="ideal", metavar="NAME", help="the medium (see simulate)")
    p.add_argument(
        "--no-monitor", action="store_true", help="run without the independent safety monitor"
    )
    p.set_defaults(func=cmd_demo)
    p = sub.add_parser(
        "simulate",
        help="compile, schedule and simulate a cell (a .toml cell file or a built-in cell's name)",
    )
    p.add_argument("cell", metavar="CELL")
    p.add_argument("--solver", choices=["tree", "greedy", "cpsat"], default="tree")
    p.add_argument("--time-limit", type=float, default=5.0, metavar="SECONDS")
    p.add_argument("--seed", type=int, default=0, help="for the solver and the simulation")
    p.add_argument(
        "--evaluations",
        type=int,
        metavar="N",
        help="tree search: stop after N schedules evaluated (a work limit: the same plan anywhere)",
    )
    p.add_argument(
        "--faults", metavar="FILE", help="fault records to inject (.toml [[faults]] or .json list)"
    )
    p.add_argument(
        "--network",
        default="ideal",
        metavar="NAME",
        help="the medium between coordinator and arms (workcell.sim.network.MEDIA)",
    )
    p.add_argument(
        "--tick",
        type=float,
        metavar="SECONDS",
        help="model every controller tick of this period (default: event level)",
    )
    p.add_argument(
        "--insertion",
        choices=["planned", "drawn"],
        default="planned",
        help="force-guided insertions: the planned tries, or tries drawn at run time (S1.7)",
    )
    p.add_argument("--out", metavar="DIR", help="output directory (default ./out/CELLNAME)")
    p.add_argument("--frames", type=int, default=0, metavar="N", help="also write N motion frames")
    p.add_argument(
        "--no-monitor", action="store_true", help="run without the independent safety monitor"
    )
    p.add_argument(
        "--central-unit",
        action="store_true",
        help="also run the plan as a task program on the SUPERSIGMA central unit over MICROBUS (S1)",
    )
    p.set_defaults(func=cmd_simulate)
    p = sub.add_parser(
        "check",
        help="validate .tdl/.sdl/task-set/problem/schedule files; explain cell files (.toml)",
    )
    p.add_argument("files", nargs="+", metavar="FILE")
    p.add_argument(
        "--problem", metavar="PROBLEM", help="the problem that schedule files are validated against"
    )
    p.add_argument(
        "--json", action="store_true", help="print one JSON report of every file (for scripts)"
    )
    p.set_defaults(func=cmd_check)
    p = sub.add_parser(
        "schedule",
        help="solve a problem (.json), an FJSP instance (.fjs), a cell file (.toml) or a built-in cell",
    )
    p.add_argument("problem", metavar="PROBLEM")
    p.add_argument("--solver", choices=["tree", "greedy", "cpsat"], default="tree")
    p.add_argument("--time-limit", type=float, default=10.0, metavar="SECONDS")
    p.add_argument("--seed", type=int, default=0)
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
    p.set_defaults(func=cmd_schedule)
    p = sub.add_parser("bench", help="run the benchmarks (writes benchmarks/results/)")
    p.add_argument("--quick", action="store_true", help="tiny sizes, a smoke run")
    p.set_defaults(func=cmd_bench)
    p = sub.add_parser(
        "campaign",
        help="a seeded fault campaign: random fault plans simulated and checked, findings replayable",
    )
    p.add_argument("cells", nargs="+", metavar="CELL", help="built-in cells' names or cell files")
    p.add_argument("--episodes", type=int, default=100, metavar="N", help="episodes per cell")
    p.add_argument("--seed", type=int, default=0, help="the campaign's seed")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help="local processes (default: CPUs)")
    where.add_argument(
        "--dask-address",
        "--scheduler",
        dest="dask_address",
        metavar="ADDRESS",
        help="run on the Dask cluster whose scheduler is at ADDRESS, e.g. tcp://host:8786",
    )
    p.add_argument("--out", metavar="DIR", help="write the episodes table (Parquet and CSV) here")
    p.add_argument("--replay", metavar="SEED:EPISODE", help="run one episode again and print it")
    p.add_argument("--no-progress", action="store_true", help="no progress bar or lines")
    p.set_defaults(func=cmd_campaign)
    p = sub.add_parser(
        "sweep", help="run a sweep file (TOML) locally or on a Dask cluster; results as Parquet"
    )
    p.add_argument("file", metavar="FILE")
    p.add_argument(
        "--dask-address",
        "--scheduler",
        dest="dask_address",
        metavar="ADDRESS",
        help="run on the Dask cluster whose scheduler is at ADDRESS, e.g. tcp://host:8786 "
        "(--scheduler is the old name)",
    )
    p.add_argument("--workers", type=int, metavar="N", help="local processes (default: CPU count)")
    p.add_argument("--out", metavar="PATH", help="results file (default: the sweep file's out)")
    p.add_argument("--retry-failed", action="store_true", help="run failed runs again")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_sweep)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``multiarm`` command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        return func(args)
    except MultiarmError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
