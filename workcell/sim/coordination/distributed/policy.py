"""``coordination="distributed"``: one peer per arm, no coordinator (S2.4, S2.7).

:class:`DistributedPolicy` builds one :class:`~.peer.Peer` per arm at the
arm's station and routes the frames of that station: peer records
(:mod:`workcell.sim.protocol.peers`) to the peer, the controller's own
messages and reports to the peer without the medium (they share the
station). It holds no decision, no record and no view of the arms of its
own: what the harness reads at the end of a run it reads from the peers'
own records (each task's state and cause from the peer of the task's arm,
each arm's view and geometric hold from its own peer), and it hands each
fault to the peer where it happens. The geometric check (S2.12) is each
peer's (:mod:`.sight`): its own view of the arms, from frames, its own
:class:`~workcell.sim.coordination.guard.GeometryGuard` (the cell's
geometry, which every station holds, with caches of its own), and a
request/reply round among the arms that may meet before every departure.

**What the peers share** is the event loop (the simulation itself: the
clock every station reads, the medium's deliveries) and, read only, what
every station derives once from the cell and the plan it holds (the
resources' plan orders, :func:`~.plan.resource_orders`; the arms that may
meet, :func:`~.reach.may_meet`): computed once here and handed to every
peer, never written after. Nothing one peer writes is read by another;
the trace is the harness's recorder, written by every station and read by
none, and the failed arms are the fault injection's record, of which a
peer reads only whether its own arm is in it (its station's power).

Faults under this policy:

* ``message_loss``: the link sends a lost peer frame again (as every frame).
* ``crash``, ``lost_sync``: local to the arm's controller (its peer is told
  of a reflex stop after the fact).
* ``emergency_stop``: raised at the station of the lowest working arm, whose
  peer stops its arm and broadcasts the alarm to the other peers, then its
  release ``duration`` seconds later (matched by id at every controller).
* ``late_part``: the feeder's notice reaches the peers of the gated tasks;
  each holds its task until the part comes (the plan is kept: no re-solve;
  a task dispatched with its start allowed is withdrawn and sent again).
  A part that never comes fails its tasks and, through notices, every task
  after them.
* ``activate_zones``: raised at the lowest working arm's station; its peer
  broadcasts the stop, every peer stops its arm (and dispatches nothing
  new) and answers once its controller stands; with every working arm's
  answer in, the raiser broadcasts the change and every arm goes on (stops
  and releases matched by id). The peers keep their mutual exclusion over
  every zone of the plan, active or not.
* ``arm_failure``: the failed arm's station sends its last frames: its
  view (failed) to the arms that may meet it, then
  :class:`~workcell.sim.protocol.peers.ArmOut` to every peer. Its uses of
  every resource and its departure answers then hold no one back, and each peer fails its tasks that
  come after an unfinished task of the failed arm (and tells the peers of
  their successors). There is no re-solve under this policy: the plan is
  kept, as with ``SimOptions(resolve=False)`` under the centralized
  coordinator, whatever ``resolve`` says.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any

from multiarm.errors import InternalError
from scheduler import Problem, Schedule
from workcell.compile import CompiledCell
from workcell.sim.comms.link import Link
from workcell.sim.comms.medium import BROADCAST, Frame
from workcell.sim.coordination.distributed.peer import Peer
from workcell.sim.coordination.distributed.plan import arm_of, resource_orders
from workcell.sim.coordination.distributed.reach import may_meet
from workcell.sim.coordination.distributed.sight import Sight
from workcell.sim.coordination.guard import GeometryGuard
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.exchange import (
    ArmView,
    Fail,
    MotionReport,
    Report,
    TaskEnded,
    TaskStarted,
)
from workcell.sim.protocol.messages import LateNotice, Piece
from workcell.sim.protocol.peers import PEER_RECORDS, Activation, Alarm, Resource
from workcell.sim.protocol.states import TaskState

__all__ = ["DistributedPolicy"]

_PEER_TYPES = (*PEER_RECORDS, Alarm, Activation)


class DistributedPolicy:
    """Distributed coordination: one :class:`Peer` per arm (module docstring).

    Parameters are those of every policy
    (:data:`~workcell.sim.coordination.policy.PolicyFactory`);
    ``resolve_budget`` and ``resolve_evaluations`` are kept for the records
    (this policy never re-solves), ``zone_checks=False`` grants every use at
    once (tests of the safety monitor only), ``geometry`` runs each arm's
    check before it sets off (S2.12); ``detours``, ``detour_checks`` and
    ``guard_answer`` are the :class:`~workcell.sim.harness.options.SimOptions`
    fields of the same names (alternative trajectories on or off, the detour
    search's work limit, a stand-in for the geometric check's answer).
    """

    colocated = True
    """The peers share the arms' stations: a controller's messages to
    station 0 go to its own peer (:meth:`controller_message`)."""

    def __init__(
        self,
        compiled: CompiledCell,
        plan: Schedule,
        kernel: EventLoop,
        net: Link,
        trace: Trace,
        channel: ControlChannel,
        *,
        seed: int = 0,
        resolve_budget: float = 0.015,
        resolve_evaluations: int = 200,
        zone_checks: bool = True,
        geometry: bool = True,
        resolving: bool = True,
        detours: bool = True,
        detour_checks: int = 10_000,
        guard_answer: Callable[[ArmView, Sequence[ArmView]], Sequence[int]] | None = None,
    ) -> None:
        self.cc = compiled
        self.p: Problem = compiled.problem
        self.plan = plan
        self.kernel = kernel
        self.link = net
        self.trace = trace
        self.channel = channel
        self.failed_arms: set[int] = set()
        self.seed = seed
        self.resolve_budget = float(resolve_budget)
        self.resolving = False
        del resolve_evaluations, resolving
        p = self.p
        T, A = p.n_tasks, p.n_arms
        self.plans: list[Schedule] = [plan]
        self.plan_of: list[int] = [0] * T
        self.dropped: frozenset[int] = frozenset()
        self.resolves = 0
        self.resolve_latency: list[float] = []
        self.orders: dict[Resource, list[Piece]] = resource_orders(p, plan) if zone_checks else {}
        self.position: dict[Piece, int] = {
            piece: i for order in self.orders.values() for i, piece in enumerate(order)
        }
        self.start_pieces: list[list[Piece]] = [
            [
                Piece("zone", int(z), -1 - a, 0.0)
                for z in p.arm_start_zones[a]
                if p.zone_exclusive[z]
            ]
            for a in range(A)
        ]
        self._stop_ids = itertools.count(1)
        self.max_stalled = 200
        self.recheck_limit = 8 + 4 * A
        self.max_backoffs = 2 * T + 2
        self.detour_checks = int(detour_checks)
        """Work limit of one OMPL detour search (validity checks)."""
        self.detours_on = bool(detours)
        self.near: list[frozenset[int]] = may_meet(compiled) if geometry else [frozenset()] * A
        """Per arm, the arms that may meet it (:func:`~.reach.may_meet`):
        the only peers it tells where it is and asks before it sets off."""
        self.peers: list[Peer] = [
            Peer(
                self,
                a,
                self._local(a),
                Sight(
                    self,
                    a,
                    # each station's own geometric check, with its own caches
                    GeometryGuard(compiled, clock=lambda: kernel.now, answer=guard_answer)
                    if geometry
                    else None,
                    self.near[a],
                ),
            )
            for a in range(A)
        ]
        self._arm_of = [arm_of(p, plan, t) for t in range(T)]
        net.receivers[0] = self._from_controller
        channel.attach_coordination(self.on_report, self.controller_message, self._at_station)

    # ------------------------------------------------------------ published records
    @property
    def book(self) -> list[ArmView]:
        """Per arm, its view as its own peer has it (the harness reads it
        at the end of a run; no peer reads another's)."""
        return [peer.sight.view[peer.a] for peer in self.peers]

    @property
    def status(self) -> list[TaskState]:
        """Per task, its state as the peer of its arm records it (each peer
        publishes the records of its own tasks; the harness reads them at
        the end of a run, no peer reads another's)."""
        return [self.peers[a].status[t] for t, a in enumerate(self._arm_of)]

    @property
    def cause(self) -> list[str]:
        """Per task, why it failed ("" if it did not), from its peer's record."""
        return [self.peers[a].cause.get(t, ("", ""))[0] for t, a in enumerate(self._arm_of)]

    @property
    def cause_kind(self) -> list[str]:
        """Per task, the category of :attr:`cause`, from its peer's record."""
        return [self.peers[a].cause.get(t, ("", ""))[1] for t, a in enumerate(self._arm_of)]

    @property
    def geo_held(self) -> dict[int, list[int]]:
        """Per arm held by its peer's geometric check, the arms in its way."""
        return {peer.a: list(peer.sight.held_by) for peer in self.peers if peer.sight.held_by}

    @property
    def detours(self) -> int:
        """Alternative trajectories and back-offs, every peer's."""
        return sum(peer.sight.detours for peer in self.peers)

    # ------------------------------------------------------------ plumbing
    def owner(self, piece: Piece) -> int:
        """The arm that makes use ``piece``."""
        return -1 - piece.task if piece.task < 0 else arm_of(self.p, self.plan, piece.task)

    def resource_name(self, piece: Piece) -> str:
        """The zone's or tool's name."""
        if piece.kind == "tool":
            return str(self.p.tool_names[piece.resource])
        return str(self.p.zone_names[piece.resource])

    def done_for_good(self, a: int) -> bool:
        """Every task the plan gives arm ``a`` is done or failed (asked by
        ``a``'s own station: its peer's records)."""
        return self.peers[a].done_for_good()

    def _local(self, a: int) -> Any:
        def deliver(kind: str, payload: Any) -> None:
            self.kernel.schedule(0.0, self.channel.to_controller, a, kind, payload)

        return deliver

    def _at_station(self, a: int, frame: Frame) -> bool:
        """A frame reached arm ``a``'s station: a peer record is its peer's
        (a failed arm's station is silent); anything else is the controller's."""
        payload = frame.payload[0]  # type: ignore[index]
        if a in self.failed_arms:
            return True
        if isinstance(payload, _PEER_TYPES):
            self.peers[a].from_peer(frame.src - 1, frame.kind, payload)
            return True
        return False  # pragma: no cover - nothing else is sent to an arm's station

    def _from_controller(self, frame: Frame) -> None:
        """Station 0 has no coordinator: a peer's broadcast reaches it and is
        not read; any other frame there is a bug."""
        if frame.dst == BROADCAST:
            return
        raise InternalError(  # pragma: no cover - every arm's messages stay at its station
            f"distributed coordination: arm station {frame.src} sent {frame.kind!r} to station 0"
        )

    def controller_message(self, src: int, kind: str, payload: Any) -> None:
        """A controller's message to its own peer (the same station; no medium:
        handed over as a new event at the same instant, as the ideal medium)."""
        if src - 1 not in self.failed_arms:
            self.kernel.schedule(0.0, self.peers[src - 1].from_controller, kind, payload)

    # ------------------------------------------------------------ policy protocol
    def start(self) -> None:
        """Every peer dispatches its arm's first task."""
        for peer in self.peers:
            peer.start()

    def on_report(self, a: int, report: Report, taken: int = -1) -> None:
        """A report of arm ``a``'s controller, taken by its peer at its
        station (``taken`` is for a coordinator across the medium: unused)."""
        del taken
        if isinstance(report, TaskStarted):
            self.task_started(a, report.task, report.time)
        elif isinstance(report, TaskEnded):
            self.task_ended(a, report.task, report.time)
        elif a not in self.failed_arms or (
            isinstance(report, MotionReport) and report.view.failed
        ):  # a failed arm's station sends its last view, then nothing
            self.peers[a].sight.own_report(report)

    def task_started(self, a: int, t: int, now: float) -> None:
        """Notice: arm ``a`` left task ``t``'s start station."""
        self.peers[a].set_status(t, TaskState.RUNNING)
        self.peers[a].sight.looks.progress()
        self.trace.add(now, "task_start", arm=self.p.arm_names[a], task=self.p.task_names[t])

    def task_ended(self, a: int, t: int, now: float) -> None:
        """Notice: arm ``a`` ended task ``t``'s trajectory."""
        self.peers[a].sight.looks.progress()
        self.trace.add(now, "task_end", arm=self.p.arm_names[a], task=self.p.task_names[t])

    def arm_failed(self, a: int) -> None:
        """Fault: arm ``a`` fails for good (its peer with it, after its last frame)."""
        if a in self.failed_arms:
            return
        self.failed_arms.add(a)
        self.channel.order(a, Fail())
        self.trace.add(self.kernel.now, "fault", arm=self.p.arm_names[a], detail="arm failure")
        self.peers[a].fail()

    def _raiser(self) -> int:
        """The lowest working arm (where a cell-wide fault is raised)."""
        return min(x for x in range(self.p.n_arms) if x not in self.failed_arms)

    def activate(self, zones: tuple[str, ...]) -> None:
        """Fault: change the active zones (S2.5), raised at the lowest working arm."""
        if len(self.failed_arms) == self.p.n_arms:
            return
        a = self._raiser()
        self.trace.add(
            self.kernel.now,
            "fault",
            arm=self.p.arm_names[a],
            detail=f"zone activation {', '.join(zones)} (raised by arm {self.p.arm_names[a]!r})",
        )
        self.peers[a].raise_activation(next(self._stop_ids), tuple(zones))

    def emergency_stop(self, duration: float) -> None:
        """The stop is raised at the lowest working arm's station; its peer
        stops its arm and broadcasts the alarm, and its release later."""
        if len(self.failed_arms) == self.p.n_arms:
            return
        a = self._raiser()
        stop = next(self._stop_ids)
        self.trace.add(
            self.kernel.now,
            "fault",
            arm=self.p.arm_names[a],
            detail=f"emergency stop for {duration:g} s (broadcast by arm {self.p.arm_names[a]!r})",
        )
        self.peers[a].from_peer(a, "alarm", Alarm(stop, True))
        self.link.send(a + 1, BROADCAST, "alarm", Alarm(stop, True))
        self.kernel.schedule(duration, self._clear_alarm, a, stop)

    def _clear_alarm(self, a: int, stop: int) -> None:
        if a in self.failed_arms:  # the raiser failed: the next working arm releases it
            if len(self.failed_arms) == self.p.n_arms:
                return
            a = self._raiser()
        self.trace.add(
            self.kernel.now, "fault", arm=self.p.arm_names[a], detail="emergency stop cleared"
        )
        self.peers[a].from_peer(a, "wake_up", Alarm(stop, False))
        self.link.send(a + 1, BROADCAST, "wake_up", Alarm(stop, False))

    def part_late(self, notice: LateNotice) -> None:
        """The feeder's notice reaches the peers of the gated tasks."""
        self.parts_late([notice])

    def parts_late(self, notices: Sequence[LateNotice]) -> None:
        """Parts found late at one instant (one :class:`LateNotice` each)."""
        for notice in notices:
            self.trace.add(self.kernel.now, "fault", detail=notice.describe())
            for t in notice.tasks:
                self.peers[arm_of(self.p, self.plan, t)].part_late(t, notice.arrival, notice.part)
