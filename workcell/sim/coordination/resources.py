"""The centralized coordinator's resource service (S2.5-S2.7): zone and tool
requests served in plan order through :class:`zones.ZoneManager`, grants,
sleeps, wake-ups, releases and position reports.

Functions here are methods of :class:`~workcell.sim.coordination.centralized.Coordinator`
(bound in its class body), kept apart to keep each module small.
"""

from __future__ import annotations

from collections.abc import Iterable
from collections.abc import Set as AbstractSet
from typing import Any, Self

from multiarm.errors import InternalError, UsageError
from workcell.sim.comms.medium import Frame
from workcell.sim.protocol.messages import Piece, PositionReport
from zones.manager import Deadlock, Wake

_Self = Any
"""The :class:`~workcell.sim.coordination.centralized.Coordinator` these functions are methods of (bound in its
class body; typed loosely here: workcell.sim.coordination.centralized imports this module, never the reverse)."""

__all__ = ["Released"]


class Released(set[Piece]):
    """The set of released resource uses, counting what leaves it.

    ``shrunk`` grows whenever a use is taken out again (an arm failure or a
    withdrawal hands its task's uses back to the plan), so a cached scan
    position in a resource's order (``Coordinator._grantable``) is
    known to be stale.
    """

    __slots__ = ("shrunk",)

    def __init__(self) -> None:
        super().__init__()
        self.shrunk = 0

    def discard(self, piece: object) -> None:
        self.shrunk += 1
        super().discard(piece)

    def remove(self, piece: Piece) -> None:
        self.shrunk += 1
        super().remove(piece)

    def pop(self) -> Piece:
        self.shrunk += 1
        return super().pop()

    def clear(self) -> None:
        self.shrunk += 1
        super().clear()

    def difference_update(self, *others: Iterable[Any]) -> None:
        self.shrunk += 1
        super().difference_update(*others)

    def intersection_update(self, *others: Iterable[Any]) -> None:
        self.shrunk += 1
        super().intersection_update(*others)

    def symmetric_difference_update(self, other: Iterable[Piece]) -> None:
        self.shrunk += 1
        super().symmetric_difference_update(other)

    def __isub__(self, other: AbstractSet[object]) -> Self:
        self.shrunk += 1
        return super().__isub__(other)

    def __iand__(self, other: AbstractSet[object]) -> Self:
        self.shrunk += 1
        return super().__iand__(other)

    def __ixor__(self, other: AbstractSet[Any]) -> Self:  # type: ignore[override, misc]
        self.shrunk += 1
        return super().__ixor__(other)


def receive(self: _Self, frame: Frame) -> None:
    """A frame for the coordinator."""
    payload: Any = frame.payload[0]  # type: ignore[index]
    a = frame.src - 1
    kind = frame.kind
    if a in self.failed_arms:
        return
    if kind == "zone_request":
        t = int(payload.task)
        if t >= 0 and self.status[t] not in ("dispatched", "running"):
            return  # sent before the arm heard the task was withdrawn
        self.pending[a].append(payload)
        self._serve(a)
    elif kind == "zone_release":
        self._release(a, payload)
        self._serve_all()
    elif kind == "trajectory_end":
        if payload.outcome == "failed":  # ran, but failed
            self.task_failed(a, payload.task, payload.cause)
        elif payload.outcome == "withdrawn":  # a withdrawn trajectory
            self.arm_busy[a] = False
            self._dispatch_next(a)
        else:
            self._task_done(a, payload.task)
    elif kind == "position":
        self._position(a, payload)
    elif kind == "alarm":
        self.trace.add(
            self.kernel.now,
            "fault",
            arm=self.p.arm_names[a],
            detail=f"coordinator told of a reflex stop ({payload.cause}), after the fact (S1.2)",
        )


def _zone_name(self: _Self, piece: Piece) -> str:
    if piece.kind == "tool":
        return str(self.p.tool_names[piece.resource])
    return str(self.p.zone_names[piece.resource])


def _serve_all(self: _Self) -> None:
    for b in range(self.p.n_arms):
        if self.pending[b] and self.zm_wait[b] is None:
            self._serve(b)


def _serve(self: _Self, a: int) -> None:
    arm_name = self.p.arm_names[a]
    while self.pending[a] and self.zm_wait[a] is None:
        piece = self.pending[a][0]
        name = self._zone_name(piece)
        task = self.p.task_names[piece.task] if piece.task >= 0 else ""
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


def _sleep(self: _Self, a: int, piece: Piece, name: str, task: str, why: str) -> None:
    if piece in self.told_sleep:
        return
    self.told_sleep.add(piece)
    self.trace.add(
        self.kernel.now, "sleep", arm=self.p.arm_names[a], task=task, zone=name, detail=why
    )
    self.channel.send(0, a + 1, "sleep", piece)


def _granted(self: _Self, a: int, piece: Piece) -> None:
    self.held[piece] = a
    name = self._zone_name(piece)
    task = self.p.task_names[piece.task] if piece.task >= 0 else ""
    if piece in self.told_sleep:
        self.trace.add(self.kernel.now, "wake", arm=self.p.arm_names[a], task=task, zone=name)
        self.channel.send(0, a + 1, "wake_up", piece)
    else:
        self.trace.add(
            self.kernel.now,
            "grant",
            arm=self.p.arm_names[a],
            task=task,
            zone=name,
            detail=piece.kind,
        )
        self.channel.send(0, a + 1, "zone_grant", piece)


def _zm_request(self: _Self, a: int, piece: Piece) -> tuple[bool, tuple[Any, ...]]:
    if not self.zone_checks:
        return True, ()
    kind, idx = piece.kind, piece.resource
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


def _events(self: _Self, events: tuple[Any, ...]) -> None:
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


def _release(self: _Self, a: int, piece: Piece) -> None:
    self.released.add(piece)
    self.held.pop(piece, None)
    if not self.zone_checks:
        return
    kind, idx = piece.kind, piece.resource
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


def _position(self: _Self, a: int, payload: PositionReport) -> None:
    piece, xyz = payload.piece, payload.xyz
    if piece is None:
        self.activation_acks.add(a)
        self._try_activation()
        return
    zm = self.zm
    if not self.zone_checks:
        return
    zname = self.p.zone_names[piece.resource]
    if zname not in self.sdl_zones:
        return
    if zm.waiting(a) is None and zm.is_moving(a):
        self._events(zm.stop(a).events)
    if zname in zm.zones_of(a) and not zm.is_moving(a):
        zm.report_position(a, zname, xyz)
