"""The centralized coordinator (S2.4 loose coordination, S2.5-S2.7, S2.12).

The coordinator executes a :class:`scheduler.Schedule`:

* **Dispatch.** Each arm gets its tasks in the schedule's order: at the
  planned departure (task start minus the travel time) the coordinator sends
  a *trajectory and start* message (S2.7) holding the travel to the task's
  first pose and the task's own trajectory, with the plan's times at the
  task's start and at every zone border (the arm never passes them early).
  The message says whether the task may start (its predecessors are done and
  its parts have arrived); if not, the arm stops at the task's start and is
  woken when it may go on.
* **Zones and tools** (S2.5-S2.7). The arm asks for every resource it needs
  at a border ``lookahead`` seconds ahead (zone request); the coordinator
  drives :class:`zones.ZoneManager` and answers with a grant, or with
  *sleep* (stop at the border) and later *wake up*. Requests are also held
  back until every use of the same resource that the plan puts earlier is
  over, so the executed order of every zone and tool is the plan's: late
  arms never overtake, and the hold-and-wait of exclusive zones cannot close
  a cycle (every wait is for something planned earlier). The manager still
  checks each grant (one arm per exclusive zone, one mover per shared zone,
  tools exclusive) and reports deadlocks, which the plan order excludes.
* **Geometric conflicts** (S2.6, S2.12). Before an arm sets off towards
  its next station it asks (a departure request on the control channel,
  :mod:`workcell.sim.protocol.exchange`); :class:`GeometryGuard` checks
  that motion against the other arms (standing or moving) as the
  coordinator's own book has them (the trajectories it sent and the motion
  the arms reported); a contact means *stop*. Around arms
  standing in the way the coordinator tries an alternative trajectory (an
  OMPL detour to the next station); failing that, when those arms are
  themselves waiting (a geometric deadlock), they back off to their home
  joints and come back once the mover has passed.
* **Zone activation** (S2.5) changes only while every arm is stopped: the
  coordinator stops the arms (sleep), applies the change, sends the
  active-zone grant to every arm, then wakes them.
* **Re-solving.** When a part comes late, an arm fails, or a detour costs
  more than planned, the coordinator calls :func:`scheduler.reschedule` from
  the current state (finished and running tasks frozen) under a work limit
  (so the same seed gives the same decisions), measures its wall-clock
  latency against the real-time budget, and goes on with the new plan.
* **Faults**: emergency-stop broadcast (alarm), arm failures (the failed
  arm's zones and tools are given back, its interrupted and remaining tasks
  reassigned), crashes reported after the reflex stop (S1.2).

Every coordinator-arm message is a :class:`~workcell.sim.comms.medium.Frame` of
the S2.9 size (:data:`~workcell.sim.comms.medium.MESSAGE_BYTES`) through the
medium; a lost or dropped frame is sent again after a timeout. The S2.12
exchange (motion reports, departure requests and answers, excursion
orders, the failure order, task start and end notices) is made of the
records of :mod:`workcell.sim.protocol.exchange` on the control channel,
delivered at once (its docstring says why).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from scheduler import Problem, Schedule
from workcell.compile import CompiledCell
from workcell.sim.comms.link import Link
from workcell.sim.coordination import geometric, recovery, resources
from workcell.sim.coordination.constants import CAUSE_KINDS
from workcell.sim.coordination.distributed.plan import PieceUse, build_legs, task_pieces
from workcell.sim.coordination.guard import GeometryGuard
from workcell.sim.coordination.throttle import Throttle
from workcell.sim.events.loop import EventLoop, Handle
from workcell.sim.events.trace import Trace
from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.exchange import ArmView, BackOffUntil
from workcell.sim.protocol.messages import Piece, StartPermit, Trajectory
from workcell.sim.protocol.states import TASK_MACHINE, TaskState
from zones import ZoneManager
from zones.manager import ReportOnly

__all__ = ["CAUSE_KINDS", "Coordinator"]


class Coordinator:
    """The centralized coordinator of a simulated run (module docstring).

    Parameters
    ----------
    compiled : CompiledCell
    plan : Schedule
    kernel : EventLoop
    net : Link
    trace : Trace
    channel : ControlChannel
        The S2.12 exchange with the arms (:mod:`workcell.sim.protocol.exchange`).
    seed : int
    resolve_budget : float
        Real-time budget of one re-solve, seconds (latency recorded against it).
    resolve_evaluations : int
        Work limit of one re-solve (decoded schedules).
    zone_checks : bool
        False only for tests of the safety monitor: grant every request at once.
    geometry : bool
        Run the geometric check (:class:`GeometryGuard`) before each motion.
    resolving : bool
        Re-solve when reality departs from the plan; False keeps the plan
        (a failed arm's tasks are then reported failed, late parts push the
        tasks they gate back).
    detours : bool
        Plan S2.12 alternative trajectories around standing arms.
    detour_checks : int
        Work limit of one detour search (configuration checks).
    guard_answer : callable, optional
        Asked in place of :meth:`GeometryGuard.blockers`
        (:attr:`~workcell.sim.harness.options.SimOptions.guard_answer`).

    Attributes
    ----------
    book : list of ArmView
        Per arm, its motion as the coordinator knows it: the view it last
        reported (the trajectories in it are those the coordinator sent,
        or the excursions it ordered).
    away_until : dict of int -> BackOffUntil
        The arms it backed off, and the mover each waits for.
    """

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
        self.net = net
        self.trace = trace
        self.channel = channel
        self.book: list[ArmView] = geometric.initial_book(compiled)
        self.away_until: dict[int, BackOffUntil] = {}
        self.seed = seed
        self.resolve_budget = float(resolve_budget)
        self.resolve_evaluations = int(resolve_evaluations)
        self.zone_checks = zone_checks
        self.resolving = bool(resolving)
        p = self.p
        T, A = p.n_tasks, p.n_arms
        self.status: list[TaskState] = [TaskState.PENDING] * T
        """Per task, its state (:data:`~workcell.sim.protocol.states.TASK_MACHINE`);
        changed only through :meth:`set_status`."""
        self.cause = [""] * T
        self.cause_kind = [""] * T
        """Per failed task, the category of its cause (:data:`CAUSE_KINDS`)."""
        self.release = np.asarray(p.task_release, dtype=float).copy()
        self.late: dict[int, float] = {}
        self.permitted: set[int] = set()
        self.prev = [-1] * A
        self.arm_busy = [False] * A
        self.failed_arms: set[int] = set()
        self.dispatch_h: list[Handle | None] = [None] * A
        self.pending: list[list[Piece]] = [[] for _ in range(A)]
        self.zm_wait: list[Piece | None] = [None] * A
        self.told_sleep: set[Piece] = set()
        self.released: set[Piece] = resources.Released()
        self._heads: dict[tuple[str, int], tuple[list[Piece], int, int]] = {}
        """Per resource: (its order list, ``released.shrunk``, index of the
        first use in it not released), the scan position of :meth:`_grantable`."""
        self.held: dict[Piece, int] = {}
        self.orders: dict[tuple[str, int], list[Piece]] = {}
        self.plans: list[Schedule] = [plan]
        """Every plan followed, in order: the one given, then one per re-solve."""
        self.plan_of: list[int] = [0] * T
        """Per task, the plan (index in :attr:`plans`) its planned times and
        arm come from: the last one that planned it to run."""
        self.dropped: frozenset[int] = frozenset()
        """Tasks the last re-solve dropped (:attr:`scheduler.Rescheduled.dropped`)."""
        self.never: set[int] = set()
        """Tasks that cannot run under the current plan (see _build_orders)."""
        self.task_pieces: dict[int, list[PieceUse]] = {}
        self.activation: tuple[str, ...] | None = None
        self.activation_acks: set[int] = set()
        self.resolve_latency: list[float] = []
        self.resolves = 0
        self.detours = 0
        self.alarms: set[int] = set()
        """Emergency stops in force (by id)."""
        self._stop_ids = itertools.count(1)
        self.activation_id = 0
        self.activation_slept: set[int] = set()
        """Arms told to stop for the pending activation (each is woken after it)."""
        zm = compiled.cell.zone_map
        start_in: dict[Any, list[str | int]] = {
            a: [p.zone_names[z] for z in p.arm_start_zones[a]]
            for a in range(A)
            if p.arm_start_zones[a]
        }
        self.zm = ZoneManager(zm, list(range(A)), start_in=start_in, deadlock_policy=ReportOnly())
        # Zones of the problem that are not in the SDL (the compile's arm-pair
        # zones, workcell.geometry.reach) are kept apart by the plan order alone.
        self.sdl_zones = frozenset(zm.zone_names())
        self.cleared: list[list[tuple[int, ArmView]]] = [[] for _ in range(A)]
        """Per arm, the departures cleared (S2.12) that its reports have not
        acknowledged yet: (number of the answer, the view it asked from)."""
        self.failing: set[int] = set()
        """Arms told to fail whose report of the failure has not come yet."""
        net.receivers[0] = channel.at_coordinator
        channel.attach_coordination(self.on_report, frames=self.receive)
        self.guard = (
            GeometryGuard(compiled, clock=lambda: self.kernel.now, answer=guard_answer)
            if geometry
            else None
        )
        self.geo_held: dict[int, list[int]] = {}
        self.backoffs = 0
        self.max_backoffs = 2 * self.p.n_tasks + 2
        self.detour_tried: set[tuple[int, int, int]] = set()
        self.recheck_limit = 8 + 4 * A
        """Passes of the geometric recheck at one instant before the next waits."""
        self.max_stalled = 200
        self.recheck = Throttle(
            kernel,
            self._recheck,
            limit=self.recheck_limit,
            max_stalled=self.max_stalled,
            period=self.guard.dt if self.guard is not None else 0.01,
        )
        """The geometric recheck's throttle (its ``stalled``: deferred
        rechecks since a task last started or ended)."""
        self.detour_planning = bool(detours)
        """Plan S2.12 alternative trajectories (off: an ablation)."""
        self.detour_checks = int(detour_checks)
        """Work limit of one OMPL detour search (validity checks, about 10 us
        each): a search that needs more answers "no detour" and the arm waits."""
        self._build_orders()

    def set_status(self, t: int, new: TaskState) -> None:
        """Move task ``t`` to ``new``; an illegal transition raises
        :class:`~multiarm.errors.InternalError`."""
        TASK_MACHINE.check(self.status[t], new)
        self.status[t] = new

    # ------------------------------------------------------------ plan data
    def _pieces(self, t: int, plan: Schedule) -> list[PieceUse]:
        """Every resource use of task ``t`` under ``plan``."""
        return task_pieces(self.p, plan, t)

    def _build_orders(self) -> None:
        """Per resource, the uses in plan order (held ones first)."""
        p = self.p
        orders: dict[tuple[str, int], list[tuple[float, int, float, Piece]]] = {}
        for a in range(p.n_arms):
            for z in p.arm_start_zones[a]:
                if p.zone_exclusive[z]:
                    piece: Piece = Piece("zone", int(z), -1 - a, 0.0)
                    if piece not in self.released:
                        orders.setdefault(("zone", int(z)), []).append((-math.inf, -1, 0.0, piece))
        # tasks that will never run under this plan (on a failed arm, dropped
        # by the last re-solve, or after such a task) hold no place in any order
        never: set[int] = set()
        for t in p.topological_order:
            if self.status[t] in ("done", "running"):
                continue
            if (
                self.status[t] == "failed"
                or t in self.dropped
                or int(p.mode_arm[int(self.plan.mode[t])]) in self.failed_arms
                or any(q in never for q in p.task_preds[t])
            ):
                never.add(t)
        self.never = never
        for t in range(p.n_tasks):
            if self.status[t] in ("done", "failed") or t in never:
                continue
            pieces = self.task_pieces.get(t)
            if pieces is None or self.status[t] == "pending":
                pieces = self._pieces(t, self.plan)
            for piece, _s, _e, wall in pieces:
                if piece in self.released:
                    continue
                key = (piece.kind, piece.resource)
                first = -math.inf if piece in self.held else wall
                orders.setdefault(key, []).append((first, t, piece.tau, piece))
        self.orders = {k: [x[3] for x in sorted(v, key=lambda x: x[:3])] for k, v in orders.items()}

    def _grantable(self, piece: Piece) -> bool:
        """Every use of ``piece``'s resource that the order puts before it is
        released (the first use not released is ``piece``, or there is none).

        The uses before the first one not released stay released (until
        the set shrinks, or the order list is rebuilt), so the scan goes
        on from where the last one stopped."""
        if not self.zone_checks:
            return True
        key = (piece.kind, piece.resource)
        order = self.orders.get(key)
        if not order:
            return True
        released = self.released
        if piece in released:  # rare: a use asked for again after its release
            for q in order:
                if q == piece:
                    return True
                if q not in released:
                    return False
            return True
        shrunk = getattr(released, "shrunk", -1)
        head = self._heads.get(key)
        i = head[2] if head is not None and head[0] is order and head[1] == shrunk >= 0 else 0
        n = len(order)
        while i < n and order[i] in released:
            i += 1
        self._heads[key] = (order, shrunk, i)
        return i == n or order[i] == piece

    # ------------------------------------------------------------ dispatch
    def start(self) -> None:
        """Dispatch the first task of every arm (at its planned departure)."""
        for t in range(self.p.n_tasks):
            if self.release[t] > 0 and math.isfinite(self.release[t]):
                self.kernel.schedule(self.release[t], self._on_release, t, absolute=True)
        for a in range(self.p.n_arms):
            self._dispatch_next(a)

    def _next_task(self, a: int) -> int:
        seq = [
            t
            for t in range(self.p.n_tasks)
            if self.status[t] == "pending"
            and int(self.p.mode_arm[int(self.plan.mode[t])]) == a
            and t not in self.never
        ]
        if not seq:
            return -1
        return min(seq, key=lambda t: (float(self.plan.start[t]), t))

    def _dispatch_next(self, a: int) -> None:
        h = self.dispatch_h[a]
        if h is not None:
            h.cancel()
            self.dispatch_h[a] = None
        if (
            a in self.failed_arms
            or a in self.failing
            or self.arm_busy[a]
            or self.activation is not None
        ):
            return
        t = self._next_task(a)
        if t < 0 or t in self.dropped:
            return
        depart = float(self.plan.start[t]) - self.p.setup_time(a, self.prev[a], t)
        now = self.kernel.now
        if depart > now:
            self.dispatch_h[a] = self.kernel.schedule(depart, self._dispatch_next, a, absolute=True)
            return
        self._send_trajectory(a, t)

    def _send_trajectory(self, a: int, t: int) -> None:
        pieces = self._pieces(t, self.plan)
        self.task_pieces[t] = pieces
        legs = build_legs(self.cc, self.plan, self.book[a], t, self.prev[a] < 0, pieces)
        self.set_status(t, TaskState.DISPATCHED)
        self.prev[a] = t
        permit = self._startable(t)
        if permit:
            self.permitted.add(t)
        self.arm_busy[a] = True
        self.channel.send(0, a + 1, "trajectory", Trajectory(tuple(legs), permit))

    def _startable(self, t: int) -> bool:
        return self.kernel.now >= self.release[t] and all(
            self.status[q] == "done" for q in self.p.task_preds[t]
        )

    def _permit(self, t: int) -> None:
        if t in self.permitted or self.status[t] != "dispatched" or not self._startable(t):
            return
        self.permitted.add(t)
        a = int(self.p.mode_arm[int(self.plan.mode[t])])
        self.channel.send(0, a + 1, "wake_up", StartPermit(t))

    def _on_release(self, t: int) -> None:
        if self.kernel.now >= self.release[t]:
            self._permit(t)

    def task_started(self, a: int, t: int, now: float) -> None:
        self.set_status(t, TaskState.RUNNING)
        self.recheck.progress()
        self.trace.add(now, "task_start", arm=self.p.arm_names[a], task=self.p.task_names[t])

    def task_ended(self, a: int, t: int, now: float) -> None:
        self.trace.add(now, "task_end", arm=self.p.arm_names[a], task=self.p.task_names[t])

    # ------------------------------------------------------------ geometry

    # ------------------------------------------------------------ messages

    def _task_done(self, a: int, t: int) -> None:
        self.set_status(t, TaskState.DONE)
        self.recheck.progress()
        self.arm_busy[a] = False
        if self.zone_checks and self.zm.waiting(a) is None and self.zm.is_moving(a):
            self._events(self.zm.stop(a).events)
        for s in self.p.task_succs[t]:
            self._permit(s)
        if self.activation is not None:
            self.activation_acks.add(a)
            self._try_activation()
            return
        self._dispatch_next(a)

    def task_failed(self, a: int, t: int, cause: str) -> None:
        """Task ``t`` ran on arm ``a`` to its end but failed (an insertion
        whose hole was never found, S1.7): it and every task after it are
        reported failed with the cause (as for a part that never comes); the
        arms go on with the rest of the plan."""
        p = self.p
        now = self.kernel.now
        self.set_status(t, TaskState.FAILED)
        self.cause[t] = cause
        self.cause_kind[t] = "insertion"
        self.recheck.progress()
        self.arm_busy[a] = False
        self.trace.add(now, "task_failed", arm=p.arm_names[a], task=p.task_names[t], detail=cause)
        if self.zone_checks and self.zm.waiting(a) is None and self.zm.is_moving(a):
            self._events(self.zm.stop(a).events)
        stack = list(p.task_succs[t])
        while stack:
            s = stack.pop()
            if self.status[s] not in ("pending", "dispatched"):
                continue
            if self.status[s] == "dispatched":  # its arm waits at its start
                self._withdraw(s)
            self.set_status(s, TaskState.FAILED)
            if not self.cause[s]:
                self.cause[s] = f"predecessor {p.task_names[t]!r} failed: {cause}"
                self.cause_kind[s] = "predecessor"
            self.trace.add(now, "task_failed", task=p.task_names[s], detail=self.cause[s])
            stack.extend(p.task_succs[s])
        self._build_orders()
        self._serve_all()
        if self.activation is not None:
            self.activation_acks.add(a)
            self._try_activation()
            return
        for b in range(p.n_arms):
            self._dispatch_next(b)

    # geometric
    on_report = geometric.on_report
    blockers = geometric.blockers
    check_departure = geometric.check_departure
    reserved = geometric.reserved
    try_detour = geometric.try_detour
    back_off = geometric.back_off
    arm_moved = geometric.arm_moved
    _recheck = geometric._recheck
    _promote = geometric._promote

    # resources
    receive = resources.receive
    _zone_name = resources._zone_name
    _serve_all = resources._serve_all
    _serve = resources._serve
    _sleep = resources._sleep
    _granted = resources._granted
    _zm_request = resources._zm_request
    _events = resources._events
    _release = resources._release
    _position = resources._position

    # recovery
    emergency_stop = recovery.emergency_stop
    _clear_alarm = recovery._clear_alarm
    arm_failed = recovery.arm_failed
    arm_out = recovery.arm_out
    part_late = recovery.part_late
    parts_late = recovery.parts_late
    activate = recovery.activate
    _try_activation = recovery._try_activation
    _withdraw = recovery._withdraw
    _withdraw_never = recovery._withdraw_never
    _fail_never = recovery._fail_never
    _fail_impossible = recovery._fail_impossible
    resolve = recovery.resolve

    # ------------------------------------------------------------ faults

    # ------------------------------------------------------------ re-solve
