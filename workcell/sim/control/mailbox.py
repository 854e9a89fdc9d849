"""The arm controller's communication processor (S2.3): frames from the
coordinator turned into the internal messages ``TRAJECTORY``, ``STOP_C`` and
``CONTINUE``; stops matched by id with their releases; withdrawals.

Functions here are methods of :class:`~workcell.sim.control.controller.ArmController`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

from typing import Any

from workcell.sim.protocol.messages import (
    ActivationGo,
    ActivationStop,
    AlarmClear,
    PositionReport,
    StartPermit,
    TrajectoryEnd,
    Withdraw,
)

_Self = Any
"""The :class:`~workcell.sim.control.controller.ArmController` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.control.controller imports this module, never the reverse)."""

__all__: list[str] = []


def receive(self: _Self, kind: str, payload: Any) -> None:
    """A frame from the coordinator (already delivered by the medium); what
    it changed is reported on the control channel."""
    _receive(self, kind, payload)
    self._report()


def _receive(self: _Self, kind: str, payload: Any) -> None:
    if self.failed:
        return
    if kind == "trajectory":
        legs = payload.legs
        self.internal("TRAJECTORY", legs[-1].task)
        if payload.permit:
            self.permit.add(legs[-1].task)
        self.busy = True
        self.legs.extend(legs)
        if self.leg is None:
            self._start_leg(self.legs.pop(0))
    elif kind in ("zone_grant", "wake_up"):
        if isinstance(payload, StartPermit):
            self.permit.add(payload.task)
        elif isinstance(payload, AlarmClear):
            self.internal("CONTINUE", detail="alarm cleared")
            self._release_stop(f"alarm#{payload.stop}")
            return
        elif isinstance(payload, ActivationGo):
            self._release_stop(f"activation#{payload.stop}")
            return
        else:  # a Piece
            self.granted.add(payload)
        if kind == "wake_up":
            self.internal("CONTINUE")
        self._try_pass()
    elif kind == "sleep":
        if isinstance(payload, ActivationStop):
            self.internal("STOP_C", detail="zone activation: stop")
            self._stop_by_id(f"activation#{payload.stop}")
            self._report_stop()
            self.send(self.station, 0, "position", PositionReport(None, self.flange()))
        elif isinstance(payload, Withdraw):
            self._withdraw(payload.task)
        else:
            self.internal("STOP_C", detail="zone not available: stop at its border")
    elif kind == "alarm":
        self.internal("STOP_C", detail="emergency broadcast")
        self._stop_by_id(f"alarm#{payload.stop}")
        self._report_stop()
    elif kind == "active_zone_grant":
        pass


def _stop_by_id(self: _Self, stop: str) -> None:
    """A coordinator's stop (``"alarm#<id>"``, ``"activation#<id>"``): in
    force until the release with the same id (a release that overtook
    its stop on the medium cancels it in advance)."""
    if stop in self.released_stops:
        return
    self._pause(stop)


def _release_stop(self: _Self, stop: str) -> None:
    """The release of the coordinator's stop ``stop`` (matched by id)."""
    self.released_stops.add(stop)
    self._unpause(stop)


def _withdraw(self: _Self, t: int) -> None:
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
    self.granted = {g for g in self.granted if g.task != t}  # given back by the coordinator
    if self.leg is None:
        self.busy = False
        self._seg_t0 = self.kernel.now
        self._report()  # where it stands goes first: the next trajectory starts there
        self.send(self.station, 0, "trajectory_end", TrajectoryEnd(t, "withdrawn"))


def internal(self: _Self, message: str, task: int = -1, detail: str = "") -> None:
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


def _report_stop(self: _Self) -> None:
    """Tell the coordinator where it stopped when inside a shared zone (S2.7)."""
    held = sorted(p for p in self.granted if p.kind == "move")
    for p in held:
        self.send(self.station, 0, "position", PositionReport(p, self.flange()))


def flange(self: _Self) -> tuple[float, float, float]:
    """Flange position now (metres)."""
    q = self.position()
    x = self.arm.fk(q[None])[0][:3, 3]
    return (float(x[0]), float(x[1]), float(x[2]))
