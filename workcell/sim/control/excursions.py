"""The arm controller's excursions and its answers to the geometric check
(S2.6, S2.12): back-offs to the home joints, alternative trajectories, the
way back, and what the coordinator's check reads (predicted motion, holds).

Functions here are methods of :class:`~workcell.sim.control.controller.ArmController`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from multiarm.types import FloatArray
from workcell.arms import JointTrajectory
from workcell.sim.protocol.messages import Leg, Station

_Self = Any
"""The :class:`~workcell.sim.control.controller.ArmController` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.control.controller imports this module, never the reverse)."""

__all__: list[str] = []


def back_off(self: _Self, until: tuple[int, Any, int]) -> bool:
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
    self.away = (leg, k2, float(rejoin), False)
    self.away_until = None
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
    saved_leg, _k, tau, _st = self.away
    target = saved_leg.trajectory.sample(np.array([tau]))[0]
    traj = self.arm.move(self.q, target, self.arm.interpolation)
    self.away_until = None
    self._close_segment()
    self.leg = Leg("return", saved_leg.task, -1, traj, [Station(traj.duration, end=True)])
    self.k, self.tau, self.t_ref = 0, 0.0, self.kernel.now
    self.at_station = False
    self._run()


def predict(self: _Self, times: FloatArray) -> FloatArray:
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
    out: FloatArray = leg.trajectory.sample(taus)
    return out


def next_stop_time(self: _Self) -> float:
    """When the arm reaches its next station if it moves now (seconds)."""
    leg = self.leg
    if leg is None:
        return float(self.kernel.now)
    return float(self.kernel.now + max(0.0, leg.stations[self.k].tau - self.current_tau()))


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
