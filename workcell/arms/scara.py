"""The SCARA arm (SEEDS.md S2): two revolute joints in the horizontal plane,
a prismatic quill and a wrist yaw, servo driven, with closed-form IK.

In the base frame the flange (tool centre point, tool pointing down) is at
``(l1 cos t1 + l2 cos(t1 + t2), l1 sin t1 + l2 sin(t1 + t2), z)`` turned by
``t1 + t2 + t4`` about the vertical. The two arm links move in a plane at
``arm_height`` above the base; the quill slides through the second link.

Examples
--------
>>> import numpy as np
>>> s = Scara("sw", base=np.eye(4))
>>> q = np.array([[0.4, 1.1, 0.1, -0.3]])
>>> right = s.ik(s.fk(q)[0], np.array([0.0, -1.0, 0.0, 0.0]))  # the other elbow
>>> bool(np.allclose(s.fk(right[None])[0], s.fk(q)[0])), bool(right[1] < 0)
(True, True)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Literal

import numpy as np

from multiarm.errors import Unreachable, ValidationError
from multiarm.types import FloatArray, JointVector, Transform
from workcell.arms._common import FLIP_X, DriveArm, rot_z, vertical_tool_yaw, wrap_near
from workcell.arms._kinematics_jit import scara_frames
from workcell.arms.base import LinkShape
from workcell.arms.profiles import ServoDrive

__all__ = ["Scara"]

Elbow = Literal["nearest", "left", "right"]

_ALONG_X = np.array(
    [[0.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0, 0, 0, 1.0]]
)
"""A quarter turn about y: a capsule's local z axis along x."""


def _at(x: float, y: float, z: float, rot: Transform | None = None) -> Transform:
    t = np.eye(4) if rot is None else rot.copy()
    t[:3, 3] = (x, y, z)
    return t


