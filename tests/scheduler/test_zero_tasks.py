"""A problem without tasks: every solver returns the empty plan, the CLI prints a line."""

from __future__ import annotations

from pathlib import Path

import pytest

from scheduler import SOLVERS, Model, save_problem, solve, validate
from scheduler.reference import solve_reference
from workcell.cli import main


def _empty(zones: bool = False) -> Model:
    m = Model("empty")
    m.add_arm("a")
    m.add_arm("b")
    if zones:
        m.add_zone("z")
        m.add_tool("k")
    return m


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("waits", [True, False])
def test_every_solver_returns_an_empty_optimal_plan(solver: str, waits: bool) -> None:
    p = _empty(zones=waits).build()
    r = solve(p, solver, time_limit=1, seed=3, waits=waits)  # type: ignore[arg-type]
    assert r.status.value == "optimal"
    assert r.objective == 0.0 and r.bound == 0.0
    assert r.schedule is not None and r.schedule.n_tasks == 0
    assert validate(p, r.schedule) == 0.0
    plan = r.plan
    assert plan is not None
    assert "no tasks" in plan.table()
    assert plan.table(max_rows=0) == plan.table()
    assert plan.to_csv().count("\n") == 1  # the header only


def test_the_reference_on_an_empty_problem() -> None:
    r = solve_reference(_empty(zones=True).build(), 1, 0)
    assert (r.status, r.makespan, r.bound) == ("optimal", 0.0, 0.0)


@pytest.mark.parametrize("solver", SOLVERS)
def test_cli_schedule_prints_a_line_for_an_empty_problem(
    solver: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = save_problem(_empty().build(), tmp_path / "empty.json")
    out_csv = tmp_path / "plan.csv"
    code = main(
        ["schedule", str(path), "--solver", solver, "--time-limit", "1", "--out", str(out_csv)]
    )
    captured = capsys.readouterr()
    assert code == 0
    assert "Traceback" not in captured.out + captured.err
    assert "no tasks: the plan is empty, makespan 0" in captured.out
    assert out_csv.read_text().count("\n") == 1  # the header only
