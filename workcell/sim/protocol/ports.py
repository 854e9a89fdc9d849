"""The arm port: the coordinator's geometric view of an arm (S2.6, S2.12).

Coordination and control exchange messages through the medium
(:mod:`workcell.sim.comms.link`). One exchange is not modelled as frames:
S2.12's geometric check. Before an arm sets off towards its next station,
the coordinator checks that motion against the trajectories it sent and the
positions it was told, and answers *stop*, *continue* or *continue with an
alternative trajectory*; the simulator asks and answers at the same instant
(a check modelled as free of delay and loss). :class:`ArmPort` is the typed
surface of that exchange: what the coordinator may read of an arm's motion
and the excursions it may order. The coordination layer sees arms only
through it and never imports :mod:`workcell.sim.control`.
"""

from __future__ import annotations

from typing import Any, Protocol

from multiarm.types import FloatArray
from workcell.arms import DriveArm, JointTrajectory
from workcell.sim.protocol.messages import Leg

__all__ = ["ArmPort", "Excursion"]

Excursion = tuple[Leg, int, float, bool]
"""Where an arm left its leg for an excursion: ``(leg, station, tau, at_station)``."""


class ArmPort(Protocol):
    """What the coordinator's geometric check reads of an arm and may order."""

    index: int
    name: str
    arm: DriveArm
    leg: Leg | None
    k: int
    tau: float
    q: FloatArray
    running: bool
    failed: bool
    at_station: bool
    away: Excursion | None
    away_until: tuple[int, Any, int] | None

    def position(self) -> FloatArray:
        """Commanded joints now."""

    def predict(self, times: FloatArray) -> FloatArray:
        """(N, dof) joints at future ``times`` if the arm goes on to its next station."""

    def next_stop_time(self) -> float:
        """When the arm reaches its next station if it moves now."""

    def stuck(self) -> bool:
        """Standing and waiting on something other than the clock."""

    def held_by_geometry(self) -> bool:
        """Held at its place by the geometric check (S2.12 *stop*)."""

    def release_geometry_hold(self) -> None:
        """End the geometric hold: the arm goes on unless another stop holds it."""

    def back_off(self, until: tuple[int, Any, int]) -> bool:
        """Retreat to the home joints out of a mover's way (S2.6)."""

    def take_detour(self, traj: JointTrajectory, task: int, rejoin: float | None = None) -> None:
        """Go along ``traj`` (S2.12 alternative trajectory) to the leg offset
        ``rejoin`` (default: the next station), keeping the reservations of
        the stations it passes."""

    def come_back(self) -> None:
        """Return from a back-off."""

    def fail(self) -> None:
        """The arm fails for good."""
