"""Arm models, drives and timed trajectories (workcell.arms; SEEDS.md S1.5, S1.6, S1.9, S2.11)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import Unreachable, ValidationError
from workcell.arms import (
    CartesianGantry,
    JointTrajectory,
    Scara,
    SerialArm,
    ServoDrive,
    StepperDrive,
    arm_from_dict,
)
from workcell.arms._common import pose_xyz_yaw

GANTRY = CartesianGantry("g", rails={"x": (0.0, 1.2), "y": (0.0, 1.0), "z": (0.0, 0.5)})
SCARA = Scara("s", base=pose_xyz_yaw([0.3, -0.2, 0.0, 0.7]))
SERIAL = SerialArm.example_6dof("r", base=pose_xyz_yaw([1.0, 0.5, 0.0, 1.2]))
ARMS = (GANTRY, SCARA, SERIAL)

unit = st.floats(0.0, 1.0, allow_nan=False)


def _q(arm, fr):  # type: ignore[no-untyped-def]
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return lo + (hi - lo) * np.asarray(fr)


# ----------------------------------------------------------- kinematics


@pytest.mark.parametrize("arm", ARMS, ids=lambda a: a.kind)
@settings(max_examples=40, deadline=None)
@given(fr=st.lists(unit, min_size=6, max_size=6), noise=st.floats(-0.05, 0.05))
def test_fk_ik_round_trip(arm, fr, noise) -> None:  # type: ignore[no-untyped-def]
    q = _q(arm, fr[: arm.dof])
    pose = arm.fk(q[None])[0]
    q2 = arm.ik(pose, q + noise)
    assert bool(arm.within_limits(q2[None])[0])
    back = arm.fk(q2[None])[0]
    # steppers and servos reach the pose exactly (to numerical precision)
    assert np.allclose(back[:3, 3], pose[:3, 3], atol=1e-6)
    assert np.allclose(back[:3, :3], pose[:3, :3], atol=1e-6)


def test_scara_elbow_choice_is_respected() -> None:
    q = np.array([[0.3, 1.0, 0.1, 0.2]])
    pose = SCARA.fk(q)[0]
    left = Scara("l", base=SCARA.base, elbow="left").ik(pose)
    right = Scara("r", base=SCARA.base, elbow="right").ik(pose)
    assert left[1] > 0 > right[1]
    for sol in (left, right):
        assert np.allclose(SCARA.fk(sol[None])[0], pose, atol=1e-9)
    # "nearest" follows the hint
    assert SCARA.ik(pose, right)[1] < 0 < SCARA.ik(pose, left)[1]


@pytest.mark.parametrize("arm", ARMS, ids=lambda a: a.kind)
def test_far_pose_is_unreachable_with_a_reason(arm) -> None:  # type: ignore[no-untyped-def]
    pose = np.diag([1.0, -1.0, -1.0, 1.0])
    pose[:3, 3] = [9.0, 9.0, 0.1]
    with pytest.raises(Unreachable, match=f"arm {arm.name!r}"):
        arm.ik(pose)


def test_four_axis_arms_refuse_a_tilted_tool() -> None:
    pose = GANTRY.fk(GANTRY.home[None])[0]
    tilt = pose.copy()
    tilt[:3, :3] = tilt[:3, :3] @ np.array(
        [[1, 0, 0], [0, math.cos(0.2), -math.sin(0.2)], [0, math.sin(0.2), math.cos(0.2)]]
    )
    with pytest.raises(Unreachable, match="keeps its tool vertical"):
        GANTRY.ik(tilt)


@pytest.mark.parametrize("arm", ARMS, ids=lambda a: a.kind)
def test_displacement_bound_bounds_every_shape_point(arm) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(7)
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    for _ in range(200):
        q0 = lo + (hi - lo) * rng.random(arm.dof)
        q1 = np.clip(q0 + rng.normal(0, 0.2, arm.dof), lo, hi)
        # the bound holds along the straight (monotone) joint path, sampled finely
        path = q0 + np.linspace(0, 1, 21)[:, None] * (q1 - q0)
        tf = arm.shape_transforms(path)
        bound = float(arm.displacement_bound((q1 - q0)[None])[0])
        for s, shape in enumerate(arm.shapes):
            pts = np.einsum("nij,kj->nki", tf[:, s], _surface(shape))[..., :3]
            moved = np.linalg.norm(pts - pts[0], axis=2).max()
            assert moved <= bound + 1e-9, shape.name


def _surface(shape) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Extreme points of a shape, homogeneous, in the shape's frame."""
    if shape.kind == "box":
        sx, sy, sz = (v / 2 for v in shape.size)
        pts = [(x, y, z) for x in (-sx, sx) for y in (-sy, sy) for z in (-sz, sz)]
    elif shape.kind == "sphere":
        r = shape.size[0]
        pts = [(r, 0, 0), (-r, 0, 0), (0, r, 0), (0, -r, 0), (0, 0, r), (0, 0, -r)]
    else:  # capsule (radius, length) / cylinder (radius, height): rims at both ends
        r, h = shape.size[0], shape.size[1] / 2
        pts = [(x, y, z) for z in (-h, h) for x, y in ((r, 0), (-r, 0), (0, r), (0, -r))]
        if shape.kind == "capsule":
            pts += [(0, 0, h + r), (0, 0, -h - r)]
    return np.array([(*p, 1.0) for p in pts])


