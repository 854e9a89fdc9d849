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

The pipeline of S2.3 is in :mod:`.pipeline`; force sensing, the reflex
arc and insertion searches (S1.7, S1.2) in :mod:`.search`; excursions and
the answers to the geometric check (S2.6, S2.12) in :mod:`.excursions`; the
communication processor's inbox in :mod:`.mailbox`. Motion between events
follows the compiled trajectories exactly; stops are pauses of the
trajectory clock at the stopping point. The controller publishes its motion
in :attr:`ArmController.log` (:class:`~workcell.sim.protocol.records.MotionLog`)
and checks its state (:class:`~workcell.sim.protocol.states.ArmState`)
against :data:`~workcell.sim.protocol.states.ARM_MACHINE` at every change.

Examples
--------
>>> from workcell.arms.profiles import StepperDrive
>>> pipeline_offset([StepperDrive()], 1e-3)
132
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from multiarm.types import FloatArray, JointVector
from workcell.arms import DriveArm
from workcell.sim.control import excursions, mailbox, recording, search
from workcell.sim.control.force import (
    FREE_THRESHOLD,
    ForceSensor,
    InsertSearch,
)
from workcell.sim.control.pipeline import (
    INTERNAL_MESSAGES,
    Ticker,
    flush_ring,
    pipeline_offset,
    pipeline_step,
    ring_points,
    stop_time,
)
from workcell.sim.events.loop import EventLoop, Handle
from workcell.sim.events.trace import Trace
from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.exchange import (
    DepartureRequest,
    Excursion,
    TaskEnded,
    TaskStarted,
)
from workcell.sim.protocol.messages import Leg, Piece, Station, TrajectoryEnd
from workcell.sim.protocol.records import MotionLog, TaskRecord
from workcell.sim.protocol.states import ArmState

