"""Sweeps of ``benchmark`` instances (named measurement functions), ``[quick]``
grids, the sweep's default worker count, and the tables of the published sweeps.

Nothing here is timed: measurement functions are called and their rows
stored; solver runs are work-limited.
"""

from __future__ import annotations

import inspect
import json
import math
import os
from pathlib import Path

import pytest

from multiarm.errors import FormatError, ValidationError
from workcell.experiments import benchmark_function, load_sweep, parse_sweep, run_sweep
from workcell.experiments.analysis import measurements, scale_table, sweep_note

ROOT = Path(__file__).resolve().parents[2]
SWEEPS = ROOT / "benchmarks" / "sweeps"
FJSP = ROOT.parent / "shared" / "data" / "fjsp"

BENCH = f"""
[sweep]
name = "bench"
out = "bench.parquet"
workers = 1

[quick]
instances = ["small-*"]
params = {{ n = 1 }}

[[instances]]
kind = "benchmark"
family = "table"
function = "tests.experiments.measures:table"
path = "{ROOT}"
params = [{{ name = "small", n = 2 }}, {{ name = "big", n = 4, scale = 10.0 }}]
seeds = [0, 1]

[[instances]]
kind = "benchmark"
family = "one"
function = "tests.experiments.measures:one"
path = "{ROOT}"
params = {{ label = "a" }}
seeds = [7]
"""


def _bench(tmp_path: Path, text: str = BENCH) -> object:
    return parse_sweep(text, filename="bench.toml", base_dir=tmp_path)


def test_benchmark_instances_are_parameter_tables_times_seeds(tmp_path: Path) -> None:
    sweep = _bench(tmp_path)
    runs = sweep.runs()  # type: ignore[attr-defined]
    assert [r.instance.name for r in runs] == [
        "small-s0",
        "small-s1",
        "big-s0",
        "big-s1",
        "one-s7",
    ]
    assert {r.config.solver for r in runs} == {"benchmark"}
    assert [r.seed for r in runs] == [0, 1, 0, 1, 7]
    assert dict(runs[2].instance.params) == {"n": 4, "scale": 10.0}
    assert sweep.workers == 1  # type: ignore[attr-defined]
    # the key does not depend on where the module is imported from
    moved = _bench(tmp_path, BENCH.replace(f'path = "{ROOT}"', 'path = "."'))
    assert [r.key for r in moved.runs()] == [r.key for r in runs]  # type: ignore[attr-defined]


def test_a_benchmark_sweep_stores_each_measured_row(tmp_path: Path) -> None:
    outcome = run_sweep(_bench(tmp_path), progress=False)  # type: ignore[arg-type]
    df = outcome.results(current=True)
    assert outcome.ran == 5 and outcome.failed == 0
    assert set(df["status"]) == {"measured"}
    assert int(df["pid"].iloc[0]) == os.getpid()  # the sweep's workers = 1: in this process
    assert (df["package_version"] != "").all() and df["load_average"].notna().all()
    m = measurements(df, "table")
    assert len(m) == 2 + 2 + 4 + 4
    big0 = m[m["instance"] == "big-s0"]
    assert big0["i"].tolist() == [0, 1, 2, 3] and big0["size"].iloc[3] == [4, 3]
    # the measurement function's own result, seeded: the same numbers again
    from tests.experiments.measures import table

    assert big0["x"].tolist() == [r["x"] for r in table(0, 4, 10.0)]
    one = measurements(df, "one")
    assert one.to_dict("records")[0]["seed_seen"] == 7 and list(one.columns)[-3:] == [
        "label",
        "seed_seen",
        "flag",
    ]
    again = run_sweep(_bench(tmp_path), progress=False)  # type: ignore[arg-type]
    assert again.ran == 0 and again.skipped == 5