# ----------------------------------------------------------- drives (S1.5)


def test_stepper_defaults_give_562_5_mm_per_s() -> None:
    d = StepperDrive()
    assert d.steps_per_turn == 400
    assert d.step_length == pytest.approx(0.0375e-3)
    assert d.top_speed == pytest.approx(0.5625)


def test_stepper_profile_choice_and_switch_over_length() -> None:
    d = StepperDrive()
    a, f0, fmax = d.accel_steps, d.low_rate, d.max_rate
    n_star = (fmax**2 - f0**2) / a
    assert d.switch_steps() == pytest.approx(n_star)
    assert d.kind_of(d.short_steps) == "constant"
    assert d.kind_of(d.short_steps + 1) == "triangle"
    assert d.kind_of(int(n_star)) == "triangle"
    assert d.kind_of(int(n_star) + 1) == "trapezoid"
    # closed forms: constant, triangle, trapezoid
    assert d.steps_duration(np.array([10.0]))[0] == pytest.approx(10 / f0)
    n = 1000.0
    assert d.steps_duration(np.array([n]))[0] == pytest.approx(
        2 * (math.sqrt(f0**2 + a * n) - f0) / a
    )
    n = 3 * n_star
    assert d.steps_duration(np.array([n]))[0] == pytest.approx(
        2 * (fmax - f0) / a + (n - n_star) / fmax
    )
    # continuous at the switch-over
    left = d.steps_duration(np.array([n_star - 1e-6]))[0]
    right = d.steps_duration(np.array([n_star + 1e-6]))[0]
    assert right - left == pytest.approx(0.0, abs=1e-6)


def test_stepper_rate_is_continuous_at_the_cruise_join() -> None:
    d = StepperDrive()
    p = d.profile(0.5)  # a trapezoid
    assert p.kind == "trapezoid"
    join = float(p.durations[0])
    v = p.velocity(np.array([join - 1e-9, join + 1e-9]))
    assert v[0] == pytest.approx(v[1], rel=1e-6)
    assert v[1] == pytest.approx(d.top_speed, rel=1e-9)


def test_exact_square_root_ramp() -> None:
    d = StepperDrive(low_rate=1.0, short_steps=0)
    a, f0 = d.accel_steps, d.low_rate
    t = d.step_times(20_000)
    k = np.arange(1, 101)
    assert np.allclose(t[:100], (np.sqrt(f0**2 + 2 * a * k) - f0) / a)
    assert np.all(np.diff(t) > 0)
    assert t[-1] == pytest.approx(d.steps_duration(np.array([20_000]))[0])


def test_accelstepper_recurrence_follows_the_exact_ramp() -> None:
    d = StepperDrive(low_rate=1.0, short_steps=0)
    exact = d.step_times(4000)
    approx = d.step_times(4000, ramp="accelstepper")
    # Austin 2005: the recurrence's step delays approach the exact ones after
    # the first few steps (the 0.676 factor corrects the first one)
    de, da = np.diff(exact)[10:1000], np.diff(approx)[10:1000]
    assert np.max(np.abs(da / de - 1)) < 0.02
    assert np.all(np.diff(approx) > 0)


def test_stop_and_homing_times() -> None:
    d = StepperDrive()
    assert d.stop_time(d.max_rate) == pytest.approx(
        (d.max_rate - d.low_rate) * d.step_length / d.stop_accel
    )
    assert d.stop_steps(d.low_rate) == 0
    assert d.homing_time(0.3) == pytest.approx(
        round(0.3 / d.step_length) / d.homing_rate + d.switch_hysteresis / d.low_rate
    )


def test_stepper_rejects_bad_parameters() -> None:
    with pytest.raises(ValidationError, match="unknown acceleration curve 'heavy'"):
        StepperDrive(curve="heavy")
    with pytest.raises(ValidationError, match="low_rate"):
        StepperDrive(low_rate=20_000.0)


