"""The run-time zone protocol (S2.5-S2.7) and deadlock handling (S2.6).

Scenario tests, then Hypothesis rule-based state machines that drive a
ZoneManager with random sequences of requests, releases, motion starts and
stops, tool use and activation changes, and check it against an independent
model built only from the responses and events it returns.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pytest
from hypothesis import settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from multiarm.errors import UsageError
from zones.manager import (
    BackOff,
    Blocked,
    Deadlock,
    LowestPriorityBacksOff,
    ReportOnly,
    Response,
    Wake,
    YoungestBacksOff,
    ZoneManager,
)
from zones.sdl import parse_sdl

MAP = parse_sdl(
    """
cell (0, 0, 0) (4, 1, 1)
zone E1 exclusive box (0, 0, 0) (1, 1, 1)
zone E2 exclusive box (1, 0, 0) (2, 1, 1)
zone S1 shared    box (2, 0, 0) (3, 1, 1)
zone S2 shared    box (2.5, 0, 0) (4, 1, 1)
tool T1 rack (2.2, 0.5, 0.5)
tool T2 rack (3.8, 0.5, 0.5)
phase only_shared { S1, S2 }
"""
)
SHARED_MAP = parse_sdl(
    """
cell (0, 0, 0) (4, 1, 1)
zone S1 shared box (0, 0, 0) (2, 1, 1)
zone S2 shared box (1, 0, 0) (3, 1, 1)
zone S3 shared box (2, 0, 0) (4, 1, 1)
"""
)


# ----------------------------------------------------------------- scenarios


def test_exclusive_zone_one_arm_at_a_time_fifo() -> None:
    m = ZoneManager(MAP, ["a", "b", "c"])
    assert m.request_enter("a", "E1").granted
    rb = m.request_enter("b", "E1")
    rc = m.request_enter("c", "E1")
    assert not rb.granted and rb.waiting_for == (("zone", "E1"),)
    assert not rc.granted
    assert m.sleepers() == ("b", "c")
    r = m.release("a", "E1")
    assert r.events == (Wake("b", ("enter", "E1")),)  # first come, first served
    assert m.occupants("E1") == ("b",)
    assert m.release("b", "E1").events == (Wake("c", ("enter", "E1")),)
    assert m.sleepers() == ()


def test_priority_wake_order() -> None:
    m = ZoneManager(MAP, ["a", "b", "c"], wake_order="priority", priorities={"c": 5})
    m.request_enter("a", "E1")
    m.request_enter("b", "E1")
    m.request_enter("c", "E1")
    assert m.release("a", "E1").events == (Wake("c", ("enter", "E1")),)


def test_shared_zone_many_stand_one_moves() -> None:
    m = ZoneManager(MAP, ["a", "b"])
    assert m.request_enter("a", "S1").granted
    assert m.mover("S1") == "a"
    r = m.request_enter("b", "S1")
    assert not r.granted and r.waiting_for == (("move", "S1"),)
    # a stops inside S1: it gives back the movement and b goes on
    assert m.stop("a").events == (Wake("b", ("enter", "S1")),)
    assert m.occupants("S1") == ("a", "b")
    assert m.mover("S1") == "b"
    # a wants to move again: refused while b moves
    assert not m.request_move("a", "S1").granted
    assert m.stop("b").events == (Wake("a", ("move", "S1")),)


def test_refused_mover_gives_back_its_movement() -> None:
    # S2.6: a refused arm never holds two resources of movement
    m = ZoneManager(MAP, ["a", "b", "c"])
    assert m.request_enter("a", "S1").granted
    assert m.request_enter("b", "E1").granted
    r = m.request_enter("c", "S1")
    assert not r.granted
    r = m.request_enter("a", "E1")  # a moving in S1 is refused E1 ...
    assert not r.granted
    assert r.events == (Wake("c", ("enter", "S1")),)  # ... so S1's movement passes to c
    assert m.mover("S1") == "c"
    assert not m.is_moving("a")


def test_entering_from_inside_a_shared_zone_needs_its_movement_too() -> None:
    m = ZoneManager(MAP, ["a", "b"], start_in={"a": ["S1"], "b": ["S1"]})
    assert m.request_move("b").granted
    r = m.request_enter("a", "E2")  # a would move inside S1 while b moves there
    assert not r.granted and r.waiting_for == (("move", "S1"),)
    assert m.stop("b").events == (Wake("a", ("enter", "E2")),)


def test_tool_deadlock_detected_and_reported() -> None:
    m = ZoneManager(MAP, ["a", "b"], deadlock_policy=ReportOnly())
    assert m.acquire_tool("a", "T1").granted
    assert m.acquire_tool("b", "T2").granted
    assert not m.acquire_tool("a", "T2").granted
    r = m.acquire_tool("b", "T1")
    assert not r.granted
    (dl,) = r.events
    assert isinstance(dl, Deadlock)
    assert set(dl.arms) == {"a", "b"}
    assert set(dl.resources) == {("tool", "T1"), ("tool", "T2")}
    assert "waits for tool 'T1' held by 'a'" in dl.describe()
    assert m.find_deadlock() is not None
    assert m.wait_for_graph() == {"a": frozenset({"b"}), "b": frozenset({"a"})}


def test_zone_and_tool_deadlock_youngest_backs_off() -> None:
    m = ZoneManager(MAP, ["a", "b"])  # default policy: YoungestBacksOff
    assert m.request_enter("a", "E1").granted
    assert m.acquire_tool("b", "T1").granted
    assert not m.acquire_tool("a", "T1").granted  # a in E1 waits for T1
    r = m.request_enter("b", "E1")  # b holding T1 waits for E1: cycle
    assert not r.granted
    kinds = [type(e) for e in r.events]
    assert kinds == [Deadlock, BackOff, Wake]
    back = r.events[1]
    assert isinstance(back, BackOff) and back.arm == "b"  # the youngest waiter
    assert back.released == (("tool", "T1"),)
    assert r.events[2] == Wake("a", ("tool", "T1"))
    assert m.holder("T1") == "a" and m.waiting("b") is None
    assert m.find_deadlock() is None


def test_lowest_priority_backs_off() -> None:
    policy = LowestPriorityBacksOff({"a": 0, "b": 10})
    m = ZoneManager(MAP, ["a", "b"], deadlock_policy=policy)
    m.request_enter("a", "E1")
    m.request_enter("b", "E2")
    m.request_enter("a", "E2")
    r = m.request_enter("b", "E1")
    back = next(e for e in r.events if isinstance(e, BackOff))
    assert back.arm == "a" and back.released == (("zone", "E1"),)
    assert Wake("b", ("enter", "E1")) in r.events


def test_geometric_block_is_reported() -> None:
    m = ZoneManager(MAP, ["a", "b"], clearance=0.1)
    assert m.request_enter("b", "S1").granted
    m.stop("b")
    m.report_position("b", "S1", (2.5, 0.5, 0.5))
    path = np.array([[2.0, 0.5, 0.5], [3.0, 0.5, 0.5]])
    r = m.request_enter("a", "S1", path=path)
    assert r.granted
    assert r.events == (Blocked("a", "S1", ("b",)),)
    m.stop("a")
    far = np.array([[2.0, 0.9, 0.9], [3.0, 0.9, 0.9]])
    assert m.request_move("a", "S1", path=far).events == ()
    assert m.stats["blocked"] == 1


def test_activation_changes_only_when_all_stopped() -> None:
    m = ZoneManager(MAP, ["a", "b"])
    m.request_enter("a", "S1")
    r = m.set_active(["S1"])
    assert not r.granted and "'a'" in r.reason and "stopped" in r.reason
    m.stop("a")
    assert m.set_phase("only_shared").granted
    assert m.active_zones() == ("S1", "S2")
    # E1 is inactive now: anyone may enter, no constraint
    assert m.request_enter("a", "E1").granted
    assert m.request_enter("b", "E1").granted
    m.stop("a")
    m.stop("b")
    r = m.set_active(["E1", "S1", "S2"])
    assert not r.granted and "would become active with arms 'a', 'b'" in r.reason
    assert m.active_zones() == ("S1", "S2")


def test_deactivation_wakes_waiters() -> None:
    m = ZoneManager(MAP, ["a", "b"])
    m.request_enter("a", "E1")
    m.stop("a")
    assert not m.request_enter("b", "E1").granted
    r = m.set_active(["E2", "S1", "S2"])
    assert r.granted and r.events == (Wake("b", ("enter", "E1")),)


def test_misuse_raises_usage_error_and_changes_nothing() -> None:
    m = ZoneManager(MAP, ["a", "b"])
    m.request_enter("a", "E1")
    m.request_enter("b", "E1")
    before = m.snapshot()
    for call in (
        lambda: m.request_enter("zed", "E1"),
        lambda: m.request_enter("a", "nowhere"),
        lambda: m.request_enter("a", "E1"),
        lambda: m.request_enter("b", "E2"),  # asleep
        lambda: m.release("b", "E1"),
        lambda: m.stop("b"),
        lambda: m.release_tool("a", "T1"),
        lambda: m.acquire_tool("a", "hammer"),
        lambda: m.report_position("a", "E1", (0, 0, 0)),  # moving
        lambda: m.cancel("a"),
        lambda: m.request_move("a", "S1"),
        lambda: m.set_phase("lunch"),
    ):
        with pytest.raises(UsageError):
            call()
    assert m.snapshot() == before
    with pytest.raises(UsageError, match="cannot all start in exclusive zone"):
        ZoneManager(MAP, ["a", "b"], start_in={"a": ["E1"], "b": ["E1"]})
    with pytest.raises(UsageError, match="distinct"):
        ZoneManager(MAP, ["a", "a"])


def test_cancel_withdraws() -> None:
    m = ZoneManager(MAP, ["a", "b"])
    m.request_enter("a", "E1")
    m.request_enter("b", "E1")
    assert m.cancel("b").granted
    assert m.release("a", "E1").events == ()


# ------------------------------------------------------------ state machine


class Model:
    """What the arms do, as told by the manager's answers only."""

    def __init__(self, zm, arms: list[str]) -> None:  # type: ignore[no-untyped-def]
        self.zm = zm
        self.excl = {z.name: z.exclusive for z in zm.zones}
        self.active = {z.name for z in zm.zones if zm.active_mask()[zm.zone_id(z.name)]}
        self.inside: dict[str, set[str]] = {a: set() for a in arms}
        self.moving = dict.fromkeys(arms, False)
        self.sleeping: dict[str, tuple[str, str | None] | None] = dict.fromkeys(arms)
        self.tools: dict[str, set[str]] = {a: set() for a in arms}
        self.woken: list[str] = []

    def holder(self, tool: str) -> str | None:
        return next((a for a, ts in self.tools.items() if tool in ts), None)

    def blockers(self, arm: str, kind: str, target: str | None) -> set[str]:
        """Arms holding something ``arm`` needs for its request (reference rule)."""
        out: set[str] = set()
        if kind == "tool":
            h = self.holder(target)  # type: ignore[arg-type]
            return {h} if h and h != arm else set()
        zones = set()
        if kind == "enter":
            assert target is not None
            if target in self.active:
                if self.excl[target]:
                    out |= {b for b in self.inside if b != arm and target in self.inside[b]}
                else:
                    zones.add(target)
        zones |= {z for z in self.inside[arm] if z in self.active and not self.excl[z]}
        for z in zones:
            out |= {b for b in self.inside if b != arm and self.moving[b] and z in self.inside[b]}
        return out

    def apply(self, arm: str, request: tuple[str, str | None], r: Response) -> None:
        kind, target = request
        if r.granted:
            self._granted(arm, kind, target)
        else:
            self.sleeping[arm] = request
            self.moving[arm] = False
        for e in r.events:
            self.event(e)

    def _granted(self, arm: str, kind: str, target: str | None) -> None:
        if kind == "tool":
            self.tools[arm].add(target)  # type: ignore[arg-type]
            return
        if kind == "enter":
            self.inside[arm].add(target)  # type: ignore[arg-type]
        self.moving[arm] = True

    def event(self, e: object) -> None:
        if isinstance(e, Wake):
            assert self.sleeping[e.arm] == e.request, (
                f"wake of {e.arm} which waits for {self.sleeping[e.arm]}"
            )
            self.sleeping[e.arm] = None
            self.woken.append(e.arm)
            self._granted(e.arm, *e.request)
        elif isinstance(e, BackOff):
            assert self.sleeping[e.arm] == e.withdrawn
            self.sleeping[e.arm] = None
            for kind, name in e.released:
                if kind == "tool":
                    self.tools[e.arm].discard(name)
                else:
                    self.inside[e.arm].discard(name)

    def graph(self) -> dict[str, set[str]]:
        return {a: self.blockers(a, *req) for a, req in self.sleeping.items() if req is not None}


