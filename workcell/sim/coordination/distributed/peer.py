"""One arm's coordination half under distributed coordination (S2.4, S2.7).

A :class:`Peer` lives beside its arm's controller, at the arm's station: it
talks to its own controller without the medium (the two share the station)
and to the other peers only through frames on the medium
(:mod:`workcell.sim.protocol.peers`).

* **Dispatch.** The peer sends its controller the arm's tasks in the plan's
  order, each at its planned departure (as the centralized coordinator), and
  lets a task start once its release time has passed and every predecessor
  is done: a peer whose task ends tells the peers of the successors' arms
  (a :class:`~workcell.sim.protocol.peers.Notice`).
* **Resources.** Mutual exclusion per resource (exclusive zone, movement in
  a shared zone, tool, space-grid block) in the style of Ricart and
  Agrawala, with the plan order as the priority. When the controller asks
  for a use at place ``i`` of the resource's order, the peer asks every arm
  with an earlier use that it does not know to be over
  (:class:`~workcell.sim.protocol.peers.Ask`); an arm answers
  (:class:`~workcell.sim.protocol.peers.Reply`) once every use of its own
  placed before ``i`` is over, at once or when its controller releases the
  last of them. The use is granted when every answer is in and the arm's own
  earlier uses are over. Every wait is for a use planned earlier, so no
  cycle can close when the plan has none (as the centralized plan-order
  rule); an answer says how far its sender is, so a later request to the
  same arm is saved when the answer already covers it.
* **Failed tasks** (an insertion that failed, a part that never comes): the
  peer of the task reports it failed, treats its uses as over (answering
  the arms that wait), and tells the peers of the successors, which fail
  theirs in turn.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from workcell.sim.comms.medium import BROADCAST
from workcell.sim.coordination.distributed.plan import arm_of, build_legs, task_pieces
from workcell.sim.events.loop import Handle
from workcell.sim.protocol.messages import (
    ActivationGo,
    ActivationStop,
    ActiveZones,
    AlarmClear,
    AlarmStop,
    Piece,
    StartPermit,
    Trajectory,
    Withdraw,
)
from workcell.sim.protocol.peers import (
    ACTIVATION_KINDS,
    Activation,
    Alarm,
    ArmOut,
    Ask,
    Notice,
    Reply,
    Resource,
)
from workcell.sim.protocol.states import TASK_MACHINE, TaskState

if TYPE_CHECKING:
    from scheduler import Problem, Schedule
    from workcell.compile import CompiledCell
    from workcell.sim.comms.link import Link
    from workcell.sim.coordination.distributed.sight import Sight
    from workcell.sim.events.loop import EventLoop
    from workcell.sim.events.trace import Trace
    from workcell.sim.protocol.peers import Resource


class PeerHost(Protocol):
    """What a :class:`Peer` reads of the policy that holds the peers
    (:class:`~workcell.sim.coordination.distributed.policy.DistributedPolicy`;
    typed here so that the two modules do not import each other)."""

    cc: CompiledCell
    p: Problem
    plan: Schedule
    kernel: EventLoop
    link: Link
    trace: Trace
    failed_arms: set[int]
    orders: dict[Resource, list[Piece]]
    position: dict[Piece, int]
    start_pieces: list[list[Piece]]

    def owner(self, piece: Piece) -> int: ...

    def resource_name(self, piece: Piece) -> str: ...


__all__ = ["Peer"]

Deliver = Callable[[str, Any], None]
"""``deliver(kind, payload)``: a message to the peer's own controller."""


