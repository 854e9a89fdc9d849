"""The one compile: CompileOptions, the CompiledCell record, the space grid as
an option, detours off, the deprecated aliases, and no hidden registry."""

from __future__ import annotations

import dataclasses
import gc
import math
import sys
import warnings
from pathlib import Path

import grimp
import pytest

from multiarm.errors import UsageError, ValidationError
from scheduler import solve, validate
from workcell import (
    CompiledCell,
    CompileOptions,
    compile_cell,
    compile_cell_detailed,
    compile_details,
    load_cell,
    load_example,
    simulate,
)
from workcell.viz import render_instants

EXAMPLES = Path(__file__).resolve().parents[2] / "workcell" / "examples"


@pytest.fixture(scope="module")
def supersigma() -> CompiledCell:
    return compile_cell(load_example("supersigma"))


# ------------------------------------------------------------- options


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("grid", -0.1),
        ("grid", math.inf),
        ("grid", math.nan),
        ("grid", True),
        ("grid", "0.3"),
        ("detours", 1),
        ("plan_with", "best"),
        ("linear_step", 0.0),
        ("linear_step", -1.0),
        ("grid_padding", math.nan),
        ("contact_padding", 0),
        ("detour_budget", math.inf),
        ("detour_max_checks", 0),
        ("detour_max_checks", 2.5),
        ("detour_seed", -1),
        ("detour_seed", False),
    ],
)
def test_a_bad_option_is_refused_naming_its_field(field: str, value: object) -> None:
    with pytest.raises(UsageError, match=rf"^CompileOptions\.{field} must"):
        CompileOptions(**{field: value})


def test_options_are_frozen_plain_values() -> None:
    o = CompileOptions(grid=0.45, detours=False)
    assert o == CompileOptions(grid=0.45, detours=False) and hash(o) == hash(
        CompileOptions(grid=0.45, detours=False)
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.grid = 0.2  # type: ignore[misc]
    assert o.to_dict()["grid"] == 0.45 and o.to_dict()["detours"] is False
    with pytest.raises(UsageError, match=r"options must be a workcell\.CompileOptions"):
        compile_cell(load_example("supersigma"), options={"grid": 0.3})  # type: ignore[arg-type]


def test_the_compiled_cell_carries_everything_and_is_frozen(supersigma: CompiledCell) -> None:
    cc = supersigma
    assert cc.oracle is cc.problem.blocking
    # the options applied: the cell's own choices filled in
    assert cc.options == CompileOptions(grid=0.3, plan_with="nominal")
    assert len(cc.modes) == cc.problem.n_modes
    assert ("scan_board", "right") in cc.rejected
    with pytest.raises(TypeError):
        cc.rejected[("x", "y")] = "no"  # type: ignore[index]
    with pytest.raises(dataclasses.FrozenInstanceError):
        cc.problem = cc.problem  # type: ignore[misc]


def test_solve_and_validate_take_the_compiled_cell(supersigma: CompiledCell) -> None:
    a = solve(supersigma, "greedy", time_limit=None, seed=0)
    b = solve(supersigma.problem, "greedy", time_limit=None, seed=0)
    assert a.schedule is not None and b.schedule is not None
    assert a.objective == b.objective
    assert validate(supersigma, a.schedule) == validate(supersigma.problem, b.schedule)


# ---------------------------------------------------------------- grid


@pytest.mark.parametrize("name", ["supersigma"])
def test_grid_off_and_block_sizes_change_the_zones(name: str) -> None:
    cell = load_example(name)
    sdl = cell.zone_map.n_zones
    off = compile_cell(cell, options=CompileOptions(grid=0))
    coarse = compile_cell(cell, options=CompileOptions(grid=0.6))
    default = compile_cell(cell)
    assert off.options.grid == 0.0 and off.problem.n_zones == sdl
    assert not any(z.startswith("grid_") for z in off.problem.zone_names)

    def blocks(cc: CompiledCell) -> int:
        return sum(z.startswith("grid_") for z in cc.problem.zone_names)

    assert coarse.options.grid == 0.6 and default.options.grid == 0.3
    assert 0 < blocks(coarse) < blocks(default)
    assert coarse.problem.n_zones == sdl + blocks(coarse)
    # the SDL zones' windows are the same whatever the grid
    for a, b in zip(off.modes, coarse.modes, strict=True):
        assert a.windows == tuple(w for w in b.windows if not str(w.zone).startswith("grid_"))
    # the cell's own grid is used when the options leave it open
    half = compile_cell(dataclasses.replace(cell, grid=0.6))
    assert half.options.grid == 0.6
    assert half.problem.zone_names == coarse.problem.zone_names
    # and the options' grid wins over the cell's
    assert (
        compile_cell(
            dataclasses.replace(cell, grid=0.6), options=CompileOptions(grid=0)
        ).problem.n_zones
        == sdl
    )


def _cell_file(tmp_path: Path, compile_table: str) -> Path:
    text = (EXAMPLES / "supersigma.toml").read_text(encoding="utf-8")
    assert "[compile]\n" in text
    text = text.replace("[compile]\n", "[compile]\n" + compile_table)
    path = tmp_path / "cell.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_cell_file_sets_the_grid(tmp_path: Path) -> None:
    assert load_cell(_cell_file(tmp_path, "grid = 0.45\n")).grid == 0.45
    assert load_cell(_cell_file(tmp_path, "grid = 0\n")).grid == 0.0
    for bad in ("-0.3", "1e-300", "0.001", "1e300"):
        with pytest.raises(
            ValidationError,
            match=r"cell\.toml: compile\.grid: must be 0 \(off\) or in \[0\.01, 100\] metres",
        ):
            load_cell(_cell_file(tmp_path, f"grid = {bad}\n"))
    with pytest.raises(ValidationError, match=r"cell\.toml: compile\.grid: expected a number"):
        load_cell(_cell_file(tmp_path, 'grid = "fine"\n'))
    with pytest.raises(ValidationError, match=r"grid must be 0 \(off\) or .* \[0\.01, 100\]"):
        dataclasses.replace(load_example("supersigma"), grid=-1.0)


def test_separate_arms_still_reads_as_the_grid_switch_with_a_warning(tmp_path: Path) -> None:
    with pytest.warns(DeprecationWarning, match="separate_arms is deprecated"):
        assert load_cell(_cell_file(tmp_path, "separate_arms = false\n")).grid == 0.0
    with pytest.warns(DeprecationWarning):
        assert load_cell(_cell_file(tmp_path, "separate_arms = true\ngrid = 0.2\n")).grid == 0.2
    with (
        pytest.raises(ValidationError, match=r"compile\.separate_arms: false contradicts grid"),
        warnings.catch_warnings(),
    ):
        warnings.simplefilter("ignore", DeprecationWarning)
        load_cell(_cell_file(tmp_path, "separate_arms = false\ngrid = 0.3\n"))


# ------------------------------------------------------------- detours


def test_detours_off_makes_every_contact_a_block() -> None:
    """Arms parked at their last poses (S2.6): where the oracle plans a
    detour, with detours off the same question costs inf, without planning."""
    cell = dataclasses.replace(load_example("scara4"), park="last")
    cc_on = compile_cell(cell)
    on, p = cc_on.oracle, cc_on.problem
    off = compile_cell(cell, options=CompileOptions(detours=False)).oracle
    found = False
    answers = []
    for m in range(p.n_modes):
        for b in range(p.n_arms):
            for pose in [t for t in range(p.n_tasks) if p.mode_of[b, t] >= 0]:
                c_on, c_off = on.cost(m, b, pose), off.cost(m, b, pose)
                answers.append((c_on, c_off))
                found = 0 < c_on < math.inf
                if found:
                    break
            if found:
                break
        if found:
            break
    assert found, "scara4 with arms parked at their last poses needs some detour"
    for c_on, c_off in answers:
        # no contact: free either way; a contact: blocked without detours
        assert c_off == (0.0 if c_on == 0.0 else math.inf)
    assert off.stats.plan_seconds == [] and off.stats.detoured == 0
    assert on.stats.detoured >= 1


# ---------------------------------------------------- bare problems refused


def test_a_bare_problem_is_refused_where_the_trajectories_are_needed(
    supersigma: CompiledCell,
) -> None:
    plan = solve(supersigma, "greedy", time_limit=None, seed=0).schedule
    assert plan is not None
    with pytest.raises(UsageError, match="pass the CompiledCell"):
        simulate(supersigma.problem, plan)  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="needs the CompiledCell"):
        render_instants(supersigma.cell, plan, [0.0])  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="needs the CompiledCell"):
        render_instants(supersigma.problem, plan, [0.0])  # type: ignore[arg-type]


