"""``multiarm check FILE...``: validate files and explain cells (:mod:`workcell.check`).

Problem JSON, schedules (validated against ``--problem``) and FJSPLIB
instances are recognised by content; then by extension ``.tdl``, ``.sdl``,
``.json`` and ``.toml`` (a task set when it holds a ``tasks`` list, else a
cell file, compiled and explained per arm); a built-in cell's name is
explained too. Exit status 0 when every file is clean or has warnings only.
"""

from __future__ import annotations

import argparse

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``check``."""
    p.add_argument("files", nargs="+", metavar="FILE", help="files, or built-in cells' names")
    p.add_argument(
        "--problem", metavar="PROBLEM", help="the problem that schedule files are validated against"
    )
    p.add_argument(
        "--json", action="store_true", help="print one JSON report of every file (for scripts)"
    )


def run(args: argparse.Namespace) -> int:
    """Run ``check``; the exit status."""
    from workcell.check import check_files

    return check_files(args.files, args.problem, as_json=args.json)
