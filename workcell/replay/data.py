"""The replay of a run as data: sampled poses, zone states, tasks and faults.

:func:`build_replay` turns a simulation result and its cell into a
:class:`ReplayData`, a JSON document (format ``"multiarm.replay/1"``) that
holds everything the browser page draws, so that the page can be rebuilt
from a run directory without the cell or the simulator
(:meth:`ReplayData.save`, :func:`load_replay`):

* ``arms``: name and colour (:func:`workcell.style.arm_colours`, the
  colours of every plot of a run);
* ``bodies``: what is drawn of each arm, one entry per body: a collision
  primitive (capsule, box, sphere, cylinder; :class:`workcell.arms.base.LinkShape`)
  or, for an arm read from URDF, a collision mesh of a link (``meshes``,
  shared between bodies and zones, stored once);
* ``frames``: every body's pose on a uniform time grid, sampled in one
  vectorised call per arm (``result.joints(times)``, then the arm's
  ``shape_transforms`` or ``mesh_transforms``): positions quantised to int16
  on the cell's box, unit quaternions times 32767, laid out ``(bodies, 7,
  frames)``, zlib-compressed and base64-encoded;
* ``zones`` and ``zone_states``: the zones' solids (SDL zones, and the
  space-grid blocks the run used) and, per zone, the intervals in which it
  is ``occupied`` (an arm holds it), ``moving`` (an arm moves inside a
  shared zone) or ``waiting`` (an arm stands at its border, asleep until it
  is granted, S2.6); ``free`` otherwise;
* ``tasks``: the arm that ran it and the arm the given plan put it on,
  executed start and end, planned start and end, status and
  cause (a task cut short ends at its arm's first fault after its start,
  or at the end of the replay; a task that never ran has no start);
* ``faults``: kind (a key of :data:`workcell.style.FAULT_MARKS`), arm,
  time and end;
* ``tools`` (optional; documents without it show no tools): each tool of
  the zone map with its rack point and the intervals in which an arm holds
  it (the run's tool reservations); the page draws it at its rack and, while
  held, at the arm's ``tip`` body (each arm entry names its body on the
  deepest kinematic frame).

Nothing here imports the simulator: a run is whatever offers the few
attributes of :class:`RunLike`.

Examples
--------
>>> from workcell import compile_cell, load_example, simulate
>>> from scheduler import solve
>>> cc = compile_cell(load_example("scara4"))
>>> result = simulate(cc, solve(cc.problem, "greedy", seed=0).schedule)
>>> data = build_replay(result, cc, max_frames=200)
>>> data.arm_names
('sw', 'se', 'ne', 'nw')
>>> data.n_frames, round(data.duration, 3) == round(result.metrics.executed_makespan, 3)
(200, True)
>>> ReplayData.from_json(data.to_json()) == data
True
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import zlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any, Literal, Protocol

import numpy as np

from multiarm.errors import UsageError, ValidationError
from multiarm.types import FloatArray
from workcell.style import FAULT_MARKS, arm_colours, fault_kind

__all__ = [
    "FORMAT",
    "REPLAY_FILE",
    "STATE_COLOURS",
    "ReplayData",
    "RunLike",
    "build_replay",
    "load_replay",
]

FORMAT = "multiarm.replay/1"
"""The ``format`` field of a replay document."""

REPLAY_FILE = "replay.json"
"""The name of the replay document in a run directory."""

STATE_COLOURS: dict[str, str] = {
    "free": "#9a9a9a",
    "occupied": "#505050",
    "moving": "#e0b000",
    "waiting": "#c2187a",
}
"""Fill colour of a zone in each state (its outline takes the colour of the
arm that holds it or waits for it)."""

Geometry = Literal["auto", "shapes"]


class EventLike(Protocol):
    """A record of a run's trace (:class:`workcell.sim.events.trace.TraceEvent`)."""

    @property
    def time(self) -> float: ...
    @property
    def kind(self) -> str: ...
    @property
    def arm(self) -> str: ...
    @property
    def task(self) -> str: ...
    @property
    def zone(self) -> str: ...
    @property
    def delay(self) -> float: ...
    @property
    def detail(self) -> str: ...


