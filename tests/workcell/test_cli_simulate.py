"""``multiarm simulate`` and the simulating ``multiarm demo``: outputs, tables, early errors."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

import workcell.cli.demo
import workcell.compile
import workcell.pipeline
from workcell.cli import main

OUTPUTS = (
    "trace.json",
    "metrics.json",
    "tasks.csv",
    "schedule.json",
    "gantt.png",
    "zones.png",
    "instants.png",
    "replay.json",
    "replay.html",
)


def _is_png(path: Path) -> bool:
    return path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_simulate_writes_every_output_and_prints_the_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    assert main(["simulate", "supersigma", "--solver", "greedy", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    for row in (
        "makespan (s)",
        "utilisation left",
        "utilisation right",
        "zone waits (s)",
        "sleeps / wakes",
        "detours",
        "re-solves",
        "re-solve latency p50 / p99 (ms)",
        "messages; delay mean / p99 (ms)",
        "failed tasks",
    ):
        assert f"\n{row} " in text
    assert "metric" in text and "planned" in text and "executed" in text
    for name in OUTPUTS:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    for name in ("gantt.png", "zones.png", "instants.png"):
        assert _is_png(out / name)
    tasks = pd.read_csv(out / "tasks.csv")
    assert len(tasks) == 10 and set(tasks["status"]) == {"done"}
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["summary"]["failed_tasks"] == 0
    trace = json.loads((out / "trace.json").read_text())
    assert trace["format"] == "multiarm.trace/1" and trace["events"]
    # the 3D replay (issue 19): the page is written, and 'view' rebuilds it from replay.json
    assert json.loads((out / "replay.json").read_text())["format"] == "multiarm.replay/1"
    page = out / "again.html"
    assert main(["view", str(out), "--out", str(page)]) == 0
    assert page.read_text().startswith("<!DOCTYPE html>")
    assert page.stat().st_size > 100_000  # the viewer script is inside: the page works offline
    schedule = json.loads((out / "schedule.json").read_text())
    assert len(schedule["tasks"]) == 10
    # the table's planned makespan is the plan written out
    (line,) = [ln for ln in text.splitlines() if ln.startswith("makespan (s)")]
    assert float(line.split()[2]) == pytest.approx(schedule["makespan"], abs=0.01)


def test_simulate_with_a_faults_file_re_solves(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    faults = tmp_path / "faults.toml"
    faults.write_text('[[faults]]\nkind = "arm_failure"\narm = "right"\nat = 20.0\n')
    out = tmp_path / "run"
    args = ["simulate", "supersigma", "--solver", "greedy", "--faults", str(faults)]
    assert main([*args, "--out", str(out), "--seed", "3"]) == 0
    text = capsys.readouterr().out
    assert f"faults from {faults}" in text
    summary = json.loads((out / "metrics.json").read_text())["summary"]
    assert summary["resolves"] >= 1
    trace = json.loads((out / "trace.json").read_text())["events"]
    assert any(e["kind"] == "fault" and e["arm"] == "right" for e in trace)
    # a JSON list of records works the same way
    as_json = tmp_path / "faults.json"
    as_json.write_text(json.dumps([{"kind": "arm_failure", "arm": "right", "at": 20.0}]))
    out2 = tmp_path / "run2"
    assert main([*args[:-1], str(as_json), "--out", str(out2), "--seed", "3"]) == 0
    capsys.readouterr()
    # the same faults from either file give the same run (wall-clock figures aside)
    assert _same_but_wall(out2 / "metrics.json", out / "metrics.json")


def _same_but_wall(a: Path, b: Path) -> bool:
    da, db = json.loads(a.read_text()), json.loads(b.read_text())
    for d in (da, db):
        for k in list(d["summary"]):
            if "latency" in k or "wall" in k or k == "resolves_over_budget":
                del d["summary"][k]
        del d["resolve_latency"]
    return bool(da == db)


@pytest.fixture
def no_compile(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any compile is a failure: bad arguments must be refused before the long work."""

    def refuse(*_args: object, **_kw: object) -> None:
        raise AssertionError("compiled before checking the arguments")

    monkeypatch.setattr(workcell.compile, "compile_cell", refuse)
    monkeypatch.setattr(workcell.pipeline, "compile_cell", refuse)
    monkeypatch.setattr(workcell.cli.demo, "compile_cell", refuse)


