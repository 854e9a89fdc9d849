"""FJSP with sequence-dependent setup times (SDST-FJSP): tree against CP-SAT.

A thin wrapper of the sweep ``benchmarks/sweeps/setups.toml``: problems from
:func:`scheduler.generate.random_setup_fjsp` (Brandimarte-like FJSPs, a
metric setup matrix per machine drawn as a fraction of the processing
times). CP-SAT gets a long limit to prove optima (the reference, with its
setup circuits), tree, CP-SAT and greedy the short one. It runs the sweep
(resuming; ``--fresh`` to start over) into
``benchmarks/results/setups.parquet`` and writes the table of
:func:`workcell.experiments.analysis.generated_table` to ``setups.md`` and
``setups.json``.

Run: ``python -m benchmarks.bench_setups [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

from functools import partial

from benchmarks.common import table_main

NAME = "setups"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import generated_table

    render = partial(
        generated_table, title="FJSP with sequence-dependent setups (SDST-FJSP)", sweep=NAME
    )
    table_main(NAME, render, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