def test_the_quick_grid_filters_instances_and_replaces_only_named_parameters(
    tmp_path: Path,
) -> None:
    full = _bench(tmp_path)
    quick = full.quick_version()  # type: ignore[attr-defined]
    assert [r.instance.name for r in quick.runs()] == ["small-s0", "small-s1"]
    assert dict(quick.instances[0].params) == {"n": 1}
    full_keys = {r.key for r in full.runs()}  # type: ignore[attr-defined]
    assert not full_keys & {r.key for r in quick.runs()}
    assert quick.quick_version() is quick  # no [quick] left: unchanged


def test_the_quick_grid_of_solver_sweeps_replaces_wall_clock_limits_only() -> None:
    sweep = parse_sweep(
        """
[sweep]
name = "q"
[quick]
instances = ["2x6x2x1-s1"]
solvers = ["tree", "greedy"]
time_limit = 0.5
repetitions = 2
[[instances]]
kind = "generated"
sizes = [[2, 6, 2, 1]]
seeds = [0, 1]
[[solvers]]
solver = "tree"
time_limit = 10.0
[[solvers]]
solver = "greedy"
[[solvers]]
solver = "cpsat"
time_limit = 3.0
"""
    ).quick_version()
    got = [(r.instance.name, r.config.label, r.config.time_limit, r.seed) for r in sweep.runs()]
    assert got == [
        ("2x6x2x1-s1", "tree", 0.5, 0),
        ("2x6x2x1-s1", "tree", 0.5, 1),
        ("2x6x2x1-s1", "greedy", None, 0),
        ("2x6x2x1-s1", "greedy", None, 1),
    ]


def test_failing_and_malformed_measurements_are_recorded_as_errors(tmp_path: Path) -> None:
    text = "\n".join(
        f"""
[[instances]]
kind = "benchmark"
family = "{f}"
function = "tests.experiments.measures:{f}"
path = "{ROOT}"
"""
        for f in ("fails", "wrong", "unplain", "one")
    ).replace('family = "one"', 'family = "one"\nparams = { label = "b" }')
    sweep = parse_sweep('[sweep]\nname = "e"\nout = "e.parquet"\n' + text, base_dir=tmp_path)
    outcome = run_sweep(sweep, workers=1, progress=False)
    df = outcome.results().set_index("family")
    assert outcome.failed == 3
    assert df.loc["fails", "error_type"] == "RuntimeError"
    assert "measurement 0 broke" in df.loc["fails", "error"]
    assert "must return a dict or a list of dicts, got int" in df.loc["wrong", "error"]
    assert "a measurement must be numbers, strings, lists or dicts" in df.loc["unplain", "error"]
    assert df.loc["one", "status"] == "measured"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            ('function = "tests.experiments.measures:one"', 'function = "measures.one"'),
            "instances[1].function: expected 'module:function', got 'measures.one'",
        ),
        (
            ('function = "tests.experiments.measures:one"', 'function = "no_such_mod:one"'),
            "instances[1].function: benchmark 'no_such_mod:one': cannot import 'no_such_mod'",
        ),
        (
            (
                'function = "tests.experiments.measures:one"',
                'function = "tests.experiments.measures:NOT_CALLABLE"',
            ),
            "has no function 'NOT_CALLABLE'",
        ),
        (
            ('params = { label = "a" }', "params = { label = { x = 1 } }"),
            "instances[1].params.label: expected a number, string, boolean or list of them",
        ),
        (
            ("seeds = [7]\n", "seeds = [7]\nbest_known = { a = 1 }\n"),
            "instances[1].best_known: unknown field",
        ),
        (('instances = ["small-*"]', 'instances = ["nothing*"]'), "quick.instances[0]: 'nothing*'"),
        (("params = { n = 1 }", "params = { m = 1 }"), "quick.params.m: no benchmark instance"),
        (("workers = 1", "workers = 0"), "sweep.workers: expected an integer >= 1, got 0"),
        (
            ('params = { label = "a" }', 'params = { label = "a", seed = 3 }'),
            "instances[1].params.seed: the seed comes from the seeds field",
        ),
    ],
)
def test_bad_benchmark_fields_are_named_with_their_path(
    tmp_path: Path, change: tuple[str, str], message: str
) -> None:
    assert change[0] in BENCH
    with pytest.raises(ValidationError, match=None) as err:
        _bench(tmp_path, BENCH.replace(change[0], change[1]))
    assert str(err.value).startswith("bench.toml: ")
    assert message in str(err.value)