__all__ = [
    "INTERNAL_MESSAGES",
    "ArmController",
    "Ticker",
    "pipeline_offset",
    "stop_time",
]


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
    channel : ControlChannel
        The S2.12 exchange with the coordination
        (:mod:`workcell.sim.protocol.exchange`): the controller reports its
        motion and its tasks' starts and ends there, asks before every
        departure (when ``geometry``) and takes its orders from it.
    trace : Trace
    period : float
        Sampling period, seconds (for the pipeline offset).
    ticker : Ticker, optional
        The shared tick driver when every controller tick is modelled
        (``SimOptions(tick=...)``); ``None`` at event level.
    force_threshold : float
        The wrist force sensor's free-motion threshold, newtons (S1.7).
    searches : dict of int -> tuple of InsertSearch, optional
        Per compiled mode, its insert steps' searches with the tries drawn
        (:func:`~workcell.sim.harness.simulate.simulate` with
        ``insertion="drawn"``; empty: every insertion takes its planned time).
    names : (tuple of str, tuple of str, tuple of str)
        The problem's task, zone and tool names (for the trace).
    geometry : bool
        Ask the coordination before every departure (S2.12); else set off
        without asking.

    Attributes
    ----------
    sensor : ForceSensor
        The wrist force sensor (:mod:`workcell.sim.control.force`).
    log : MotionLog
        The published motion and task records.
    """

    def __init__(
        self,
        kernel: EventLoop,
        index: int,
        arm: DriveArm,
        q0: JointVector,
        send: Callable[[int, int, str, Any], None],
        channel: ControlChannel,
        trace: Trace,
        period: float,
        ticker: Ticker | None = None,
        force_threshold: float = FREE_THRESHOLD,
        *,
        searches: dict[int, tuple[InsertSearch, ...]] | None = None,
        names: tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]] = ((), (), ()),
        geometry: bool = True,
    ) -> None:
        self.task_names, self.zone_names, self.tool_names = names
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
        self._ring = np.zeros((self.offset + 2, arm.dof))
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
        self._state_seen = ArmState.IDLE
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
        self._chunk_at = 0  # the pipeline index of the chunk's first point
        self._chunk_done = 0  # the chunk's points already in the ring
        self._pipe_i = 0
        self.away: Excursion | None = None  # where it left its leg for an excursion
        self.channel = channel
        self.geometry = bool(geometry)
        self._asked = False  # a departure request not answered yet
        self._ask = 0  # the number of the last departure request
        self._sent_key: tuple[Any, ...] | None = None  # what the last motion report said
        channel.attach_arm(index, self.take_order, self.receive)
        if ticker is not None:
            ticker.arms.append(self)
        # wrist force sensing and force-guided insertion (S1.7)
        self.sensor = ForceSensor(force_threshold)
        self.searches: dict[int, tuple[InsertSearch, ...]] = dict(searches or {})
        self.pushing = False  # thresholds raised for a search
        self._mark_h: Handle | None = None
        self._extra: search.ExtraTries | None = None  # tries made while the clock stands
        self._extra_h: Handle | None = None
        self._extra_due = 0.0

    # ------------------------------------------------------------ helpers

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
            self._extra.left = max(0.0, self._extra_due - self.kernel.now)
        self.stops.add(reason)
        if self.running:
            tau = self.current_tau()
            self._close_segment()
            self.tau = tau
            self.t_ref = self.kernel.now
            self.running = False
            self._cancel()
            self._report(True)

    def _unpause(self, reason: str) -> None:
        """End the stop ``reason``; with no stop left the arm goes on: it
        moves again, or, standing at a station, tries its pass again (the
        grants and permissions that came during the stop count)."""
        self.stops.discard(reason)
        if self._extra is not None and self._extra_h is None and self.stops == {"search"}:
            if not self.failed:
                self._extra_due = self.kernel.now + self._extra.left
                self._extra_h = self.kernel.schedule(self._extra.left, self._event, self._extra_try)
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
        if self.geometry:  # S2.12: ask; the answer (an order) sets off or holds
            self._asked = True
            self._ask += 1
            self._sent_key = self._view_key()  # the request carries the view
            self.channel.report(self.index, DepartureRequest(self.view(), self._ask))
            return
        self._depart()

    def _depart(self) -> None:
        """Set off towards station k (the departure is allowed)."""
        self._close_segment()
        self.running = True
        self.t_ref = self.kernel.now
        if self.geometry:
            # cleared: the coordination holds the whole motion reserved
            # until a later report (its arrival) acknowledges the answer
            self._sent_key = self._view_key()
        else:
            self._report(True)
        if self.ticker is not None:
            flush_ring(self)  # the points taken so far into the ring; recompute the rest
            self._chunk_i = self._chunk_done = len(self._chunk)
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
            self._request_h = self.kernel.schedule(
                t_req, self._event, self._request, st, absolute=True
            )
        self._arrive_h = self.kernel.schedule(t_reach, self._event, self._arrive, absolute=True)
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
        self.t_ref = self.kernel.now
        # reported at the end of this step (_event), unless a departure
        # request carries the view first
        self._sent_key = None
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
                self._resume_h = self.kernel.schedule(
                    st.notbefore, self._event, self._resume_at, absolute=True
                )
            return
        if self.stops:
            return
        self._leave_station(st)

    def _resource_name(self, piece: Piece) -> str:
        names = self.tool_names if piece.kind == "tool" else self.zone_names
        return names[piece.resource] if 0 <= piece.resource < len(names) else str(piece.resource)

    def _zone_event(self, kind: str, piece: Piece, task: int) -> None:
        self.trace.add(
            self.kernel.now,
            kind,
            arm=self.name,
            task=self._task_name(task),
            zone=self._resource_name(piece),
            detail=piece.kind,
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
            self.channel.report(self.index, TaskStarted(leg.task, now))
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
            self._report(True)
            return
        if leg.kind in ("return", "detour"):
            assert self.away is not None
            saved = self.away
            k, tau, at_station = saved.station, saved.tau, saved.at_station
            self.away = None
            self.leg = saved.leg
            self.k, self.tau, self.t_ref = k, tau, now
            self.at_station = at_station
            self._wait_start = now
            self._report(True)
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
                self.channel.report(self.index, TaskEnded(leg.task, now))
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

            self.kernel.schedule(seconds, self._event, homed)
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
            # where it stands goes first (its stream is in order): the
            # coordination builds the next trajectory from there
            self._report()
            if leg.kind == "task":
                cause = self._search_failure(leg)
                if cause is None:
                    self.send(self.station, 0, "trajectory_end", TrajectoryEnd(leg.task))
                else:  # the task ran but failed: told with its cause
                    self.send(
                        self.station, 0, "trajectory_end", TrajectoryEnd(leg.task, "failed", cause)
                    )

    def _start_leg(self, leg: Leg) -> None:
        if leg.kind == "task" and leg.marks is None:
            leg.searches = self.searches.get(leg.mode, ())
            leg.marks = search.marks(leg.searches)
        self._close_segment()
        self.leg = leg
        self.k = 0
        self.tau = 0.0
        self.t_ref = self.kernel.now
        self.at_station = False
        self._run()

    # ------------------------------------------------------- from the medium

    def finish(self) -> None:
        """Close the motion record at the end of the run."""
        self._close_segment()

    def is_stopped(self) -> bool:
        """Standing still (idle, at a station or paused)."""
        return not self.running

    # ------------------------------------------------------------ faults

    # --------------------------------------------------- force sensing (S1.7)

    # the published motion
    state = recording.state
    _close_segment = recording._close_segment
    _open_record = recording._open_record
    is_running = recording.is_running
    _record_state = recording._record_state

    # the S2.12 exchange and excursions
    view = excursions.view
    _report = excursions._report
    _view_key = excursions._view_key
    _event = excursions._event
    take_order = excursions.take_order
    back_off = excursions.back_off
    take_detour = excursions.take_detour
    come_back = excursions.come_back
    held_by_geometry = excursions.held_by_geometry
    release_geometry_hold = excursions.release_geometry_hold
    stuck = excursions.stuck

    # search
    crash = search.crash
    sense_crash = search.sense_crash
    _resume = search._resume
    read_force = search.read_force
    set_thresholds = search.set_thresholds
    _force_event = search._force_event
    _search_failure = search._search_failure
    _plan_mark = search._plan_mark
    _mark = search._mark
    _fire_marks = search._fire_marks
    _try_done = search._try_done
    _extra_try = search._extra_try
    _skip_to = search._skip_to
    fail = search.fail
    lose_sync = search.lose_sync
    homing_time = search.homing_time

    # pipeline
    pipeline_step = pipeline_step

    @property
    def ring(self) -> FloatArray:
        """The S2.3 ring buffer: the pipeline's last ``offset + 2`` points
        (point ``i`` at slot ``i % (offset + 2)``; zeros at event level)."""
        return ring_points(self)

    # mailbox
    internal = mailbox.internal
    _report_stop = mailbox._report_stop
    flange = mailbox.flange
    receive = mailbox.receive
    _stop_by_id = mailbox._stop_by_id
    _release_stop = mailbox._release_stop
    _withdraw = mailbox._withdraw