def reaches_itself(graph: dict[str, set[str]], start: str) -> bool:
    seen: set[str] = set()
    todo = list(graph.get(start, ()))
    while todo:
        x = todo.pop()
        if x == start:
            return True
        if x not in seen:
            seen.add(x)
            todo.extend(graph.get(x, ()))
    return False


ARMS = ["r0", "r1", "r2", "r3"]


class ProtocolMachine(RuleBasedStateMachine):
    zonemap = MAP
    policy_factory: object = ReportOnly

    @initialize(order=st.sampled_from(["fifo", "priority"]))
    def setup(self, order: str) -> None:
        self.m = ZoneManager(
            self.zonemap,
            ARMS,
            wake_order=order,
            priorities={"r2": 3, "r0": 1},
            deadlock_policy=self.policy_factory(),  # type: ignore[operator]
        )
        self.model = Model(self.zonemap, ARMS)
        self.deadlocks_seen = 0
        self.zone_names = [z.name for z in self.zonemap.zones]
        self.tool_names = [t.name for t in self.zonemap.tools]

    # Rules draw indices, mapped onto this machine's own zone map.
    zones = st.integers(0, 7)
    arms = st.sampled_from(ARMS)
    tools = st.integers(0, 3)

    def _zone(self, i: int) -> str:
        return self.zone_names[i % len(self.zone_names)]

    def _after_request(self, arm: str, req: tuple[str, str | None], r: Response) -> None:
        self.model.apply(arm, req, r)
        dls = [e for e in r.events if isinstance(e, Deadlock)]
        self.deadlocks_seen += len(dls)
        resolved = any(isinstance(e, BackOff) for e in r.events)
        if not r.granted and not resolved and isinstance(self.m.policy, ReportOnly):
            # a deadlock is reported if and only if this wait closed a cycle
            graph = self.model.graph()
            assert bool(dls) == reaches_itself(graph, arm), (graph, r)
        if dls and not any(isinstance(e, BackOff) for e in r.events):
            # every edge of the reported cycle is real
            for d in dls:
                n = len(d.arms)
                for i, a in enumerate(d.arms):
                    req = self.model.sleeping[a]
                    assert req is not None
                    assert d.arms[(i + 1) % n] in self.model.blockers(a, *req)

    @rule(arm=arms, zi=zones)
    def enter(self, arm: str, zi: int) -> None:
        zone = self._zone(zi)
        if self.model.sleeping[arm] is not None or zone in self.model.inside[arm]:
            with pytest.raises(UsageError):
                self.m.request_enter(arm, zone)
            return
        self._after_request(arm, ("enter", zone), self.m.request_enter(arm, zone))

    @rule(arm=arms)
    def move(self, arm: str) -> None:
        if self.model.sleeping[arm] is not None:
            with pytest.raises(UsageError):
                self.m.request_move(arm)
            return
        self._after_request(arm, ("move", None), self.m.request_move(arm))

    @rule(arm=arms)
    def stop(self, arm: str) -> None:
        if self.model.sleeping[arm] is not None:
            with pytest.raises(UsageError):
                self.m.stop(arm)
            return
        r = self.m.stop(arm)
        self.model.moving[arm] = False
        for e in r.events:
            self.model.event(e)

    @rule(arm=arms, zi=zones)
    def leave(self, arm: str, zi: int) -> None:
        zone = self._zone(zi)
        if self.model.sleeping[arm] is not None or zone not in self.model.inside[arm]:
            with pytest.raises(UsageError):
                self.m.release(arm, zone)
            return
        r = self.m.release(arm, zone)
        self.model.inside[arm].discard(zone)
        for e in r.events:
            self.model.event(e)

    @rule(arm=arms, ti=tools)
    def take_tool(self, arm: str, ti: int) -> None:
        if not self.tool_names:
            return
        tool = self.tool_names[ti % len(self.tool_names)]
        if self.model.sleeping[arm] is not None or tool in self.model.tools[arm]:
            with pytest.raises(UsageError):
                self.m.acquire_tool(arm, tool)
            return
        self._after_request(arm, ("tool", tool), self.m.acquire_tool(arm, tool))

    @rule(arm=arms, ti=tools)
    def put_tool(self, arm: str, ti: int) -> None:
        if not self.tool_names:
            return
        tool = self.tool_names[ti % len(self.tool_names)]
        if tool not in self.model.tools[arm]:
            with pytest.raises(UsageError):
                self.m.release_tool(arm, tool)
            return
        r = self.m.release_tool(arm, tool)
        self.model.tools[arm].discard(tool)
        for e in r.events:
            self.model.event(e)

    @rule(arm=arms)
    def give_up(self, arm: str) -> None:
        if self.model.sleeping[arm] is None:
            with pytest.raises(UsageError):
                self.m.cancel(arm)
            return
        self.m.cancel(arm)
        self.model.sleeping[arm] = None

    @rule(chosen=st.sets(zones))
    def activate(self, chosen: set[int]) -> None:
        active = {self._zone(i) for i in chosen}
        r = self.m.set_active(sorted(active))
        if any(self.model.moving.values()):
            assert not r.granted
            return
        crowded = [
            z
            for z in active
            if self.model.excl[z] and sum(z in s for s in self.model.inside.values()) > 1
        ]
        assert r.granted == (not crowded), r.reason
        if r.granted:
            self.model.active = set(active)
            for e in r.events:
                self.model.event(e)

    # -- invariants ---------------------------------------------------------
    @invariant()
    def never_two_inside_an_exclusive_zone(self) -> None:
        for z in self.model.active:
            if self.model.excl[z]:
                assert sum(z in s for s in self.model.inside.values()) <= 1, z

    @invariant()
    def never_two_moving_in_a_shared_zone(self) -> None:
        for z in self.model.active:
            if not self.model.excl[z]:
                movers = [a for a in ARMS if self.model.moving[a] and z in self.model.inside[a]]
                assert len(movers) <= 1, (z, movers)
                assert self.m.mover(z) == (movers[0] if movers else None)

    @invariant()
    def tools_are_exclusive(self) -> None:
        for t in self.tool_names:
            holders = [a for a in ARMS if t in self.model.tools[a]]
            assert len(holders) <= 1 and self.m.holder(t) == (holders[0] if holders else None)

    @invariant()
    def model_and_manager_agree(self) -> None:
        # the events told the whole story: no lost and no duplicate wake-ups
        for a in ARMS:
            assert set(self.m.zones_of(a)) == self.model.inside[a]
            assert self.m.is_moving(a) == self.model.moving[a]
            assert self.m.waiting(a) == self.model.sleeping[a]
            assert set(self.m.tools_of(a)) == self.model.tools[a]

    @invariant()
    def nobody_sleeps_on_a_free_resource(self) -> None:
        for a, req in self.model.sleeping.items():
            if req is not None:
                assert self.model.blockers(a, *req), f"{a} sleeps on {req} although it is free"

    @invariant()
    def deadlock_state_matches_the_graph(self) -> None:
        graph = self.model.graph()
        cyclic = any(reaches_itself(graph, a) for a in graph)
        assert (self.m.find_deadlock() is not None) == cyclic
        if not isinstance(self.m.policy, ReportOnly):
            assert not cyclic  # every deadlock was resolved at once


