"""Task sets to and from plain data, JSON and TOML files.

The file layout mirrors the records (see ``docs/tasklib.md``)::

    format = "multiarm.taskset/1"
    name = "demo"
    tdl = '''trajectory t { taught { stop (0, 0, 0.3) } }'''

    [[feeders]]
    id = "tray"
    parts = ["pin"]
    position = [0.1, 0.5, 0.0]
    arrival = { model = "poisson", rate = 0.2 }

    [[parts]]
    id = "pin"

    [[tasks]]
    id = "pick_pin"
    consumes = ["pin"]
    steps = [
        { kind = "move", trajectory = "t" },
        { kind = "grasp", part = "pin" },
    ]

Numbers are written so that they read back exactly:
``load_taskset(save_taskset(ts, path)) == ts`` for both formats. Unknown
keys, missing keys and wrong types are errors that name the place
(``tasks[3].steps[1]``) and the file.
"""

from __future__ import annotations

import dataclasses
import json
import math
import types
import typing
from collections.abc import Mapping
from functools import cache
from os import PathLike, fspath
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin

import tomli_w

from multiarm.errors import FormatError, SourceError, ValidationError
from multiarm.text import parse_json, parse_toml
from tasklib.arrivals import ARRIVAL_MODELS, Feeder
from tasklib.model import Part, PartGroup, Task, TaskSet
from tasklib.pose import Pose
from tasklib.steps import STEP_KINDS
from tasklib.tdl import TDLDocument, parse_tdl, print_tdl

__all__ = ["FORMAT", "load_taskset", "save_taskset", "taskset_from_dict", "taskset_to_dict"]

FORMAT = "multiarm.taskset/1"

_SKIP = {"line", "column", "filename"}


class _Bad(Exception):
    def __init__(self, where: str, message: str) -> None:
        super().__init__(f"{where}: {message}" if where else message)


# ------------------------------------------------------------------- to data


def _plain(obj: Any) -> Any:
    if isinstance(obj, Pose):
        return {"position": list(obj.position), "orientation": list(obj.orientation)}
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        out: dict[str, Any] = {}
        kind = getattr(type(obj), "kind", None)
        if kind:
            out["kind"] = kind
        model = getattr(type(obj), "model", None)
        if isinstance(model, str):
            out["model"] = model
        for f in dataclasses.fields(obj):
            if not f.init or f.name in _SKIP or f.name.startswith("_"):
                continue
            value = getattr(obj, f.name)
            if value is None:
                continue
            out[f.name] = _plain(value)
        return out
    if isinstance(obj, tuple | list):
        return [_plain(v) for v in obj]
    return obj


def taskset_to_dict(ts: TaskSet) -> dict[str, Any]:
    """Plain data (dicts, lists, str, float, int, bool; no ``None``) for a task set."""
    out: dict[str, Any] = {"format": FORMAT, "name": ts.name}
    if ts.description:
        out["description"] = ts.description
    if len(ts.trajectories) or ts.trajectories.frames:
        out["tdl"] = print_tdl(ts.trajectories)
    for key in ("feeders", "parts", "groups", "tasks"):
        items = getattr(ts, key)
        if items:
            out[key] = [_plain(x) for x in items]
    return out


# ----------------------------------------------------------------- from data


@cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _is_optional(tp: Any) -> bool:
    return get_origin(tp) in (Union, types.UnionType) and type(None) in get_args(tp)