class Peer:
    """The coordination half of arm ``a`` (module docstring).

    Parameters
    ----------
    shared : PeerHost
        The run's clock, link and trace, and the tables every station
        derives from the plan it holds (read only).
    a : int
        The arm's index (its station is ``a + 1``).
    deliver : callable
        ``deliver(kind, payload)`` hands a message to the arm's controller.
    sight : Sight
        The peer's own view of the arms and its departure check (:mod:`.sight`).
    """

    def __init__(self, shared: PeerHost, a: int, deliver: Deliver, sight: Sight) -> None:
        self.s = shared
        self.sight = sight
        self.a = a
        self.station = a + 1
        self.deliver = deliver
        p = shared.p
        plan = shared.plan
        self.tasks = sorted(
            (t for t in range(p.n_tasks) if arm_of(p, plan, t) == a),
            key=lambda t: (float(plan.start[t]), t),
        )
        self.release = {t: float(p.task_release[t]) for t in self.tasks}
        self.status: dict[int, TaskState] = dict.fromkeys(self.tasks, TaskState.PENDING)
        """Per own task, its state: the peer's published record (no other
        peer reads it; the harness reads it at the end of a run)."""
        self.cause: dict[int, tuple[str, str]] = {}
        """Per own failed task, its cause and the cause's category
        (:data:`~workcell.sim.coordination.constants.CAUSE_KINDS`): published
        with :attr:`status`."""
        self.prev = -1
        self.busy = False
        self.dispatch_h: Handle | None = None
        self.permitted: set[int] = set()
        self.done: set[int] = set()
        """Tasks known done (own ones, and others' from their notices)."""
        self.failed: set[int] = set()
        self.over: set[Piece] = set()
        """Own uses over (released by the controller, or of a failed task)."""
        self.own: dict[Resource, list[int]] = {}
        """Per resource, the places of the arm's own uses in its order."""
        self.others: dict[Resource, dict[int, list[int]]] = {}
        """Per resource, per other arm, the places of its uses."""
        for k, order in shared.orders.items():
            for i, piece in enumerate(order):
                b = shared.owner(piece)
                if b == a:
                    self.own.setdefault(k, []).append(i)
                else:
                    self.others.setdefault(k, {}).setdefault(b, []).append(i)
        self.known: dict[tuple[int, Resource], int] = {}
        """(arm, resource) -> every use of that arm placed before this is over."""
        self.asked: dict[tuple[int, Resource], int] = {}
        self.waiting: list[Piece] = []
        """Uses the controller asked for, not granted yet (in request order)."""
        self.told_sleep: set[Piece] = set()
        self.deferred: dict[Resource, list[tuple[int, int]]] = {}
        """Per resource, the requests of other arms ``(arm, place)`` not answered yet."""
        self.out: set[int] = set()
        """Arms known to have failed (from their last frame)."""
        self.halts: dict[int, int] = {}
        """Zone activations in force: id -> the arm that raised it."""
        self.unacked: list[Activation] = []
        """Activation stops handed to the controller, not yet confirmed by it."""
        self.acks: dict[int, set[int]] = {}
        """Activations this arm raised: id -> the arms that confirmed their stop."""
        self.raised: dict[int, Activation] = {}

    # ------------------------------------------------------------ own records
    def set_status(self, t: int, new: TaskState) -> None:
        """Move own task ``t`` to ``new`` (checked against the task machine)."""
        TASK_MACHINE.check(self.status[t], new)
        self.status[t] = new

    def done_for_good(self) -> bool:
        """Every task the plan gives this arm is done or failed."""
        return all(st in (TaskState.DONE, TaskState.FAILED) for st in self.status.values())

    # ------------------------------------------------------------ dispatch
    def start(self) -> None:
        """Schedule the releases of the arm's tasks, dispatch the first."""
        for t in self.tasks:
            r = self.release[t]
            if r > 0 and math.isfinite(r):
                self.s.kernel.schedule(r, self._on_release, t, absolute=True)
        self.dispatch_next()

    def _next_task(self) -> int:
        for t in self.tasks:
            if self.status[t] == TaskState.PENDING:
                return t
        return -1

    def dispatch_next(self) -> None:
        """Send the next task to the controller at its planned departure."""
        if self.dispatch_h is not None:
            self.dispatch_h.cancel()
            self.dispatch_h = None
        if self.busy or self.halts or self.a in self.s.failed_arms:
            return
        t = self._next_task()
        if t < 0:
            return
        s = self.s
        depart = float(s.plan.start[t]) - s.p.setup_time(self.a, self.prev, t)
        if depart > s.kernel.now:
            self.dispatch_h = s.kernel.schedule(depart, self.dispatch_next, absolute=True)
            return
        first = any(q not in self.over for q in s.start_pieces[self.a])
        legs = build_legs(s.cc, s.plan, self.sight.view[self.a], t, first)
        self.set_status(t, TaskState.DISPATCHED)
        self.prev = t
        permit = self._startable(t)
        if permit:
            self.permitted.add(t)
        self.busy = True
        self.deliver("trajectory", Trajectory(tuple(legs), permit))

    def _startable(self, t: int) -> bool:
        return self.s.kernel.now >= self.release[t] and all(
            q in self.done for q in self.s.p.task_preds[t]
        )

    def _permit(self, t: int) -> None:
        if t in self.permitted or self.status[t] != TaskState.DISPATCHED:
            return
        if not self._startable(t):
            return
        self.permitted.add(t)
        self.deliver("wake_up", StartPermit(t))

    def _on_release(self, t: int) -> None:
        if self.s.kernel.now >= self.release[t]:
            self._permit(t)

    def _learn_done(self, t: int) -> None:
        self.done.add(t)
        for q in self.s.p.task_succs[t]:
            if q in self.release:
                self._permit(q)

    def _tell_successors(self, notice: Notice) -> None:
        """Send ``notice`` to the peers of the arms of the task's successors."""
        s = self.s
        to = sorted({arm_of(s.p, s.plan, q) for q in s.p.task_succs[notice.task]} - {self.a})
        for b in to:
            if b not in self.out:
                s.link.send(self.station, b + 1, "trajectory_end", notice)

    # ------------------------------------------------------------ task ends
    def task_done(self, t: int) -> None:
        """The controller ended task ``t``'s trajectory."""
        self.set_status(t, TaskState.DONE)
        self.busy = False
        self._learn_done(t)
        self._tell_successors(Notice(t, "done"))
        self.dispatch_next()

    def task_failed(self, t: int, cause: str, kind: str) -> None:
        """Own task ``t`` failed (ran and failed, or can never run)."""
        s = self.s
        st = self.status[t]
        if st in (TaskState.DONE, TaskState.FAILED):
            return
        if st == TaskState.DISPATCHED:
            self._withdraw(t)
        if st == TaskState.RUNNING:
            self.busy = False
        self.set_status(t, TaskState.FAILED)
        self.cause[t] = (cause, kind)
        s.trace.add(
            s.kernel.now,
            "task_failed",
            arm=s.p.arm_names[self.a],
            task=s.p.task_names[t],
            detail=cause,
        )
        self.failed.add(t)
        for piece, *_ in task_pieces(s.p, s.plan, t):
            self._over(piece)
        self._tell_successors(Notice(t, "failed", cause, kind))
        self._fail_successors(t, cause)
        self.dispatch_next()

    def _fail_successors(self, t: int, cause: str) -> None:
        why = f"predecessor {self.s.p.task_names[t]!r} failed: {cause}"
        for q in self.s.p.task_succs[t]:
            if q in self.release:
                self.task_failed(q, why, "predecessor")

    def _withdraw(self, t: int) -> None:
        self.permitted.discard(t)
        self.waiting = [q for q in self.waiting if q.task != t]
        self.told_sleep = {q for q in self.told_sleep if q.task != t}
        self.deliver("sleep", Withdraw(t))

    def part_late(self, t: int, arrival: float, part: str) -> None:
        """Own task ``t``'s part ``part`` comes at ``arrival`` (inf: never)."""
        s = self.s
        if self.a in s.failed_arms:
            return  # its station is silent; the harness reports its tasks
        if self.status[t] in (TaskState.DONE, TaskState.RUNNING, TaskState.FAILED):
            return
        self.release[t] = max(self.release[t], arrival)
        if math.isinf(arrival):
            self.task_failed(t, f"part {part!r} never arrived", "part_missing")
            return
        if self.status[t] == TaskState.DISPATCHED and t in self.permitted:
            self._withdraw(t)
            self.set_status(t, TaskState.PENDING)
        s.kernel.schedule(arrival, self._on_release, t, absolute=True)

    # ------------------------------------------------------------ controller
    def from_controller(self, kind: str, payload: Any) -> None:
        """A message from the arm's own controller (no medium between them)."""
        s = self.s
        if kind == "zone_request":
            t = int(payload.task)
            if t >= 0 and self.status[t] not in (TaskState.DISPATCHED, TaskState.RUNNING):
                return  # sent before the controller heard of the withdrawal
            self._request(payload)
        elif kind == "zone_release":
            self._over(payload)
        elif kind == "trajectory_end":
            if payload.outcome == "failed":
                self.task_failed(payload.task, payload.cause, "insertion")
            elif payload.outcome == "withdrawn":  # a withdrawn trajectory
                self.busy = False
                if self.status[payload.task] == TaskState.DISPATCHED:
                    self.set_status(payload.task, TaskState.PENDING)
                self.dispatch_next()
            else:
                self.task_done(payload.task)
        elif kind == "position" and payload.piece is None and self.unacked:
            act = self.unacked.pop(0)  # the controller stands for this activation
            self._send_activation(
                act.origin, Activation(act.stop, act.zones, "stopped", act.origin)
            )
        elif kind == "alarm":
            s.trace.add(
                s.kernel.now,
                "fault",
                arm=s.p.arm_names[self.a],
                detail=f"peer told of a reflex stop ({payload.cause}), after the fact (S1.2)",
            )
        # "position" reports serve the centralized zone manager only

    # ------------------------------------------------------------ peers
    def from_peer(self, b: int, kind: str, payload: Any) -> None:
        """A frame from the peer of arm ``b``."""
        if isinstance(payload, Ask):
            self._on_ask(b, payload)
        elif isinstance(payload, Reply):
            key = (b, payload.resource)
            self.known[key] = max(self.known.get(key, -1), payload.upto)
            self._serve()
        elif isinstance(payload, Notice):
            if payload.outcome == "done":
                self._learn_done(payload.task)
            else:
                self.failed.add(payload.task)
                self._fail_successors(payload.task, payload.cause)
        elif isinstance(payload, Alarm):
            if payload.on:
                self.deliver("alarm", AlarmStop(payload.stop))
            else:
                self.deliver("wake_up", AlarmClear(payload.stop))
        elif isinstance(payload, Activation):
            self._on_activation(b, payload)
        elif isinstance(payload, ArmOut):
            self.arm_out(payload.arm)
            self.sight.arm_out(payload.arm)
        else:  # the arms' views, departure requests and answers, back-off requests
            self.sight.from_peer(b, payload)

    # ------------------------------------------------------------ zone activation (S2.5)
    def _send_activation(self, to: int, act: Activation) -> None:
        """To one arm's peer, or to every peer (``to == BROADCAST``; this one too)."""
        kind = ACTIVATION_KINDS[act.phase]
        if to == self.a:
            self._on_activation(self.a, act)
            return
        if to == BROADCAST:
            self._on_activation(self.a, act)
        self.s.link.send(self.station, to + 1 if to >= 0 else BROADCAST, kind, act)

    def raise_activation(self, stop: int, zones: tuple[str, ...]) -> None:
        """Raise a zone activation here: every arm stops, then the change is
        made and every arm goes on."""
        act = Activation(stop, zones, "stop", self.a)
        self.raised[stop] = act
        self.acks[stop] = set()
        self._send_activation(BROADCAST, act)

    def _on_activation(self, b: int, act: Activation) -> None:
        s = self.s
        if act.phase == "stop":
            if act.origin in self.out:
                return
            self.halts[act.stop] = act.origin
            if self.dispatch_h is not None:
                self.dispatch_h.cancel()
                self.dispatch_h = None
            self.unacked.append(act)
            self.deliver("sleep", ActivationStop(act.stop))
        elif act.phase == "stopped":
            if act.stop in self.acks:
                self.acks[act.stop].add(b)
                self._try_go(act.stop)
        elif act.phase == "go":
            if self.halts.pop(act.stop, None) is None:
                return
            if act.zones:
                self.deliver("active_zone_grant", ActiveZones(tuple(act.zones)))
            self.deliver("wake_up", ActivationGo(act.stop))
            if act.origin == self.a:
                s.trace.add(
                    s.kernel.now,
                    "grant",
                    arm=s.p.arm_names[self.a],
                    detail="active zones activated: " + ", ".join(act.zones),
                )
            self.dispatch_next()

    def _try_go(self, stop: int) -> None:
        live = set(range(self.s.p.n_arms)) - self.out
        got = self.acks.get(stop)
        if got is None or not live <= got:
            return
        act = self.raised.pop(stop)
        del self.acks[stop]
        self._send_activation(BROADCAST, Activation(stop, act.zones, "go", self.a))

    # ------------------------------------------------------------ arm failures
    def fail(self) -> None:
        """This arm failed: its unfinished tasks go back to pending (reported
        by the harness with their cause), and its station sends its last
        frame, :class:`~workcell.sim.protocol.peers.ArmOut`, to every peer."""
        s = self.s
        if self.dispatch_h is not None:
            self.dispatch_h.cancel()
            self.dispatch_h = None
        for t in self.tasks:
            if self.status[t] in (TaskState.DISPATCHED, TaskState.RUNNING):
                self.set_status(t, TaskState.PENDING)
                s.trace.add(
                    s.kernel.now,
                    "task_failed",
                    arm=s.p.arm_names[self.a],
                    task=s.p.task_names[t],
                    detail="interrupted by the arm's failure; "
                    "no re-solve under distributed coordination",
                )
        self.waiting.clear()
        self.deferred.clear()
        s.link.send(self.station, BROADCAST, "alarm", ArmOut(self.a))

    def arm_out(self, b: int) -> None:
        """Arm ``b`` failed: its uses no longer hold anyone back, and the own
        tasks after its unfinished ones can never run (the plan is kept)."""
        if b in self.out or b == self.a:
            return
        s = self.s
        self.out.add(b)
        for k, order in s.orders.items():
            if b in self.others.get(k, {}):
                self.known[(b, k)] = len(order)
        for k, waits in self.deferred.items():
            self.deferred[k] = [(x, i) for x, i in waits if x != b]
        for t in self.tasks:
            if self.status[t] in (TaskState.DONE, TaskState.FAILED, TaskState.RUNNING):
                continue
            lost = [
                q for q in s.p.task_preds[t] if q not in self.done and arm_of(s.p, s.plan, q) == b
            ]
            if lost:
                name = s.p.task_names[lost[0]]
                why = f"predecessor {name!r} cannot run: its arm {s.p.arm_names[b]!r} failed"
                self.task_failed(
                    t, why + " (no re-solve under distributed coordination)", "predecessor"
                )
        for stop in list(self.halts):  # an activation its raiser cannot end
            if self.halts[stop] == b:
                self._on_activation(b, Activation(stop, (), "go", b))
        for stop in list(self.acks):
            self._try_go(stop)
        self._serve()

    # ------------------------------------------------------------ mutual exclusion
    def _upto(self, k: Resource) -> int:
        """The place of the arm's first use of ``k`` not over (or the order's length)."""
        order = self.s.orders[k]
        for i in self.own.get(k, ()):
            if order[i] not in self.over:
                return i
        return len(order)

    def _missing(self, k: Resource, i: int) -> list[int]:
        """Arms with a use of ``k`` before place ``i`` not known to be over."""
        out = []
        for b, places in self.others.get(k, {}).items():
            lo = self.known.get((b, k), -1)
            j = bisect.bisect_left(places, lo)
            if j < len(places) and places[j] < i:
                out.append(b)
        return out

    def _request(self, piece: Piece) -> None:
        s = self.s
        k = (piece.kind, piece.resource)
        i = s.position.get(piece)
        if i is None:  # no zone protocol (SimOptions(zone_protocol=False)): granted at once
            self.deliver("zone_grant", piece)
            return
        if piece not in self.waiting:
            self.waiting.append(piece)
        for b in self._missing(k, i):
            if b in self.out or self.asked.get((b, k), -1) >= i:
                continue
            self.asked[(b, k)] = i
            s.link.send(self.station, b + 1, "zone_request", Ask(k, i))
        self._serve()
        if piece in self.waiting and piece not in self.told_sleep:
            self.told_sleep.add(piece)
            s.trace.add(
                s.kernel.now,
                "sleep",
                arm=s.p.arm_names[self.a],
                task=s.p.task_names[piece.task] if piece.task >= 0 else "",
                zone=s.resource_name(piece),
                detail="planned earlier use not over",
            )
            self.deliver("sleep", piece)

    def _ready(self, piece: Piece) -> bool:
        k = (piece.kind, piece.resource)
        i = self.s.position[piece]
        return self._upto(k) >= i and not self._missing(k, i)

    def _serve(self) -> None:
        s = self.s
        for piece in list(self.waiting):
            if not self._ready(piece):
                continue
            self.waiting.remove(piece)
            name = s.resource_name(piece)
            task = s.p.task_names[piece.task] if piece.task >= 0 else ""
            arm = s.p.arm_names[self.a]
            if piece in self.told_sleep:
                self.told_sleep.discard(piece)
                s.trace.add(s.kernel.now, "wake", arm=arm, task=task, zone=name)
                self.deliver("wake_up", piece)
            else:
                s.trace.add(s.kernel.now, "grant", arm=arm, task=task, zone=name, detail=piece.kind)
                self.deliver("zone_grant", piece)

    def _on_ask(self, b: int, ask: Ask) -> None:
        if self._upto(ask.resource) >= ask.position:
            self.s.link.send(
                self.station, b + 1, "zone_grant", Reply(ask.resource, self._upto(ask.resource))
            )
        else:
            self.deferred.setdefault(ask.resource, []).append((b, ask.position))

    def _over(self, piece: Piece) -> None:
        """Own use ``piece`` is over: answer the requests it held back."""
        if piece in self.over:
            return
        self.over.add(piece)
        k = (piece.kind, piece.resource)
        waiting = self.deferred.get(k)
        if waiting:
            u = self._upto(k)
            keep = []
            for b, i in waiting:
                if u >= i:
                    if b not in self.out:
                        self.s.link.send(self.station, b + 1, "zone_grant", Reply(k, u))
                else:
                    keep.append((b, i))
            self.deferred[k] = keep
        self._serve()
