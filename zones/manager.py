"""The run-time zone protocol: a pure state machine the coordinator drives.

:class:`ZoneManager` implements SEEDS.md S2.5-S2.7. It knows which arm is in
which zone, which arm moves in each shared zone, who holds each tool and who
waits for what. It has no clock and no event loop: every call is one message
from the (simulated) coordinator and returns a :class:`Response` saying
whether the request is granted now or the arm must sleep (stop at the zone
border), plus the :data:`Event`\\ s the call caused: wake-ups of other arms,
a detected deadlock and its resolution, a geometric block.

Resources
---------
* an **exclusive** zone: at most one arm inside (occupancy);
* a **shared** zone (simultaneous with restrictions): any number of arms
  inside, at most one moving there (the zone's *movement* resource);
* a **tool**: at most one holder.

An arm moving inside several shared zones holds the movement of each. Every
request is all-or-nothing: it names everything the arm needs to move (the
target and the movement of every active shared zone it stands in) and is
granted only when all of it is free. A refused arm stops, and a stopped arm
gives back every movement it held (S2.6), so a waiting arm never holds a
movement; it keeps its occupancy of exclusive zones and its tools.

Only active zones constrain anything. Activation changes only while every
arm is stopped (S2.5).

Deadlock (S2.6)
---------------
Exclusive zones and tools allow hold-and-wait, so the manager keeps the
wait-for graph (a waiting arm → the arms holding what it needs) and checks for
a cycle the moment an arm starts waiting. A cycle is reported as a
:class:`Deadlock` event (arms and resources in cycle order) and handed to the
``deadlock_policy``: :class:`YoungestBacksOff` (default) withdraws the
request of the arm that started waiting last and releases its exclusive zones
and tools (a :class:`BackOff` event: the caller moves it out and returns the
tools); :class:`ReportOnly` leaves the cycle to the caller. With shared zones
alone no cycle can form (a waiter holds no movement); tools deadlock like any
other resource. *Geometric* deadlock — a granted mover whose path a
stationary arm blocks — is reported as a :class:`Blocked` event naming the
standing arms, and the caller asks for a detour (S2.6, S2.12).

Examples
--------
>>> from zones.sdl import parse_sdl
>>> zm = parse_sdl('''cell (0,0,0) (2,1,1)
... zone fixture shared box (0.8,0,0) (1.2,1,1)''')
>>> zmgr = ZoneManager(zm, arms=["left", "right"])
>>> zmgr.request_enter("left", "fixture").granted
True
>>> r = zmgr.request_enter("right", "fixture")   # left is moving there
>>> r.granted, r.waiting_for
(False, (('move', 'fixture'),))
>>> zmgr.stop("left").events                      # left stands still: right goes on
(Wake(arm='right', request=('enter', 'fixture')),)
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol, TypeAlias

import numpy as np

from multiarm.errors import UsageError
from multiarm.types import FloatArray
from zones.model import ZoneMap

__all__ = [
    "BackOff",
    "Blocked",
    "Deadlock",
    "DeadlockPolicy",
    "Event",
    "LowestPriorityBacksOff",
    "ReportOnly",
    "Response",
    "Wake",
    "YoungestBacksOff",
    "ZoneManager",
]

Arm: TypeAlias = Hashable
ResourceName: TypeAlias = tuple[Literal["zone", "move", "tool"], str]
"""A resource as users see it: ``("zone", name)`` (exclusive occupancy),
``("move", name)`` (movement in a shared zone) or ``("tool", name)``."""

_ZONE, _MOVE, _TOOL = 0, 1, 2
_KIND_NAMES: tuple[Literal["zone", "move", "tool"], ...] = ("zone", "move", "tool")
_ENTER, _MOVE_REQ, _TOOL_REQ = "enter", "move", "tool"


@dataclass(frozen=True, slots=True)
class Wake:
    """A sleeping arm's request is now granted: send it *wake up* (S2.7)."""

    arm: Arm
    request: tuple[str, str | None]


@dataclass(frozen=True, slots=True)
class Deadlock:
    """A cycle in the wait-for graph: ``arms[i]`` waits for ``resources[i]``,
    held by ``arms[i + 1]`` (the last by the first)."""

    arms: tuple[Arm, ...]
    resources: tuple[ResourceName, ...]

    def describe(self) -> str:
        """One line naming every arm and resource of the cycle."""
        parts = [
            f"{a!r} waits for {k} {n!r} held by {self.arms[(i + 1) % len(self.arms)]!r}"
            for i, (a, (k, n)) in enumerate(zip(self.arms, self.resources, strict=True))
        ]
        return "deadlock: " + "; ".join(parts)


