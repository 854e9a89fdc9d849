"""Cells, cell files and their compilation into scheduling problems (workcell.cell, .compile, .oracle)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import FormatError, NoFeasibleSchedule, ValidationError
from scheduler import solve, validate
from workcell import (
    CompiledCell,
    CompileOptions,
    compile_cell,
    load_cell,
    load_example,
)
from workcell.geometry import ObstacleSet, check_path

EXAMPLE_DIR = Path(__file__).resolve().parents[2] / "workcell" / "examples"


@pytest.fixture(scope="module")
def supersigma() -> CompiledCell:
    return compile_cell(load_example("supersigma"))


@pytest.fixture(scope="module")
def scara4() -> CompiledCell:
    return compile_cell(load_example("scara4"))


# ------------------------------------------------------------------ loading


def test_builtin_cells_load() -> None:
    kinds = {
        name: sorted({a.kind for a in load_example(name).arms})
        for name in ("supersigma", "scara4", "cell8")
    }
    assert kinds == {
        "supersigma": ["gantry"],
        "scara4": ["scara"],
        "cell8": ["gantry", "scara", "serial"],
    }
    assert len(load_example("cell8").arms) == 8


def _cell_file(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "cell.toml"
    path.write_text(body, encoding="utf-8")
    return path


GOOD = """
name = "mine"
zones = "builtin:scara4"
tasks = "builtin:scara4"
[arms.a]
type = "scara"
base = [-0.5, -0.5, 0.0, 0.785]
"""


def test_a_cell_file_loads_with_builtin_references(tmp_path: Path) -> None:
    cell = load_cell(_cell_file(tmp_path, GOOD))
    assert cell.name == "mine" and [a.name for a in cell.arms] == ["a"]
    assert cell.park == "home" and cell.plan_with == "nominal"


@pytest.mark.parametrize(
    ("body", "error", "message"),
    [
        ('name = "x"\nzones = [', FormatError, r"cell\.toml:2:\d+: TOML syntax error"),
        ("colour = 3\n" + GOOD, ValidationError, r"cell\.toml: unknown field 'colour'"),
        (GOOD + "colour = 3\n", ValidationError, r"cell\.toml: arms\.a: unknown field 'colour'"),
        (GOOD.replace('name = "mine"\n', ""), ValidationError, r"cell\.toml: missing field 'name'"),
        (
            GOOD.replace('builtin:scara4"\ntasks', 'nope.sdl"\ntasks'),
            ValidationError,
            r"cell\.toml: zones: file .*nope\.sdl' does not exist",
        ),
        (
            GOOD.replace('tasks = "builtin:scara4"', 'tasks = "builtin:pump"'),
            ValidationError,
            r"tasks: unknown built-in task set 'pump'",
        ),
        (
            GOOD + '[compile]\nplan_with = "best"\n',
            ValidationError,
            r"cell\.toml: compile\.plan_with: expected 'nominal' or 'worst'",
        ),
        (
            GOOD + "[compile]\npadding = -1\n",
            ValidationError,
            r"compile\.padding: must be in \[0\.0001, 0\.1\]",
        ),
        (
            GOOD + '[compile]\npark = "away"\n',
            ValidationError,
            r"compile\.park: expected 'home' or 'last'",
        ),
        (
            GOOD + "start = [0, 0, 0]\n",
            ValidationError,
            r"cell\.toml: arms\.a\.start: expected 4 numbers",
        ),
        (
            GOOD + "start = [0, 3.0, 0.1, 0]\n",
            ValidationError,
            r"arms\.a\.start: .* outside the joint limits",
        ),
        (
            GOOD + 'link_lengths = [0.4, "x"]\n',
            ValidationError,
            r"cell\.toml: arms\.a\.link_lengths: expected 2 numbers",
        ),
        (
            GOOD.split("[arms.a]")[0],
            ValidationError,
            r"cell\.toml: arms: expected a table with at least one",
        ),
    ],
)
def test_bad_cell_files_give_located_errors(
    tmp_path: Path, body: str, error: type, message: str
) -> None:
    with pytest.raises(error, match=message):
        load_cell(_cell_file(tmp_path, body))


def test_binary_and_missing_cell_files(tmp_path: Path) -> None:
    junk = tmp_path / "junk.toml"
    junk.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(FormatError, match="not UTF-8"):
        load_cell(junk)
    with pytest.raises(FormatError, match="cannot read cell file"):
        load_cell(tmp_path / "missing.toml")


# ------------------------------------------------------------------ compile


def test_supersigma_compiles_everything_the_task_set_says(supersigma: CompiledCell) -> None:
    p = supersigma.problem
    ts = supersigma.cell.taskset
    t = {n: i for i, n in enumerate(p.task_names)}
    # part prerequisites: the pin goes into the base placed before
    assert t["place_base"] in p.task_preds[t["insert_pin"]]
    # flag synchronisation (S1.9): every sort task waits for the scan that sets the flag
    for piece in ("king", "queen", "rook", "pawn"):
        assert t["scan_board"] in p.task_preds[t[f"sort_{piece}"]]
    assert ts.flag_edges()  # the task set has flags at all
    # releases from the part-arrival model: pin at 2 s, cap at 6 s (fixed arrivals)
    assert p.task_release[t["insert_pin"]] == 2.0
    assert p.task_release[t["place_cap"]] == 6.0
    # the screw task holds the screwdriver
    for m in p.task_modes[t["screw_cap"]]:
        assert p.tool_names[p.mode_tools[m][0]] == "screwdriver"
    # the right arm has no object detector: no mode for the scan
    assert p.mode_of[p.arm_names.index("right"), t["scan_board"]] == -1
    assert "object_detector" in supersigma.rejected[("scan_board", "right")]


def test_scara4_carries_part_groups_and_zone_windows(scara4: CompiledCell) -> None:
    p = scara4.problem
    t = {n: i for i, n in enumerate(p.task_names)}
    groups = {p.task_group[t[f"place_cover{k}"]] for k in (1, 2)}
    assert -1 not in groups and len(groups) == 2
    # every mode has windows inside its duration, and the shared centre is entered
    centre = p.zone_names.index("centre")
    for m in range(p.n_modes):
        for w in p.mode_windows[m]:
            assert 0 <= p.win_start[w] < p.win_end[w] <= p.mode_duration[m] + 1e-9
    assert any(p.win_zone[w] == centre and p.win_move[w] for w in range(p.n_windows))


def test_mode_details_match_the_problem(scara4: CompiledCell) -> None:
    p = scara4.problem
    assert scara4.oracle is p.blocking and scara4.options == CompileOptions(
        grid=0.3, plan_with="nominal"
    )
    for m, cm in enumerate(scara4.modes):
        assert cm.task == p.task_names[p.mode_task[m]] and cm.arm == p.arm_names[p.mode_arm[m]]
        assert cm.duration == pytest.approx(p.mode_duration[m])
        arm = scara4.cell.arm(cm.arm)
        # park = "home": the task ends back at the arm's start joints
        start = scara4.cell.start[scara4.cell.arms.index(arm)]
        assert np.allclose(cm.q_end, start, atol=1e-9)
    with pytest.raises(ValidationError, match="no mode for task"):
        scara4.mode("place_cover1", "sw")


def test_travel_setups_are_the_arms_move_times(scara4: CompiledCell) -> None:
    p = scara4.problem
    for a, arm in enumerate(scara4.cell.arms):
        tasks = np.flatnonzero(p.mode_of[a] >= 0)
        first = scara4.modes[int(p.mode_of[a, tasks[0]])]
        assert p.setup_time(a, -1, int(tasks[0])) == pytest.approx(
            arm.move_time(scara4.cell.start[a], first.q_start)
        )
        prev = scara4.modes[int(p.mode_of[a, tasks[1]])]
        assert p.setup_time(a, int(tasks[1]), int(tasks[0])) == pytest.approx(
            arm.move_time(prev.q_end, first.q_start)
        )


def test_worst_case_plans_longer_insertions(supersigma: CompiledCell) -> None:
    worst = compile_cell(supersigma.cell, options=CompileOptions(plan_with="worst")).problem
    p = supersigma.problem
    t = p.task_names.index("insert_pin")
    for m_n, m_w in zip(p.task_modes[t], worst.task_modes[t], strict=True):
        assert worst.mode_duration[m_w] > p.mode_duration[m_n] + 1.0  # 12 more tries of 0.4 s


def test_compiling_twice_gives_the_same_problem(scara4: CompiledCell) -> None:
    again = compile_cell(scara4.cell).problem
    assert again.to_dict() == scara4.problem.to_dict()


def test_a_task_no_arm_can_do_names_it_and_every_reason(tmp_path: Path) -> None:
    body = GOOD.replace('type = "scara"', 'type = "scara"\ncapabilities = ["gripper"]')
    with pytest.raises(NoFeasibleSchedule, match=r"no arm can do task '\w+' \(a: .*"):
        compile_cell(load_cell(_cell_file(tmp_path, body)))


@pytest.mark.parametrize("solver", ["greedy", "tree"])
@pytest.mark.parametrize("name", ["supersigma", "scara4"])
def test_every_solver_schedule_of_a_builtin_cell_validates(name: str, solver: str) -> None:
    cc = compile_cell(load_example(name))
    p = cc.problem
    limits = {} if solver == "greedy" else {"max_evaluations": 300}
    r = solve(cc, solver, time_limit=None if solver == "greedy" else 30.0, seed=0, **limits)
    assert r.schedule is not None
    assert validate(cc, r.schedule) == pytest.approx(r.objective) == validate(p, r.schedule)


def test_cpsat_schedule_of_scara4_validates_when_found(scara4: CompiledCell) -> None:
    r = solve(scara4.problem, "cpsat", time_limit=3.0, seed=0)
    if r.schedule is not None:
        assert validate(scara4.problem, r.schedule) == pytest.approx(r.objective)
    else:  # CP-SAT decodes its order again with the oracle; a miss is reported, not hidden
        assert r.status.value == "unknown"


# ------------------------------------------------------------------ oracle


def test_oracle_detours_are_collision_free_and_cost_their_extra_time() -> None:
    cell = load_example("scara4")
    from dataclasses import replace

    cc = compile_cell(replace(cell, park="last"))
    p, o = cc.problem, cc.problem.blocking
    assert o is not None
    found = None
    for m in range(p.n_modes):
        for b in range(p.n_arms):
            for pose in [t for t in range(p.n_tasks) if p.mode_of[b, t] >= 0]:
                c = o.cost(m, b, pose)
                if 0 < c < math.inf:
                    found = (m, b, pose, c)
                    break
            if found:
                break
        if found:
            break
    assert found is not None, "scara4 with arms parked at their last poses needs some detour"
    m, b, pose, c = found
    detours = o.detours(m, b, pose)
    assert detours and sum(max(1e-3, d.extra) for d in detours) == pytest.approx(c)
    mover = cc.cell.arm(cc.modes[m].arm)
    obstacles = ObstacleSet.from_arm(cc.cell.arms[b], o.parked_joints(b, pose))
    for d in detours:
        assert check_path(mover, d.path, obstacles, step=0.001)
    # cached: asking again costs nothing new
    before = o.stats.queries - o.stats.cached
    assert o.cost(m, b, pose) == c
    assert o.stats.queries - o.stats.cached == before


# ------------------------------------------------------------------ poses


def test_the_readme_c_style_example_compiles_in_a_cell_of_gantries_and_scaras() -> None:
    """A bare (x, y, z) points the tool down, the pose gantries and SCARAs reach (issue 18)."""
    import re

    from tasklib import TaskSet
    from workcell import Cell
    from workcell.arms import arm_from_dict
    from zones import parse_sdl

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    block = next(b for b in re.findall(r"```python\n(.*?)```", readme, flags=re.S) if "capi" in b)
    assert "(0.5, 0.5, 0.1)" in block  # a bare 3-tuple pose
    namespace: dict[str, object] = {}
    exec(compile(block, "README.md", "exec"), namespace)
    taskset = namespace["taskset"]
    assert isinstance(taskset, TaskSet)
    zone_map = parse_sdl("cell (-1, -1, 0) (2, 2, 1.5)\n", "empty.sdl")
    rails = {"x": [0.0, 1.0], "y": [0.0, 1.0], "z": [0.0, 0.4]}
    caps = ["gripper", "force_sensor"]
    gantry = arm_from_dict("g", {"type": "gantry", "rails": rails, "capabilities": caps}, "g")
    base = [0.9, 0.5, 0.0, math.pi]
    scara = arm_from_dict("s", {"type": "scara", "base": base, "capabilities": caps}, "s")
    for arms in ((gantry,), (scara,)):
        cell = Cell("readme", taskset, zone_map, arms, grid=0.0)
        cc = compile_cell(cell)
        assert {cc.problem.arm_names[int(a)] for a in cc.problem.mode_arm} == {
            a.name for a in arms
        }, cc.rejected


# ------------------------------------------------- physical ranges of arm keys


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            "link_lengths = [1e300, 0.3]\n",
            r"cell\.toml: arms\.a\.link_lengths: 1e\+300 is out of range: .* \[1e-06, 100\] m",
        ),
        ("max_velocity = [1e-300, 4, 1, 6]\n", r"arms\.a\.max_velocity: 1e-300 is out of range"),
        ("max_acceleration = [10, 1e9, 5, 30]\n", r"arms\.a\.max_acceleration: 1e\+09 is out"),
        ("payload = 1e300\n", r"arms\.a\.payload: 1e\+300 is out of range: .* kg"),
        ("radius = 1e-300\n", r"arms\.a\.radius: 1e-300 is out of range"),
        ("z_range = [0, 1e300]\n", r"arms\.a\.z_range: 1e\+300 is out of range"),
        ("joint_limits = [[-1e300, 1], [-1, 1], [0, 0.3], [-1, 1]]\n", r"arms\.a\.joint_limits"),
    ],
)
def test_numbers_outside_their_physical_range_are_refused_by_field(
    tmp_path: Path, extra: str, message: str
) -> None:
    body = GOOD.replace("base = [-0.5, -0.5, 0.0, 0.785]", "base = [1e300, 0, 0, 0]")
    with pytest.raises(ValidationError, match=r"arms\.a\.base: 1e\+300 is out of range"):
        load_cell(_cell_file(tmp_path, body))
    with pytest.raises(ValidationError, match=message):
        load_cell(_cell_file(tmp_path, GOOD + extra))


GANTRY = """
name = "g"
zones = "builtin:supersigma"
tasks = "builtin:supersigma"
[arms.a]
type = "gantry"
rails = { x = [0.0, 1.0], y = [0.0, 1.0], z = [0.0, 0.5] }
[arms.a.stepper]
"""


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("step_length = 1e-300\n", r"arms\.a\.stepper\.step_length: 1e-300 is out of range"),
        ("max_rate = 1e300\n", r"arms\.a\.stepper\.max_rate: 1e\+300 is out of range"),
        ("curves = { light = 1e-300 }\n", r"arms\.a\.stepper\.curves\.light: 1e-300 is out"),
        (
            "step_length = 1e-9\nmax_rate = 10\nlow_rate = 1\n",
            r"arms\.a\.stepper: top speed max_rate x step_length = 1e-08 m/s is out of range",
        ),
        ("short_steps = 10000000000\n", r"arms\.a\.stepper\.short_steps: 1e\+10 is out"),
    ],
)
def test_stepper_numbers_outside_their_range_are_refused(
    tmp_path: Path, extra: str, message: str
) -> None:
    with pytest.raises(ValidationError, match=message):
        load_cell(_cell_file(tmp_path, GANTRY + extra))


def test_empty_capabilities_stay_empty_and_a_nameless_arm_is_refused(tmp_path: Path) -> None:
    cell = load_cell(_cell_file(tmp_path, GOOD + "capabilities = []\n"))
    assert cell.arms[0].capabilities == frozenset()
    assert load_cell(_cell_file(tmp_path, GOOD)).arms[0].capabilities == {"gripper"}
    with pytest.raises(ValidationError, match=r"cell\.toml: arms\.: an arm's name must be"):
        load_cell(_cell_file(tmp_path, GOOD.replace("[arms.a]", '[arms.""]')))
    with pytest.raises(ValidationError, match=r"arms\.a\|b: an arm's name must be"):
        load_cell(_cell_file(tmp_path, GOOD.replace("[arms.a]", '[arms."a|b"]')))


_EXTREMES = st.one_of(
    st.sampled_from([1e-300, 1e-12, 1e-7, 1e-6, 1.0, 99.0, 1e6, 1e7, 1e300, -1e300, -1.0, 0.0]),
    st.floats(-1e8, 1e8, allow_nan=False),
)
# (section, key) -> how many numbers (0: one number)
_NUMERIC_FIELDS = {
    ("scara", "max_velocity"): 4,
    ("scara", "max_acceleration"): 4,
    ("scara", "max_jerk"): 4,
    ("scara", "link_lengths"): 2,
    ("scara", "z_range"): 2,
    ("scara", "payload"): 0,
    ("scara", "radius"): 0,
    ("scara", "arm_height"): 0,
    ("scara", "base"): 4,
    ("gantry", "height"): 0,
    ("gantry", "hand"): 3,
    ("gantry", "yaw_limits"): 2,
    ("gantry.stepper", "step_length"): 0,
    ("gantry.stepper", "max_rate"): 0,
    ("gantry.stepper", "low_rate"): 0,
    ("gantry.stepper", "stop_accel"): 0,
    ("serial", "max_velocity"): 6,
    ("serial", "max_acceleration"): 6,
    ("serial", "max_jerk"): 6,
    ("serial", "radius"): 0,
}


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(sorted(_NUMERIC_FIELDS)), st.lists(_EXTREMES, min_size=6, max_size=6))
def test_arm_numbers_are_refused_by_field_or_give_finite_timings(
    field: tuple[str, str], values: list[float]
) -> None:
    """Hypothesis over the cell file's numeric arm fields, extremes included: either a
    ValidationError naming the field, or an arm whose move times are finite (no
    overflow later)."""
    from workcell.arms import arm_from_dict

    section, key = field
    n = _NUMERIC_FIELDS[field]
    value: object = values[0] if n == 0 else values[:n]
    data: dict[str, object] = {"type": section.split(".")[0]}
    if data["type"] == "gantry":
        data["rails"] = {"x": [0.0, 1.0], "y": [0.0, 1.0], "z": [0.0, 0.5]}
    if data["type"] == "serial":
        data["example"] = "6dof"
    if section == "gantry.stepper":
        data["stepper"] = {key: value}
        path = "c.toml: arms.a.stepper"
    else:
        data[key] = value
        path = f"c.toml: arms.a.{key}"
    try:
        arm = arm_from_dict("a", data, "c.toml: arms.a")
    except ValidationError as exc:
        text = str(exc)
        assert text.startswith(path) or text.startswith("c.toml: arms.a: "), text
        return
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    for q1 in (hi, lo + (hi - lo) * 1e-3):
        t = arm.move_time(lo, q1)
        assert math.isfinite(t) and 0.0 <= t < 1e9


def test_the_6dof_example_takes_its_keys_instead_of_failing_or_ignoring_them() -> None:
    from workcell.arms import arm_from_dict

    base = {"type": "serial", "example": "6dof"}
    arm = arm_from_dict("r", {**base, "joint_limits": [[-3.0, 3.0]] * 6}, "c.toml: arms.r")
    assert arm.joint_limits.tolist() == [[-3.0, 3.0]] * 6  # was a TypeError
    arm = arm_from_dict("r", {**base, "radius": 0.2}, "c.toml: arms.r")
    assert arm.shapes[-1].size == (0.2,)  # was silently ignored
    with pytest.raises(ValidationError, match=r"c\.toml: arms\.r\.kinds: the 6dof example"):
        arm_from_dict("r", {**base, "kinds": ["revolute"] * 6}, "c.toml: arms.r")
    with pytest.raises(ValidationError, match=r"c\.toml: arms\.r: serial arm 'r': home"):
        arm_from_dict("r", {**base, "joint_limits": [[-0.1, 0.1]] * 6}, "c.toml: arms.r")
