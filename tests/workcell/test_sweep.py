"""Sweeps: the file format and its errors, the grid, running, resuming, failures, results."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from multiarm.errors import FormatError, UsageError, ValidationError
from scheduler import REGISTRY, solve, validate
from scheduler.generate import random_problem
from workcell.cli import main
from workcell.experiments import (
    COLUMNS,
    build_problem,
    load_sweep,
    parse_sweep,
    read_results,
    run_sweep,
)

ROOT = Path(__file__).resolve().parents[2]
SWEEPS = ROOT / "benchmarks" / "sweeps"
FJSP = ROOT.parent / "shared" / "data" / "fjsp"

TINY = """
[sweep]
name = "tiny"
out = "tiny.parquet"

[[instances]]
kind = "generated"
sizes = [[2, 6, 2, 1]]
seeds = [0, 1]

[[solvers]]
solver = "greedy"

[[solvers]]
solver = "tree"
seeds = ["instance"]
options = { max_evaluations = 60, workers = 1 }

[[solvers]]
solver = "cpsat"
options = { workers = 1, max_deterministic_time = 0.2 }
"""

SAME = ["status", "makespan", "objective", "bound", "nodes", "evaluations", "n_tasks"]
"""Columns that work-limited runs reproduce exactly."""


def write(tmp: Path, text: str, name: str = "sweep.toml") -> Path:
    path = tmp / name
    path.write_text(text)
    return path


def test_the_grid_is_instances_times_solvers_times_seeds_times_repetitions() -> None:
    sweep = parse_sweep(
        TINY.replace('name = "tiny"', 'name = "tiny"\nrepetitions = 2'), filename="t.toml"
    )
    runs = sweep.runs()
    assert len(runs) == 2 * 3 * 2
    assert [r.instance.name for r in runs[:6]] == ["2x6x2x1-s0"] * 6
    # tree's seed is the problem's seed; repetitions add to it
    tree = [(r.instance.seed, r.seed, r.repetition) for r in runs if r.config.solver == "tree"]
    assert tree == [(0, 0, 0), (0, 1, 1), (1, 1, 0), (1, 2, 1)]
    assert len({r.key for r in runs}) == len(runs)
    assert [r.key for r in parse_sweep(TINY).runs()] == [r.key for r in parse_sweep(TINY).runs()]
    assert dict(runs[2].config.options) == {"workers": 1, "max_evaluations": 60}


def test_generated_instances_are_the_benchmark_generators_problems() -> None:
    inst = parse_sweep(TINY.replace("seeds = [0, 1]", "seeds = [5]\nstart_zones = true")).instances
    assert len(inst) == 1 and dict(inst[0].params)["start_zones"] is True
    p = build_problem(inst[0])
    assert p.to_dict() == random_problem(2, 6, 2, 1, seed=5, start_zones=True).to_dict()


def test_every_published_sweep_file_loads() -> None:
    counts = {}
    for path in sorted(SWEEPS.glob("*.toml")):
        if path.stem == "fjsp" and not FJSP.is_dir():
            continue
        counts[path.stem] = len(load_sweep(path).runs())
    assert counts["generated"] == 25 * 4 and counts["small"] == 20 * 2
    assert counts["cells"] == 4 * 3 and counts["quick"] == 18
    if FJSP.is_dir():
        assert counts["fjsp"] == 30 * 3
        bk = {i.name: i.best_known for i in load_sweep(SWEEPS / "fjsp.toml").instances}
        assert bk["mk10"] == 193 and bk["mfjs10"] == 1196 and len(bk) == 30


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            ('kind = "generated"', 'kind = "random"'),
            r"t\.toml: instances\[0\]\.kind: expected one of",
        ),
        (
            ("sizes = [[2, 6, 2, 1]]", "sizes = [[2, 6, 2]]"),
            r"instances\[0\]\.sizes\[0\]: expected \[arms",
        ),
        (
            ("seeds = [0, 1]", "seeds = [0, -1]"),
            r"instances\[0\]\.seeds\[1\]: expected an integer >= 0",
        ),
        (("seeds = [0, 1]", "seeds = [0]\ncolour = 1"), r"instances\[0\]\.colour: unknown field"),
        (('solver = "greedy"', 'solver = "magic"'), r"solvers\[0\]\.solver: expected one of tree"),
        (
            ("max_evaluations = 60, workers = 1", "max_evaluations = 60, workers = 0"),
            r"solvers\[1\]\.options: TreeOptions\.workers must be an int >= 1, got 0",
        ),
        (
            ("max_evaluations = 60, workers = 1", "workers = 1"),
            r"solvers\[1\]\.time_limit: missing: a 'tree' run needs a time limit or the work "
            r"limit options\.max_evaluations",
        ),
        (
            ("max_deterministic_time = 0.2", "deterministic = 0.2"),
            r"solvers\[2\]\.options\.deterministic: solver 'cpsat' has no option",
        ),
        (
            ('solver = "greedy"', 'solver = "greedy"\ntime_limit = -1'),
            r"solvers\[0\]\.time_limit: expected a number in \[1e-06, 1e\+06\]",
        ),
        (
            ('solver = "greedy"', 'solver = "greedy"\nlabel = "cpsat"'),
            r"label 'cpsat' is used twice",
        ),
        (
            ('name = "tiny"', 'name = "tiny"\nrepetitions = 0'),
            r"sweep\.repetitions: expected an integer >= 1",
        ),
    ],
)
def test_bad_fields_are_named_with_their_path(change: tuple[str, str], message: str) -> None:
    assert change[0] in TINY
    with pytest.raises(ValidationError, match=message):
        parse_sweep(TINY.replace(*change), filename="t.toml")


def test_toml_syntax_errors_give_file_line_column(tmp_path: Path) -> None:
    path = write(tmp_path, TINY.replace('name = "tiny"', "name = tiny"))
    with pytest.raises(FormatError) as info:
        load_sweep(path)
    assert (info.value.filename, info.value.line, info.value.column) == (str(path), 3, 8)
    assert str(info.value).startswith(f"{path}:3:8: TOML syntax error")
    with pytest.raises(FormatError, match="cannot read"):
        load_sweep(tmp_path / "missing.toml")


def test_files_and_cells_that_do_not_exist_are_named(tmp_path: Path) -> None:
    fjsp = '[[instances]]\nkind = "fjsp"\nfiles = ["data/*.fjs"]\n[[solvers]]\nsolver = "greedy"\n'
    with pytest.raises(
        ValidationError,
        match=r"s\.toml: instances\[0\]\.files\[0\]: 'data/\*\.fjs' matches no file",
    ):
        load_sweep(write(tmp_path, fjsp, "s.toml"))
    cells = (
        '[[instances]]\nkind = "cell"\ncells = ["scara4", "nope"]\n[[solvers]]\nsolver = "greedy"\n'
    )
    with pytest.raises(
        ValidationError, match=r"instances\[0\]\.cells\[1\]: 'nope' is neither a built-in cell"
    ):
        load_sweep(write(tmp_path, cells, "s.toml"))


def test_a_local_run_records_validated_makespans_and_provenance(tmp_path: Path) -> None:
    sweep = parse_sweep(TINY, filename="tiny.toml", base_dir=tmp_path)
    outcome = run_sweep(sweep, workers=1, progress=False)
    assert (outcome.total, outcome.ran, outcome.skipped, outcome.failed) == (6, 6, 0, 0)
    assert outcome.out == tmp_path / "tiny.parquet" and outcome.out.is_file()
    assert not (tmp_path / "tiny.parquet.journal").exists()
    df = read_results(outcome.out)
    assert list(df.columns) == list(COLUMNS) and len(df) == 6
    for _, row in df.iterrows():
        p = random_problem(2, 6, 2, 1, seed=int(row["instance_seed"]))
        assert row["n_tasks"] == 6 and row["status"] in ("feasible", "optimal")
        assert row["makespan"] == row["objective"]
        assert row["lower_bound"] <= row["makespan"]
        # every run is the run scheduler.solve gives with the same typed options
        # (CP-SAT's work limit included): same status, makespan, objective, bound
        options = REGISTRY[str(row["solver"])].options(**json.loads(str(row["options"])))
        r = solve(p, str(row["solver"]), time_limit=None, seed=int(row["seed"]), options=options)
        assert r.schedule is not None and validate(p, r.schedule) == row["makespan"]
        assert (r.status.value, r.objective, r.bound) == (
            row["status"],
            row["objective"],
            row["bound"],
        )
    row = df.iloc[0]
    from multiarm import __version__

    assert row["package_version"] == __version__
    deps = json.loads(str(row["dependencies"]))
    assert deps["numpy"] == np.__version__ and deps["ortools"]
    assert row["host"] and int(row["cpus"]) >= 1 and row["python"]
    tree = df[df["solver"] == "tree"].iloc[0]
    assert json.loads(str(tree["options"])) == {"max_evaluations": 60, "workers": 1}
    assert math.isnan(tree["time_limit"]) and tree["evaluations"] > 0
    assert json.loads(str(tree["improvements"]))[-1][1] == tree["makespan"]
    phases = json.loads(str(tree["phases"]))
    assert phases and all(isinstance(v, float) and v >= 0 for v in phases.values())
    assert "improve" in phases or "exact" in phases
    greedy = df[df["solver"] == "greedy"].iloc[0]
    assert set(json.loads(str(greedy["phases"]))) == {"bound"}


def test_an_interrupted_sweep_resumes_without_redoing_finished_runs(tmp_path: Path) -> None:
    sweep = parse_sweep(TINY, filename="tiny.toml", base_dir=tmp_path)
    seen: list[dict[str, Any]] = []

    def stop_after_two(row: dict[str, Any]) -> None:
        seen.append(row)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep, workers=1, progress=False, on_row=stop_after_two)
    assert len(read_results(sweep.out)) == 2  # written before the interrupt went on
    again: list[dict[str, Any]] = []
    outcome = run_sweep(sweep, workers=1, progress=False, on_row=again.append)
    assert (outcome.ran, outcome.skipped) == (4, 2)
    assert {r["key"] for r in again}.isdisjoint({r["key"] for r in seen})
    full = run_sweep(
        parse_sweep(TINY, base_dir=tmp_path / "other"), workers=1, progress=False
    ).results()
    df = read_results(sweep.out)
    assert sorted(df["key"]) == sorted(full["key"])
    a, b = df.set_index("key").sort_index(), full.set_index("key").sort_index()
    assert a[SAME].equals(b[SAME])


def test_a_journal_cut_mid_line_is_read_and_the_cut_run_redone(tmp_path: Path) -> None:
    sweep = parse_sweep(TINY, filename="tiny.toml", base_dir=tmp_path)
    rows: list[dict[str, Any]] = []
    with pytest.raises(KeyboardInterrupt):
        run_sweep(
            sweep, workers=1, progress=False, on_row=lambda r: (rows.append(r), _stop(rows, 3))
        )
    sweep.out.unlink()  # as if killed before consolidating: only the journal remains
    journal = tmp_path / "tiny.parquet.journal"
    journal.write_text("".join(json.dumps(r) + "\n" for r in rows[:2]) + json.dumps(rows[2])[:40])
    assert len(read_results(sweep.out)) == 2
    assert run_sweep(sweep, workers=1, progress=False).ran == 4


def _stop(rows: list[dict[str, Any]], n: int) -> None:
    if len(rows) == n:
        raise KeyboardInterrupt


def test_a_broken_instance_file_stops_the_sweep_naming_the_file_and_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # issue 18: a broken instance file used to end a sweep with "2 failed",
    # naming neither the file nor the error; it is now read before any run
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "ok.fjs").write_text("1 1 1\n1 1 1 3\n")
    (tmp_path / "data" / "bad.fjs").write_text("1 1 1\n1 1 1 x\n")
    fjsp = '[[instances]]\nkind = "fjsp"\nfiles = ["data/*.fjs"]\n[[solvers]]\nsolver = "greedy"\n'
    with pytest.raises(ValidationError) as info:
        load_sweep(write(tmp_path, fjsp, "s.toml"))
    msg = str(info.value)
    assert msg.startswith(f"{tmp_path / 's.toml'}: instances[0].files[0]: instance file is broken")
    assert "bad.fjs" in msg and ":2" in msg  # the instance file and its line
    (tmp_path / "cell.toml").write_text('name = "broken"\nzones = "builtin:scara4"\n')
    cells = '[[instances]]\nkind = "cell"\ncells = ["scara4", "cell.toml"]\n[[solvers]]\nsolver = "greedy"\n'
    with pytest.raises(
        ValidationError, match=r"instances\[0\]\.cells\[1\]: instance file is broken: .*cell\.toml"
    ):
        load_sweep(write(tmp_path, cells, "c.toml"))
    out = tmp_path / "r.parquet"
    assert main(["sweep", str(tmp_path / "c.toml"), "--no-progress", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert (
        err.startswith(f"error: {tmp_path / 'c.toml'}: instances[0].cells[1]")
        and "cell.toml" in err
    )
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_a_failing_run_is_recorded_and_the_others_go_on(tmp_path: Path) -> None:
    cell = tmp_path / "broken.toml"
    cell.write_text((ROOT / "workcell" / "examples" / "scara4.toml").read_text())
    text = TINY.replace(
        '[[solvers]]\nsolver = "greedy"',
        '[[instances]]\nkind = "cell"\ncells = ["broken.toml"]\n\n[[solvers]]\nsolver = "greedy"',
        1,
    )
    sweep = parse_sweep(text, filename="tiny.toml", base_dir=tmp_path)
    # the file breaks after the sweep was read (edited meanwhile, or another
    # copy on a cluster's workers): its runs fail, the others go on
    cell.write_text('name = "broken"\nzones = "builtin:scara4"\n')
    outcome = run_sweep(sweep, workers=1, progress=False)
    assert (outcome.total, outcome.failed) == (9, 3)
    df = outcome.results()
    bad = df[df["status"] == "error"]
    assert set(bad["instance"]) == {"broken"} and len(df) == 9
    assert (bad["error_type"] == "ValidationError").all()
    assert bad["error"].str.contains("broken.toml").all()
    assert (bad["makespan"] == math.inf).all()
    assert (df[df["status"] != "error"]["makespan"] < math.inf).all()
    # each failure is named with its instance file, solver and error
    assert len(outcome.failures) == 3
    assert all(
        f.startswith("cell/broken (broken.toml) [")
        and ": ValidationError: " in f
        and "broken.toml" in f.split("ValidationError: ")[1]
        for f in outcome.failures
    )
    report = outcome.report()
    assert (
        sum(line.startswith("failed: cell/broken (broken.toml)") for line in report.splitlines())
        == 3
    )
    # failures are not retried unless asked
    assert run_sweep(sweep, workers=1, progress=False).ran == 0
    again = run_sweep(sweep, workers=1, progress=False, retry_failed=True)
    assert (again.ran, again.failed) == (3, 3) and len(again.results()) == 9


def test_results_of_another_sweep_are_not_mixed(tmp_path: Path) -> None:
    run_sweep(parse_sweep(TINY, base_dir=tmp_path), workers=1, progress=False)
    other = parse_sweep(TINY.replace('name = "tiny"', 'name = "other"'), base_dir=tmp_path)
    with pytest.raises(UsageError, match="holds results of sweep 'tiny', not 'other'"):
        run_sweep(other, workers=1, progress=False)
    with pytest.raises(UsageError, match="workers must be an int >= 1"):
        run_sweep(other, workers=0, out=tmp_path / "x.parquet")


def test_a_local_process_pool_gives_the_in_process_results(tmp_path: Path) -> None:
    sweep = parse_sweep(TINY, filename="tiny.toml")
    one = run_sweep(sweep, workers=1, out=tmp_path / "one.parquet", progress=False).results()
    two = run_sweep(sweep, workers=2, out=tmp_path / "two.parquet", progress=False).results()
    a, b = one.set_index("key").sort_index(), two.set_index("key").sort_index()
    assert a[SAME].equals(b[SAME])
    assert len(set(two["pid"])) >= 1 and os.getpid() not in set(two["pid"])


def test_the_sweep_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, TINY)
    out = tmp_path / "r.parquet"
    assert main(["sweep", str(path), "--workers", "1", "--no-progress", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "sweep 'tiny': 6 runs, 1 processes" in text
    assert "6 runs in" in text and "0 already done, 0 failed" in text and str(out) in text
    # the result table: one line per family and solver label, two instances each
    lines = text.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("family"))
    assert lines[head].split() == [
        "family",
        "solver",
        "runs",
        "failed",
        "makespan",
        "gap",
        "time",
        "(s)",
    ]
    rows = {line.split()[1]: line.split() for line in lines[head + 1 : head + 4]}
    assert set(rows) == {"greedy", "tree", "cpsat"}
    df = read_results(out)
    for label, row in rows.items():
        mine = df[df["label"] == label]
        assert row[0] == "generated" and row[2:4] == ["2", "0"]
        assert float(row[4]) == pytest.approx(mine["makespan"].mean(), abs=0.05)
    assert main(["sweep", str(path), "--workers", "1", "--no-progress", "--out", str(out)]) == 0
    assert "0 runs in" in capsys.readouterr().out
    bad = write(tmp_path, TINY.replace("kind =", "kind ="[:-1]), "bad.toml")
    assert main(["sweep", str(bad)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"error: {bad}:") and "Traceback" not in err


@pytest.mark.skipif(not FJSP.is_dir(), reason="../shared/data/fjsp is not beside the repository")
def test_fjsp_instances_and_the_fjsp_table(tmp_path: Path) -> None:
    from workcell.experiments.analysis import fjsp_table

    rel = os.path.relpath(FJSP / "fattahi", tmp_path)
    text = f"""
