"""The arm controller's force sensing (S1.7, S1.2): the reflex stop on a
crash, the S1.7 commands, and force-guided insertion searches on a task
leg's clock; lost stepper steps and homing (S1.6); the arm's failure.

Functions here are methods of :class:`~workcell.sim.control.controller.ArmController`
(bound in its class body), kept apart to keep each module small.

Each controller has the arm's wrist force sensor
(:class:`~workcell.sim.control.force.ForceSensor`) and its two commands,
:meth:`~workcell.sim.control.controller.ArmController.read_force` and :meth:`~workcell.sim.control.controller.ArmController.set_thresholds`.
A crash above the threshold in force stops the motors at once (``STOP_D``,
the reflex arc) and is reported to the coordinator afterwards
(:meth:`~workcell.sim.control.controller.ArmController.sense_crash`). With drawn insertion tries
(``ArmController.searches``) a task leg carries its searches as marks
on its clock (:class:`~workcell.sim.protocol.messages.Mark`): the thresholds are raised at the start of a
search dwell, each try ends with a force reading, and the free thresholds
come back after the last; extra tries are made while the clock stands (a
stop with reason ``"search"``), and when fewer tries than planned are
needed the rest of the dwell is skipped. The leg keeps the compiled
offsets, so the zone windows of the compiled mode stay valid.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from workcell.arms.profiles import StepperDrive
from workcell.sim.control.force import CRASH_AXIS, CRASH_FORCE, InsertSearch
from workcell.sim.protocol.messages import AlarmStop, Leg, Mark

_Self = Any
"""The :class:`~workcell.sim.control.controller.ArmController` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.control.controller imports this module, never the reverse)."""

__all__ = ["ExtraTries", "marks"]

_EPS = 1e-9
"""Seconds: marks this close to a station belong to it."""


@dataclass(slots=True)
class ExtraTries:
    """The tries of a search made while the leg's clock stands (more than planned).

    Attributes
    ----------
    leg : Leg
    search : int
        Index of the search in the leg.
    attempt : int
        The try under way (1-based).
    last : int
        The last try made while the clock stands.
    left : float
        Seconds left of the try under way (kept while another stop holds the arm).
    """

    leg: Leg
    search: int
    attempt: int
    last: int
    left: float


def marks(searches: Sequence[InsertSearch]) -> list[Mark]:
    """The events of ``searches`` on the task leg's clock (compiled offsets).

    A search raises the thresholds at the start of its dwell. When it needs
    more tries than planned, the first extra ones are made there while the
    clock stands (:meth:`ArmController._extra_try`); the planned dwell then
    holds the last ``min(tries, planned)`` tries, one mark at the end of each.
    When it needs fewer, the clock skips the rest of the dwell after the last.
    """
    out: list[Mark] = []
    for si, s in enumerate(searches):
        T = s.search.try_time
        out.append(Mark(s.start, "raise", si, 0))
        base = max(0, s.tries - s.planned)
        for j in range(1, min(s.tries, s.planned) + 1):
            out.append(Mark(s.start + j * T, "try", si, base + j))
    return out


def crash(self: _Self, recovery: float, force: float = CRASH_FORCE) -> bool:
    """A crash of ``force`` newtons (S1.7); see :meth:`sense_crash`.

    Returns whether the arm stopped (reflex arc, S1.2)."""
    return bool(self.sense_crash(force, recovery) == "stop")


def sense_crash(self: _Self, force: float, recovery: float) -> str:
    """A crash pushing ``force`` newtons on the wrist's z axis now.

    While the arm moves (free motion, low thresholds) or pushes (an
    insertion search, raised thresholds, not stopped for another
    reason), a force above the threshold in force stops the motors at
    once by themselves (the reflex arc of S1.2, ``STOP_D``); the
    coordinator is told afterwards (``alarm``); the arm goes on
    ``recovery`` seconds later. A force at or below it is not sensed as
    a crash (a push of an insertion): the arm goes on.

    Returns
    -------
    {"stop", "below", "standing"}
        Stopped; not above the threshold (no effect); standing idle,
        waiting or stopped (no effect, as before force sensing was
        modelled).
    """
    pushing = self.pushing and self.stops <= {"search"}
    if self.failed or self.leg is None or not (self.running or pushing):
        return "standing"
    self.sensor.force = np.zeros(3)
    self.sensor.force[CRASH_AXIS] = float(force)
    if not self.sensor.exceeds(force):
        return "below"
    self.internal("STOP_D", self.leg.task, "excessive force: reflex stop")
    self._pause("crash")
    self.send(self.station, 0, "alarm", AlarmStop(0, "crash", recovery))
    self.kernel.schedule(recovery, self._event, self._resume, "crash")
    self._report()
    return "stop"


def _resume(self: _Self, reason: str) -> None:
    """End an unplanned stop, also when standing at a station."""
    self._unpause(reason)


def read_force(self: _Self, axis: int) -> float:
    """The S1.7 command "tell me the force on axis k" (newtons, the last
    sample of the wrist sensor; 0 in free motion: inertial forces are
    not modelled)."""
    return float(self.sensor.read(axis))


def set_thresholds(self: _Self, values: float | Sequence[float], why: str = "") -> None:
    """The S1.7 command "set the thresholds" (newtons: one value for the
    three components, or three), recorded as a ``"force"`` trace event."""
    self.sensor.set_thresholds(values)
    th = self.sensor.thresholds
    shown = f"{th[0]:g} N" if th[0] == th[1] == th[2] else ", ".join(f"{x:g}" for x in th)
    leg = self.leg
    self.trace.add(
        self.kernel.now,
        "force",
        arm=self.name,
        task=self._task_name(leg.task if leg is not None else -1),
        detail=f"set thresholds {shown}" + (f": {why}" if why else ""),
    )


def _force_event(self: _Self, leg: Leg, detail: str) -> None:
    self.trace.add(
        self.kernel.now, "force", arm=self.name, task=self._task_name(leg.task), detail=detail
    )


def _search_failure(self: _Self, leg: Leg) -> str | None:
    """The cause when a search of the task leg never found its hole."""
    for s in leg.searches:
        if not s.found:
            return str(s.cause)
    return None


def _plan_mark(self: _Self) -> None:
    """Schedule the leg's next force-search mark if it comes before the
    next station."""
    if self._mark_h is not None:
        self._mark_h.cancel()
        self._mark_h = None
    leg = self.leg
    if leg is None or not self.running or not leg.marks or leg.fired >= len(leg.marks):
        return
    tau = leg.marks[leg.fired].tau
    if tau > leg.stations[self.k].tau + _EPS:
        return
    now = self.kernel.now
    self._mark_h = self.kernel.schedule(
        now + max(0.0, tau - self.current_tau()), self._event, self._mark, absolute=True
    )


def _mark(self: _Self) -> None:
    self._mark_h = None
    if self.leg is None or self.failed:
        return
    self._fire_marks(self.current_tau())
    if self.running and self._mark_h is None:
        self._plan_mark()


def _fire_marks(self: _Self, tau: float) -> None:
    """Do every mark of the leg due at offset ``tau``."""
    leg = self.leg
    assert leg is not None and leg.marks is not None
    while leg.fired < len(leg.marks) and leg.marks[leg.fired].tau <= tau + _EPS:
        mark = leg.marks[leg.fired]
        action, si, k = mark.action, mark.search, mark.attempt
        leg.fired += 1
        s = leg.searches[si]
        if action == "raise":
            self.pushing = True
            self.set_thresholds(s.search.threshold, f"force-guided search of step {s.step} (S1.7)")
            extra = s.tries - s.planned
            if extra > 0:  # more tries than planned: the clock stands meanwhile
                self._extra = ExtraTries(leg, si, 1, extra, s.search.try_time)
                self._extra_due = self.kernel.now + s.search.try_time
                self._extra_h = self.kernel.schedule(
                    s.search.try_time, self._event, self._extra_try
                )
                self._pause("search")
                return
        else:
            self._try_done(leg, s, k)
            if k == s.tries and s.tries < s.planned and self.running:
                self._skip_to(s.end)
                return


def _try_done(self: _Self, leg: Leg, s: InsertSearch, k: int) -> None:
    """Try ``k`` of search ``s`` ends: read the force on z (S1.7)."""
    fs = s.search
    off = fs.offsets()[k - 1]
    landed = s.found and k == s.tries
    self.sensor.force = np.zeros(3)
    self.sensor.force[CRASH_AXIS] = 0.0 if landed else fs.threshold
    f = self.read_force(CRASH_AXIS)
    where = f"try {k} of {fs.max_tries} at offset ({off[0] * 1e3:.3g}, {off[1] * 1e3:.3g}) mm"
    if landed:
        verdict = "in the hole"
    elif k < fs.max_tries:
        verdict = "reached the threshold: not in the hole"
    else:
        verdict = "reached the threshold: not in the hole; " + s.cause
    self._force_event(leg, f"read force on axis {CRASH_AXIS}: {f:g} N, {where}: {verdict}")
    if k == s.tries:
        self.sensor.force = np.zeros(3)
        self.pushing = False
        self.set_thresholds(self.sensor.free, f"search of step {s.step} over: free motion")


def _extra_try(self: _Self) -> None:
    """A try made while the trajectory clock stands (more tries than planned)."""
    self._extra_h = None
    st = self._extra
    if st is None or self.failed:
        return
    leg, si, k = st.leg, st.search, st.attempt
    self._try_done(leg, leg.searches[si], k)
    if k < st.last:
        st.attempt = k + 1
        st.left = leg.searches[si].search.try_time
        self._extra_due = self.kernel.now + st.left
        self._extra_h = self.kernel.schedule(st.left, self._event, self._extra_try)
        return
    self._extra = None
    self._resume("search")


def _skip_to(self: _Self, tau: float) -> None:
    """The hole was found before the planned tries were over: the rest of
    the search dwell is skipped (the arm stands meanwhile); it sets off
    towards its next station now, checked like any departure."""
    tau = max(self.current_tau(), tau)
    self._close_segment()
    self.tau = tau
    self.t_ref = self.kernel.now
    self.running = False
    self._cancel()
    self._report(True)
    self._run()


def fail(self: _Self) -> None:
    """The arm fails for good: it stops, and is taken to its home joints
    outside every zone (not modelled: the retraction itself)."""
    if self.failed:
        return
    task = self.leg.task if self.leg else -1
    self.internal("STOP_D", task, "arm failure")
    self._pause("failed")
    self._close_segment()
    self._extra = None  # a search in progress ends with the arm
    self.pushing = False
    self.failed = True
    self.failed_at = self.log.failed_at = self.kernel.now
    self.leg = None
    self.legs.clear()
    self.at_station = False
    self.q = self.home_q.copy()
    self._seg_t0 = self.kernel.now


def lose_sync(self: _Self, axis: int, steps: int) -> float:
    """Stepper ``axis`` loses ``steps`` steps: the actual position drifts
    from the tracked one (S1.6). Returns the error in metres."""
    d = self.arm.drives[axis]
    assert isinstance(d, StepperDrive)
    err = steps * d.step_length
    self._close_segment()
    self.sync_error[axis] -= err
    return err


def homing_time(self: _Self) -> float:
    """Seconds to home every stepper axis that lost steps (S1.6)."""
    q = self.position()
    out = 0.0
    for j, d in enumerate(self.arm.drives):
        if isinstance(d, StepperDrive) and self.sync_error[j] != 0:
            lo = float(self.arm.joint_limits[j, 0])
            out = max(out, d.homing_time(abs(float(q[j]) - lo)))
    return out
