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
        del node[int(last) if isinstance(node, list) else last]
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


# ------------------------------------------------------------ FJSP files

# (file content, message regex after "f.fjs:"): every one a FormatError naming the
# file, and the line and column of the culprit where there is one
FJSP_CASES: list[tuple[str, str]] = [
    ("", r"^ empty FJSP file$"),
    ("\n  \n\t\n", r"^ empty FJSP file$"),
    ("2\n", r"^1: the header needs the number of jobs and of machines$"),
    ("a 2\n1 1 1 3\n", r"^1:1: 'a' is not an integer$"),
    ("1 b\n1 1 1 3\n", r"^1:3: 'b' is not an integer$"),
    ("1.0 2\n1 1 1 3\n", r"^1:1: '1\.0' is not an integer$"),
    ("0 2\n", r"^1:1: the header says 0 jobs \(needs >= 1\)$"),
    ("-1 2\n1 1 1 3\n", r"^1:1: the header says -1 jobs \(needs >= 1\)$"),
    ("1 0\n1 1 1 3\n", r"^1:3: the header says 0 machines \(needs 1\.\.10000\)$"),
    ("1 99999999\n1 1 1 3\n", r"^1:3: the header says 99999999 machines"),
    ("1 " + "9" * 40 + "\n1 1 1 3\n", r"^1:3: 9{20}\.\.\. is far too large$"),
    ("2 2\n1 1 1 3\n", r"^1:1: the header announces 2 jobs but the file has 1 job lines$"),
    ("1 2\n1 1 1 3\n1 1 1 3\n", r"^1:1: the header announces 1 jobs but the file has 2 job lines$"),
    ("1 2\n0\n", r"^2:1: job 1 has 0 operations \(needs >= 1\)$"),
    ("1 2\n-2 1 1 3\n", r"^2:1: job 1 has -2 operations \(needs >= 1\)$"),
    ("1 2\n2 1 1 3\n", r"^2: job 1 ends before operation 2 of 2$"),
    ("1 2\n1 0\n", r"^2:3: job 1 operation 1: 0 machines \(needs 1\.\.2\)$"),
    ("1 2\n1 -1 1 3\n", r"^2:3: job 1 operation 1: -1 machines \(needs 1\.\.2\)$"),
    ("1 2\n1 3 1 3 2 3 1 1\n", r"^2:3: job 1 operation 1: 3 machines \(needs 1\.\.2\)$"),
    ("1 2\n1 2 1 3\n", r"^2:3: job 1 operation 1: 2 machine/time pairs announced, 1 given$"),
    ("1 2\n1 1 1\n", r"^2:3: job 1 operation 1: 1 machine/time pairs announced, 0 given$"),
    ("1 2\n1 1 3 5\n", r"^2:5: job 1 operation 1: machine 3 outside 1\.\.2$"),
    ("1 2\n1 1 0 5\n", r"^2:5: job 1 operation 1: machine 0 outside 1\.\.2$"),
    ("1 2\n1 1 -1 5\n", r"^2:5: job 1 operation 1: machine -1 outside 1\.\.2$"),
    ("1 2\n1 2 1 5 1 4\n", r"^2:9: job 1 operation 1: machine 1 listed twice$"),
    ("1 2\n1 1 1 0\n", r"^2:7: job 1 operation 1: time 0 must be > 0$"),
    ("1 2\n1 1 1 -4\n", r"^2:7: job 1 operation 1: time -4 must be > 0$"),
    ("1 2\n1 1 1 2000000000\n", r"^2:7: job 1 operation 1: time 2000000000 is beyond"),
    ("1 2\n1 1 1 " + "1" * 400 + "\n", r"^2:7: 1{20}\.\.\. is far too large$"),
    ("1 2\n1 1 1 2.5\n", r"^2:7: '2\.5' is not an integer$"),
    ("1 2\n1 1 1 1e3\n", r"^2:7: '1e3' is not an integer$"),
    ("1 2\n1 1 1 1_0\n", r"^2:7: '1_0' is not an integer$"),
    ("1 2\n1 1 1 3 7\n", r"^2:9: job 1 has 1 values left over \(corrupt line\)$"),
    ("1 2\n1 1 1 3 # note\n", r"^2:9: '#' is not an integer$"),
    ("1 2\n1 1 1 NaN\n", r"^2:7: 'NaN' is not an integer$"),
    ("2 2\n1 1 1 3\n1 1 2 x\n", r"^3:7: 'x' is not an integer$"),
    ("2 2\n1 1 1 3\n\n1 1 2 0\n", r"^4:7: job 2 operation 1: time 0 must be > 0$"),
    ("1 2\n2 1 1 3 1 0 2\n", r"^2:11: job 1 operation 2: machine 0 outside 1\.\.2$"),
    ("1 2 3 4\n1 1 1 3 4\n", r"^2:9: job 1 has 1 values left over"),
    ("1\t2\n1\t1\t1\t-3\n", r"^2:7: job 1 operation 1: time -3 must be > 0$"),
    ("1 2\r\n1 1 9 3\r\n", r"^2:5: job 1 operation 1: machine 9 outside 1\.\.2$"),
]


