"""The centralized coordinator's geometric conflicts (S2.6, S2.12): the check
before every departure, alternative trajectories, back-offs and promotions.

Everything here reads the coordinator's own book of the arms
(``Coordinator.book``: the last :class:`~workcell.sim.protocol.exchange.ArmView`
each arm reported) and acts by orders on the control channel
(:mod:`workcell.sim.protocol.exchange`), never on a controller.

Functions here are methods of :class:`~workcell.sim.coordination.centralized.Coordinator`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from workcell.geometry import DetourPlanner, ObstacleSet
from workcell.sim.protocol.exchange import (
    ArmView,
    BackOff,
    BackOffUntil,
    ComeBack,
    Departure,
    DepartureRequest,
    Detour,
    MotionReport,
    ReleaseHold,
    Report,
    TaskEnded,
    TaskStarted,
)
from workcell.sim.protocol.messages import Leg, Station
from workcell.sim.protocol.states import TaskState

_Self = Any
"""The :class:`~workcell.sim.coordination.centralized.Coordinator` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.coordination.centralized imports this module, never the reverse)."""

__all__ = ["blockers", "check_departure", "initial_book", "on_report", "reserved"]


def initial_book(compiled: Any) -> list[ArmView]:
    """Every arm standing idle at its start joints (before any report)."""
    return [
        ArmView(a, None, 0, 0.0, 0.0, False, np.array(q, dtype=float))
        for a, q in enumerate(compiled.cell.start)
    ]


def on_report(self: _Self, a: int, report: Report, taken: int = -1) -> None:
    """A record from arm ``a`` (``taken``: the number of the last frame
    from the coordination it had taken when it sent it): its view goes into
    the book, and the motions cleared for it that it has acknowledged
    leave the book's reservations (:func:`reserved`); a departure request is
    answered (S2.12); task notices."""
    if self.cleared[a] and taken >= 0:
        left = [(seq, v) for seq, v in self.cleared[a] if seq > taken]
        if len(left) < len(self.cleared[a]):
            self.cleared[a] = left
            self.arm_moved()  # space freed: the held arms look again
    if isinstance(report, MotionReport):
        view = report.view
        self.book[a] = view
        if view.failed and a in self.failing:
            self.arm_out(a)
        if self.guard is not None and (self.geo_held or self.away_until):
            self.arm_moved()  # what the held and backed-off arms wait for may be over
    elif isinstance(report, DepartureRequest):
        self.book[a] = report.view
        go = self.guard is None or self.check_departure(report.view)
        if go and self.guard is not None:
            # reserved from now until the arm's report acknowledges the answer
            seq = self.channel.next_order(a)
            self.cleared[a].append((seq, report.view.as_running()))
        self.channel.order(a, Departure(go, report.ask))
    elif isinstance(report, TaskStarted):
        self.task_started(a, report.task, report.time)
    elif isinstance(report, TaskEnded):
        self.task_ended(a, report.task, report.time)


def reserved(self: _Self, a: int) -> list[ArmView]:
    """The motions the coordination cleared for arm ``a`` whose start or
    end it has not heard of yet (each a view moving from where the arm
    asked; :meth:`~workcell.sim.coordination.guard.GeometryGuard.blockers`
    checks them whatever the time)."""
    return [v for _seq, v in self.cleared[a]]


def blockers(self: _Self, mover: ArmView) -> list[int]:
    """The guard's answer for ``mover`` against the book (``mover`` in
    its arm's place) and the motions cleared and not yet acknowledged."""
    assert self.guard is not None
    book = list(self.book)
    book[mover.index] = mover
    extra = [v for b, cl in enumerate(self.cleared) if b != mover.index for _s, v in cl]
    out: list[int] = self.guard.blockers(mover, book, extra)
    return out


def check_departure(self: _Self, ctl: ArmView) -> bool:
    """S2.12: may the arm of ``ctl`` set off towards its next station?
    (*continue*; else *stop*, and the arms in its way are recorded.)"""
    blockers = self.blockers(ctl)
    a = ctl.index
    if not blockers:
        if a in self.geo_held:
            del self.geo_held[a]
            self.trace.add(
                self.kernel.now,
                "wake",
                arm=self.p.arm_names[a],
                detail="geometric conflict over: go on",
            )
        return True
    if self.geo_held.get(a) != blockers:
        names = ", ".join(repr(self.p.arm_names[b]) for b in blockers)
        self.trace.add(
            self.kernel.now,
            "sleep",
            arm=self.p.arm_names[a],
            task=self.p.task_names[ctl.leg.task] if ctl.leg is not None else "",
            detail=f"geometric conflict (S2.12): arm {names} in the way: stop",
        )
        self.geo_held[a] = blockers
        self.arm_moved()
    return False


