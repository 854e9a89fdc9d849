"""The arm controller's published motion (S2.1): its state, checked against
:data:`~workcell.sim.protocol.states.ARM_MACHINE` at every change, and the
:class:`~workcell.sim.protocol.records.MotionRecord` segments of its
:class:`~workcell.sim.protocol.records.MotionLog` (the monitor's only input).

Functions here are methods of :class:`~workcell.sim.control.controller.ArmController`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

from typing import Any

from workcell.sim.protocol.records import MotionRecord
from workcell.sim.protocol.states import ARM_MACHINE, ArmState

_Self = Any
"""The :class:`~workcell.sim.control.controller.ArmController` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.control.controller imports this module, never the reverse)."""

__all__: list[str] = []


def state(self: _Self) -> ArmState:
    """The controller's state (:class:`~workcell.sim.protocol.states.ArmState`)."""
    if self.failed:
        return ArmState.FAILED
    if self.leg is None:
        return ArmState.IDLE
    if self.running:
        return ArmState.MOVING
    return ArmState.AT_STATION if self.at_station else ArmState.STOPPED


def _close_segment(self: _Self) -> None:
    """End the current motion record at now (every change of the arm's
    motion closes one: its state is checked against the arm machine)."""
    st = self.state()
    ARM_MACHINE.check(self._state_seen, st)
    self._state_seen = st
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


def _open_record(self: _Self, now: float) -> MotionRecord:
    """The motion record in progress, as it would be closed at ``now``."""
    leg = self.leg
    t0 = self._seg_t0
    if leg is None:
        return MotionRecord(t0, now, None, 0.0, False, self.q)
    tau0 = self.tau + (t0 - self.t_ref) if self.running else self.tau
    return MotionRecord(t0, now, leg, tau0, self.running, self.sync_error)


def is_running(self: _Self) -> bool:
    """The trajectory clock runs."""
    return bool(self.running)


def _record_state(self: _Self) -> tuple[Any, ...]:
    """What the record in progress depends on (equal: the same record)."""
    leg = self.leg
    n = len(self.log.tasks)
    if leg is None:
        return (self._seg_t0, 0, False, 0.0, n, self.failed, self.q.tobytes())
    running = self.running
    tau0 = self.tau + (self._seg_t0 - self.t_ref) if running else self.tau
    return (self._seg_t0, id(leg), running, tau0, n, self.failed, self.sync_error.tobytes())
