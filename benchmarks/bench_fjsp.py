"""FJSP benchmark: Brandimarte MK01-MK10 and Fattahi SFJS/MFJS with every solver.

A thin wrapper of the sweep ``benchmarks/sweeps/fjsp.toml`` (every solver at
the same time limit and seed on every instance, one run at a time): it runs
the sweep (resuming where a previous run stopped; ``--fresh`` to start
over), stores one Parquet row per run in ``benchmarks/results/fjsp.parquet``
and writes the table of :func:`workcell.experiments.analysis.fjsp_table`
(makespans validated, gaps to the best-known makespans of
``../shared/data/fjsp/README.md``, for mk10 also to its soft lower bound
189) to ``fjsp.md`` and ``fjsp.json``.

Run: ``python -m benchmarks.bench_fjsp [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

from benchmarks.common import table_main

NAME = "fjsp"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import fjsp_table

    table_main(NAME, fjsp_table, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
