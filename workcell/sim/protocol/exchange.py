"""The S2.12 exchange between an arm and its coordination: reports, the
departure question and its answer, and the excursion orders.

Zone requests, grants, sleeps, wake-ups, releases, trajectories and alarms
travel through the medium (:mod:`workcell.sim.comms.link`). The geometric
check of S2.12 is the other exchange, and it is made of messages too:

* **Reports** (arm -> coordination). :class:`MotionReport` carries the
  arm's :class:`ArmView` whenever its motion or its standing changes (S2.7:
  the coordinator knows the trajectories it sent, where each arm stands,
  and when a trajectory ends); :class:`TaskStarted` and :class:`TaskEnded`
  say when a task's start station was left and its trajectory ended.
* **The question** (arm -> coordination). Before an arm sets off towards
  its next station it sends a :class:`DepartureRequest` with its view.
* **The answers and orders** (coordination -> arm). :class:`Departure`
  answers *continue* (``go=True``) or *stop* (``go=False``); :class:`Detour`
  is S2.12's *continue with alternative trajectory*; :class:`ReleaseHold`
  ends a *stop*; :class:`BackOff` and :class:`ComeBack` take an arm out of
  a mover's way and back (S2.6); :class:`Fail` is the arm's failure.

The coordination decides from its own book of the arms (the last
:class:`ArmView` each reported), never from a controller. Every record is
frozen. The :class:`ControlChannel` numbers the records of each direction of
each arm (0, 1, 2, ...) and the receiver drops one not newer than the last
it took.

**Delay.** The channel delivers at the instant of sending, free of delay and
loss: S2.12's check is modelled as answered at once. The check is only
sound on a current book: a motion cleared against a report one medium
delay old could run into an arm that stopped in the meantime (a crash, an
alarm) or set off since, so on a delayed medium the honest check would
have to reserve each motion's whole swept volume regardless of time, which
is a different (far more conservative) check than S2.12's. The numbers of
frames and bytes on the medium (:class:`~workcell.sim.comms.link.Link`) do
not count these records; :attr:`ControlChannel.sent` does.

Examples
--------
>>> ch = ControlChannel(2)
>>> got = []
>>> ch.attach_coordination(lambda arm, rec: got.append((arm, type(rec).__name__)))
>>> ch.attach_arm(1, lambda rec: got.append(("arm 1", type(rec).__name__)))
>>> ch.report(1, TaskStarted(3, 0.5))
>>> ch.order(1, ReleaseHold())
>>> got, ch.sent
([(1, 'TaskStarted'), ('arm 1', 'ReleaseHold')], 2)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from multiarm.errors import InternalError
from multiarm.types import FloatArray
from workcell.arms import JointTrajectory
from workcell.sim.protocol.messages import Leg

__all__ = [
    "ORDERS",
    "REPORTS",
    "ArmView",
    "BackOff",
    "BackOffUntil",
    "ComeBack",
    "ControlChannel",
    "Departure",
    "DepartureRequest",
    "Detour",
    "Excursion",
    "Fail",
    "MotionReport",
    "Order",
    "ReleaseHold",
    "Report",
    "TaskEnded",
    "TaskStarted",
]


@dataclass(frozen=True, slots=True, eq=False)
class ArmView:
    """An arm's motion and standing as it reported them (frozen).

    Attributes
    ----------
    index : int
        The arm.
    leg : Leg or None
        The leg it follows (``None``: standing idle at ``q``).
    k : int
        Its next station on the leg.
    tau : float
        Progress in the leg at ``t_ref``, seconds.
    t_ref : float
        When it was at ``tau``, seconds.
    running : bool
        The leg's clock runs.
    q : (dof,) float
        The standing joints when idle (never written after it is reported).
    at_station : bool
        Stopped at station ``k``, waiting for its conditions.
    held : bool
        Held by the geometric check (S2.12 *stop*).
    waiting : bool
        Standing and waiting on something other than the clock (a grant, a
        start permission, the geometric check).
    away : bool
        On an excursion from its leg (a back-off or a detour).
    pushing : bool
        In the middle of a force-guided search (S1.7): it cannot back off.
    failed : bool
    """

    index: int
    leg: Leg | None
    k: int
    tau: float
    t_ref: float
    running: bool
    q: FloatArray
    at_station: bool = False
    held: bool = False
    waiting: bool = False
    away: bool = False
    pushing: bool = False
    failed: bool = False

    def current_tau(self, now: float) -> float:
        """Progress in the leg at ``now`` (0 without a leg)."""
        leg = self.leg
        if leg is None:
            return 0.0
        if self.running:
            return min(leg.duration, self.tau + (now - self.t_ref))
        return self.tau

    def position(self, now: float) -> FloatArray:
        """Commanded joints at ``now``."""
        leg = self.leg
        if leg is None:
            return self.q
        out: FloatArray = leg.trajectory.sample(np.array([self.current_tau(now)]))[0]
        return out

    def predict(self, times: FloatArray, now: float) -> FloatArray:
        """(N, dof) commanded joints at ``times`` (>= ``now``) if the arm
        keeps going to its next station and stops there (standing arms stand)."""
        leg = self.leg
        if leg is None:
            return np.repeat(self.q[None, :], len(times), axis=0)
        tau_now = self.current_tau(now)
        if not self.running:
            return np.repeat(leg.trajectory.sample(np.array([tau_now])), len(times), axis=0)
        stop = leg.stations[self.k].tau
        out: FloatArray = leg.trajectory.sample(np.minimum(stop, tau_now + (times - now)))
        return out

    def next_stop_time(self, now: float) -> float:
        """When the arm reaches its next station if it moves now, seconds."""
        leg = self.leg
        if leg is None:
            return float(now)
        return float(now + max(0.0, leg.stations[self.k].tau - self.current_tau(now)))


@dataclass(frozen=True, slots=True)
class Excursion:
    """Where an arm left its leg for an excursion (frozen).

    Attributes
    ----------
    leg : Leg
        The leg it left.
    station : int
        The station it goes on towards when it is back.
    tau : float
        The offset in the leg it comes back to, seconds.
    at_station : bool
        It stood at ``station`` waiting for its conditions.
    """

    leg: Leg
    station: int
    tau: float
    at_station: bool


@dataclass(frozen=True, slots=True)
class BackOffUntil:
    """Until when an arm stays backed off (the coordination's own record).

    Attributes
    ----------
    mover : int
        The arm it made way for.
    leg : Leg or None
        The mover's leg then: once the mover is off it (and not on an
        excursion), the arm comes back.
    station : int
        The mover's next station then.
    """

    mover: int
    leg: Leg | None
    station: int


# ----------------------------------------------------------------- reports


@dataclass(frozen=True, slots=True)
class MotionReport:
    """The arm's view changed; ``moved``: it started or stopped moving (the
    held arms are looked at again)."""

    view: ArmView
    moved: bool


@dataclass(frozen=True, slots=True)
class DepartureRequest:
    """S2.12: may the arm set off from ``view`` towards its next station?"""

    view: ArmView


@dataclass(frozen=True, slots=True)
class TaskStarted:
    """The arm left ``task``'s start station at ``time``."""

    task: int
    time: float


