"""TDL, the trajectory description language (SEEDS.md S2.10).

A TDL text names trajectories as sequences of Cartesian waypoints (position
and orientation) in a reference frame. A trajectory is made of segments, each
either *taught* (points given by hand) or *learned* (points recorded by
leading the arm, optionally labelled with the recording they came from);
the two kinds mix freely. Each point is a *via* point (passed through without
stopping) or a *stop* point (the arm comes to rest there). Speeds are
fractions of the arm's top speed, at trajectory, segment or point level (the
innermost wins). Segments say how to interpolate between their points:
``linear`` (straight line in Cartesian space) or ``axis`` (every axis moves
independently, S1.9). Frames are named poses relative to ``cell`` or to
another frame.

The parsed form, :class:`TDLDocument`, is robot-independent intermediate
code: it knows nothing of arms. :func:`print_tdl` prints a document so that
``parse_tdl(print_tdl(doc)) == doc``. The language reference with examples is
``docs/tdl.md``.

Examples
--------
>>> doc = parse_tdl('''
... frame fixture = (0.5, 0.2, 0.0) rpy(0, 0, 1.5707963267948966)
... trajectory to_fixture {
...     frame fixture
...     speed 0.5
...     taught { via (0, 0, 0.2)  stop (0, 0, 0.05) quat(1, 0, 0, 0) speed 0.1 }
... }
... ''')
>>> doc.trajectory("to_fixture").n_points
2
>>> doc.resolve("to_fixture").positions.round(6).tolist()[1]
[0.5, 0.2, 0.05]
>>> parse_tdl(print_tdl(doc)) == doc
True
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from os import PathLike, fspath
from typing import Any, Literal, TypeVar

import lark
import numpy as np

from multiarm.errors import TDLError, TDLSyntaxError, ValidationError
from multiarm.graph import find_cycle
from multiarm.text import fmt_float, meta_location, parse_text, quote, read_source, unquote
from multiarm.types import FloatArray, Point3, Quaternion, Transform, check_finite
from tasklib.pose import Pose, quat_from_rpy, quat_to_matrix

__all__ = [
    "CELL_FRAME",
    "Frame",
    "ResolvedTrajectory",
    "Segment",
    "TDLDocument",
    "Trajectory",
    "Waypoint",
    "load_tdl",
    "parse_tdl",
    "print_tdl",
]

CELL_FRAME = "cell"
"""Name of the cell frame, the root every frame chain ends in."""

Interpolation = Literal["linear", "axis"]
Source = Literal["taught", "learned"]

_R = TypeVar("_R")

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def check_name(name: object, what: str) -> str:
    """Validate an identifier (letters, digits, underscores; not starting with a digit)."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValidationError(f"{what} {name!r} is not a valid name (letters, digits, '_')")
    return name


def _check_speed(speed: float | None, what: str) -> float | None:
    if speed is None:
        return None
    s = float(speed)
    if not (math.isfinite(s) and 0.0 < s <= 1.0):
        raise ValidationError(f"{what} speed must be a fraction in (0, 1], got {speed!r}")
    if s < 1e-6:
        raise ValidationError(
            f"{what} speed must be at least 1e-06 of the top speed, got {speed!r}"
        )
    return s


@dataclass(frozen=True, slots=True)
class Waypoint:
    """One point of a trajectory.

    Parameters
    ----------
    position : (3,) float, metres
        In the trajectory's frame.
    orientation : (4,) float or None
        Unit quaternion ``(w, x, y, z)``; ``None`` keeps the orientation of
        the previous point (or the arm's current one for the first point).
    stop : bool
        True for a stop point (the arm comes to rest), False for a via point.
    speed : float or None
        Speed fraction for the motion *into* this point; ``None`` inherits
        the segment's.
    """

    position: Point3
    orientation: Quaternion | None = None
    stop: bool = False
    speed: float | None = None
    line: int | None = field(default=None, compare=False, repr=False)
    column: int | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        pose = Pose(self.position, self.orientation or (1.0, 0.0, 0.0, 0.0))
        object.__setattr__(self, "position", pose.position)
        if self.orientation is not None:
            object.__setattr__(self, "orientation", pose.orientation)
        object.__setattr__(self, "stop", bool(self.stop))
        object.__setattr__(self, "speed", _check_speed(self.speed, "waypoint"))


