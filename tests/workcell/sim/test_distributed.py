"""Distributed coordination (S2.4, S2.7's last sentence): one peer per arm, no
coordinator; resource uses agreed among peers by request/reply in plan order;
emergency stops and zone activations broadcast; arm failures told by the failed
station's last frame; the plan kept (no re-solve).

Every check reads public records only: the SimResult's task and reservation
frames, its metrics and its trace (messages with their stations)."""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import pytest

from scheduler import solve
from workcell import compile_cell, load_example
from workcell.sim import (
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    LatePart,
    MessageLoss,
    SimOptions,
    simulate,
)
from workcell.sim.comms.media import MEDIA

SMALL = ("supersigma", "scara4", "urdf_cell", "parking")


@functools.cache
def _cell(name: str) -> tuple[Any, Any]:
    cc = compile_cell(load_example(name))
    return cc, solve(cc.problem, "greedy", seed=0).schedule


@functools.cache
def _run(name: str, medium: str, coordination: str = "distributed") -> Any:
    cc, plan = _cell(name)
    return simulate(cc, plan, medium=medium, coordination=coordination)


def _messages(r: Any) -> list[Any]:
    """Frames delivered by the medium (internal S2.3 messages have src == dst)."""
    return [e for e in r.trace.of_kind("message") if e.src != e.dst]


def _no_overlap(r: Any) -> None:
    rf = r.reservations_frame()
    for (kind, res), g in rf.groupby(["kind", "resource"]):
        g = g.sort_values("start")
        ends = g["end"].to_numpy()[:-1]
        starts = g["start"].to_numpy()[1:]
        assert (starts >= ends - 1e-9).all(), (kind, res, g)


@pytest.mark.parametrize("medium", MEDIA)
@pytest.mark.parametrize("name", SMALL)
def test_every_small_cell_runs_on_every_medium(name: str, medium: str) -> None:
    """No failed task, a clean monitor (simulate raises SafetyViolation
    otherwise), each resource used by one task at a time, and no frame to or
    from station 0 but the peers' broadcasts (alarms, and on a medium whose
    broadcast is one transfer the views and departure requests; station 0 is
    an empty place on the medium): there is no coordinator."""
    r = _run(name, medium)
    tf = r.tasks_frame()
    assert (tf["status"] == "done").all(), tf[tf["status"] != "done"]
    assert r.metrics.failed_tasks == 0
    assert r.executed is not None
    _no_overlap(r)
    msgs = _messages(r)
    assert all(e.src != 0 for e in msgs)
    broadcast = ("alarm", "wake_up", "motion_report", "departure_request")
    assert all(e.message in broadcast for e in msgs if e.dst == 0)
    sent = {(e.src, round(e.time - e.delay, 9), e.message) for e in msgs}  # one per broadcast
    assert r.metrics.messages >= len(sent) > 0 or (r.problem.n_arms == 1)


@pytest.mark.parametrize("name", ("supersigma", "scara4"))
def test_resources_are_used_in_the_plan_order_of_the_centralized_coordinator(name: str) -> None:
    """Both policies give every zone and tool to its tasks in plan order."""

    def order(r: Any) -> dict[tuple[str, str], list[str]]:
        rf = r.reservations_frame()
        rf = rf[rf["task"] != ""].sort_values(["start", "end"])
        return {k: list(g["task"]) for k, g in rf.groupby(["kind", "resource"])}

    d = order(_run(name, "ideal"))
    c = order(_run(name, "ideal", "centralized"))
    assert d == c
    assert any(len(v) > 1 for v in d.values())  # some resource is shared in time


def test_peers_ask_only_the_arms_that_may_interfere() -> None:
    """Zone requests go peer to peer; a cell whose arms share resources
    exchanges requests and replies, each request answered."""
    r = _run("scara4", "ideal")
    msgs = _messages(r)
    asks = [e for e in msgs if e.message == "zone_request"]
    replies = [e for e in msgs if e.message == "zone_grant"]
    assert asks and len(replies) >= len(asks)
    assert {(e.src, e.dst) for e in replies} == {(e.dst, e.src) for e in asks}
    # a peer never sends itself a frame, and no trajectory crosses the medium
    assert not [e for e in msgs if e.message == "trajectory"]


