"""Small vectorised transform helpers shared by the arm models."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

from multiarm.errors import Unreachable, ValidationError
from multiarm.types import BoolArray, FloatArray, JointVector, Transform
from workcell.arms._urdf_jit import chain_ik
from workcell.arms.base import Arm
from workcell.arms.profiles import Drive
from workcell.arms.trajectory import Interpolation, JointTrajectory, move_segment

ORIENT_TOL = 1e-6
"""Largest angle (radians) by which a 4-DOF arm's tool axis may differ from vertical."""

FLIP_X: Transform = np.diag([1.0, -1.0, -1.0, 1.0])
"""A half turn about x: the flange of a gantry or SCARA points its tool (z) down."""

IK_TOL = 1e-9
"""Numerical IK convergence: position error (metres) and orientation error (radians)."""

IK_RESTARTS = 16
"""Pseudo-random starts (fixed seed) tried after the hint and the home pose."""

IK_LENGTH = 0.3
"""Metres per radian weighing the orientation error against the position error."""

IK_WEIGHTS: FloatArray = np.array([1.0, 1.0, 1.0, IK_LENGTH, IK_LENGTH, IK_LENGTH])
"""Weights of the (position, rotation vector) error of the numerical IK."""

Chain = tuple[FloatArray, FloatArray, FloatArray, BoolArray, FloatArray]
"""A serial chain for :func:`workcell.arms._urdf_jit.chain_ik`: the base
(4, 4), the joint origins (n, 4, 4), the unit joint axes (n, 3), which joints
are prismatic (n,) and the tool (4, 4)."""


def rot_z(theta: FloatArray) -> FloatArray:
    """(N, 4, 4) rotations about z by ``theta`` (N,)."""
    th = np.asarray(theta, dtype=float).reshape(-1)
    c, s = np.cos(th), np.sin(th)
    out = np.zeros((len(th), 4, 4))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = c, -s, s, c
    out[:, 2, 2] = out[:, 3, 3] = 1.0
    return out


def translation(p: FloatArray) -> FloatArray:
    """(N, 4, 4) translations by ``p`` (N, 3)."""
    p = np.asarray(p, dtype=float).reshape(-1, 3)
    out = np.repeat(np.eye(4)[None], len(p), axis=0)
    out[:, :3, 3] = p
    return out


def pose_xyz_yaw(v: Sequence[float], where: str = "base") -> Transform:
    """A (4, 4) pose from ``(x, y, z, yaw)`` (yaw about z, radians)."""
    if len(v) != 4:
        raise ValidationError(f"{where}: expected [x, y, z, yaw], got {list(v)!r}")
    t: Transform = rot_z(np.array([float(v[3])]))[0]
    t[:3, 3] = [float(v[0]), float(v[1]), float(v[2])]
    return t


def wrap_near(angle: float, ref: float) -> float:
    """``angle`` plus a multiple of 2 pi, as near ``ref`` as possible."""
    return angle + 2 * math.pi * round((ref - angle) / (2 * math.pi))


def vertical_tool_yaw(local: Transform, arm: str) -> float:
    """Yaw of a tool-down flange pose (in the arm's base frame), or Unreachable."""
    z = local[:3, 2]
    tilt = math.acos(max(-1.0, min(1.0, -float(z[2]))))
    if tilt > ORIENT_TOL:
        raise Unreachable(
            f"arm {arm!r} keeps its tool vertical (pointing down); the pose tilts it by "
            f"{math.degrees(tilt):.3g} degrees"
        )
    return math.atan2(float(local[1, 0]), float(local[0, 0]))


@functools.lru_cache(maxsize=64)
def _random_starts(limits: bytes, n: int) -> FloatArray:
    lim = np.frombuffer(limits, dtype=float).reshape(n, 2)
    lo, hi = lim[:, 0], lim[:, 1]
    rng = np.random.default_rng(12345)
    out: FloatArray = lo + (hi - lo) * rng.random((IK_RESTARTS, n))
    out.setflags(write=False)
    return out


