"""The arm controller of S2.3: a dynamic and a communication controller per arm.

Each simulated arm has two processors:

* the **dynamic controller** computes trajectory points and drives the arm;
* the **communication controller** talks to the coordinator over the medium
  and checks each point for zone conflicts.

They exchange six messages (recorded in the trace with ``src == dst`` the
arm's station and size 0): from dynamic to communication ``STOP_D`` (cannot
finish: a crash seen by the force sensor, a failure), ``TRAJECTORY_END``,
``TRAJECTORY_POINT`` (check this point); from communication to dynamic
``STOP_C`` (stop: an emergency broadcast or an unavailable zone ahead),
``TRAJECTORY`` (a new trajectory in the mailbox) and ``CONTINUE`` (resume
after ``STOP_C``).

Pipeline
--------
Computing, checking and executing are pipelined: while point ``i`` is
computed, point ``i - 1`` is checked and point ``i - offset`` is executed,
in a ring buffer of ``offset + 2`` points at the sampling period ``T``.
``offset`` is derived from the arm's top speed and its steepest allowed
stop: ``offset = ceil(t_stop / T)`` with ``t_stop`` the longest time any
joint needs to stop from its top speed (stepper: along ``stop_accel``,
S1.5; servo: at its acceleration limit). So a conflict seen at the checked
point leaves the arm time to stop before it executes that point: the
controller asks for a zone ``offset * T`` seconds (the *lookahead*) before
it reaches the zone's border, and an arm not granted the zone by then stops
at the border (S2.6) until woken.

At event level (the default) only the points that matter are events: the
lookahead point of each border, the border, the ends of zone windows and
the end of the trajectory; idle time is skipped. With a sampling period
(``tick``), a :class:`Ticker` runs the pipeline every tick for every moving
arm (one kernel event per tick for the whole cell, as the centralized
controller of S2.2 would), computing each point, checking it, and keeping
the ring buffer; the decisions are the same as at event level.

Motion between events follows the compiled trajectories exactly (closed-form
drive profiles, never a stepper pulse per event). Stops are modelled as
pauses of the trajectory clock at the stopping point.

Force sensing (S1.7, S1.2)
--------------------------
Each controller has the arm's wrist force sensor
(:class:`~workcell.sim.control.force.ForceSensor`) and its two commands,
:meth:`ArmController.read_force` and :meth:`ArmController.set_thresholds`.
A crash above the threshold in force stops the motors at once (``STOP_D``,
the reflex arc) and is reported to the coordinator afterwards
(:meth:`ArmController.sense_crash`). With drawn insertion tries
(:attr:`ArmController.searches`) a task leg carries its searches as marks
on its clock (:data:`Mark`): the thresholds are raised at the start of a
search dwell, each try ends with a force reading, and the free thresholds
come back after the last; extra tries are made while the clock stands (a
stop with reason ``"search"``), and when fewer tries than planned are
needed the rest of the dwell is skipped. The leg keeps the compiled
offsets, so the zone windows of the compiled mode stay valid.

Examples
--------
>>> from workcell.arms.profiles import StepperDrive
>>> pipeline_offset([StepperDrive()], 1e-3)
132
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, JointVector
from workcell.arms import DriveArm, JointTrajectory
from workcell.arms.profiles import Drive, ServoDrive, StepperDrive
from workcell.sim.control.force import (
    CRASH_AXIS,
    CRASH_FORCE,
    FREE_THRESHOLD,
    ForceSensor,
    InsertSearch,
)
from workcell.sim.events.loop import EventLoop, Handle
from workcell.sim.events.trace import Trace
from workcell.sim.protocol.messages import Leg, Mark, Piece, Station
from workcell.sim.protocol.records import MotionLog, MotionRecord, TaskRecord

__all__ = [
    "INTERNAL_MESSAGES",
    "ArmController",
    "Ticker",
    "pipeline_offset",
    "stop_time",
]

INTERNAL_MESSAGES: tuple[str, ...] = (
    "STOP_D",
    "TRAJECTORY_END",
    "TRAJECTORY_POINT",
    "STOP_C",
    "TRAJECTORY",
    "CONTINUE",
)
"""The six messages between an arm's two processors (S2.3)."""

_EPS = 1e-9
"""Seconds: marks this close to a station belong to it."""


