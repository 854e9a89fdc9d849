"""The arm controller's side of the S2.12 exchange (its reports, the
answers and orders it takes) and its excursions and its answers to the geometric check
(S2.6, S2.12): back-offs to the home joints, alternative trajectories, the
way back, and the geometric hold (the orders of
:mod:`workcell.sim.protocol.exchange`).

Functions here are methods of :class:`~workcell.sim.control.controller.ArmController`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from workcell.arms import JointTrajectory
from workcell.sim.protocol.exchange import (
    ArmView,
    BackOff,
    ComeBack,
    Departure,
    Detour,
    Excursion,
    Fail,
    MotionReport,
    Order,
    ReleaseHold,
)
from workcell.sim.protocol.messages import Leg, Station

_Self = Any
"""The :class:`~workcell.sim.control.controller.ArmController` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.control.controller imports this module, never the reverse)."""

__all__: list[str] = []


def view(self: _Self) -> ArmView:
    """The arm's motion and standing now, as it reports them."""
    return ArmView(
        self.index,
        self.leg,
        self.k,
        self.tau,
        self.t_ref,
        self.running,
        self.q,
        self.at_station,
        "geometry" in self.stops,
        self.stuck(),
        self.away is not None,
        self.pushing,
        self.failed,
    )


def _report(self: _Self, moved: bool = False) -> None:
    """Report the view if it changed since the last report (``moved``:
    the arm started or stopped moving, reported in any case)."""
    key = self._view_key()
    if not moved and key == self._sent_key:
        return
    self._sent_key = key
    self.channel.report(self.index, MotionReport(self.view(), moved))


def _view_key(self: _Self) -> tuple[Any, ...]:
    """What a report says, to tell whether the view changed since the last one."""
    return (
        id(self.leg),
        self.k,
        self.tau,
        self.t_ref,
        self.running,
        id(self.q),
        self.at_station,
        "geometry" in self.stops,
        self.stuck(),
        self.away is not None,
        self.pushing,
        self.failed,
    )


def _event(self: _Self, callback: Callable[..., object], *args: Any) -> None:
    """Run a timed step of the controller, then report what changed."""
    callback(*args)
    self._report()


def take_order(self: _Self, order: Order) -> None:
    """An answer or an order of the coordination (S2.12, S2.6)."""
    if isinstance(order, Departure):
        if self._asked and order.ask == self._ask:
            self._asked = False
            if not order.go:
                self.stops.add("geometry")  # S2.12 "stop": released by an order
            elif not (self.stops or self.failed or self.leg is None or self.running):
                self._depart()  # reported: the report acknowledges the answer
                return
            # else a stop came since it asked: it stands, and asks again
            # when the stop is over
        # report in any case: the report acknowledges the answer, so the
        # coordination learns that the arm did not set off
        self._sent_key = None
    elif isinstance(order, ReleaseHold):
        self.release_geometry_hold()
    elif isinstance(order, Detour):
        self.take_detour(order.trajectory, order.task, order.rejoin)
    elif isinstance(order, BackOff):
        self.back_off(order.trajectory)
    elif isinstance(order, ComeBack):
        self.come_back()
    elif isinstance(order, Fail):
        self.fail()
    self._report()


def back_off(self: _Self, traj: JointTrajectory) -> bool:
    """Retreat along ``traj`` (to the home joints) out of a mover's way
    (S2.6 geometric deadlock); the coordination chose it, checked its way
    and orders the way back once the mover has passed. Returns whether the
    retreat started.

    An idle arm (no trajectory: the coordination orders this only when it
    has nothing left to do) goes home and stays there: no way back is kept,
    and a later trajectory starts from where it then stands."""
    if (
        self.away is not None
        or self.running
        or self.failed
        or self.pushing  # not out of a hole in the middle of a search
        or traj.duration <= 0
    ):
        return False
    if self.leg is None:
        self._close_segment()
        self.leg = Leg("retreat", self.pose_task, -1, traj, [Station(traj.duration, end=True)])
        self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
        self.at_station = False
        self.stops.discard("geometry")
        self.internal("STOP_D", self.pose_task, "idle in a mover's way: to the home joints")
        self._run()
        return True
    task = self.leg.task
    self._close_segment()
    self.away = Excursion(self.leg, self.k, self.tau, self.at_station)
    self.leg = Leg("retreat", task, -1, traj, [Station(traj.duration, end=True)])
    self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
    self.at_station = False
    self.stops.discard("geometry")
    self.internal("STOP_D", task, "standing in a mover's way: back off to the home joints")
    self._run()
    return True


def take_detour(self: _Self, traj: JointTrajectory, task: int, rejoin: float | None = None) -> None:
    """Go along ``traj`` instead (S2.12 alternative trajectory) to the leg
    offset ``rejoin`` (default: the next station), then on with the task
    from there.

    The stations the detour passes (before ``rejoin``) keep their zone
    reservations (S2.5): their resources are requested now and must all be
    granted before the detour sets off (not before the earliest time the
    plan lets the arm reach them), and those they give back are given back
    at its end."""
    leg = self.leg
    assert leg is not None
    k = self.k
    if rejoin is None:
        rejoin = leg.stations[k].tau
    k2 = k
    while k2 < len(leg.stations) - 1 and leg.stations[k2].tau < rejoin:
        k2 += 1
    passed = leg.stations[k:k2]
    stations = [Station(traj.duration, end=True)]
    if passed:
        for st in passed:
            self._send_requests(st)
        stations[0].release = [p for st in passed for p in st.release]
        notbefore = max(st.notbefore - (st.tau - self.tau) for st in passed)
        first = Station(
            0.0,
            notbefore=notbefore,
            acquire=[p for st in passed for p in st.acquire],
            requested=True,
        )
        stations.insert(0, first)
    self.away = Excursion(leg, k2, float(rejoin), False)
    self._close_segment()
    self.leg = Leg("detour", task, -1, traj, stations)
    self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
    self.at_station = False
    self.stops.discard("geometry")
    self._run()


def come_back(self: _Self) -> None:
    """Return from a back-off to where the arm stopped."""
    if self.away is None or self.leg is not None:
        return
    saved = self.away
    target = saved.leg.trajectory.sample(np.array([saved.tau]))[0]
    traj = self.arm.move(self.q, target, self.arm.interpolation)
    self._close_segment()
    self.leg = Leg("return", saved.leg.task, -1, traj, [Station(traj.duration, end=True)])
    self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
    self.at_station = False
    self._run()


def held_by_geometry(self: _Self) -> bool:
    """Held at its place by the coordinator's geometric check (S2.12 *stop*)."""
    return "geometry" in self.stops


def release_geometry_hold(self: _Self) -> None:
    """End the geometric hold: the arm sets off again unless it stands at
    a station (it passes when its conditions hold) or another stop holds it."""
    self.stops.discard("geometry")
    if not self.at_station and not self.stops:
        self._run()


def stuck(self: _Self) -> bool:
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
