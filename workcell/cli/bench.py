"""``multiarm bench``: run the benchmark scripts (``benchmarks/``, beside the package)."""

from __future__ import annotations

import argparse
import runpy
import sys

from multiarm.errors import MultiarmError
from workcell.cli.output import EXIT_OK

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``bench``."""
    p.add_argument("--quick", action="store_true", help="tiny sizes, a smoke run")


def run(args: argparse.Namespace) -> int:
    """Run ``bench``; the exit status."""
    sys.argv = ["benchmarks", *(["--quick"] if args.quick else [])]
    try:
        runpy.run_module("benchmarks", run_name="__main__")
    except ImportError:
        raise MultiarmError(
            "the benchmarks/ folder is not importable: run from the project's root"
        ) from None
    return EXIT_OK
