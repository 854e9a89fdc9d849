"""The centralized coordinator's faults and re-solving: emergency stops,
arm failures, late parts, zone activation (S2.5), withdrawals, and the
re-solve from the current state.

Functions here are methods of :class:`~workcell.sim.coordination.centralized.Coordinator`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from scheduler.reschedule import FrozenTask, reschedule
from workcell.sim.comms.medium import BROADCAST
from workcell.sim.protocol.exchange import Fail
from workcell.sim.protocol.messages import (
    ActivationGo,
    ActivationStop,
    ActiveZones,
    AlarmClear,
    AlarmStop,
    LateNotice,
    Piece,
    Withdraw,
)
from workcell.sim.protocol.states import TaskState

_Self = Any
"""The :class:`~workcell.sim.coordination.centralized.Coordinator` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.coordination.centralized imports this module, never the reverse)."""

__all__: list[str] = []


def emergency_stop(self: _Self, duration: float) -> None:
    """Broadcast the alarm; clear it ``duration`` seconds later."""
    self.trace.add(self.kernel.now, "fault", detail=f"emergency stop for {duration:g} s")
    stop = next(self._stop_ids)
    self.alarms.add(stop)
    self.channel.send(0, BROADCAST, "alarm", AlarmStop(stop))
    self.kernel.schedule(duration, self._clear_alarm, stop)


def _clear_alarm(self: _Self, stop: int) -> None:
    """Release the emergency stop ``stop`` at every working arm (matched
    by id: an arm stays stopped while any alarm is in force)."""
    self.alarms.discard(stop)
    self.trace.add(self.kernel.now, "fault", detail="emergency stop cleared")
    for a in range(self.p.n_arms):
        if a not in self.failed_arms:
            self.channel.send(0, a + 1, "wake_up", AlarmClear(stop))


def arm_failed(self: _Self, a: int) -> None:
    """Arm ``a`` failed: it is told to stop for good (a
    :class:`~workcell.sim.protocol.exchange.Fail` order, one medium delay
    away); once its report says it is out (:func:`arm_out`) its resources
    are given back and its tasks reassigned. Nothing new is sent to it."""
    if a in self.failed_arms or a in self.failing:
        return
    self.failing.add(a)
    self.channel.order(a, Fail())
    self.trace.add(self.kernel.now, "fault", arm=self.p.arm_names[a], detail="arm failure")
    h = self.dispatch_h[a]
    if h is not None:
        h.cancel()
        self.dispatch_h[a] = None


def arm_out(self: _Self, a: int) -> None:
    """Arm ``a`` reported its failure: give back its resources, reassign its tasks."""
    p = self.p
    self.failing.discard(a)
    self.failed_arms.add(a)
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
            if piece.task >= 0 and self.status[piece.task] == "running":
                self.trace.add(
                    self.kernel.now,
                    "zone_leave",
                    arm=p.arm_names[a],
                    task=p.task_names[piece.task],
                    zone=self._zone_name(piece),
                    detail=piece.kind,
                )
    for z in p.arm_start_zones[a]:  # retracted: out of its start zones too
        self.released.add(Piece("zone", int(z), -1 - a, 0.0))
    self.pending[a].clear()
    self.zm_wait[a] = None
    for t in range(p.n_tasks):
        if (
            self.status[t] in ("dispatched", "running")
            and int(p.mode_arm[int(self.plan.mode[t])]) == a
        ):
            self.set_status(t, TaskState.PENDING)
            self.permitted.discard(t)
            for piece, *_ in self.task_pieces.pop(t, []):
                self.released.discard(piece)
                self.held.pop(piece, None)
                self.told_sleep.discard(piece)
            if not self.resolving:  # failed with the others below (_fail_never)
                self.cause[t] = (
                    f"interrupted by the arm's failure: arm {p.arm_names[a]!r} failed "
                    "(re-solving off: its tasks are not reassigned)"
                )
                self.cause_kind[t] = "arm_out"
                continue
            self.trace.add(
                self.kernel.now,
                "task_failed",
                arm=p.arm_names[a],
                task=p.task_names[t],
                detail="interrupted by the arm's failure; reassigned by a re-solve",
            )
    self.resolve(f"arm {p.arm_names[a]!r} failed")
    self._serve_all()
    if self.activation is not None:
        # a failed arm never answers a pending activation's stop: it counts as
        # stopped, else the activation (and every arm it stopped) waits for good
        self.activation_acks.add(a)
        self._try_activation()


def parts_late(self: _Self, notices: Sequence[LateNotice]) -> None:
    """Parts found late at one instant (one :class:`LateNotice` each).

    Every gated task's release moves first, then each notice is handled
    (:func:`part_late`): a re-dispatch that one notice triggers can never
    permit a task that another notice of the same instant holds back (a
    trajectory sent with its start permitted between two notices reached
    its arm before the withdrawal did, on a medium with delay)."""
    for notice in notices:
        for t in notice.tasks:
            if self.status[t] not in ("done", "running"):
                self.release[t] = max(self.release[t], notice.arrival)
    for notice in notices:
        self.part_late(notice)


def part_late(self: _Self, notice: LateNotice) -> None:
    """Part ``notice.part`` will come at ``notice.arrival`` (inf: never)
    for ``notice.tasks``.

    A gated task already dispatched with its start permitted has the
    permission revoked: it is withdrawn (its arm has not started it)
    and dispatched again under the new release."""
    tasks, arrival, part = notice.tasks, notice.arrival, notice.part
    for t in tasks:
        if self.status[t] in ("done", "running"):
            continue
        self.release[t] = max(self.release[t], arrival)
        if self.status[t] == "dispatched" and t in self.permitted:
            self._withdraw(t)
            self.set_status(t, TaskState.PENDING)
        self.late[t] = arrival
        if math.isinf(arrival):
            self.cause[t] = f"part {part!r} never arrived"
            self.cause_kind[t] = "part_missing"
        else:
            self.kernel.schedule(arrival, self._on_release, t, absolute=True)
    self.trace.add(self.kernel.now, "fault", detail=notice.describe())
    if math.isinf(arrival):
        # the tasks it gates, and everything after them, can never run
        stack = [t for t in tasks if self.status[t] in ("pending", "dispatched")]
        while stack:
            t = stack.pop()
            if self.status[t] not in ("pending", "dispatched"):
                continue
            if self.status[t] == "dispatched":  # its arm waits at its start
                self._withdraw(t)
            self.set_status(t, TaskState.FAILED)
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


def activate(self: _Self, zones: tuple[str, ...]) -> None:
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
            self.channel.send(0, a + 1, "sleep", ActivationStop(self.activation_id))
    self._try_activation()


def _try_activation(self: _Self) -> None:
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
        self.channel.send(0, a + 1, "active_zone_grant", ActiveZones(tuple(zones)))
        # every arm told to stop is released, busy or not by now (its task
        # may have ended while the stop was on its way)
        if a in self.activation_slept:
            self.channel.send(0, a + 1, "wake_up", ActivationGo(self.activation_id))
    self.activation_slept = set()
    for a in range(self.p.n_arms):
        self._dispatch_next(a)


def _withdraw(self: _Self, t: int) -> None:
    """Take back the dispatched, not started task ``t``: its grants and
    requests are given back (the arm drops them too) and its arm told."""
    a = int(self.p.mode_arm[int(self.plan.mode[t])])
    if self.zm_wait[a] is not None and self.zm_wait[a][2] == t:
        if self.zone_checks and self.zm.waiting(a) is not None:
            self.zm.cancel(a)
        self.zm_wait[a] = None
    self.pending[a] = [q for q in self.pending[a] if q.task != t]
    for piece, holder in list(self.held.items()):
        if holder == a and piece.task == t:
            self._release(a, piece)
            self.released.discard(piece)
    self.told_sleep = {q for q in self.told_sleep if q.task != t}
    self.task_pieces.pop(t, None)
    self.permitted.discard(t)
    self.channel.send(0, a + 1, "sleep", Withdraw(t))


def _fail_never(self: _Self) -> None:
    """Re-solving off: the tasks that can no longer run under the kept plan
    (on a failed arm, or after such a task: :attr:`never`) fail now, at the
    instant that became known, each with its cause (a dispatched one is
    withdrawn first); the arms go on with the rest of the plan."""
    p = self.p
    now = self.kernel.now
    failed = False
    for t in p.topological_order:
        if t not in self.never or self.status[t] not in ("pending", "dispatched"):
            continue
        a = int(p.mode_arm[int(self.plan.mode[t])])
        if self.cause[t]:
            pass
        elif all(int(p.mode_arm[m]) in self.failed_arms for m in p.task_modes[t]):
            self.cause[t] = "no working arm can do it (every capable arm failed)"
            self.cause_kind[t] = "arm_failed"
        elif a in self.failed_arms:
            self.cause[t] = (
                f"arm {p.arm_names[a]!r} failed (re-solving off: its tasks are not reassigned)"
            )
            self.cause_kind[t] = "arm_out"
        else:
            q = next(q for q in sorted(p.task_preds[t]) if self.cause[q])
            self.cause[t] = f"predecessor {p.task_names[q]!r} failed: {self.cause[q]}"
            self.cause_kind[t] = "predecessor"
        if self.status[t] == "dispatched":  # its arm waits at its start
            self._withdraw(t)
        self.set_status(t, TaskState.FAILED)
        self.trace.add(
            now, "task_failed", arm=p.arm_names[a], task=p.task_names[t], detail=self.cause[t]
        )
        failed = True
    if failed:
        self._build_orders()
        self._serve_all()
    for b in range(p.n_arms):
        self._dispatch_next(b)


def _fail_impossible(self: _Self) -> None:
    """After a re-solve: the tasks no working arm can do (every capable arm
    failed) and the tasks after them can never run, whatever later plans
    say: they fail now, at the instant that became known, with their cause."""
    p = self.p
    now = self.kernel.now
    root: dict[int, int] = {}
    for t in p.topological_order:
        if self.status[t] not in ("pending", "dispatched"):
            continue
        if all(int(p.mode_arm[m]) in self.failed_arms for m in p.task_modes[t]):
            root[t] = t
            self.cause[t] = "no working arm can do it (every capable arm failed)"
            self.cause_kind[t] = "arm_failed"
        else:
            q = next((root[q] for q in sorted(p.task_preds[t]) if q in root), None)
            if q is None:
                continue
            root[t] = q
            self.cause[t] = (
                f"predecessor {p.task_names[q]!r} cannot run: every arm able to do it failed"
            )
            self.cause_kind[t] = "predecessor"
        if self.status[t] == "dispatched":  # its arm waits at its start
            self._withdraw(t)
        self.set_status(t, TaskState.FAILED)
        a = int(p.mode_arm[int(self.plan.mode[t])])
        self.trace.add(
            now, "task_failed", arm=p.arm_names[a], task=p.task_names[t], detail=self.cause[t]
        )


def _withdraw_never(self: _Self) -> None:
    """Take back the dispatched tasks that can no longer run under the
    kept plan (a predecessor on a failed arm): their arms would wait at
    their starts for good; freed, they go on with their other tasks."""
    for t in sorted(self.never):
        if self.status[t] == "dispatched":
            self._withdraw(t)
            self.set_status(t, TaskState.PENDING)
    for a in range(self.p.n_arms):
        self._dispatch_next(a)


def resolve(self: _Self, reason: str) -> None:
    """Re-solve from the current state (module docstring)."""
    p = self.p
    now = self.kernel.now
    if not self.resolving:
        self.trace.add(now, "resolve", detail=f"{reason}: re-solving off; plan kept")
        self._build_orders()  # a failed arm's tasks no longer hold others back
        self._fail_never()
        return
    frozen: dict[int, FrozenTask] = {}
    changed = True
    live = {t for t in range(p.n_tasks) if self.status[t] in ("done", "dispatched", "running")}
    while changed:
        changed = False
        for t in sorted(live - set(frozen)):
            if self.status[t] == "done" or all(q in frozen for q in p.task_preds[t]):
                if self.status[t] == "dispatched" and not all(q in frozen for q in p.task_preds[t]):
                    continue
                frozen[t] = FrozenTask(
                    int(self.plan.mode[t]),
                    float(self.plan.start[t]),
                    float(self.plan.end[t]),
                    tuple(self.plan.waits[t].tolist()),
                )
                changed = True
    res = reschedule(
        p,
        now=now,
        previous=self.plan,
        done={t: f for t, f in frozen.items() if self.status[t] == "done"},
        running={t: f for t, f in frozen.items() if self.status[t] != "done"},
        failed={t for t in range(p.n_tasks) if self.status[t] == "failed"},
        arms_out=self.failed_arms,
        parts_late=self.late,
        evaluations=self.resolve_evaluations,
        seed=self.seed,
    )
    self.resolve_latency.append(res.latency)
    self.resolves += 1
    new = res.schedule
    if new is None:
        self.trace.add(now, "resolve", detail=f"{reason}: re-solve failed: {res.reason}; plan kept")
        self._build_orders()
        self._withdraw_never()
        return
    # withdraw dispatched tasks that were not frozen (their arm waits at the start)
    for t in range(p.n_tasks):
        if self.status[t] == "dispatched" and t not in frozen:
            self._withdraw(t)
            self.set_status(t, TaskState.PENDING)
    self.plan = new
    self.dropped = res.dropped
    self._fail_impossible()
    self.plans.append(new)
    for t in range(p.n_tasks):
        if t not in res.dropped:
            self.plan_of[t] = len(self.plans) - 1
    self._build_orders()
    mk = res.makespan
    # the wall-clock latency goes to the metrics only: the trace is
    # reproducible bit for bit
    self.trace.add(now, "resolve", detail=f"{reason}: new plan, makespan {mk:.6g} s")
    for a in range(p.n_arms):
        self._dispatch_next(a)
