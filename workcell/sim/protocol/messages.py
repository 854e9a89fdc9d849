"""The records that travel between the coordination and control layers.

A trajectory message (S2.7 *trajectory description + start*) carries
:class:`Leg` records, each with its :class:`Station` list; zone requests,
grants, sleeps, wake-ups and releases carry a :class:`Piece` (one use of a
resource by a task). Both layers import these definitions from here and never
each other (import-linter contracts in ``pyproject.toml``).

Examples
--------
>>> p = Piece("zone", 0, 3, 0.5)
>>> p.kind, p.task
('zone', 3)
>>> p == ("zone", 0, 3, 0.5)  # a typed record that still orders and hashes as a tuple
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from workcell.arms import JointTrajectory

__all__ = [
    "LEG_KINDS",
    "PIECE_KINDS",
    "ActivationGo",
    "ActivationStop",
    "ActiveZones",
    "AlarmClear",
    "AlarmStop",
    "LateNotice",
    "Leg",
    "Mark",
    "Piece",
    "PositionReport",
    "StartPermit",
    "Station",
    "Trajectory",
    "TrajectoryEnd",
    "Withdraw",
]

PIECE_KINDS: tuple[str, ...] = ("zone", "move", "tool")
"""Kinds of resource use: an exclusive zone's occupancy, movement in a
shared (restricted-simultaneous) zone, a tool."""

LEG_KINDS: tuple[str, ...] = ("travel", "task", "retreat", "return", "detour")
"""Kinds of leg: the two sent by the coordinator (travel to a task's first
pose, the task's own trajectory), and the three an arm runs on an
excursion (a back-off to its home joints, the way back, a detour)."""


class Piece(NamedTuple):
    """One use of a resource by a task (frozen; orders and hashes as a tuple).

    Attributes
    ----------
    kind : {"zone", "move", "tool"}
        An exclusive zone's occupancy, movement in a shared zone, a tool.
    resource : int
        The zone's or tool's index in the problem.
    task : int
        The task (``-1 - arm`` for an arm's start zone before its first move).
    tau : float
        Offset in the task where the use starts, seconds.
    """

    kind: str
    resource: int
    task: int
    tau: float


class Mark(NamedTuple):
    """A force-search event on a task leg's clock (S1.7).

    Attributes
    ----------
    tau : float
        Offset in the leg, seconds.
    action : {"raise", "try"}
        Raise the thresholds (start of the search dwell) or end a try.
    search : int
        Index of the search in the leg.
    attempt : int
        The try that ends (1-based; 0 for ``"raise"``).
    """

    tau: float
    action: str
    search: int
    attempt: int


@dataclass(slots=True)
class Station:
    """A point of a leg where something happens.

    Attributes
    ----------
    tau : float
        Offset in the leg, seconds.
    notbefore : float
        The arm may not pass before this absolute time (the plan's time).
    acquire : list of Piece
        Resources needed to pass (granted by the coordinator).
    release : list of Piece
        Resources given back on arrival.
    border : int
        Index of the mode's border here (for the executed waits), -1 if none.
    start : bool
        The task's start (needs the coordinator's permission).
    end : bool
        The leg's end.
    requested : bool
        Requests for ``acquire`` sent.
    """

    tau: float
    notbefore: float = -math.inf
    acquire: list[Piece] = field(default_factory=list)
    release: list[Piece] = field(default_factory=list)
    border: int = -1
    start: bool = False
    end: bool = False
    requested: bool = False


@dataclass(slots=True)
class Leg:
    """A piece of work sent in one trajectory message: travel or task.

    Attributes
    ----------
    kind : str
        One of :data:`LEG_KINDS`.
    task : int
    mode : int (-1 for travel)
    trajectory : JointTrajectory
    stations : list of Station
        Sorted by ``tau``; the last one is the end.
    searches : tuple of InsertSearch
        (:class:`workcell.sim.control.force.InsertSearch`)
        The force-guided searches of a task leg whose insertion tries are
        drawn (:mod:`workcell.sim.control.force`); empty otherwise.
    marks : list of Mark, or None
        The searches' events on the leg's clock (built when the leg starts).
    fired : int
        Marks done.
    """

    kind: str
    task: int
    mode: int
    trajectory: JointTrajectory
    stations: list[Station]
    searches: tuple[Any, ...] = ()
    marks: list[Mark] | None = None
    fired: int = 0

    @property
    def duration(self) -> float:
        """Seconds."""
        return float(self.trajectory.duration)


# ---------------------------------------------------------------- payloads
# The payloads of the coordination frames other than a Piece (zone and tool
# requests, grants, sleeps, wake-ups, releases carry a Piece). ``describe()``
# is the frame's text in the trace; ``frame_task`` the task a coordinator's
# frame is about (the link drops a frame older than its task's withdrawal).


@dataclass(frozen=True, slots=True)
class Trajectory:
    """*Trajectory description + start* (S2.7): the legs of one task (travel,
    then the task) and whether the task may start on arrival."""

    legs: tuple[Leg, ...]
    permit: bool

    @property
    def frame_task(self) -> int:
        """The task."""
        return self.legs[-1].task

    def describe(self) -> str:
        """Trace text (none)."""
        return ""


@dataclass(frozen=True, slots=True)
class StartPermit:
    """Wake-up: ``task`` may start (its predecessors are done, its parts came)."""

    task: int

    @property
    def frame_task(self) -> int:
        """The task."""
        return self.task

    def describe(self) -> str:
        """Trace text."""
        return f"start -1 task {self.task} at 0"


@dataclass(frozen=True, slots=True)
class Withdraw:
    """Sleep: drop the not yet started ``task`` (the plan changed)."""

    task: int
    withdraws = True
    """The link drops any older frame about the task after this one."""

    @property
    def frame_task(self) -> int:
        """The task."""
        return self.task

    def describe(self) -> str:
        """Trace text."""
        return f"withdraw -1 task {self.task} at 0"


@dataclass(frozen=True, slots=True)
class AlarmStop:
    """Alarm: an emergency stop ``stop`` (by id) in force until its release;
    from an arm, ``cause="crash"``: it stopped by reflex (S1.2), told after
    the fact, going on ``recovery`` seconds later."""

    stop: int = 0
    cause: str = "emergency"
    recovery: float = 0.0

    def describe(self) -> str:
        """Trace text."""
        return self.cause


@dataclass(frozen=True, slots=True)
class AlarmClear:
    """Wake-up: the emergency stop ``stop`` is released."""

    stop: int

    def describe(self) -> str:
        """Trace text."""
        return "alarm_clear"


@dataclass(frozen=True, slots=True)
class ActivationStop:
    """Sleep: stop for the zone activation ``stop`` (S2.5) and tell where."""

    stop: int

    def describe(self) -> str:
        """Trace text."""
        return "activation"


@dataclass(frozen=True, slots=True)
class ActivationGo:
    """Wake-up: the zone activation ``stop`` is over."""

    stop: int

    def describe(self) -> str:
        """Trace text."""
        return "activation"


@dataclass(frozen=True, slots=True)
class ActiveZones:
    """Active-zone grant (S2.5): the zones active now."""

    zones: tuple[str, ...]

    def describe(self) -> str:
        """Trace text."""
        return "zones"


@dataclass(frozen=True, slots=True)
class TrajectoryEnd:
    """Trajectory end: ``task``'s trajectory is over (``outcome="done"``),
    it ran but failed with ``cause`` (``"failed"``), or it was withdrawn
    before it started (``"withdrawn"``)."""

    task: int
    outcome: str = "done"
    cause: str = ""

    def describe(self) -> str:
        """Trace text."""
        return f"task {self.task}" if self.outcome == "done" else self.outcome


@dataclass(frozen=True, slots=True)
class PositionReport:
    """Position (S2.7): the arm stopped inside the shared zone of ``piece``
    with its flange at ``xyz``; ``piece=None``: it stands for a zone
    activation."""

    piece: Piece | None
    xyz: tuple[float, float, float]

    def describe(self) -> str:
        """Trace text (none)."""
        return ""


@dataclass(frozen=True, slots=True)
class LateNotice:
    """The feeder's notice that a part is late (a
    :class:`~workcell.sim.harness.faults.LatePart` fault), given to the
    coordination at the part's expected arrival (at the start when that is
    time 0).

    Attributes
    ----------
    tasks : tuple of int
        The tasks the part gates.
    arrival : float
        When it comes, seconds (``inf``: never).
    part : str
        The part's name.
    """

    tasks: tuple[int, ...]
    arrival: float
    part: str

    def describe(self) -> str:
        """Trace text."""
        when = "never comes" if self.arrival == float("inf") else f"comes at {self.arrival:.6g} s"
        return f"part {self.part!r} is late: {when}"