def stop_time(drive: Drive) -> float:
    """Seconds a joint needs to stop from its top speed along its steepest
    allowed deceleration (stepper: ``stop_accel``, S1.5; servo: its
    acceleration limit).

    Examples
    --------
    >>> round(stop_time(StepperDrive()), 6)
    0.13125
    >>> stop_time(ServoDrive(1.0, 4.0))
    0.25
    """
    if isinstance(drive, StepperDrive):
        return drive.stop_time(drive.max_rate)
    if isinstance(drive, ServoDrive):
        return drive.max_velocity / drive.max_acceleration
    return 0.0


def pipeline_offset(drives: Sequence[Drive], period: float) -> int:
    """The pipeline offset (points) of S2.3: ``ceil(t_stop / period)``, at least 1.

    Parameters
    ----------
    drives : sequence of Drive
    period : float
        Sampling period, seconds (> 0).

    Returns
    -------
    int

    Raises
    ------
    ValidationError
        For a non-positive period.
    """
    if not (period > 0 and math.isfinite(period)):
        raise ValidationError(f"sampling period must be > 0 seconds, got {period!r}")
    t = max((stop_time(d) for d in drives), default=0.0)
    return max(1, math.ceil(t / period - 1e-9))


def _marks(searches: Sequence[InsertSearch]) -> list[Mark]:
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


class Ticker:
    """The sampling-period loop (S2.2, S2.3): one kernel event per tick while
    any arm moves, running every moving arm's compute/check/execute step.

    Parameters
    ----------
    kernel : EventLoop
    period : float
        Seconds.
    """

    def __init__(self, kernel: EventLoop, period: float) -> None:
        self.kernel = kernel
        self.period = float(period)
        self.arms: list[ArmController] = []
        self.ticks = 0
        self._handle: Handle | None = None

    def wake(self) -> None:
        """Make sure the loop runs (an arm started moving)."""
        if self._handle is None:
            now = self.kernel.now
            k = math.floor(now / self.period + 1e-9) + 1
            self._handle = self.kernel.schedule(k * self.period, self._tick, k, absolute=True)

    def _tick(self, k: int) -> None:
        self._handle = None
        any_moving = False
        for arm in self.arms:
            if arm.running:
                arm.pipeline_step()
                any_moving = True
        if any_moving:
            self.ticks += 1
            self._handle = self.kernel.schedule(
                (k + 1) * self.period, self._tick, k + 1, absolute=True
            )


