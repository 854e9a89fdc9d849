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
  its next station, :class:`GeometryGuard` checks that motion against the
  other arms (standing or moving); a contact means *stop*. Around arms
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
medium; a lost or dropped frame is sent again after a timeout.
"""

from __future__ import annotations

import bisect
import itertools
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from multiarm.errors import InternalError, UsageError
from multiarm.types import FloatArray
from scheduler import Problem, Schedule
from scheduler.online import CellState, reschedule
from scheduler.schedule import ScheduleError
from workcell.compile import CompiledCell
from workcell.geometry import CollisionWorld, ObstacleSet, plan_detour
from workcell.geometry._sweep_jit import capsules_touch
from workcell.geometry.sweep import _segment_distances, _segments, _shape_capsules
from workcell.sim.comms.medium import BROADCAST, MESSAGE_BYTES, Frame, Medium, trajectory_bytes
from workcell.sim.control.controller import ArmController, Leg, Piece, Station
from workcell.sim.events.loop import EventLoop, Handle
from workcell.sim.events.trace import Trace
from workcell.sim.harness.faults import MessageLoss
from zones import ZoneManager
from zones.manager import Deadlock, ReportOnly, Wake

__all__ = ["CAUSE_KINDS", "FAR", "Coordinator", "GeometryGuard", "Network"]

CAUSE_KINDS: tuple[str, ...] = (
    "arm_failed",
    "part_missing",
    "deadlock",
    "insertion",
    "predecessor",
    "arm_out",
    "stall",
)
"""The categories of a failed task's cause (``SimResult.tasks_frame()``
column ``cause_kind``): every capable arm failed; a part never came; a
deadlock (with its wait-for cycle); its insertion failed; a predecessor
could not run; its arm failed with re-solving off; the run stalled (an arm
with work, no stop in force and no event pending: a bug of the simulator)."""

FAR = 1e7
"""Seconds: where a re-solve puts tasks that can never run (no working arm,
a part that never comes); they are reported failed with their cause."""


class Network:
    """Sends coordination messages through a medium, with loss and retransmission.

    Parameters
    ----------
    kernel : EventLoop
    medium : Medium
    trace : Trace
    names : sequence of str
        Station names (0: the coordinator, then the arms).
    loss : MessageLoss, optional
    rng : numpy Generator
    """

    def __init__(
        self,
        kernel: EventLoop,
        medium: Medium,
        trace: Trace,
        names: list[str],
        loss: MessageLoss | None,
        rng: np.random.Generator,
    ) -> None:
        self.kernel = kernel
        self.medium = medium
        self.trace = trace
        self.names = names
        self.loss = loss
        self.rng = rng
        self.receivers: dict[int, Callable[[Frame], None]] = {}
        self._next_seq: dict[tuple[int, int], int] = {}
        self._seen: dict[tuple[int, int, int], set[int]] = {}
        """(src, dst as sent, receiving station) -> sequence numbers delivered."""
        self._cancelled: dict[tuple[int, int], int] = {}
        """(receiving station, task) -> sequence number of its withdrawal."""
        self.stale = 0
        """Frames dropped at the receiver: duplicates and frames older than a
        withdrawal of their task."""
        self.sent = 0
        self.retransmissions = 0
        self.delays: list[float] = []
        for st in range(len(names)):
            medium.attach(st, self._receiver(st))
        medium.on_drop(self._dropped)

    def send(
        self, src: int, dst: int, kind: str, payload: Any, retry: int = 0, seq: int = -1
    ) -> None:
        """Send a frame now (``dst`` may be BROADCAST).

        Each link ``(src, dst)`` numbers its frames 0, 1, 2, ...; a
        retransmission (``retry > 0``) keeps the number of the original
        (``seq``)."""
        size = trajectory_bytes(5) if kind == "trajectory" else MESSAGE_BYTES[kind]
        if seq < 0:
            seq = self._next_seq.get((src, dst), 0)
            self._next_seq[(src, dst)] = seq + 1
        frame = Frame(src=src, dst=dst, size=size, kind=kind, payload=(payload, retry), seq=seq)
        self.sent += 1
        if retry:
            self.retransmissions += 1
        lp = self.loss
        if (
            lp is not None
            and lp.probability > 0
            and (lp.kinds is None or kind in lp.kinds)
            and self.rng.random() < lp.probability
        ):
            self.trace.add(
                self.kernel.now,
                "fault",
                arm=self._arm_of(src, dst),
                message=kind,
                src=src,
                dst=dst,
                size=size,
                detail=f"message lost or corrupted; sent again after {lp.timeout:g} s",
            )
            self.kernel.schedule(lp.timeout, self.send, src, dst, kind, payload, retry + 1, seq)
            return
        self.medium.send(frame)

    def _arm_of(self, src: int, dst: int) -> str:
        st = src if src > 0 else dst
        return self.names[st] if 0 < st < len(self.names) else ""

    def _receiver(self, station: int) -> Callable[[Frame, float], None]:
        def rx(frame: Frame, t: float) -> None:
            self._deliver(frame, t, station)

        return rx

    def _stale(self, frame: Frame, payload: Any, station: int) -> str:
        """Why the receiver drops ``frame`` ("" if it does not)."""
        seen = self._seen.setdefault((frame.src, frame.dst, station), set())
        if frame.seq in seen:
            return f"duplicate (sequence number {frame.seq})"
        seen.add(frame.seq)
        task = _frame_task(frame.kind, payload)
        if task < 0 or frame.src != 0:
            return ""
        if frame.kind == "sleep" and payload[0] == "withdraw":
            self._cancelled[(station, task)] = frame.seq
            return ""
        cut = self._cancelled.get((station, task), -1)
        if frame.seq < cut:
            return f"older than the withdrawal of task {task} (sequence number {frame.seq} < {cut})"
        return ""

    def _deliver(self, frame: Frame, t: float, station: int) -> None:
        payload: Any = frame.payload[0]  # type: ignore[index]
        why = self._stale(frame, payload, station)
        if why:
            self.stale += 1
            self.trace.add(
                t,
                "drop",
                arm=self._arm_of(frame.src, station),
                message=frame.kind,
                src=frame.src,
                dst=station,
                size=frame.size,
                detail=f"dropped at the receiver: {why}",
            )
            return
        delay = t - frame.send_time
        self.delays.append(delay)
        dst = station
        self.trace.add(
            t,
            "message",
            arm=self._arm_of(frame.src, dst),
            message=frame.kind,
            src=frame.src,
            dst=dst,
            size=frame.size,
            delay=delay,
            detail=_describe(payload),
        )
        rx = self.receivers.get(station)
        if rx is not None:
            rx(frame)

    def _dropped(self, frame: Frame, reason: str) -> None:
        payload: Any = frame.payload[0]  # type: ignore[index]
        retry: int = frame.payload[1]  # type: ignore[index]
        timeout = self.loss.timeout if self.loss is not None else 0.005
        self.trace.add(
            self.kernel.now,
            "fault",
            arm=self._arm_of(frame.src, frame.dst),
            message=frame.kind,
            src=frame.src,
            dst=frame.dst,
            size=frame.size,
            detail=f"dropped by the medium ({reason}); sent again after {timeout:g} s",
        )
        self.kernel.schedule(
            timeout, self.send, frame.src, frame.dst, frame.kind, payload, retry + 1, frame.seq
        )


class GeometryGuard:
    """The coordinator's geometric check (S2.6, S2.12) before an arm moves.

    The coordinator knows every trajectory it sent and where every standing
    arm is (position reports). Before an arm sets off towards its next
    station it checks that motion, sampled every ``dt`` seconds, against
    every other arm: a standing arm where it stands, a moving arm along its
    trajectory until its own next station (where it may stop; it is checked
    again before it goes on), over the time until every one of them has
    reached its next station. The test is the conservative capsule test of
    the zone sweep (every shape inside a capsule, grown by ``padding``),
    whose candidates FCL decides with the shapes grown by ``padding / 2``.
    A contact means *stop*: the arm waits at its station until the way is
    clear.

    Parameters
    ----------
    compiled : CompiledCell
    dt : float
        Seconds between samples.
    padding : float
        Metres added around every shape.
    """

    def __init__(self, compiled: CompiledCell, dt: float = 0.01, padding: float = 0.02) -> None:
        cell = compiled.cell
        self.cell = cell
        self.dt = float(dt)
        self.padding = float(padding)
        self.capsules = [_shape_capsules(arm.shapes) for arm in cell.arms]
        self._boxes: dict[int, tuple[FloatArray, Any]] = {}
        self.world = CollisionWorld()
        for arm, q in zip(cell.arms, cell.start, strict=True):
            self.world.add_arm(arm, q=q, padding=self.padding / 2)
        self.checks = 0

    def _box(self, ctl: ArmController) -> FloatArray:
        """(2, 3) box holding everything the arm may sweep on its current leg
        (or where it stands), grown by the padding; cached per leg."""
        leg = ctl.leg
        key = id(leg) if leg is not None else -1 - ctl.index
        got = self._boxes.get(key)
        if got is not None and (leg is not None or got[1] is ctl.q):
            return got[0]
        arm = self.cell.arms[ctl.index]
        if leg is None:
            q = ctl.q[None, :]
            margin = 0.0
        else:
            tr = leg.trajectory
            t = np.union1d(tr.knot_times, np.arange(0.0, tr.duration, 0.02))
            q = tr.sample(t)
            step = arm.displacement_bound(np.diff(q, axis=0)) if len(q) > 1 else np.zeros(1)
            margin = float(step.max()) / 2 if len(step) else 0.0
        p0, p1 = self._ends(ctl.index, q)
        r = float(self.capsules[ctl.index][1].max()) + self.padding + margin
        box = np.stack(
            [
                np.minimum(p0.min(axis=(0, 1)), p1.min(axis=(0, 1))) - r,
                np.maximum(p0.max(axis=(0, 1)), p1.max(axis=(0, 1))) + r,
            ]
        )
        self._boxes[key] = (box, leg if leg is not None else ctl.q)
        return box

    def _ends(self, a: int, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        return _segments(self.cell.arms[a], q, self.capsules[a][0])

    def blockers(self, mover: ArmController, arms: list[ArmController]) -> list[int]:
        """Arms in the way of ``mover``'s motion to its next station."""
        leg = mover.leg
        if leg is None:
            return []
        tau0 = mover.tau
        tau1 = leg.stations[mover.k].tau
        dur = tau1 - tau0
        if dur <= 0:
            return []
        self.checks += 1
        (mx0, my0, mz0), (mx1, my1, mz1) = self._box(mover).tolist()
        near = []
        for o in arms:
            if o is mover:
                continue
            (ox0, oy0, oz0), (ox1, oy1, oz1) = self._box(o).tolist()
            if (
                ox0 <= mx1
                and oy0 <= my1
                and oz0 <= mz1
                and ox1 >= mx0
                and oy1 >= my0
                and oz1 >= mz0
            ):
                near.append(o)
        if not near:
            return []
        now = mover.kernel.now
        # until the mover and every moving arm near it reach their next stations
        horizon = max([dur] + [o.next_stop_time() - now for o in near if o.running])
        n = max(2, math.ceil(horizon / self.dt) + 1)
        off = np.linspace(0.0, horizon, n)
        times = now + off
        qa = leg.trajectory.sample(np.minimum(tau0 + off, tau1))
        a0, a1 = self._ends(mover.index, qa)
        ra = self.capsules[mover.index][1]
        out = []
        reach = float(ra.max()) + self.padding
        lo = np.minimum(a0.min(axis=(0, 1)), a1.min(axis=(0, 1))) - reach
        hi = np.maximum(a0.max(axis=(0, 1)), a1.max(axis=(0, 1))) + reach
        for other in near:
            # a standing arm is sampled once
            qb = other.predict(times if other.running else times[:1])
            b0, b1 = self._ends(other.index, qb)
            rb = self.capsules[other.index][1]
            rmax = float(rb.max())
            blo = np.minimum(b0.min(axis=(0, 1)), b1.min(axis=(0, 1))) - rmax
            bhi = np.maximum(b0.max(axis=(0, 1)), b1.max(axis=(0, 1))) + rmax
            if np.any(blo > hi) or np.any(bhi < lo):
                continue  # swept boxes apart
            if other.running:
                d = _segment_distances(
                    a0[:, :, None, :], a1[:, :, None, :], b0[:, None, :, :], b1[:, None, :, :]
                )
                hit = np.any(d <= ra[:, None] + rb[None, :] + self.padding, axis=(1, 2))
            else:  # a standing arm: the compiled test against fixed capsules
                hit = capsules_touch(
                    np.ascontiguousarray(a0),
                    np.ascontiguousarray(a1),
                    np.ascontiguousarray(ra, dtype=float),
                    np.ascontiguousarray(b0[0]),
                    np.ascontiguousarray(b1[0]),
                    np.ascontiguousarray(rb, dtype=float),
                    self.padding,
                )
            if hit.any() and self._confirm(mover.index, qa, other.index, other, times, hit):
                out.append(other.index)
        return out

    def _confirm(
        self,
        a: int,
        qa: FloatArray,
        b: int,
        other: ArmController,
        times: FloatArray,
        near: FloatArray,
    ) -> bool:
        """FCL (shapes grown by half the padding) on the capsule test's candidates."""
        idx = np.flatnonzero(near)
        arm_a, arm_b = self.cell.arms[a], self.cell.arms[b]
        tfa = arm_a.shape_transforms(qa[idx])
        tfb = arm_b.shape_transforms(other.predict(times[idx]))
        if len(tfb) < len(idx):  # pragma: no cover - predict keeps the length
            tfb = np.repeat(tfb[:1], len(idx), axis=0)
        for i in range(len(idx)):
            self.world.set_group_transforms(arm_a.name, tfa[i])
            self.world.set_group_transforms(arm_b.name, tfb[i])
            if self.world.collide(arm_a.name, arm_b.name):
                return True
        return False


