"""Zone-constrained problems from the seeded generator: gaps to CP-SAT.

A thin wrapper of the sweep ``benchmarks/sweeps/generated.toml``: problems
from :func:`scheduler.generate.random_problem` (arms of different speeds and
capabilities, precedence, releases, exclusive and shared zones, tools,
travel setups); CP-SAT gets a long limit to prove optima (the reference),
tree, CP-SAT and greedy the short one. Where the reference proved its
schedule optimal, the gap is to the optimum; elsewhere to its best bound
(and tree is also compared with the reference's schedule). It runs the sweep
(resuming; ``--fresh`` to start over) into
``benchmarks/results/generated.parquet`` and writes the table of
:func:`workcell.experiments.analysis.generated_table` to ``generated.md``
and ``generated.json``.

Run: ``python -m benchmarks.bench_generated [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

from benchmarks.common import table_main

NAME = "generated"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import generated_table

    table_main(NAME, generated_table, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