class Scara(DriveArm):
    """A 4-axis SCARA arm (module docstring).

    Parameters
    ----------
    name : str
    base : (4, 4) float
    link_lengths : (l1, l2)
        Metres.
    z_range : (low, high)
        Flange height travel above the base, metres.
    joint_limits : (4, 2), optional
        Default: t1 in [-170, 170] deg, t2 in [-150, 150] deg, the z range,
        the wrist in [-2 pi, 2 pi].
    max_velocity, max_acceleration : (4,) float
        Per joint (rad/s, m/s; rad/s^2, m/s^2).
    max_jerk : (4,) float, optional
        With jerk limits the joints move along S-curves.
    elbow : {"nearest", "left", "right"}
        Which IK branch: nearest the hint (default), or always ``t2 > 0``
        (left) / ``t2 < 0`` (right).
    radius : float
        Radius of the link capsules.
    """

    kind = "scara"
    interpolation = "sync"

    def __init__(
        self,
        name: str,
        *,
        base: Transform | None = None,
        link_lengths: tuple[float, float] = (0.45, 0.4),
        z_range: tuple[float, float] = (0.0, 0.35),
        arm_height: float | None = None,
        joint_limits: Sequence[Sequence[float]] | None = None,
        max_velocity: Sequence[float] = (3.0, 4.0, 1.0, 6.0),
        max_acceleration: Sequence[float] = (10.0, 15.0, 5.0, 30.0),
        max_jerk: Sequence[float] | None = None,
        elbow: Elbow = "nearest",
        radius: float = 0.04,
        capabilities: Iterable[str] = ("gripper",),
        tools: Iterable[str] = (),
        payload: float = 3.0,
        home: JointVector | None = None,
    ) -> None:
        self.name = name
        self.base = np.eye(4) if base is None else np.array(base, dtype=float)
        self.base_inv = np.linalg.inv(self.base)
        self.l1, self.l2 = (float(v) for v in link_lengths)
        if not (self.l1 > 0 and self.l2 > 0):
            raise ValidationError(f"scara {name!r}: link lengths must be > 0, got {link_lengths}")
        z0, z1 = (float(v) for v in z_range)
        if not z0 < z1:
            raise ValidationError(f"scara {name!r}: z_range needs low < high, got {z_range}")
        if elbow not in ("nearest", "left", "right"):
            raise ValidationError(f"scara {name!r}: elbow must be nearest, left or right")
        self.elbow: Elbow = elbow
        lim = (
            np.array(joint_limits, dtype=float)
            if joint_limits is not None
            else np.array(
                [
                    [-math.radians(170), math.radians(170)],
                    [-math.radians(150), math.radians(150)],
                    [z0, z1],
                    [-2 * math.pi, 2 * math.pi],
                ]
            )
        )
        if lim.shape != (4, 2) or not np.all(lim[:, 0] < lim[:, 1]):
            raise ValidationError(f"scara {name!r}: joint_limits must be 4 (low < high) pairs")
        self.joint_limits = lim
        self.joint_names = ("j1", "j2", "z", "wrist")
        self.joint_kinds = ("revolute", "revolute", "prismatic", "revolute")
        jerk = list(max_jerk) if max_jerk is not None else [None] * 4
        if not (len(max_velocity) == len(max_acceleration) == len(jerk) == 4):
            raise ValidationError(f"scara {name!r}: limits need one value per joint (4)")
        self.drives = tuple(
            ServoDrive(float(v), float(a), None if j is None else float(j))
            for v, a, j in zip(max_velocity, max_acceleration, jerk, strict=True)
        )
        self.capabilities = frozenset(capabilities)
        self.tools = tuple(tools)
        self.payload = float(payload)
        r = float(radius)
        self.arm_height = float(arm_height) if arm_height is not None else z1 + 0.12
        h = self.arm_height
        hand = 0.08
        quill = max(h - z0 - hand, 0.01)
        # frames: 0 base, 1 link 1 (t1), 2 link 2 (elbow, t1 + t2), 3 flange
        self.shapes = (
            LinkShape("column", "capsule", (0.08, h), 0, _at(0.0, 0.0, h / 2)),
            LinkShape("link1", "capsule", (r, self.l1), 1, _at(self.l1 / 2, 0.0, h, _ALONG_X)),
            LinkShape("link2", "capsule", (r, self.l2), 2, _at(self.l2 / 2, 0.0, h, _ALONG_X)),
            LinkShape("quill", "capsule", (0.02, quill), 3, _at(0.0, 0.0, -(hand + quill / 2))),
            LinkShape("hand", "box", (0.05, 0.05, hand), 3, _at(0.0, 0.0, -hand / 2)),
        )
        self.allowed_pairs = frozenset(
            {
                frozenset({"column", "link1"}),
                frozenset({"link1", "link2"}),
                frozenset({"link2", "quill"}),
                frozenset({"quill", "hand"}),
            }
        )
        tip = max(r, 0.02, math.sqrt(3) * 0.05 / 2 * 1.2)
        self._reach = np.array([self.l1 + self.l2 + tip, self.l2 + tip, 1.0, tip])
        self.home = np.array([0.0, math.pi / 2, z1, 0.0]) if home is None else np.array(home, float)
        if self.home.shape != (4,) or not bool(self.within_limits(self.home[None])[0]):
            raise ValidationError(
                f"scara {name!r}: home {self.home.tolist()} is outside its limits"
            )

    def frames(self, q: FloatArray) -> FloatArray:
        qq = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=float)))
        out: FloatArray = scara_frames(
            np.ascontiguousarray(self.base, dtype=float), self.l1, self.l2, qq
        )
        return out

    def _frames_numpy(self, q: FloatArray) -> FloatArray:
        """The numpy version of :meth:`frames` (the tests' reference)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        n = len(q)
        t1, t2, z, t4 = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
        f1 = rot_z(t1)
        elbow = np.repeat(np.eye(4)[None], n, axis=0)
        elbow[:, 0, 3] = self.l1
        f2 = f1 @ elbow @ rot_z(t2)
        f3 = rot_z(t1 + t2 + t4) @ FLIP_X
        f3[:, 0, 3] = self.l1 * np.cos(t1) + self.l2 * np.cos(t1 + t2)
        f3[:, 1, 3] = self.l1 * np.sin(t1) + self.l2 * np.sin(t1 + t2)
        f3[:, 2, 3] = z
        out = np.empty((n, 4, 4, 4))
        out[:, 0] = self.base
        out[:, 1] = self.base @ f1
        out[:, 2] = self.base @ f2
        out[:, 3] = self.base @ f3
        return out

    def ik(self, pose: Transform, q_hint: JointVector | None = None) -> JointVector:
        local = self.base_inv @ np.asarray(pose, dtype=float)
        phi = vertical_tool_yaw(local, self.name)
        x, y, z = (float(v) for v in local[:3, 3])
        hint = self.home if q_hint is None else np.asarray(q_hint, dtype=float)
        r2 = x * x + y * y
        c2 = (r2 - self.l1**2 - self.l2**2) / (2 * self.l1 * self.l2)
        if not -1 - 1e-12 <= c2 <= 1 + 1e-12:
            raise Unreachable(
                f"arm {self.name!r}: the point is {math.sqrt(r2):.4g} m from the base axis, "
                f"outside the reach [{abs(self.l1 - self.l2):.4g}, {self.l1 + self.l2:.4g}] m"
            )
        c2 = min(1.0, max(-1.0, c2))
        branches = {"left": math.acos(c2), "right": -math.acos(c2)}
        order = [self.elbow] if self.elbow != "nearest" else ["left", "right"]
        # plain floats: a handful of candidates, no per-candidate arrays
        lo = self.joint_limits[:, 0].tolist()
        hi = self.joint_limits[:, 1].tolist()
        h = [float(v) for v in hint]
        cands: list[list[float]] = []
        reasons: list[str] = []
        for b in order:
            t2 = branches[b]
            t1 = math.atan2(y, x) - math.atan2(
                self.l2 * math.sin(t2), self.l1 + self.l2 * math.cos(t2)
            )
            for k in (-1, 0, 1):
                a1 = wrap_near(t1, h[0]) + 2 * math.pi * k
                a4 = wrap_near(phi - a1 - t2, h[3])
                q = [a1, t2, z, a4]
                best4 = [a4 + 2 * math.pi * m for m in (-1, 0, 1)]
                best4 = [v for v in best4 if lo[3] - 1e-9 <= v <= hi[3] + 1e-9]
                if best4:
                    q[3] = min(best4, key=lambda v: abs(v - h[3]))
                bad = [j for j in range(4) if q[j] < lo[j] - 1e-9 or q[j] > hi[j] + 1e-9]
                if bad:
                    j = bad[0]
                    reasons.append(
                        f"{b} elbow needs {self.joint_names[j]} = {q[j]:.4g} outside "
                        f"[{lo[j]:.4g}, {hi[j]:.4g}]"
                    )
                    continue
                cands.append([min(max(v, lo[j]), hi[j]) for j, v in enumerate(q)])
        if not cands:
            raise Unreachable(f"arm {self.name!r}: {'; '.join(dict.fromkeys(reasons))}")
        best = min(cands, key=lambda q: sum(abs(v - w) for v, w in zip(q, h, strict=True)))
        return np.array(best, dtype=float)

    def displacement_bound(self, dq: FloatArray) -> FloatArray:
        out: FloatArray = np.abs(np.atleast_2d(dq)) @ self._reach
        return out