def test_a_path_that_is_not_a_directory_and_unknown_quick_solvers_are_refused(
    tmp_path: Path,
) -> None:
    with pytest.raises(ValidationError, match=r"instances\[0\]\.path: 'nowhere' is not a dir"):
        _bench(tmp_path, BENCH.replace(f'path = "{ROOT}"', 'path = "nowhere"', 1))
    text = """
[sweep]
name = "s"
[quick]
solvers = ["tabu"]
[[instances]]
kind = "generated"
sizes = [[2, 6, 2, 1]]
seeds = [0]
[[solvers]]
solver = "greedy"
"""
    with pytest.raises(ValidationError, match=r"quick\.solvers\[0\]: no solver .* 'tabu'"):
        parse_sweep(text, filename="s.toml")
    with pytest.raises(ValidationError, match="solvers: missing"):
        parse_sweep(text.split("[[solvers]]")[0].replace('solvers = ["tabu"]', ""))
    with pytest.raises(FormatError):
        parse_sweep("[quick\n", filename="s.toml")


def test_solver_runs_load_the_kernel_before_the_clock_and_old_grids_are_left_out(
    tmp_path: Path,
) -> None:
    text = """
[sweep]
name = "w"
out = "w.parquet"
workers = 1
[[instances]]
kind = "generated"
sizes = [[2, 6, 2, 1]]
seeds = [0, 1]
[[solvers]]
solver = "greedy"
"""
    first = run_sweep(parse_sweep(text, base_dir=tmp_path), progress=False)
    df = first.results()
    assert (df["warmup_time"] >= 0).all() and df["warmup_time"].notna().all()
    assert (df["pid"] == os.getpid()).all()
    second = run_sweep(
        parse_sweep(text.replace("seeds = [0, 1]", "seeds = [1, 2]"), base_dir=tmp_path),
        progress=False,
    )
    assert second.ran == 1 and second.skipped == 1
    assert len(second.results()) == 3  # the file keeps seed 0 of the earlier grid
    now = second.results(current=True)
    assert sorted(now["instance"]) == ["2x6x2x1-s1", "2x6x2x1-s2"]


def test_the_scale_table_reads_the_greedy_and_tree_runs(tmp_path: Path) -> None:
    text = """
[sweep]
name = "scale"
out = "scale.parquet"
[[instances]]
kind = "generated"
family = "scale"
sizes = [[3, 20, 3, 1]]
seeds = [0, 1]
start_zones = true
[[solvers]]
solver = "greedy"
seeds = ["instance"]
[[solvers]]
solver = "tree"
seeds = ["instance"]
options = { max_evaluations = 40, workers = 1 }
"""
    df = run_sweep(parse_sweep(text, base_dir=tmp_path), workers=1, progress=False).results()
    md = scale_table(df)
    assert md.startswith("# Scale: 3 arms x 20 tasks x 3 zones x 1 tools\n")
    rows = [
        line for line in md.splitlines() if line.startswith("| 0 |") or line.startswith("| 1 |")
    ]
    assert len(rows) == 2
    for line in rows:
        cells = [c.strip() for c in line.strip("|").split("|")]
        seed = int(cells[0])
        g = df[(df["label"] == "greedy") & (df["instance_seed"] == seed)].iloc[0]
        t = df[(df["label"] == "tree") & (df["instance_seed"] == seed)].iloc[0]
        assert cells[3] == f"{g['makespan']:.0f}" and cells[4] == f"{t['makespan']:.0f}"
        assert cells[2] == f"{g['runtime']:.3f}" and cells[8] == str(int(t["evaluations"]))
        lb = float(g["lower_bound"])
        assert cells[6] == f"{100 * (g['makespan'] - lb) / lb:.1f}%"
    note = sweep_note(df, "benchmarks/sweeps/scale.toml", "python -m benchmarks.bench_scale")
    assert (
        "Reproduce: `python -m benchmarks.bench_scale` (sweep `benchmarks/sweeps/scale.toml`)"
        in note
    )
    assert "tree (tree, work-limited, max_evaluations=40, workers=1)" in note
    assert "Ran: 4 runs, " in note


