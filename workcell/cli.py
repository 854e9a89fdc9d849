"""The ``multiarm`` console command: a thin layer over the library.

It parses arguments, calls the library and prints; errors of ours are printed
as one line (``file:line:col: message``) with exit status 1, never as a
traceback.

Sub-commands:

``demo``
    Run the main job on the built-in example cells and print what it did.
``check FILE...``
    Parse and validate files by extension: ``.tdl`` (trajectories), ``.sdl``
    (zones), ``.toml`` / ``.json`` (task sets).
``schedule PROBLEM``
    Solve a scheduling problem (``.json`` written by ``save_problem``, or an
    FJSPLIB ``.fjs`` file) and print the result; ``--out`` writes the schedule.
``bench``
    Run the benchmark scripts (``--quick`` for a smoke run).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from multiarm import MultiarmError, __version__

__all__ = ["main"]


def _print_table(rows: list[dict[str, Any]], columns: Sequence[str]) -> None:
    table = [[str(r[c]) for c in columns] for r in rows]
    widths = [max(len(c), *(len(row[i]) for row in table)) for i, c in enumerate(columns)]
    print("  ".join(c.ljust(w) for c, w in zip(columns, widths, strict=True)))
    print("  ".join("-" * w for w in widths))
    for row in table:
        print("  ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)))


def cmd_demo(args: argparse.Namespace) -> int:
    """Load the built-in example task sets and zone maps and summarise them."""
    from tasklib import EXAMPLES
    from zones import examples as zone_examples

    print(f"multiarm {__version__}: built-in example task sets\n")
    print(
        "(the cell model that turns these into scheduling problems comes with the workcell layer;\n"
        " below, the scheduler runs on a generated problem instead)\n"
    )
    rows: list[dict[str, Any]] = [make().summary() for make in EXAMPLES.values()]
    _print_table(
        rows,
        [
            "name",
            "tasks",
            "steps",
            "parts",
            "feeders",
            "part_groups",
            "depth",
            "trajectories",
            "waypoints",
        ],
    )
    print()
    for s in rows:
        caps = ", ".join(s["capabilities"])
        tools = ", ".join(s["tools"]) or "none"
        print(f"{s['name']}: capabilities {caps}; tools {tools}")
    print("\nbuilt-in zone maps (SDL)\n")
    zrows = []
    for name in zone_examples.EXAMPLES:
        zs = zone_examples.load_example(name).summary()
        zrows.append({"cell": name, **zs})
    _print_table(
        zrows, ["cell", "zones", "exclusive", "shared", "walls", "tools", "phases", "active"]
    )
    _demo_schedule()
    return 0


def _demo_schedule() -> None:
    """Schedule a generated cell-like problem with every solver (2 s each)."""
    from scheduler import lower_bound, solve, validate
    from scheduler.generate import random_problem

    problem = random_problem(4, 40, 6, 2, seed=0, start_zones=True)
    print(f"\nscheduling a generated problem (seed 0): {problem!r}")
    print(f"lower bound {lower_bound(problem):.6g} s\n")
    rows = []
    for solver in ("greedy", "tree", "cpsat"):
        r = solve(problem, solver, time_limit=2.0, seed=0)
        if r.schedule is None:
            rows.append(
                {
                    "solver": solver,
                    "status": r.status.value,
                    "makespan": "-",
                    "bound": f"{r.bound:.6g}",
                    "waits (s)": "-",
                    "first (s)": "-",
                    "time (s)": f"{r.runtime:.2f}",
                }
            )
            continue
        rows.append(
            {
                "solver": solver,
                "status": r.status.value,
                "makespan": f"{validate(problem, r.schedule):.6g}",
                "bound": f"{r.bound:.6g}",
                "waits (s)": f"{r.schedule.total_wait():.6g}",
                "first (s)": f"{r.stats.first_time:.3f}",
                "time (s)": f"{r.runtime:.2f}",
            }
        )
    _print_table(
        rows, ["solver", "status", "makespan", "bound", "waits (s)", "first (s)", "time (s)"]
    )


def _check_one(path: Path) -> str:
    suffix = path.suffix.lower()
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


def cmd_schedule(args: argparse.Namespace) -> int:
    """Solve a problem file and print (and optionally write) the schedule."""
    import json

    from scheduler import load_problem, lower_bound, read_fjsp, solve

    path = Path(args.problem)
    problem = read_fjsp(path) if path.suffix.lower() == ".fjs" else load_problem(path)
    print(f"{problem!r}; lower bound {lower_bound(problem):.6g}")
    result = solve(
        problem, args.solver, time_limit=args.time_limit, seed=args.seed, waits=not args.no_waits
    )
    print(result.summary())
    if result.schedule is not None and args.out:
        Path(args.out).write_text(json.dumps(result.schedule.to_dict(problem), indent=1) + "\n")
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
    p.set_defaults(func=cmd_demo)
    p = sub.add_parser("check", help="parse and validate .tdl/.sdl/.toml/.json files")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.set_defaults(func=cmd_check)
    p = sub.add_parser("schedule", help="solve a problem (.json) or an FJSP instance (.fjs)")
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
