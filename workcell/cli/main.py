"""The ``multiarm`` parser and entry point: one sub-command a module.

Each command module has ``add_arguments(parser)`` and ``run(args) -> int``;
:data:`COMMANDS` lists them with their one-line help. :func:`main` turns an
error of the package's family into one line on stderr and exit status 1,
Ctrl-C into one line and 130 (the statuses: :mod:`workcell.cli.output`).
While a command runs, the scheduler kernel's one-time compile note
(:data:`scheduler.kernel.COMPILE_NOTE`, an INFO message of the library) is
shown on stderr, so that the first run on a machine does not sit silent
for a minute.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
from collections.abc import Callable, Iterator, Sequence
from types import ModuleType

from multiarm import MultiarmError, __version__
from workcell.cli import bench, campaign, check, demo, schedule, simulate, sweep, view
from workcell.cli.output import EXIT_ERROR, EXIT_INTERRUPTED

__all__ = ["COMMANDS", "DefaultsFormatter", "build_parser", "main"]

COMMANDS: tuple[tuple[str, str, ModuleType], ...] = (
    (
        "demo",
        "the main job on the built-in cells: compile, schedule, simulate, one arm failing",
        demo,
    ),
    (
        "simulate",
        "compile, schedule and simulate a cell (a .toml cell file or a built-in cell's name)",
        simulate,
    ),
    (
        "view",
        "write the 3D replay page (one self-contained HTML file) of a run directory",
        view,
    ),
    (
        "check",
        "validate .tdl/.sdl/task-set/problem/schedule files; explain cell files (.toml)",
        check,
    ),
    (
        "schedule",
        "solve a problem (.json), an FJSP instance (.fjs), a cell file (.toml) or a built-in cell",
        schedule,
    ),
    ("bench", "run the benchmarks (writes benchmarks/results/)", bench),
    (
        "campaign",
        "a seeded fault campaign: random fault plans simulated and checked, findings replayable",
        campaign,
    ),
    ("sweep", "run a sweep file (TOML) locally or on a Dask cluster; results as Parquet", sweep),
)
"""(name, help, module) of every sub-command, in the order ``--help`` lists them."""


class DefaultsFormatter(argparse.HelpFormatter):
    """Help that ends every option with its default: ``(default: 5.0)``,
    ``(default: off)`` for a flag, ``(default: none)`` for an option without
    one, unless the help text states its default itself."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if "(default" in text or action.default is argparse.SUPPRESS or not action.option_strings:
            return text
        if isinstance(action, argparse._StoreTrueAction):
            return f"{text} (default: off)"
        if action.default is None:
            return f"{text} (default: none)"
        return f"{text} (default: %(default)s)"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for documentation and tests).

    Every sub-command's ``--help`` shows the defaults of its options.
    """
    parser = argparse.ArgumentParser(
        prog="multiarm",
        description="Schedule and coordinate several robot arms in one assembly cell.",
        epilog="exit status: 0 done, 1 error, 2 bad command line, 3 failed tasks, "
        "findings or runs, 130 interrupted (docs/cli.md)",
    )
    parser.add_argument("--version", action="version", version=f"multiarm {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, help_, module in COMMANDS:
        p = sub.add_parser(
            name,
            help=help_,
            description=help_,
            formatter_class=DefaultsFormatter,
        )
        module.add_arguments(p)
        p.set_defaults(func=module.run)
    return parser


def _one_line(exc: BaseException) -> str:
    return " ".join(part.strip() for part in str(exc).splitlines() if part.strip())


class _NoteHandler(logging.StreamHandler):  # type: ignore[type-arg]
    """A line on stderr; on a terminal through tqdm, so that a progress bar
    (:class:`workcell.cli.output.Progress`) is cleared first and redrawn after."""

    def emit(self, record: logging.LogRecord) -> None:
        if self.stream.isatty():
            try:
                from tqdm import tqdm  # type: ignore[import-untyped,unused-ignore]
            except ImportError:  # pragma: no cover - no bar without tqdm either
                pass
            else:
                tqdm.write(self.format(record), file=self.stream)
                return
        super().emit(record)


@contextlib.contextmanager
def _compile_notes() -> Iterator[None]:
    """Show the ``scheduler.kernel`` logger's INFO messages (its one-time
    compile note) on stderr as ``multiarm: ...`` lines while the block runs."""
    logger = logging.getLogger("scheduler.kernel")
    handler = _NoteHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("multiarm: %(message)s"))
    handler.setLevel(logging.INFO)
    level = logger.level
    logger.addHandler(handler)
    if logger.getEffectiveLevel() > logging.INFO:
        logger.setLevel(logging.INFO)
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``multiarm`` command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        with _compile_notes():
            return func(args)
    except MultiarmError as exc:
        print(f"error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print(f"interrupted: multiarm {args.command} stopped (Ctrl-C)", file=sys.stderr)
        return EXIT_INTERRUPTED
