"""Small vectorised transform helpers shared by the arm models."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from multiarm.errors import Unreachable, ValidationError
from multiarm.types import FloatArray, JointVector, Transform
from workcell.arms.base import Arm
from workcell.arms.profiles import Drive
from workcell.arms.trajectory import Interpolation, JointTrajectory, move_segment

ORIENT_TOL = 1e-6
"""Largest angle (radians) by which a 4-DOF arm's tool axis may differ from vertical."""

FLIP_X: Transform = np.diag([1.0, -1.0, -1.0, 1.0])
"""A half turn about x: the flange of a gantry or SCARA points its tool (z) down."""


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
