"""A sweep on a Dask LocalCluster gives exactly the results of the local run.

Every run of the sweep is work-limited (tree: ``max_evaluations``; CP-SAT:
one worker and ``max_deterministic_time``; greedy: one list pass), so its
result depends on its seed only, wherever it runs.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from workcell.experiments import parse_sweep, run_sweep

SWEEP = """
[sweep]
name = "cluster"

[[instances]]
kind = "generated"
sizes = [[2, 8, 2, 1], [3, 10, 3, 1]]
seeds = [0, 1]

[[solvers]]
solver = "greedy"

[[solvers]]
solver = "tree"
seeds = ["instance"]
options = { max_evaluations = 100, workers = 1 }

[[solvers]]
solver = "cpsat"
options = { workers = 1, max_deterministic_time = 0.3 }
"""

SAME = ["status", "makespan", "objective", "bound", "nodes", "evaluations", "first_objective"]


@pytest.mark.slow  # about 20-30 s on a busy 2-core machine: the cluster's processes start
def test_a_local_cluster_reproduces_the_local_run(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    sweep = parse_sweep(SWEEP, filename="cluster.toml")
    local = run_sweep(sweep, workers=1, out=tmp_path / "local.parquet", progress=False)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = run_sweep(
            sweep, dask_address=client, out=tmp_path / "dask.parquet", progress=False
        )
        # the address form connects a client of its own
        again = run_sweep(
            sweep, dask_address=cluster.scheduler_address, out=tmp_path / "dask.parquet"
        )
    assert (local.ran, remote.ran, remote.failed) == (12, 12, 0)
    assert (again.ran, again.skipped) == (0, 12)  # resumed: everything was done
    a = local.results().set_index("key").sort_index()
    b = remote.results().set_index("key").sort_index()
    assert list(a.index) == list(b.index)
    assert a[SAME].equals(b[SAME])
    assert os.getpid() not in set(b["pid"].astype(int))  # the runs really ran on the workers