def try_detour(self: _Self, a: int) -> bool:
    """S2.12 "continue with alternative trajectory": an OMPL path around the
    arms standing in the way (tried once per station; work-limited, so the
    same seed plans the same path).

    The path starts where the arm stands and ends at its next station, or,
    when that station lies inside the stretch of the motion that touches
    the standing arms (a zone border of the space grid can), at the first
    pose of the leg after that stretch: the detour then passes the stations
    in between, whose resources the arm holds for the whole detour
    (:class:`~workcell.sim.protocol.exchange.Detour`), as the
    compile's oracle plans it from the knot before the contact to the knot
    after it."""
    ctl = self.book[a]
    now = self.kernel.now
    leg = ctl.leg
    blockers = self.geo_held.get(ctl.index, [])
    if (
        not self.detour_planning
        or leg is None
        or leg.kind != "task"
        or ctl.away
        or not blockers
        or any(self.book[b].running or self.cleared[b] for b in blockers)
    ):
        return False
    key = (ctl.index, id(leg), ctl.k)
    if key in self.detour_tried:
        return False
    self.detour_tried.add(key)
    arm = self.cc.cell.arms[a]
    qa = ctl.position(now)
    items: list[Any] = []
    for b in blockers:
        other = self.book[b]
        items.extend(ObstacleSet.from_arm(self.cc.cell.arms[b], other.position(now)).items)
    ctx = DetourPlanner(
        arm, ObstacleSet(items, name="standing arms"), resolution=0.01, clearance=0.02
    )
    rejoin = _rejoin(ctx, leg, float(leg.stations[ctl.k].tau))
    if rejoin is None:  # a pose the task must pass touches them: no way around
        return False
    passed = [st for st in leg.stations[ctl.k :] if st.tau < rejoin]
    if not all(self._grantable(piece) for st in passed for piece in st.acquire):
        # the zones of the stations it would pass are not all free in plan
        # order: holding some while waiting for others could deadlock; try
        # again at the next look (after something moved)
        self.detour_tried.discard(key)
        return False
    qb = leg.trajectory.sample(np.array([rejoin]))[0]
    res = ctx.plan(qa, qb, budget=60.0, seed=self.seed, max_checks=self.detour_checks)
    if not res.solved:  # "direct" (the straight joint move is free) or "solved"
        return False
    traj = arm.time_path(res.path, "sync")
    extra = traj.duration - (rejoin - ctl.tau)
    self.detours += 1
    self.trace.add(
        self.kernel.now,
        "detour",
        arm=self.p.arm_names[a],
        task=self.p.task_names[leg.task],
        delay=extra,
        detail=f"alternative trajectory around arm(s) "
        f"{', '.join(repr(self.p.arm_names[b]) for b in blockers)} (S2.12): "
        f"{extra:+.6g} s"
        + (f", past {len(passed)} station(s) to offset {rejoin:.6g} s" if passed else ""),
    )
    self.channel.order(a, Detour(traj, leg.task, rejoin))
    if extra > float(self.plan.blocking[leg.task]) + 1e-9:
        self.resolve(f"detour of task {self.p.task_names[leg.task]!r} costs more than planned")
    return True


def _rejoin(ctx: DetourPlanner, leg: Leg, tau: float, step: float = 0.01) -> float | None:
    """Where a detour towards the station at leg offset ``tau`` rejoins the
    leg: that station when its pose is clear of the standing arms, else the
    first clear pose after it (sampled every ``step`` seconds of the leg, and
    at its knots). ``None`` when a knot of the trajectory touches them first
    (as for the compile's oracle: the task must pass through that pose, no
    detour can avoid it) or the leg never clears them again."""
    end = float(leg.stations[-1].tau)
    knots = np.asarray(leg.trajectory.knot_times, dtype=float)
    knots = knots[(knots > tau) & (knots <= end)]
    taus = np.union1d(np.append(np.arange(tau, end, step), end), knots)
    is_knot = np.isin(taus, knots)
    qs = leg.trajectory.sample(taus)
    for t, q, knot in zip(taus.tolist(), qs, is_knot.tolist(), strict=True):
        if ctx.is_valid(q):
            return float(t)
        if knot:
            return None
    return None


def back_off(self: _Self, b: int, until: BackOffUntil) -> bool:
    """Order arm ``b`` back to its home joints out of a mover's way (S2.6)
    if it can go (standing on a leg, not pushing, not already away) and
    its way home is free. Returns whether it was ordered."""
    v = self.book[b]
    idle = done_for_good(self, b)
    if v.away or v.running or v.failed or v.pushing or self.cleared[b]:
        return False
    if v.leg is None and not idle:
        return False
    arm = self.cc.cell.arms[b]
    home = np.asarray(self.cc.cell.start[b], dtype=float)
    traj = arm.move(v.position(self.kernel.now), home, arm.interpolation)
    if traj.duration <= 0:
        return False
    task = v.leg.task if v.leg is not None else -1
    retreat = Leg("retreat", task, -1, traj, [Station(traj.duration, end=True)])
    probe = ArmView(b, retreat, 0, 0.0, v.t_ref, False, v.q, v.at_station)
    if self.blockers(probe):  # the way back home is not free either
        return False
    self.channel.order(b, BackOff(traj))
    if not idle:  # an idle arm stays home: nothing to come back to
        self.away_until[b] = until
    return True


