"""The simulation's fast paths give exactly what the plain computations give.

The geometric guard (S2.12) keeps each arm's constant capsule data and
bounds swept boxes in one compiled pass; the event loop pauses the cyclic
garbage collector while it runs. Seeded random inputs, bit-for-bit equality.
"""

from __future__ import annotations

import gc
import math
from typing import Any

import numpy as np
import pytest

from workcell import SimOptions, simulate
from workcell.geometry.zone_sweep import _segments
from workcell.sim.coordination.guard import GeometryGuard, _swept_box
from workcell.sim.events.loop import EventLoop
from workcell.sim.harness.monitor import ZoneWindows
from workcell.sim.harness.monitor_geometry import (
    MonitorGeometry,
    first_touching_sample,
    touching_pairs,
)


@pytest.mark.parametrize("seed", range(5))
def test_swept_box_is_the_numpy_bounds(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, s = int(rng.integers(1, 40)), int(rng.integers(1, 9))
    p0, p1 = rng.normal(size=(2, n, s, 3)) * 10.0 ** rng.uniform(-3, 1)
    grow = float(rng.uniform(0.0, 0.2))
    box = _swept_box(p0, p1, grow)
    lo = np.minimum(p0.min(axis=(0, 1)), p1.min(axis=(0, 1))) - grow
    hi = np.maximum(p0.max(axis=(0, 1)), p1.max(axis=(0, 1))) + grow
    assert np.array_equal(box, np.concatenate([lo, hi]))


@pytest.mark.parametrize("name", ["cell", "scara4"])
def test_guard_capsule_ends_are_those_of_the_zone_sweep(
    name: str, request: pytest.FixtureRequest
) -> None:
    cc: Any = request.getfixturevalue(name)
    guard = GeometryGuard(cc)
    rng = np.random.default_rng(7)
    for a, arm in enumerate(cc.cell.arms):
        lim = np.asarray(arm.joint_limits, dtype=float)
        q = rng.uniform(lim[:, 0], lim[:, 1], size=(int(rng.integers(1, 30)), arm.dof))
        mine = guard._ends(a, q)
        ref = _segments(arm, q, guard.capsules[a][0])
        assert np.array_equal(mine[0], ref[0]) and np.array_equal(mine[1], ref[1])


def test_the_loop_pauses_the_collector_and_restores_it() -> None:
    seen: list[bool] = []
    k = EventLoop()
    k.schedule(1.0, lambda: seen.append(gc.isenabled()))
    was = gc.isenabled()
    try:
        gc.enable()
        k.run()
        assert seen == [False] and gc.isenabled()

        def boom() -> None:
            raise RuntimeError("callback failed")

        k.schedule(1.0, boom)
        with pytest.raises(RuntimeError):
            k.run()
        assert gc.isenabled()  # restored when a callback raises
        gc.disable()
        k.schedule(1.0, lambda: seen.append(gc.isenabled()))
        k.run()
        assert not gc.isenabled()  # left as it was found
    finally:
        if was:
            gc.enable()
        else:  # pragma: no cover - the suite runs with the collector on
            gc.disable()


@pytest.mark.parametrize("name", ["cell", "scara4"])
def test_monitor_capsule_ends_are_the_rotated_axes(
    name: str, request: pytest.FixtureRequest
) -> None:
    """The monitor's capsule ends pick each shape's axis column of its pose:
    exactly the rotated local axis (a rotation times a unit vector) times the
    half-length, for batches of any shape."""
    cc: Any = request.getfixturevalue(name)
    geo = MonitorGeometry(cc)
    rng = np.random.default_rng(3)
    for a, arm in enumerate(cc.cell.arms):
        lim = np.asarray(arm.joint_limits, dtype=float)
        q = rng.uniform(lim[:, 0], lim[:, 1], size=(int(rng.integers(1, 40)), arm.dof))
        tfs = arm.shape_transforms(q)
        sl = slice(int(geo.offsets[a]), int(geo.offsets[a + 1]))
        w = np.einsum("...ij,...j->...i", tfs[..., :3, :3], geo.axis[sl]) * geo.half[sl, None]
        c = tfs[..., :3, 3]
        for got in (geo.ends(a, tfs), [x[None] for x in geo.ends(a, tfs[0])]):
            assert np.array_equal(got[0], (c - w)[: len(got[0])])
            assert np.array_equal(got[1], (c + w)[: len(got[1])])


@pytest.mark.parametrize("seed", range(6))
def test_first_touching_sample_is_the_first_sample_with_a_touching_pair(seed: int) -> None:
    """The live monitor's batch pre-test finds the first sample at which the
    per-sample pre-test (:func:`touching_pairs`) marks a pair."""
    rng = np.random.default_rng(seed)
    arms = int(rng.integers(2, 5))
    sizes = rng.integers(1, 5, size=arms)
    arm_of = np.repeat(np.arange(arms, dtype=np.int64), sizes)
    s, n = int(sizes.sum()), int(rng.integers(1, 30))
    radii = rng.uniform(0.01, 0.2, size=s)
    r2 = (radii[:, None] + radii[None, :]) ** 2
    r2[arm_of[:, None] == arm_of[None, :]] = -1.0
    rc = radii * rng.uniform(0.3, 1.0, size=s)
    c = rng.uniform(0.0, float(rng.uniform(0.3, 3.0)), size=(n, s, 3))
    axis = rng.normal(size=(n, s, 3)) * rng.uniform(0.0, 0.2, size=(n, s, 1))
    p0, p1 = c - axis, c + axis
    movers = sorted(rng.choice(arms, size=int(rng.integers(1, arms + 1)), replace=False))
    rows = np.flatnonzero(np.isin(arm_of, movers)).astype(np.int64)
    want = -1
    for k in range(n):
        out = np.zeros((arms, arms), dtype=np.bool_)
        if touching_pairs(c[k], p0[k], p1[k], rows, r2, rc, arm_of, out):
            want = k
            break
    assert first_touching_sample(c, p0, p1, rows, r2, rc, arm_of) == want


def _plain_uses(windows: ZoneWindows, rec: Any, t_end: float | None) -> list[Any]:
    """ZoneWindows.uses as array arithmetic (the plain computation)."""
    leg = rec.leg
    if leg is None or leg.kind != "task":
        return []
    p = windows.p
    sh = p.shapes[leg.mode]
    n_ex = len(sh.exclusive)
    keys = [("inside exclusive zone", p.zone_names[r]) for r, _s, _e in sh.exclusive]
    keys += [("moving in shared zone", p.zone_names[r - p.n_zones]) for r, _s, _e in sh.moves]
    s = np.array([x for _r, x, _y in (*sh.exclusive, *sh.moves)], dtype=float)
    e = np.array([y for _r, _x, y in (*sh.exclusive, *sh.moves)], dtype=float)
    t0, t1 = rec.start, rec.end if t_end is None else t_end
    if rec.moving:
        tb = rec.tau0 + (t1 - t0)
        lo, hi = np.maximum(s, rec.tau0), np.minimum(e, tb)
        idx = np.flatnonzero(hi > lo)
        return [
            (keys[i], float(t0 + lo[i] - rec.tau0), float(t0 + hi[i] - rec.tau0))
            for i in idx.tolist()
        ]
    if not t1 > t0:
        return []
    inside = np.flatnonzero((s[:n_ex] < rec.tau0) & (rec.tau0 < e[:n_ex]))
    return [(keys[i], t0, t1) for i in inside.tolist()]


def test_zone_uses_are_the_array_computation(scara4: Any, scara4_plan: Any) -> None:
    """The monitor's zone uses of every record of a run (as they are, and
    as predicted for ever) are those of the plain array arithmetic."""
    run = simulate(scara4, scara4_plan, seed=0, options=SimOptions(monitor=False))
    windows = ZoneWindows(scara4.problem)
    seen = 0
    for log in run.arm_logs:
        for rec in log.records:
            for t_end in (None, math.inf, rec.end + 1.0):
                got = windows.uses(rec, t_end)
                assert got == _plain_uses(windows, rec, t_end)
                seen += len(got)
    assert seen > 0


@pytest.mark.parametrize("seed", range(6))
def test_first_touch_is_the_plain_loop_over_poses(seed: int) -> None:
    from workcell.geometry._zone_sweep_jit import capsules_touch
    from workcell.sim.coordination.guard import _first_touch

    rng = np.random.default_rng(seed)
    n, m, sa, sb = (int(x) for x in rng.integers(1, 12, size=4))
    a0, a1 = rng.uniform(-1, 1, size=(2, n, sa, 3))
    b0, b1 = rng.uniform(-1, 1, size=(2, m, sb, 3))
    ra, rb = rng.uniform(0.0, 0.15, size=sa), rng.uniform(0.0, 0.15, size=sb)
    box = _swept_box(a0, a1, float(ra.max()) + 0.02)
    lo = np.minimum(b0.min(axis=1), b1.min(axis=1)) - rb.max()
    hi = np.maximum(b0.max(axis=1), b1.max(axis=1)) + rb.max()
    boxes = np.ascontiguousarray(np.concatenate([lo, hi], axis=1))
    # the plain loop: every pose whose box meets, in order, with its samples
    want = []
    for j in range(m):
        if (boxes[j, :3] <= box[3:]).all() and (boxes[j, 3:] >= box[:3]).all():
            hit = capsules_touch(a0, a1, ra, b0[j], b1[j], rb, 0.02)
            if hit.any():
                want.append((j, hit))
    got = []
    j = 0
    while True:
        j, hit = _first_touch(a0, a1, ra, box, b0, b1, boxes, rb, 0.02, j)
        if j < 0:
            break
        got.append((j, hit))
        j += 1
    assert [j for j, _h in got] == [j for j, _h in want]
    assert all(np.array_equal(h, w) for (_j, h), (_k, w) in zip(got, want, strict=True))


class _Piped:
    """The pipeline's part of an arm controller (S2.3), stepped by hand."""

    def __init__(self, offset: int, period: float) -> None:
        from workcell.arms.profiles import ServoDrive
        from workcell.arms.trajectory import JointTrajectory

        drives = (ServoDrive(1.0, 2.0), ServoDrive(1.0, 2.0))
        path = np.array([[0.0, 0.0], [0.5, -1.0], [2.0, 1.0]])

        class _Leg:
            trajectory = JointTrajectory.from_waypoints(drives, path, "sync")

        self.leg: Any = _Leg()
        self.period = period
        self.lookahead = offset * period
        self.now = 0.0
        self._ring = np.zeros((offset + 2, 2))
        self._chunk = np.zeros((0, 2))
        self._chunk_i = self._chunk_at = self._chunk_done = self._pipe_i = 0
        self.points_checked = 0

    def current_tau(self) -> float:
        return self.now


@pytest.mark.parametrize("offset", [1, 5, 70, 132])
def test_the_ring_filled_a_chunk_at_a_time_is_the_ring_filled_every_tick(offset: int) -> None:
    from workcell.sim.control.pipeline import flush_ring, pipeline_step, ring_points

    rng = np.random.default_rng(offset)
    fast = _Piped(offset, 1e-3)
    ring = np.zeros_like(fast._ring)  # the reference: one point written per tick
    chunk = np.zeros((0, 2))
    ci = pi = 0
    for _ in range(600):
        if rng.random() < 0.02:  # a new departure: the points are computed again
            flush_ring(fast)
            fast._chunk_i = fast._chunk_done = len(fast._chunk)
            ci = len(chunk)
        if ci >= len(chunk):
            taus = fast.now + fast.lookahead + fast.period * np.arange(64, dtype=np.float64)
            chunk = fast.leg.trajectory.sample(taus)
            ci = 0
        ring[pi % len(ring)] = chunk[ci]
        ci += 1
        pi += 1
        pipeline_step(fast)
        fast.now += 1e-3
        if rng.random() < 0.05:  # read now and then
            assert np.array_equal(ring_points(fast), ring)
    assert np.array_equal(ring_points(fast), ring)
    assert fast.points_checked == pi


def test_the_trace_writes_a_message_detail_when_it_is_read() -> None:
    from workcell.sim.events.trace import Trace

    described: list[object] = []

    def describe(payload: object) -> str:
        described.append(payload)
        return f"payload {payload}"

    tr = Trace()
    tr.add(2.0, "sleep", arm="a", detail="held")
    tr.row_described(1.0, "message", "a", "zone_request", 1, 0, 51, 0.001, describe, 7)
    tr.add(0.5, "wake", arm="b")
    assert described == []  # nothing written while the run appends
    assert (tr.count("sleep"), tr.count("message"), len(tr)) == (1, 1, 3)
    assert [e.kind for e in tr.select(("wake", "sleep"))] == ["sleep", "wake"]
    assert described == []
    tr.sort()
    assert [(e.time, e.kind) for e in tr] == [(0.5, "wake"), (1.0, "message"), (2.0, "sleep")]
    assert tr[1].detail == "payload 7" and tr[1].message == "zone_request"
    assert described == [7]  # written once
    tr.add(0.1, "fault")
    assert tr[-1].time == 0.1 and len(tr) == 4 and described == [7]
