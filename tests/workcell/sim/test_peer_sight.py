"""Distributed peers see the other arms only through frames on the medium
(S2.4, S2.7, S2.12): each peer's own view, the departure check by request
and reply among the arms that may meet, reservations, watch and notify.

As in test_exchange, the policy is built with no controller: the arms are
the channel's ends, driven by hand with their records, and a peer's
decisions are read from the orders it gives its own arm and the frames on
the medium (the trace)."""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workcell.campaign import prepare
from workcell.sim.comms.link import Link
from workcell.sim.comms.medium import FixedLatencyMedium
from workcell.sim.coordination.distributed import DistributedPolicy
from workcell.sim.coordination.distributed.reach import may_meet
from workcell.sim.coordination.guard import GeometryGuard
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
from workcell.sim.harness.faults import MessageLoss
from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.exchange import (
    ArmView,
    Departure,
    DepartureRequest,
    MotionReport,
    ReleaseHold,
)
from workcell.sim.protocol.messages import Leg, Station


@functools.cache
def _parking() -> Any:
    return prepare("parking")


class _PointToPoint(FixedLatencyMedium):
    """The fixed-latency medium with a broadcast taken as dear as one frame
    per station (as the serial star): the peers send one frame per arm."""

    broadcast_once = False


def _wired(cc: Any, latency: float, loss: Any = None, seed: int = 0, broadcast: bool = True) -> Any:
    kernel = EventLoop()
    trace = Trace()
    n = cc.problem.n_arms
    names = ["coordinator", *cc.problem.arm_names]
    kind = FixedLatencyMedium if broadcast else _PointToPoint
    med = kind(kernel, stations=n + 1, latency=latency)
    link = Link(kernel, med, trace, names, loss, np.random.default_rng(seed))
    channel = ControlChannel(n, link)
    for a in range(n):
        link.receivers[a + 1] = functools.partial(channel.at_station, a)
    orders: dict[int, list[tuple[float, Any]]] = {a: [] for a in range(n)}
    for a in range(n):
        channel.attach_arm(
            a, lambda o, a=a: orders[a].append((kernel.now, o)), lambda kind, payload: None
        )
    return kernel, trace, channel, orders


def _motion(cc: Any, a: int, mode: int, f0: float, f1: float) -> ArmView:
    """Arm ``a`` standing at fraction ``f0`` of mode ``mode``'s trajectory,
    its next station at fraction ``f1`` (> f0)."""
    traj = cc.modes[mode].trajectory
    d = float(traj.duration)
    t0, t1 = f0 * d, max(f1 * d, f0 * d + 1e-3)
    leg = Leg("task", 0, mode, traj, [Station(t1, end=True)])
    q = traj.sample(np.array([t0]))[0]
    return ArmView(a, leg, 0, t0, 0.0, False, q)


def _standing_at_end(view: ArmView, now: float) -> ArmView:
    assert view.leg is not None
    tau = float(view.leg.stations[0].tau)
    q = view.leg.trajectory.sample(np.array([tau]))[0]
    return ArmView(view.index, None, 0, 0.0, now, False, q)


def _departures(orders: list[tuple[float, Any]]) -> list[Departure]:
    return [o for _t, o in orders if isinstance(o, Departure)]


