"""``multiarm sweep FILE``: run a sweep file (:mod:`workcell.experiments`).

In a local process pool, or on a Dask cluster with ``--dask-address``; an
interrupted sweep resumes where it stopped. Failed runs give exit status 3.
"""

from __future__ import annotations

import argparse
import os
import sys

from workcell.cli import args as common
from workcell.cli.output import EXIT_FAILURES, EXIT_INTERRUPTED, EXIT_OK

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``sweep``."""
    p.add_argument("file", metavar="FILE", help="the sweep file (TOML)")
    p.add_argument(
        "--dask-address",
        "--scheduler",
        dest="dask_address",
        metavar="ADDRESS",
        help="run on the Dask cluster whose scheduler is at ADDRESS, e.g. tcp://host:8786 "
        "(--scheduler is the old name; default: a local process pool)",
    )
    p.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help=f"local processes (default: the sweep file's, else the CPU count; at most "
        f"{common.MAX_WORKERS})",
    )
    p.add_argument("--out", metavar="PATH", help="results file (default: the sweep file's out)")
    p.add_argument("--retry-failed", action="store_true", help="run failed runs again")
    p.add_argument("--no-progress", action="store_true", help="no progress bar or lines")


def run(args: argparse.Namespace) -> int:
    """Run ``sweep``; the exit status."""
    from workcell.experiments import check_dask_address, load_sweep, run_sweep

    common.check_count("--workers", args.workers, 1, common.MAX_WORKERS)
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
        return EXIT_INTERRUPTED
    print(outcome.report())  # the result table, each failure named, the totals
    return EXIT_FAILURES if outcome.failed else EXIT_OK
