"""Malformed problem files: every one a clear error of ours naming the file and the JSON path."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

from multiarm.errors import CycleError, FormatError, ValidationError
from scheduler import load_problem

BASE: dict[str, Any] = {
    "format": "multiarm.problem/1",
    "name": "p",
    "arms": [{"name": "a", "available": 0.0, "capabilities": [], "start_zones": []}, {"name": "b"}],
    "zones": [{"name": "z", "policy": "exclusive"}, {"name": "s", "policy": "shared"}],
    "tools": ["k"],
    "tasks": [
        {
            "name": "t1",
            "release": 0.0,
            "predecessors": [],
            "group": -1,
            "modes": [
                {
                    "arm": "a",
                    "duration": 4.0,
                    "windows": [{"zone": "z", "start": 1.0, "end": 2.0, "kind": "occupy"}],
                    "tools": ["k"],
                }
            ],
        },
        {"name": "t2", "predecessors": ["t1"], "modes": [{"arm": "b", "duration": 3.0}]},
    ],
    "setup": {"kind": "none"},
}

W = "tasks[0].modes[0].windows[0]"
M = "tasks[0].modes[0]"

# (path into the data, new value or DELETE, error type, message regex after "p.json: ")
DELETE = object()
CASES: list[tuple[str, Any, type[Exception], str]] = [
    ("", [], FormatError, r"expected an object, got a list"),
    ("", "text", FormatError, r"expected an object, got 'text'"),
    ("", 3, FormatError, r"expected an object, got 3"),
    ("", None, FormatError, r"expected an object, got None"),
    ("format", "multiarm.problem/9", FormatError, r"format: unsupported problem format"),
    ("format", 1, FormatError, r"format: unsupported problem format 1"),
    ("name", 5, FormatError, r"name: expected a non-empty string, got 5"),
    ("name", "", FormatError, r"name: expected a non-empty string, got ''"),
    ("colour", "red", FormatError, r"unknown key 'colour'"),
    ("arms", DELETE, FormatError, r"missing key 'arms'"),
    ("tasks", DELETE, FormatError, r"missing key 'tasks'"),
    ("arms", "a", FormatError, r"arms: expected a list, got 'a'"),
    ("arms", {}, FormatError, r"arms: expected a list, got a dict"),
    ("arms.0", "a", FormatError, r"arms\[0\]: expected an object, got 'a'"),
    ("arms.0.name", DELETE, FormatError, r"arms\[0\]: missing key 'name'"),
    ("arms.0.name", 7, FormatError, r"arms\[0\]\.name: expected a non-empty string, got 7"),
    ("arms.0.available", "abc", FormatError, r"arms\[0\]\.available: expected a number, got 'abc'"),
    ("arms.0.available", True, FormatError, r"arms\[0\]\.available: expected a number, got True"),
    ("arms.0.available", None, FormatError, r"arms\[0\]\.available: expected a number, got None"),
    ("arms.0.available", -1.0, ValidationError, r"arm 'a': available time must be finite and >= 0"),
    ("arms.0.available", 1e300, ValidationError, r"arm 'a': available time 1e\+300 s is beyond"),
    (
        "arms.0.capabilities",
        "gripper",
        FormatError,
        r"arms\[0\]\.capabilities: expected a list, got 'gripper'",
    ),
    (
        "arms.0.capabilities",
        [1],
        FormatError,
        r"arms\[0\]\.capabilities\[0\]: expected a non-empty string",
    ),
    ("arms.0.start_zones", "z", FormatError, r"arms\[0\]\.start_zones: expected a list, got 'z'"),
    ("arms.0.start_zones", ["nope"], ValidationError, r"unknown zone 'nope'"),
    ("arms.0.speed", 1, FormatError, r"arms\[0\]: unknown key 'speed'"),
    ("arms.1.name", "a", ValidationError, r"duplicate arm name 'a'"),
    ("zones", "z", FormatError, r"zones: expected a list, got 'z'"),
    ("zones.0", "z", FormatError, r"zones\[0\]: expected an object, got 'z'"),
    ("zones.0.name", DELETE, FormatError, r"zones\[0\]: missing key 'name'"),
    (
        "zones.0.policy",
        "private",
        FormatError,
        r"zones\[0\]\.policy: expected 'exclusive' or 'shared', got 'private'",
    ),
    (
        "zones.0.policy",
        1,
        FormatError,
        r"zones\[0\]\.policy: expected 'exclusive' or 'shared', got 1",
    ),
    ("zones.1.name", "z", ValidationError, r"duplicate zone name 'z'"),
    ("zones.0.size", 2, FormatError, r"zones\[0\]: unknown key 'size'"),
    ("tools", "k", FormatError, r"tools: expected a list, got 'k'"),
    ("tools", [None], FormatError, r"tools\[0\]: expected a non-empty string, got None"),
    ("tools", ["k", "k"], ValidationError, r"duplicate tool name 'k'"),
    ("tasks", "t1", FormatError, r"tasks: expected a list, got 't1'"),
    ("tasks.0", 1, FormatError, r"tasks\[0\]: expected an object, got 1"),
    ("tasks.0.name", DELETE, FormatError, r"tasks\[0\]: missing key 'name'"),
    (
        "tasks.0.name",
        ["t1"],
        FormatError,
        r"tasks\[0\]\.name: expected a non-empty string, got a list",
    ),
    ("tasks.1.name", "t1", ValidationError, r"duplicate task name 't1'"),
    ("tasks.0.release", "soon", FormatError, r"tasks\[0\]\.release: expected a number, got 'soon'"),
    ("tasks.0.release", -2, ValidationError, r"task 't1': release must be finite and >= 0"),
    ("tasks.0.release", 1e12, ValidationError, r"task 't1': release 1e\+12 s is beyond"),
    ("tasks.0.group", 1.5, FormatError, r"tasks\[0\]\.group: expected an integer, got 1\.5"),
    ("tasks.0.group", "g", FormatError, r"tasks\[0\]\.group: expected an integer, got 'g'"),
    (
        "tasks.1.predecessors",
        "t1",
        FormatError,
        r"tasks\[1\]\.predecessors: expected a list, got 't1'",
    ),
    ("tasks.1.predecessors", ["t9"], ValidationError, r"task 't2' has unknown predecessor 't9'"),
    (
        "tasks.1.predecessors",
        [1],
        FormatError,
        r"tasks\[1\]\.predecessors\[0\]: expected a non-empty string, got 1",
    ),
    ("tasks.0.predecessors", ["t2"], CycleError, r"precedence cycle"),
    ("tasks.0.predecessors", ["t1"], CycleError, r"precedence cycle"),
    ("tasks.0.modes", "a", FormatError, r"tasks\[0\]\.modes: expected a list, got 'a'"),
    ("tasks.0.modes", [], ValidationError, r"task 't1' has no mode"),
    (
        "tasks.0.modes.0",
        "a",
        FormatError,
        rf"{M}: expected an object".replace("[", r"\[").replace("]", r"\]"),
    ),
    ("tasks.0.modes.0.arm", DELETE, FormatError, r"tasks\[0\]\.modes\[0\]: missing key 'arm'"),
    ("tasks.0.modes.0.arm", "c", ValidationError, r"a mode names unknown arm 'c'"),
    ("tasks.0.modes.0.arm", 0, FormatError, r"modes\[0\]\.arm: expected a non-empty string, got 0"),
    ("tasks.0.modes.0.duration", DELETE, FormatError, r"modes\[0\]: missing key 'duration'"),
    (
        "tasks.0.modes.0.duration",
        "abc",
        FormatError,
        r"tasks\[0\]\.modes\[0\]\.duration: expected a number, got 'abc'",
    ),
    (
        "tasks.0.modes.0.duration",
        "4",
        FormatError,
        r"modes\[0\]\.duration: expected a number, got '4'",
    ),
    (
        "tasks.0.modes.0.duration",
        [4],
        FormatError,
        r"modes\[0\]\.duration: expected a number, got a list",
    ),
    (
        "tasks.0.modes.0.duration",
        False,
        FormatError,
        r"modes\[0\]\.duration: expected a number, got False",
    ),
    ("tasks.0.modes.0.duration", -4.0, ValidationError, r"duration must be finite and >= 0"),
    (
        "tasks.0.modes.0.duration",
        1e308,
        ValidationError,
        r"duration 1e\+308 s is beyond the largest time",
    ),
    ("tasks.0.modes.0.speed", 2, FormatError, r"modes\[0\]: unknown key 'speed'"),
    ("tasks.0.modes.0.tools", "k", FormatError, r"modes\[0\]\.tools: expected a list, got 'k'"),
    ("tasks.0.modes.0.tools", ["x"], ValidationError, r"unknown tool 'x'"),
    (
        "tasks.0.modes.0.windows",
        {},
        FormatError,
        r"modes\[0\]\.windows: expected a list, got a dict",
    ),
    (
        "tasks.0.modes.0.windows.0",
        [1, 2],
        FormatError,
        r"windows\[0\]: expected an object, got a list",
    ),
    ("tasks.0.modes.0.windows.0.zone", DELETE, FormatError, r"windows\[0\]: missing key 'zone'"),
    ("tasks.0.modes.0.windows.0.zone", "y", ValidationError, r"window in unknown zone 'y'"),
    (
        "tasks.0.modes.0.windows.0.start",
        "1",
        FormatError,
        r"windows\[0\]\.start: expected a number, got '1'",
    ),
    (
        "tasks.0.modes.0.windows.0.start",
        3.0,
        ValidationError,
        r"window \[3\.0, 2\.0\) in zone 'z' is outside the mode",
    ),
    (
        "tasks.0.modes.0.windows.0.end",
        9.0,
        ValidationError,
        r"window \[1\.0, 9\.0\) in zone 'z' is outside the mode",
    ),
    (
        "tasks.0.modes.0.windows.0.end",
        None,
        FormatError,
        r"windows\[0\]\.end: expected a number, got None",
    ),
    (
        "tasks.0.modes.0.windows.0.kind",
        "walk",
        FormatError,
        r"windows\[0\]\.kind: expected 'occupy' or 'move', got 'walk'",
    ),
    ("tasks.0.modes.0.windows.0.policy", "x", FormatError, r"windows\[0\]: unknown key 'policy'"),
    ("setup", "none", FormatError, r"setup: expected an object, got 'none'"),
    ("setup", [], FormatError, r"setup: expected an object, got a list"),
    (
        "setup.kind",
        "magic",
        FormatError,
        r"setup\.kind: expected 'none', 'matrix' or 'travel', got 'magic'",
    ),
    ("setup.kind", DELETE, FormatError, r"setup: missing key 'kind'"),
    ("setup.extra", 1, FormatError, r"setup: unknown key 'extra'"),
    (
        "setup",
        {"kind": "matrix", "times": "x"},
        FormatError,
        r"setup\.times: expected a list, got 'x'",
    ),
    (
        "setup",
        {"kind": "matrix", "times": [[["a"]]]},
        FormatError,
        r"setup\.times\[0\]\[0\]\[0\]: expected a number, got 'a'",
    ),
    (
        "setup",
        {"kind": "matrix", "times": [[[1.0]]]},
        ValidationError,
        r"setup matrix must have shape \(A, T \+ 1, T\), got \(1, 1, 1\)",
    ),
    ("setup", {"kind": "travel"}, FormatError, r"setup: missing key 'start'"),
    (
        "arms.0.start_zones",
        ["z"],
        ValidationError,
        r"arms \['a', 'b'\] cannot all start in exclusive zone 'z'",
    ),
]


def _set(data: dict[str, Any], path: str, value: Any) -> Any:
    if path == "":
        return value
    keys = path.split(".")
    node: Any = data
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node[k]
    last = keys[-1]
    if value is DELETE:
        del node[last]
    elif isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value
    return data


@pytest.mark.parametrize(
    ("path", "value", "error", "message"),
    CASES,
    ids=[f"{i}-{c[0] or 'top'}" for i, c in enumerate(CASES)],
)
def test_malformed_problem_files(
    tmp_path: Path, path: str, value: Any, error: type[Exception], message: str
) -> None:
    data = _set(copy.deepcopy(BASE), path, value)
    if path == "arms.0.start_zones" and value == ["z"]:
        data["arms"][1]["start_zones"] = ["z"]  # two arms in one exclusive zone
    f = tmp_path / "p.json"
    f.write_text(json.dumps(data))
    with pytest.raises(error) as info:
        load_problem(f)
    text = str(info.value)
    assert text.startswith(f"{f}: "), text  # the file is named
    import re

    assert re.search(message, text[len(str(f)) + 2 :]), text


def test_the_base_problem_is_valid(tmp_path: Path) -> None:
    f = tmp_path / "p.json"
    f.write_text(json.dumps(BASE))
    assert load_problem(f).n_tasks == 2


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xff\xfe\x00\x01binary", r"not UTF-8"),
        (b"", r"Expecting value"),
        (b"{", r"Expecting property name"),
        (b"[" * 100_000, r"nested too deeply|Expecting"),
        (b'{"arms": [], "tasks": []', r"Expecting"),
    ],
)
def test_unreadable_problem_files(tmp_path: Path, content: bytes, message: str) -> None:
    f = tmp_path / "p.json"
    f.write_bytes(content)
    with pytest.raises(FormatError, match=message) as info:
        load_problem(f)
    assert str(f) in str(info.value)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--time-limit", "inf"], r"time"),
        (["--time-limit", "nan"], r"time"),
        (["--time-limit", "-1"], r"time"),
        (["--time-limit", "0"], r"time"),
        (["--seed", "-1"], r"seed must be in 0\.\.2147483647, got -1"),
        (["--seed", str(2**40)], r"seed must be in 0\.\.2147483647"),
        (
            ["--out", "/nonexistent/dir/s.json"],
            r"--out: directory '/nonexistent/dir' does not exist",
        ),
        (["--out", "{tmp}"], r"--out: '.*' is a directory"),
    ],
)
def test_bad_command_lines_fail_before_solving(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    from workcell.cli import main

    f = tmp_path / "p.json"
    f.write_text(json.dumps(BASE))
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    assert main(["schedule", str(f), "--solver", "greedy", *args]) == 1
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    assert "greedy:" not in captured.out  # nothing was solved
    import re

    assert re.search(message, captured.err), captured.err