class RunLike(Protocol):
    """What :func:`build_replay` reads of a run (a :class:`workcell.SimResult`)."""

    @property
    def trace(self) -> Iterable[EventLike]: ...
    @property
    def metrics(self) -> Any: ...
    @property
    def problem(self) -> Any: ...
    def joints(self, times: Sequence[float] | FloatArray) -> dict[str, FloatArray]: ...
    def tasks_frame(self) -> Any: ...
    def reservations_frame(self) -> Any: ...


# ------------------------------------------------------------------ codec


def _pack(arr: np.ndarray[Any, Any]) -> str:
    """Little-endian bytes of ``arr``, zlib (level 9), base64 text."""
    a = np.ascontiguousarray(arr)
    if a.dtype.byteorder == ">":  # pragma: no cover - little-endian machines
        a = a.byteswap().view(a.dtype.newbyteorder("<"))
    return base64.b64encode(zlib.compress(a.tobytes(), 9)).decode("ascii")


def _unpack(text: str, dtype: Any, where: str) -> np.ndarray[Any, Any]:
    try:
        raw = zlib.decompress(base64.b64decode(text.encode("ascii"), validate=True))
        return np.frombuffer(raw, dtype=np.dtype(dtype).newbyteorder("<"))
    except (ValueError, zlib.error, UnicodeEncodeError, AttributeError) as exc:
        raise ValidationError(f"{where}: not packed array data ({exc})") from None


def _finite(x: Any) -> float | None:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _hex(rgba: Sequence[float]) -> str:
    r, g, b = (round(255 * float(c)) for c in rgba[:3])
    return f"#{r:02x}{g:02x}{b:02x}"


def _quaternions(rot: FloatArray) -> FloatArray:
    """(..., 4) unit quaternions (x, y, z, w) of rotation matrices (..., 3, 3)."""
    from scipy.spatial.transform import Rotation

    flat = rot.reshape(-1, 3, 3)
    q: FloatArray = Rotation.from_matrix(flat).as_quat()
    return q.reshape(*rot.shape[:-2], 4)


# --------------------------------------------------------------- the data


