"""Options several commands share, and the checks made before any long work.

Caps on sizes the user gives (exceeded: a one-line error, exit status 1):
:data:`~workcell.pipeline.MAX_FRAMES` motion frames,
:data:`~workcell.pipeline.MAX_EVALUATIONS` evaluations,
:data:`~workcell.pipeline.MAX_TIME_LIMIT` seconds of time limit,
:data:`MAX_EPISODES` campaign episodes a cell, :data:`MAX_WORKERS` processes.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from multiarm.errors import MultiarmError, UsageError
from scheduler.solve import SOLVERS
from workcell.pipeline import (
    EVALUATIONS_PER_SECOND,
    MAX_EVALUATIONS,
    MAX_FRAMES,
    MAX_TIME_LIMIT,
    WALL_CAP_FACTOR,
    check_out_dir,
)

__all__ = [
    "MAX_EPISODES",
    "MAX_WORKERS",
    "add_evaluations",
    "add_network",
    "add_seed",
    "add_solver",
    "add_time_limit",
    "check_count",
    "check_network",
    "check_sim",
    "check_time_limit",
    "out_dir",
]

MAX_EPISODES = 100_000
"""The most campaign episodes a cell (about a day of simulation)."""
MAX_WORKERS = 256
"""The most local worker processes."""


def add_solver(p: argparse.ArgumentParser) -> None:
    """``--solver``."""
    p.add_argument("--solver", choices=SOLVERS, default="tree", help="the scheduler's solver")


def add_time_limit(p: argparse.ArgumentParser, default: float, what: str = "per solve") -> None:
    """``--time-limit`` (the tree search's work limit derives from it)."""
    p.add_argument(
        "--time-limit",
        type=float,
        default=default,
        metavar="SECONDS",
        help=f"{what}; the tree search stops after {EVALUATIONS_PER_SECOND} evaluations a "
        f"second of it (the same plan on any machine) or {WALL_CAP_FACTOR:g} times it on the "
        "clock",
    )


def add_evaluations(p: argparse.ArgumentParser) -> None:
    """``--evaluations``."""
    p.add_argument(
        "--evaluations",
        type=int,
        metavar="N",
        help="tree search: stop after N schedules evaluated (default: "
        f"{EVALUATIONS_PER_SECOND} a second of --time-limit; at most {MAX_EVALUATIONS})",
    )


def add_seed(p: argparse.ArgumentParser, what: str = "for the solver and the simulation") -> None:
    """``--seed``."""
    p.add_argument("--seed", type=int, default=0, help=what)


def add_network(p: argparse.ArgumentParser) -> None:
    """``--network``."""
    p.add_argument(
        "--network",
        default="ideal",
        metavar="NAME",
        help="the medium between coordinator and arms (workcell.sim.comms.MEDIA)",
    )


def check_time_limit(seconds: float) -> None:
    """``--time-limit`` is finite, > 0 and at most :data:`MAX_TIME_LIMIT`."""
    if not (math.isfinite(seconds) and seconds > 0):
        raise UsageError(f"--time-limit must be a finite number of seconds > 0, got {seconds}")
    if seconds > MAX_TIME_LIMIT:
        raise UsageError(f"--time-limit must be at most {MAX_TIME_LIMIT:g} s, got {seconds:g}")


def check_count(option: str, value: int | None, least: int, most: int) -> None:
    """An integer option within ``least..most`` (None passes)."""
    if value is None:
        return
    if value < least:
        raise UsageError(f"{option} must be >= {least}, got {value}")
    if value > most:
        raise UsageError(f"{option} must be at most {most}, got {value}")


def check_network(name: str) -> None:
    """``--network`` names a known medium."""
    from workcell.sim.comms import MEDIA

    if name not in MEDIA:
        raise UsageError(f"--network: unknown medium {name!r} (known: {', '.join(MEDIA)})")


def check_sim(args: argparse.Namespace) -> None:
    """The checks of ``simulate`` and ``demo`` that need no long work."""
    check_time_limit(args.time_limit)
    check_network(args.network)
    tick = getattr(args, "tick", None)
    if tick is not None and not (math.isfinite(tick) and 0 < tick <= 1.0):
        raise UsageError(f"--tick must be a finite number of seconds in (0, 1], got {tick}")
    check_count("--frames", getattr(args, "frames", 0), 0, MAX_FRAMES)
    evaluations = getattr(args, "evaluations", None)
    if evaluations is not None and args.solver != "tree":
        raise UsageError("--evaluations is a work limit of the tree search (--solver tree)")
    check_count("--evaluations", evaluations, 1, MAX_EVALUATIONS)


def out_dir(name: str) -> Path:
    """``--out`` as an existing, writable directory (created if missing), checked early."""
    try:
        return check_out_dir(name)
    except MultiarmError as exc:
        raise UsageError(f"--out: {exc}") from None