def _convert(tp: Any, value: Any, where: str) -> Any:
    origin = get_origin(tp)
    if tp is Any:
        return value
    if origin in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        if value is None:
            return None
        if len(args) == 1:
            return _convert(args[0], value, where)
        names = {getattr(a, "__name__", "") for a in args}
        if "Move" in names:
            return _step(value, where)
        if "PoissonArrivals" in names:
            return _arrival(value, where)
        raise _Bad(where, f"cannot read a value of type {tp}")  # pragma: no cover
    if origin is Literal:
        if value not in get_args(tp):
            allowed = ", ".join(repr(a) for a in get_args(tp))
            raise _Bad(where, f"{value!r} is not one of {allowed}")
        return value
    if origin is tuple:
        targs = get_args(tp)
        if not isinstance(value, list | tuple):
            raise _Bad(where, f"expected a list, got {type(value).__name__}")
        if len(targs) == 2 and targs[1] is Ellipsis:
            return tuple(_convert(targs[0], v, f"{where}[{i}]") for i, v in enumerate(value))
        if len(value) != len(targs):
            raise _Bad(where, f"expected {len(targs)} values, got {len(value)}")
        return tuple(
            _convert(a, v, f"{where}[{i}]")
            for i, (a, v) in enumerate(zip(targs, value, strict=True))
        )
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise _Bad(where, f"expected a number, got {value!r}")
        if not math.isfinite(value):
            raise _Bad(where, f"expected a finite number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise _Bad(where, f"expected an integer, got {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise _Bad(where, f"expected true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise _Bad(where, f"expected text, got {value!r}")
        return value
    if tp is Pose:
        return _record(Pose, value, where)
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return _record(tp, value, where)
    raise _Bad(where, f"cannot read a value of type {tp}")  # pragma: no cover


def _record(cls: type, value: Any, where: str, ignore: tuple[str, ...] = ()) -> Any:
    if not isinstance(value, Mapping):
        raise _Bad(where, f"expected a table/object, got {type(value).__name__}")
    hints = _hints(cls)
    fields = {
        f.name: f
        for f in dataclasses.fields(cls)
        if f.init and f.name not in _SKIP and not f.name.startswith("_")
    }
    unknown = [k for k in value if k not in fields and k not in ignore]
    if unknown:
        raise _Bad(where, f"unknown key {unknown[0]!r} (allowed: {', '.join(fields)})")
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        sub = f"{where}.{name}" if where else name
        if name not in value:
            required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            if required and not _is_optional(hints[name]):
                raise _Bad(where, f"missing key {name!r}")
            continue
        kwargs[name] = _convert(hints[name], value[name], sub)
    try:
        return cls(**kwargs)
    except ValidationError as exc:
        raise _Bad(where, str(exc)) from None


def _step(value: Any, where: str) -> Any:
    if not isinstance(value, Mapping) or "kind" not in value:
        raise _Bad(where, "a step needs a 'kind'")
    cls = STEP_KINDS.get(value["kind"])
    if cls is None:
        raise _Bad(where, f"unknown step kind {value['kind']!r} (known: {', '.join(STEP_KINDS)})")
    return _record(cls, value, where, ignore=("kind",))


def _arrival(value: Any, where: str) -> Any:
    if not isinstance(value, Mapping) or "model" not in value:
        raise _Bad(where, "an arrival model needs a 'model'")
    cls = ARRIVAL_MODELS.get(value["model"])
    if cls is None:
        raise _Bad(
            where, f"unknown arrival model {value['model']!r} (known: {', '.join(ARRIVAL_MODELS)})"
        )
    return _record(cls, value, where, ignore=("model",))


def taskset_from_dict(data: Mapping[str, Any], filename: str | None = None) -> TaskSet:
    """Build a task set from plain data (the inverse of :func:`taskset_to_dict`).

    Raises
    ------
    FormatError
        On a structural problem (unknown or missing key, wrong type, bad
        format tag), naming the place and the file.
    ValidationError
        When the records are well-formed but break a task-set rule
        (see :class:`~tasklib.model.TaskSet`).
    TDLError
        When the embedded TDL text is wrong.
    """
    if not isinstance(data, Mapping):
        raise FormatError("a task set file must hold a table/object at the top", filename=filename)
    allowed = {"format", "name", "description", "tdl", "feeders", "parts", "groups", "tasks"}
    unknown = [k for k in data if k not in allowed]
    if unknown:
        raise FormatError(f"unknown top-level key {unknown[0]!r}", filename=filename)
    if data.get("format", FORMAT) != FORMAT:
        raise FormatError(
            f"unsupported format {data.get('format')!r} (expected {FORMAT!r})", filename=filename
        )
    if "name" not in data or not isinstance(data["name"], str):
        raise FormatError("a task set needs a 'name' (text)", filename=filename)
    tdl = data.get("tdl", "")
    if not isinstance(tdl, str):
        raise FormatError("'tdl' must be TDL text", filename=filename)
    doc = parse_tdl(tdl, filename=f"{filename or '<data>'}[tdl]") if tdl else TDLDocument()
    kinds = {"feeders": Feeder, "parts": Part, "groups": PartGroup, "tasks": Task}
    lists: dict[str, tuple[Any, ...]] = {}
    try:
        for key, cls in kinds.items():
            raw = data.get(key, [])
            if not isinstance(raw, list):
                raise _Bad(key, "expected a list")
            lists[key] = tuple(_record(cls, v, f"{key}[{i}]") for i, v in enumerate(raw))
    except _Bad as exc:
        raise FormatError(str(exc), filename=filename) from None
    description = data.get("description", "")
    if not isinstance(description, str):
        raise FormatError("'description' must be text", filename=filename)
    return TaskSet(
        data["name"],
        lists["tasks"],
        lists["parts"],
        lists["feeders"],
        lists["groups"],
        doc,
        description,
    )


def _format_of(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix in (".toml", ".json"):
        return suffix[1:]
    raise FormatError(
        f"unknown task-set file type {suffix!r}: use .toml or .json", filename=fspath(path)
    )


def save_taskset(ts: TaskSet, path: str | PathLike[str]) -> Path:
    """Write a task set to ``path`` (``.toml`` or ``.json``); returns the path."""
    p = Path(path)
    data = taskset_to_dict(ts)
    if _format_of(p) == "json":
        p.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    else:
        p.write_text(tomli_w.dumps(data, multiline_strings=True), encoding="utf-8")
    return p


def load_taskset(path: str | PathLike[str]) -> TaskSet:
    """Read a task set from a ``.toml`` or ``.json`` file.

    Raises
    ------
    FormatError
        Unreadable file, bad syntax (with line and column where the parser
        gives them), or a structural problem.
    ValidationError, TDLError
        See :func:`taskset_from_dict`.
    """
    p = Path(path)
    name = fspath(path)
    kind = _format_of(p)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise FormatError(f"cannot read task-set file: {exc.strerror}", filename=name) from None
    except UnicodeDecodeError as exc:
        raise FormatError(
            f"task-set file is not UTF-8 text ({exc.reason})", filename=name
        ) from None
    parse = parse_json if kind == "json" else parse_toml
    data = parse(text, name, FormatError, "task-set file")
    try:
        return taskset_from_dict(data, filename=name)
    except SourceError:
        raise
    except ValidationError as exc:
        # Found after parsing (a cycle, a duplicate id, ...): name the file too.
        exc.args = (f"{name}: {exc.args[0]}", *exc.args[1:])
        raise