def _frame_task(kind: str, payload: Any) -> int:
    """The task a coordinator frame is about (-1: none): a trajectory's, a
    grant's or wake-up's piece ``(kind, index, task, tau)``, a start
    permission or a withdrawal."""
    if kind == "trajectory":
        return int(payload[0][-1].task)
    if (
        kind in ("zone_grant", "wake_up", "sleep")
        and isinstance(payload, tuple)
        and len(payload) == 4
        and payload[0] in ("zone", "move", "tool", "start", "withdraw")
    ):
        return int(payload[2])
    return -1


def _describe(payload: Any) -> str:
    if isinstance(payload, tuple) and len(payload) == 4 and isinstance(payload[0], str):
        return f"{payload[0]} {payload[1]} task {payload[2]} at {payload[3]:.6g}"
    if isinstance(payload, tuple) and payload and isinstance(payload[0], str):
        return str(payload[0])
    if isinstance(payload, int):
        return f"task {payload}"
    return ""


class Coordinator:
    """The centralized coordinator of a simulated run (module docstring).

    Parameters
    ----------
    compiled : CompiledCell
    plan : Schedule
    kernel : EventLoop
    net : Network
    trace : Trace
    arms : list of ArmController
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
    """

    def __init__(
        self,
        compiled: CompiledCell,
        plan: Schedule,
        kernel: EventLoop,
        net: Network,
        trace: Trace,
        arms: list[ArmController],
        *,
        seed: int = 0,
        resolve_budget: float = 0.015,
        resolve_evaluations: int = 200,
        zone_checks: bool = True,
        geometry: bool = True,
        resolving: bool = True,
    ) -> None:
        self.cc = compiled
        self.p: Problem = compiled.problem
        self.plan = plan
        self.kernel = kernel
        self.net = net
        self.trace = trace
        self.arms = arms
        self.seed = seed
        self.resolve_budget = float(resolve_budget)
        self.resolve_evaluations = int(resolve_evaluations)
        self.zone_checks = zone_checks
        self.resolving = bool(resolving)
        p = self.p
        T, A = p.n_tasks, p.n_arms
        self.status = ["pending"] * T
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
        self.released: set[Piece] = set()
        self.held: dict[Piece, int] = {}
        self.orders: dict[tuple[str, int], list[Piece]] = {}
        self.never: set[int] = set()
        """Tasks that cannot run under the current plan (see _build_orders)."""
        self.task_pieces: dict[int, list[tuple[Piece, float, float, float]]] = {}
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
        net.receivers[0] = self.receive
        self.guard = GeometryGuard(compiled) if geometry else None
        self.geo_held: dict[int, list[int]] = {}
        self._recheck_h: Handle | None = None
        self.backoffs = 0
        self.max_backoffs = 2 * self.p.n_tasks + 2
        self.detour_tried: set[tuple[int, int, int]] = set()
        self._recheck_at = -math.inf
        self._recheck_n = 0
        self.recheck_limit = 8 + 4 * A
        """Passes of the geometric recheck at one instant before the next waits."""
        self.stalled = 0
        """Deferred rechecks since a task last started or ended."""
        self.max_stalled = 200
        self.detour_checks = 10_000
        """Work limit of one OMPL detour search (validity checks, about 10 us
        each): a search that needs more answers "no detour" and the arm waits."""
        for arm in arms:
            arm.on_task_start = self._on_task_start
            arm.on_task_end = self._on_task_end
            if self.guard is not None:
                arm.guard = self._guard
                arm.probe = self._probe
                arm.notify = self._notify
        self._build_orders()

    # ------------------------------------------------------------ plan data
    def _pieces(self, t: int, plan: Schedule) -> list[tuple[Piece, float, float, float]]:
        """(piece, acquire tau, release tau, planned wall start) of task ``t``."""
        p = self.p
        m = int(plan.mode[t])
        sh = p.shapes[m]
        S = float(plan.start[t])
        w = plan.waits[t]
        Z = p.n_zones
        out: list[tuple[Piece, float, float, float]] = []
        borders = sh.borders
        wl = w.tolist()
        cw = [0.0]  # waits at the borders <= x: cw[bisect_right(borders, x)] (as ModeShape.shift)
        for x in wl:
            cw.append(cw[-1] + x)
        for r, s, e in sh.exclusive:
            out.append((("zone", r, t, s), s, e, S + s + cw[bisect.bisect_right(borders, s)]))
        wait_at = dict(zip(borders, wl, strict=True))
        for r, s, e in sh.moves:
            cuts = [b for b in borders if s < b < e and wait_at[b] > 0]
            pts = [s, *cuts, e]
            for p0, p1 in itertools.pairwise(pts):
                out.append(
                    (("move", r - Z, t, p0), p0, p1, S + p0 + cw[bisect.bisect_right(borders, p0)])
                )
        for r in sh.tools:
            out.append((("tool", r - 2 * Z, t, 0.0), 0.0, sh.duration, S))
        return out

    def _build_orders(self) -> None:
        """Per resource, the uses in plan order (held ones first)."""
        p = self.p
        orders: dict[tuple[str, int], list[tuple[float, int, float, Piece]]] = {}
        for a in range(p.n_arms):
            for z in p.arm_start_zones[a]:
                if p.zone_exclusive[z]:
                    piece: Piece = ("zone", int(z), -1 - a, 0.0)
                    if piece not in self.released:
                        orders.setdefault(("zone", int(z)), []).append((-math.inf, -1, 0.0, piece))
        # tasks that will never run under this plan (on a failed arm, after
        # FAR, or after such a task) hold no place in any order
        never: set[int] = set()
        for t in p.topological_order:
            if self.status[t] in ("done", "running"):
                continue
            if (
                self.status[t] == "failed"
                or float(self.plan.start[t]) >= FAR
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
                key = (piece[0], piece[1])
                first = -math.inf if piece in self.held else wall
                orders.setdefault(key, []).append((first, t, piece[3], piece))
        self.orders = {k: [x[3] for x in sorted(v, key=lambda x: x[:3])] for k, v in orders.items()}

    def _grantable(self, piece: Piece) -> bool:
        if not self.zone_checks:
            return True
        for q in self.orders.get((piece[0], piece[1]), ()):
            if q == piece:
                return True
            if q not in self.released:
                return False
        return True

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
        if a in self.failed_arms or self.arm_busy[a] or self.activation is not None:
            return
        t = self._next_task(a)
        if t < 0 or float(self.plan.start[t]) >= FAR:
            return
        depart = float(self.plan.start[t]) - self.p.setup_time(a, self.prev[a], t)
        now = self.kernel.now
        if depart > now:
            self.dispatch_h[a] = self.kernel.schedule(depart, self._dispatch_next, a, absolute=True)
            return
        self._send_trajectory(a, t)

    def _send_trajectory(self, a: int, t: int) -> None:
        p = self.p
        arm = self.arms[a]
        m = int(self.plan.mode[t])
        cm = self.cc.modes[m]
        pieces = self._pieces(t, self.plan)
        self.task_pieces[t] = pieces
        S = float(self.plan.start[t])
        sh = p.shapes[m]
        w = self.plan.waits[t]
        stations: dict[float, Station] = {0.0: Station(0.0, notbefore=S, start=True)}
        for j, b in enumerate(sh.borders):
            stations[b] = Station(b, notbefore=S + b + float(np.sum(w[: j + 1])), border=j)
        D = float(cm.trajectory.duration)
        end = Station(D, end=True)
        for piece, s, e, _wall in pieces:
            stations.setdefault(s, Station(s)).acquire.append(piece)
            if e >= D:
                end.release.append(piece)
            else:
                stations.setdefault(e, Station(e)).release.append(piece)
        stations.pop(D, None)
        task_st = [stations[k] for k in sorted(stations)] + [end]
        legs: list[Leg] = []
        travel = arm.arm.move(arm.q, cm.q_start, arm.arm.interpolation)
        first: list[Piece] = []
        if self.prev[a] < 0:  # leaving the start zones
            first = [
                ("zone", int(z), -1 - a, 0.0) for z in p.arm_start_zones[a] if p.zone_exclusive[z]
            ]
        if travel.duration > 0:
            legs.append(
                Leg(
                    "travel",
                    t,
                    -1,
                    travel,
                    [Station(0.0, release=first), Station(travel.duration, end=True)],
                )
            )
        else:
            task_st[0].release.extend(first)
        legs.append(Leg("task", t, m, cm.trajectory, task_st))
        self.status[t] = "dispatched"
        self.prev[a] = t
        permit = self._startable(t)
        if permit:
            self.permitted.add(t)
        self.arm_busy[a] = True
        self.net.send(0, a + 1, "trajectory", (legs, permit))

    def _startable(self, t: int) -> bool:
        return self.kernel.now >= self.release[t] and all(
            self.status[q] == "done" for q in self.p.task_preds[t]
        )

    def _permit(self, t: int) -> None:
        if t in self.permitted or self.status[t] != "dispatched" or not self._startable(t):
            return
        self.permitted.add(t)
        a = int(self.p.mode_arm[int(self.plan.mode[t])])
        self.net.send(0, a + 1, "wake_up", ("start", -1, t, 0.0))

    def _on_release(self, t: int) -> None:
        if self.kernel.now >= self.release[t]:
            self._permit(t)

    def _on_task_start(self, a: int, t: int, now: float) -> None:
        self.status[t] = "running"
        self.stalled = 0
        self.trace.add(now, "task_start", arm=self.p.arm_names[a], task=self.p.task_names[t])

    def _on_task_end(self, a: int, t: int, now: float) -> None:
        self.trace.add(now, "task_end", arm=self.p.arm_names[a], task=self.p.task_names[t])

    # ------------------------------------------------------------ geometry
    def _guard(self, ctl: ArmController) -> bool:
        assert self.guard is not None
        blockers = self.guard.blockers(ctl, self.arms)
        a = ctl.index
        if not blockers:
            if a in self.geo_held:
                del self.geo_held[a]
                self.trace.add(
                    self.kernel.now, "wake", arm=ctl.name, detail="geometric conflict over: go on"
                )
            return True
        if self.geo_held.get(a) != blockers:
            names = ", ".join(repr(self.p.arm_names[b]) for b in blockers)
            self.trace.add(
                self.kernel.now,
                "sleep",
                arm=ctl.name,
                task=self.p.task_names[ctl.leg.task] if ctl.leg is not None else "",
                detail=f"geometric conflict (S2.12): arm {names} in the way: stop",
            )
            self.geo_held[a] = blockers
            self._notify()
        return False

    def _detour(self, ctl: ArmController) -> bool:
        """S2.12 "continue with alternative trajectory": an OMPL path to the
        next station around the arms standing in the way (tried once per
        station; work-limited, so the same seed plans the same path)."""
        leg = ctl.leg
        blockers = self.geo_held.get(ctl.index, [])
        if (
            leg is None
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
        if not res.solved:  # "direct" (the straight joint move is free) or "solved"
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
        if extra > float(self.plan.blocking[leg.task]) + 1e-9:
            self.resolve(f"detour of task {self.p.task_names[leg.task]!r} costs more than planned")
        return True

    def _probe(self, ctl: ArmController) -> bool:
        assert self.guard is not None
        return not self.guard.blockers(ctl, self.arms)

    def _notify(self) -> None:
        """Look at the geometric stops again (after something moved or stopped).

        Progress is guaranteed: at most ``recheck_limit`` passes run at one
        instant; after that the next pass comes one guard period later (the
        kernel's time advances), and after ``max_stalled`` such deferred
        passes with no task starting or ending the arms still stopped stay
        stopped (an unresolved geometric deadlock, reported per task)."""
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

    def _recheck(self) -> None:
        self._recheck_h = None
        for ctl in self.arms:
            if ctl.failed:
                continue
            if ctl.away is not None and ctl.leg is None and ctl.away_until is not None:
                ai, leg_a, k_a = ctl.away_until
                mover = self.arms[ai]
                # back once the mover has finished that task (its leg is over
                # and it is not on an excursion from it), or waits for a grant
                passed = mover.leg is not leg_a and mover.away is None
                waits = mover.stuck() and "geometry" not in mover.stops
                del k_a
                if mover.failed or passed or waits:
                    ctl.come_back()
            if "geometry" not in ctl.stops:
                continue
            ctl.stops.discard("geometry")
            if not ctl.at_station and not ctl.stops:
                ctl._run()
            if "geometry" in ctl.stops and self._detour(ctl):
                continue
            if "geometry" in ctl.stops:
                blockers = self.geo_held.get(ctl.index, [])
                if (
                    blockers
                    and self.backoffs < self.max_backoffs
                    and all(self.arms[b].stuck() and self.arms[b].away is None for b in blockers)
                ):
                    moved = False
                    for b in blockers:
                        if self.arms[b].back_off((ctl.index, ctl.leg, ctl.k)):
                            moved = True
                            self.backoffs += 1
                            self.detours += 1
                            self.trace.add(
                                self.kernel.now,
                                "detour",
                                arm=self.p.arm_names[b],
                                detail=f"geometric deadlock (S2.6): backs off to its home joints "
                                f"out of arm {ctl.name!r}'s way",
                            )
                    if not moved:
                        self._promote(ctl.index, blockers)

    def _promote(self, a: int, blockers: list[int]) -> None:
        """Last resort of a geometric deadlock: an arm standing in ``a``'s way
        waits for a resource the plan gives ``a`` first, and cannot back off;
        let it go first (``a`` has not taken that resource yet)."""
        for b in blockers:
            if not self.pending[b] or self.zm_wait[b] is not None:
                continue
            piece = self.pending[b][0]
            order = self.orders.get((piece[0], piece[1]), [])
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
                task=self.p.task_names[piece[2]] if piece[2] >= 0 else "",
                zone=self._zone_name(piece),
                detail=f"geometric deadlock (S2.6): goes before arm {self.p.arm_names[a]!r}",
            )
            self._serve(b)

    # ------------------------------------------------------------ messages
    def receive(self, frame: Frame) -> None:
        """A frame for the coordinator."""
        payload: Any = frame.payload[0]  # type: ignore[index]
        a = frame.src - 1
        kind = frame.kind
        if a in self.failed_arms:
            return
        if kind == "zone_request":
            t = int(payload[2])
            if t >= 0 and self.status[t] not in ("dispatched", "running"):
                return  # sent before the arm heard the task was withdrawn
            self.pending[a].append(payload)
            self._serve(a)
        elif kind == "zone_release":
            self._release(a, payload)
            self._serve_all()
        elif kind == "trajectory_end":
            if isinstance(payload, tuple) and payload[0] == "failed":  # ran, but failed
                self.task_failed(a, int(payload[1]), str(payload[2]))
            elif isinstance(payload, tuple):  # a withdrawn trajectory
                self.arm_busy[a] = False
                self._dispatch_next(a)
            else:
                self._task_done(a, int(payload))
        elif kind == "position":
            self._position(a, payload)
        elif kind == "alarm":
            self.trace.add(
                self.kernel.now,
                "fault",
                arm=self.p.arm_names[a],
                detail=f"coordinator told of a reflex stop ({payload[0]}), after the fact (S1.2)",
            )

    def _zone_name(self, piece: Piece) -> str:
        if piece[0] == "tool":
            return self.p.tool_names[piece[1]]
        return self.p.zone_names[piece[1]]

    def _serve_all(self) -> None:
        for b in range(self.p.n_arms):
            if self.pending[b] and self.zm_wait[b] is None:
                self._serve(b)

    def _serve(self, a: int) -> None:
        arm_name = self.p.arm_names[a]
        while self.pending[a] and self.zm_wait[a] is None:
            piece = self.pending[a][0]
            name = self._zone_name(piece)
            task = self.p.task_names[piece[2]] if piece[2] >= 0 else ""
            if not self._grantable(piece):
                self._sleep(a, piece, name, task, "planned earlier use not over")
                return
            granted, events = self._zm_request(a, piece)
            if granted:
                self.pending[a].pop(0)
                self._granted(a, piece)
            else:
                self.zm_wait[a] = piece
                self._sleep(a, piece, name, task, "resource busy")
            self._events(events)
            if not granted:
                return
        del arm_name

    def _sleep(self, a: int, piece: Piece, name: str, task: str, why: str) -> None:
        if piece in self.told_sleep:
            return
        self.told_sleep.add(piece)
        self.trace.add(
            self.kernel.now, "sleep", arm=self.p.arm_names[a], task=task, zone=name, detail=why
        )
        self.net.send(0, a + 1, "sleep", piece)

    def _granted(self, a: int, piece: Piece) -> None:
        self.held[piece] = a
        name = self._zone_name(piece)
        task = self.p.task_names[piece[2]] if piece[2] >= 0 else ""
        if piece in self.told_sleep:
            self.trace.add(self.kernel.now, "wake", arm=self.p.arm_names[a], task=task, zone=name)
            self.net.send(0, a + 1, "wake_up", piece)
        else:
            self.trace.add(
                self.kernel.now,
                "grant",
                arm=self.p.arm_names[a],
                task=task,
                zone=name,
                detail=piece[0],
            )
            self.net.send(0, a + 1, "zone_grant", piece)

    def _zm_request(self, a: int, piece: Piece) -> tuple[bool, tuple[Any, ...]]:
        if not self.zone_checks:
            return True, ()
        kind, idx = piece[0], piece[1]
        zm = self.zm
        if kind == "tool":
            if zm.holder(self.p.tool_names[idx]) == a:
                return True, ()
            r = zm.acquire_tool(a, self.p.tool_names[idx])
        else:
            zname = self.p.zone_names[idx]
            if zname not in self.sdl_zones:
                return True, ()
            if zname in zm.zones_of(a):
                r = zm.request_move(a, zname)
            else:
                r = zm.request_enter(a, zname)
        return r.granted, r.events

    def _events(self, events: tuple[Any, ...]) -> None:
        for ev in events:
            if isinstance(ev, Wake):
                b = int(ev.arm)  # type: ignore[call-overload]
                piece = self.zm_wait[b]
                if piece is None:
                    continue
                self.zm_wait[b] = None
                self.pending[b].pop(0)
                self._granted(b, piece)
                self._serve(b)
            elif isinstance(ev, Deadlock):
                raise InternalError(
                    f"{ev.describe()}: the plan order should exclude it (please report)"
                )

    def _release(self, a: int, piece: Piece) -> None:
        self.released.add(piece)
        self.held.pop(piece, None)
        if not self.zone_checks:
            return
        kind, idx = piece[0], piece[1]
        zm = self.zm
        try:
            if zm.waiting(a) is not None:
                # asleep on a request sent ahead: withdraw it, leave, ask again
                zm.cancel(a)
                self.zm_wait[a] = None
            if kind == "tool":
                if zm.holder(self.p.tool_names[idx]) == a:
                    self._events(zm.release_tool(a, self.p.tool_names[idx]).events)
            else:
                zname = self.p.zone_names[idx]
                if zname in self.sdl_zones and zname in zm.zones_of(a):
                    self._events(zm.release(a, zname).events)
        except UsageError as exc:  # pragma: no cover - protocol bookkeeping
            raise InternalError(f"zone protocol: {exc}") from None

    def _position(self, a: int, payload: Any) -> None:
        piece, xyz = payload
        if piece is None:
            self.activation_acks.add(a)
            self._try_activation()
            return
        zm = self.zm
        if not self.zone_checks:
            return
        zname = self.p.zone_names[piece[1]]
        if zname not in self.sdl_zones:
            return
        if zm.waiting(a) is None and zm.is_moving(a):
            self._events(zm.stop(a).events)
        if zname in zm.zones_of(a) and not zm.is_moving(a):
            zm.report_position(a, zname, xyz)

    def _task_done(self, a: int, t: int) -> None:
        self.status[t] = "done"
        self.stalled = 0
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
        self.status[t] = "failed"
        self.cause[t] = cause
        self.cause_kind[t] = "insertion"
        self.stalled = 0
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
            self.status[s] = "failed"
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

    # ------------------------------------------------------------ faults
    def emergency_stop(self, duration: float) -> None:
        """Broadcast the alarm; clear it ``duration`` seconds later."""
        self.trace.add(self.kernel.now, "fault", detail=f"emergency stop for {duration:g} s")
        stop = next(self._stop_ids)
        self.alarms.add(stop)
        self.net.send(0, BROADCAST, "alarm", ("emergency", stop))
        self.kernel.schedule(duration, self._clear_alarm, stop)

    def _clear_alarm(self, stop: int) -> None:
        """Release the emergency stop ``stop`` at every working arm (matched
        by id: an arm stays stopped while any alarm is in force)."""
        self.alarms.discard(stop)
        self.trace.add(self.kernel.now, "fault", detail="emergency stop cleared")
        for a in range(self.p.n_arms):
            if a not in self.failed_arms:
                self.net.send(0, a + 1, "wake_up", ("alarm_clear", stop))

    def arm_failed(self, a: int) -> None:
        """Arm ``a`` failed: give back its resources, reassign its tasks."""
        p = self.p
        self.failed_arms.add(a)
        arm = self.arms[a]
        arm.fail()
        self.trace.add(self.kernel.now, "fault", arm=p.arm_names[a], detail="arm failure")
        h = self.dispatch_h[a]
        if h is not None:
            h.cancel()
        zm = self.zm
        if self.zone_checks:
            if zm.waiting(a) is not None:
                zm.cancel(a)
            for zname in zm.zones_of(a):
                self._events(zm.release(a, zname).events)
            for tool in zm.tools_of(a):
                self._events(zm.release_tool(a, tool).events)
        for piece, holder in list(self.held.items()):
            if holder == a:
                self.released.add(piece)
                del self.held[piece]
                if piece[2] >= 0 and self.status[piece[2]] == "running":
                    self.trace.add(
                        self.kernel.now,
                        "zone_leave",
                        arm=p.arm_names[a],
                        task=p.task_names[piece[2]],
                        zone=self._zone_name(piece),
                        detail=piece[0],
                    )
        for z in p.arm_start_zones[a]:  # retracted: out of its start zones too
            self.released.add(("zone", int(z), -1 - a, 0.0))
        self.pending[a].clear()
        self.zm_wait[a] = None
        for t in range(p.n_tasks):
            if (
                self.status[t] in ("dispatched", "running")
                and int(p.mode_arm[int(self.plan.mode[t])]) == a
            ):
                self.status[t] = "pending"
                self.permitted.discard(t)
                for piece, *_ in self.task_pieces.pop(t, []):
                    self.released.discard(piece)
                    self.held.pop(piece, None)
                    self.told_sleep.discard(piece)
                self.trace.add(
                    self.kernel.now,
                    "task_failed",
                    arm=p.arm_names[a],
                    task=p.task_names[t],
                    detail="interrupted by the arm's failure; "
                    + ("reassigned by a re-solve" if self.resolving else "re-solving off"),
                )
        self.resolve(f"arm {p.arm_names[a]!r} failed")
        self._serve_all()

    def part_late(self, tasks: list[int], arrival: float, part: str) -> None:
        """Part ``part`` will come at ``arrival`` (inf: never) for ``tasks``.

        A gated task already dispatched with its start permitted has the
        permission revoked: it is withdrawn (its arm has not started it)
        and dispatched again under the new release."""
        for t in tasks:
            if self.status[t] in ("done", "running"):
                continue
            self.release[t] = max(self.release[t], arrival)
            if self.status[t] == "dispatched" and t in self.permitted:
                self._withdraw(t)
                self.status[t] = "pending"
            self.late[t] = arrival
            if math.isinf(arrival):
                self.cause[t] = f"part {part!r} never arrived"
                self.cause_kind[t] = "part_missing"
            else:
                self.kernel.schedule(arrival, self._on_release, t, absolute=True)
        when = "never comes" if math.isinf(arrival) else f"comes at {arrival:.6g} s"
        self.trace.add(self.kernel.now, "fault", detail=f"part {part!r} is late: {when}")
        if math.isinf(arrival):
            # the tasks it gates, and everything after them, can never run
            stack = [t for t in tasks if self.status[t] in ("pending", "dispatched")]
            while stack:
                t = stack.pop()
                if self.status[t] not in ("pending", "dispatched"):
                    continue
                if self.status[t] == "dispatched":  # its arm waits at its start
                    self._withdraw(t)
                self.status[t] = "failed"
                if not self.cause[t]:
                    self.cause[t] = f"predecessor failed: part {part!r} never arrived"
                    self.cause_kind[t] = "predecessor"
                self.trace.add(
                    self.kernel.now, "task_failed", task=self.p.task_names[t], detail=self.cause[t]
                )
                stack.extend(self.p.task_succs[t])
            self._build_orders()
            self._serve_all()
            for a in range(self.p.n_arms):
                self._dispatch_next(a)
            return
        self.resolve(f"part {part!r} late")

    def activate(self, zones: tuple[str, ...]) -> None:
        """Change the active zones once every arm has stopped (S2.5)."""
        if self.activation is None:  # else: the pending change is replaced
            self.activation_id = next(self._stop_ids)
            self.activation_acks = set()
            self.activation_slept = set()
        self.activation = zones
        for a in range(self.p.n_arms):
            h = self.dispatch_h[a]
            if h is not None:
                h.cancel()
                self.dispatch_h[a] = None
            if a in self.activation_acks or a in self.activation_slept:
                continue
            if a in self.failed_arms or not self.arm_busy[a]:
                self.activation_acks.add(a)
            else:
                self.activation_slept.add(a)
                self.net.send(0, a + 1, "sleep", ("activation", self.activation_id))
        self._try_activation()

    def _try_activation(self) -> None:
        zones = self.activation
        if zones is None or len(self.activation_acks) < self.p.n_arms:
            return
        zm = self.zm
        for a in range(self.p.n_arms):
            if zm.waiting(a) is None and zm.is_moving(a):
                self._events(zm.stop(a).events)
        r = zm.set_active(zones)
        self._events(r.events)
        detail = "activated: " + ", ".join(zones) if r.granted else f"refused: {r.reason}"
        self.trace.add(self.kernel.now, "grant", detail=f"active zones {detail}")
        self.activation = None
        for a in range(self.p.n_arms):
            if a in self.failed_arms:
                continue
            self.net.send(0, a + 1, "active_zone_grant", ("zones", zones))
            # every arm told to stop is released, busy or not by now (its task
            # may have ended while the stop was on its way)
            if a in self.activation_slept:
                self.net.send(0, a + 1, "wake_up", ("activation", self.activation_id))
        self.activation_slept = set()
        for a in range(self.p.n_arms):
            self._dispatch_next(a)

    def _withdraw(self, t: int) -> None:
        """Take back the dispatched, not started task ``t``: its grants and
        requests are given back (the arm drops them too) and its arm told."""
        a = int(self.p.mode_arm[int(self.plan.mode[t])])
        if self.zm_wait[a] is not None and self.zm_wait[a][2] == t:  # type: ignore[index]
            if self.zone_checks and self.zm.waiting(a) is not None:
                self.zm.cancel(a)
            self.zm_wait[a] = None
        self.pending[a] = [q for q in self.pending[a] if q[2] != t]
        for piece, holder in list(self.held.items()):
            if holder == a and piece[2] == t:
                self._release(a, piece)
                self.released.discard(piece)
        self.told_sleep = {q for q in self.told_sleep if q[2] != t}
        self.task_pieces.pop(t, None)
        self.permitted.discard(t)
        self.net.send(0, a + 1, "sleep", ("withdraw", -1, t, 0.0))

    def _withdraw_never(self) -> None:
        """Take back the dispatched tasks that can no longer run under the
        kept plan (a predecessor on a failed arm): their arms would wait at
        their starts for good; freed, they go on with their other tasks."""
        for t in sorted(self.never):
            if self.status[t] == "dispatched":
                self._withdraw(t)
                self.status[t] = "pending"
        for a in range(self.p.n_arms):
            self._dispatch_next(a)

    # ------------------------------------------------------------ re-solve
    def _dead(self, frozen: Any = ()) -> set[int]:
        """Tasks that can never run: no working arm has a mode for them, a
        part they need never comes, or a predecessor of theirs cannot run
        (tasks done or running are never dead)."""
        p = self.p
        failed = self.failed_arms
        out: set[int] = set()
        for t in p.topological_order:
            if t in frozen or self.status[t] in ("done", "running"):
                continue
            if (
                self.status[t] == "failed"
                or math.isinf(self.late.get(t, 0.0))
                or all(int(p.mode_arm[m]) in failed for m in p.task_modes[t])
                or any(q in out for q in p.task_preds[t])
            ):
                out.add(t)
        return out

    def resolve(self, reason: str) -> None:
        """Re-solve from the current state (module docstring)."""
        p = self.p
        now = self.kernel.now
        if not self.resolving:
            self.trace.add(now, "resolve", detail=f"{reason}: re-solving off; plan kept")
            self._build_orders()  # a failed arm's tasks no longer hold others back
            self._withdraw_never()
            return
        frozen: dict[
            int | str, tuple[int, float, float] | tuple[int, float, float, list[float]]
        ] = {}
        changed = True
        live = {t for t in range(p.n_tasks) if self.status[t] in ("done", "dispatched", "running")}
        while changed:
            changed = False
            for t in sorted(live - set(frozen)):
                if self.status[t] == "done" or all(q in frozen for q in p.task_preds[t]):
                    if self.status[t] == "dispatched" and not all(
                        q in frozen for q in p.task_preds[t]
                    ):
                        continue
                    frozen[t] = (
                        int(self.plan.mode[t]),
                        float(self.plan.start[t]),
                        float(self.plan.end[t]),
                        self.plan.waits[t].tolist(),
                    )
                    changed = True
        releases: dict[int | str, float] = {t: r for t, r in self.late.items() if math.isfinite(r)}
        failed = self.failed_arms
        dead = self._dead(frozen)
        # warm start: tasks planned on a failed arm move to a working arm's
        # fastest mode; the tasks that cannot run (no working arm has a mode
        # for them, a part that never comes, or a predecessor that cannot
        # run) come last, each at its own time far after the rest, so the
        # plan's makespan is theirs whatever the live tasks do, and the
        # search can never gain by pushing a live task after them
        mode = np.array(self.plan.mode, dtype=np.int64)
        start = np.array(self.plan.start, dtype=float)
        waits = list(self.plan.waits)
        for t in range(p.n_tasks):
            if t in frozen:
                continue
            alive = [m for m in p.task_modes[t] if int(p.mode_arm[m]) not in failed]
            if t in dead:
                alive = list(p.task_modes[t])
            elif int(p.mode_arm[mode[t]]) not in failed:
                continue
            mode[t] = min(alive, key=lambda m: (float(p.mode_duration[m]), m))
            waits[t] = np.zeros(len(p.shapes[int(mode[t])].borders))
        span = 2.0 * float(np.sum(p.mode_duration)) + 1e4
        for k, t in enumerate(x for x in p.topological_order if x in dead):
            releases[t] = start[t] = FAR + k * span
        if dead:
            # a failed arm keeps the modes of the tasks only it could do (they
            # stay planned after FAR and are reported failed)
            state = CellState(
                time=now,
                done=frozen,
                releases=releases,
                arm_busy_until={a: FAR for a in failed},
            )
        else:
            state = CellState(time=now, done=frozen, releases=releases, failed_arms=set(failed))
        warm = Schedule(mode, start, self.plan.end, tuple(waits), self.plan.blocking)
        t0 = time.perf_counter()
        new: Schedule | None = None
        err = ""
        for limit in (self.resolve_evaluations, 1):
            try:
                res = reschedule(
                    p, state, warm, time_limit=1e6, seed=self.seed, max_evaluations=limit
                )
                new = res.schedule
                err = "" if new is not None else f"no schedule ({res.status.value})"
            except (ScheduleError, UsageError) as exc:
                new, err = None, str(exc)
            if new is not None and any(
                float(new.start[t]) >= FAR for t in range(p.n_tasks) if t not in dead
            ):
                # a task that can run was put after the ones that cannot: take
                # the warm start decoded instead (every task in plan order)
                new, err = None, "a task that can run was planned after FAR"
                continue
            break
        latency = time.perf_counter() - t0
        self.resolve_latency.append(latency)
        self.resolves += 1
        if new is None:
            self.trace.add(now, "resolve", detail=f"{reason}: re-solve failed: {err}; plan kept")
            self._build_orders()
            self._withdraw_never()
            return
        # withdraw dispatched tasks that were not frozen (their arm waits at the start)
        for t in range(p.n_tasks):
            if self.status[t] == "dispatched" and t not in frozen:
                self._withdraw(t)
                self.status[t] = "pending"
        self.plan = new
        self._build_orders()
        mk = float(np.max(np.where(new.start < FAR, new.end, 0.0))) if p.n_tasks else 0.0
        # the wall-clock latency goes to the metrics only: the trace is
        # reproducible bit for bit
        self.trace.add(now, "resolve", detail=f"{reason}: new plan, makespan {mk:.6g} s")
        for a in range(p.n_arms):
            self._dispatch_next(a)
