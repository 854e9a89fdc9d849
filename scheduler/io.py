"""Problems as JSON: a reader that type-checks every field and names the place.

:func:`load_problem` / :func:`problem_from_dict` read what
:func:`save_problem` / :meth:`Problem.to_dict` write. Every mistake is a
:class:`~multiarm.errors.FormatError` naming the file and the JSON path
(``p.json: tasks[3].modes[0].duration: expected a number, got 'abc'``); a
rule broken across records (an unknown predecessor, a cycle, a window outside
its mode) is the :class:`~multiarm.errors.ValidationError` of
:meth:`Model.build`, with the file named in front. Strings are never taken
for lists, booleans never for numbers, and unknown keys are refused.

Examples
--------
>>> problem_from_dict({"arms": [{"name": "a"}], "tasks": [{"name": "t", "modes": [
...     {"arm": "a", "duration": "abc"}]}]}, filename="p.json")
Traceback (most recent call last):
...
multiarm.errors.FormatError: p.json: tasks[0].modes[0].duration: expected a number, got 'abc'
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from os import PathLike, fspath
from pathlib import Path
from typing import Any, Literal

import numpy as np

from multiarm.errors import FormatError, ValidationError
from multiarm.text import parse_json, read_source
from scheduler.problem import BlockingOracle, Model, Problem, Window
from scheduler.schedule import Schedule

__all__ = [
    "detect_format",
    "load_problem",
    "load_schedule",
    "problem_from_dict",
    "save_problem",
    "schedule_from_dict",
]

FORMAT = "multiarm.problem/1"
SCHEDULE_FORMAT = "multiarm.schedule/1"


class _Reader:
    def __init__(self, filename: str | None) -> None:
        self.filename = filename

    def fail(self, where: str, message: str) -> FormatError:
        return FormatError(f"{where}: {message}" if where else message, filename=self.filename)

    def table(
        self,
        value: Any,
        where: str,
        keys: set[str],
        required: frozenset[str] | set[str] = frozenset(),
    ) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise self.fail(where, f"expected an object, got {_show(value)}")
        unknown = sorted(set(value) - keys)
        if unknown:
            raise self.fail(where, f"unknown key {unknown[0]!r} (known: {', '.join(sorted(keys))})")
        missing = sorted(required - set(value))
        if missing:
            raise self.fail(where, f"missing key {missing[0]!r}")
        return value

    def items(self, value: Any, where: str) -> list[Any]:
        if not isinstance(value, list):
            raise self.fail(where, f"expected a list, got {_show(value)}")
        return value

    def name(self, value: Any, where: str) -> str:
        if not isinstance(value, str) or not value:
            raise self.fail(where, f"expected a non-empty string, got {_show(value)}")
        return value

    def names(self, value: Any, where: str) -> list[str]:
        return [self.name(v, f"{where}[{i}]") for i, v in enumerate(self.items(value, where))]

    def number(self, value: Any, where: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(where, f"expected a number, got {_show(value)}")
        x = float(value)
        if not math.isfinite(x):
            raise self.fail(where, f"expected a finite number, got {value!r}")
        return x

    def integer(self, value: Any, where: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(where, f"expected an integer, got {_show(value)}")
        return int(value)


def _show(value: Any) -> str:
    if isinstance(value, str | int | float | bool) or value is None:
        return repr(value)
    return f"a {type(value).__name__}"


_TOP = {"format", "name", "arms", "zones", "tools", "tasks", "setup"}
_ARM = {"name", "available", "capabilities", "start_zones"}
_TASK = {"name", "release", "predecessors", "group", "modes"}
_MODE = {"arm", "duration", "windows", "tools"}
_WINDOW = {"zone", "start", "end", "kind"}


def _setup(r: _Reader, value: Any) -> dict[str, Any]:
    s = r.table(
        value,
        "setup",
        {"kind", "times", "start", "end", "home", "speed", "base", "metric"},
        {"kind"},
    )
    kind = s["kind"]
    if kind not in ("none", "matrix", "travel"):
        raise r.fail("setup.kind", f"expected 'none', 'matrix' or 'travel', got {_show(kind)}")
    if kind == "matrix":
        times = r.items(s.get("times"), "setup.times")
        for a, rows in enumerate(times):
            width = None
            for i, row in enumerate(r.items(rows, f"setup.times[{a}]")):
                items = r.items(row, f"setup.times[{a}][{i}]")
                for j, v in enumerate(items):
                    r.number(v, f"setup.times[{a}][{i}][{j}]")
                if width is not None and len(items) != width:
                    raise r.fail(
                        f"setup.times[{a}][{i}]",
                        f"expected {width} values like the rows before, got {len(items)}",
                    )
                width = len(items)
        shapes = {
            (len(rows), len(rows[0]) if rows else 0) for rows in times if isinstance(rows, list)
        }
        if len(shapes) > 1:
            raise r.fail("setup.times", "every arm's table must have the same shape")
    if kind == "travel":
        for key in ("start", "end", "home", "speed", "base"):
            if key not in s:
                raise r.fail("setup", f"missing key {key!r}")
        for key in ("start", "end", "home"):
            for i, point in enumerate(r.items(s[key], f"setup.{key}")):
                xyz = r.items(point, f"setup.{key}[{i}]")
                if len(xyz) != 3:
                    raise r.fail(f"setup.{key}[{i}]", f"expected [x, y, z], got {len(xyz)} values")
                for j, v in enumerate(xyz):
                    r.number(v, f"setup.{key}[{i}][{j}]")
        for key in ("speed", "base"):
            if isinstance(s[key], list):
                for i, v in enumerate(s[key]):
                    r.number(v, f"setup.{key}[{i}]")
            else:
                r.number(s[key], f"setup.{key}")
        if "metric" in s and s["metric"] not in ("euclidean", "manhattan"):
            raise r.fail(
                "setup.metric", f"expected 'euclidean' or 'manhattan', got {_show(s['metric'])}"
            )
    return dict(s)


def problem_from_dict(
    data: Any, *, filename: str | None = None, blocking: BlockingOracle | None = None
) -> Problem:
    """Build and validate a problem from JSON data (see the module docstring).

    Raises
    ------
    FormatError
        A field of the wrong type, a missing or unknown key, naming the path.
    ValidationError, CycleError
        A rule of :meth:`Model.build` (the file named in front).
    """
    r = _Reader(filename)
    if isinstance(data, Mapping) and data.get("format", FORMAT) != FORMAT:
        raise r.fail(
            "format",
            f"unsupported problem format {_show(data.get('format'))} (expected {FORMAT!r})",
        )
    top = r.table(data, "", _TOP, {"arms", "tasks"})
    if top.get("format", FORMAT) != FORMAT:  # pragma: no cover - checked above
        raise r.fail(
            "format", f"unsupported problem format {_show(top.get('format'))} (expected {FORMAT!r})"
        )
    m = Model(r.name(top.get("name", "problem"), "name"))
    for i, z in enumerate(r.items(top.get("zones", []), "zones")):
        zt = r.table(z, f"zones[{i}]", {"name", "policy"}, {"name"})
        policy = zt.get("policy", "exclusive")
        if policy not in ("exclusive", "shared"):
            raise r.fail(
                f"zones[{i}].policy", f"expected 'exclusive' or 'shared', got {_show(policy)}"
            )
        m.add_zone(r.name(zt["name"], f"zones[{i}].name"), policy)
    for tool in r.names(top.get("tools", []), "tools"):
        m.add_tool(tool)
    for i, a in enumerate(r.items(top["arms"], "arms")):
        w = f"arms[{i}]"
        at = r.table(a, w, _ARM, {"name"})
        m.add_arm(
            r.name(at["name"], f"{w}.name"),
            available=r.number(at.get("available", 0.0), f"{w}.available"),
            capabilities=r.names(at.get("capabilities", []), f"{w}.capabilities"),
            start_zones=r.names(at.get("start_zones", []), f"{w}.start_zones"),
        )
    tasks = r.items(top["tasks"], "tasks")
    # names are resolved to ids here (the first of a duplicate name, as the
    # model does), so that building stays linear in the number of tasks;
    # unknown names go to the model as names, which refuses them by name
    task_id: dict[str, int] = {}
    arm_id: dict[str, int] = {}
    for i, a in enumerate(top["arms"]):
        arm_id.setdefault(a["name"], i)
    for i, t in enumerate(tasks):
        w = f"tasks[{i}]"
        tt = r.table(t, w, _TASK, {"name"})
        name = r.name(tt["name"], f"{w}.name")
        task_id.setdefault(name, i)
        m.add_task(
            name,
            release=r.number(tt.get("release", 0.0), f"{w}.release"),
            group=r.integer(tt.get("group", -1), f"{w}.group"),
        )
    for i, tt in enumerate(tasks):
        w = f"tasks[{i}]"
        preds = r.names(tt.get("predecessors", []), f"{w}.predecessors")
        m.add_predecessors(i, [task_id.get(p, p) for p in preds])
        for j, md in enumerate(r.items(tt.get("modes", []), f"{w}.modes")):
            wm = f"{w}.modes[{j}]"
            mt = r.table(md, wm, _MODE, {"arm", "duration"})
            windows = []
            for k, win in enumerate(r.items(mt.get("windows", []), f"{wm}.windows")):
                ww = f"{wm}.windows[{k}]"
                wt = r.table(win, ww, _WINDOW, {"zone", "start", "end"})
                kind = wt.get("kind", "occupy")
                if kind not in ("occupy", "move"):
                    raise r.fail(f"{ww}.kind", f"expected 'occupy' or 'move', got {_show(kind)}")
                windows.append(
                    Window(
                        r.name(wt["zone"], f"{ww}.zone"),
                        r.number(wt["start"], f"{ww}.start"),
                        r.number(wt["end"], f"{ww}.end"),
                        kind,
                    )
                )
            arm = r.name(mt["arm"], f"{wm}.arm")
            m.add_mode(
                i,
                arm_id.get(arm, arm),
                r.number(mt["duration"], f"{wm}.duration"),
                windows=windows,
                tools=r.names(mt.get("tools", []), f"{wm}.tools"),
            )
    if "setup" in top:
        m._setup_dict = _setup(r, top["setup"])
    m.set_blocking(blocking)
    try:
        return m.build()
    except ValidationError as exc:
        if filename:
            exc.args = (f"{filename}: {exc.args[0]}", *exc.args[1:])
        raise
    except (KeyError, TypeError, IndexError) as exc:  # a setup table of the wrong shape
        raise r.fail("setup", f"malformed setup data ({exc})") from None


def save_problem(problem: Problem, path: str | PathLike[str]) -> Path:
    """Write ``problem`` as JSON; returns the path.

    Raises
    ------
    FormatError
        When the file cannot be written (the problem is kept in memory).
    """
    p = Path(path)
    text = json.dumps(problem.to_dict(), indent=1, allow_nan=False) + "\n"
    try:
        p.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise FormatError(
            f"cannot write problem file: {exc.strerror}", filename=fspath(p)
        ) from None
    return p


def load_problem(path: str | PathLike[str], blocking: BlockingOracle | None = None) -> Problem:
    """Read a problem written by :func:`save_problem` (see the module docstring)."""
    name = fspath(path)
    data = _read_json(path, "problem")
    return problem_from_dict(data, filename=name, blocking=blocking)


_SCHEDULE_TOP = {"format", "makespan", "tasks"}
_SCHEDULE_ROW = {"task", "arm", "start", "end", "waits", "blocking"}


def schedule_from_dict(data: Any, problem: Problem, *, filename: str | None = None) -> Schedule:
    """A schedule from the JSON data of :meth:`Schedule.to_dict`, type-checked.

    Parameters
    ----------
    data : Any
        The parsed JSON.
    problem : Problem
        The problem the schedule is for (names are resolved in it).
    filename : str or None
        Named in errors.

    Returns
    -------
    Schedule
        Bound to ``problem``; not validated (use :func:`scheduler.validate`).

    Raises
    ------
    FormatError
        A field of the wrong type, an unknown task or arm, a task listed twice
        or missing, a wait at an offset that is not a border: naming the
        JSON path.

    Examples
    --------
    >>> from scheduler.fjsp import parse_fjsp
    >>> p = parse_fjsp("1 1\\n1 1 1 2\\n")
    >>> schedule_from_dict({"tasks": [{"task": "J1.O1", "arm": "M2", "start": 0, "end": 2}]}, p)
    Traceback (most recent call last):
    ...
    multiarm.errors.FormatError: <string>: tasks[0].arm: unknown arm 'M2'
    """
    r = _Reader(filename)
    top = r.table(data, "", _SCHEDULE_TOP, {"tasks"})
    if top.get("format", SCHEDULE_FORMAT) != SCHEDULE_FORMAT:
        raise r.fail(
            "format",
            f"unsupported schedule format {_show(top.get('format'))} (expected "
            f"{SCHEDULE_FORMAT!r})",
        )
    T = problem.n_tasks
    task_ids = {n: i for i, n in enumerate(problem.task_names)}
    arm_ids = {n: i for i, n in enumerate(problem.arm_names)}
    mode = np.full(T, -1, dtype=np.int64)
    start, end, blocking = np.zeros(T), np.zeros(T), np.zeros(T)
    waits: list[Any] = [np.zeros(0)] * T
    for i, row in enumerate(r.items(top["tasks"], "tasks")):
        w = f"tasks[{i}]"
        rt = r.table(row, w, _SCHEDULE_ROW, {"task", "arm", "start", "end"})
        name = r.name(rt["task"], f"{w}.task")
        if name not in task_ids:
            raise r.fail(f"{w}.task", f"unknown task {name!r}")
        t = task_ids[name]
        if mode[t] >= 0:
            raise r.fail(f"{w}.task", f"task {name!r} is listed twice")
        arm = r.name(rt["arm"], f"{w}.arm")
        if arm not in arm_ids:
            raise r.fail(f"{w}.arm", f"unknown arm {arm!r}")
        m = int(problem.mode_of[arm_ids[arm], t])
        if m < 0:
            raise r.fail(f"{w}.arm", f"arm {arm!r} cannot do task {name!r}")
        mode[t] = m
        start[t] = r.number(rt["start"], f"{w}.start")
        end[t] = r.number(rt["end"], f"{w}.end")
        blocking[t] = r.number(rt.get("blocking", 0.0), f"{w}.blocking")
        borders = problem.shapes[m].borders
        wt = np.zeros(len(borders))
        for j, pair in enumerate(r.items(rt.get("waits", []), f"{w}.waits")):
            items = r.items(pair, f"{w}.waits[{j}]")
            if len(items) != 2:
                raise r.fail(f"{w}.waits[{j}]", f"expected [border, wait], got {len(items)} values")
            b = r.number(items[0], f"{w}.waits[{j}][0]")
            x = r.number(items[1], f"{w}.waits[{j}][1]")
            if b not in borders:
                raise r.fail(
                    f"{w}.waits[{j}][0]", f"{b:g} is not a border of the mode of task {name!r}"
                )
            wt[borders.index(b)] = x
        waits[t] = wt
    if T and (mode < 0).any():
        missing = problem.task_names[int(np.argmax(mode < 0))]
        raise r.fail("tasks", f"task {missing!r} is missing")
    return Schedule(mode, start, end, tuple(waits), blocking).bind(problem)


def load_schedule(path: str | PathLike[str], problem: Problem) -> Schedule:
    """Read a schedule written by ``Plan.write`` / ``Schedule.to_dict`` (JSON).

    Parameters
    ----------
    path : path-like
    problem : Problem

    Returns
    -------
    Schedule
        Bound to ``problem``, not validated.

    Raises
    ------
    FormatError
        Unreadable, not JSON, or malformed (see :func:`schedule_from_dict`).
    """
    name = fspath(path)
    data = _read_json(path, "schedule")
    return schedule_from_dict(data, problem, filename=name)


def _read_json(path: str | PathLike[str], what: str) -> Any:
    name = fspath(path)
    text = read_source(path, FormatError, what)
    return parse_json(text, name, FormatError, f"{what} file")


FileKind = Literal["problem", "schedule", "fjsp"]


def detect_format(path: str | PathLike[str]) -> FileKind | None:
    """What a file holds, judged by its content (not its name).

    A JSON object with ``"format": "multiarm.problem/1"`` (or with ``arms``
    and ``tasks`` whose entries have ``modes``) is a problem; with
    ``"format": "multiarm.schedule/1"`` (or ``tasks`` whose entries have
    ``start``) a schedule; text whose first line holds two or three numbers
    and whose next line holds only integers is an FJSPLIB instance.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    {"problem", "schedule", "fjsp"} or None
        None when it is none of these, or cannot be read.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "x.txt").write_text("2 2 1\\n1 1 1 3\\n1 1 2 4\\n")
    >>> detect_format(d / "x.txt")
    'fjsp'
    >>> _ = (d / "y").write_text('{"arms": [{"name": "a"}], "tasks": []}')
    >>> detect_format(d / "y")
    'problem'
    """
    try:
        with Path(path).open("rb") as fh:
            text = fh.read(64 * 1024 * 1024).decode("utf-8")  # a problem is far smaller
    except (OSError, UnicodeDecodeError):
        return None
    head = text.lstrip()
    if head.startswith("{"):
        try:
            data = json.loads(text)
        except (json.JSONDecodeError, RecursionError):
            return None
        if not isinstance(data, dict):
            return None
        fmt = data.get("format")
        if fmt == FORMAT:
            return "problem"
        if fmt == SCHEDULE_FORMAT:
            return "schedule"
        tasks = data.get("tasks")
        if fmt is None and isinstance(tasks, list):
            rows = [t for t in tasks if isinstance(t, dict)]
            if "arms" in data and all("modes" in t or "task" not in t for t in rows):
                return "problem"
            if rows and all("task" in t and "start" in t for t in rows):
                return "schedule"
        return None
    lines = [ln.split() for ln in text.splitlines() if ln.strip()]
    if len(lines) >= 2 and 2 <= len(lines[0]) <= 3:
        try:
            [float(x) for x in lines[0]]
            [int(x) for x in lines[1]]
        except ValueError:
            return None
        return "fjsp"
    return None