@dataclass(frozen=True, slots=True)
class Segment:
    """A run of waypoints of one origin (taught or learned).

    Parameters
    ----------
    points : tuple of Waypoint
        At least one.
    source : {"taught", "learned"}
    label : str or None
        Free text, e.g. the recording a learned segment came from.
    interpolation : {"linear", "axis"}
        Straight-line Cartesian interpolation, or independent per-axis moves
        (S1.9).
    speed : float or None
        Speed fraction in (0, 1]; ``None`` inherits the trajectory's.
    """

    points: tuple[Waypoint, ...]
    source: Source = "taught"
    label: str | None = None
    interpolation: Interpolation = "linear"
    speed: float | None = None
    line: int | None = field(default=None, compare=False, repr=False)
    column: int | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", tuple(self.points))
        if not self.points:
            raise ValidationError("a trajectory segment needs at least one point")
        for p in self.points:
            if not isinstance(p, Waypoint):
                raise ValidationError(f"segment points must be Waypoint, got {type(p).__name__}")
        if self.source not in ("taught", "learned"):
            raise ValidationError(
                f"segment source must be 'taught' or 'learned', not {self.source!r}"
            )
        if self.interpolation not in ("linear", "axis"):
            raise ValidationError(
                f"segment interpolation must be 'linear' or 'axis', not {self.interpolation!r}"
            )
        if self.label is not None and not isinstance(self.label, str):
            raise ValidationError(f"segment label must be text, got {self.label!r}")
        object.__setattr__(self, "speed", _check_speed(self.speed, "segment"))


@dataclass(frozen=True, slots=True)
class Trajectory:
    """A named trajectory: segments of waypoints in one reference frame.

    Parameters
    ----------
    name : str
    segments : tuple of Segment
        At least one.
    frame : str
        Reference frame of every point (``"cell"`` by default).
    speed : float
        Default speed fraction in (0, 1].
    """

    name: str
    segments: tuple[Segment, ...]
    frame: str = CELL_FRAME
    speed: float = 1.0
    line: int | None = field(default=None, compare=False, repr=False)
    column: int | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        check_name(self.name, "trajectory")
        check_name(self.frame, f"frame of trajectory {self.name!r}:")
        object.__setattr__(self, "segments", tuple(self.segments))
        if not self.segments:
            raise ValidationError(f"trajectory {self.name!r} has no segment")
        speed = _check_speed(self.speed, f"trajectory {self.name!r}")
        object.__setattr__(self, "speed", speed)

    @property
    def n_points(self) -> int:
        """Number of waypoints over all segments."""
        return sum(len(s.points) for s in self.segments)

    def waypoints(self) -> Iterator[tuple[Segment, Waypoint]]:
        """Every (segment, waypoint) pair in order."""
        for seg in self.segments:
            for p in seg.points:
                yield seg, p


@dataclass(frozen=True, slots=True)
class Frame:
    """A named reference frame: a pose relative to its parent frame."""

    name: str
    position: Point3
    orientation: Quaternion = (1.0, 0.0, 0.0, 0.0)
    parent: str = CELL_FRAME
    line: int | None = field(default=None, compare=False, repr=False)
    column: int | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        check_name(self.name, "frame")
        if self.name == CELL_FRAME:
            raise ValidationError(f"frame name {CELL_FRAME!r} is reserved for the cell frame")
        check_name(self.parent, f"parent of frame {self.name!r}:")
        pose = Pose(self.position, self.orientation)
        object.__setattr__(self, "position", pose.position)
        object.__setattr__(self, "orientation", pose.orientation)

    def matrix(self) -> Transform:
        """(4, 4) transform from this frame to its parent."""
        return Pose(self.position, self.orientation).matrix()


