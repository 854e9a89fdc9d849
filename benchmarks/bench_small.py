"""Small zone-constrained problems: time to optimal and final makespan, tree vs CP-SAT.

A thin wrapper of the sweep ``benchmarks/sweeps/small.toml``: 20 problems
from :func:`scheduler.generate.random_problem` (2-3 arms, 8-14 tasks,
exclusive and shared zones, a tool, travel setups; half with arms starting
in exclusive zones), each solved by ``tree`` and ``cpsat`` (1 worker) at the
same time limit. Time to optimal is when the solver proved its schedule
optimal (status ``optimal``: its runtime, as it stops there); "-" when it
did not within the limit. It runs the sweep (resuming; ``--fresh`` to start
over) into ``benchmarks/results/small.parquet`` and writes the table of
:func:`workcell.experiments.analysis.small_table` to ``small.md`` and
``small.json``.

Run: ``python -m benchmarks.bench_small [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

from benchmarks.common import table_main

NAME = "small"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import small_table

    table_main(NAME, small_table, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
