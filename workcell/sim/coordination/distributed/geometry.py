"""Each arm's geometric check under distributed coordination (S2.6, S2.12).

Before an arm sets off towards its next station, its peer checks that
motion against the other arms' motion and positions (the
:class:`~workcell.sim.coordination.guard.GeometryGuard` of the centralized
coordinator, modelled like it as answered at the same instant through the
arms' ports): a contact holds the arm at its station. Held arms check again
whenever an arm starts or stops. Around arms that stand in the way the peer
tries an alternative trajectory (an OMPL detour to the next station,
work-limited and seeded); failing that, when every arm in the way stands
waiting for something else (a geometric deadlock), those arms back off to
their home joints and come back once the held arm has passed.

Functions here are methods of
:class:`~workcell.sim.coordination.distributed.policy.DistributedPolicy`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from workcell.geometry import ObstacleSet, plan_detour
from workcell.sim.coordination.geometric import check_departure
from workcell.sim.protocol.ports import ArmPort

_Self = Any
"""The :class:`~workcell.sim.coordination.distributed.policy.DistributedPolicy`
these functions are methods of (typed loosely: that module imports this one)."""

__all__ = ["check_departure"]  # the arm's own check before it sets off: the centralized one


def check_way(self: _Self, ctl: ArmPort) -> bool:
    """Port: is the arm's way to its next station free?"""
    assert self.guard is not None
    return not self.guard.blockers(ctl, self.arms)


def arm_moved(self: _Self) -> None:
    """Port: something moved or stopped: the held arms check again (at
    most ``recheck_limit`` passes at one instant, then one guard period
    later, at most ``max_stalled`` times with no task starting or ending)."""
    if self._recheck_h is not None:
        return
    now = self.kernel.now
    if now != self._recheck_at:
        self._recheck_at, self._recheck_n = now, 0
    self._recheck_n += 1
    delay = 0.0
    if self._recheck_n > self.recheck_limit:
        if self.stalled >= self.max_stalled:
            return
        self.stalled += 1
        delay = self.guard.dt if self.guard is not None else 0.01
    self._recheck_h = self.kernel.schedule(delay, self._recheck, priority=1)


def recheck(self: _Self) -> None:
    """The held arms check again; an arm held by arms that all stand
    waiting for something else (a geometric deadlock, S2.6) has them back
    off to their home joints, and they come back once it has passed."""
    self._recheck_h = None
    for ctl in self.arms:
        if ctl.failed:
            continue
        if ctl.away is not None and ctl.leg is None and ctl.away_until is not None:
            ai, leg_a, _k = ctl.away_until
            mover = self.arms[ai]
            passed = mover.leg is not leg_a and mover.away is None
            waits = mover.stuck() and not mover.held_by_geometry()
            if mover.failed or passed or waits:
                ctl.come_back()
        if not ctl.held_by_geometry():
            continue
        ctl.release_geometry_hold()
        if ctl.held_by_geometry() and try_detour(self, ctl):
            continue
        blockers = self.geo_held.get(ctl.index, [])
        if (
            not ctl.held_by_geometry()
            or not blockers
            or self.backoffs >= self.max_backoffs
            or not all(self.arms[b].stuck() and self.arms[b].away is None for b in blockers)
        ):
            continue
        for b in blockers:
            if self.arms[b].back_off((ctl.index, ctl.leg, ctl.k)):
                self.backoffs += 1
                self.detours += 1
                self.trace.add(
                    self.kernel.now,
                    "detour",
                    arm=self.p.arm_names[b],
                    detail=f"geometric deadlock (S2.6): backs off to its home joints "
                    f"out of arm {ctl.name!r}'s way",
                )


def try_detour(self: _Self, ctl: ArmPort) -> bool:
    """S2.12 "continue with alternative trajectory": an OMPL path to the
    next station around the arms standing in the way (tried once per
    station; work-limited, so the same seed plans the same path). There is
    no re-solve under this policy: a detour longer than planned only delays."""
    leg = ctl.leg
    blockers = self.geo_held.get(ctl.index, [])
    if (
        not self.detours_on
        or leg is None
        or leg.kind != "task"
        or ctl.away is not None
        or not blockers
        or any(self.arms[b].running for b in blockers)
    ):
        return False
    key = (ctl.index, id(leg), ctl.k)
    if key in self.detour_tried:
        return False
    self.detour_tried.add(key)
    arm = ctl.arm
    qa = ctl.position()
    qb = leg.trajectory.sample(np.array([leg.stations[ctl.k].tau]))[0]
    items: list[Any] = []
    for b in blockers:
        other = self.arms[b]
        items.extend(ObstacleSet.from_arm(other.arm, other.position()).items)
    res = plan_detour(
        arm,
        qa,
        qb,
        ObstacleSet(items, name="standing arms"),
        budget=60.0,
        seed=self.seed,
        resolution=0.01,
        clearance=0.02,
        max_checks=self.detour_checks,
    )
    if not res.solved:
        return False
    traj = arm.time_path(res.path, "sync")
    extra = traj.duration - (leg.stations[ctl.k].tau - ctl.tau)
    self.detours += 1
    self.trace.add(
        self.kernel.now,
        "detour",
        arm=ctl.name,
        task=self.p.task_names[leg.task],
        delay=extra,
        detail=f"alternative trajectory around arm(s) "
        f"{', '.join(repr(self.p.arm_names[b]) for b in blockers)} (S2.12): "
        f"{extra:+.6g} s",
    )
    ctl.take_detour(traj, leg.task)
    return True