@dataclass(frozen=True, slots=True)
class TaskEnded:
    """``task``'s trajectory ended at ``time`` (its end is told on the
    medium, ``trajectory_end``, once the arm is idle)."""

    task: int
    time: float


Report = MotionReport | DepartureRequest | TaskStarted | TaskEnded
"""A record from an arm to its coordination."""

REPORTS: tuple[type, ...] = (MotionReport, DepartureRequest, TaskStarted, TaskEnded)


# ------------------------------------------------------------------ orders


@dataclass(frozen=True, slots=True)
class Departure:
    """The answer to a :class:`DepartureRequest`: *continue* or *stop*.

    Sent unasked with ``go=False``: *stop* where the arm is now (an arm that
    stopped off its plan stands in the way of its motion); released by
    :class:`ReleaseHold`."""

    go: bool


@dataclass(frozen=True, slots=True)
class Detour:
    """S2.12 *continue with alternative trajectory*: go along ``trajectory``
    to the leg offset ``rejoin`` (``None``: the next station), keeping the
    reservations of the stations it passes."""

    trajectory: JointTrajectory
    task: int
    rejoin: float | None = None


@dataclass(frozen=True, slots=True)
class ReleaseHold:
    """End the geometric hold (the arm asks again before it sets off)."""


@dataclass(frozen=True, slots=True)
class BackOff:
    """Retreat along ``trajectory`` (to the home joints) out of a mover's way (S2.6)."""

    trajectory: JointTrajectory


@dataclass(frozen=True, slots=True)
class ComeBack:
    """Return from a back-off to where the arm left its leg."""