def _published() -> list[Path]:
    return sorted(p for p in SWEEPS.glob("*.toml") if p.stem != "fjsp" or FJSP.is_dir())


@pytest.mark.parametrize("path", _published(), ids=lambda p: p.stem)
def test_every_published_sweep_and_its_quick_grid_bind_their_functions(path: Path) -> None:
    sweep = load_sweep(path)
    quick = sweep.quick_version()
    assert quick.runs() and len(quick.runs()) <= len(sweep.runs())
    assert sweep.out.parent.resolve() == (ROOT / "benchmarks" / "results").resolve()
    assert sweep.workers == 1 or path.stem == "quick"
    for s in (sweep, quick):
        for inst in s.instances:
            if inst.kind == "benchmark":
                fn = benchmark_function(inst)
                inspect.signature(fn).bind(seed=inst.seed, **dict(inst.params))
    if path.stem != "quick":
        assert quick is not sweep, "every published sweep has a [quick] grid for the smoke run"


def test_quick_runs_never_write_to_the_published_results(monkeypatch: pytest.MonkeyPatch) -> None:
    from benchmarks import common

    monkeypatch.delenv("MULTIARM_RESULTS", raising=False)
    quick = common.output_dir(True)
    assert quick.is_dir() and quick.resolve() != common.RESULTS.resolve()
    assert not any(quick.iterdir())
    quick.rmdir()
    assert common.output_dir(False) == common.RESULTS
    monkeypatch.setenv("MULTIARM_RESULTS", str(quick))
    assert common.output_dir(True) == quick


def test_a_wrapper_resumes_its_sweep_and_renders_the_same_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from benchmarks import bench_small

    monkeypatch.setenv("MULTIARM_RESULTS", str(tmp_path))
    small = SWEEPS / "small.toml"
    text = small.read_text().replace(
        'instances = ["2x8x3x1-s0", "2x10x3x1-s0"]', 'instances = ["2x8x3x1-s0"]'
    )
    text = text.replace("time_limit = 1.0", "time_limit = 0.2")
    monkeypatch.setattr(
        "workcell.experiments.load_sweep",  # what the wrapper reads: a smaller grid
        lambda _p: parse_sweep(text, filename=str(small), base_dir=small.parent),
    )
    bench_small.main(["--quick"])
    first = (tmp_path / "small.md").read_text()
    data = json.loads((tmp_path / "small.json").read_text())
    assert data["seeds"] == [0] and data["sweeps"] == ["small.toml"] and len(data["rows"]) == 2
    assert "| small | 2x8x3x1-s0 |" in first
    bench_small.main(["--quick"])
    assert "small: 0 runs now, 2 recorded before" in capsys.readouterr().out
    second = (tmp_path / "small.md").read_text()
    assert second.split("Ran:")[0] == first.split("Ran:")[0]
    assert math.isfinite(float(data["rows"][0]["makespan"]))


def test_the_sweep_command_runs_a_benchmark_sweep(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from workcell.cli import main

    f = tmp_path / "bench.toml"
    f.write_text(BENCH)
    assert main(["sweep", str(f), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "sweep 'bench': 5 runs, 1 processes" in out and "0 failed" in out
    from workcell.experiments import read_results

    df = read_results(tmp_path / "bench.parquet")
    assert len(measurements(df)) == 13