@dataclass(frozen=True, slots=True)
class BackOff:
    """Deadlock resolution: ``arm`` gives up ``withdrawn`` and releases
    ``released``; the caller moves it out of those zones and returns the tools."""

    arm: Arm
    withdrawn: tuple[str, str | None]
    released: tuple[ResourceName, ...]


@dataclass(frozen=True, slots=True)
class Blocked:
    """Geometric deadlock (S2.6): ``arm`` may move in ``zone`` but stationary
    ``blockers`` stand on its path; the caller asks for an alternative path."""

    arm: Arm
    zone: str
    blockers: tuple[Arm, ...]


Event: TypeAlias = Wake | Deadlock | BackOff | Blocked
"""Anything a call can cause besides its own answer."""


@dataclass(frozen=True, slots=True)
class Response:
    """The answer to one call.

    Attributes
    ----------
    granted : bool
        For requests: True = go on; False = sleep (stop at the border) until
        a :class:`Wake` for this arm, or backed off (see ``events``). For
        activation changes: accepted or refused.
    events : tuple of Event
        Wake-ups of other arms, deadlocks, back-offs, geometric blocks, in
        the order they happened.
    waiting_for : tuple of ResourceName
        When sleeping: the resources not yet available.
    reason : str
        Why an activation change was refused.
    """

    granted: bool
    events: tuple[Event, ...] = ()
    waiting_for: tuple[ResourceName, ...] = ()
    reason: str = ""


class DeadlockPolicy(Protocol):
    """Chooses which arm of a deadlock backs off (``None``: leave it)."""

    def victim(self, deadlock: Deadlock, manager: ZoneManager) -> Arm | None: ...


class ReportOnly:
    """Report deadlocks, resolve none (the caller decides)."""

    def victim(self, deadlock: Deadlock, manager: ZoneManager) -> Arm | None:
        return None


class YoungestBacksOff:
    """The arm of the cycle that started waiting last backs off."""

    def victim(self, deadlock: Deadlock, manager: ZoneManager) -> Arm | None:
        return max(deadlock.arms, key=manager.wait_order)


class LowestPriorityBacksOff:
    """The arm with the lowest priority backs off (ties: the youngest waiter)."""

    def __init__(self, priorities: Mapping[Arm, float]) -> None:
        self.priorities = dict(priorities)

    def victim(self, deadlock: Deadlock, manager: ZoneManager) -> Arm | None:
        return min(
            deadlock.arms,
            key=lambda a: (self.priorities.get(a, 0.0), -manager.wait_order(a)),
        )


BlockingTest: TypeAlias = Callable[[FloatArray, FloatArray], bool]
"""``(path (M, 3), position (3,)) -> bool``: does a stationary arm at
``position`` block a mover following ``path``?"""


def clearance_test(clearance: float) -> BlockingTest:
    """A blocking test: the standing arm is within ``clearance`` metres of the
    path polyline."""

    def blocked(path: FloatArray, position: FloatArray) -> bool:
        p = np.asarray(position, dtype=float)
        pts = np.asarray(path, dtype=float)
        if len(pts) == 1:
            return bool(np.linalg.norm(pts[0] - p) <= clearance)
        a, b = pts[:-1], pts[1:]
        ab = b - a
        denom = np.einsum("ij,ij->i", ab, ab)
        t = np.where(denom > 0, np.einsum("ij,ij->i", p - a, ab) / np.where(denom > 0, denom, 1), 0)
        t = np.clip(t, 0.0, 1.0)
        closest = a + t[:, None] * ab
        return bool(np.min(np.linalg.norm(closest - p, axis=1)) <= clearance)

    return blocked


