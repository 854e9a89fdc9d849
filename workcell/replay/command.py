"""``multiarm view RUN_DIR [--out FILE]``: the replay page of a run directory.

A run directory written by ``multiarm simulate --out DIR`` holds the replay
document ``replay.json`` (:func:`workcell.replay.save_replay`); this command
writes the self-contained page from it (default ``RUN_DIR/replay.html``).

Examples
--------
>>> import argparse
>>> parser = argparse.ArgumentParser(prog="multiarm view")
>>> add_arguments(parser)
>>> args = parser.parse_args(["runs/scara4", "--out", "scara4.html"])
>>> args.run_dir, args.out
('runs/scara4', 'scara4.html')
"""

from __future__ import annotations

import argparse
from pathlib import Path

from multiarm.errors import UsageError
from workcell.replay.data import REPLAY_FILE, load_replay
from workcell.replay.page import write_html

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``view``: ``RUN_DIR`` and ``--out FILE``."""
    parser.add_argument(
        "run_dir",
        metavar="RUN_DIR",
        help=f"a run directory holding {REPLAY_FILE} (multiarm simulate --out DIR), "
        "or a replay document itself",
    )
    parser.add_argument(
        "--out",
        metavar="FILE",
        default=None,
        help="the HTML file to write (default: RUN_DIR/replay.html)",
    )


def run(args: argparse.Namespace) -> int:
    """Write the page; print its path and size. Returns the exit status (0).

    Raises
    ------
    UsageError
        No replay document in ``RUN_DIR``, or an ``--out`` that cannot be written.
    ValidationError
        A file that is not a replay document.
    """
    src = Path(args.run_dir)
    data = load_replay(src)
    if args.out is not None:
        out = Path(args.out)
    else:
        out = (src if src.is_dir() else src.parent) / "replay.html"
    if out.suffix.lower() not in (".html", ".htm"):
        raise UsageError(f"--out: {str(out)!r} must end in .html")
    path = write_html(data, None, out)
    size = path.stat().st_size
    print(
        f"{path}: replay of {data.document['cell']!r}, {data.duration:.2f} s, "
        f"{data.n_frames} frames, {size / 1e6:.2f} MB"
    )
    return 0