@dataclass(frozen=True, slots=True)
class ResolvedTrajectory:
    """A trajectory expressed in the cell frame, as arrays.

    Attributes
    ----------
    name : str
    positions : (N, 3) float, metres, cell frame
    orientations : (N, 4) float
        Unit quaternions ``(w, x, y, z)``; points without an orientation take
        the previous one, and leading ones the frame's.
    stop : (N,) bool
        Stop point (True) or via point (False).
    speed : (N,) float
        Effective speed fraction into each point.
    linear : (N,) bool
        True when the motion into the point is interpolated in a straight
        line, False for independent per-axis motion.
    """

    name: str
    positions: FloatArray
    orientations: FloatArray
    stop: np.ndarray[Any, np.dtype[np.bool_]]
    speed: FloatArray
    linear: np.ndarray[Any, np.dtype[np.bool_]]


def _rotation_to_quat(r: FloatArray) -> Quaternion:
    tr = float(np.trace(r))
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2]) * 2
        q = ((r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s)
    elif r[1, 1] > r[2, 2]:
        s = math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2]) * 2
        q = ((r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s)
    else:
        s = math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1]) * 2
        q = ((r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s)
    return (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


@dataclass(frozen=True, slots=True)
class TDLDocument:
    """A set of frames and trajectories (what one or more TDL texts define).

    Construction checks the cross-references: unique names, known frames,
    no cycle among frame parents.

    Parameters
    ----------
    frames : tuple of Frame
    trajectories : tuple of Trajectory
    filename : str or None
        Where the text came from (used in error messages; not compared).
    """

    frames: tuple[Frame, ...] = ()
    trajectories: tuple[Trajectory, ...] = ()
    filename: str | None = field(default=None, compare=False, repr=False)
    _by_name: dict[str, Trajectory] = field(
        default_factory=dict, init=False, compare=False, repr=False
    )
    _frames: dict[str, Frame] = field(default_factory=dict, init=False, compare=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "frames", tuple(self.frames))
        object.__setattr__(self, "trajectories", tuple(self.trajectories))
        for f in self.frames:
            if f.name in self._frames:
                self._fail(f"frame {f.name!r} is defined twice", f)
            self._frames[f.name] = f
        for f in self.frames:
            if f.parent != CELL_FRAME and f.parent not in self._frames:
                self._fail(f"frame {f.name!r} is relative to unknown frame {f.parent!r}", f)
        graph = {f.name: [f.parent] if f.parent != CELL_FRAME else [] for f in self.frames}
        cycle = find_cycle(graph)
        if cycle is not None:
            self._fail(
                "frames are defined relative to each other in a cycle: " + " -> ".join(cycle),
                self._frames[cycle[0]],
            )
        for t in self.trajectories:
            if t.name in self._by_name:
                self._fail(f"trajectory {t.name!r} is defined twice", t)
            if t.frame != CELL_FRAME and t.frame not in self._frames:
                self._fail(f"trajectory {t.name!r} uses unknown frame {t.frame!r}", t)
            self._by_name[t.name] = t

    def _fail(self, message: str, where: Frame | Trajectory) -> None:
        raise TDLError(message, filename=self.filename, line=where.line, column=where.column)

    # -- lookup ---------------------------------------------------------------
    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __len__(self) -> int:
        return len(self.trajectories)

    def names(self) -> tuple[str, ...]:
        """Trajectory names in definition order."""
        return tuple(t.name for t in self.trajectories)

    def trajectory(self, name: str) -> Trajectory:
        """The trajectory called ``name``.

        Raises
        ------
        ValidationError
            When there is none.
        """
        try:
            return self._by_name[name]
        except KeyError:
            raise ValidationError(f"unknown trajectory {name!r}") from None

    def frame(self, name: str) -> Frame:
        """The frame called ``name`` (not ``"cell"``)."""
        try:
            return self._frames[name]
        except KeyError:
            raise ValidationError(f"unknown frame {name!r}") from None

    def frame_matrix(self, name: str) -> Transform:
        """(4, 4) transform from frame ``name`` to the cell frame."""
        t = np.eye(4)
        while name != CELL_FRAME:
            f = self.frame(name)
            t = f.matrix() @ t
            name = f.parent
        return t

    def merge(self, other: TDLDocument) -> TDLDocument:
        """A document with the frames and trajectories of both (names must not clash)."""
        return TDLDocument(
            self.frames + other.frames,
            self.trajectories + other.trajectories,
            filename=self.filename or other.filename,
        )

    def resolve(self, name: str) -> ResolvedTrajectory:
        """The trajectory ``name`` in the cell frame, as arrays."""
        traj = self.trajectory(name)
        tf = self.frame_matrix(traj.frame)
        rot = tf[:3, :3]
        frame_q = _rotation_to_quat(rot)
        n = traj.n_points
        pos = np.empty((n, 3))
        quat = np.empty((n, 4))
        stop = np.empty(n, dtype=bool)
        speed = np.empty(n)
        linear = np.empty(n, dtype=bool)
        current: Quaternion = frame_q
        for i, (seg, p) in enumerate(traj.waypoints()):
            pos[i] = rot @ np.asarray(p.position) + tf[:3, 3]
            if p.orientation is not None:
                current = _rotation_to_quat(rot @ quat_to_matrix(p.orientation))
            quat[i] = current
            stop[i] = p.stop
            speed[i] = p.speed or seg.speed or traj.speed
            linear[i] = seg.interpolation == "linear"
        return ResolvedTrajectory(name, pos, quat, stop, speed, linear)


# ------------------------------------------------------------------ parsing


@cache
def _parser() -> lark.Lark:
    grammar = resources.files("tasklib").joinpath("tdl.lark").read_text(encoding="utf-8")
    return lark.Lark(grammar, parser="lalr", propagate_positions=True, maybe_placeholders=True)


class _Build(lark.Transformer[lark.Token, TDLDocument]):
    def __init__(self, filename: str | None) -> None:
        super().__init__()
        self.filename = filename

    def _guard(self, meta: Any, make: Callable[[], _R]) -> _R:
        try:
            return make()
        except ValidationError as exc:
            line, column = meta_location(meta)
            raise TDLError(str(exc), filename=self.filename, line=line, column=column) from None

    def number(self, items: list[lark.Token]) -> float:
        return float(items[0])

    def position(self, items: list[float]) -> Point3:
        return (items[0], items[1], items[2])

    def quat(self, items: list[float]) -> Quaternion:
        return (items[0], items[1], items[2], items[3])

    def rpy(self, items: list[float]) -> Quaternion:
        if not check_finite(items):
            raise TDLError(f"rpy angles must be finite, got {tuple(items)}", filename=self.filename)
        return quat_from_rpy(items[0], items[1], items[2])

    def point_speed(self, items: list[float]) -> float:
        return items[0]

    @lark.v_args(meta=True)
    def point(self, meta: Any, items: list[Any]) -> Waypoint:
        kind, position, orientation, speed = items
        line, column = meta_location(meta)
        return self._guard(
            meta,
            lambda: Waypoint(
                position, orientation, kind == "stop", speed, line=line, column=column
            ),
        )

    def seg_interp(self, items: list[lark.Token]) -> tuple[str, str]:
        return ("interpolation", str(items[0]))

    def seg_speed(self, items: list[float]) -> tuple[str, float]:
        return ("speed", items[0])

    @lark.v_args(meta=True)
    def segment(self, meta: Any, items: list[Any]) -> Segment:
        source = str(items[0])
        label = unquote(items[1]) if items[1] is not None else None
        opts: dict[str, Any] = {}
        points: list[Waypoint] = []
        for it in items[2:]:
            if isinstance(it, Waypoint):
                points.append(it)
            else:
                key, value = it
                if key in opts:
                    line, column = meta_location(meta)
                    raise TDLError(
                        f"segment option {key!r} is given twice",
                        filename=self.filename,
                        line=line,
                        column=column,
                    )
                opts[key] = value
        line, column = meta_location(meta)
        return self._guard(
            meta,
            lambda: Segment(tuple(points), source, label, line=line, column=column, **opts),  # type: ignore[arg-type]
        )

    def traj_frame(self, items: list[lark.Token]) -> tuple[str, str]:
        return ("frame", str(items[0]))

    def traj_speed(self, items: list[float]) -> tuple[str, float]:
        return ("speed", items[0])

    @lark.v_args(meta=True)
    def trajectory(self, meta: Any, items: list[Any]) -> Trajectory:
        name = str(items[0])
        opts: dict[str, Any] = {}
        segments: list[Segment] = []
        line, column = meta_location(meta)
        for it in items[1:]:
            if isinstance(it, Segment):
                segments.append(it)
            else:
                key, value = it
                if key in opts:
                    raise TDLError(
                        f"trajectory {name!r} sets {key!r} twice",
                        filename=self.filename,
                        line=line,
                        column=column,
                    )
                opts[key] = value
        return self._guard(
            meta,
            lambda: Trajectory(name, tuple(segments), line=line, column=column, **opts),
        )

    def frame_parent(self, items: list[lark.Token]) -> str:
        return str(items[0])

    @lark.v_args(meta=True)
    def frame_def(self, meta: Any, items: list[Any]) -> Frame:
        name, parent, position, orientation = items
        line, column = meta_location(meta)
        return self._guard(
            meta,
            lambda: Frame(
                str(name),
                position,
                orientation if orientation is not None else (1.0, 0.0, 0.0, 0.0),
                parent if parent is not None else CELL_FRAME,
                line=line,
                column=column,
            ),
        )

    def start(self, items: list[Any]) -> TDLDocument:
        frames = tuple(i for i in items if isinstance(i, Frame))
        trajs = tuple(i for i in items if isinstance(i, Trajectory))
        return TDLDocument(frames, trajs, filename=self.filename)


def parse_tdl(text: str, filename: str | None = None) -> TDLDocument:
    """Parse a TDL text.

    Parameters
    ----------
    text : str
        The TDL source.
    filename : str, optional
        Shown in error messages (``file:line:col``).

    Returns
    -------
    TDLDocument

    Raises
    ------
    TDLSyntaxError
        When the text does not follow the grammar; carries ``filename``,
        ``line``, ``column`` and the ``expected`` tokens.
    TDLError
        When the text is grammatical but wrong (unknown frame, duplicate
        name, speed outside (0, 1], non-unit quaternion, non-finite number),
        located at the element concerned.

    Examples
    --------
    >>> parse_tdl("trajectory t { taught { stop (0, 0, 1) } }").names()
    ('t',)
    >>> parse_tdl("trajectory t { taught { stop (0, 0) } }", "a.tdl")
    Traceback (most recent call last):
    ...
    multiarm.errors.TDLSyntaxError: a.tdl:1:35: unexpected ')' (expected ',')
    """
    doc = parse_text(_parser(), text, filename, TDLSyntaxError, _Build(filename))
    assert isinstance(doc, TDLDocument)
    return doc


def load_tdl(path: str | PathLike[str]) -> TDLDocument:
    """Read and parse a ``.tdl`` file (errors name the file)."""
    text = read_source(path, TDLError, "TDL")
    return parse_tdl(text, filename=fspath(path))


# ----------------------------------------------------------------- printing


def _vec(values: Iterable[float]) -> str:
    return "(" + ", ".join(fmt_float(v) for v in values) + ")"


def print_tdl(doc: TDLDocument) -> str:
    """TDL text for ``doc``; ``parse_tdl(print_tdl(doc)) == doc``."""
    out: list[str] = []
    for f in doc.frames:
        parent = f" in {f.parent}" if f.parent != CELL_FRAME else ""
        out.append(f"frame {f.name}{parent} = {_vec(f.position)} quat{_vec(f.orientation)}")
    if doc.frames and doc.trajectories:
        out.append("")
    for t in doc.trajectories:
        out.append(f"trajectory {t.name} {{")
        if t.frame != CELL_FRAME:
            out.append(f"    frame {t.frame}")
        if t.speed != 1.0:
            out.append(f"    speed {fmt_float(t.speed)}")
        for seg in t.segments:
            head: str = seg.source
            if seg.label is not None:
                head += " " + quote(seg.label)
            if seg.interpolation != "linear":
                head += f" interp {seg.interpolation}"
            if seg.speed is not None:
                head += f" speed {fmt_float(seg.speed)}"
            out.append(f"    {head} {{")
            for p in seg.points:
                line = f"        {'stop' if p.stop else 'via'} {_vec(p.position)}"
                if p.orientation is not None:
                    line += f" quat{_vec(p.orientation)}"
                if p.speed is not None:
                    line += f" speed {fmt_float(p.speed)}"
                out.append(line)
            out.append("    }")
        out.append("}")
    return "\n".join(out) + "\n"
