"""Fixtures of the replay tests: scara4 compiled once per test process, run
with its greedy plan (seed 0), with and without faults."""

from __future__ import annotations

from typing import Any

import pytest

from scheduler import solve
from workcell import ArmFailure, Crash, compile_cell, load_example, simulate


@pytest.fixture(scope="session")
def scara4_cc() -> Any:
    return compile_cell(load_example("scara4"))


@pytest.fixture(scope="session")
def scara4_run(scara4_cc: Any) -> Any:
    return simulate(scara4_cc, solve(scara4_cc.problem, "greedy", seed=0).schedule)


@pytest.fixture(scope="session")
def scara4_faulty_run(scara4_cc: Any) -> Any:
    """se crashes at 20 s (stands 2 s), nw fails for good at 60 s."""
    plan = solve(scara4_cc.problem, "greedy", seed=0).schedule
    faults = [Crash("se", 20.0, recovery=2.0), ArmFailure("nw", 60.0)]
    return simulate(scara4_cc, plan, faults=faults)


@pytest.fixture(scope="session")
def scara4_failed_run(scara4_cc: Any) -> Any:
    """se fails for good at 30 s and nothing is re-solved: 15 tasks fail."""
    from workcell import SimOptions

    plan = solve(scara4_cc.problem, "greedy", seed=0).schedule
    return simulate(
        scara4_cc, plan, faults=[ArmFailure("se", 30.0)], options=SimOptions(resolve=False)
    )