[sweep]
name = "f"
[[instances]]
kind = "fjsp"
family = "fattahi"
files = ["{rel}/sfjs0[12].fjs"]
best_known = {{ sfjs01 = 66, sfjs02 = 107 }}
[[solvers]]
solver = "greedy"
[[solvers]]
solver = "tree"
options = {{ max_evaluations = 50, workers = 1 }}
[[solvers]]
solver = "cpsat"
options = {{ workers = 1, max_deterministic_time = 0.5 }}
"""
    sweep = load_sweep(write(tmp_path, text, "f.toml"))
    assert [i.source for i in sweep.instances] == [f"{rel}/sfjs01.fjs", f"{rel}/sfjs02.fjs"]
    df = run_sweep(sweep, workers=1, progress=False).results()
    assert (df["makespan"] >= df["best_known"]).all()
    table = fjsp_table(df)
    assert "| sfjs01 | 4 | 2 | 66 | 66.0 | 66 (0.0%" in table
    assert "- **fattahi**: mean gap to BKS tree 0.00%" in table


@pytest.mark.parametrize(
    "address", ["tcp//host", "tcp://host:99999", "http://host:8786", "host:port", "", "a b"]
)
def test_a_malformed_dask_address_is_refused_before_any_run(address: str, tmp_path: Path) -> None:
    from workcell.experiments import check_dask_address, parse_sweep, run_sweep

    with pytest.raises(UsageError, match=r"--dask-address: .* is not a Dask scheduler address"):
        check_dask_address(address)
    sweep = parse_sweep(
        '[sweep]\nname = "t"\n[[instances]]\nkind = "generated"\nsizes = [[2, 4, 1, 0]]\n'
        'seeds = [0]\n[[solvers]]\nsolver = "greedy"\n',
        filename="t.toml",
    )
    out = tmp_path / "r.parquet"
    with pytest.raises(UsageError, match="dask-address"):
        run_sweep(sweep, dask_address=address, out=out, progress=False)
    assert not out.exists()


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "localhost:8786", "tls://[::1]:1"])
def test_a_well_formed_dask_address_passes(address: str) -> None:
    from workcell.experiments import check_dask_address

    assert check_dask_address(address) == address


def test_the_old_scheduler_keyword_still_works_and_warns(tmp_path: Path) -> None:
    from workcell.experiments import parse_sweep, run_sweep

    sweep = parse_sweep(
        '[sweep]\nname = "t"\n[[instances]]\nkind = "generated"\nsizes = [[2, 4, 1, 0]]\n'
        'seeds = [0]\n[[solvers]]\nsolver = "greedy"\n',
        filename="t.toml",
    )
    with (
        pytest.warns(DeprecationWarning, match="dask_address"),
        pytest.raises(UsageError, match="dask-address"),
    ):
        run_sweep(sweep, scheduler="tcp//bad", out=tmp_path / "r.parquet", progress=False)


def test_an_unwritable_or_directory_output_is_refused_before_any_run(tmp_path: Path) -> None:
    from workcell.experiments import parse_sweep, run_sweep

    sweep = parse_sweep(
        '[sweep]\nname = "t"\n[[instances]]\nkind = "generated"\nsizes = [[2, 4, 1, 0]]\n'
        'seeds = [0]\n[[solvers]]\nsolver = "greedy"\n',
        filename="t.toml",
    )
    rows: list[Any] = []
    with pytest.raises(UsageError, match="is a directory"):
        run_sweep(sweep, out=tmp_path, progress=False, workers=1, on_row=rows.append)
    blocker = tmp_path / "file"
    blocker.write_text("keep me")
    with pytest.raises(UsageError, match="cannot create the folder"):
        run_sweep(sweep, out=blocker / "r.parquet", progress=False, workers=1, on_row=rows.append)
    assert rows == [] and blocker.read_text() == "keep me"