class ZoneManager:
    """The coordinator's zone and tool bookkeeping (S2.5-S2.7), as a state machine.

    Parameters
    ----------
    zonemap : ZoneMap
        Zones (with their policy and initial activation) and tools.
    arms : sequence of hashable
        The arms' identifiers (names or ints).
    start_in : mapping arm -> iterable of zone, optional
        Zones each arm stands in at the start (all arms start stopped).
    wake_order : {"fifo", "priority"}
        Order in which sleepers are considered when something frees: first
        come first served, or by ``priorities`` (higher first, then FIFO).
    priorities : mapping arm -> float, optional
    deadlock_policy : DeadlockPolicy, optional
        Default :class:`YoungestBacksOff`; :class:`ReportOnly` to resolve
        nothing.
    blocking_test : callable, optional
        Decides geometric blocking for requests that carry a path; default
        :func:`clearance_test` with ``clearance``.
    clearance : float, metres
        For the default blocking test.

    Notes
    -----
    Calls that misuse the protocol (an unknown arm, a second request while
    asleep, leaving a zone one is not in...) raise
    :class:`~multiarm.errors.UsageError` and change nothing.
    """

    def __init__(
        self,
        zonemap: ZoneMap,
        arms: Sequence[Arm],
        *,
        start_in: Mapping[Arm, Iterable[str | int]] | None = None,
        wake_order: Literal["fifo", "priority"] = "fifo",
        priorities: Mapping[Arm, float] | None = None,
        deadlock_policy: DeadlockPolicy | None = None,
        blocking_test: BlockingTest | None = None,
        clearance: float = 0.1,
    ) -> None:
        self.zonemap = zonemap
        self.arms: tuple[Arm, ...] = tuple(arms)
        if len(set(self.arms)) != len(self.arms):
            raise UsageError("arm identifiers must be distinct")
        if wake_order not in ("fifo", "priority"):
            raise UsageError(f"wake_order must be 'fifo' or 'priority', not {wake_order!r}")
        self._index: dict[Arm, int] = {a: i for i, a in enumerate(self.arms)}
        self.wake_order = wake_order
        self.priorities: dict[Arm, float] = dict(priorities or {})
        self.policy: DeadlockPolicy = (
            deadlock_policy if deadlock_policy is not None else YoungestBacksOff()
        )
        self.blocking_test: BlockingTest = blocking_test or clearance_test(clearance)
        n_arms, n_zones, n_tools = len(self.arms), zonemap.n_zones, zonemap.n_tools
        self._zname = zonemap.zone_names()
        self._tname = tuple(t.name for t in zonemap.tools)
        self._excl: list[bool] = zonemap.exclusive_mask().tolist()
        self._active: list[bool] = zonemap.active_mask().tolist()
        self._occ: list[set[int]] = [set() for _ in range(n_zones)]
        self._inside: list[set[int]] = [set() for _ in range(n_arms)]
        self._mover: list[int] = [-1] * n_zones
        self._moves: list[set[int]] = [set() for _ in range(n_arms)]
        self._holder: list[int] = [-1] * n_tools
        self._tools: list[set[int]] = [set() for _ in range(n_arms)]
        self._moving: list[bool] = [False] * n_arms
        self._req: list[tuple[str, int, FloatArray | None] | None] = [None] * n_arms
        self._seq: list[int] = [0] * n_arms
        self._counter = 0
        self._waiters: dict[int, None] = {}
        self._pos: list[dict[int, FloatArray]] = [{} for _ in range(n_arms)]
        self.stats: dict[str, int] = dict.fromkeys(
            ("calls", "granted", "slept", "woken", "deadlocks", "backoffs", "blocked"), 0
        )
        for arm, zs in (start_in or {}).items():
            a = self._arm(arm)
            for z in zs:
                zid = self._zone(z)
                self._occ[zid].add(a)
                self._inside[a].add(zid)
        for z in range(n_zones):
            if self._excl[z] and self._active[z] and len(self._occ[z]) > 1:
                names = sorted(repr(self.arms[a]) for a in self._occ[z])
                raise UsageError(
                    f"arms {', '.join(names)} cannot all start in exclusive zone {self._zname[z]!r}"
                )

    # ------------------------------------------------------------ helpers
    def _arm(self, arm: Arm) -> int:
        try:
            return self._index[arm]
        except (KeyError, TypeError):
            raise UsageError(f"unknown arm {arm!r}") from None

    def _zone(self, zone: str | int) -> int:
        try:
            return self.zonemap.zone_id(zone)
        except Exception:
            raise UsageError(f"unknown zone {zone!r}") from None

    def _tool(self, tool: str | int) -> int:
        try:
            return self.zonemap.tool_id(tool)
        except Exception:
            raise UsageError(f"unknown tool {tool!r}") from None

    def _name(self, kind: int, idx: int) -> ResourceName:
        return (_KIND_NAMES[kind], self._tname[idx] if kind == _TOOL else self._zname[idx])

    def _needs(self, a: int, kind: str, target: int) -> list[tuple[int, int]]:
        needs: list[tuple[int, int]] = []
        if kind == _TOOL_REQ:
            return [(_TOOL, target)]
        if kind == _ENTER:
            needs.append((_ZONE, target) if self._excl[target] else (_MOVE, target))
        for z in self._inside[a]:
            if self._active[z] and not self._excl[z] and (_MOVE, z) not in needs:
                needs.append((_MOVE, z))
        return needs

    def _available(self, a: int, res: tuple[int, int]) -> bool:
        kind, idx = res
        if kind == _TOOL:
            h = self._holder[idx]
            return h < 0 or h == a
        if not self._active[idx]:
            return True
        if kind == _ZONE:
            occ = self._occ[idx]
            return not occ or (len(occ) == 1 and a in occ)
        m = self._mover[idx]
        return m < 0 or m == a

    def _holders(self, a: int, res: tuple[int, int]) -> list[int]:
        kind, idx = res
        if kind == _TOOL:
            h = self._holder[idx]
            return [h] if h >= 0 and h != a else []
        if not self._active[idx]:
            return []
        if kind == _ZONE:
            return sorted(b for b in self._occ[idx] if b != a)
        m = self._mover[idx]
        return [m] if m >= 0 and m != a else []

    def _grant(self, a: int, kind: str, target: int, needs: list[tuple[int, int]]) -> None:
        for rk, idx in needs:
            if rk == _TOOL:
                self._holder[idx] = a
                self._tools[a].add(idx)
            elif rk == _MOVE and self._active[idx]:
                self._mover[idx] = a
                self._moves[a].add(idx)
        if kind == _ENTER:
            self._occ[target].add(a)
            self._inside[a].add(target)
        if kind != _TOOL_REQ:
            self._moving[a] = True
            self._pos[a].clear()

    def _release_moves(self, a: int) -> None:
        for z in self._moves[a]:
            if self._mover[z] == a:
                self._mover[z] = -1
        self._moves[a].clear()

    def _waiter_order(self) -> list[int]:
        order = list(self._waiters)
        if self.wake_order == "priority":
            order.sort(key=lambda b: (-self.priorities.get(self.arms[b], 0.0), self._seq[b]))
        return order

    def _wake_pass(self, events: list[Event]) -> None:
        # Granting only takes resources, so one ordered pass reaches the
        # fixpoint: nobody skipped can have become satisfiable later on.
        for b in self._waiter_order():
            req = self._req[b]
            assert req is not None
            kind, target, path = req
            needs = self._needs(b, kind, target)
            if all(self._available(b, r) for r in needs):
                del self._waiters[b]
                self._req[b] = None
                self._grant(b, kind, target, needs)
                self.stats["woken"] += 1
                events.append(Wake(self.arms[b], (kind, self._label(kind, target))))
                self._check_blocking(b, kind, target, path, events)

    def _label(self, kind: str, target: int) -> str | None:
        if kind == _TOOL_REQ:
            return self._tname[target]
        return self._zname[target] if target >= 0 else None

    def _check_blocking(
        self, a: int, kind: str, target: int, path: FloatArray | None, events: list[Event]
    ) -> None:
        if path is None or kind == _TOOL_REQ:
            return
        zones = [target] if target >= 0 else sorted(self._inside[a])
        for z in zones:
            if self._excl[z] or not self._active[z]:
                continue
            blockers = tuple(
                self.arms[b]
                for b in sorted(self._occ[z])
                if b != a
                and not self._moving[b]
                and z in self._pos[b]
                and self.blocking_test(path, self._pos[b][z])
            )
            if blockers:
                self.stats["blocked"] += 1
                events.append(Blocked(self.arms[a], self._zname[z], blockers))

    def _find_cycle(self, start: int) -> list[tuple[int, tuple[int, int]]] | None:
        """A cycle of the wait-for graph through ``start``: [(arm, resource it waits for)]."""

        def out_edges(x: int) -> list[tuple[int, tuple[int, int]]]:
            req = self._req[x]
            if req is None:
                return []
            return [
                (h, res) for res in self._needs(x, req[0], req[1]) for h in self._holders(x, res)
            ]

        path: list[tuple[int, tuple[int, int]]] = []
        on_path: set[int] = set()
        visited: set[int] = set()
        stack: list[tuple[int, Iterable[tuple[int, tuple[int, int]]]]] = [
            (start, iter(out_edges(start)))
        ]
        on_path.add(start)
        while stack:
            node, it = stack[-1]
            advanced = False
            for nxt, res in it:
                if nxt == start:
                    path.append((node, res))
                    return path
                if nxt in on_path or nxt in visited:
                    continue
                path.append((node, res))
                on_path.add(nxt)
                stack.append((nxt, iter(out_edges(nxt))))
                advanced = True
                break
            if not advanced:
                stack.pop()
                on_path.discard(node)
                visited.add(node)
                if path:
                    path.pop()
        return None

    def _detect(self, a: int, events: list[Event]) -> None:
        cycle = self._find_cycle(a)
        if cycle is None:
            return
        self.stats["deadlocks"] += 1
        dl = Deadlock(
            tuple(self.arms[x] for x, _ in cycle), tuple(self._name(*r) for _, r in cycle)
        )
        events.append(dl)
        victim = self.policy.victim(dl, self)
        if victim is not None:
            self._back_off(self._arm(victim), events)

    def _back_off(self, v: int, events: list[Event]) -> None:
        req = self._req[v]
        if req is None:
            raise UsageError(f"deadlock policy chose arm {self.arms[v]!r}, which is not waiting")
        kind, target, _ = req
        self._req[v] = None
        del self._waiters[v]
        released: list[ResourceName] = []
        for z in sorted(self._inside[v]):
            if self._excl[z]:
                self._occ[z].discard(v)
                self._inside[v].discard(z)
                self._pos[v].pop(z, None)
                released.append(self._name(_ZONE, z))
        for t in sorted(self._tools[v]):
            self._holder[t] = -1
            released.append(self._name(_TOOL, t))
        self._tools[v].clear()
        self.stats["backoffs"] += 1
        events.append(BackOff(self.arms[v], (kind, self._label(kind, target)), tuple(released)))
        self._wake_pass(events)

    def _request(self, a: int, kind: str, target: int, path: FloatArray | None) -> Response:
        self.stats["calls"] += 1
        if self._req[a] is not None:
            raise UsageError(f"arm {self.arms[a]!r} is asleep waiting; it cannot request again")
        needs = self._needs(a, kind, target)
        events: list[Event] = []
        if all(self._available(a, r) for r in needs):
            self._grant(a, kind, target, needs)
            self.stats["granted"] += 1
            self._check_blocking(a, kind, target, path, events)
            return Response(True, tuple(events))
        # Sleep: stop at the border, give back every movement (S2.6).
        self.stats["slept"] += 1
        self._counter += 1
        self._seq[a] = self._counter
        self._req[a] = (kind, target, path)
        self._waiters[a] = None
        self._moving[a] = False
        if self._moves[a]:
            self._release_moves(a)
            self._wake_pass(events)
        missing = tuple(
            self._name(*r) for r in self._needs(a, kind, target) if not self._available(a, r)
        )
        if self._req[a] is not None:
            self._detect(a, events)
        return Response(False, tuple(events), missing if self._req[a] is not None else ())

    # ------------------------------------------------------------ messages
    def request_enter(
        self, arm: Arm, zone: str | int, path: Sequence[Sequence[float]] | FloatArray | None = None
    ) -> Response:
        """The arm asks to enter ``zone`` (S2.7 "request to move in a shared zone").

        Granted when the zone is free (exclusive: nobody inside; shared:
        nobody moving inside) and the arm can keep moving in every active
        shared zone it stands in. Otherwise the arm sleeps at the border.
        ``path`` ((M, 3) metres), when given, is checked against the reported
        positions of arms standing in the zone (:class:`Blocked` events).
        """
        a = self._arm(arm)
        z = self._zone(zone)
        if z in self._inside[a]:
            raise UsageError(f"arm {arm!r} is already inside zone {self._zname[z]!r}")
        return self._request(a, _ENTER, z, None if path is None else np.asarray(path, dtype=float))

    def request_move(
        self,
        arm: Arm,
        zone: str | int | None = None,
        path: Sequence[Sequence[float]] | FloatArray | None = None,
    ) -> Response:
        """The (stopped) arm asks to start moving again.

        It needs the movement of every active shared zone it stands in;
        ``zone``, when given, must be one of them (the S2.7 message names
        it). An arm in no shared zone is granted at once.
        """
        a = self._arm(arm)
        target = -1
        if zone is not None:
            target = self._zone(zone)
            if target not in self._inside[a]:
                raise UsageError(f"arm {arm!r} is not inside zone {self._zname[target]!r}")
        return self._request(
            a, _MOVE_REQ, target, None if path is None else np.asarray(path, dtype=float)
        )

    def acquire_tool(self, arm: Arm, tool: str | int) -> Response:
        """The arm asks for ``tool`` (exclusive; the arm sleeps while another holds it)."""
        a = self._arm(arm)
        t = self._tool(tool)
        if self._holder[t] == a:
            raise UsageError(f"arm {arm!r} already holds tool {self._tname[t]!r}")
        return self._request(a, _TOOL_REQ, t, None)

    def release_tool(self, arm: Arm, tool: str | int) -> Response:
        """The arm puts ``tool`` back; waiters may wake."""
        a = self._arm(arm)
        t = self._tool(tool)
        self.stats["calls"] += 1
        if self._holder[t] != a:
            raise UsageError(f"arm {arm!r} does not hold tool {self._tname[t]!r}")
        self._holder[t] = -1
        self._tools[a].discard(t)
        events: list[Event] = []
        self._wake_pass(events)
        return Response(True, tuple(events))

    def stop(self, arm: Arm) -> Response:
        """The arm stopped (trajectory end, or stopped inside a zone): it gives
        back every movement it held, and waiters may wake."""
        a = self._arm(arm)
        self.stats["calls"] += 1
        if self._req[a] is not None:
            raise UsageError(f"arm {arm!r} is asleep (already stopped)")
        self._moving[a] = False
        events: list[Event] = []
        if self._moves[a]:
            self._release_moves(a)
            self._wake_pass(events)
        return Response(True, tuple(events))

    def release(self, arm: Arm, zone: str | int) -> Response:
        """The arm has left ``zone`` (S2.7 "zone release"); waiters may wake."""
        a = self._arm(arm)
        z = self._zone(zone)
        self.stats["calls"] += 1
        if z not in self._inside[a]:
            raise UsageError(f"arm {arm!r} is not inside zone {self._zname[z]!r}")
        if self._req[a] is not None:
            raise UsageError(f"arm {arm!r} is asleep: it cannot leave zone {self._zname[z]!r}")
        self._inside[a].discard(z)
        self._occ[z].discard(a)
        self._pos[a].pop(z, None)
        if self._mover[z] == a:
            self._mover[z] = -1
            self._moves[a].discard(z)
        events: list[Event] = []
        self._wake_pass(events)
        return Response(True, tuple(events))

    def cancel(self, arm: Arm) -> Response:
        """Withdraw the arm's pending request (it stays stopped where it is)."""
        a = self._arm(arm)
        self.stats["calls"] += 1
        if self._req[a] is None:
            raise UsageError(f"arm {arm!r} has no pending request")
        self._req[a] = None
        del self._waiters[a]
        return Response(True)

    def report_position(self, arm: Arm, zone: str | int, position: Sequence[float]) -> Response:
        """A stopped arm inside a shared zone reports where it stands (S2.7)."""
        a = self._arm(arm)
        z = self._zone(zone)
        self.stats["calls"] += 1
        if z not in self._inside[a]:
            raise UsageError(f"arm {arm!r} is not inside zone {self._zname[z]!r}")
        if self._moving[a]:
            raise UsageError(f"arm {arm!r} is moving: only stopped arms report their position")
        p = np.asarray(position, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise UsageError(f"position must be 3 finite numbers, got {position!r}")
        self._pos[a][z] = p
        return Response(True)

    def set_active(self, zones: Iterable[str | int]) -> Response:
        """Make exactly ``zones`` active (S2.5 "active-zone grant").

        Refused, with the reason, while any arm moves, or when an exclusive
        zone would become active with several arms inside.
        """
        self.stats["calls"] += 1
        new = [False] * len(self._active)
        for z in zones:
            new[self._zone(z)] = True
        moving = [repr(self.arms[a]) for a, m in enumerate(self._moving) if m]
        if moving:
            return Response(
                False,
                reason=f"arm(s) {', '.join(moving)} moving: zones change only while every arm is stopped (S2.5)",
            )
        for z, on in enumerate(new):
            if on and self._excl[z] and len(self._occ[z]) > 1:
                inside = ", ".join(sorted(repr(self.arms[a]) for a in self._occ[z]))
                return Response(
                    False,
                    reason=f"exclusive zone {self._zname[z]!r} would become active with arms {inside} inside",
                )
        self._active = new
        events: list[Event] = []
        self._wake_pass(events)
        for b in list(self._waiters):
            if self._req[b] is not None:
                self._detect(b, events)
        return Response(True, tuple(events))

    def set_phase(self, phase: str) -> Response:
        """Switch to the named activation set of the zone map."""
        try:
            zones = self.zonemap.phase(phase).zones
        except Exception:
            raise UsageError(f"unknown phase {phase!r}") from None
        return self.set_active(zones)

    # ------------------------------------------------------------- queries
    def occupants(self, zone: str | int) -> tuple[Arm, ...]:
        """Arms inside ``zone``."""
        return tuple(self.arms[a] for a in sorted(self._occ[self._zone(zone)]))

    def mover(self, zone: str | int) -> Arm | None:
        """The arm holding the movement of a shared zone, if any."""
        m = self._mover[self._zone(zone)]
        return self.arms[m] if m >= 0 else None

    def holder(self, tool: str | int) -> Arm | None:
        """The arm holding ``tool``, if any."""
        h = self._holder[self._tool(tool)]
        return self.arms[h] if h >= 0 else None

    def zones_of(self, arm: Arm) -> tuple[str, ...]:
        """Zones the arm stands in."""
        return tuple(self._zname[z] for z in sorted(self._inside[self._arm(arm)]))

    def tools_of(self, arm: Arm) -> tuple[str, ...]:
        """Tools the arm holds."""
        return tuple(self._tname[t] for t in sorted(self._tools[self._arm(arm)]))

    def is_moving(self, arm: Arm) -> bool:
        """Whether the arm is moving (granted and not stopped since)."""
        return self._moving[self._arm(arm)]

    def waiting(self, arm: Arm) -> tuple[str, str | None] | None:
        """The arm's pending request ``(kind, target)``, or None."""
        req = self._req[self._arm(arm)]
        return None if req is None else (req[0], self._label(req[0], req[1]))

    def sleepers(self) -> tuple[Arm, ...]:
        """Waiting arms, oldest request first."""
        return tuple(self.arms[a] for a in self._waiters)

    def wait_order(self, arm: Arm) -> int:
        """Sequence number of the arm's current wait (larger = younger)."""
        return self._seq[self._arm(arm)]

    def is_active(self, zone: str | int) -> bool:
        """Whether ``zone`` is active."""
        return self._active[self._zone(zone)]

    def active_zones(self) -> tuple[str, ...]:
        """Names of the active zones."""
        return tuple(n for n, on in zip(self._zname, self._active, strict=True) if on)

    def waiting_for(self, arm: Arm) -> tuple[ResourceName, ...]:
        """Resources the arm waits for that are not available now."""
        a = self._arm(arm)
        req = self._req[a]
        if req is None:
            return ()
        return tuple(
            self._name(*r) for r in self._needs(a, req[0], req[1]) if not self._available(a, r)
        )

    def wait_for_graph(self) -> dict[Arm, frozenset[Arm]]:
        """Waiting arm → the arms holding something it needs."""
        out: dict[Arm, frozenset[Arm]] = {}
        for a in self._waiters:
            req = self._req[a]
            assert req is not None
            holders = {h for r in self._needs(a, req[0], req[1]) for h in self._holders(a, r)}
            out[self.arms[a]] = frozenset(self.arms[h] for h in holders)
        return out

    def find_deadlock(self) -> Deadlock | None:
        """A current deadlock (only with a policy that leaves them), or None."""
        for a in self._waiters:
            cycle = self._find_cycle(a)
            if cycle is not None:
                return Deadlock(
                    tuple(self.arms[x] for x, _ in cycle), tuple(self._name(*r) for _, r in cycle)
                )
        return None

    def snapshot(self) -> dict[str, Any]:
        """A plain-data view of the whole state (for logs and tests)."""
        return {
            "active": self.active_zones(),
            "occupants": {n: self.occupants(n) for n in self._zname},
            "movers": {n: self.mover(n) for n in self._zname},
            "tools": {n: self.holder(n) for n in self._tname},
            "moving": {a: self._moving[i] for i, a in enumerate(self.arms)},
            "waiting": {self.arms[a]: self.waiting(self.arms[a]) for a in self._waiters},
        }