# ---------------------------------------------------------- deprecations


def test_the_deprecated_aliases_warn_and_point_to_the_compiled_cell(
    supersigma: CompiledCell,
) -> None:
    with pytest.warns(DeprecationWarning, match="compile_cell_detailed is deprecated"):
        cc = compile_cell_detailed(supersigma.cell, plan_with="worst")
    assert isinstance(cc, CompiledCell) and cc.options.plan_with == "worst"
    with pytest.warns(DeprecationWarning, match="compile_details is deprecated"):
        assert compile_details(supersigma) is supersigma
    with (
        pytest.warns(DeprecationWarning),
        pytest.raises(UsageError, match="keep the CompiledCell"),
    ):
        compile_details(supersigma.problem)


# ------------------------------------------------------------ no registry


def _module_containers() -> dict[tuple[str, str], int]:
    """Sizes of every module-level container of our packages."""
    out = {}
    for name, mod in list(sys.modules.items()):
        if name.split(".")[0] not in ("workcell", "scheduler", "tasklib", "zones", "multiarm"):
            continue
        for attr, value in list(vars(mod).items()):
            if isinstance(value, dict | list | set) or type(value).__name__.startswith("Weak"):
                try:
                    out[(name, attr)] = len(value)
                except TypeError:
                    continue
    return out


def test_compiling_keeps_nothing_in_module_globals() -> None:
    """No registry of compiled cells: compiling again grows no module-level
    container of ours. The one module-level memo, the zone solids of the
    sweep (derived arrays of immutable zone maps), is bounded."""
    from workcell.geometry import zone_sweep

    cell = load_example("supersigma")
    compile_cell(cell, options=CompileOptions(grid=0.6))  # imports and warm caches
    gc.collect()  # weakly keyed memos drop entries of earlier tests' problems
    before = _module_containers()
    for grid in (0.6, 0.45):
        compile_cell(cell, options=CompileOptions(grid=grid))
    gc.collect()
    after = _module_containers()
    grown = {k: (before.get(k), n) for k, n in after.items() if n > before.get(k, 0)}
    memo = ("workcell.geometry.zone_sweep", "_SOLIDS")
    assert set(grown) <= {memo}, grown
    assert len(zone_sweep._SOLIDS) <= zone_sweep._SOLIDS_SIZE


def test_compile_and_oracle_do_not_import_each_other() -> None:
    graph = grimp.build_graph("workcell", include_external_packages=False)
    assert graph.chain_exists(importer="workcell.compile", imported="workcell.oracle")
    assert not graph.chain_exists(importer="workcell.oracle", imported="workcell.compile")
    assert not graph.chain_exists(importer="workcell.compiled", imported="workcell.compile")
