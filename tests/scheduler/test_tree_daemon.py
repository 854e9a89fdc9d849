"""The tree search inside a daemon process (a Dask worker, a process pool):
it cannot start worker processes, so it searches alone and says so."""

from __future__ import annotations

import multiprocessing
from typing import Any

from scheduler import solve, validate
from scheduler.generate import random_problem
from scheduler.tree import TreeOptions


def _solve_in_child(queue: Any) -> None:
    p = random_problem(3, 30, 3, 1, seed=4)
    r = solve(p, "tree", time_limit=1.2, seed=0, options=TreeOptions(workers=2))
    assert r.schedule is not None
    queue.put((validate(p, r.schedule), r.objective, r.stats.extra.get("workers")))


def test_a_daemon_process_searches_alone() -> None:
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_solve_in_child, args=(queue,), daemon=True)
    proc.start()
    makespan, objective, workers = queue.get(timeout=60)
    proc.join(timeout=30)
    assert proc.exitcode == 0
    assert makespan == objective
    assert workers == "1 (a daemon process may not start worker processes)"
