"""Task sets to and from plain data, JSON and TOML files.

A task-set file is short enough to write by hand (``docs/tasklib.md``
documents every field)::

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
        { kind = "approach", target = [0.1, 0.5, 0.05] },
        { kind = "grasp", part = "pin" },
    ]

A pose is ``[x, y, z]`` (metres; the tool points down) or ``[x, y, z, qw,
qx, qy, qz]`` (with a unit quaternion); the older table form ``{ position =
[...], orientation = [...] }`` still reads. Keys left out take their
defaults. :func:`save_taskset` writes the same compact layout (one line a
step, defaults left out), and numbers so that they read back exactly:
``load_taskset(save_taskset(ts, path)) == ts`` for both formats. Unknown
keys, missing keys and wrong types are errors that name the file and the
place (``tasks[3].steps[1].target``); TOML syntax errors give
``file:line:col``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
import types
import typing
from collections.abc import Mapping
from functools import cache
from os import PathLike, fspath
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin

from multiarm.errors import FormatError, SourceError, ValidationError
from multiarm.text import parse_json
from multiarm.text import parse_toml as _parse_toml
from tasklib.arrivals import ARRIVAL_MODELS, Feeder
from tasklib.model import Part, PartGroup, Task, TaskSet
from tasklib.pose import DOWN, Pose
from tasklib.steps import STEP_KINDS
from tasklib.tdl import TDLDocument, parse_tdl, print_tdl

__all__ = [
    "FORMAT",
    "load_taskset",
    "parse_toml",
    "read_toml_source",
    "save_taskset",
    "taskset_from_dict",
    "taskset_to_dict",
    "taskset_to_toml",
]

FORMAT = "multiarm.taskset/1"

_SKIP = {"line", "column", "filename"}


class _Bad(Exception):
    def __init__(self, where: str, message: str) -> None:
        super().__init__(f"{where}: {message}" if where else message)


# ------------------------------------------------------------------- to data


def _same(value: Any, default: Any) -> bool:
    """``value`` is the default, to the bit (so that leaving it out round-trips)."""
    return type(value) is type(default) and repr(value) == repr(default)


def _is_down(q: tuple[float, ...]) -> bool:
    return repr(tuple(q)) == repr(DOWN)


def _plain(obj: Any) -> Any:
    if isinstance(obj, Pose):
        if _is_down(obj.orientation):
            return list(obj.position)
        return [*obj.position, *obj.orientation]
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
            if f.default is not dataclasses.MISSING and _same(value, f.default):
                continue
            if f.default_factory is not dataclasses.MISSING and _same(value, f.default_factory()):
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
        if isinstance(value, list | tuple):
            return _pose_list(value, where)
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


def _pose_list(value: list[Any] | tuple[Any, ...], where: str) -> Pose:
    numbers = all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    if not numbers or len(value) not in (3, 7):
        raise _Bad(
            where,
            "a pose is [x, y, z] (metres, tool pointing down) or [x, y, z, qw, qx, qy, qz], "
            f"got {value!r}",
        )
    try:
        if len(value) == 3:
            return Pose((value[0], value[1], value[2]))
        return Pose((value[0], value[1], value[2]), (value[3], value[4], value[5], value[6]))
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


# ---------------------------------------------------------------- TOML text

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def _toml_str(text: str) -> str:
    out = []
    for ch in text:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _toml_str(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValidationError(f"cannot write the non-finite number {value!r}")
        return repr(value)
    if isinstance(value, str):
        return _toml_str(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        if not value:
            return "{}"
        items = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{ " + items + " }"
    raise ValidationError(
        f"cannot write a value of type {type(value).__name__}"
    )  # pragma: no cover


def _toml_text_block(text: str) -> str:
    """A multi-line literal string when the text allows it (TDL reads best so)."""
    plain = all(ch in "\n\t" or (ord(ch) >= 0x20 and ord(ch) != 0x7F) for ch in text)
    if plain and "'''" not in text and not text.endswith("'"):
        return "'''\n" + text + "'''"
    return _toml_str(text)


def taskset_to_toml(ts: TaskSet) -> str:
    """The task set as the short TOML text :func:`save_taskset` writes.

    One ``[[tasks]]`` table a task, one line a step, poses as ``[x, y, z]``
    when the tool points down, defaults left out; reads back exactly with
    :func:`taskset_from_dict` (``tomllib.loads``).
    """
    data = taskset_to_dict(ts)
    lines: list[str] = []
    for key in ("format", "name", "description"):
        if key in data:
            lines.append(f"{key} = {_toml_value(data[key])}")
    if "tdl" in data:
        lines.append(f"tdl = {_toml_text_block(data['tdl'])}")
    for key in ("feeders", "parts", "groups", "tasks"):
        for item in data.get(key, []):
            lines += ["", f"[[{key}]]"]
            for k, v in item.items():
                if k == "steps":
                    lines.append("steps = [")
                    lines += [f"    {_toml_value(step)}," for step in v]
                    lines.append("]")
                else:
                    lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
    return "\n".join(lines) + "\n"


_TOML_POS = re.compile(r"\s*\(at line (\d+), column (\d+)\)")


def read_toml_source(path: str | PathLike[str], what: str) -> str:
    """The UTF-8 text of a TOML file; a :class:`FormatError` naming the file otherwise.

    Undecodable bytes are located (``file:line:col``, the column counted in
    bytes) and an empty file is an error at ``file:1:1``.
    """
    name = fspath(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise FormatError(f"cannot read {what} file: {exc.strerror}", filename=name) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise FormatError(
            f"{what} file is not UTF-8 text (byte 0x{raw[exc.start]:02x}: {exc.reason}); "
            "save it as UTF-8",
            filename=name,
            line=line,
            column=col,
        ) from None
    if not text.strip():
        raise FormatError(f"the {what} file is empty", filename=name, line=1, column=1)
    return text


def parse_toml(text: str, filename: str) -> dict[str, Any]:
    """Parse TOML text; a syntax error is a :class:`FormatError` at ``file:line:col``.

    Shared by every TOML file of the package (task sets, cells); nesting too
    deep and numbers with too many digits are errors naming the file too
    (:func:`multiarm.text.parse_toml`).
    """
    data: dict[str, Any] = _parse_toml(text, filename, FormatError, "TOML file")
    return data


def save_taskset(ts: TaskSet, path: str | PathLike[str]) -> Path:
    """Write a task set to ``path`` (``.toml`` or ``.json``); returns the path.

    TOML is the short, hand-editable layout of :func:`taskset_to_toml`.
    """
    p = Path(path)
    if _format_of(p) == "json":
        data = taskset_to_dict(ts)
        p.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    else:
        p.write_text(taskset_to_toml(ts), encoding="utf-8")
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
    text = read_toml_source(p, "task-set")
    if kind == "toml":
        data: Any = parse_toml(text, name)
    else:
        data = parse_json(text, name, FormatError, "task-set file")
    try:
        return taskset_from_dict(data, filename=name)
    except SourceError:
        raise
    except ValidationError as exc:
        # Found after parsing (a cycle, a duplicate id, ...): name the file too.
        exc.args = (f"{name}: {exc.args[0]}", *exc.args[1:])
        raise