def _bad(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    return err


@pytest.mark.usefixtures("no_compile")
def test_bad_arguments_are_one_line_errors_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    err = _bad(["simulate", "nocell"], capsys)
    assert "unknown cell 'nocell'" in err and "supersigma, scara4, cell8" in err
    err = _bad(["simulate", "supersigma", "--network", "pigeon"], capsys)
    assert "--network: unknown medium 'pigeon'" in err and "ideal" in err
    blocker = tmp_path / "file"
    blocker.write_text("")
    err = _bad(["simulate", "supersigma", "--out", str(blocker / "sub")], capsys)
    assert f"--out: cannot create directory {str(blocker / 'sub')!r}" in err
    err = _bad(["simulate", "supersigma", "--out", str(blocker)], capsys)
    assert "is not a directory" in err
    err = _bad(["simulate", "supersigma", "--time-limit", "0"], capsys)
    assert "--time-limit must be a finite number of seconds > 0" in err
    err = _bad(["simulate", "supersigma", "--tick", "-1"], capsys)
    assert "--tick must be a finite number of seconds in (0, 1]" in err
    err = _bad(["simulate", "supersigma", "--tick", "1e6"], capsys)
    assert "--tick must be a finite number of seconds in (0, 1], got 1000000.0" in err
    err = _bad(["simulate", "supersigma", "--faults", str(tmp_path / "missing.toml")], capsys)
    assert "--faults: cannot read" in err and "No such file" in err
    bad = tmp_path / "bad.toml"
    bad.write_text("[[faults]]\nkind = \n")
    err = _bad(["simulate", "supersigma", "--faults", str(bad)], capsys)
    assert f"--faults: {bad}:2:" in err and "TOML syntax error" in err  # file:line:col
    bad.write_text('[[faults]]\nkind = "crash"\narm = "left"\n')
    err = _bad(["simulate", "supersigma", "--faults", str(bad)], capsys)
    assert f"--faults: {bad}: faults[0]: missing field 'at'" in err
    bad_json = tmp_path / "bad.json"
    bad_json.write_text('[{"kind": "meteor"}]')
    err = _bad(["simulate", "supersigma", "--faults", str(bad_json)], capsys)
    assert "faults[0].kind: unknown fault kind 'meteor'" in err
    bad_json.write_text("{")
    err = _bad(["simulate", "supersigma", "--faults", str(bad_json)], capsys)
    assert f"--faults: {bad_json}:1:2: " in err
    bad_json.write_text('{"faults": 3}')
    err = _bad(["simulate", "supersigma", "--faults", str(bad_json)], capsys)
    assert "expected a list of fault records under 'faults'" in err
    txt = tmp_path / "faults.txt"
    txt.write_text("")
    err = _bad(["simulate", "supersigma", "--faults", str(txt)], capsys)
    assert "expected a .toml or .json file" in err
    err = _bad(["simulate", "supersigma", "--solver", "greedy", "--evaluations", "9"], capsys)
    assert "--evaluations is a work limit of the tree search" in err
    err = _bad(["simulate", "supersigma", "--evaluations", "0"], capsys)
    assert "--evaluations must be >= 1, got 0" in err
    err = _bad(["simulate", "supersigma", "--evaluations", "10000001"], capsys)
    assert "--evaluations must be at most 10000000, got 10000001" in err
    err = _bad(["simulate", "supersigma", "--frames", "1000000"], capsys)
    assert "--frames must be at most 1000, got 1000000" in err
    err = _bad(["simulate", "supersigma", "--time-limit", "1e9"], capsys)
    assert "--time-limit must be at most 86400 s" in err
    err = _bad(["demo", "--cells", "nocell"], capsys)
    assert "--cells: unknown built-in cell 'nocell'" in err
    err = _bad(["demo", "--network", "pigeon", "--out", str(tmp_path / "d")], capsys)
    assert "--network: unknown medium 'pigeon'" in err


def test_demo_simulates_and_injects_a_fault(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert main(["demo", "--cells", "supersigma", "--time-limit", "0.3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "== supersigma:" in text and "per arm:" in text and "per zone:" in text
    assert "== planned vs executed" in text
    summary = text[text.index("== planned vs executed") :]
    (row,) = [ln for ln in summary.splitlines() if ln.startswith("supersigma ")]
    trace = json.loads((out / "supersigma" / "arm_failure" / "trace.json").read_text())["events"]
    (failure,) = [e for e in trace if e["kind"] == "fault" and "fail" in e["detail"]]
    assert f"{failure['arm']} at " in row  # the table names the arm that failed
    for run in ("nominal", "arm_failure"):
        for name in OUTPUTS:
            assert (out / "supersigma" / run / name).is_file(), (run, name)
    faulty = json.loads((out / "supersigma" / "arm_failure" / "metrics.json").read_text())
    assert faulty["summary"]["resolves"] >= 1
    nominal = json.loads((out / "supersigma" / "nominal" / "metrics.json").read_text())
    assert nominal["summary"]["resolves"] == 0 and nominal["summary"]["failed_tasks"] == 0


def test_demo_reports_a_stopped_run_and_fails(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from multiarm.errors import MultiarmError

    real = workcell.pipeline.simulate

    def stop_faulty_runs(*args: object, **kw: object) -> object:
        if kw.get("faults"):  # a non-empty fault plan
            raise MultiarmError("arms 'left' and 'right' collide at t = 1 s")
        return real(*args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(workcell.pipeline, "simulate", stop_faulty_runs)
    out = tmp_path / "out"
    argv = ["demo", "--cells", "supersigma", "--time-limit", "0.3", "--out", str(out)]
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert "error: supersigma, arm_failure run: arms 'left' and 'right' collide" in captured.err
    assert captured.err.rstrip().endswith("error: some runs stopped (see above)")
    (row,) = [
        ln
        for ln in captured.out[captured.out.index("== planned vs executed") :].splitlines()
        if ln.startswith("supersigma ")
    ]
    assert row.count("stopped") == 4  # makespan, re-solves, latency and failures of that run
    assert (out / "supersigma" / "nominal" / "gantt.png").is_file()
    assert not (out / "supersigma" / "arm_failure").exists()


def test_simulate_a_cell_file_with_motion_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from workcell.cell import _example_text

    cell = tmp_path / "mine.toml"
    cell.write_text(_example_text("supersigma").replace('name = "supersigma"', 'name = "mine"'))
    out = tmp_path / "run"
    argv = ["simulate", str(cell), "--solver", "greedy", "--frames", "3", "--out", str(out)]
    assert main(argv) == 0
    assert capsys.readouterr().out.startswith("mine: 2 arms, 10 tasks")
    frames = sorted((out / "frames").glob("frame_*.png"))
    assert [f.name for f in frames] == ["frame_0000.png", "frame_0001.png", "frame_0002.png"]
    not_a_cell = tmp_path / "cell.json"
    not_a_cell.write_text("{}")
    assert main(["simulate", str(not_a_cell)]) == 1
    assert "a cell file is a .toml file" in capsys.readouterr().err


def test_simulate_writes_to_out_cellname_by_default(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "supersigma", "--solver", "greedy"]) == 0
    text = capsys.readouterr().out
    assert "wrote 9 files to out/supersigma/" in text
    assert text.rstrip().endswith("\nstatus: ok, 10 of 10 tasks done")  # the last line
    assert sorted(p.name for p in (tmp_path / "out" / "supersigma").iterdir()) == sorted(OUTPUTS)


def test_simulate_with_a_work_limit_is_reproducible(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = []
    for k in range(2):
        out = tmp_path / str(k)
        argv = ["simulate", "supersigma", "--evaluations", "300", "--time-limit", "60"]
        assert main([*argv, "--out", str(out)]) == 0
        capsys.readouterr()
        runs.append(json.loads((out / "schedule.json").read_text()))
    assert runs[0] == runs[1]
    assert _same_but_wall(tmp_path / "0" / "metrics.json", tmp_path / "1" / "metrics.json")


def test_simulate_draws_insertion_tries_when_asked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    kinds = {}
    for how in ("planned", "drawn"):
        out = tmp_path / how
        args = ["simulate", "supersigma", "--solver", "greedy", "--seed", "1"]
        assert main([*args, "--insertion", how, "--out", str(out)]) == 0
        trace = json.loads((out / "trace.json").read_text())
        kinds[how] = {e["kind"] for e in trace["events"]}
    capsys.readouterr()
    assert "force" not in kinds["planned"]
    assert "force" in kinds["drawn"]
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "supersigma", "--insertion", "worst"])
    assert exc.value.code == 2
    assert "argument --insertion: invalid choice: 'worst'" in capsys.readouterr().err
