"""Each peer's own sight of the arms and its departure check (S2.6, S2.12).

Under distributed coordination a peer knows the other arms only from the
frames it takes on the medium; nothing is shared between peers.

* **Who talks to whom.** Every peer derives, from the compiled cell every
  station holds, the arms that may ever meet its own (:func:`~.reach.may_meet`:
  two arms whose workspace balls overlap; a ball holds every pose the arm
  can take within its joint limits). It tells only those arms where its
  arm is and asks only them before it sets off. On a medium whose
  broadcast is one transfer that every station hears (the serial bus,
  Multibus II, Ethernet and CSMA/DCR, and the ideal and fixed-latency
  media: :attr:`~workcell.sim.comms.medium.BaseMedium.broadcast_once`)
  the view and the request go out once, as a broadcast, instead of one
  frame per such arm; a peer that hears a broadcast from an arm that cannot
  meet its own does not read it. The answers stay point to point. On the
  serial star, whose hub relays a broadcast on every line, one frame goes
  to each arm.
* **Its own check.** Each peer has its own
  :class:`~workcell.sim.coordination.guard.GeometryGuard` (built from the
  compiled cell every station holds; its caches are its own).
* **Its own view.** :class:`Sight` keeps one
  :class:`~workcell.sim.protocol.exchange.ArmView` per arm: its own arm's
  from its controller's reports at the station, the others' from the
  frames they send (:class:`~workcell.sim.protocol.peers.PeerView`, and the
  views carried by requests and answers). Frames between peers are not
  kept in order by the link (a retransmitted one may be overtaken), so
  each carries its sender's count and the view of the highest count is
  kept.
* **The departure check** is a per-departure mutual exclusion among the
  arms that may meet, in the style of Ricart and Agrawala. When its
  controller asks whether the arm may set off, the peer sends a
  :class:`~workcell.sim.protocol.peers.Clearance` with the motion and a
  Lamport time to every such arm and waits for every answer
  (:class:`~workcell.sim.protocol.peers.ClearanceReply`). A peer answers at
  once, unless it is asking itself with a lower ``(clock, arm)``: then it
  answers once it has decided its own departure. An answer carries where
  the answering arm is (standing, or moving up to its next station) and is
  a *reservation*: from then on the answering peer counts the asked motion
  as under way (anywhere from where the asker stood to its next station)
  in its own checks, until a frame of the asker sent after it decided that
  request says its arm stands. With every answer in, the asker checks the
  motion (:class:`~workcell.sim.coordination.guard.GeometryGuard`, time
  free, as the centralized coordinator) against its view and the motions
  it reserved for others, and answers its controller *continue* or *stop*.

  Why it is sound: the argument below needs only that every arm that may
  meet the asker takes the request (once: the link drops a duplicate) and
  answers it, and that the asker decides only with every answer in; a
  broadcast request is the same record taken by the same peers as the
  frames one per arm (a lost broadcast is sent again whole), so the
  argument holds for both. Take two motions of arms A and B that overlap in time.
  A set off only after B's answer, B only after A's. If B decided its
  departure before it answered A, the answer showed B moving on that
  motion, and A's check saw it. Otherwise B answered A first, and so held
  A's motion reserved when it decided, unless A's report that it stands
  had come: then A's motion was over, and a later one of A needed B's
  answer again (B asking with a lower clock defers it until B decided, so
  A sees B moving; else B answers and reserves it before B decides). An
  arm stopped on the way (a crash, an alarm) stands inside the stretch
  already reserved and asks again before it goes on. Two arms asking at
  once are ordered by the clock: the first decides against the other's
  standing pose, the second against the first one's motion, so they never
  both set off into each other, and never both hold each other back.
* **Why every asked arm answers.** An answer is not only consent: it is
  the point after which the answering peer holds the motion reserved, and
  the asker cannot tell a peer that took the request and saw no conflict
  from one that has not taken it yet (frames are delayed, lost and sent
  again with no bound known to the asker). Letting a silent peer count as
  consenting would let the asker set off while the request is still on its
  way to a peer that then sets off into it, so every asked peer answers.
  Asking fewer arms per departure (the arms whose *remaining* planned
  motions can meet the asked one) is not sound either: a detour (an OMPL
  path anywhere within the joint limits) and a back-off to the home joints
  leave the planned motions, so only the workspace bound of
  :func:`~.reach.may_meet` holds for every motion an arm can make. Asking
  only the arms whose workspace ball meets the box of the asked motion
  would be sound, but on the built-in cells it asks the same arms: every
  task trajectory's box meets every other arm's ball on ``cell8``,
  ``scara4`` and ``urdf_cell``.
* **Held arms** are looked at again when a frame says another arm started,
  stopped or failed, or a reservation ended (watch and notify): a clear
  way ends the hold (the controller asks again, a new round), else the
  peer plans its arm an alternative trajectory around standing arms (an
  OMPL detour, its own arm: at its own station), or, when every arm in the
  way stands waiting for something else (a geometric deadlock, S2.6),
  sends each a back-off request
  (:class:`~workcell.sim.protocol.exchange.BackOffUntil`, a frame). The
  asked peer decides from its own arm's state: it backs off to its home
  joints (a motion asked for like any other) and comes back once the
  mover's frames show it has passed.
* **Failures.** An arm that fails sends its last view and
  :class:`~workcell.sim.protocol.peers.ArmOut`; the others stop waiting
  for its answers. Lost frames are sent again by the link; a request that
  waits for one simply waits longer.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from workcell.geometry import ObstacleSet, plan_detour
from workcell.sim.comms.medium import BROADCAST
from workcell.sim.coordination.geometric import initial_book
from workcell.sim.coordination.throttle import Throttle
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
)
from workcell.sim.protocol.messages import Leg, Station
from workcell.sim.protocol.peers import Clearance, ClearanceReply, PeerView
from workcell.sim.protocol.states import ANSWER_MACHINE, ROUND_MACHINE, AnswerState, RoundState

if TYPE_CHECKING:
    from scheduler import Problem
    from workcell.compile import CompiledCell
    from workcell.sim.comms.link import Link
    from workcell.sim.coordination.guard import GeometryGuard
    from workcell.sim.events.loop import EventLoop
    from workcell.sim.events.trace import Trace
    from workcell.sim.protocol.channel import ControlChannel

__all__ = ["Sight", "SightHost"]


class SightHost(Protocol):
    """What a :class:`Sight` uses of the run (the clock, the medium, its own
    arm's channel, the trace, the cell every station holds and the check's
    settings); typed here so that the policy's module and this one do not
    import each other."""

    cc: CompiledCell
    p: Problem
    kernel: EventLoop
    link: Link
    trace: Trace
    channel: ControlChannel
    seed: int
    detours_on: bool
    detour_checks: int
    max_backoffs: int
    recheck_limit: int
    max_stalled: int

    def done_for_good(self, a: int) -> bool: ...


@dataclass(slots=True)
class _Round:
    """An own departure request out for answers."""

    ask: int
    view: ArmView
    clock: int
    waiting: set[int] = field(default_factory=set)


class Sight:
    """Arm ``a``'s peer's view of the arms and its departure check (module docstring).

    Parameters
    ----------
    host : SightHost
    a : int
        The arm.
    guard : GeometryGuard or None
        The geometric check (``None``: every departure is cleared at once).
    near : frozenset of int
        The arms that may meet this one (:func:`~.reach.may_meet`).
    """

    def __init__(self, host: SightHost, a: int, guard: GeometryGuard | None, near: frozenset[int]):
        self.h = host
        self.a = a
        self.station = a + 1
        self.guard = guard
        self.near = near
        self.view: list[ArmView] = initial_book(host.cc)
        """Per arm, where this peer believes it is (its own from its controller)."""
        self.heard: dict[int, int] = {}
        """Per other arm, the highest view count taken from it."""
        self.n = 0
        self.clock = 0
        self.decided = 0
        self.round: _Round | None = None
        self.state = RoundState.IDLE
        """The own departure request's state (:data:`~workcell.sim.protocol.states.ROUND_MACHINE`)."""
        self.queued: DepartureRequest | None = None
        """A request the controller made while a round was out (asked next)."""
        self.deferred: list[tuple[int, Clearance]] = []
        self.reserved: dict[int, dict[int, ArmView]] = {}
        """Per other arm, per request answered, the motion reserved for it."""
        self.out: set[int] = set()
        self.held_by: list[int] = []
        """While the own arm is held: the arms in its way."""
        self.away_until: BackOffUntil | None = None
        self.wanted: BackOffUntil | None = None
        """A back-off asked of this arm that it could not make yet (tried
        again when something changes, until the mover moves on)."""
        self.backoffs = 0
        self.detours = 0
        self.rounds = 0
        self.detour_tried: set[tuple[int, int]] = set()
        self.backoff_asked: set[tuple[int, int, int, int]] = set()
        self.looks = Throttle(
            host.kernel,
            self._look,
            limit=host.recheck_limit,
            max_stalled=host.max_stalled,
            period=guard.dt if guard is not None else 0.01,
        )
        """The throttle of the look again at the own arm's hold (its
        ``stalled``: deferred looks since the own arm's last task start or end)."""

    # ------------------------------------------------------------ sending
    def _send(self, b: int, kind: str, payload: Any) -> None:
        if b not in self.out:
            self.h.link.send(self.station, b + 1, kind, payload)

    def _send_near(self, kind: str, payload: Any) -> None:
        """Send ``payload`` to every working arm that may meet this one: one
        broadcast where the medium's broadcast is one transfer
        (:attr:`~workcell.sim.comms.link.Link.broadcast_once`; the others
        that hear it ignore it), else one frame per arm."""
        if self.h.link.broadcast_once:
            self.h.link.send(self.station, BROADCAST, kind, payload)
            return
        for b in sorted(self.near):
            self._send(b, kind, payload)

    def _tell(self) -> None:
        """Tell the arms that may meet this one where it is."""
        if self.near - self.out:
            self.n += 1
            self._send_near("motion_report", PeerView(self.view[self.a], self.n, self.decided))

    # ------------------------------------------------------------ own arm
    def own_report(self, report: Report) -> None:
        """A report of the own arm's controller (at the station, no medium)."""
        if isinstance(report, MotionReport):
            self.view[self.a] = report.view
            self._tell()
            if report.view.held or self.away_until is not None or self.wanted is not None:
                self._notify()
        elif isinstance(report, DepartureRequest):
            self.view[self.a] = report.view
            if self.round is not None:
                self.queued = report
            else:
                self._open(report)

    def _open(self, req: DepartureRequest) -> None:
        ROUND_MACHINE.check(self.state, RoundState.ASKING)
        self.state = RoundState.ASKING
        self.clock += 1
        self.rounds += 1
        live = set(self.near - self.out)
        self.round = _Round(req.ask, req.view, self.clock, live)
        if not live:
            self._decide()
            return
        self.n += 1
        self._send_near(
            "departure_request", Clearance(req.view, self.n, self.decided, req.ask, self.clock)
        )

    def _decide(self) -> None:
        """Every answer is in: *continue* or *stop* (S2.12)."""
        rnd = self.round
        assert rnd is not None
        self.round = None
        ROUND_MACHINE.check(self.state, RoundState.IDLE)
        self.state = RoundState.IDLE
        self.decided = rnd.ask
        h, a = self.h, self.a
        if self.queued is not None:  # the controller asked again since: not this one
            go = False
            found: list[int] = []
        else:
            found = self.blockers(rnd.view)
            go = not found
        if go:
            if self.held_by:
                self.held_by = []
                h.trace.add(
                    h.kernel.now, "wake", arm=h.p.arm_names[a], detail="geometric conflict over"
                )
            self.view[a] = rnd.view.as_running(h.kernel.now)
        elif found:
            if self.held_by != found:
                leg = rnd.view.leg
                names = ", ".join(repr(h.p.arm_names[b]) for b in found)
                h.trace.add(
                    h.kernel.now,
                    "sleep",
                    arm=h.p.arm_names[a],
                    task=h.p.task_names[leg.task] if leg is not None else "",
                    detail=f"geometric conflict (S2.12): arm {names} in the way: stop",
                )
            self.held_by = found
        h.channel.order(a, Departure(go, rnd.ask))
        for b, c in self.deferred:
            self._answer(b, c, AnswerState.DEFERRED)
        self.deferred = []
        if self.queued is not None:
            req, self.queued = self.queued, None
            self._open(req)
        elif not go or self.wanted is not None:
            self._notify()

    def blockers(self, mover: ArmView) -> list[int]:
        """The arms in the way of ``mover`` (the own arm's motion) in this
        peer's view, the motions it reserved for others included."""
        if self.guard is None:
            return []
        book = list(self.view)
        book[self.a] = mover
        extra = [v for res in self.reserved.values() for v in res.values()]
        return self.guard.blockers(mover, book, extra)

    # ------------------------------------------------------------ peers' frames
    def from_peer(self, b: int, payload: Any) -> None:
        """A frame of the peer of arm ``b`` (a view, a request, an answer, a
        back-off); a broadcast view or request of an arm that cannot meet
        this one is not read."""
        if isinstance(payload, (PeerView, Clearance)) and b not in self.near:
            return
        if isinstance(payload, PeerView):
            self._take(b, payload.n, payload.view, payload.decided)
        elif isinstance(payload, Clearance):
            self._take(b, payload.n, payload.view, payload.decided)
            self.clock = max(self.clock, payload.clock)
            rnd = self.round
            if rnd is not None and (rnd.clock, self.a) < (payload.clock, b):
                ANSWER_MACHINE.check(AnswerState.RECEIVED, AnswerState.DEFERRED)
                self.deferred.append((b, payload))
            else:
                self._answer(b, payload, AnswerState.RECEIVED)
        elif isinstance(payload, ClearanceReply):
            self._take(b, payload.n, payload.view, payload.decided)
            rnd = self.round
            if rnd is not None and payload.ask == rnd.ask and b in rnd.waiting:
                rnd.waiting.discard(b)
                if not rnd.waiting:
                    self._decide()
        elif isinstance(payload, BackOffUntil):
            self._back_off(payload)

    def _answer(self, b: int, c: Clearance, state: AnswerState) -> None:
        """Answer ``b``'s request (in ``state``): reserve its motion, say
        where this arm is."""
        if b in self.out:
            return
        ANSWER_MACHINE.check(state, AnswerState.RESERVED)
        self.reserved.setdefault(b, {})[c.ask] = c.view.as_running()
        self.n += 1
        self._send(
            b, "motion_report", ClearanceReply(self.view[self.a], self.n, self.decided, c.ask)
        )

    def _take(self, b: int, n: int, view: ArmView, decided: int) -> None:
        """A view of arm ``b`` (count ``n``; ``decided``: its last request decided)."""
        moved = False
        if n > self.heard.get(b, -1):
            self.heard[b] = n
            old = self.view[b]
            self.view[b] = view
            moved = (
                old.running != view.running
                or old.leg is not view.leg
                or old.failed != view.failed
                or old.away != view.away
                or old.waiting != view.waiting
            )
            if old.leg is not view.leg:
                self.looks.progress()
        res = self.reserved.get(b)
        if res and not view.running:
            # sent after that request was decided, standing: those motions are over
            left = {k: v for k, v in res.items() if k > decided}
            if len(left) < len(res):
                ANSWER_MACHINE.check(AnswerState.RESERVED, AnswerState.OVER)
                self.reserved[b] = left
                moved = True
        if moved and (
            self.view[self.a].held or self.away_until is not None or self.wanted is not None
        ):
            self._notify()

    def arm_out(self, b: int) -> None:
        """Arm ``b`` failed (its last frame): no answer from it is awaited."""
        if b in self.out:
            return
        self.out.add(b)
        if any(x == b for x, _c in self.deferred):
            ANSWER_MACHINE.check(AnswerState.DEFERRED, AnswerState.OVER)
        self.deferred = [(x, c) for x, c in self.deferred if x != b]
        # it was taken to its home joints (its last view says so) and never
        # moves again: a motion asked for when it failed is void
        if self.reserved.pop(b, None):
            ANSWER_MACHINE.check(AnswerState.RESERVED, AnswerState.OVER)
        rnd = self.round
        if rnd is not None and b in rnd.waiting:
            rnd.waiting.discard(b)
            if not rnd.waiting:
                self._decide()
        self._notify()

    # ------------------------------------------------------------ watch and notify
    def _notify(self) -> None:
        """Look at the own arm's hold and back-off again (throttled: at most
        ``recheck_limit`` looks at one instant, then one guard period later,
        at most ``max_stalled`` times with no progress in sight;
        :class:`~workcell.sim.coordination.throttle.Throttle`)."""
        self.looks.poke()

    def _look(self) -> None:
        h, a = self.h, self.a
        own = self.view[a]
        if own.failed:
            return
        until = self.away_until
        if until is not None and own.away and own.leg is None:
            mover = self.view[until.mover]
            passed = mover.leg is not until.leg and not mover.away
            waits = mover.waiting and not mover.held
            if mover.failed or until.mover in self.out or passed or waits:
                self.away_until = None
                h.channel.order(a, ComeBack())
                return
        want = self.wanted
        if want is not None:
            mover = self.view[want.mover]
            if mover.failed or want.mover in self.out or mover.running or mover.leg is not want.leg:
                self.wanted = None  # the mover went on (or out): nothing to make way for
            else:
                self._back_off(want)
        if not own.held or self.round is not None:
            return
        found = self.blockers(own)
        if not found:
            if self.held_by:
                h.trace.add(
                    h.kernel.now, "wake", arm=h.p.arm_names[a], detail="geometric conflict over"
                )
            self.held_by = []
            h.channel.order(a, ReleaseHold())  # it asks again before it sets off
            return
        self.held_by = found
        if self._try_detour(own, found):
            return
        if (
            self.backoffs < h.max_backoffs
            and own.leg is not None
            and all(
                # an idle arm may have nothing left to do: its own peer decides
                (self.view[b].waiting or (self.view[b].leg is None and not self.view[b].running))
                and not self.view[b].away
                and not self.reserved.get(b)
                for b in found
            )
        ):
            for b in found:
                key = (b, id(own.leg), own.k, self.heard.get(b, -1))
                if key not in self.backoff_asked:
                    self.backoff_asked.add(key)
                    self._send(b, "back_off", BackOffUntil(a, own.leg, own.k))

    # ------------------------------------------------------------ S2.6 and S2.12 answers
    def _back_off(self, until: BackOffUntil) -> None:
        """Arm ``until.mover``'s peer asks this arm out of its way (S2.6):
        back off to the home joints if the arm stands waiting, can go and
        its way home is clear in this peer's view."""
        h, a = self.h, self.a
        v = self.view[a]
        self.wanted = None
        # an idle arm with nothing left to do (its part never came, say) may
        # stand where the plan had it move on: it goes home and stays there
        idle = v.leg is None and not v.running and h.done_for_good(a)
        if (
            v.away
            or v.failed
            or (v.leg is None and not idle)
            or v.pushing
            or self.away_until is not None
            or self.backoffs >= h.max_backoffs
        ):
            return
        if v.running or not (v.waiting or idle) or self.round is not None:
            self.wanted = until  # not now: again when something changes
            return
        arm = h.cc.cell.arms[a]
        home = np.asarray(h.cc.cell.start[a], dtype=float)
        traj = arm.move(v.position(h.kernel.now), home, arm.interpolation)
        if traj.duration <= 0:
            return
        task = v.leg.task if v.leg is not None else -1
        retreat = Leg("retreat", task, -1, traj, [Station(traj.duration, end=True)])
        if self.blockers(ArmView(a, retreat, 0, 0.0, v.t_ref, False, v.q, v.at_station)):
            self.wanted = until  # the way back home is not free now: again when it may be
            return
        if not idle:  # an idle arm stays home: nothing to come back to
            self.away_until = until
        self.backoffs += 1
        self.detours += 1
        h.trace.add(
            h.kernel.now,
            "detour",
            arm=h.p.arm_names[a],
            detail=f"geometric deadlock (S2.6): backs off to its home joints "
            f"out of arm {h.p.arm_names[until.mover]!r}'s way",
        )
        h.channel.order(a, BackOff(traj))  # the retreat is asked for like any motion

    def _try_detour(self, own: ArmView, found: list[int]) -> bool:
        """S2.12 "continue with alternative trajectory": an OMPL path to the
        next station around the arms standing in the way (tried once per
        station; work-limited, so the same seed plans the same path). There is
        no re-solve under this policy: a detour longer than planned only delays."""
        h, a = self.h, self.a
        leg = own.leg
        if (
            not h.detours_on
            or leg is None
            or leg.kind != "task"
            or own.away
            or any(self.view[b].running or self.reserved.get(b) for b in found)
        ):
            return False
        key = (id(leg), own.k)
        if key in self.detour_tried:
            return False
        self.detour_tried.add(key)
        now = h.kernel.now
        arm = h.cc.cell.arms[a]
        qa = own.position(now)
        qb = leg.trajectory.sample(np.array([leg.stations[own.k].tau]))[0]
        items: list[Any] = []
        for b in found:
            items.extend(ObstacleSet.from_arm(h.cc.cell.arms[b], self.view[b].position(now)).items)
        res = plan_detour(
            arm,
            qa,
            qb,
            ObstacleSet(items, name="standing arms"),
            budget=60.0,
            seed=h.seed,
            resolution=0.01,
            clearance=0.02,
            max_checks=h.detour_checks,
        )
        if not res.solved:
            return False
        traj = arm.time_path(res.path, "sync")
        extra = traj.duration - (leg.stations[own.k].tau - own.tau)
        self.detours += 1
        self.held_by = []
        h.trace.add(
            now,
            "detour",
            arm=h.p.arm_names[a],
            task=h.p.task_names[leg.task],
            delay=extra,
            detail=f"alternative trajectory around arm(s) "
            f"{', '.join(repr(h.p.arm_names[b]) for b in found)} (S2.12): "
            f"{extra:+.6g} s",
        )
        h.channel.order(a, Detour(traj, leg.task))  # the detour is asked for too
        return True
