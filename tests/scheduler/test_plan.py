"""A self-describing plan (a schedule bound to its problem) and Problem equality."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np
import pytest

from multiarm.errors import UsageError, ValidationError
from scheduler import (
    FunctionSetup,
    Model,
    Plan,
    Problem,
    Schedule,
    TreeOptions,
    Window,
    load_problem,
    save_problem,
    solve,
    validate,
)
from scheduler.generate import random_problem
from scheduler.online import CellState, reschedule

COLUMNS = ["task", "arm", "mode", "start", "end", "duration", "wait", "detour"]


def _waiting_problem() -> Problem:
    # B waits 1 s at its border 3 for E (see test_solvers): a plan with a wait
    m = Model("waits")
    m.add_zone("E")
    m.add_zone("F")
    m.add_arm("A")
    m.add_arm("B")
    m.add_task("hold")
    m.add_mode("hold", "A", 6.0, windows=[Window("E", 0.0, 4.0), Window("F", 3.0, 6.0)])
    m.add_task("pass")
    m.add_mode("pass", "B", 6.0, windows=[Window("F", 0.0, 3.0), Window("E", 3.0, 5.0)])
    return m.build()


def test_a_solved_schedule_carries_its_problem() -> None:
    p = _waiting_problem()
    r = solve(p, "tree", time_limit=None, options=TreeOptions(max_evaluations=100))
    assert r.schedule is not None and r.schedule.bound_problem is p
    df = r.schedule.to_dataframe()  # no argument needed
    assert df.columns.tolist() == COLUMNS
    assert df.set_index("task").loc["pass", "wait"] == 1.0
    assert np.allclose(df["end"], df["start"] + df["duration"] + df["wait"] + df["detour"])
    # the old call with the problem still works and gives the same frame
    assert r.schedule.to_dataframe(p).equals(df)
    plan = r.plan
    assert plan is not None and plan.makespan == r.objective == plan.validate() == 7.0
    assert plan.to_dataframe().equals(df)


def test_the_reservations_frame() -> None:
    p = _waiting_problem()
    s = solve(p, "greedy").schedule
    assert s is not None
    res = s.reservations_frame()
    assert res.columns.tolist() == ["kind", "resource", "task", "arm", "start", "end"]
    assert res["start"].is_monotonic_increasing
    e = res[(res.resource == "E") & (res.task == "pass")]
    assert e[["start", "end"]].values.tolist() == [[4.0, 6.0]]  # after A leaves E at 4


def test_reschedule_binds_too() -> None:
    p = random_problem(3, 12, 2, 1, seed=2)
    r = reschedule(p, CellState(time=0.0), None, time_limit=30.0, max_evaluations=20)
    assert r.schedule is not None and r.schedule.bound_problem is p
    assert len(r.schedule.to_dataframe()) == p.n_tasks


def test_an_unbound_schedule_asks_for_its_problem() -> None:
    p = _waiting_problem()
    s = Schedule.from_starts(p, [0, 1], [0.0, 6.0])
    assert s.bound_problem is None
    with pytest.raises(UsageError, match="not bound to a problem"):
        s.to_dataframe()
    assert s.bind(p).to_dataframe()["start"].tolist() == [0.0, 6.0]
    assert s.bind(p) == s  # binding changes no data
    with pytest.raises(ValidationError, match="a schedule of 2 tasks cannot be bound"):
        s.bind(random_problem(2, 3, 1, 0, seed=0))
    with pytest.raises(ValidationError, match="no plan for a problem of 3 tasks"):
        Plan(random_problem(2, 3, 1, 0, seed=0), s)


def test_the_table_and_the_files(tmp_path: Path) -> None:
    p = random_problem(3, 9, 2, 1, seed=4)
    r = solve(p, "greedy")
    plan = r.plan
    assert plan is not None
    lines = plan.table().splitlines()
    assert lines[0].split() == COLUMNS and len(lines) == 2 + p.n_tasks
    assert plan.table(max_rows=3).splitlines()[-1] == f"... {p.n_tasks - 3} more tasks"
    js = plan.write(tmp_path / "s.json")
    back = Schedule.from_dict(p, json.loads(js.read_text()))
    assert validate(p, back) == r.objective
    rows = list(csv.DictReader(io.StringIO(plan.write(tmp_path / "s.csv").read_text())))
    assert [row["task"] for row in rows] == list(p.task_names)
    assert float(rows[0]["end"]) == pytest.approx(float(r.schedule.end[0]))  # type: ignore[union-attr]
    with pytest.raises(UsageError, match=r"\.json or \.csv, not '\.txt'"):
        plan.write(tmp_path / "s.txt")
    with pytest.raises(UsageError, match="cannot write"):
        plan.write(tmp_path / "missing" / "s.csv")


# ------------------------------------------------------------- equality


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_saved_problem_loads_equal(tmp_path: Path, seed: int) -> None:
    p = random_problem(3, 10, 3, 1, seed=seed, start_zones=seed == 1)
    q = load_problem(save_problem(p, tmp_path / "p.json"))
    assert q == p and hash(q) == hash(p) and q is not p
    assert load_problem(save_problem(_waiting_problem(), tmp_path / "w.json")) == _waiting_problem()


def test_problems_that_differ_are_not_equal() -> None:
    p = random_problem(3, 10, 3, 1, seed=0)
    assert p != random_problem(3, 10, 3, 1, seed=1)
    d = p.to_dict()
    d["tasks"][0]["modes"][0]["duration"] += 0.5
    from scheduler import problem_from_dict

    assert problem_from_dict(d) != p
    d = p.to_dict()
    d["name"] = "other"
    assert problem_from_dict(d) != p
    assert p != "not a problem"


def test_a_setup_that_is_code_is_equal_only_to_itself() -> None:
    def build(fn: FunctionSetup) -> Problem:
        m = Model()
        m.add_arm("a")
        m.add_task("t")
        m.add_mode("t", "a", 1.0)
        m.set_setup(fn)
        return m.build()

    f = FunctionSetup(lambda a, p, n: 1.0)
    assert build(f) == build(f)
    assert build(f) != build(FunctionSetup(lambda a, p, n: 1.0))
