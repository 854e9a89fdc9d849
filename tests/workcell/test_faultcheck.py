"""Fault records checked against the cell before the compile and the solve
(workcell.faultcheck): each error names the file and the field path."""

from __future__ import annotations

import functools
import math
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import ValidationError
from scheduler import solve
from scheduler.generate import random_problem
from workcell import Cell, load_example
from workcell.faultcheck import MESSAGE_KINDS, PLAN_END_MARGIN, check_faults, plan_end_bound
from workcell.sim import MESSAGE_BYTES, EmergencyStop, FaultPlan, MessageLoss


@functools.cache
def _cell(name: str) -> Cell:
    return load_example(name)


def _refused(cell: str, records: list[dict[str, Any]], **kw: Any) -> str:
    with pytest.raises(ValidationError) as info:
        check_faults(_cell(cell), records, source="faults.toml", **kw)
    return str(info.value)


ALL_KINDS = [
    {"kind": "arm_failure", "arm": "left", "at": 12.0},
    {"kind": "crash", "arm": "right", "at": 3.0, "recovery": 0.5},
    {"kind": "lost_sync", "arm": "right", "axis": 0, "at": 3.0},
    {"kind": "message_loss", "probability": 0.1, "kinds": ["zone_request", "position"]},
    {"kind": "late_part", "part": "pin", "delay": 5.0},
    {"kind": "emergency_stop", "at": 4.0, "duration": 1.0},
    {"kind": "activate_zones", "at": 1.0, "zones": ["fixture"]},
]


def test_records_that_fit_the_cell_pass() -> None:
    check_faults(_cell("supersigma"), ALL_KINDS, source="faults.toml")
    check_faults(_cell("supersigma"), FaultPlan.from_dicts(ALL_KINDS))
    check_faults(_cell("supersigma"), None)


@pytest.mark.parametrize(
    ("record", "message"),
    [
        (
            {"kind": "arm_failure", "arm": "sx", "at": 1.0},
            "faults.toml: faults[1].arm: unknown arm 'sx'; known: left, right",
        ),
        (
            {"kind": "crash", "arm": "lft", "at": 1.0},
            "faults.toml: faults[1].arm: unknown arm 'lft' (did you mean 'left'?); "
            "known: left, right",
        ),
        (
            {"kind": "lost_sync", "arm": "left", "axis": 7, "at": 1.0},
            "faults.toml: faults[1].axis: arm 'left' has axes 0 .. 3, not 7",
        ),
        (
            {"kind": "late_part", "part": "pn", "delay": 1.0},
            "faults.toml: faults[1].part: unknown part 'pn' (did you mean 'pin'?); known: ",
        ),
        (
            {"kind": "activate_zones", "at": 1.0, "zones": ["fixture", "fixtur"]},
            "faults.toml: faults[1].zones[1]: unknown zone 'fixtur' (did you mean 'fixture'?)",
        ),
        (
            {"kind": "message_loss", "probability": 0.2, "kinds": ["position", "zone_reqest"]},
            "faults.toml: faults[1].kinds[1]: unknown message kind 'zone_reqest' "
            "(did you mean 'zone_request'?); known: active_zone_grant, alarm,",
        ),
    ],
)
def test_an_unknown_name_is_refused_with_its_file_field_and_the_known_names(
    record: dict[str, Any], message: str
) -> None:
    first = {"kind": "emergency_stop", "at": 1.0, "duration": 0.5}
    assert _refused("supersigma", [first, record]).startswith(message)


def test_a_servo_axis_cannot_lose_steps() -> None:
    text = _refused("scara4", [{"kind": "lost_sync", "arm": "sw", "axis": 0, "at": 1.0}])
    assert text.startswith("faults.toml: faults[0].axis: axis 0 of arm 'sw' is a servo joint")


def test_an_arm_fails_once() -> None:
    text = _refused(
        "supersigma",
        [
            {"kind": "arm_failure", "arm": "left", "at": 12.0},
            {"kind": "crash", "arm": "left", "at": 13.0},
            {"kind": "arm_failure", "arm": "left", "at": 20.0},
        ],
    )
    assert text == (
        "faults.toml: faults[2].arm: arm 'left' already fails for good at 12 s (faults[0]); "
        "an arm fails once"
    )