@dataclass(frozen=True, slots=True, eq=False)
class ReplayData:
    """A replay document (module docstring); compare with ``==`` by content.

    Attributes
    ----------
    document : dict
        The JSON-ready document, format :data:`FORMAT`. Treat it as read-only.
    """

    document: dict[str, Any]

    def __post_init__(self) -> None:
        _check(self.document, "replay")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ReplayData):
            return NotImplemented
        return self.to_json() == other.to_json()

    def __hash__(self) -> int:
        return hash(self.to_json())

    @property
    def duration(self) -> float:
        """Seconds of the run shown (the slider's range)."""
        return float(self.document["duration"])

    @property
    def n_frames(self) -> int:
        """Samples of the time grid."""
        return int(self.document["frames"]["n"])

    @property
    def arm_names(self) -> tuple[str, ...]:
        """The arms, in the problem's order."""
        return tuple(str(a["name"]) for a in self.document["arms"])

    def times(self) -> FloatArray:
        """(n_frames,) float: the time grid, seconds."""
        fr = self.document["frames"]
        out: FloatArray = fr["t0"] + fr["dt"] * np.arange(int(fr["n"]), dtype=float)
        return out

    def poses(self) -> FloatArray:
        """(n_frames, bodies, 7) float: each body's position (metres) and unit
        quaternion (x, y, z, w) at each time of :meth:`times`, as stored."""
        fr = self.document["frames"]
        b, n = len(self.document["bodies"]), int(fr["n"])
        raw = _unpack(fr["poses"], np.int16, "replay.frames.poses").astype(float)
        if raw.size != b * 7 * n:
            raise ValidationError(
                f"replay.frames.poses: {raw.size} values, expected {b} bodies x 7 x {n} frames"
            )
        v = raw.reshape(b, 7, n).transpose(2, 0, 1)
        out = np.empty_like(v)
        lo, scale = np.asarray(fr["lo"], float), np.asarray(fr["scale"], float)
        out[..., :3] = lo + (v[..., :3] + 32768.0) * scale
        q = v[..., 3:] / 32767.0
        out[..., 3:] = q / np.linalg.norm(q, axis=-1, keepdims=True)
        return out

    def to_json(self, path: str | PathLike[str] | None = None) -> str:
        """The document as JSON text, written to ``path`` when given."""
        text = json.dumps(self.document, allow_nan=False, separators=(",", ":"))
        if path is not None:
            Path(path).write_text(text, encoding="utf-8")
        return text

    @classmethod
    def from_json(cls, text: str, filename: str = "replay") -> ReplayData:
        """Inverse of :meth:`to_json`.

        Raises
        ------
        ValidationError
            Text that is not a replay document (``filename`` and the field named).
        """
        try:
            doc = json.loads(text)
        except ValueError as exc:
            raise ValidationError(f"{filename}: not JSON ({exc})") from None
        _check(doc, filename)
        return cls(doc)

    def save(self, directory: str | PathLike[str]) -> Path:
        """Write :data:`REPLAY_FILE` into ``directory`` (created); returns its path."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        p = d / REPLAY_FILE
        self.to_json(p)
        return p


_REQUIRED: dict[str, type | tuple[type, ...]] = {
    "format": str,
    "title": str,
    "duration": (int, float),
    "bounds": list,
    "arms": list,
    "bodies": list,
    "meshes": list,
    "frames": dict,
    "zones": list,
    "zone_states": list,
    "tasks": list,
    "faults": list,
    "fault_marks": dict,
    "states": dict,
    "summary": dict,
}


def _check(doc: Any, where: str) -> None:
    if not isinstance(doc, dict):
        raise ValidationError(f"{where}: a replay document is a JSON object")
    if doc.get("format") != FORMAT:
        raise ValidationError(f"{where}.format: expected {FORMAT!r}, got {doc.get('format')!r}")
    for key, kind in _REQUIRED.items():
        if key not in doc:
            raise ValidationError(f"{where}.{key}: missing")
        if not isinstance(doc[key], kind) or isinstance(doc[key], bool):
            raise ValidationError(f"{where}.{key}: wrong type {type(doc[key]).__name__}")
    fr = doc["frames"]
    for key in ("t0", "dt", "n", "lo", "scale", "poses"):
        if key not in fr:
            raise ValidationError(f"{where}.frames.{key}: missing")
    n_arms = len(doc["arms"])
    for i, b in enumerate(doc["bodies"]):
        if not isinstance(b, dict) or not isinstance(b.get("arm"), int):
            raise ValidationError(f"{where}.bodies[{i}]: needs an integer 'arm'")
        if not 0 <= b["arm"] < n_arms:
            raise ValidationError(f"{where}.bodies[{i}].arm: no arm {b['arm']}")
    tools = doc.get("tools", [])
    if not isinstance(tools, list):
        raise ValidationError(f"{where}.tools: wrong type {type(tools).__name__}")
    for i, t in enumerate(tools):
        rack = t.get("rack") if isinstance(t, dict) else None
        if not (isinstance(rack, list) and len(rack) == 3 and isinstance(t.get("held"), list)):
            raise ValidationError(f"{where}.tools[{i}]: needs a 'rack' point and 'held' intervals")
        for k, h in enumerate(t["held"]):
            if not (isinstance(h, dict) and isinstance(h.get("arm"), int)):
                raise ValidationError(f"{where}.tools[{i}].held[{k}]: needs an integer 'arm'")
            if not 0 <= h["arm"] < n_arms:
                raise ValidationError(f"{where}.tools[{i}].held[{k}].arm: no arm {h['arm']}")


def load_replay(path: str | PathLike[str]) -> ReplayData:
    """Read a replay document: a file, or a run directory holding :data:`REPLAY_FILE`.

    Raises
    ------
    UsageError
        No such file, or a directory without a replay document.
    ValidationError
        A file that is not a replay document.
    """
    p = Path(path)
    if p.is_dir():
        p = p / REPLAY_FILE
        if not p.is_file():
            raise UsageError(
                f"{str(path)!r} holds no {REPLAY_FILE} (write one with "
                "workcell.replay.save_replay, or 'multiarm simulate --out DIR')"
            )
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UsageError(f"{str(p)!r}: no such file or directory") from None
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise UsageError(f"{str(p)!r}: cannot read it: {why}") from None
    return ReplayData.from_json(text, str(p))


# ---------------------------------------------------------------- building


class _Meshes:
    """Triangle meshes stored once each (two arms of one model share theirs)."""

    def __init__(self) -> None:
        self.items: list[dict[str, str]] = []
        self._index: dict[str, int] = {}

    def add(self, vertices: Any, faces: Any) -> int:
        v = np.asarray(vertices, dtype="<f4").reshape(-1, 3)
        f = np.asarray(faces, dtype="<u4").reshape(-1, 3)
        key = hashlib.sha1(v.tobytes() + b"|" + f.tobytes()).hexdigest()
        if key not in self._index:
            self._index[key] = len(self.items)
            self.items.append({"vertices": _pack(v), "faces": _pack(f)})
        return self._index[key]


def _cell_of(cell_or_compiled: Any, result: Any = None) -> tuple[Any, float]:
    """The Cell and its space-grid block side (metres, 0: off); with no cell
    given, the run's own (``result.compiled`` or ``result.cell``) if it keeps one."""
    if cell_or_compiled is None:
        cell_or_compiled = getattr(result, "compiled", None) or getattr(result, "cell", None)
        if cell_or_compiled is None:
            raise UsageError(
                "this run does not keep its cell: pass the Cell or CompiledCell it was simulated in"
            )
    cell = getattr(cell_or_compiled, "cell", cell_or_compiled)
    if not (hasattr(cell, "arms") and hasattr(cell, "zone_map")):
        raise UsageError(
            f"expected a Cell or a CompiledCell, not {type(cell_or_compiled).__name__}"
        )
    grid: Any = getattr(getattr(cell_or_compiled, "options", None), "grid", None)
    if grid is None:
        grid = getattr(cell, "grid", 0.0)
    return cell, float(grid or 0.0)


