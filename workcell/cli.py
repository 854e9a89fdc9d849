"""The ``multiarm`` console command: a thin layer over the library.

It parses arguments, calls the library and prints; errors of ours are printed
as one line (``file:line:col: message``) with exit status 1, never as a
traceback.

Sub-commands:

``demo``
    The main job on the built-in cells: compile each, schedule it with every
    solver, validate, and print per-arm and per-zone summaries.
``check FILE...``
    Parse and validate files by extension: ``.tdl`` (trajectories), ``.sdl``
    (zones), ``.toml`` / ``.json`` (task sets; a ``.toml`` with ``[arms]``
    tables is a cell file, checked by compiling it).
``schedule PROBLEM``
    Solve a scheduling problem (``.json`` written by ``save_problem``, an
    FJSPLIB ``.fjs`` file, a cell file, or a built-in cell's name) and print
    the result; ``--out`` writes the schedule.
``bench``
    Run the benchmark scripts (``--quick`` for a smoke run).
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
    """The main job on every built-in cell: compile, schedule with every solver, validate."""
    from workcell.cell import EXAMPLES, load_example

    print(f"multiarm {__version__}: the built-in cells, compiled and scheduled\n")
    cells = [load_example(name) for name in EXAMPLES]
    _print_table(
        [c.summary() for c in cells], ["name", "arms", "arm types", "tasks", "zones", "tools"]
    )
    for cell in cells:
        _demo_cell(cell, args.time_limit)
    return 0


def _demo_cell(cell: Any, time_limit: float) -> None:
    import time

    from scheduler import lower_bound, solve, validate
    from workcell.compile import compile_cell_detailed

    print(f"\n== {cell.name}: {cell.description}")
    t0 = time.perf_counter()
    cc = compile_cell_detailed(cell)
    p = cc.problem
    print(
        f"compiled in {time.perf_counter() - t0:.1f} s: {p.n_tasks} tasks, {p.n_modes} modes "
        f"({len(cc.rejected)} (task, arm) pairs have none), {p.n_windows} zone windows; "
        f"lower bound {lower_bound(p):.1f} s"
    )
    rows = []
    best = None
    for solver in ("greedy", "tree", "cpsat"):
        r = solve(p, solver, time_limit=time_limit, seed=0)
        ok = r.schedule is not None
        mk = validate(p, r.schedule) if r.schedule is not None else math.inf
        if r.schedule is not None and (best is None or mk < best[0]):
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
        return
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
    for z, name in enumerate(p.zone_names):
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
    _print_table(zone_rows, ["zone", "policy", "uses", "occupied or moved in (s)"])


def _is_cell(path: Path) -> bool:
    """A TOML file with an ``[arms...]`` table is a cell file (else a task set)."""
    import tomllib

    try:
        return "arms" in tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False


def _check_one(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix == ".toml" and _is_cell(path):
        from workcell import compile_cell, load_cell

        cell = load_cell(path)
        p = compile_cell(cell)
        return (
            f"cell {cell.name!r}: {len(cell.arms)} arms, {p.n_tasks} tasks, {p.n_modes} modes, "
            f"{p.n_zones} zones"
        )
    if suffix == ".tdl":
        from tasklib import load_tdl

        doc = load_tdl(path)
        return f"{len(doc.trajectories)} trajectories, {len(doc.frames)} frames"
    if suffix in (".toml", ".json"):
        from tasklib import load_taskset

        ts = load_taskset(path)
        s = ts.summary()
        return f"task set {s['name']!r}: {s['tasks']} tasks, {s['parts']} parts, depth {s['depth']}"
    if suffix == ".sdl":
        from zones import load_sdl

        s = load_sdl(path).summary()
        return (
            f"{s['zones']} zones ({s['exclusive']} exclusive, {s['shared']} shared), "
            f"{s['walls']} walls, {s['tools']} tools, {s['phases']} phases"
        )
    raise MultiarmError(f"{path}: unknown file type {suffix!r} (known: .tdl, .sdl, .toml, .json)")


def cmd_check(args: argparse.Namespace) -> int:
    """Validate each file; print one line per file."""
    status = 0
    for name in args.files:
        path = Path(name)
        try:
            print(f"{path}: ok ({_check_one(path)})")
        except MultiarmError as exc:
            print(f"error: {exc}", file=sys.stderr)
            status = 1
    return status


def _load_schedulable(name: str) -> Any:
    """A problem from a problem JSON, an FJSP file, a cell file or a built-in cell's name."""
    from scheduler import load_problem, read_fjsp
    from workcell.cell import EXAMPLES, load_example

    path = Path(name)
    if not path.exists() and name in EXAMPLES:
        from workcell import compile_cell

        return compile_cell(load_example(name))
    if path.suffix.lower() == ".fjs":
        return read_fjsp(path)
    if path.suffix.lower() == ".toml":
        from workcell import compile_cell, load_cell

        return compile_cell(load_cell(path))
    return load_problem(path)


def cmd_schedule(args: argparse.Namespace) -> int:
    """Solve a problem file or a cell and print (and optionally write) the schedule."""
    import json

    from scheduler import lower_bound, solve

    if args.out:  # checked before any work, so a solved schedule is never lost
        out = Path(args.out)
        if out.is_dir():
            raise UsageError(f"--out: {str(out)!r} is a directory")
        parent = out.parent if str(out.parent) else Path(".")
        if not parent.is_dir():
            raise UsageError(f"--out: directory {str(parent)!r} does not exist")
        if not os.access(parent, os.W_OK):
            raise UsageError(f"--out: directory {str(parent)!r} is not writable")
    if not (math.isfinite(args.time_limit) and args.time_limit > 0):
        raise UsageError(
            f"--time-limit must be a finite number of seconds > 0, got {args.time_limit}"
        )
    problem = _load_schedulable(args.problem)
    print(f"{problem!r}; lower bound {lower_bound(problem):.6g}")
    result = solve(
        problem, args.solver, time_limit=args.time_limit, seed=args.seed, waits=not args.no_waits
    )
    print(result.summary())
    if result.schedule is not None and args.out:
        try:
            Path(args.out).write_text(json.dumps(result.schedule.to_dict(problem), indent=1) + "\n")
        except OSError as exc:
            print(json.dumps(result.schedule.to_dict(problem)))  # keep the result
            raise UsageError(f"--out: cannot write {args.out!r}: {exc.strerror}") from None
        print(f"schedule written to {args.out}")
    return 0 if result.schedule is not None else 1


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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for documentation and tests)."""
    parser = argparse.ArgumentParser(
        prog="multiarm",
        description="Schedule and coordinate several robot arms in one assembly cell.",
    )
    parser.add_argument("--version", action="version", version=f"multiarm {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="run the main job on the built-in example cells")
    p.add_argument(
        "--time-limit", type=float, default=3.0, metavar="SECONDS", help="per solver and cell"
    )
    p.set_defaults(func=cmd_demo)
    p = sub.add_parser(
        "check", help="parse and validate .tdl/.sdl files, task sets and cell files (.toml/.json)"
    )
    p.add_argument("files", nargs="+", metavar="FILE")
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
    p.add_argument("--out", metavar="FILE", help="write the schedule as JSON")
    p.set_defaults(func=cmd_schedule)
    p = sub.add_parser("bench", help="run the benchmarks (writes benchmarks/results/)")
    p.add_argument("--quick", action="store_true", help="tiny sizes, a smoke run")
    p.set_defaults(func=cmd_bench)
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
