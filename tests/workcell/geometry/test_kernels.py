"""Compiled geometry kernels against plain references: segment end points,
the bounding-sphere skips of the capsule test, and the single-pose check."""

from __future__ import annotations

import numpy as np

from workcell.arms import CartesianGantry, Scara, SerialArm
from workcell.arms._common import pose_xyz_yaw
from workcell.geometry._zone_sweep_jit import _segment_distance, capsules_touch, pose_near
from workcell.geometry.planner import DetourPlanner, ObstacleSet
from workcell.geometry.zone_sweep import (
    _segments,
    _segments_numpy,
    _shape_capsules,
)

ARMS = (
    CartesianGantry("g", rails={"x": (0.0, 1.2), "y": (0.0, 1.0), "z": (0.0, 0.5)}),
    Scara("s", base=pose_xyz_yaw([0.3, -0.2, 0.0, 0.7])),
    SerialArm.example_6dof("r", base=pose_xyz_yaw([1.0, 0.5, 0.0, 1.2])),
)


def test_segment_points_equal_the_numpy_reference() -> None:
    rng = np.random.default_rng(0)
    for arm in ARMS:
        lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
        q = rng.uniform(lo, hi, (250, arm.dof))
        local, _ = _shape_capsules(arm.shapes)
        got, want = _segments(arm, q, local), _segments_numpy(arm, q, local)
        for g, w in zip(got, want, strict=True):
            np.testing.assert_allclose(g, w, rtol=0, atol=1e-12)


def _all_pairs(
    a0: np.ndarray,
    a1: np.ndarray,
    ra: np.ndarray,
    b0: np.ndarray,
    b1: np.ndarray,
    rb: np.ndarray,
    pad: float,
) -> np.ndarray:
    """Every pair's segment distance, no skipping."""
    out = np.zeros(len(a0), dtype=bool)
    for i in range(len(a0)):
        for s in range(a0.shape[1]):
            for k in range(len(b0)):
                d = _segment_distance(a0[i, s], a1[i, s], b0[k], b1[k], 1e-18)
                out[i] |= d <= ra[s] + rb[k] + pad
    return out


def test_capsule_skips_never_change_an_answer() -> None:
    """Capsules placed at distances within 1e-12 of their reach on either side:
    the bounding-sphere skips must leave every answer as the all-pairs loop's."""
    rng = np.random.default_rng(1)
    b0 = rng.uniform(-0.5, 0.5, (4, 3))
    b1 = b0 + rng.normal(scale=0.2, size=b0.shape)
    rb = rng.uniform(0.01, 0.05, 4)
    ra = np.array([0.02, 0.04])
    n = 600
    a0 = np.empty((n, 2, 3))
    a1 = np.empty((n, 2, 3))
    for i in range(n):
        for s in range(2):
            # a short segment at a random direction, shifted to a distance
            # of (reach + eps) from capsule k's nearest point
            k = int(rng.integers(0, 4))
            u = rng.uniform()
            base = b0[k] + u * (b1[k] - b0[k])
            v = rng.normal(size=3)
            v /= np.linalg.norm(v)
            eps = rng.choice([-1e-12, 0.0, 1e-12, 1e-3, -1e-3, 0.5])
            start = base + v * (ra[s] + rb[k] + eps)
            a0[i, s] = start
            a1[i, s] = start + v * rng.uniform(0.0, 0.3)  # pointing away
    want = _all_pairs(a0, a1, ra, b0, b1, rb, 0.0)
    got = capsules_touch(a0, a1, ra, b0, b1, rb, 0.0)
    assert want.any() and not want.all()
    np.testing.assert_array_equal(got, want)


def test_single_pose_check_equals_the_batched_check() -> None:
    rng = np.random.default_rng(2)
    mover = Scara("a")
    other = Scara("b", base=pose_xyz_yaw([0.6, 0.0, 0.0, 0.0]))
    obs = ObstacleSet.from_arm(other, other.home, 0.005)
    ctx = DetourPlanner(mover, obs, resolution=0.005, clearance=0.005)
    lo, hi = mover.joint_limits[:, 0], mover.joint_limits[:, 1]
    q = rng.uniform(lo, hi, (300, 4))
    pts = _segments(mover, q, ctx._local)
    batched = capsules_touch(pts[0], pts[1], ctx._rad, ctx._ob0, ctx._ob1, ctx._orad, 0.0)
    single = [
        pose_near(
            mover.frames(q[i]), ctx._idx, ctx._hw, ctx._rad, ctx._ob0, ctx._ob1, ctx._orad, 0.0
        )
        for i in range(len(q))
    ]
    assert batched.any() and not batched.all()
    np.testing.assert_array_equal(single, batched)
    # and is_valid agrees with the batched first-hit search pose by pose
    valid = [ctx.is_valid(row) for row in q]
    assert valid == [ctx.first_invalid(row[None]) < 0 for row in q]
    assert not all(valid)
