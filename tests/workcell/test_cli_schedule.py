"""``multiarm check`` and ``multiarm schedule`` on problems, schedules and FJSP files."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from scheduler import Model, Window, save_problem, solve
from workcell.cli import main

FJSP = "2 2 1\n2 1 1 3 1 2 2\n1 1 1 4\n"


def _problem(tmp_path: Path, name: str = "p.json") -> Path:
    m = Model("two")
    m.add_zone("z")
    m.add_arm("a")
    m.add_arm("b")
    m.add_task("t1")
    m.add_task("t2")
    m.add_mode("t1", "a", 4.0, windows=[Window("z", 1.0, 3.0)])
    m.add_mode("t2", "b", 4.0, windows=[Window("z", 1.0, 3.0)])
    return save_problem(m.build(), tmp_path / name)


def test_check_recognises_files_by_content(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    prob = _problem(tmp_path, "problem.data")  # no telling extension
    fj = tmp_path / "instance.txt"
    fj.write_text(FJSP)
    assert main(["check", str(prob), str(fj)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == f"{prob}: ok (problem 'two': 2 arms, 2 tasks, 2 modes, 1 zones, lower bound 6)"
    assert out[1] == f"{fj}: ok (FJSP instance: 2 machines, 3 operations, 3 modes)"


def test_check_validates_a_schedule_against_its_problem(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    prob = _problem(tmp_path)
    from scheduler import load_problem

    p = load_problem(prob)
    plan = solve(p, "greedy").plan
    assert plan is not None
    good = plan.write(tmp_path / "s.json")
    assert main(["check", str(good), "--problem", str(prob)]) == 0
    assert capsys.readouterr().out.strip() == f"{good}: ok (schedule of 2 tasks, valid, makespan 6)"
    # the same schedule with both tasks at 0: two arms in z
    data = json.loads(good.read_text())
    for row in data["tasks"]:
        row.update(start=0.0, end=4.0, waits=[])
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    assert main(["check", str(bad), "--problem", str(prob)]) == 1
    err = capsys.readouterr().err
    assert "both inside exclusive zone 'z'" in err and "Traceback" not in err
    # a malformed one names the file and the JSON path
    data["tasks"][1]["arm"] = "c"
    bad.write_text(json.dumps(data))
    assert main(["check", str(bad), "--problem", str(prob)]) == 1
    assert f"{bad}: tasks[1].arm: unknown arm 'c'" in capsys.readouterr().err
    # without its problem a schedule is not judged
    assert main(["check", str(good)]) == 1
    assert "add --problem PROBLEM" in capsys.readouterr().err


def test_check_reports_a_malformed_fjsp_file_with_its_place(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = tmp_path / "broken.fjs"
    f.write_text("1 2\n1 1 7 3\n")
    assert main(["check", str(f)]) == 1
    assert f"{f}:2:5: job 1 operation 1: machine 7 outside 1..2" in capsys.readouterr().err


def test_schedule_prints_improvements_and_a_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fj = tmp_path / "instance.txt"  # an FJSP file recognised by content
    fj.write_text(FJSP)
    assert main(["schedule", str(fj), "--solver", "greedy", "--verbose"]) == 0
    out = capsys.readouterr().out.splitlines()
    improvements = [ln for ln in out if ln.strip().endswith("bound 7") and "makespan" in ln]
    assert improvements and improvements[-1].split()[3] == "7"  # greedy's makespan
    head = out.index(next(ln for ln in out if ln.startswith("task ")))
    assert out[head].split() == [
        "task",
        "arm",
        "mode",
        "start",
        "end",
        "duration",
        "wait",
        "detour",
    ]
    assert len(out) - head - 2 == 3  # one row per operation
    assert main(["schedule", str(fj), "--solver", "greedy", "--rows", "1"]) == 0
    assert "... 2 more tasks" in capsys.readouterr().out


@pytest.mark.parametrize("suffix", [".json", ".csv"])
def test_schedule_out_by_extension(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    prob = _problem(tmp_path)
    out = tmp_path / f"s{suffix}"
    assert main(["schedule", str(prob), "--solver", "greedy", "--out", str(out)]) == 0
    assert f"schedule written to {out}" in capsys.readouterr().out
    if suffix == ".json":
        assert json.loads(out.read_text())["format"] == "multiarm.schedule/1"
        assert main(["check", str(out), "--problem", str(prob)]) == 0
    else:
        rows = list(csv.DictReader(out.open()))
        assert [r["task"] for r in rows] == ["t1", "t2"]
        assert {r["arm"] for r in rows} == {"a", "b"}


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--out", "s.txt"], r"--out: '.*s\.txt' must end in \.json or \.csv"),
        (["--out", "s"], r"must end in \.json or \.csv"),
        (["--rows", "-1"], r"--rows must be >= 0, got -1"),
    ],
)
def test_schedule_refuses_bad_output_before_solving(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    import re

    prob = _problem(tmp_path)
    args = [str(tmp_path / a) if a.startswith("s") else a for a in args]
    assert main(["schedule", str(prob), "--solver", "greedy", *args]) == 1
    captured = capsys.readouterr()
    assert "greedy:" not in captured.out and "Traceback" not in captured.err
    assert re.search(message, captured.err), captured.err