class ResolvingMachine(ProtocolMachine):
    policy_factory = YoungestBacksOff


class SharedOnlyMachine(ProtocolMachine):
    """Only restricted-simultaneous zones, no tools: logical deadlock cannot occur (S2.6)."""

    zonemap = SHARED_MAP

    @invariant()
    def no_deadlock_ever(self) -> None:
        assert self.deadlocks_seen == 0
        assert self.m.find_deadlock() is None


def _run(machine: type[RuleBasedStateMachine], examples: int) -> None:
    test = machine.TestCase
    test.settings = settings(max_examples=examples, stateful_step_count=60, deadline=None)
    test().runTest()


def test_protocol_state_machine_report_only() -> None:
    _run(ProtocolMachine, 150)


def test_protocol_state_machine_resolving() -> None:
    _run(ResolvingMachine, 150)


def test_shared_zones_cannot_deadlock() -> None:
    _run(SharedOnlyMachine, 100)


def test_deadlocks_do_occur_in_the_machine_with_exclusive_zones() -> None:
    """The iff-check above is not vacuous: scripted cycles are found."""
    m = ZoneManager(MAP, ARMS, deadlock_policy=ReportOnly())
    steps: Iterable[tuple[str, str]] = [("r0", "E1"), ("r1", "E2"), ("r0", "E2"), ("r1", "E1")]
    found = [e for a, z in steps for e in m.request_enter(a, z).events if isinstance(e, Deadlock)]
    assert len(found) == 1