_ACTIVITY = frozenset(
    {"fault", "task_start", "task_end", "zone_enter", "zone_leave", "sleep", "wake", "grant"}
)
"""Trace records that happen in the cell and so bound the replay's time range."""


def _duration(result: RunLike, tasks: Sequence[Mapping[str, Any]]) -> float:
    m = result.metrics
    ends = [
        _finite(getattr(m, "executed_makespan", math.nan)),
        *(_finite(t["end"]) for t in tasks),
        *(_finite(t["start"]) for t in tasks),
        *(_finite(t["planned_end"]) for t in tasks if t["status"] != "done"),
    ]
    for e in result.trace:  # what moved or happened in the cell (not when a failure was logged)
        if e.kind == "segment":
            ends.append(_finite(float(e.time) + float(e.delay)))
        elif e.kind in _ACTIVITY:
            ends.append(_finite(e.time))
    known = [e for e in ends if e is not None]
    return max([*known, 1e-3])


def _planned_arms(result: RunLike) -> dict[str, str]:
    """Task -> the arm the given plan put it on (a re-solve may have moved it)."""
    schedule = getattr(result, "schedule", None)
    if schedule is None or not hasattr(schedule, "to_dataframe"):
        return {}
    df = schedule.to_dataframe(result.problem)
    return {str(r["task"]): str(r["arm"]) for r in df.to_dict("records")}


def _tasks(result: RunLike, arm_index: Mapping[str, int]) -> list[dict[str, Any]]:
    df = result.tasks_frame()
    planned_on = _planned_arms(result)
    out = []
    for row in df.to_dict("records"):
        arm = str(row["arm"])
        if arm not in arm_index:
            continue
        task = str(row["task"])
        out.append(
            {
                "task": task,
                "arm": arm_index[arm],
                "planned_arm": arm_index.get(planned_on.get(task, arm), arm_index[arm]),
                "start": _finite(row.get("start")),
                "end": _finite(row.get("end")),
                "planned_start": _finite(row.get("planned_start")),
                "planned_end": _finite(row.get("planned_end")),
                "status": str(row.get("status", "done")),
                "cause": "" if row.get("cause") is None else str(row.get("cause") or ""),
            }
        )
    return out


def _faults(result: RunLike, arm_index: Mapping[str, int]) -> list[dict[str, Any]]:
    events = list(result.trace)
    out = []
    for i, ev in enumerate(events):
        kind = fault_kind(ev)
        if kind is None:
            continue
        end = float(ev.time)
        if kind == "emergency_stop":
            end = next(
                (
                    float(e.time)
                    for e in events[i + 1 :]
                    if e.kind == "fault" and str(e.detail).startswith("emergency stop cleared")
                ),
                end,
            )
        cellwide = kind in ("emergency_stop", "late_part", "zone_activation")
        arm = -1 if cellwide else arm_index.get(str(ev.arm), -1)
        out.append(
            {
                "kind": kind,
                "arm": arm,
                "time": float(ev.time),
                "end": end,
                "detail": str(ev.detail),
            }
        )
    return out


