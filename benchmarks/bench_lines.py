"""Line-cell zone problems from a second generator: tree against CP-SAT.

A thin wrapper of the sweep ``benchmarks/sweeps/lines.toml``: problems from
:func:`scheduler.generate.random_line_problem` (arms on a line, zones as
stretches of it, each arm's windows from its own motion, tools, travel
setups), a structure the tree search was not developed on. CP-SAT gets a
long limit to prove optima (the reference), tree, CP-SAT and greedy the
short one. It runs the sweep (resuming; ``--fresh`` to start over) into
``benchmarks/results/lines.parquet`` and writes the table of
:func:`workcell.experiments.analysis.generated_table` to ``lines.md`` and
``lines.json``.

Run: ``python -m benchmarks.bench_lines [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

from functools import partial

from benchmarks.common import table_main

NAME = "lines"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import generated_table

    render = partial(
        generated_table, title="Line-cell zone problems (second generator)", sweep=NAME
    )
    table_main(NAME, render, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