@pytest.mark.parametrize("medium", ["ideal", "serial-star"])
def test_a_departure_request_is_one_broadcast_where_the_medium_broadcasts_once(
    medium: str,
) -> None:
    """On a medium whose broadcast is one transfer (``ideal``, as the serial
    bus, Multibus II and the Ethernet bus) a peer sends each departure
    request once, and every station takes that one frame (station 0 and the
    arms that cannot meet the asker do not read it); on the serial star
    (whose hub would relay a broadcast on every line) one frame goes to
    each arm that may meet. Either way each request is answered by every
    arm asked."""
    r = _run("urdf_cell", medium)
    n = r.problem.n_arms
    asks = [e for e in _messages(r) if e.message == "departure_request"]
    assert asks
    takers: dict[tuple[int, float], set[int]] = {}
    for e in asks:
        takers.setdefault((e.src, e.time), set()).add(e.dst)
    if medium == "ideal":
        assert all(dst == set(range(n + 1)) - {src} for (src, _t), dst in takers.items())
    else:
        assert not [e for e in asks if e.dst == 0]
    answers = [e for e in _messages(r) if e.message == "motion_report" and e.dst != 0]
    assert {(e.dst, e.src) for e in asks if e.dst != 0} <= {(e.src, e.dst) for e in answers}


def test_same_seed_same_trace_under_faults() -> None:
    cc, plan = _cell("supersigma")
    faults = [
        MessageLoss(0.2),
        EmergencyStop(at=30.0, duration=2.0),
        Crash("left", at=50.0),
    ]
    runs = [
        simulate(cc, plan, seed=3, faults=faults, medium="ethernet", coordination="distributed")
        for _ in range(2)
    ]
    a, b = (r.trace.to_records() for r in runs)
    assert a == b
    assert runs[0].metrics.retransmissions > 0
    assert (runs[0].tasks_frame()["status"] == "done").all()


def test_emergency_stop_is_broadcast_by_a_peer_and_released_by_id() -> None:
    cc, plan = _cell("scara4")
    at, dur = 20.0, 3.0
    r = simulate(
        cc,
        plan,
        faults=[EmergencyStop(at=at, duration=dur)],
        medium="multibus2",
        coordination="distributed",
    )
    assert (r.tasks_frame()["status"] == "done").all()
    alarms = [e for e in _messages(r) if e.message == "alarm"]
    clears = [e for e in _messages(r) if e.message == "wake_up"]
    n = r.problem.n_arms
    assert {e.dst for e in alarms} == set(range(n + 1)) - {alarms[0].src}  # a broadcast
    assert alarms[0].src == 1  # raised at the lowest working arm's station
    assert all(at <= e.time < at + dur for e in alarms)
    assert all(e.time >= at + dur for e in clears)
    base = _run("scara4", "multibus2")
    assert r.metrics.executed_makespan >= base.metrics.executed_makespan


def test_a_late_part_holds_its_tasks_until_it_comes() -> None:
    cc, plan = _cell("supersigma")
    arrivals = cc.cell.taskset.expected_arrivals()
    part = next(iter(arrivals)) if arrivals else cc.cell.taskset.parts[0].id
    gated = {
        task.id for task in cc.cell.taskset.tasks if part in cc.cell.taskset.gating_parts(task.id)
    }
    delay = 25.0
    r = simulate(cc, plan, faults=[LatePart(part, delay)], coordination="distributed")
    tf = r.tasks_frame()
    assert (tf["status"] == "done").all()
    come = float(arrivals.get(part, 0.0)) + delay
    assert (tf.loc[tf["task"].isin(gated), "start"] >= come - 1e-9).all()
    assert r.metrics.resolves == 0  # the plan is kept


def test_a_part_that_never_comes_fails_its_tasks_and_their_successors() -> None:
    cc, plan = _cell("supersigma")
    p = cc.problem
    part = cc.cell.taskset.parts[0].id
    gated = [
        t
        for t, task in enumerate(cc.cell.taskset.tasks)
        if part in cc.cell.taskset.gating_parts(task.id)
    ]
    r = simulate(cc, plan, faults=[LatePart(part, math.inf)], coordination="distributed")
    tf = r.tasks_frame().set_index("task")
    after: set[int] = set()
    stack = list(gated)
    while stack:
        t = stack.pop()
        if t not in after:
            after.add(t)
            stack.extend(p.task_succs[t])
    for t in range(p.n_tasks):
        row = tf.loc[p.task_names[t]]
        if t in gated:
            assert row["status"] == "failed" and row["cause_kind"] == "part_missing"
        elif t in after:
            assert row["status"] == "failed" and row["cause_kind"] == "predecessor"
        else:
            assert row["status"] == "done"