def _zone_states(
    result: RunLike, arm_index: Mapping[str, int], duration: float, failed: Mapping[int, float]
) -> tuple[list[str], list[dict[str, Any]]]:
    """Zone names in order of first use and the intervals of their states
    (an arm never woken waits until it fails for good, ``failed``, or to the end)."""
    names: dict[str, int] = {}
    states: list[dict[str, Any]] = []

    def zone(name: str) -> int:
        return names.setdefault(name, len(names))

    df = result.reservations_frame()
    for row in df.to_dict("records"):
        kind = str(row["kind"])
        if kind == "tool":
            continue
        s, e = _finite(row["start"]), _finite(row["end"])
        arm = str(row["arm"])
        if s is None or arm not in arm_index:
            continue
        states.append(
            {
                "zone": zone(str(row["resource"])),
                "state": "moving" if kind == "move" else "occupied",
                "arm": arm_index[arm],
                "task": row["task"] if isinstance(row["task"], str) else "",
                "start": s,
                "end": duration if e is None else e,
            }
        )
    asleep: dict[tuple[str, str], tuple[float, str]] = {}
    for ev in result.trace:
        key = (str(ev.arm), str(ev.zone))
        if ev.kind == "sleep" and ev.zone and key not in asleep:
            asleep[key] = (float(ev.time), str(ev.task))
        elif ev.kind == "wake" and key in asleep:
            t0, task = asleep.pop(key)
            if ev.arm in arm_index and float(ev.time) > t0:
                states.append(
                    {
                        "zone": zone(str(ev.zone)),
                        "state": "waiting",
                        "arm": arm_index[str(ev.arm)],
                        "task": task,
                        "start": t0,
                        "end": float(ev.time),
                    }
                )
    for (arm, name), (t0, task) in asleep.items():  # never woken
        end = failed.get(arm_index.get(arm, -1), duration)
        if arm in arm_index and end > t0:
            states.append(
                {
                    "zone": zone(name),
                    "state": "waiting",
                    "arm": arm_index[arm],
                    "task": task,
                    "start": t0,
                    "end": end,
                }
            )
    states.sort(key=lambda s: (s["start"], s["zone"]))
    return list(names), states


def _zone_solids(cell: Any, meshes: _Meshes) -> dict[str, tuple[str, list[dict[str, Any]]]]:
    """Policy and solids of every SDL zone, by name."""
    zm = cell.zone_map
    out: dict[str, tuple[str, list[dict[str, Any]]]] = {}
    excl = zm.exclusive_mask()
    for z, name in enumerate(zm.zone_names()):
        solids = []
        for prim in zm.primitives(z):
            tf = np.asarray(prim.transform, dtype=float).reshape(4, 4)
            solid: dict[str, Any] = {"kind": str(prim.kind), "transform": tf.ravel().tolist()}
            if prim.kind in ("box", "cylinder", "sphere"):
                solid["size"] = [float(x) for x in np.atleast_1d(prim.extents)]
            else:
                solid["kind"] = "mesh"
                solid["transform"] = np.eye(4).ravel().tolist()  # vertices are in the cell frame
                solid["mesh"] = meshes.add(prim.vertices, prim.faces)
            solids.append(solid)
        out[str(name)] = ("exclusive" if bool(excl[z]) else "shared", solids)
    return out


def _grid_solid(name: str, grid: float) -> list[dict[str, Any]]:
    from workcell.geometry.reach import block_bounds, grid_block

    if grid <= 0 or grid_block(name) is None:
        return []
    lo, hi = (np.asarray(c, dtype=float) for c in block_bounds(name, grid))
    tf = np.eye(4)
    tf[:3, 3] = (lo + hi) / 2
    return [{"kind": "box", "size": (hi - lo).tolist(), "transform": tf.ravel().tolist()}]


