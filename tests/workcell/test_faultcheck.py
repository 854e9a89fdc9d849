"""Fault records checked against the cell before the compile and the solve
(workcell.faultcheck): each error names the file and the field path."""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import InputError, ValidationError
from scheduler import solve
from scheduler.generate import random_problem
from workcell import Cell, load_example
from workcell.faultcheck import MESSAGE_KINDS, PLAN_END_MARGIN, check_faults, plan_end_bound
from workcell.sim import (
    MESSAGE_BYTES,
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
)


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
    assert text == "faults.toml: faults[0]: missing field 'at' (a crash record needs arm, at)"
    with pytest.raises(ValidationError, match=r"^faults: expected a FaultPlan"):
        check_faults(_cell("supersigma"), "arm_failure")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("record", "words"),
    [
        ({"kind": "emergency_stop", "at": 1e300, "duration": 1.0}, "at: must be in [0, 1e+06]"),
        ({"kind": "emergency_stop", "at": 1.0, "duration": 1e300}, "duration: must be in"),
        ({"kind": "crash", "arm": "left", "at": 1.0, "force": 1e300}, "force: must be in"),
        ({"kind": "message_loss", "probability": 0.999999}, "probability: must be in [0, 0.999]"),
        ({"kind": "message_loss", "probability": 0.9991}, "a dead link is an arm_failure"),
        ({"kind": "message_loss", "probability": 0.1, "timeout": 1e-300}, "timeout: must be in"),
        ({"kind": "late_part", "part": "pin", "delay": 1e300}, "delay: must be in"),
        ({"kind": "lost_sync", "arm": "left", "axis": 0, "at": 1.0, "steps": 10**12}, "steps"),
    ],
)
def test_numbers_outside_their_physical_range_are_refused(
    record: dict[str, Any], words: str
) -> None:
    text = _refused("supersigma", [record])
    assert text.startswith("faults.toml: faults[0].")
    assert words in text


# ---------------------------------------------- a record's own field checks

_RECORDS = {
    cls.kind: cls
    for cls in (ArmFailure, Crash, LostSync, MessageLoss, LatePart, EmergencyStop, ActivateZones)
}
_VALID = {r["kind"]: r for r in ALL_KINDS}


def _bad_values(cls: type[Any], name: str) -> list[object]:
    """Values field ``name`` of record ``cls`` refuses: of the wrong type, and out of range."""
    hint = str(next(f.type for f in dataclasses.fields(cls) if f.name == name))
    if name in ("arm", "part"):
        return [3, "", ["left"], True]
    if name in ("kinds", "zones"):
        return [5, "fixture", [1], [""], {"a": 1}]
    if hint == "int":  # axis, steps
        return [1.5, "1", True, -1, *([0, 10**7] if name == "steps" else [])]
    # seconds, newtons, a probability
    out: list[object] = ["soon", True, None, -1.0, math.nan, 1e300, [1.0]]
    if name == "probability":
        out.append(0.9999)
    if name in ("timeout", "delay"):
        out.append(0.0 if name == "delay" else 1e-9)
    return out


_FIELD_CASES = [
    pytest.param(kind, f.name, value, id=f"{kind}.{f.name}={value!r}")
    for kind, cls in _RECORDS.items()
    for f in dataclasses.fields(cls)
    for value in _bad_values(cls, f.name)
]


def test_every_field_of_every_kind_is_covered() -> None:
    covered = {(k, n) for k, n, _ in (c.values for c in _FIELD_CASES)}
    every = {(k, f.name) for k, cls in _RECORDS.items() for f in dataclasses.fields(cls)}
    assert covered == every
    assert set(_VALID) == set(_RECORDS)


@pytest.mark.parametrize(("kind", "name", "value"), _FIELD_CASES)
def test_a_records_own_check_names_the_file_then_the_field_path(
    kind: str, name: str, value: object, tmp_path: Path
) -> None:
    """``faults.toml: faults[1].at: must be ...``: the file, then the field's
    path, for every field of every kind, read from a file (TOML and JSON),
    from dicts, and through check_faults; a record built directly names
    ``Record.field``."""
    from workcell.pipeline import load_faults

    record = dict(_VALID[kind], **{name: value})
    records = [{"kind": "emergency_stop", "at": 0.5, "duration": 0.1}, record]
    path = f"faults[1].{name}: "
    with pytest.raises(ValidationError) as info:
        FaultPlan.from_dicts(records)
    assert str(info.value).startswith(path), str(info.value)
    assert f"({kind})" not in str(info.value) and _RECORDS[kind].__name__ not in str(info.value)
    text = _refused("supersigma", records)
    assert text.startswith(f"faults.toml: {path}"), text
    json_file = tmp_path / "faults.json"
    try:
        json_file.write_text(json.dumps(records, allow_nan=True))
    except TypeError:
        return  # not a JSON value
    with pytest.raises(InputError) as info:
        load_faults(json_file)
    assert str(info.value).startswith(f"{json_file}: {path}"), str(info.value)
    args = {k: v for k, v in record.items() if k != "kind"}
    with pytest.raises(ValidationError) as info:
        _RECORDS[kind](**args)
    assert str(info.value).startswith(f"{_RECORDS[kind].__name__}.{name}: "), str(info.value)


@pytest.mark.parametrize("kind", sorted(_RECORDS))
def test_missing_and_unknown_fields_name_the_record(kind: str, tmp_path: Path) -> None:
    toml = tmp_path / "faults.toml"
    record = dict(_VALID[kind], colour=3)
    lines = [f"{k} = {json.dumps(v)}" for k, v in record.items()]
    toml.write_text("[[faults]]\n" + "\n".join(lines) + "\n")
    from workcell.pipeline import load_faults

    with pytest.raises(InputError) as info:
        load_faults(toml)
    assert str(info.value).startswith(f"{toml}: faults[0]: unknown field 'colour' of a {kind}")
    cls = _RECORDS[kind]
    required = [
        f.name
        for f in dataclasses.fields(cls)
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    ]
    for name in required:
        rec = {k: v for k, v in _VALID[kind].items() if k != name}
        assert _refused("supersigma", [rec]).startswith(
            f"faults.toml: faults[0]: missing field {name!r} (a {kind} record needs "
        )


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