@pytest.mark.parametrize("at", [20.0, 60.0])
def test_an_arm_failure_fails_what_comes_after_its_tasks_as_centralized_without_resolve(
    at: float,
) -> None:
    """The failed arm's station sends its last frames (its view, failed, to
    the arms that may meet it, then the failure to every station); the peers fail the
    tasks after its unfinished ones, and the others all run: the same tasks
    as the centralized coordinator keeping its plan (resolve=False)."""
    cc, plan = _cell("supersigma")
    fault = [ArmFailure("right", at)]
    d = simulate(cc, plan, faults=fault, medium="ethernet", coordination="distributed")
    c = simulate(cc, plan, faults=fault, medium="ethernet", options=SimOptions(resolve=False))
    tf, tc = d.tasks_frame(), c.tasks_frame()
    assert (tf["status"] == "failed").any()
    assert list(tf["status"]) == list(tc["status"])
    assert set(tf["cause_kind"]) <= {"", "arm_out", "predecessor"}
    assert (tf.loc[tf["status"] == "failed", "cause"] != "").all()
    right = 1 + cc.problem.arm_names.index("right")
    last = [e for e in _messages(d) if e.src == right and e.time >= at]
    assert {e.message for e in last} <= {"alarm", "motion_report"}
    assert [e.message for e in last][-1] == "alarm"  # its last frame, to every station
    assert d.metrics.resolves == 0


def test_a_zone_activation_stops_every_arm_then_lets_them_go_on() -> None:
    cc, plan = _cell("scara4")
    zone = cc.cell.zone_map.zone_names()[0]
    at = 30.0
    r = simulate(
        cc,
        plan,
        faults=[ActivateZones(at=at, zones=(zone,))],
        medium="csma-dcr",
        coordination="distributed",
    )
    assert (r.tasks_frame()["status"] == "done").all()
    msgs = _messages(r)
    stops = [e for e in msgs if e.message == "sleep"]
    stood = [e for e in msgs if e.message == "position"]
    go = [e for e in msgs if e.message == "active_zone_grant"]
    raiser = stops[0].src
    others = set(range(1, r.problem.n_arms + 1)) - {raiser}
    assert {e.dst for e in stops} >= others
    assert {e.src for e in stood} == others and {e.dst for e in stood} == {raiser}
    assert {e.dst for e in go} >= others
    assert max(e.time for e in stood) <= min(e.time for e in go)
    assert r.metrics.executed_makespan >= _run("scara4", "csma-dcr").metrics.executed_makespan


@pytest.mark.parametrize("delay", [5.0, 16.4])
def test_an_arm_waiting_in_the_way_backs_off_when_a_late_part_reorders_the_cell(
    delay: float,
) -> None:
    """Regression (found by a seeded fault campaign on `parking`): with the
    blank late, the delivering arm waits at its start, in the way of the
    press arm that holds the zones it waits for. The held arm has the
    waiting arm back off to its home joints (S2.6) instead of a stall: its
    peer asks over the medium (a ``back_off`` frame between the arms'
    stations) and the asked peer orders its own arm back."""
    cc, plan = _cell("parking")
    r = simulate(
        cc, plan, faults=[LatePart("blank1", delay)], medium="fixed", coordination="distributed"
    )
    tf = r.tasks_frame()
    assert (tf["status"] == "done").all(), tf[["task", "status", "cause"]]
    backs = r.trace.of_kind("detour")
    assert backs and all("backs off" in e.detail for e in backs)
    assert r.metrics.detours == len(backs)
    # the held arm's peer asks over the medium; the asked peer orders its own arm
    asks = [e for e in _messages(r) if e.message == "back_off"]
    names = r.problem.arm_names
    assert asks and all(e.src > 0 and e.dst > 0 for e in asks)
    backing = {b.arm for b in backs}
    assert backing <= {names[e.dst - 1] for e in asks}
    assert all(min(e.time for e in asks if names[e.dst - 1] == b.arm) <= b.time for b in backs)


