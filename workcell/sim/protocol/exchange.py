"""The S2.12 exchange between an arm and its coordination: reports, the
departure question and its answer, and the excursion orders.

Zone requests, grants, sleeps, wake-ups, releases, trajectories and alarms
travel through the medium (:mod:`workcell.sim.comms.link`). The geometric
check of S2.12 is the other exchange, made of messages through the same
medium:

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
frozen.

**On the medium.** Every record is a frame of the medium like the S2.7
messages, of its own kind and size (:data:`KINDS`, the sizes in
:data:`~workcell.sim.comms.medium.MESSAGE_BYTES`: a report or request 67
bytes, a task notice 37, the answer 30, release/come back/fail 27, a
back-off 148, a detour 154), counted in the link's frames, delayed,
lost and sent again like the rest. The :class:`~workcell.sim.protocol.channel.ControlChannel` only routes
them: every frame between an arm's station and the coordinator's (the
records and the S2.7 messages) goes on that arm's stream of its direction,
numbered 0, 1, 2, ... (:class:`~workcell.sim.protocol.channel.Sequenced`), and the receiver takes each
stream in order (a frame that overtook a lost one waits for it). So the
coordinator hears an arm's reports in the order they were made (where an
arm stands before its ``trajectory_end``), and an arm takes the answers and
orders in the order they were given.

**Soundness on an old book.** The book is one medium delay old (more with
losses), so the check (:class:`~workcell.sim.coordination.guard.GeometryGuard`)
never relies on *when* an arm is where:

* an arm sets off only on a *continue* answer to its latest request, and
  only if nothing stopped it since it asked (:class:`Departure`); it stops
  at its next station at the latest (every station pass is asked for);
* a motion the coordinator clears is in its book from that instant: the
  arm may be anywhere from where it asked to its next station, until a
  report sent after the arm took the answer comes back
  (:attr:`~workcell.sim.protocol.channel.Sequenced.taken` acknowledges it). Whatever the arm did
  meanwhile (set off late, stopped on a crash or an alarm) stays on that
  stretch;
* an arm the book has moving is checked anywhere on what is left of its
  leg from where it reported, up to its next station, whatever the time;
  an arm the book has standing stands there (it cannot set off without an
  answer the coordinator would know of).

Two arms are cleared only if every pose one may take touches no pose the
other may take; the check is the time-free swept test of both stretches.
A crash or an alarm stop leaves the arm on a stretch the book already
reserves, so no moving arm has to be stopped for it. The literal S2.12
check (the mover against the arms *standing* in the subzone, the zones
keeping the moving arms apart) is not enough for the compiled cells: with
the moving arms left out of the check, 15 of 300 campaign episodes on
``parking`` and ``scara4`` collide (docs/simulation.md). A failed arm is
told :class:`Fail` and its zones are given back once its report says it
is out.

The routing is :class:`~workcell.sim.protocol.channel.ControlChannel`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from multiarm.types import FloatArray
from workcell.arms import JointTrajectory
from workcell.sim.protocol.messages import Leg

__all__ = [
    "KINDS",
    "ORDERS",
    "REPORTS",
    "ArmView",
    "BackOff",
    "BackOffUntil",
    "ComeBack",
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

    def as_running(self, t_ref: float | None = None) -> ArmView:
        """This view with its leg's clock running (from ``t_ref``, if given):
        ``dataclasses.replace(view, running=True)`` without its cost (a hot path)."""
        return ArmView(
            self.index,
            self.leg,
            self.k,
            self.tau,
            self.t_ref if t_ref is None else t_ref,
            True,
            self.q,
            self.at_station,
            self.held,
            self.waiting,
            self.away,
            self.pushing,
            self.failed,
        )

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
    """S2.12: may the arm set off from ``view`` towards its next station?
    ``ask`` numbers the arm's requests (the answer names it)."""

    view: ArmView
    ask: int = 0


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
    """The answer to the :class:`DepartureRequest` numbered ``ask``:
    *continue* (``go``) or *stop* (released by :class:`ReleaseHold`).

    The arm sets off on *continue* only if the answer is to its latest
    request and nothing stopped it since it asked; else it stands, and its
    next report tells the coordination so."""

    go: bool
    ask: int = 0


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


KINDS: dict[type, str] = {
    MotionReport: "motion_report",
    DepartureRequest: "departure_request",
    TaskStarted: "task_started",
    TaskEnded: "task_ended",
    Departure: "departure",
    Detour: "detour",
    ReleaseHold: "release_hold",
    BackOff: "back_off",
    ComeBack: "come_back",
    Fail: "fail",
}
"""The frame kind of each record of the exchange (sizes:
:data:`~workcell.sim.comms.medium.MESSAGE_BYTES`)."""
