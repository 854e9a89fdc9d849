"""Each arm's geometric check under distributed coordination (S2.6, S2.12).

Before an arm sets off towards its next station, its peer checks that
motion against the other arms' motion and positions (the
:class:`~workcell.sim.coordination.guard.GeometryGuard` of the centralized
coordinator, asked and answered like it on the control channel,
:mod:`workcell.sim.protocol.exchange`, from the book of the arms' motion
reports): a contact holds the arm at its station. Held arms check again
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
from workcell.sim.coordination.geometric import (
    back_off,
    blockers,
    check_departure,
    on_report,
)
from workcell.sim.protocol.exchange import BackOffUntil, ComeBack, Detour, ReleaseHold

_Self = Any
"""The :class:`~workcell.sim.coordination.distributed.policy.DistributedPolicy`
these functions are methods of (typed loosely: that module imports this one)."""

# the arm's own check before it sets off, the book and the back-off order:
# the centralized coordinator's
__all__ = ["back_off", "blockers", "check_departure", "on_report"]


def arm_moved(self: _Self) -> None:
    """Something moved or stopped: the held arms check again (at
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
    for a in range(self.p.n_arms):
        ctl = self.book[a]
        if ctl.failed:
            continue
        until = self.away_until.get(a)
        if ctl.away and ctl.leg is None and until is not None:
            mover = self.book[until.mover]
            passed = mover.leg is not until.leg and not mover.away
            waits = mover.waiting and not mover.held
            if mover.failed or passed or waits:
                del self.away_until[a]
                self.channel.order(a, ComeBack())
        if not self.book[a].held:
            continue
        self.channel.order(a, ReleaseHold())
        if self.book[a].held and try_detour(self, a):
            continue
        ctl = self.book[a]
        blockers = self.geo_held.get(a, [])
        if (
            not ctl.held
            or not blockers
            or self.backoffs >= self.max_backoffs
            or not all(self.book[b].waiting and not self.book[b].away for b in blockers)
        ):
            continue
        for b in blockers:
            if back_off(self, b, BackOffUntil(a, ctl.leg, ctl.k)):
                self.backoffs += 1
                self.detours += 1
                self.trace.add(
                    self.kernel.now,
                    "detour",
                    arm=self.p.arm_names[b],
                    detail=f"geometric deadlock (S2.6): backs off to its home joints "
                    f"out of arm {self.p.arm_names[a]!r}'s way",
                )


def try_detour(self: _Self, a: int) -> bool:
    """S2.12 "continue with alternative trajectory": an OMPL path to the
    next station around the arms standing in the way (tried once per
    station; work-limited, so the same seed plans the same path). There is
    no re-solve under this policy: a detour longer than planned only delays."""
    ctl = self.book[a]
    now = self.kernel.now
    leg = ctl.leg
    blockers = self.geo_held.get(ctl.index, [])
    if (
        not self.detours_on
        or leg is None
        or leg.kind != "task"
        or ctl.away
        or not blockers
        or any(self.book[b].running for b in blockers)
    ):
        return False
    key = (ctl.index, id(leg), ctl.k)
    if key in self.detour_tried:
        return False
    self.detour_tried.add(key)
    arm = self.cc.cell.arms[a]
    qa = ctl.position(now)
    qb = leg.trajectory.sample(np.array([leg.stations[ctl.k].tau]))[0]
    items: list[Any] = []
    for b in blockers:
        other = self.book[b]
        items.extend(ObstacleSet.from_arm(self.cc.cell.arms[b], other.position(now)).items)
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
        arm=self.p.arm_names[a],
        task=self.p.task_names[leg.task],
        delay=extra,
        detail=f"alternative trajectory around arm(s) "
        f"{', '.join(repr(self.p.arm_names[b]) for b in blockers)} (S2.12): "
        f"{extra:+.6g} s",
    )
    self.channel.order(a, Detour(traj, leg.task))
    return True
