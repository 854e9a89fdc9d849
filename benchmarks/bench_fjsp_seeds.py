"""The seed spread of the Brandimarte numbers: tree and CP-SAT, seeds 0-4.

A thin wrapper of the sweep ``benchmarks/sweeps/fjsp_seeds.toml`` (MK01-MK10,
both solvers at 10 s with solver seeds 0-4, one run at a time): it runs the
sweep (resuming; ``--fresh`` to start over) into
``benchmarks/results/fjsp_seeds.parquet`` and writes the table of
:func:`workcell.experiments.analysis.seed_spread_table` (per instance the
makespan of each seed, per seed the mean gap to the best-known makespans) to
``fjsp_seeds.md`` and ``fjsp_seeds.json``.

Run: ``python -m benchmarks.bench_fjsp_seeds [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

from benchmarks.common import table_main

NAME = "fjsp_seeds"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import seed_spread_table

    table_main(NAME, seed_spread_table, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