@pytest.mark.parametrize(
    ("content", "message"), FJSP_CASES, ids=[f"fjsp-{i}" for i in range(len(FJSP_CASES))]
)
def test_malformed_fjsp_files(tmp_path: Path, content: str, message: str) -> None:
    import re

    from scheduler import read_fjsp

    f = tmp_path / "f.fjs"
    f.write_bytes(content.encode("ascii"))
    with pytest.raises(FormatError) as info:
        read_fjsp(f)
    text = str(info.value)
    assert text.startswith(f"{f}:"), text
    assert re.search(message, text[len(str(f)) + 1 :]), text


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"1 2\n1 1 1 3\xff\n", r"FJSP files are ASCII text"),
        (b"\x89PNG\r\n\x1a\n\x00\x00", r"FJSP files are ASCII text"),
        ("1 2\n1 1 1 \u0663\n".encode(), r"FJSP files are ASCII text"),
        (b"1 2\n1 1 1 3\x00\n", r"'3\\x00' is not an integer"),
    ],
)
def test_unreadable_fjsp_files(tmp_path: Path, content: bytes, message: str) -> None:
    from scheduler import read_fjsp

    f = tmp_path / "f.fjs"
    f.write_bytes(content)
    with pytest.raises(FormatError, match=message) as info:
        read_fjsp(f)
    assert str(info.value).startswith(str(f))


def test_fjsp_paths_that_cannot_be_read(tmp_path: Path) -> None:
    from scheduler import read_fjsp

    with pytest.raises(FormatError, match="cannot read FJSP file") as info:
        read_fjsp(tmp_path / "missing.fjs")
    assert "missing.fjs" in str(info.value)
    with pytest.raises(FormatError, match="cannot read FJSP file"):
        read_fjsp(tmp_path)  # a directory


def test_fjsp_text_that_is_not_a_string() -> None:
    from scheduler import parse_fjsp

    with pytest.raises(FormatError, match="FJSP text must be a str, got bytes"):
        parse_fjsp(b"1 1\n1 1 1 1\n")  # type: ignore[arg-type]


# ------------------------------------------------------------ schedule files

SCHEDULE = {
    "format": "multiarm.schedule/1",
    "makespan": 7.0,
    "tasks": [
        {"task": "t1", "arm": "a", "start": 0.0, "end": 4.0, "waits": [], "blocking": 0.0},
        {"task": "t2", "arm": "b", "start": 4.0, "end": 7.0},
    ],
}

SCHEDULE_CASES: list[tuple[str, Any, str]] = [
    ("", [], r"expected an object, got a list"),
    ("format", "multiarm.schedule/7", r"format: unsupported schedule format"),
    ("tasks", "t1", r"tasks: expected a list, got 't1'"),
    ("tasks.0.task", "t9", r"tasks\[0\]\.task: unknown task 't9'"),
    ("tasks.1.task", "t1", r"tasks\[1\]\.task: task 't1' is listed twice"),
    ("tasks.0.arm", "b", r"tasks\[0\]\.arm: arm 'b' cannot do task 't1'"),
    ("tasks.0.arm", 3, r"tasks\[0\]\.arm: expected a non-empty string, got 3"),
    ("tasks.0.start", "0", r"tasks\[0\]\.start: expected a number, got '0'"),
    ("tasks.0.end", None, r"tasks\[0\]\.end: expected a number, got None"),
    ("tasks.0.waits", [[1.0]], r"tasks\[0\]\.waits\[0\]: expected \[border, wait\], got 1 values"),
    ("tasks.0.waits", [[3.5, 1.0]], r"tasks\[0\]\.waits\[0\]\[0\]: 3\.5 is not a border"),
    ("tasks.0.colour", "red", r"tasks\[0\]: unknown key 'colour'"),
    ("tasks.1", DELETE, r"tasks: task 't2' is missing"),
]


@pytest.mark.parametrize(
    ("path", "value", "message"),
    SCHEDULE_CASES,
    ids=[f"schedule-{i}" for i in range(len(SCHEDULE_CASES))],
)
def test_malformed_schedule_files(tmp_path: Path, path: str, value: Any, message: str) -> None:
    import re

    from scheduler import load_schedule

    problem = load_problem(_write(tmp_path / "p.json", BASE))
    data = _set(copy.deepcopy(SCHEDULE), path, value)
    f = _write(tmp_path / "s.json", data)
    with pytest.raises(FormatError) as info:
        load_schedule(f, problem)
    text = str(info.value)
    assert text.startswith(f"{f}: "), text
    assert re.search(message, text[len(str(f)) + 2 :]), text


def test_the_base_schedule_is_valid(tmp_path: Path) -> None:
    from scheduler import load_schedule, validate

    problem = load_problem(_write(tmp_path / "p.json", BASE))
    s = load_schedule(_write(tmp_path / "s.json", SCHEDULE), problem)
    assert validate(problem, s) == 7.0 and s.bound_problem is problem


def _write(path: Path, data: Any) -> Path:
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    ("content", "kind"),
    [
        (json.dumps(BASE), "problem"),
        (json.dumps({k: v for k, v in BASE.items() if k != "format"}), "problem"),
        (json.dumps(SCHEDULE), "schedule"),
        (json.dumps({"tasks": SCHEDULE["tasks"]}), "schedule"),
        ("2 2 1\n1 1 1 3\n1 1 2 4\n", "fjsp"),
        ("2 2\r\n1 1 1 3\r\n1 1 2 4\r\n", "fjsp"),
        ('{"name": "a task set", "tasks": [{"name": "t"}]}', None),
        ("zone a { }\n", None),
        ("[1, 2]", None),
        ("{", None),
        ("1 2\n", None),
    ],
)
def test_files_are_recognised_by_content(tmp_path: Path, content: str, kind: str | None) -> None:
    from scheduler import detect_format

    f = tmp_path / "file.dat"
    f.write_text(content)
    assert detect_format(f) == kind
    assert detect_format(tmp_path / "missing") is None