@dataclass(frozen=True, slots=True)
class Fail:
    """The arm fails for good."""


Order = Departure | Detour | ReleaseHold | BackOff | ComeBack | Fail
"""A record from the coordination to an arm."""

ORDERS: tuple[type, ...] = (Departure, Detour, ReleaseHold, BackOff, ComeBack, Fail)


class ControlChannel:
    """The S2.12 exchange: records delivered at the instant of sending
    (module docstring), numbered per arm and direction.

    Parameters
    ----------
    arms : int
        Number of arms.

    Attributes
    ----------
    sent : int
        Records sent (both directions).
    stale : int
        Records dropped as not newer than the last taken.
    """

    def __init__(self, arms: int) -> None:
        self.n_arms = int(arms)
        self._arm_rx: list[Callable[[Any], None] | None] = [None] * self.n_arms
        self._arm_msg: list[Callable[[str, Any], None] | None] = [None] * self.n_arms
        self._coord_rx: Callable[[int, Any], None] | None = None
        self._local_rx: Callable[[int, str, Any], None] | None = None
        self._station_rx: Callable[[int, Any], bool] | None = None
        self._next = [[0, 0] for _ in range(self.n_arms)]
        """Per arm: next sequence number of its reports, of its orders."""
        self._seen = [[-1, -1] for _ in range(self.n_arms)]
        """Per arm: last sequence number taken of its reports, of its orders."""
        self.sent = 0
        self.stale = 0

    def attach_arm(
        self,
        arm: int,
        receive: Callable[[Any], None],
        message: Callable[[str, Any], None] | None = None,
    ) -> None:
        """The arm's controller takes its orders with ``receive(order)``
        and the coordination's messages at its station with
        ``message(kind, payload)``."""
        self._arm_rx[arm] = receive
        self._arm_msg[arm] = message

    def attach_coordination(
        self,
        receive: Callable[[int, Any], None],
        local: Callable[[int, str, Any], None] | None = None,
        station: Callable[[int, Any], bool] | None = None,
    ) -> None:
        """The coordination takes reports with ``receive(arm, report)``.
        A policy whose peers share the arms' stations also takes the
        controllers' messages with ``local(station, kind, payload)`` and
        the frames that reach arm ``a``'s station first with
        ``station(a, frame) -> taken``."""
        self._coord_rx = receive
        self._local_rx = local
        self._station_rx = station

    def at_station(self, arm: int, frame: Any) -> None:
        """A frame of the medium reached ``arm``'s station: a coordination
        sharing the station takes it first, else the controller does
        (``frame.kind``, ``frame.payload[0]``)."""
        take = self._station_rx
        if take is not None and take(arm, frame):
            return
        self.to_controller(arm, frame.kind, frame.payload[0])

    def to_controller(self, arm: int, kind: str, payload: Any) -> None:
        """A coordination message handed to ``arm``'s controller at its station."""
        rx = self._arm_msg[arm]
        if rx is None:
            raise InternalError(f"control channel: no controller at arm {arm}'s station")
        rx(kind, payload)

    @property
    def colocated(self) -> bool:
        """The coordination takes the controllers' messages at their own station."""
        return self._local_rx is not None

    def local(self, station: int, kind: str, payload: Any) -> None:
        """A controller's message to a coordination at its own station."""
        if self._local_rx is None:
            raise InternalError("control channel: no coordination at the arms' stations")
        self._local_rx(station, kind, payload)

    def report(self, arm: int, record: Report) -> None:
        """Send ``record`` from ``arm`` to the coordination."""
        seq = self._next[arm][0]
        self._next[arm][0] = seq + 1
        self.sent += 1
        rx = self._coord_rx
        if rx is None:
            return
        if seq <= self._seen[arm][0]:  # pragma: no cover - in order by construction
            self.stale += 1
            return
        self._seen[arm][0] = seq
        rx(arm, record)

    def order(self, arm: int, record: Order) -> None:
        """Send ``record`` from the coordination to ``arm``."""
        seq = self._next[arm][1]
        self._next[arm][1] = seq + 1
        self.sent += 1
        rx = self._arm_rx[arm]
        if rx is None:
            raise InternalError(f"control channel: no controller for arm {arm}")
        if seq <= self._seen[arm][1]:  # pragma: no cover - in order by construction
            self.stale += 1
            return
        self._seen[arm][1] = seq
        rx(record)
