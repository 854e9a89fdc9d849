"""``multiarm campaign CELL...``: a seeded fault campaign (:mod:`workcell.campaign`).

Each cell is compiled and solved once by :func:`workcell.pipeline.solve_cell`
(the compile and solve steps of :func:`workcell.run_cell`, under a work
limit: the same plan in every process); each episode then simulates that
plan under drawn faults. Findings give exit status 3.
"""

from __future__ import annotations

import argparse

from multiarm.errors import UsageError
from workcell.cli import args as common
from workcell.cli.output import EXIT_FAILURES, EXIT_OK

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``campaign``."""
    p.add_argument("cells", nargs="+", metavar="CELL", help="built-in cells' names or cell files")
    p.add_argument(
        "--episodes",
        type=int,
        default=100,
        metavar="N",
        help=f"episodes per cell (at most {common.MAX_EPISODES})",
    )
    p.add_argument("--seed", type=int, default=0, help="the campaign's seed")
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help=f"local processes (default: the CPU count; at most {common.MAX_WORKERS})",
    )
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


def run(args: argparse.Namespace) -> int:
    """Run ``campaign``; the exit status."""
    from workcell import campaign

    if args.episodes > common.MAX_EPISODES:  # the campaign checks the rest (>= 1)
        raise UsageError(f"--episodes must be at most {common.MAX_EPISODES}, got {args.episodes}")
    common.check_count("--workers", args.workers, 1, common.MAX_WORKERS)
    if args.replay is not None:
        seed, index = campaign.parse_replay(args.replay)
        print(campaign.describe(campaign.replay(args.cells[0], seed, index)))
        return EXIT_OK
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
    return EXIT_FAILURES if outcome.findings or outcome.errors else EXIT_OK
