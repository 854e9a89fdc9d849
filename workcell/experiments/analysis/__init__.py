"""Sweep results in pandas, the standard plots of the scheduling literature, and the tables.

Every plot function returns a :class:`matplotlib.figure.Figure` built
without pyplot (no global state, no display needed: it renders with Agg,
``fig.savefig("x.png")``); each has a ``*_data`` twin that returns the
numbers behind it as a DataFrame.

* :func:`performance_profile`: Dolan and Moré's profiles. For solver ``s``
  and instance ``p``, the ratio ``r(p, s) = m(p, s) / min_s' m(p, s')`` of
  its makespan to the best one; the profile ``rho_s(tau)`` is the share of
  instances with ``r(p, s) <= tau`` (a run without a schedule has ratio inf).
  ``rho_s(1)`` is the share where ``s`` is best; the curve's height at large
  ``tau`` the share solved at all.
* :func:`gap_over_time`: the median gap ``(incumbent - reference) /
  reference`` of each solver's runs over time, from the improvements each
  run recorded; the reference is the best-known makespan where the sweep
  file gives one, else the best makespan of any run on the instance
  (:func:`reference`).
* :func:`time_to_target`: the share of runs whose incumbent came within a
  relative ``target`` of the reference by time ``t`` (an empirical CDF).
* :func:`scaling`: a measure (runtime, gap, makespan, ...) against problem
  size (tasks, arms or zones): median and inter-quartile band per solver.
* :func:`box_per_solver`: the distribution of a measure per solver.
* :func:`fjsp_table`, :func:`seed_spread_table`, :func:`generated_table`,
  :func:`small_table`, :func:`cells_table`, :func:`scale_table`: the Markdown tables of
  ``benchmarks/results/`` from the results of the sweep files in
  ``benchmarks/sweeps/``; :func:`sweep_note` says what ran, on what;
  :func:`summary_table` is the short table ``multiarm sweep`` prints at its end.
* :func:`measurements`: the rows the ``benchmark`` runs of a sweep measured
  (the speed tables), as one DataFrame.

Examples
--------
>>> import pandas as pd
>>> df = pd.DataFrame({
...     "family": ["f"] * 4, "instance": ["a", "a", "b", "b"],
...     "label": ["x", "y", "x", "y"], "makespan": [10.0, 12.0, 8.0, 4.0]})
>>> performance_profile_data(df, taus=[1.0, 1.2, 2.0]).to_dict("list")  # x best on a, y on b
{'x': [0.5, 0.5, 1.0], 'y': [0.5, 1.0, 1.0]}
"""

from workcell.experiments.analysis.gaps import incumbent_at, reference, with_gaps
from workcell.experiments.analysis.plots import (
    box_per_solver,
    gap_over_time,
    gap_over_time_data,
    performance_profile,
    performance_profile_data,
    scaling,
    scaling_data,
    time_to_target,
    time_to_target_data,
)
from workcell.experiments.analysis.seeds import seed_spread_table
from workcell.experiments.analysis.tables import (
    cells_table,
    fjsp_table,
    generated_table,
    measurements,
    scale_table,
    small_table,
    summary_table,
    sweep_note,
)

__all__ = [
    "box_per_solver",
    "cells_table",
    "fjsp_table",
    "gap_over_time",
    "gap_over_time_data",
    "generated_table",
    "incumbent_at",
    "measurements",
    "performance_profile",
    "performance_profile_data",
    "reference",
    "scale_table",
    "scaling",
    "scaling_data",
    "seed_spread_table",
    "small_table",
    "summary_table",
    "sweep_note",
    "time_to_target",
    "time_to_target_data",
    "with_gaps",
]
