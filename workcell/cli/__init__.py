"""The ``multiarm`` console command: a thin layer over the library.

One module a sub-command, each with ``add_arguments(parser)`` and
``run(args) -> int``: it parses, makes one call into the library and prints.
The main job goes through :func:`workcell.run_cell` (:mod:`workcell.pipeline`).

``demo`` (:mod:`.demo`)
    The built-in cells compiled, scheduled with every solver, simulated as
    planned and with one arm failing; plots, traces and metrics in ``./out``.
``simulate CELL`` (:mod:`.simulate`)
    One cell (a cell file or a built-in name) through :func:`workcell.run_cell`,
    optionally with faults and a network medium; planned against executed.
``check FILE...`` (:mod:`.check`)
    Validate files and explain cells (:mod:`workcell.check`).
``schedule PROBLEM`` (:mod:`.schedule`)
    Solve a problem file, an FJSP instance or a cell; print the schedule.
``campaign CELL...`` (:mod:`.campaign`)
    A seeded fault campaign (:mod:`workcell.campaign`).
``sweep FILE`` (:mod:`.sweep`)
    A sweep file, locally or on Dask (:mod:`workcell.experiments`).
``bench`` (:mod:`.bench`)
    The benchmark scripts.

:mod:`.output` holds the tables, status lines, progress and exit statuses
(0 done, 1 error, 2 bad command line, 3 failed tasks, findings or runs, 130
interrupted; docs/cli.md); :mod:`.args` the shared options and their caps.
"""

from __future__ import annotations

from multiarm.errors import MultiarmError, UsageError
from workcell.cli.main import build_parser, main
from workcell.sim.harness.faults import FaultPlan

__all__ = ["build_parser", "main"]


def _load_faults(name: str) -> FaultPlan:
    """The ``--faults`` reader (errors prefixed ``--faults:``); kept for the fuzz harness,
    which reads fault files the way the command does (:func:`workcell.pipeline.load_faults`)."""
    from workcell.pipeline import load_faults

    try:
        return load_faults(name)
    except MultiarmError as exc:
        raise UsageError(f"--faults: {exc}") from None
