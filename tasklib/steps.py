"""Step primitives: what one arm does, in order, inside an elementary task.

Every step is an immutable record with a ``kind`` (its name in files) and
enough data for ``workcell`` to time and simulate it later. Durations are
seconds, distances metres, forces newtons, speeds fractions of the arm's top
speed in (0, 1].

=============  =============================================================
kind           meaning
=============  =============================================================
``move``       to a pose, or along a named TDL trajectory; interpolated in
               a straight line or per axis (S1.9)
``approach``   to a pose along its tool axis, from ``distance`` above it
``depart``     back along the tool axis by ``distance``
``grasp``      close the gripper (on a part); ``duration`` is its time
``release``    open the gripper
``insert``     push a part into a hole under force control, with a search at
               offsets and raised force thresholds when the hole is missed
               (S1.7)
``use_tool``   operate a tool (screwdriver, press, ...) for ``duration``
``actuate``    command a non-robot device (conveyor, clamp, lamp)
``detect``     scan with the finger object detector along a line, to search
               for parts or measure them (S1.8)
``set_flag``   raise a synchronisation flag (S1.9)
``wait_flag``  wait until a flag is raised (S1.9)
``dwell``      wait a fixed time
=============  =============================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar, Literal, TypeAlias

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray
from tasklib.pose import Pose

__all__ = [
    "STEP_KINDS",
    "Actuate",
    "Approach",
    "Depart",
    "Detect",
    "Dwell",
    "ForceSearch",
    "Grasp",
    "Insert",
    "Move",
    "Release",
    "SetFlag",
    "Step",
    "UseTool",
    "WaitFlag",
]


LARGEST = 1e6
"""Largest duration (s), distance (m), force (N) or count a step accepts."""
MAX_TRIES = 100_000
"""Most insertion tries of one force search (each is an offset the search visits)."""
SMALLEST_FRACTION = 1e-6
"""Smallest speed fraction: slower moves would last beyond any plan."""


def _positive(value: float, what: str, *, allow_zero: bool = False) -> float:
    v = float(value)
    ok = math.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise ValidationError(f"{what} must be finite and {bound}, got {value!r}")
    if v > LARGEST:
        raise ValidationError(f"{what} must be at most {LARGEST:g}, got {value!r}")
    return v


def _fraction(value: float, what: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and 0.0 < v <= 1.0):
        raise ValidationError(f"{what} must be a fraction in (0, 1], got {value!r}")
    if v < SMALLEST_FRACTION:
        raise ValidationError(
            f"{what} must be at least {SMALLEST_FRACTION:g} of the top speed, got {value!r}"
        )
    return v


def _name(value: object, what: str) -> str:
    if not isinstance(value, str) or not value:
        raise ValidationError(f"{what} must be a non-empty name, got {value!r}")
    return value


def _pose(value: object, what: str) -> Pose:
    if isinstance(value, Pose):
        return value
    raise ValidationError(f"{what} must be a Pose, got {type(value).__name__}")


@dataclass(frozen=True, slots=True)
class _StepBase:
    kind: ClassVar[str] = ""
    capabilities: ClassVar[tuple[str, ...]] = ()
    """Arm capabilities a step of this kind needs (see ``Task.required_capabilities``)."""


@dataclass(frozen=True, slots=True)
class Move(_StepBase):
    """Move to ``target``, or along the TDL trajectory named ``trajectory``.

    Exactly one of the two is given. ``interpolation`` is ``"linear"``
    (straight line in Cartesian space) or ``"axis"`` (each axis moves on its
    own, the cheap move of a Cartesian robot, S1.9); a trajectory's own
    segments override it.
    """

    kind: ClassVar[str] = "move"
    target: Pose | None = None
    trajectory: str | None = None
    interpolation: Literal["linear", "axis"] = "axis"
    speed: float = 1.0

    def __post_init__(self) -> None:
        if (self.target is None) == (self.trajectory is None):
            raise ValidationError("a move step needs exactly one of 'target' and 'trajectory'")
        if self.target is not None:
            _pose(self.target, "move target")
        if self.trajectory is not None:
            _name(self.trajectory, "move trajectory")
        if self.interpolation not in ("linear", "axis"):
            raise ValidationError(
                f"move interpolation must be 'linear' or 'axis', not {self.interpolation!r}"
            )
        object.__setattr__(self, "speed", _fraction(self.speed, "move speed"))


@dataclass(frozen=True, slots=True)
class Approach(_StepBase):
    """Come down onto ``target`` along its tool axis from ``distance`` away."""

    kind: ClassVar[str] = "approach"
    target: Pose
    distance: float = 0.05
    speed: float = 0.25

    def __post_init__(self) -> None:
        _pose(self.target, "approach target")
        object.__setattr__(self, "distance", _positive(self.distance, "approach distance"))
        object.__setattr__(self, "speed", _fraction(self.speed, "approach speed"))


@dataclass(frozen=True, slots=True)
class Depart(_StepBase):
    """Back off along the tool axis by ``distance``."""

    kind: ClassVar[str] = "depart"
    distance: float = 0.05
    speed: float = 0.5

    def __post_init__(self) -> None:
        object.__setattr__(self, "distance", _positive(self.distance, "depart distance"))
        object.__setattr__(self, "speed", _fraction(self.speed, "depart speed"))


@dataclass(frozen=True, slots=True)
class Grasp(_StepBase):
    """Close the gripper, on ``part`` when given; takes ``duration`` seconds."""

    kind: ClassVar[str] = "grasp"
    capabilities: ClassVar[tuple[str, ...]] = ("gripper",)
    part: str | None = None
    duration: float = 0.3

    def __post_init__(self) -> None:
        if self.part is not None:
            _name(self.part, "grasp part")
        object.__setattr__(
            self, "duration", _positive(self.duration, "grasp duration", allow_zero=True)
        )


@dataclass(frozen=True, slots=True)
class Release(_StepBase):
    """Open the gripper, letting go of ``part`` when given."""

    kind: ClassVar[str] = "release"
    capabilities: ClassVar[tuple[str, ...]] = ("gripper",)
    part: str | None = None
    duration: float = 0.2

    def __post_init__(self) -> None:
        if self.part is not None:
            _name(self.part, "release part")
        object.__setattr__(
            self, "duration", _positive(self.duration, "release duration", allow_zero=True)
        )


@dataclass(frozen=True, slots=True)
class ForceSearch:
    """How an insertion searches for a hole whose position is not well known (S1.7).

    The arm raises its force thresholds to ``threshold`` (the free-motion
    thresholds are low, to detect a crash), pushes, and reads a force above
    the threshold as "not in the hole"; it then tries again at the next
    offset, up to ``max_tries`` tries, and restores the thresholds after.

    Parameters
    ----------
    max_tries : int
        Tries in all, the nominal position included (>= 1).
    step : float, metres
        Distance between neighbouring offsets.
    pattern : {"spiral", "grid"}
        Order of the offsets: an outward square spiral, or a raster.
    threshold : float, newtons
        Raised force threshold used while pushing.
    try_time : float, seconds
        Time of one push and retract.
    """

    max_tries: int = 9
    step: float = 0.0005
    pattern: Literal["spiral", "grid"] = "spiral"
    threshold: float = 20.0
    try_time: float = 0.4

    def __post_init__(self) -> None:
        if isinstance(self.max_tries, bool) or not isinstance(self.max_tries, int | np.integer):
            raise ValidationError(f"force search max_tries must be an int, got {self.max_tries!r}")
        if not 1 <= self.max_tries <= MAX_TRIES:
            raise ValidationError(
                f"force search needs max_tries in [1, {MAX_TRIES}], got {self.max_tries}"
            )
        object.__setattr__(self, "max_tries", int(self.max_tries))
        object.__setattr__(self, "step", _positive(self.step, "force search step"))
        if self.pattern not in ("spiral", "grid"):
            raise ValidationError(
                f"force search pattern must be 'spiral' or 'grid', not {self.pattern!r}"
            )
        object.__setattr__(self, "threshold", _positive(self.threshold, "force search threshold"))
        object.__setattr__(self, "try_time", _positive(self.try_time, "force search try_time"))

    def offsets(self) -> FloatArray:
        """(max_tries, 2) float, metres: the xy offsets tried, nominal first.

        Examples
        --------
        >>> ForceSearch(max_tries=5, step=1.0).offsets().tolist()
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [-1.0, 1.0]]
        """
        n = self.max_tries
        if self.pattern == "grid":
            side = math.ceil(math.sqrt(n))
            half = (side - 1) / 2
            cells = [(i - half, j - half) for j in range(side) for i in range(side)]
            cells.sort(key=lambda c: (c[0] ** 2 + c[1] ** 2, c[1], c[0]))
            return np.array(cells[:n], dtype=float) * self.step
        out = [(0, 0)]
        x = y = 0
        dx, dy = 1, 0
        run = 1
        while len(out) < n:
            for _ in range(2):
                for _ in range(run):
                    x, y = x + dx, y + dy
                    out.append((x, y))
                    if len(out) == n:
                        break
                dx, dy = -dy, dx
                if len(out) == n:
                    break
            run += 1
        return np.array(out, dtype=float) * self.step


@dataclass(frozen=True, slots=True)
class Insert(_StepBase):
    """Insert ``part`` at ``target`` by ``depth`` under force control (S1.7)."""

    kind: ClassVar[str] = "insert"
    capabilities: ClassVar[tuple[str, ...]] = ("force_sensor",)
    part: str
    target: Pose
    depth: float = 0.01
    speed: float = 0.05
    search: ForceSearch = field(default_factory=ForceSearch)

    def __post_init__(self) -> None:
        _name(self.part, "insert part")
        _pose(self.target, "insert target")
        object.__setattr__(self, "depth", _positive(self.depth, "insert depth"))
        object.__setattr__(self, "speed", _fraction(self.speed, "insert speed"))
        if not isinstance(self.search, ForceSearch):
            raise ValidationError(f"insert search must be a ForceSearch, got {self.search!r}")


@dataclass(frozen=True, slots=True)
class UseTool(_StepBase):
    """Operate ``tool`` for ``duration`` seconds (the task must declare the tool)."""

    kind: ClassVar[str] = "use_tool"
    capabilities: ClassVar[tuple[str, ...]] = ("tool_changer",)
    tool: str
    duration: float

    def __post_init__(self) -> None:
        _name(self.tool, "use_tool tool")
        object.__setattr__(self, "duration", _positive(self.duration, "use_tool duration"))


@dataclass(frozen=True, slots=True)
class Actuate(_StepBase):
    """Send ``command`` to a non-robot ``device``; wait ``duration`` for it."""

    kind: ClassVar[str] = "actuate"
    device: str
    command: str = "on"
    duration: float = 0.0

    def __post_init__(self) -> None:
        _name(self.device, "actuate device")
        _name(self.command, "actuate command")
        object.__setattr__(
            self, "duration", _positive(self.duration, "actuate duration", allow_zero=True)
        )


@dataclass(frozen=True, slots=True)
class Detect(_StepBase):
    """Scan with the finger object detector from ``start`` to ``end`` (S1.8).

    ``mode="search"`` looks for parts along the line (finding parts not
    exactly fed); ``mode="measure"`` also measures their size (the chess-piece
    demo measured heights and sorted the pieces). ``part`` names what is
    looked for, when known.
    """

    kind: ClassVar[str] = "detect"
    capabilities: ClassVar[tuple[str, ...]] = ("object_detector",)
    start: Pose
    end: Pose
    mode: Literal["search", "measure"] = "search"
    speed: float = 0.2
    part: str | None = None

    def __post_init__(self) -> None:
        _pose(self.start, "detect start")
        _pose(self.end, "detect end")
        if self.mode not in ("search", "measure"):
            raise ValidationError(f"detect mode must be 'search' or 'measure', not {self.mode!r}")
        object.__setattr__(self, "speed", _fraction(self.speed, "detect speed"))
        if self.part is not None:
            _name(self.part, "detect part")

    @property
    def length(self) -> float:
        """Scan length, metres."""
        return float(np.linalg.norm(np.subtract(self.end.position, self.start.position)))


@dataclass(frozen=True, slots=True)
class SetFlag(_StepBase):
    """Raise ``flag`` (S1.9 synchronisation between task boxes)."""

    kind: ClassVar[str] = "set_flag"
    flag: str

    def __post_init__(self) -> None:
        _name(self.flag, "set_flag flag")


@dataclass(frozen=True, slots=True)
class WaitFlag(_StepBase):
    """Wait until ``flag`` is raised; ``timeout`` seconds, or forever when None."""

    kind: ClassVar[str] = "wait_flag"
    flag: str
    timeout: float | None = None

    def __post_init__(self) -> None:
        _name(self.flag, "wait_flag flag")
        if self.timeout is not None:
            object.__setattr__(self, "timeout", _positive(self.timeout, "wait_flag timeout"))


@dataclass(frozen=True, slots=True)
class Dwell(_StepBase):
    """Stay still for ``duration`` seconds."""

    kind: ClassVar[str] = "dwell"
    duration: float

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "duration", _positive(self.duration, "dwell duration", allow_zero=True)
        )


Step: TypeAlias = (
    Move
    | Approach
    | Depart
    | Grasp
    | Release
    | Insert
    | UseTool
    | Actuate
    | Detect
    | SetFlag
    | WaitFlag
    | Dwell
)
"""Any step primitive."""

STEP_KINDS: dict[str, type[_StepBase]] = {
    cls.kind: cls
    for cls in (
        Move,
        Approach,
        Depart,
        Grasp,
        Release,
        Insert,
        UseTool,
        Actuate,
        Detect,
        SetFlag,
        WaitFlag,
        Dwell,
    )
}
"""Step classes by their ``kind``."""