def _integrate(drive: ServoDrive, dist: float) -> float:
    """Brute force: the time of a bang-bang-with-limits move by small steps."""
    p = drive.profile(dist)
    t = np.linspace(0, p.duration, 200_001)
    v = p.velocity(t)
    return float(np.trapezoid(v, t))


@pytest.mark.parametrize("dist", [0.01, 0.3, 2.0, 7.0])
@pytest.mark.parametrize("jerk", [None, 5.0, 50.0])
def test_servo_profiles_reach_the_distance_within_limits(dist: float, jerk: float | None) -> None:
    drive = ServoDrive(1.5, 3.0, jerk)
    p = drive.profile(dist)
    t = np.linspace(0, p.duration, 20_001)
    v = p.velocity(t)
    assert p.position(np.array([p.duration]))[0] == pytest.approx(dist)
    assert _integrate(drive, dist) == pytest.approx(dist, rel=1e-4)
    assert v.max() <= 1.5 + 1e-9
    acc = np.diff(v) / np.diff(t)
    assert np.abs(acc).max() <= 3.0 * (1 + 1e-3)
    if jerk is not None:
        assert np.abs(np.diff(acc) / np.diff(t)[1:]).max() <= jerk * 1.01


def test_servo_closed_forms() -> None:
    assert ServoDrive(1.0, 2.0).profile(2.0).duration == pytest.approx(2.5)  # d/v + v/a
    assert ServoDrive(1.0, 2.0).profile(0.25).duration == pytest.approx(2 * math.sqrt(0.125))
    # S-curve with a cruise: d/v + v/a + a/j
    assert ServoDrive(1.0, 2.0, 10.0).profile(2.0).duration == pytest.approx(2.7)


# ----------------------------------------------------------- trajectories (S1.9)


def test_synchronised_move_ends_together_and_axis_move_does_not() -> None:
    w = np.array([[0.1, 0.1, 0.4, 0.0], [1.0, 0.2, 0.1, 0.0]])
    sync = GANTRY.time_path(w, "sync")
    axis = GANTRY.time_path(w, "axis")
    assert sync.duration == pytest.approx(axis.duration)
    t = np.linspace(0, sync.duration, 401)
    qs, qa = sync.sample(t), axis.sample(t)
    done_s = [t[np.argmax(np.isclose(qs[:, j], qs[-1, j]))] for j in range(3)]
    done_a = [t[np.argmax(np.isclose(qa[:, j], qa[-1, j]))] for j in range(3)]
    assert max(done_s) - min(done_s) < 0.01
    assert max(done_a) - min(done_a) > 0.3  # y and z stop long before x


@pytest.mark.parametrize("arm", ARMS, ids=lambda a: a.kind)
def test_trajectory_hits_waypoints_and_is_monotone_between_knots(arm) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(3)
    w = _q(arm, rng.random((5, arm.dof)) * 0.8 + 0.1)
    tr = arm.time_path(w).append_dwell(0.5)
    knots = tr.knot_times
    assert np.allclose(tr.sample(knots[:-1]), tr.waypoints()[:-1], atol=1e-12)
    # servos hit the waypoints; steppers come within half a step of them
    tol = np.array([getattr(d, "step_length", 2e-9) / 2 + 1e-12 for d in arm.drives])
    assert np.all(np.abs(tr.waypoints()[:-1] - w) <= tol)
    for a, b in itertools.pairwise(knots):
        q = tr.sample(np.linspace(a, b, 50))
        d = np.diff(q, axis=0)
        assert np.all((d >= -1e-12) | (d <= 1e-12))
        assert np.all(np.all(d >= -1e-12, axis=0) | np.all(d <= 1e-12, axis=0))
    assert tr.motion_intervals()[-1, 1] == pytest.approx(knots[-2])


def test_move_times_is_the_trajectory_duration() -> None:
    rng = np.random.default_rng(5)
    for arm in ARMS:
        q0 = _q(arm, rng.random((20, arm.dof)))
        q1 = _q(arm, rng.random((20, arm.dof)))
        times = arm.move_times(q0, q1)
        for i in range(20):
            assert times[i] == pytest.approx(arm.move(q0[i], q1[i], "axis").duration)
            assert times[i] == pytest.approx(arm.move_time(q0[i], q1[i]))


def test_concatenate_refuses_a_jump() -> None:
    a = JointTrajectory.dwell(np.zeros(2), 1.0)
    b = JointTrajectory.dwell(np.ones(2), 1.0)
    with pytest.raises(ValidationError, match="part 1 starts at"):
        JointTrajectory.concatenate([a, b])


# ----------------------------------------------------------- arm specs