def _arm_bodies(
    arm: Any, q: FloatArray, a: int, geometry: Geometry, meshes: _Meshes
) -> tuple[list[dict[str, Any]], FloatArray, int]:
    """Bodies of one arm, their world poses (N, B, 4, 4) along ``q`` (N, dof),
    and the tip: the (last) body on the deepest kinematic frame."""
    link_meshes = getattr(arm, "meshes", None)
    if geometry == "auto" and link_meshes and hasattr(arm, "mesh_transforms"):
        tfs = np.asarray(arm.mesh_transforms(q), dtype=float)
        bodies = [
            {"arm": a, "name": str(m.name), "kind": "mesh", "mesh": meshes.add(m.vertices, m.faces)}
            for m in link_meshes
        ]
        frames = [int(m.frame) for m in link_meshes]
    else:
        tfs = np.asarray(arm.shape_transforms(q), dtype=float)
        bodies = [
            {"arm": a, "name": str(s.name), "kind": str(s.kind), "size": [float(x) for x in s.size]}
            for s in arm.shapes
        ]
        frames = [int(s.frame) for s in arm.shapes]
    tip = max(range(len(frames)), key=lambda i: (frames[i], i)) if frames else -1
    return bodies, tfs, tip


def _tools(
    result: RunLike, cell: Any, arm_index: Mapping[str, int], duration: float
) -> list[dict[str, Any]]:
    """Each tool of the zone map: its rack and when which arm holds it."""
    racks = {str(t.name): [float(v) for v in t.rack] for t in getattr(cell.zone_map, "tools", ())}
    if not racks:
        return []
    held: dict[str, list[dict[str, Any]]] = {name: [] for name in racks}
    for row in result.reservations_frame().to_dict("records"):
        name, arm = str(row["resource"]), str(row["arm"])
        if str(row["kind"]) != "tool" or name not in racks or arm not in arm_index:
            continue
        s, e = _finite(row["start"]), _finite(row["end"])
        if s is None:
            continue
        end = duration if e is None else min(e, duration)
        if end > s:
            held[name].append({"arm": arm_index[arm], "start": s, "end": end})
    return [
        {
            "name": name,
            "rack": rack,
            "held": sorted(held[name], key=lambda h: (h["start"], h["end"])),
        }
        for name, rack in racks.items()
    ]