@settings(max_examples=160, deadline=None, derandomize=True)
@given(
    modes=st.tuples(st.sampled_from([2, 3]), st.sampled_from([0, 1, 4])),
    cuts=st.tuples(*[st.floats(0.0, 1.0) for _ in range(4)]),
    latency=st.sampled_from([0.0, 1e-4, 3e-3]),
    lag=st.sampled_from([0.0, 0.0, 5e-5, 2e-3]),
    loss=st.sampled_from([0.0, 0.3]),
    first=st.sampled_from([0, 1]),
    seed=st.integers(0, 2**16),
    broadcast=st.booleans(),
)
def test_two_arms_asking_at_once_never_both_set_off_into_each_other(
    modes: tuple[int, int],
    cuts: tuple[float, ...],
    latency: float,
    lag: float,
    loss: float,
    first: int,
    seed: int,
    broadcast: bool,
) -> None:
    """Seeded random timing campaign on ``parking``'s two arms, the real
    geometric check: both controllers ask to set off on motions drawn from
    their tasks' trajectories, at the same instant or a hair apart, on a
    medium with delay and loss. Each gets exactly one answer; if both are
    told *continue*, their two motions (each anywhere on its stretch, at
    any time) touch nowhere; if each motion is clear of the other arm where
    it stands, they do not both stand (the clock orders them). Then the
    arm that went reports that it stands at its station: a held arm whose
    way is now clear is released (watch and notify), and only then. Drawn
    with the requests and views sent as one broadcast (a medium whose
    broadcast is one transfer) and as one frame per arm."""
    cc = _parking().compiled
    loss_model = MessageLoss(loss, timeout=4e-3) if loss else None
    kernel, trace, channel, orders = _wired(cc, latency, loss_model, seed, broadcast)
    DistributedPolicy(cc, _parking().schedule, kernel, channel.link, Trace(), channel)
    f = sorted(cuts[:2]), sorted(cuts[2:])
    views = [_motion(cc, 0, modes[0], *f[0]), _motion(cc, 1, modes[1], *f[1])]
    kernel.schedule(0.0, channel.report, first, DepartureRequest(views[first], 1))
    kernel.schedule(lag, channel.report, 1 - first, DepartureRequest(views[1 - first], 1))
    kernel.run(until=1.0)
    asked = [e.dst for e in trace.of_kind("message") if e.message == "departure_request"]
    assert 0 in asked if broadcast else 0 not in asked  # station 0 hears a broadcast
    answers = [_departures(orders[a]) for a in (0, 1)]
    assert [len(x) for x in answers] == [1, 1]
    go = [answers[a][0].go for a in (0, 1)]
    guard = GeometryGuard(cc)

    def touches(a: int, other: ArmView) -> bool:
        return bool(guard.blockers(views[a], [views[a], other]))

    moving = [dataclasses.replace(v, running=True) for v in views]
    if all(go):
        assert not touches(0, moving[1]) and not touches(1, moving[0])
    if not touches(0, views[1]) and not touches(1, views[0]):
        assert any(go)
    if go[0] != go[1]:
        mover, held = (0, 1) if go[0] else (1, 0)
        channel.report(held, MotionReport(dataclasses.replace(views[held], held=True), True))
        kernel.run(until=2.0)
        assert not any(isinstance(o, ReleaseHold) for _t, o in orders[held])
        end = _standing_at_end(views[mover], kernel.now)
        channel.report(mover, MotionReport(end, True))
        kernel.run(until=3.0)
        released = any(isinstance(o, ReleaseHold) for _t, o in orders[held])
        assert released == (not touches(held, end))


def test_the_dangerous_pairs_exist() -> None:
    """The campaign above is not empty: some pairs of ``parking``'s motions
    are each clear of the other arm standing but touch when both move (two
    checks against the other's last report would both say *continue*)."""
    cc = _parking().compiled
    guard = GeometryGuard(cc)
    found = 0
    rng = np.random.default_rng(0)
    for _ in range(300):
        f0, f1 = np.sort(rng.random(2)), np.sort(rng.random(2))
        v = [
            _motion(cc, 0, int(rng.choice([2, 3])), *f0),
            _motion(cc, 1, int(rng.choice([0, 1, 4])), *f1),
        ]
        run = [dataclasses.replace(x, running=True) for x in v]
        clear_standing = not guard.blockers(v[0], [v[0], v[1]]) and not guard.blockers(
            v[1], [v[1], v[0]]
        )
        if clear_standing and guard.blockers(v[0], [v[0], run[1]]):
            found += 1
    assert found > 0


