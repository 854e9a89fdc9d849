"""Waits at zone borders: the executed total equals the plan's when the plan runs as planned."""

from __future__ import annotations

import pytest

from scheduler import solve
from workcell import SimOptions, compile_cell, load_example, simulate


@pytest.mark.parametrize("name", ["supersigma", "scara4"])
def test_border_waits_count_each_stop_once(name: str) -> None:
    cc = compile_cell(load_example(name))
    plan = solve(cc.problem, "greedy", seed=0).schedule
    assert plan.total_wait() > 0  # the case has waits to count
    m = simulate(cc, plan, seed=0, options=SimOptions(monitor=False)).metrics
    assert m.border_wait == pytest.approx(plan.total_wait(), abs=1e-6)
    assert m.summary()["zone_wait"] == pytest.approx(m.border_wait)
    # per zone, a stop where several zones are entered counts for each of them
    assert sum(m.zone_wait.values()) >= m.border_wait - 1e-9
    assert m.to_dict()["summary"]["zone_wait"] == pytest.approx(plan.total_wait(), abs=1e-6)