def test_one_message_loss_record() -> None:
    text = _refused(
        "supersigma",
        [
            {"kind": "message_loss", "probability": 0.1},
            {"kind": "message_loss", "probability": 0.2},
        ],
    )
    assert text.startswith("faults.toml: faults[1]: a second message_loss record")


def test_the_message_kinds_are_the_protocols() -> None:
    assert set(MESSAGE_KINDS) == set(MESSAGE_BYTES)


def test_a_malformed_record_names_the_file() -> None:
    text = _refused("supersigma", [{"kind": "crash", "arm": "left"}])
    assert text == "faults.toml: faults[0] (crash): missing field 'at'"
    with pytest.raises(ValidationError, match=r"^faults: expected a FaultPlan"):
        check_faults(_cell("supersigma"), "arm_failure")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("record", "words"),
    [
        ({"kind": "emergency_stop", "at": 1e300, "duration": 1.0}, "EmergencyStop.at must be in"),
        ({"kind": "emergency_stop", "at": 1.0, "duration": 1e300}, "EmergencyStop.duration"),
        ({"kind": "crash", "arm": "left", "at": 1.0, "force": 1e300}, "Crash.force must be in"),
        ({"kind": "message_loss", "probability": 0.999999}, "probability must be in [0, 0.999]"),
        ({"kind": "message_loss", "probability": 0.9991}, "a dead link is an arm_failure"),
        ({"kind": "message_loss", "probability": 0.1, "timeout": 1e-300}, "MessageLoss.timeout"),
        ({"kind": "late_part", "part": "pin", "delay": 1e300}, "LatePart.delay must be in"),
        ({"kind": "lost_sync", "arm": "left", "axis": 0, "at": 1.0, "steps": 10**12}, "steps"),
    ],
)
def test_numbers_outside_their_physical_range_are_refused(
    record: dict[str, Any], words: str
) -> None:
    text = _refused("supersigma", [record])
    assert text.startswith("faults.toml: faults[0] (")
    assert words in text


def test_a_part_that_never_comes_is_still_allowed() -> None:
    check_faults(_cell("supersigma"), [{"kind": "late_part", "part": "pin", "delay": math.inf}])


# ------------------------------------------------------------- fault times


def test_a_fault_after_any_possible_end_is_refused_once_the_problem_is_known() -> None:
    problem = random_problem(2, 6, 1, 0, seed=3)
    end = plan_end_bound(problem)
    late = [{"kind": "emergency_stop", "at": end * 1.01, "duration": 1.0}]
    check_faults(_cell("supersigma"), late)  # without the problem: names only
    text = _refused("supersigma", late, problem=problem)
    assert text.startswith(f"faults.toml: faults[0].at: {end * 1.01:g} s is after any possible end")
    # just inside the bound: accepted
    check_faults(
        _cell("supersigma"),
        [{"kind": "emergency_stop", "at": end * 0.99, "duration": 1.0}],
        problem=problem,
    )


def test_the_faults_own_delays_stretch_the_bound() -> None:
    problem = random_problem(2, 6, 1, 0, seed=3)
    base = plan_end_bound(problem)
    assert plan_end_bound(problem, [EmergencyStop(1.0, 30.0)]) == pytest.approx(base + 30.0)
    assert plan_end_bound(problem, [MessageLoss(0.5)]) == pytest.approx(2 * base)


@settings(max_examples=15, deadline=None)
@given(
    arms=st.integers(1, 4),
    tasks=st.integers(1, 25),
    zones=st.integers(0, 3),
    tools=st.integers(0, 2),
    seed=st.integers(0, 10_000),
    solver=st.sampled_from(["greedy", "tree"]),
)
def test_no_plan_ends_after_the_serial_bound(
    arms: int, tasks: int, zones: int, tools: int, seed: int, solver: str
) -> None:
    """The bound's premise: every plan of our solvers ends within the serial
    bound ``S`` (the bound without its margin), setups and zone waits included."""
    from scheduler import TreeOptions

    p = random_problem(arms, tasks, zones, tools, seed=seed)
    options = TreeOptions(max_evaluations=50) if solver == "tree" else None
    r = solve(p, solver, time_limit=None, seed=seed, options=options)  # type: ignore[arg-type]
    assert r.schedule is not None
    assert r.schedule.makespan <= plan_end_bound(p) / PLAN_END_MARGIN + 1e-9
