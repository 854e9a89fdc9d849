"""Scale: the first schedule and its quality at 16 arms x 1000 tasks x 30 zones.

A thin wrapper of the sweep ``benchmarks/sweeps/scale.toml``: on seeded
generated problems, the greedy run is the first valid schedule (the
earliest-finish-time list schedule that also starts the tree search; its
``build_time`` is building the problem, its ``runtime`` the time to the
first schedule, measured warm: the compiled kernel is loaded before the
clock, reported apart as ``warmup_time``), then the tree search's schedule
after the time limit, and the lower bound. It runs the sweep (resuming;
``--fresh`` to start over) into ``benchmarks/results/scale.parquet`` and
writes the table of :func:`workcell.experiments.analysis.scale_table` to
``scale.md`` and ``scale.json``.

Run: ``python -m benchmarks.bench_scale [--fresh] [--workers N] [--quick]``.
"""

from __future__ import annotations

from benchmarks.common import table_main

NAME = "scale"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import scale_table

    table_main(NAME, scale_table, argv, __doc__, speed=False)


if __name__ == "__main__":
    main()