def numerical_ik(
    arm: Arm,
    pose: Transform,
    q_hint: JointVector | None,
    shoulder: FloatArray,
    max_reach: float,
    chain: Chain,
    iterations: int,
) -> JointVector:
    """The numerical IK of a serial chain (the DH serial and the URDF arm).

    Checks the pose, rejects a point farther than ``max_reach`` from
    ``shoulder`` (the chain cannot reach it), then runs the compiled damped
    least squares loop (:func:`workcell.arms._urdf_jit.chain_ik`, at most
    ``iterations`` per start) from the hint (the branch choice), the home
    joints and :data:`IK_RESTARTS` fixed pseudo-random starts (seed 12345,
    drawn once per joint limits), in that order; the first converged start
    wins.

    Raises
    ------
    ValidationError
        When ``pose`` is not a finite (4, 4) transform, or the hint not
        ``dof`` finite joint values.
    Unreachable
        When no start converges.
    """
    target = np.asarray(pose, dtype=float)
    if target.shape != (4, 4) or not np.isfinite(target).all():
        raise ValidationError(f"arm {arm.name!r}: a pose must be a finite (4, 4) transform")
    dist = math.dist(target[:3, 3].tolist(), shoulder.tolist())
    if dist > max_reach:
        raise Unreachable(
            f"arm {arm.name!r}: the point is {dist:.4g} m from the shoulder, beyond the "
            f"reach {max_reach:.4g} m"
        )
    lim = np.ascontiguousarray(arm.joint_limits, dtype=float)
    n = lim.shape[0]
    try:
        hint = np.asarray(arm.home if q_hint is None else q_hint, dtype=float)
    except (TypeError, ValueError):
        hint = np.full(0, math.nan)
    if hint.shape != (n,) or not np.isfinite(hint).all():
        raise ValidationError(
            f"arm {arm.name!r}: the IK hint must be {n} finite joint values, got {q_hint!r}"
        )
    starts = np.empty((IK_RESTARTS + 2, n))
    starts[0] = hint
    starts[1] = arm.home
    starts[2:] = _random_starts(lim.tobytes(), n)
    base, origins, axes, prismatic, tool = chain
    q, err, ok = chain_ik(
        base,
        origins,
        axes,
        prismatic,
        tool,
        np.ascontiguousarray(lim[:, 0]),
        np.ascontiguousarray(lim[:, 1]),
        np.ascontiguousarray(target),
        starts,
        IK_WEIGHTS,
        IK_TOL,
        iterations,
    )
    if not ok:
        raise Unreachable(
            f"arm {arm.name!r}: no joint vector within the limits reaches the pose "
            f"(best error {err:.3g} after {len(starts)} starts)"
        )
    out: FloatArray = np.clip(q, lim[:, 0], lim[:, 1])
    return out


class DriveArm(Arm):
    """An arm whose joints each have a :class:`~workcell.arms.profiles.Drive`."""

    drives: tuple[Drive, ...]
    interpolation: Interpolation = "sync"

    def move_time(
        self, q0: JointVector, q1: JointVector, interpolation: Interpolation | None = None
    ) -> float:
        """Exact duration of one rest-to-rest move from ``q0`` to ``q1`` (seconds).

        The arm's natural interpolation by default (per axis for gantries,
        synchronised otherwise); both take the slowest joint's own time.
        """
        del interpolation  # both interpolations take the slowest joint's own time
        return float(self.move_times(np.asarray(q0, dtype=float), np.asarray(q1, dtype=float))[0])

    def move_times(self, q0: FloatArray, q1: FloatArray) -> FloatArray:
        """(N,) durations of the moves ``q0[i] -> q1[i]`` ((N, dof) each), vectorised."""
        dq = np.abs(np.atleast_2d(q1) - np.atleast_2d(q0))
        cols = [d.durations(dq[:, j]) for j, d in enumerate(self.drives)]
        out: FloatArray = np.max(np.stack(cols, axis=1), axis=1)
        return out

    def time_path(
        self,
        waypoints: FloatArray,
        interpolation: Interpolation | None = None,
        speed: float = 1.0,
    ) -> JointTrajectory:
        """Rest-to-rest moves through joint ``waypoints`` (K, dof), timed with the drives."""
        return JointTrajectory.from_waypoints(
            self.drives, waypoints, interpolation or self.interpolation, speed
        )

    def move(
        self, q0: JointVector, q1: JointVector, interpolation: Interpolation, speed: float = 1.0
    ) -> JointTrajectory:
        """One move (a zero-length dwell when nothing moves)."""
        seg = move_segment(self.drives, q0, q1, interpolation, speed)
        if seg is None:
            return JointTrajectory.dwell(q0, 0.0)
        return JointTrajectory.build([seg])

    def check_limits(self, q: JointVector, what: str) -> JointVector:
        """``q`` if within the joint limits, else Unreachable naming the joint."""
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        bad = np.flatnonzero((q < lo - 1e-9) | (q > hi + 1e-9))
        if len(bad):
            j = int(bad[0])
            raise Unreachable(
                f"arm {self.name!r}: {what} needs joint {self.joint_names[j]!r} = {q[j]:.6g}, "
                f"outside its limits [{lo[j]:.6g}, {hi[j]:.6g}]"
            )
        return np.clip(q, lo, hi)


def time_path(
    arm: Arm, waypoints: FloatArray, interpolation: Interpolation | None = None, speed: float = 1.0
) -> JointTrajectory:
    """Rest-to-rest moves of ``arm`` through joint ``waypoints`` (K, dof).

    Parameters
    ----------
    arm : Arm
        An arm with drives (every built-in arm).
    waypoints : (K, dof) float
    interpolation : {"sync", "axis"}, optional
        Synchronised joints, or each joint on its own (S1.9); default: the
        arm's natural one.
    speed : float
        Fraction (0, 1] of the drives' top speeds.

    Raises
    ------
    ValidationError
        For an arm without drives or bad waypoints.
    """
    if not isinstance(arm, DriveArm):
        raise ValidationError(f"arm {arm.name!r} has no drives to time a path with")
    return arm.time_path(waypoints, interpolation, speed)
