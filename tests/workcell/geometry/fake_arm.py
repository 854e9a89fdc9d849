"""A tiny planar arm and a joint trajectory for the geometry tests.

``PlanarArm`` implements :class:`workcell.arms.base.Arm` with two revolute
joints about vertical axes (a SCARA without the lift): link 1 of length
``l1`` from the base, link 2 of length ``l2``, both capsules of radius ``r``
at height ``z``. ``ProfileTrajectory`` is the trajectory contract's duck
type: joint-space knots joined by a smoothstep profile (every joint moves
monotonically between consecutive knots), with dwells where two knots are
equal.
"""

from __future__ import annotations

import math

import numpy as np

from multiarm.errors import Unreachable
from multiarm.types import FloatArray, JointVector, Transform
from workcell.arms.base import Arm, LinkShape


def _rz(a: FloatArray) -> FloatArray:
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((*np.shape(a), 4, 4))
    out[..., 0, 0] = c
    out[..., 0, 1] = -s
    out[..., 1, 0] = s
    out[..., 1, 1] = c
    out[..., 2, 2] = 1.0
    out[..., 3, 3] = 1.0
    return out


def _tx(x: float) -> FloatArray:
    t = np.eye(4)
    t[0, 3] = x
    return t


_Z_TO_X = np.array([[0.0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]])


class PlanarArm(Arm):
    """Two revolute joints about z; capsule links of radius ``r`` at height ``z``."""

    def __init__(
        self,
        name: str = "p",
        base_xy: tuple[float, float] = (0.0, 0.0),
        l1: float = 0.4,
        l2: float = 0.3,
        r: float = 0.03,
        z: float = 0.1,
        limits: tuple[tuple[float, float], ...] = ((-3.0, 3.0), (-2.8, 2.8)),
        mixed: bool = False,
    ) -> None:
        self.name = name
        self.kind = "scara"
        base = np.eye(4)
        base[:3, 3] = (base_xy[0], base_xy[1], z)
        self.base = base
        self.l1, self.l2, self.r = l1, l2, r
        self.joint_names = ("j1", "j2")
        self.joint_kinds = ("revolute", "revolute")
        self.joint_limits = np.array(limits, dtype=float)
        self.capabilities = frozenset()
        self.tools = ()
        self.payload = 1.0
        self.shapes = (
            LinkShape("link1", "capsule", (r, l1), 1, _tx(l1 / 2) @ _Z_TO_X),
            LinkShape("link2", "capsule", (r, l2), 2, _tx(l2 / 2) @ _Z_TO_X),
        )
        self.allowed_pairs = frozenset({frozenset(("link1", "link2"))})
        self._reach = np.array([l1 + l2 + r, l2 + r])
        if mixed:  # a box, a cylinder and a sphere instead of two capsules
            self.shapes = (
                LinkShape("link1", "box", (l1, 2 * r, 2 * r), 1, _tx(l1 / 2)),
                LinkShape("link2", "cylinder", (r, l2), 2, _tx(l2 / 2) @ _Z_TO_X),
                LinkShape("grip", "sphere", (2 * r,), 2, _tx(l2)),
            )
            self.allowed_pairs = frozenset(
                {frozenset(("link1", "link2")), frozenset(("link2", "grip"))}
            )
            corner = float(np.hypot(l1, r * np.sqrt(2)))
            self._reach = np.array([max(l1 + l2 + 2 * r, corner), l2 + 2 * r])
        self.home = np.zeros(2)

    def frames(self, q: FloatArray) -> FloatArray:
        q = np.atleast_2d(np.asarray(q, dtype=float))
        f1 = self.base @ _rz(q[:, 0])
        f2 = f1 @ _tx(self.l1) @ _rz(q[:, 1])
        f3 = f2 @ _tx(self.l2)
        base = np.broadcast_to(self.base, f1.shape)
        return np.stack([base, f1, f2, f3], axis=1)

    def ik(self, pose: Transform, q_hint: JointVector | None = None) -> JointVector:
        x, y = pose[0, 3] - self.base[0, 3], pose[1, 3] - self.base[1, 3]
        c2 = (x * x + y * y - self.l1**2 - self.l2**2) / (2 * self.l1 * self.l2)
        if abs(c2) > 1:
            raise Unreachable(f"arm {self.name!r}: pose out of reach")
        q2 = math.acos(c2)
        q1 = math.atan2(y, x) - math.atan2(self.l2 * math.sin(q2), self.l1 + self.l2 * c2)
        return np.array([q1, q2])

    def displacement_bound(self, dq: FloatArray) -> FloatArray:
        out: FloatArray = np.abs(np.atleast_2d(dq)) @ self._reach
        return out


class ProfileTrajectory:
    """Joint knots ``q`` (K, dof) reached at ``times`` (K,), smoothstep in between."""

    def __init__(self, q: FloatArray, times: FloatArray) -> None:
        self.q = np.asarray(q, dtype=float)
        self.knot_times = np.asarray(times, dtype=float)
        self.duration = float(self.knot_times[-1] - self.knot_times[0])
        assert self.knot_times[0] == 0.0

    def sample(self, t: FloatArray) -> FloatArray:
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        k = np.clip(np.searchsorted(self.knot_times, t, side="right") - 1, 0, len(self.q) - 2)
        t0, t1 = self.knot_times[k], self.knot_times[k + 1]
        u = np.where(t1 > t0, (t - t0) / np.where(t1 > t0, t1 - t0, 1.0), 1.0)
        s = u * u * (3 - 2 * u)
        out: FloatArray = self.q[k] + s[:, None] * (self.q[k + 1] - self.q[k])
        return out

    def motion_intervals(self) -> FloatArray:
        moving = np.any(self.q[1:] != self.q[:-1], axis=1)
        out: list[list[float]] = []
        for i in np.flatnonzero(moving):
            a, b = float(self.knot_times[i]), float(self.knot_times[i + 1])
            if out and out[-1][1] == a:
                out[-1][1] = b
            else:
                out.append([a, b])
        return np.array(out, dtype=float).reshape(-1, 2)