def done_for_good(self: _Self, b: int) -> bool:
    """Arm ``b`` stands idle with nothing left to do: no trajectory, and
    every task the plan gives it done or failed (a part that never came, a
    predecessor that failed). Such an arm may stand where the plan had it
    move on, in another arm's way: it is sent home (S2.6)."""
    v = self.book[b]
    if v.leg is not None or v.running or v.failed or v.away or self.cleared[b]:
        return False
    arm_of = self.p.mode_arm[self.plan.mode]
    return all(
        self.status[t] in (TaskState.DONE, TaskState.FAILED)
        for t in np.flatnonzero(arm_of == b).tolist()
    )


def arm_moved(self: _Self) -> None:
    """Look at the geometric stops again (after something moved or stopped),
    throttled by the coordinator's :class:`~workcell.sim.coordination.
    throttle.Throttle` (``self.recheck``): at most ``recheck_limit`` passes
    at one instant, then one guard period later, and after ``max_stalled``
    such deferred passes with no task starting or ending the arms still
    stopped stay stopped (an unresolved geometric deadlock, reported per
    task)."""
    self.recheck.poke()


def _recheck(self: _Self) -> None:
    """The backed-off arms come back once their mover has passed; each arm
    told *stop* is checked again from the book: a clear way ends its hold
    (:class:`~workcell.sim.protocol.exchange.ReleaseHold`: it asks again
    before it sets off); else an alternative trajectory, a back-off of the
    arms in its way, or a promotion (S2.6)."""
    for a in range(self.p.n_arms):
        ctl = self.book[a]
        if ctl.failed:
            self.geo_held.pop(a, None)
            continue
        until = self.away_until.get(a)
        if ctl.away and ctl.leg is None and until is not None:
            mover = self.book[until.mover]
            # back once the mover has finished that task (its leg is over
            # and it is not on an excursion from it), or waits for a grant
            passed = mover.leg is not until.leg and not mover.away
            waits = mover.waiting and not mover.held
            if mover.failed or passed or waits:
                del self.away_until[a]
                self.channel.order(a, ComeBack())
        if a not in self.geo_held:
            continue
        found = self.blockers(ctl)
        if not found:
            del self.geo_held[a]
            self.trace.add(
                self.kernel.now, "wake", arm=self.p.arm_names[a], detail="geometric conflict over"
            )
            self.channel.order(a, ReleaseHold())
            continue
        self.geo_held[a] = found
        if self.try_detour(a):
            del self.geo_held[a]  # it asks again before it sets off on the detour
            continue
        if (
            self.backoffs < self.max_backoffs
            and ctl.leg is not None
            and all(
                (self.book[b].waiting or done_for_good(self, b))
                and not self.book[b].away
                and not self.cleared[b]
                for b in found
            )
        ):
            moved = False
            for b in found:
                if self.back_off(b, BackOffUntil(a, ctl.leg, ctl.k)):
                    moved = True
                    self.backoffs += 1
                    self.detours += 1
                    self.trace.add(
                        self.kernel.now,
                        "detour",
                        arm=self.p.arm_names[b],
                        detail=f"geometric deadlock (S2.6): backs off to its home joints "
                        f"out of arm {self.p.arm_names[a]!r}'s way",
                    )
            if not moved:
                self._promote(a, found)


def _promote(self: _Self, a: int, blockers: list[int]) -> None:
    """Last resort of a geometric deadlock: an arm standing in ``a``'s way
    waits for a resource the plan gives ``a`` first, and cannot back off;
    let it go first (``a`` has not taken that resource yet)."""
    for b in blockers:
        if not self.pending[b] or self.zm_wait[b] is not None:
            continue
        piece = self.pending[b][0]
        order = self.orders.get((piece.kind, piece.resource), [])
        if piece not in order:
            continue
        i = order.index(piece)
        ahead = [q for q in order[:i] if q not in self.released]
        if not ahead or any(q in self.held for q in ahead):
            continue
        order.remove(piece)
        order.insert(order.index(ahead[0]), piece)
        self.trace.add(
            self.kernel.now,
            "grant",
            arm=self.p.arm_names[b],
            task=self.p.task_names[piece.task] if piece.task >= 0 else "",
            zone=self._zone_name(piece),
            detail=f"geometric deadlock (S2.6): goes before arm {self.p.arm_names[a]!r}",
        )
        self._serve(b)
