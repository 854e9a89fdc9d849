"""``nan`` never reaches an output (issue "bad inputs are refused early by name").

A figure that does not exist -- the start and end of a task that never
started, the executed makespan of a run where no task was done, a re-solve
latency of a run without re-solves -- is missing: NaN in memory (pandas'
missing value), an empty cell in CSV, ``null`` in JSON, "none" in the
summary (docs/simulation.md, "Missing values"). These tests run cases where
tasks never start and scan every file written and every line printed.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from workcell import load_example
from workcell.cli import main
from workcell.pipeline import solve_cell
from workcell.sim import SimOptions, simulate
from workcell.summary import run_summary

NON_FINITE = re.compile(r"(?<![A-Za-z_])(nan|NaN|NAN|-?inf|-?Inf|-?Infinity)(?![A-Za-z_])")
"""A NaN or infinity written as text: a JSON value, a CSV cell, a printed figure."""

REPLAY_JS = Path(__file__).resolve().parents[2] / "workcell" / "replay" / "static" / "replay.js"


def _no_constant(name: str) -> Any:
    raise AssertionError(f"JSON holds the non-standard constant {name}")


def _scan(text: str, where: str) -> None:
    hits = sorted({m.group(0) for m in NON_FINITE.finditer(text)})
    assert not hits, f"{where} holds {hits}"


def _scan_folder(folder: Path) -> list[str]:
    """Scan every file under ``folder``; returns the names scanned."""
    script = REPLAY_JS.read_text(encoding="utf-8")  # the viewer's code (three.js) says NaN
    scanned = []
    for f in sorted(p for p in folder.rglob("*") if p.is_file()):
        if f.suffix == ".png":
            continue
        text = f.read_text(encoding="utf-8")
        if f.suffix == ".html":
            assert script in text
            text = text.replace(script, "")
        if f.suffix == ".json":
            json.loads(text, parse_constant=_no_constant)  # strict JSON: no NaN, no Infinity
        if f.suffix == ".parquet":
            frame = pd.read_parquet(f)
            text = frame.to_csv(index=False, na_rep="")
        _scan(text, f.name)
        scanned.append(f.name)
    return scanned


@pytest.fixture(scope="module")
def nothing_done(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """``multiarm simulate`` of supersigma with both arms failing at t = 0:
    no task starts, nothing is done (the run folder, what was printed)."""
    tmp = tmp_path_factory.mktemp("nothing-done")
    faults = tmp / "faults.toml"
    faults.write_text(
        '[[faults]]\nkind = "arm_failure"\narm = "left"\nat = 0.0\n\n'
        '[[faults]]\nkind = "arm_failure"\narm = "right"\nat = 0.0\n'
    )
    out = tmp / "run"
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        status = main(
            [
                "simulate",
                "supersigma",
                "--solver",
                "greedy",
                "--faults",
                str(faults),
                "--out",
                str(out),
                "--allow-failures",
                "--no-progress",
            ]
        )
    assert status == 0, stderr.getvalue()
    return out, stdout.getvalue() + stderr.getvalue()


def test_a_run_with_nothing_done_writes_no_nan(nothing_done: tuple[Path, str]) -> None:
    out, printed = nothing_done
    scanned = _scan_folder(out)
    assert {"trace.json", "metrics.json", "tasks.csv", "schedule.json", "replay.json"} <= set(
        scanned
    )
    assert "replay.html" in scanned
    _scan(printed, "the printed summary")
    assert "none (no task done)" in printed


def test_missing_figures_are_empty_cells_and_nulls(nothing_done: tuple[Path, str]) -> None:
    out, _ = nothing_done
    summary = json.loads((out / "metrics.json").read_text())["summary"]
    assert summary["done_tasks"] == 0 and summary["failed_tasks"] == 10
    assert summary["executed_makespan"] is None
    assert isinstance(summary["planned_makespan"], float)
    for key, value in summary.items():
        assert value is None or math.isfinite(value), key
    rows = (out / "tasks.csv").read_text().splitlines()
    header = rows[0].split(",")
    start, end = header.index("start"), header.index("end")
    for row in rows[1:]:
        cells = row.split(",")
        assert cells[start] == "" and cells[end] == "", row
    # readers that take these columns as floats keep working: pandas reads
    # an empty cell back as NaN
    frame = pd.read_csv(out / "tasks.csv")
    assert frame["start"].dtype == float and frame["start"].isna().all()


def test_a_task_that_never_starts_next_to_tasks_done(tmp_path: Path) -> None:
    """One arm failing at t = 0 with re-solving off: its tasks never start,
    the other arm's run; the result's frames and every saved file."""
    cell = load_example("supersigma")
    solved = solve_cell(cell, solver="greedy")
    sched = solved.schedule
    p = solved.problem
    arms = sched.arms(p)
    busy = [int((arms == a).sum()) for a in range(p.n_arms)]
    assert min(busy) > 0, "both arms must have work for this case"
    failing = p.arm_names[busy.index(min(busy))]  # the arm other tasks depend on least
    r = simulate(
        solved.compiled,
        sched,
        faults=[{"kind": "arm_failure", "arm": failing, "at": 0.0}],
        options=SimOptions(resolve=False),
    )
    tasks = r.tasks_frame()
    never = tasks[tasks["arm"] == failing]
    assert len(never) and never["start"].isna().all() and never["end"].isna().all()
    done = tasks[tasks["status"] == "done"]
    m = r.metrics
    assert len(done) == m.done_tasks > 0  # the other arm's tasks ran
    assert m.executed_makespan == pytest.approx(done["end"].max())
    assert m.resolves == 0 and math.isnan(m.summary()["resolve_latency_p50"])
    r.save(tmp_path / "run")
    assert _scan_folder(tmp_path / "run") == ["metrics.json", "tasks.csv", "trace.json"]
    summary = json.loads((tmp_path / "run" / "metrics.json").read_text())["summary"]
    assert summary["resolve_latency_p50"] is None  # no re-solve: missing
    saved = pd.read_csv(tmp_path / "run" / "tasks.csv")
    assert saved["start"].isna().sum() == tasks["start"].isna().sum() >= len(never)
    _scan(json.dumps(m.to_dict()), "Metrics.to_dict()")
    rows = run_summary(solved.compiled, sched, r)
    _scan("\n".join(f"{x.metric} {x.planned} {x.executed}" for x in rows), "run_summary")
    _scan(repr(r), "repr(SimResult)")
