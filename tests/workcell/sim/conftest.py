"""Fixtures shared by the simulation tests: the small built-in cells, compiled
once per test process, and their greedy plans (seed 0). A module that needs
another cell or plan defines its own fixture of the same name."""

from __future__ import annotations

from typing import Any

import pytest

from scheduler import solve
from workcell import compile_cell, load_example


@pytest.fixture(scope="session")
def cell() -> Any:
    return compile_cell(load_example("supersigma"))


@pytest.fixture(scope="session")
def plan(cell: Any) -> Any:
    return solve(cell.problem, "greedy", seed=0).schedule


@pytest.fixture(scope="session")
def scara4() -> Any:
    return compile_cell(load_example("scara4"))


@pytest.fixture(scope="session")
def scara4_plan(scara4: Any) -> Any:
    return solve(scara4.problem, "greedy", seed=0).schedule