def test_arm_from_dict_builds_each_type() -> None:
    g = arm_from_dict(
        "g",
        {
            "type": "gantry",
            "rails": {"x": [0, 1], "y": [0, 1], "z": [0, 0.5]},
            "stepper": {"curve": "loaded"},
        },
        "c.toml: arms.g",
    )
    assert g.kind == "gantry" and g.drives[0].curve == "loaded"  # type: ignore[attr-defined]
    s = arm_from_dict("s", {"type": "scara", "elbow": "left", "base": [1, 2, 0, 0.5]}, "w")
    assert s.kind == "scara" and np.allclose(s.base[:3, 3], [1, 2, 0])
    r = arm_from_dict("r", {"type": "serial", "example": "6dof"}, "w")
    assert r.dof == 6


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (
            {"type": "robot"},
            r"c\.toml: arms\.a\.type: expected one of gantry, scara, serial, urdf, got 'robot'",
        ),
        (
            {"type": "scara", "link_lengths": "abc"},
            r"c\.toml: arms\.a\.link_lengths: expected 2 numbers, got 'abc'",
        ),
        ({"type": "scara", "lenghts": 1}, r"c\.toml: arms\.a: unknown field 'lenghts'"),
        (
            {"type": "scara", "elbow": "up"},
            r"c\.toml: arms\.a\.elbow: expected one of nearest, left, right",
        ),
        ({"type": "gantry"}, r"c\.toml: arms\.a\.rails: expected a table"),
        (
            {"type": "gantry", "rails": {"x": [1, 0], "y": [0, 1], "z": [0, 1]}},
            r"arms\.a\.rails\.x: needs low < high",
        ),
        (
            {
                "type": "gantry",
                "rails": {"x": [0, 1], "y": [0, 1], "z": [0, 1]},
                "stepper": {"max_rate": -3},
            },
            r"arms\.a\.stepper\.max_rate: must be > 0",
        ),
        ({"type": "serial"}, r"arms\.a\.dh: expected rows of \[a, alpha, d, offset\]"),
        ({"type": "serial", "dh": [[0, 0, 0.1]]}, r"arms\.a\.dh\[0\]\.row: expected 4 numbers"),
        ({"type": "serial", "example": "7dof"}, r"arms\.a\.example: expected '6dof'"),
        (
            {"type": "scara", "capabilities": "gripper"},
            r"arms\.a\.capabilities: expected a list of names",
        ),
        ({"type": "scara", "base": [0, 0, 0]}, r"arms\.a\.base: expected 4 numbers"),
        ({"type": "scara", "payload": True}, r"arms\.a\.payload: expected a number, got True"),
        (
            {"type": "scara", "home": [0, 9, 0, 0]},
            r"c\.toml: arms\.a: .*home .* outside its limits",
        ),
    ],
)
def test_arm_from_dict_errors_name_the_field(data, message) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValidationError, match=message):
        arm_from_dict("a", data, "c.toml: arms.a")


# ------------------------------------------------- compiled kinematics


@pytest.mark.parametrize(
    "arm",
    (
        *ARMS,
        CartesianGantry(
            "g3", rails={"x": (0.0, 1.0), "y": (0.0, 1.0), "z": (0.0, 0.4)}, wrist=False
        ),
    ),
    ids=lambda a: f"{a.kind}-{a.dof}",
)
def test_compiled_frames_equal_the_numpy_frames(arm) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(3)
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    q = rng.uniform(lo - 0.5, hi + 0.5, (300, arm.dof))  # off limits too: FK does not care
    np.testing.assert_allclose(arm.frames(q), arm._frames_numpy(q), rtol=0, atol=1e-12)
    np.testing.assert_allclose(arm.frames(q[7]), arm._frames_numpy(q[7]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("arm", ARMS, ids=lambda a: a.kind)
def test_shape_transforms_equal_the_matmul_reference(arm) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(4)
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    q = rng.uniform(lo, hi, (200, arm.dof))
    fr = arm._frames_numpy(q)
    idx = [s.frame for s in arm.shapes]
    want = np.matmul(fr[:, idx], np.stack([s.offset for s in arm.shapes]))
    np.testing.assert_allclose(arm.shape_transforms(q), want, rtol=0, atol=1e-12)


@pytest.mark.parametrize("arm", ARMS, ids=lambda a: a.kind)
def test_compiled_sampling_equals_the_numpy_sampling(arm) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(5)
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    w = rng.uniform(lo, hi, (5, arm.dof))
    w[2] = w[1]  # a repeated waypoint
    for interpolation in ("sync", "axis"):
        traj = JointTrajectory.from_waypoints(arm.drives, w, interpolation)
        t = np.concatenate(
            [rng.uniform(-1.0, traj.duration + 1.0, 400), traj.knot_times, [0.0, traj.duration]]
        )
        np.testing.assert_allclose(traj.sample(t), traj._sample_numpy(t), rtol=0, atol=1e-12)