@pytest.mark.parametrize(
    ("faults", "medium"),
    [
        ([ArmFailure("sb", 7.95)], "ideal"),
        ([LatePart("blank2", math.inf), LatePart("blank1", 14.32)], "ethernet"),
    ],
    ids=["failed_arm_in_the_way", "idle_arm_in_the_way"],
)
def test_an_arm_held_by_a_standing_arm_goes_around_it(faults: Any, medium: str) -> None:
    """Regressions (a seeded fault campaign on `parking`, the campaign's own
    plan): an arm held by an arm that failed in its way, or by one left idle
    where its last task ended, takes an alternative trajectory (S2.12) and
    finishes its tasks; the same tasks are done as under the centralized
    coordinator keeping its plan."""
    from workcell.campaign import prepare

    cc = prepare("parking")
    opts = SimOptions(resolve=False)
    d, c = (
        simulate(
            cc.compiled, cc.schedule, faults=faults, medium=medium, coordination=co, options=opts
        )
        for co in ("distributed", "centralized")
    )
    td, tc = d.tasks_frame(), c.tasks_frame()
    assert list(td["status"]) == list(tc["status"])
    assert list(td["cause_kind"]) == list(tc["cause_kind"])
    assert "deadlock" not in set(td["cause_kind"]) and "stall" not in set(td["cause_kind"])
    assert any("alternative trajectory" in e.detail for e in d.trace.of_kind("detour"))


@pytest.mark.parametrize("cell", ["parking", "urdf_cell"])
def test_a_seeded_fault_campaign_slice_finds_nothing(cell: str) -> None:
    """Seeded random fault plans of the campaign (every fault kind, 1-4 per
    episode, times at and a hair off task starts and ends, every medium) run
    under distributed coordination and checked by the campaign's own checks
    (no exception, clean monitor, every failed task explained, every task
    done that the kept plan can still do, releases and precedences kept,
    replays identical). The plan is kept under this policy, so the episodes
    are checked with re-solving off."""
    from workcell.campaign import draw_episode, prepare, run_episode

    cc = prepare(cell)
    for index in range(20):
        episode = draw_episode(cc, 7, index)
        episode = dataclasses.replace(episode, coordination="distributed", resolve=False)
        result = run_episode(cc, episode)
        assert not result.findings, (episode.faults_json(), episode.medium, result.findings)


@pytest.mark.parametrize(("cell", "seed", "index"), [("parking", 16, 239)])
def test_campaign_findings_replay_clean(cell: str, seed: int, index: int) -> None:
    """Regressions from the campaign (``multiarm campaign CELL --replay
    SEED:INDEX``). parking 16:239 (Ethernet, 14 % message loss, a late
    blank, a crash, an emergency stop): the press arm, held by the waiting
    delivery arm, asked it to back off while the press arm's report that it
    stood (which ends the delivery arm's reservation of its motion) was
    being sent again; the delivery arm's way home was not clear in its view
    yet, it refused, and nothing asked again (a stall). The asked peer now
    keeps the request and tries again whenever its view changes."""
    from workcell.campaign import draw_episode, prepare, run_episode

    cc = prepare(cell)
    episode = draw_episode(cc, seed, index)
    assert episode.coordination == "distributed"
    result = run_episode(cc, episode)
    assert not result.findings, result.findings
    assert result.done == cc.compiled.problem.n_tasks


def test_the_detour_ablations_reach_the_peers() -> None:
    """``SimOptions.detours``, ``detour_checks`` and ``guard_answer`` mean the
    same under both policies: on ``parking`` (S2.6) the tree plan's peer goes
    around the parked arm; with detours off it waits, later, every task done;
    a guard answer that never blocks leaves nothing to go around."""
    from scheduler import TreeOptions

    cc, _ = _cell("parking")
    plan = solve(cc, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=2000))
    assert plan.schedule is not None
    runs = {
        name: simulate(cc, plan.schedule, seed=0, coordination="distributed", options=opts)
        for name, opts in {
            "on": SimOptions(),
            "off": SimOptions(detours=False),
            "clear": SimOptions(monitor=False, guard_answer=lambda mover, arms: ()),
        }.items()
    }
    n = cc.problem.n_tasks
    assert runs["on"].metrics.detours >= 1 and runs["off"].metrics.detours == 0
    assert runs["clear"].metrics.detours == 0
    assert all(r.metrics.done_tasks == n for r in runs.values())
    assert runs["off"].metrics.executed_makespan > runs["on"].metrics.executed_makespan
