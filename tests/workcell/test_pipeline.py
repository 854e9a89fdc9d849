"""``workcell.run_cell``: the steps written once, checks before any long work."""

from __future__ import annotations

from pathlib import Path

import pytest

import workcell.pipeline
from multiarm.errors import FormatError, UsageError
from scheduler import validate
from workcell import CellRun, RunStatus, compile_cell, load_example, run_cell
from workcell.pipeline import MAX_FRAMES, RUN_FILES, load_faults, solve_cell


@pytest.fixture(scope="module")
def compiled() -> workcell.CompiledCell:
    return compile_cell(load_example("supersigma"))


def test_a_compiled_cell_skips_the_compile_and_everything_is_recorded(
    compiled: workcell.CompiledCell, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def refuse(*_args: object, **_kw: object) -> None:
        raise AssertionError("compiled again")

    monkeypatch.setattr(workcell.pipeline, "compile_cell", refuse)
    steps: list[str] = []
    run = run_cell(
        compiled,
        solver="greedy",
        out=tmp_path / "run",
        progress=lambda step, _detail: steps.append(step),
    )
    assert isinstance(run, CellRun) and run.compiled is compiled
    assert steps == ["solve", "simulate", "write"]
    assert run.status is RunStatus.OK and run.ok and run.failed_tasks == 0
    assert run.result.schedule is not None
    assert validate(compiled, run.result.schedule) == pytest.approx(run.result.objective)
    assert [p.name for p in run.written] == list(RUN_FILES)
    assert all(p.is_file() for p in run.written)
    assert run.evaluations is None and not run.time_bound  # greedy: no work limit


def test_failed_tasks_are_a_status_not_an_exception(compiled: workcell.CompiledCell) -> None:
    faults = [{"kind": "arm_failure", "arm": "left", "at": 0.5}]
    run = run_cell(compiled, solver="greedy", faults=faults)
    assert run.status is RunStatus.TASKS_FAILED and not run.ok
    assert run.failed_tasks == int(run.sim.metrics.failed_tasks) > 0


def test_faults_from_a_file_equal_the_same_records(
    compiled: workcell.CompiledCell, tmp_path: Path
) -> None:
    f = tmp_path / "f.toml"
    f.write_text('[[faults]]\nkind = "arm_failure"\narm = "right"\nat = 20.0\n')
    plan = load_faults(f)
    assert plan == load_faults([{"kind": "arm_failure", "arm": "right", "at": 20.0}])
    a = run_cell(compiled, solver="greedy", faults=f, seed=2)
    b = run_cell(compiled, solver="greedy", faults=plan, seed=2)
    assert a.sim.tasks_frame().equals(b.sim.tasks_frame())


def test_bad_input_is_refused_before_the_compile(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def refuse(*_args: object, **_kw: object) -> None:
        raise AssertionError("compiled before checking the arguments")

    monkeypatch.setattr(workcell.pipeline, "compile_cell", refuse)
    cell = load_example("supersigma")
    bad = tmp_path / "bad.json"
    bad.write_text('[{"kind": "arm_failure", "arm": "left"}]')
    with pytest.raises(FormatError, match=rf"{bad.name}: faults\[0\]"):
        run_cell(cell, faults=bad)
    with pytest.raises(UsageError, match=r"expected a \.toml or \.json file"):
        run_cell(cell, faults=str(tmp_path / "f.txt"))
    with pytest.raises(UsageError, match=rf"frames must be an int in 0\.\.{MAX_FRAMES}"):
        run_cell(cell, frames=MAX_FRAMES + 1)
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(UsageError, match="is not a directory"):
        run_cell(cell, out=blocker)
    with pytest.raises(UsageError, match="is a file"):
        run_cell(cell, out=blocker / "sub")
    with pytest.raises(UsageError, match="evaluations is a work limit of the tree search"):
        run_cell(cell, solver="greedy", evaluations=10)
    with pytest.raises(UsageError, match="time_limit must be a number of seconds"):
        run_cell(cell, time_limit=float("nan"))
    with pytest.raises(UsageError, match="seed must be an int in 0"):
        run_cell(cell, seed=-1)
    assert not (tmp_path / "never").exists()


def test_the_same_seed_gives_the_same_plan_under_the_work_limit(
    compiled: workcell.CompiledCell,
) -> None:
    a = solve_cell(compiled, seed=5, evaluations=300, time_limit=60.0)
    b = solve_cell(compiled, seed=5, evaluations=300, time_limit=60.0)
    assert a.schedule.to_dict(compiled.problem) == b.schedule.to_dict(compiled.problem)
    assert a.evaluations == 300 and not a.time_bound
    with pytest.raises(UsageError, match="compile_options: the cell is compiled already"):
        solve_cell(compiled, compile_options=workcell.CompileOptions())