@pytest.mark.parametrize("loss", [0.0, 0.999])
def test_a_held_peer_goes_on_only_when_the_frame_saying_the_way_is_clear_arrives(
    loss: float,
) -> None:
    """Proof that a peer decides from its own view: arm 1 moves, arm 0 is
    held; arm 1 then reports that it stands. Arm 0's peer releases its arm
    at the instant that report's frame reaches its station: one medium
    delay later, or, when the frame is lost, after its retransmission. A
    peer reading a shared book would release it at once."""
    cc = _parking().compiled
    lossy = MessageLoss(loss, kinds=("motion_report",), timeout=1e-3) if loss else None
    kernel, trace, channel, orders = _wired(cc, 0.01, lossy)

    def answer(mover: ArmView, book: Any) -> list[int]:
        return [v.index for v in book if v.index != mover.index and v.running]

    DistributedPolicy(
        cc, _parking().schedule, kernel, channel.link, Trace(), channel, guard_answer=answer
    )
    still = [
        ArmView(a, None, 0, 0.0, 0.0, False, np.asarray(q)) for a, q in enumerate(cc.cell.start)
    ]
    channel.report(1, MotionReport(dataclasses.replace(still[1], running=True), True))
    kernel.run(until=5.0)
    channel.report(0, DepartureRequest(still[0], 1))
    kernel.run(until=10.0)
    assert _departures(orders[0]) == [Departure(False, 1)]
    channel.report(0, MotionReport(dataclasses.replace(still[0], held=True), False))
    kernel.run(until=15.0)
    assert not [o for _t, o in orders[0] if isinstance(o, ReleaseHold)]
    channel.report(1, MotionReport(still[1], True))
    kernel.run(until=30.0)
    released = [t for t, o in orders[0] if isinstance(o, ReleaseHold)]
    arrived = [
        e.time
        for e in trace.of_kind("message")
        if e.message == "motion_report" and e.src == 2 and e.dst == 1 and e.time >= 15.0
    ]
    lost = [e for e in trace.of_kind("fault") if e.src == 2 and e.time >= 15.0]
    assert len(released) == 1 and arrived
    assert released[0] == pytest.approx(arrived[0])
    assert released[0] == pytest.approx(15.0 + 0.01 + 1e-3 * len(lost))
    assert bool(lost) == bool(loss)


def test_may_meet_holds_every_sampled_contact(cell: Any, scara4: Any) -> None:
    """The arms a peer talks to (:func:`may_meet`) include every arm whose
    shapes come near its own in some sampled pair of poses within the joint
    limits (each shape bounded by its sphere), on three built-in cells."""
    rng = np.random.default_rng(3)
    for name, cc in (("parking", _parking().compiled), ("supersigma", cell), ("scara4", scara4)):
        near = may_meet(cc)
        arms = cc.cell.arms
        spheres = []
        for arm in arms:
            lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
            q = lo + (hi - lo) * rng.random((200, arm.dof))
            c = arm.shape_transforms(q)[:, :, :3, 3].reshape(-1, 3)
            r = np.tile([s.radius() for s in arm.shapes], len(q))
            spheres.append((c, r))
        for a in range(len(arms)):
            for b in range(a + 1, len(arms)):
                (ca, ra), (cb, rb) = spheres[a], spheres[b]
                d = np.linalg.norm(ca[:, None, :] - cb[None, :, :], axis=2)
                if (d <= ra[:, None] + rb[None, :]).any():
                    assert b in near[a] and a in near[b], (name, a, b)


def test_peers_share_no_check_and_no_task_record() -> None:
    """Nothing a peer writes is another's: each peer has its own geometric
    check (its own caches), each publishes the records of its own tasks
    only, and the policy's task states are read from those records."""
    cc = _parking().compiled
    plan = _parking().schedule
    kernel, _trace, channel, _orders = _wired(cc, 0.0)
    policy = DistributedPolicy(cc, plan, kernel, channel.link, Trace(), channel)
    guards = [peer.sight.guard for peer in policy.peers]
    assert all(g is not None for g in guards)
    assert len({id(g) for g in guards}) == len(policy.peers)
    p = cc.problem
    for peer in policy.peers:
        own = {t for t in range(p.n_tasks) if int(p.mode_arm[int(plan.mode[t])]) == peer.a}
        assert set(peer.status) == own
    first = policy.peers[0].tasks[0]
    policy.peers[0].task_failed(first, "a test", "insertion")
    assert policy.status[first] == "failed"
    assert (policy.cause[first], policy.cause_kind[first]) == ("a test", "insertion")
    assert all(policy.peers[1].status[t] == "pending" for t in policy.peers[1].tasks if t != first)
