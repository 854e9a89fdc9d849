"""Experiments at scale: declarative sweeps, results with provenance, analysis plots.

* :func:`load_sweep` reads a sweep file (TOML: instances x solver
  configurations x seeds x repetitions, and ``benchmark`` instances: named
  measurement functions whose rows are stored like solver runs); :func:`run_sweep` runs it in a local
  process pool or on a ``dask.distributed`` cluster, streaming results,
  resuming where an interrupted sweep stopped, recording failures. The
  machinery is split by job: :mod:`~workcell.experiments.spec` (the sweep
  file's schema and validation), :mod:`~workcell.experiments.grid` (its
  records), :mod:`~workcell.experiments.instances` (problem factories),
  :mod:`~workcell.experiments.runner` (one run, through :func:`scheduler.solve`),
  :mod:`~workcell.experiments.executors` (local pool, Dask);
  :mod:`workcell.experiments.sweep` gathers the public names.
* :func:`read_results` reads the Parquet results (one row per run, with
  provenance) into pandas: :mod:`~workcell.experiments.results` (the journal
  and Parquet), :mod:`~workcell.experiments.rows` (the columns and rows),
  :mod:`~workcell.experiments.provenance` (where a run comes from).
* :mod:`workcell.experiments.analysis`: references and gaps
  (:mod:`~workcell.experiments.analysis.gaps`), performance profiles, gap
  over time, time to target, scaling and box plots
  (:mod:`~workcell.experiments.analysis.plots`, drawn with matplotlib), the
  benchmark tables and the end-of-sweep summary
  (:mod:`~workcell.experiments.analysis.tables`).

Modules import one way: ``sweep`` (the names) > ``executors`` > ``spec``,
``runner``, ``results``, ``analysis.tables``; ``runner`` > ``instances``,
``rows``; ``results`` > ``rows`` > ``provenance``, ``grid``; ``spec`` >
``instances`` > ``grid``; ``analysis`` reads results frames and imports
none of them. Only the optional dependencies (pandas, pyarrow, matplotlib,
tqdm, dask.distributed) are imported inside functions.

The command ``multiarm sweep FILE [--dask-address ADDRESS] [--workers N]`` runs a sweep file.
"""

from workcell.experiments.executors import check_dask_address
from workcell.experiments.results import read_results, write_results
from workcell.experiments.rows import COLUMNS
from workcell.experiments.sweep import (
    BENCHMARK,
    InstanceSpec,
    Run,
    SolverConfig,
    Sweep,
    SweepOutcome,
    benchmark_function,
    build_problem,
    load_sweep,
    parse_sweep,
    run_one,
    run_sweep,
)

__all__ = [
    "BENCHMARK",
    "COLUMNS",
    "InstanceSpec",
    "Run",
    "SolverConfig",
    "Sweep",
    "SweepOutcome",
    "benchmark_function",
    "build_problem",
    "check_dask_address",
    "load_sweep",
    "parse_sweep",
    "read_results",
    "run_one",
    "run_sweep",
    "write_results",
]
