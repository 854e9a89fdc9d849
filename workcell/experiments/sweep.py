"""Declarative sweeps: a TOML file names a grid of solver runs; run it locally or on Dask.

The sweep machinery is split by job; this module gathers its public names
(the stable import path ``workcell.experiments.sweep``):

* :mod:`workcell.experiments.spec` -- the sweep file, its schema and records;
* :mod:`workcell.experiments.instances` -- problem factories;
* :mod:`workcell.experiments.runner` -- one run, through :func:`scheduler.solve`;
* :mod:`workcell.experiments.executors` -- this process, a local pool, Dask;
* :mod:`workcell.experiments.results` -- the journal and Parquet
  (:mod:`~workcell.experiments.rows` the rows, :mod:`~workcell.experiments.provenance`
  where they come from).

Examples
--------
>>> sweep = parse_sweep('''
... [sweep]
... name = "tiny"
... [[instances]]
... kind = "generated"
... sizes = [[2, 6, 2, 1]]
... seeds = [0, 1]
... [[solvers]]
... solver = "greedy"
... [[solvers]]
... solver = "tree"
... options = { max_evaluations = 50 }
... ''', filename="tiny.toml")
>>> len(sweep.runs()), sweep.runs()[0].instance.name
(4, '2x6x2x1-s0')
>>> row = run_one(sweep.runs()[0])
>>> row["status"], row["makespan"] == row["objective"]
('feasible', True)
"""

from workcell.experiments.executors import SweepOutcome, run_sweep
from workcell.experiments.instances import benchmark_function, build_problem
from workcell.experiments.runner import run_one
from workcell.experiments.spec import (
    BENCHMARK,
    InstanceSpec,
    Run,
    SolverConfig,
    Sweep,
    load_sweep,
    parse_sweep,
    sweep_from_dict,
)

__all__ = [
    "BENCHMARK",
    "InstanceSpec",
    "Run",
    "SolverConfig",
    "Sweep",
    "SweepOutcome",
    "benchmark_function",
    "build_problem",
    "load_sweep",
    "parse_sweep",
    "run_one",
    "run_sweep",
    "sweep_from_dict",
]
