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
    return 0


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