class ArmController:
    """One arm's controller pair (module docstring).

    The controller executes :class:`Leg` records it receives in trajectory
    messages, stops at a station until its conditions hold (the plan's time,
    the zone grants, the task's start permission), answers faults, and keeps
    the record of its own motion (for the safety monitor and the metrics).

    Parameters
    ----------
    kernel : EventLoop
    index : int
        Arm id (its station on the medium is ``index + 1``).
    arm : DriveArm
    q0 : (dof,) float
        Initial joints.
    send : callable
        ``send(src, dst, kind, payload)`` puts a frame on the medium.
    trace : Trace
    period : float
        Sampling period, seconds (for the pipeline offset).
    ticker : Ticker, optional
        The shared tick driver when every controller tick is modelled
        (``SimOptions(tick=...)``); ``None`` at event level.
    force_threshold : float
        The wrist force sensor's free-motion threshold, newtons (S1.7).

    Attributes
    ----------
    sensor : ForceSensor
        The wrist force sensor (:mod:`workcell.sim.control.force`).
    searches : dict of int -> tuple of InsertSearch
        Per compiled mode, its insert steps' searches with the tries drawn
        (set by :func:`~workcell.sim.harness.simulate.simulate` with
        ``insertion="drawn"``; empty: every insertion takes its planned time).
    """

    def __init__(
        self,
        kernel: EventLoop,
        index: int,
        arm: DriveArm,
        q0: JointVector,
        send: Callable[[int, int, str, Any], None],
        trace: Trace,
        period: float,
        ticker: Ticker | None = None,
        force_threshold: float = FREE_THRESHOLD,
    ) -> None:
        self.kernel = kernel
        self.index = index
        self.station = index + 1
        self.arm = arm
        self.name = arm.name
        self.send = send
        self.trace = trace
        self.period = float(period)
        self.offset = pipeline_offset(arm.drives, self.period)
        self.lookahead = self.offset * self.period
        self.ring = np.zeros((self.offset + 2, arm.dof))
        self.ticker = ticker
        self.q = np.array(q0, dtype=float)  # commanded joints when idle
        self.home_q = self.q.copy()
        self.sync_error = np.zeros(arm.dof)  # lost steps, metres (S1.6)
        self.legs: list[Leg] = []
        self.leg: Leg | None = None
        self.k = 0  # next station
        self.tau = 0.0  # progress in the leg at time t_ref
        self.t_ref = 0.0
        self.running = False
        self.stops: set[str] = set()  # reasons for an unplanned stop
        self.released_stops: set[str] = set()  # coordinator stops released, by id
        self.at_station = False  # stopped at station k, waiting for its conditions
        self.granted: set[Piece] = set()
        self.permit: set[int] = set()  # tasks the coordinator allowed to start
        self.failed = False
        self.failed_at = math.inf  # when the arm failed (its tools and zones given back then)
        self.pose_task = -1
        self.busy = False
        self._arrive_h: Handle | None = None
        self._request_h: Handle | None = None
        self._resume_h: Handle | None = None
        self._wait_start = 0.0
        self._seg_t0 = 0.0
        self.log = MotionLog(
            index,
            arm.name,
            self.home_q.copy(),
            self._open_record,
            self._record_state,
            self.is_running,
        )
        """The published motion and task records (the monitor's only input)."""
        self.points_checked = 0
        self.zone_wait: dict[str, float] = {}
        self.border_wait = 0.0
        self._chunk: FloatArray = np.zeros((0, arm.dof))
        self._chunk_i = 0
        self._pipe_i = 0
        self.guard: Callable[[ArmController], bool] | None = None
        self.probe: Callable[[ArmController], bool] = lambda c: True
        self.notify: Callable[[], None] = lambda: None
        self.away: tuple[Any, ...] | None = None  # saved state during a back-off
        self.away_until: tuple[int, Any, int] | None = None
        # hooks set by the coordinator side
        self.on_task_start: Callable[[int, int, float], None] = lambda a, t, now: None
        self.on_task_end: Callable[[int, int, float], None] = lambda a, t, now: None
        # wrist force sensing and force-guided insertion (S1.7)
        self.sensor = ForceSensor(force_threshold)
        self.searches: dict[int, tuple[InsertSearch, ...]] = {}
        self.pushing = False  # thresholds raised for a search
        self._mark_h: Handle | None = None
        self._extra: list[Any] | None = None  # [leg, search, next try, last try, seconds left]
        self._extra_h: Handle | None = None
        self._extra_due = 0.0

    # ------------------------------------------------------------ helpers
    def internal(self, message: str, task: int = -1, detail: str = "") -> None:
        """Record an S2.3 message between the two processors."""
        self.trace.add(
            self.kernel.now,
            "message",
            arm=self.name,
            task=self._task_name(task),
            message=message,
            src=self.station,
            dst=self.station,
            detail=detail,
        )

    task_names: tuple[str, ...] = ()

    def _task_name(self, t: int) -> str:
        return self.task_names[t] if 0 <= t < len(self.task_names) else ""

    def position(self) -> FloatArray:
        """Commanded joints now."""
        if self.leg is None:
            return self.q
        tau = self.current_tau()
        out: FloatArray = self.leg.trajectory.sample(np.array([tau]))[0]
        return out

    def current_tau(self) -> float:
        if self.leg is None:
            return 0.0
        if self.running:
            return min(self.leg.duration, self.tau + (self.kernel.now - self.t_ref))
        return self.tau

    def _close_segment(self) -> None:
        """End the current motion record at now."""
        now = self.kernel.now
        if now > self._seg_t0 or not self.log.records:
            leg = self.leg
            if leg is None:
                self.log.records.append(
                    MotionRecord(self._seg_t0, now, None, 0.0, False, self.q.copy())
                )
            else:
                # progress at the record's start
                tau0 = self.tau + (self._seg_t0 - self.t_ref) if self.running else self.tau
                self.log.records.append(
                    MotionRecord(self._seg_t0, now, leg, tau0, self.running, self.sync_error.copy())
                )
                if self.running and now > self._seg_t0:
                    self.trace.add(
                        self._seg_t0,
                        "segment",
                        arm=self.name,
                        task=self._task_name(leg.task),
                        delay=now - self._seg_t0,
                        detail=f"{leg.kind} from offset {tau0:.6g} s",
                    )
        self._seg_t0 = now

    def _open_record(self, now: float) -> MotionRecord:
        """The motion record in progress, as it would be closed at ``now``."""
        leg = self.leg
        t0 = self._seg_t0
        if leg is None:
            return MotionRecord(t0, now, None, 0.0, False, self.q)
        tau0 = self.tau + (t0 - self.t_ref) if self.running else self.tau
        return MotionRecord(t0, now, leg, tau0, self.running, self.sync_error)

    def is_running(self) -> bool:
        """The trajectory clock runs."""
        return self.running

    def _record_state(self) -> tuple[Any, ...]:
        """What the record in progress depends on (equal: the same record)."""
        leg = self.leg
        n = len(self.log.tasks)
        if leg is None:
            return (self._seg_t0, 0, False, 0.0, n, self.failed, self.q.tobytes())
        running = self.running
        tau0 = self.tau + (self._seg_t0 - self.t_ref) if running else self.tau
        return (self._seg_t0, id(leg), running, tau0, n, self.failed, self.sync_error.tobytes())

    def _cancel(self) -> None:
        for h in (self._arrive_h, self._request_h, self._resume_h, self._mark_h):
            if h is not None:
                h.cancel()
        self._arrive_h = self._request_h = self._resume_h = self._mark_h = None

    # ------------------------------------------------------------ motion
    def _pause(self, reason: str) -> None:
        """Stop the trajectory clock now (an unplanned stop)."""
        if reason != "search" and self._extra_h is not None:
            # the pushes of a search stop too; they go on when only it is left
            self._extra_h.cancel()
            self._extra_h = None
            assert self._extra is not None
            self._extra[4] = max(0.0, self._extra_due - self.kernel.now)
        self.stops.add(reason)
        if self.running:
            tau = self.current_tau()
            self._close_segment()
            self.tau = tau
            self.t_ref = self.kernel.now
            self.running = False
            self._cancel()
            self.notify()

    def _unpause(self, reason: str) -> None:
        """End the stop ``reason``; with no stop left the arm goes on: it
        moves again, or, standing at a station, tries its pass again (the
        grants and permissions that came during the stop count)."""
        self.stops.discard(reason)
        if self._extra is not None and self._extra_h is None and self.stops == {"search"}:
            if not self.failed:
                self._extra_due = self.kernel.now + float(self._extra[4])
                self._extra_h = self.kernel.schedule(float(self._extra[4]), self._extra_try)
            return
        if self.stops or self.leg is None or self.running:
            return
        if self.at_station:
            self._try_pass()
        else:
            self._run()

    def _run(self) -> None:
        """Start (or go on) moving towards station k."""
        if self.failed or self.stops or self.leg is None:
            return
        if self.guard is not None and not self.guard(self):
            self.stops.add("geometry")  # the coordinator wakes it (S2.12 "stop")
            return
        self._close_segment()
        self.running = True
        self.t_ref = self.kernel.now
        self.notify()
        if self.ticker is not None:
            self._chunk_i = len(self._chunk)  # recompute the pipeline's points
            self.ticker.wake()
        self._plan_next()

    def _plan_next(self) -> None:
        leg = self.leg
        assert leg is not None
        st = leg.stations[self.k]
        now = self.kernel.now
        t_reach = now + max(0.0, st.tau - self.tau - (now - self.t_ref))
        if st.acquire and not st.requested:
            t_req = max(now, max(t_reach, st.notbefore) - self.lookahead)
            self._request_h = self.kernel.schedule(t_req, self._request, st, absolute=True)
        self._arrive_h = self.kernel.schedule(t_reach, self._arrive, absolute=True)
        self._plan_mark()

    def _request(self, st: Station) -> None:
        self._request_h = None
        self._send_requests(st)

    def _send_requests(self, st: Station) -> None:
        if st.requested or self.failed:
            return
        st.requested = True
        leg = self.leg
        task = leg.task if leg is not None else -1
        self.internal("TRAJECTORY_POINT", task, detail=f"check the point at offset {st.tau:.6g} s")
        for piece in st.acquire:
            self.send(self.station, 0, "zone_request", piece)

    def _arrive(self) -> None:
        """Reach station k."""
        self._arrive_h = None
        leg = self.leg
        assert leg is not None
        st = leg.stations[self.k]
        self._close_segment()
        self.tau = st.tau
        self.running = False
        self.notify()
        self.t_ref = self.kernel.now
        for piece in st.release:
            self.granted.discard(piece)
            self._zone_event("zone_leave", piece, leg.task)
            self.send(self.station, 0, "zone_release", piece)
        if leg.marks:
            self._fire_marks(st.tau)
        if self._mark_h is not None:
            self._mark_h.cancel()
            self._mark_h = None
        if st.end:
            self._leg_done()
            return
        self.at_station = True
        self._wait_start = self.kernel.now
        self._try_pass()

    def _try_pass(self) -> None:
        """Pass station k if its conditions hold; else stay stopped there."""
        leg = self.leg
        if leg is None or not self.at_station or self.failed:
            return
        st = leg.stations[self.k]
        if st.acquire and not st.requested:
            self._send_requests(st)
        now = self.kernel.now
        blocked = any(p not in self.granted for p in st.acquire)
        if blocked or (st.start and leg.task not in self.permit):
            return  # a grant, wake-up or permission will call us again
        if st.notbefore > now:
            if self._resume_h is None:
                self._resume_h = self.kernel.schedule(st.notbefore, self._resume_at, absolute=True)
            return
        if self.stops:
            return
        self._leave_station(st)

    zone_names: tuple[str, ...] = ()
    tool_names: tuple[str, ...] = ()

    def _resource_name(self, piece: Piece) -> str:
        names = self.tool_names if piece[0] == "tool" else self.zone_names
        return names[piece[1]] if 0 <= piece[1] < len(names) else str(piece[1])

    def _zone_event(self, kind: str, piece: Piece, task: int) -> None:
        self.trace.add(
            self.kernel.now,
            kind,
            arm=self.name,
            task=self._task_name(task),
            zone=self._resource_name(piece),
            detail=piece[0],
        )

    def _resume_at(self) -> None:
        self._resume_h = None
        self._try_pass()

    def _leave_station(self, st: Station) -> None:
        leg = self.leg
        assert leg is not None
        now = self.kernel.now
        waited = now - self._wait_start
        self.at_station = False
        if st.start:
            self.log.tasks[leg.task] = TaskRecord(leg.task, leg.mode, now)
            self.on_task_start(self.index, leg.task, now)
        if st.border >= 0:
            log = self.log.tasks.get(leg.task)
            if log is not None:
                self.log.tasks[leg.task] = replace(log, waits=(*log.waits, (st.border, waited)))
        if st.acquire and waited > 0:
            self.border_wait += waited  # once per stop, however many resources it waited for
        for piece in st.acquire:
            self._zone_event("zone_enter", piece, leg.task)
            if waited > 0:
                name = self._resource_name(piece)
                self.zone_wait[name] = self.zone_wait.get(name, 0.0) + waited
        self.k += 1
        self._run()

    def _leg_done(self) -> None:
        leg = self.leg
        assert leg is not None
        now = self.kernel.now
        if leg.kind == "retreat":
            self.q = leg.trajectory.q_end.copy()
            self.leg = None
            self._seg_t0 = now
            self.notify()
            return
        if leg.kind in ("return", "detour"):
            assert self.away is not None
            saved_leg, k, tau, at_station = self.away
            self.away = None
            self.leg = saved_leg
            self.k, self.tau, self.t_ref = k, tau, now
            self.at_station = at_station
            self._wait_start = now
            self.notify()
            if at_station:
                self._try_pass()
            else:
                self._run()
            return
        self.q = leg.trajectory.q_end.copy()
        if leg.kind == "task":
            self.internal("TRAJECTORY_END", leg.task)
            log = self.log.tasks.get(leg.task)
            if log is not None:
                self.log.tasks[leg.task] = replace(log, end=now)
            self.pose_task = leg.task
            if self._search_failure(leg) is None:
                self.on_task_end(self.index, leg.task, now)
        self.leg = None
        if leg.kind == "task" and np.any(self.sync_error != 0):
            # the lost steps show now (a part misplaced): home the axes (S1.6)
            seconds = self.homing_time()
            self.trace.add(
                now,
                "fault",
                arm=self.name,
                task=self._task_name(leg.task),
                delay=seconds,
                detail=f"position error found: homing the axes for {seconds:.6g} s (S1.6)",
            )
            self.homing = True

            def homed() -> None:
                self._close_segment()
                self.sync_error[:] = 0.0
                self.homing = False
                self._after_leg(leg)

            self.kernel.schedule(seconds, homed)
            return
        self._after_leg(leg)

    homing = False

    def _after_leg(self, leg: Leg) -> None:
        now = self.kernel.now
        if self.failed:
            return
        if self.legs:
            self._start_leg(self.legs.pop(0))
        else:
            self.busy = False
            self._seg_t0 = now
            if leg.kind == "task":
                cause = self._search_failure(leg)
                if cause is None:
                    self.send(self.station, 0, "trajectory_end", leg.task)
                else:  # the task ran but failed: told with its cause
                    self.send(self.station, 0, "trajectory_end", ("failed", leg.task, cause))

    def _start_leg(self, leg: Leg) -> None:
        if leg.kind == "task" and leg.marks is None:
            leg.searches = self.searches.get(leg.mode, ())
            leg.marks = _marks(leg.searches)
        self._close_segment()
        self.leg = leg
        self.k = 0
        self.tau = 0.0
        self.t_ref = self.kernel.now
        self.at_station = False
        self._run()

    # ------------------------------------------------------- from the medium
    def receive(self, kind: str, payload: Any) -> None:
        """A frame from the coordinator (already delivered by the medium)."""
        if self.failed:
            return
        if kind == "trajectory":
            legs, permit = payload
            self.internal("TRAJECTORY", legs[-1].task)
            if permit:
                self.permit.add(legs[-1].task)
            self.busy = True
            self.legs.extend(legs)
            if self.leg is None:
                self._start_leg(self.legs.pop(0))
        elif kind in ("zone_grant", "wake_up"):
            if isinstance(payload, tuple) and payload and payload[0] == "start":
                self.permit.add(int(payload[2]))
            elif isinstance(payload, tuple) and payload and payload[0] == "alarm_clear":
                self.internal("CONTINUE", detail="alarm cleared")
                self._release_stop(f"alarm#{payload[1]}")
                return
            elif isinstance(payload, tuple) and payload and payload[0] == "activation":
                self._release_stop(f"activation#{payload[1]}")
                return
            else:
                self.granted.add(payload)
            if kind == "wake_up":
                self.internal("CONTINUE")
            self._try_pass()
        elif kind == "sleep":
            if isinstance(payload, tuple) and payload and payload[0] == "activation":
                self.internal("STOP_C", detail="zone activation: stop")
                self._stop_by_id(f"activation#{payload[1]}")
                self._report_stop()
                self.send(self.station, 0, "position", (None, self.flange()))
            elif isinstance(payload, tuple) and payload and payload[0] == "withdraw":
                self._withdraw(int(payload[2]))
            else:
                self.internal("STOP_C", detail="zone not available: stop at its border")
        elif kind == "alarm":
            self.internal("STOP_C", detail="emergency broadcast")
            self._stop_by_id(f"alarm#{payload[1]}")
            self._report_stop()
        elif kind == "active_zone_grant":
            pass

    def _stop_by_id(self, stop: str) -> None:
        """A coordinator's stop (``"alarm#<id>"``, ``"activation#<id>"``): in
        force until the release with the same id (a release that overtook
        its stop on the medium cancels it in advance)."""
        if stop in self.released_stops:
            return
        self._pause(stop)

    def _release_stop(self, stop: str) -> None:
        """The release of the coordinator's stop ``stop`` (matched by id)."""
        self.released_stops.add(stop)
        self._unpause(stop)

    def _withdraw(self, t: int) -> None:
        """Drop the not yet started task ``t`` (the plan changed)."""
        if t in self.log.tasks:
            return
        if self.leg is not None and self.leg.task == t:
            self._pause("withdraw")
            q = self.position()
            self._close_segment()
            self._cancel()
            self.q = q
            self.leg = None
            self.at_station = False
            self.stops.discard("withdraw")
        self.legs = [leg for leg in self.legs if leg.task != t]
        self.permit.discard(t)
        self.granted = {g for g in self.granted if g[2] != t}  # given back by the coordinator
        if self.leg is None:
            self.busy = False
            self._seg_t0 = self.kernel.now
            self.send(self.station, 0, "trajectory_end", ("withdrawn", t))

    def back_off(self, until: tuple[int, Any, int]) -> bool:
        """Retreat to the home joints out of a mover's way (S2.6 geometric
        deadlock) and come back once the mover has passed (``until``:
        its index, leg and station). Returns whether the retreat started."""
        if (
            self.away is not None
            or self.running
            or self.failed
            or self.leg is None
            or self.pushing  # not out of a hole in the middle of a search
        ):
            return False
        q = self.position()
        traj = self.arm.move(q, self.home_q, self.arm.interpolation)
        if traj.duration <= 0:
            return False
        task = self.leg.task
        saved = (self.leg, self.k, self.tau, self.at_station)
        self.leg = Leg("retreat", task, -1, traj, [Station(traj.duration, end=True)])
        self.k, self.tau = 0, 0.0
        if not self.probe(self):  # the way back home is not free either
            self.leg, self.k, self.tau, self.at_station = saved
            return False
        self.leg = saved[0]
        self._close_segment()
        self.away = saved
        self.away_until = until
        self.leg = Leg("retreat", task, -1, traj, [Station(traj.duration, end=True)])
        self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
        self.at_station = False
        self.stops.discard("geometry")
        self.internal("STOP_D", task, "standing in a mover's way: back off to the home joints")
        self._run()
        return True

    def take_detour(self, traj: JointTrajectory, task: int) -> None:
        """Go to the next station along ``traj`` instead (S2.12 alternative
        trajectory), then on with the task from there."""
        leg = self.leg
        assert leg is not None
        self.away = (leg, self.k, leg.stations[self.k].tau, False)
        self.away_until = None
        self._close_segment()
        self.leg = Leg("detour", task, -1, traj, [Station(traj.duration, end=True)])
        self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
        self.at_station = False
        self.stops.discard("geometry")
        self._run()

    def come_back(self) -> None:
        """Return from a back-off to where the arm stopped."""
        if self.away is None or self.leg is not None:
            return
        saved_leg, _k, tau, _st = self.away
        target = saved_leg.trajectory.sample(np.array([tau]))[0]
        traj = self.arm.move(self.q, target, self.arm.interpolation)
        self.away_until = None
        self._close_segment()
        self.leg = Leg("return", saved_leg.task, -1, traj, [Station(traj.duration, end=True)])
        self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
        self.at_station = False
        self._run()

    def predict(self, times: FloatArray) -> FloatArray:
        """(N, dof) commanded joints at future ``times`` if the arm keeps going
        to its next station and stops there (standing arms stand)."""
        leg = self.leg
        if leg is None:
            return np.repeat(self.q[None, :], len(times), axis=0)
        now = self.kernel.now
        tau_now = self.current_tau()
        if not self.running:
            return np.repeat(leg.trajectory.sample(np.array([tau_now])), len(times), axis=0)
        stop = leg.stations[self.k].tau
        taus = np.minimum(stop, tau_now + (times - now))
        return leg.trajectory.sample(taus)

    def next_stop_time(self) -> float:
        """When the arm reaches its next station if it moves now (seconds)."""
        leg = self.leg
        if leg is None:
            return self.kernel.now
        return self.kernel.now + max(0.0, leg.stations[self.k].tau - self.current_tau())

    def stuck(self) -> bool:
        """Standing and waiting on something other than the clock."""
        if self.running or self.failed or self.leg is None:
            return False
        if "geometry" in self.stops:
            return True
        if self.at_station:
            st = self.leg.stations[self.k]
            if any(p not in self.granted for p in st.acquire):
                return True
            if st.start and self.leg.task not in self.permit:
                return True
        return False

    def _report_stop(self) -> None:
        """Tell the coordinator where it stopped when inside a shared zone (S2.7)."""
        held = sorted(p for p in self.granted if p[0] == "move")
        for p in held:
            self.send(self.station, 0, "position", (p, self.flange()))

    def flange(self) -> tuple[float, float, float]:
        """Flange position now (metres)."""
        q = self.position()
        x = self.arm.fk(q[None])[0][:3, 3]
        return (float(x[0]), float(x[1]), float(x[2]))

    def finish(self) -> None:
        """Close the motion record at the end of the run."""
        self._close_segment()

    def is_stopped(self) -> bool:
        """Standing still (idle, at a station or paused)."""
        return not self.running

    # ------------------------------------------------------------ faults
    def crash(self, recovery: float, force: float = CRASH_FORCE) -> bool:
        """A crash of ``force`` newtons (S1.7); see :meth:`sense_crash`.

        Returns whether the arm stopped (reflex arc, S1.2)."""
        return self.sense_crash(force, recovery) == "stop"

    def sense_crash(self, force: float, recovery: float) -> str:
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
        self.send(self.station, 0, "alarm", ("crash", recovery))
        self.kernel.schedule(recovery, self._resume, "crash")
        return "stop"

    def _resume(self, reason: str) -> None:
        """End an unplanned stop, also when standing at a station."""
        self._unpause(reason)

    # --------------------------------------------------- force sensing (S1.7)
    def read_force(self, axis: int) -> float:
        """The S1.7 command "tell me the force on axis k" (newtons, the last
        sample of the wrist sensor; 0 in free motion: inertial forces are
        not modelled)."""
        return self.sensor.read(axis)

    def set_thresholds(self, values: float | Sequence[float], why: str = "") -> None:
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

    def _force_event(self, leg: Leg, detail: str) -> None:
        self.trace.add(
            self.kernel.now, "force", arm=self.name, task=self._task_name(leg.task), detail=detail
        )

    def _search_failure(self, leg: Leg) -> str | None:
        """The cause when a search of the task leg never found its hole."""
        for s in leg.searches:
            if not s.found:
                return str(s.cause)
        return None

    def _plan_mark(self) -> None:
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
            now + max(0.0, tau - self.current_tau()), self._mark, absolute=True
        )

    def _mark(self) -> None:
        self._mark_h = None
        if self.leg is None or self.failed:
            return
        self._fire_marks(self.current_tau())
        if self.running and self._mark_h is None:
            self._plan_mark()

    def _fire_marks(self, tau: float) -> None:
        """Do every mark of the leg due at offset ``tau``."""
        leg = self.leg
        assert leg is not None and leg.marks is not None
        while leg.fired < len(leg.marks) and leg.marks[leg.fired].tau <= tau + _EPS:
            _t, action, si, k = leg.marks[leg.fired]
            leg.fired += 1
            s = leg.searches[si]
            if action == "raise":
                self.pushing = True
                self.set_thresholds(
                    s.search.threshold, f"force-guided search of step {s.step} (S1.7)"
                )
                extra = s.tries - s.planned
                if extra > 0:  # more tries than planned: the clock stands meanwhile
                    self._extra = [leg, si, 1, extra, s.search.try_time]
                    self._extra_due = self.kernel.now + s.search.try_time
                    self._extra_h = self.kernel.schedule(s.search.try_time, self._extra_try)
                    self._pause("search")
                    return
            else:
                self._try_done(leg, s, k)
                if k == s.tries and s.tries < s.planned and self.running:
                    self._skip_to(s.end)
                    return

    def _try_done(self, leg: Leg, s: InsertSearch, k: int) -> None:
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

    def _extra_try(self) -> None:
        """A try made while the trajectory clock stands (more tries than planned)."""
        self._extra_h = None
        st = self._extra
        if st is None or self.failed:
            return
        leg, si, k, last, _left = st
        self._try_done(leg, leg.searches[si], k)
        if k < last:
            st[2] = k + 1
            st[4] = leg.searches[si].search.try_time
            self._extra_due = self.kernel.now + st[4]
            self._extra_h = self.kernel.schedule(st[4], self._extra_try)
            return
        self._extra = None
        self._resume("search")

    def _skip_to(self, tau: float) -> None:
        """The hole was found before the planned tries were over: the rest of
        the search dwell is skipped (the arm stands meanwhile); it sets off
        towards its next station now, checked like any departure."""
        tau = max(self.current_tau(), tau)
        self._close_segment()
        self.tau = tau
        self.t_ref = self.kernel.now
        self.running = False
        self._cancel()
        self.notify()
        self._run()

    def fail(self) -> None:
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

    def lose_sync(self, axis: int, steps: int) -> float:
        """Stepper ``axis`` loses ``steps`` steps: the actual position drifts
        from the tracked one (S1.6). Returns the error in metres."""
        d = self.arm.drives[axis]
        assert isinstance(d, StepperDrive)
        err = steps * d.step_length
        self._close_segment()
        self.sync_error[axis] -= err
        return err

    def homing_time(self) -> float:
        """Seconds to home every stepper axis that lost steps (S1.6)."""
        q = self.position()
        out = 0.0
        for j, d in enumerate(self.arm.drives):
            if isinstance(d, StepperDrive) and self.sync_error[j] != 0:
                lo = float(self.arm.joint_limits[j, 0])
                out = max(out, d.homing_time(abs(float(q[j]) - lo)))
        return out

    # -------------------------------------------------------- tick mode
    def pipeline_step(self) -> None:
        """One sampling period (S2.3): compute point i, check point i - 1,
        execute point i - offset (the ring buffer holds offset + 2 points)."""
        leg = self.leg
        if leg is None:
            return
        if self._chunk_i >= len(self._chunk):
            tau = self.current_tau() + self.lookahead
            taus = tau + self.period * np.arange(64, dtype=np.float64)
            self._chunk = leg.trajectory.sample(taus)
            self._chunk_i = 0
        i = self._pipe_i
        self.ring[i % len(self.ring)] = self._chunk[self._chunk_i]
        self._chunk_i += 1
        self._pipe_i = i + 1
        self.points_checked += 1