def build_replay(
    result: RunLike,
    cell_or_compiled: Any,
    *,
    rate: float = 25.0,
    max_frames: int = 1500,
    geometry: Geometry = "auto",
    title: str | None = None,
) -> ReplayData:
    """The replay of a simulated run (module docstring).

    Parameters
    ----------
    result : workcell.SimResult
        The run (anything with the attributes of :class:`RunLike`).
    cell_or_compiled : Cell or CompiledCell or None
        The cell the run was simulated in (its arms draw the bodies, its
        zone map the zones; a CompiledCell also gives the space-grid block
        side it was compiled with). None: the run's own ``compiled`` or
        ``cell`` attribute, for a run that keeps it.
    rate : float
        Samples per second of the time grid over ``[0, duration]`` (the
        last event of the run, or the planned end of a task that failed) (the page interpolates between
        them), capped by ``max_frames``.
    max_frames : int
        Largest number of samples, >= 2.
    geometry : {"auto", "shapes"}
        ``"auto"``: URDF arms as their collision meshes, others as their
        collision shapes; ``"shapes"``: every arm as its collision shapes
        (the fitted capsules of a URDF arm).
    title : str, optional
        Default: the cell's name and the run's makespans.

    Returns
    -------
    ReplayData

    Raises
    ------
    UsageError
        Bad arguments, no cell, or a run whose arms are not the cell's.
    """
    if not (isinstance(rate, int | float) and math.isfinite(rate) and rate > 0):
        raise UsageError(f"rate must be a number of samples per second > 0, got {rate!r}")
    if isinstance(max_frames, bool) or not isinstance(max_frames, int) or max_frames < 2:
        raise UsageError(f"max_frames must be an integer >= 2, got {max_frames!r}")
    if geometry not in ("auto", "shapes"):
        raise UsageError(f"geometry must be 'auto' or 'shapes', not {geometry!r}")
    cell, grid = _cell_of(cell_or_compiled, result)
    order = tuple(str(a) for a in result.problem.arm_names)
    by_name = {str(a.name): a for a in cell.arms}
    if set(order) != set(by_name):
        raise UsageError(
            f"the run's arms ({', '.join(order)}) are not the cell's "
            f"({', '.join(by_name)}): pass the cell the run was simulated in"
        )
    arm_index = {n: i for i, n in enumerate(order)}
    colours = arm_colours(list(order))

    tasks = _tasks(result, arm_index)
    duration = _duration(result, tasks)
    faults = _faults(result, arm_index)
    for t in tasks:  # a task cut short ends at its arm's first fault after its start
        if t["start"] is not None and t["end"] is None:
            t["end"] = min(
                (f["time"] for f in faults if f["arm"] == t["arm"] and f["time"] >= t["start"]),
                default=duration,
            )
    n = int(min(max_frames, max(2, math.ceil(duration * rate) + 1)))
    times = np.linspace(0.0, duration, n)
    joints = result.joints(times)

    meshes = _Meshes()
    bodies: list[dict[str, Any]] = []
    tf_parts: list[FloatArray] = []
    tips: list[int] = []
    for a, name in enumerate(order):
        arm = by_name[name]
        q = np.asarray(joints[name], dtype=float).reshape(n, -1)
        b, tfs, tip = _arm_bodies(arm, q, a, geometry, meshes)
        tips.append(len(bodies) + tip if tip >= 0 else -1)
        bodies += b
        tf_parts.append(tfs.reshape(n, len(b), 4, 4))
    tf = np.concatenate(tf_parts, axis=1)  # (n, B, 4, 4)
    pos = tf[..., :3, 3]
    quat = _quaternions(tf[..., :3, :3])
    # one hemisphere along time, so that the page interpolates the short way
    flip = np.sign(np.einsum("nbk,nbk->nb", quat[1:], quat[:-1]))
    flip[flip == 0] = 1.0
    sign = np.concatenate([np.ones((1, quat.shape[1])), np.cumprod(flip, axis=0)])
    quat = quat * sign[..., None]

    # the box: the zone map's bounds and every body's path, a little margin
    zlo, zhi = (np.asarray(b, dtype=float) for b in cell.zone_map.bounds)
    lo = np.minimum(zlo, pos.reshape(-1, 3).min(0)) - 0.05
    hi = np.maximum(zhi, pos.reshape(-1, 3).max(0)) + 0.05
    scale = (hi - lo) / 65535.0
    qpos = np.clip(np.rint((pos - lo) / scale) - 32768, -32768, 32767)
    qrot = np.clip(np.rint(quat * 32767.0), -32767, 32767)
    packed = np.concatenate([qpos, qrot], axis=-1).astype("<i2").transpose(1, 2, 0)

    sdl = _zone_solids(cell, meshes)
    failed: dict[int, float] = {}
    for f in faults:
        if f["kind"] == "arm_failure" and f["arm"] >= 0:
            failed.setdefault(f["arm"], f["time"])
    used, states = _zone_states(result, arm_index, duration, failed)
    zones = []
    for name in [*sdl, *(u for u in used if u not in sdl)]:
        policy, solids = sdl.get(name, ("exclusive", _grid_solid(name, grid)))
        zones.append(
            {
                "name": name,
                "policy": policy,
                "grid": name not in sdl,
                "solids": solids,
            }
        )
    zone_index = {z["name"]: i for i, z in enumerate(zones)}
    for s in states:
        s["zone"] = zone_index[used[s["zone"]]]

    m = result.metrics
    summary = {
        "planned_makespan": _finite(getattr(m, "planned_makespan", None)),
        "executed_makespan": _finite(getattr(m, "executed_makespan", None)),
        "done_tasks": int(getattr(m, "done_tasks", 0)),
        "failed_tasks": int(getattr(m, "failed_tasks", 0)),
    }
    if title is None:
        ex = summary["executed_makespan"]
        title = f"{cell.name}: " + (
            f"executed makespan {ex:.2f} s" if ex is not None else "run with failed tasks"
        )
    doc = {
        "format": FORMAT,
        "title": str(title),
        "cell": str(cell.name),
        "duration": float(duration),
        "bounds": [lo.tolist(), hi.tolist()],
        "arms": [
            {"name": a, "colour": _hex(colours[a]), "tip": tips[i]} for i, a in enumerate(order)
        ],
        "bodies": bodies,
        "meshes": meshes.items,
        "frames": {
            "t0": 0.0,
            "dt": float(times[1] - times[0]),
            "n": n,
            "lo": lo.tolist(),
            "scale": scale.tolist(),
            "poses": _pack(packed),
        },
        "zones": zones,
        "zone_states": states,
        "tasks": tasks,
        "faults": faults,
        "tools": _tools(result, cell, arm_index, duration),
        "fault_marks": {
            k: {"symbol": mark.marker, "label": mark.label} for k, mark in FAULT_MARKS.items()
        },
        "states": dict(STATE_COLOURS),
        "summary": summary,
    }
    return ReplayData(doc)
