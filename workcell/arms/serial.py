"""A generic serial arm from Denavit-Hartenberg parameters, with numerical IK.

Standard DH: frame ``i`` follows frame ``i-1`` by ``Rz(theta_i) Tz(d_i)
Tx(a_i) Rx(alpha_i)``; a revolute joint adds ``q_i`` to ``theta_i``, a
prismatic one to ``d_i``. The flange is the last frame. Collision shapes
are capsules from each frame's origin back to the previous one (drawn in
the later frame, where the segment does not depend on the joint angle) and a
sphere at the base.

The inverse kinematics is Levenberg-Marquardt (damped least squares with
adaptive damping) on the position and orientation (rotation vector) error
with the geometric Jacobian, started from the hint, then the home pose, then
fixed pseudo-random starts (deterministic), joint limits enforced by
clipping at every step. The loop is the compiled one of the URDF arm
(:func:`workcell.arms._urdf_jit.chain_ik`, the DH rows written as joint
origins about z) behind the shared :func:`workcell.arms._common.numerical_ik`.
Points beyond the arm's reach from its shoulder are refused at once.

Examples
--------
>>> import numpy as np
>>> arm = SerialArm.example_6dof("r1")
>>> q = np.array([0.3, -0.4, 0.6, 0.2, -0.8, 0.5])
>>> sol = arm.ik(arm.fk(q[None])[0], q + 0.1)
>>> bool(np.allclose(arm.fk(sol[None])[0], arm.fk(q[None])[0], atol=1e-8))
True
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, JointVector, Transform
from workcell.arms._common import Chain, DriveArm, numerical_ik
from workcell.arms._kinematics_jit import dh_frames
from workcell.arms.base import JointKind, LinkShape
from workcell.arms.profiles import ServoDrive

__all__ = ["SerialArm"]

IK_ITERATIONS = 100
"""Levenberg-Marquardt iterations per start."""


def _capsule_between(name: str, frame: int, p: FloatArray, r: float) -> LinkShape | None:
    """A capsule from the frame's origin to point ``p`` (in that frame)."""
    length = float(np.linalg.norm(p))
    if length < 1e-6:
        return None
    z = p / length
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    off = np.eye(4)
    off[:3, 0], off[:3, 1], off[:3, 2], off[:3, 3] = x, y, z, p / 2
    return LinkShape(name, "capsule", (r, length), frame, off)


class SerialArm(DriveArm):
    """A serial arm from standard DH parameters (module docstring).

    Parameters
    ----------
    name : str
    dh : (n, 4) float
        Rows ``(a, alpha, d, theta_offset)``.
    kinds : sequence of {"revolute", "prismatic"}
    joint_limits : (n, 2) float
    base : (4, 4) float
    max_velocity, max_acceleration : (n,) float
    max_jerk : (n,) float, optional
    radius : float
        Radius of the link capsules.
    """

    kind = "serial"
    interpolation = "sync"

    def __init__(
        self,
        name: str,
        *,
        dh: Sequence[Sequence[float]],
        kinds: Sequence[JointKind] | None = None,
        joint_limits: Sequence[Sequence[float]] | None = None,
        base: Transform | None = None,
        max_velocity: Sequence[float] | None = None,
        max_acceleration: Sequence[float] | None = None,
        max_jerk: Sequence[float] | None = None,
        radius: float = 0.05,
        capabilities: Iterable[str] = ("gripper",),
        tools: Iterable[str] = (),
        payload: float = 5.0,
        home: JointVector | None = None,
    ) -> None:
        self.name = name
        table = np.array(dh, dtype=float)
        if table.ndim != 2 or table.shape[1] != 4 or len(table) == 0:
            raise ValidationError(f"serial arm {name!r}: dh must be rows of (a, alpha, d, offset)")
        if not np.all(np.isfinite(table)):
            raise ValidationError(f"serial arm {name!r}: dh parameters must be finite")
        n = len(table)
        self.dh = table
        revolute: JointKind = "revolute"
        self.joint_kinds = tuple(kinds) if kinds is not None else (revolute,) * n
        if len(self.joint_kinds) != n or any(
            k not in ("revolute", "prismatic") for k in self.joint_kinds
        ):
            raise ValidationError(
                f"serial arm {name!r}: kinds must be {n} of 'revolute'/'prismatic'"
            )
        self.joint_names = tuple(f"j{i + 1}" for i in range(n))
        lim = (
            np.array(joint_limits, dtype=float)
            if joint_limits is not None
            else np.array([[-math.pi, math.pi]] * n)
        )
        if lim.shape != (n, 2) or not np.all(lim[:, 0] < lim[:, 1]):
            raise ValidationError(
                f"serial arm {name!r}: joint_limits must be {n} (low < high) pairs"
            )
        self.joint_limits = lim
        self.base = np.eye(4) if base is None else np.array(base, dtype=float)
        self.base_inv = np.linalg.inv(self.base)
        vel = list(max_velocity) if max_velocity is not None else [2.0] * n
        acc = list(max_acceleration) if max_acceleration is not None else [8.0] * n
        jerk = list(max_jerk) if max_jerk is not None else [None] * n
        if not (len(vel) == len(acc) == len(jerk) == n):
            raise ValidationError(f"serial arm {name!r}: limits need one value per joint ({n})")
        self.drives = tuple(
            ServoDrive(float(v), float(a), None if j is None else float(j))
            for v, a, j in zip(vel, acc, jerk, strict=True)
        )
        self.capabilities = frozenset(capabilities)
        self.tools = tuple(tools)
        self.payload = float(payload)
        r = float(radius)
        shapes = [LinkShape("base", "sphere", (r * 1.6,), 0, np.eye(4))]
        for i in range(n):
            a, alpha, d, _ = table[i]
            if self.joint_kinds[i] == "prismatic":
                continue
            # origin of frame i seen from frame i+1: Rx(-alpha) (-a, 0, -d)
            ca, sa = math.cos(alpha), math.sin(alpha)
            p = np.array([-a, -d * sa, -d * ca])
            cap = _capsule_between(f"link{i + 1}", i + 1, p, r)
            if cap is not None:
                shapes.append(cap)
        shapes.append(LinkShape("hand", "sphere", (r,), n, np.eye(4)))
        self.shapes = tuple(shapes)
        self.allowed_pairs = frozenset(
            frozenset({shapes[k].name, shapes[k + 1].name}) for k in range(len(shapes) - 1)
        )
        self.home = np.zeros(n) if home is None else np.array(home, dtype=float)
        if self.home.shape != (n,) or not bool(self.within_limits(self.home[None])[0]):
            raise ValidationError(
                f"serial arm {name!r}: home {self.home.tolist()} is outside its limits"
            )
        self._reach = self._reaches()
        # no flange pose is farther from the shoulder point (0, 0, d1) than this
        lengths = np.hypot(self.dh[:, 0], self.dh[:, 2])
        self._shoulder = (self.base @ np.array([0.0, 0.0, self.dh[0, 2], 1.0]))[:3]
        self._max_reach = abs(float(self.dh[0, 0])) + float(lengths[1:].sum()) + 1e-9
        if self.joint_kinds[0] == "prismatic" or any(
            k == "prismatic" for k in self.joint_kinds[1:]
        ):
            self._max_reach = math.inf  # prismatic travel: no simple bound

    @classmethod
    def example_6dof(cls, name: str, base: Transform | None = None, **kw: object) -> SerialArm:
        """An anthropomorphic 6-DOF arm with a spherical wrist (about 0.9 m reach)."""
        half = math.pi / 2
        dh = [
            (0.0, half, 0.40, 0.0),
            (0.45, 0.0, 0.0, half),
            (0.05, half, 0.0, 0.0),
            (0.0, -half, 0.42, 0.0),
            (0.0, half, 0.0, 0.0),
            (0.0, 0.0, 0.10, 0.0),
        ]
        lim = [
            (-math.radians(170), math.radians(170)),
            (-math.radians(120), math.radians(120)),
            (-math.radians(150), math.radians(150)),
            (-math.radians(185), math.radians(185)),
            (-math.radians(125), math.radians(125)),
            (-math.radians(350), math.radians(350)),
        ]
        defaults: dict[str, object] = {
            "max_velocity": (2.5, 2.5, 3.0, 5.0, 5.0, 7.0),
            "max_acceleration": (8.0, 8.0, 10.0, 20.0, 20.0, 30.0),
            "home": (0.0, 0.3, 0.9, 0.0, 1.2, 0.0),
            "capabilities": ("gripper",),
        }
        defaults["joint_limits"] = lim
        defaults.update(kw)
        return cls(name, dh=dh, base=base, **defaults)  # type: ignore[arg-type]

    # ------------------------------------------------------- kinematics
    def _joint_transforms(self, q: FloatArray) -> FloatArray:
        """(N, n, 4, 4): each joint's DH transform."""
        n = len(self.dh)
        a, alpha, d, off = (self.dh[:, k] for k in range(4))
        prism = np.array([k == "prismatic" for k in self.joint_kinds])
        theta = off + np.where(prism, 0.0, q)
        dd = d + np.where(prism, q, 0.0)
        ct, st = np.cos(theta), np.sin(theta)
        ca, sa = np.cos(alpha), np.sin(alpha)
        out = np.zeros((len(q), n, 4, 4))
        out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = ct, -st * ca, st * sa
        out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = st, ct * ca, -ct * sa
        out[..., 2, 1], out[..., 2, 2] = sa, ca
        out[..., 0, 3], out[..., 1, 3], out[..., 2, 3] = a * ct, a * st, dd
        out[..., 3, 3] = 1.0
        return out

    def frames(self, q: FloatArray) -> FloatArray:
        qq = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=float)))
        prism = np.fromiter((k == "prismatic" for k in self.joint_kinds), dtype=np.bool_)
        out: FloatArray = dh_frames(
            np.ascontiguousarray(self.base, dtype=float),
            np.ascontiguousarray(self.dh, dtype=float),
            prism,
            qq,
        )
        return out

    def _frames_numpy(self, q: FloatArray) -> FloatArray:
        """The numpy version of :meth:`frames` (the tests' reference)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        jt = self._joint_transforms(q)
        n = len(self.dh)
        out = np.empty((len(q), n + 1, 4, 4))
        out[:, 0] = self.base
        for i in range(n):
            out[:, i + 1] = out[:, i] @ jt[:, i]
        return out

    def _reaches(self) -> FloatArray:
        """Per joint, a bound on the distance of distal shape points from its axis,
        over the whole joint space (sum of the distal link lengths plus radii)."""
        n = len(self.dh)
        lengths = np.hypot(self.dh[:, 0], self.dh[:, 2])
        rmax = max(s.radius() for s in self.shapes)
        out = np.empty(n)
        for i in range(n):
            if self.joint_kinds[i] == "prismatic":
                out[i] = 1.0
            else:
                # joint i turns about z of frame i-1: everything from frame i on
                out[i] = float(lengths[i:].sum()) + rmax
        return out

    def displacement_bound(self, dq: FloatArray) -> FloatArray:
        out: FloatArray = np.abs(np.atleast_2d(dq)) @ self._reach
        return out

    def ik(self, pose: Transform, q_hint: JointVector | None = None) -> JointVector:
        chain = self.__dict__.get("_chain_cache")
        if chain is None:
            chain = self.__dict__["_chain_cache"] = self._chain()
        return numerical_ik(
            self, pose, q_hint, self._shoulder, self._max_reach, chain, IK_ITERATIONS
        )

    def _chain(self) -> Chain:
        """The DH table as the compiled chain of :mod:`workcell.arms._urdf_jit`:
        joint ``i``'s transform is ``motion_z(q_i) @ F_i`` with the fixed
        ``F_i = Rz(offset) Tz(d) Tx(a) Rx(alpha)`` (a turn about z, or a slide
        along z, commutes with ``Rz(offset) Tz(d)``), so each ``F_i`` is the
        next joint's origin and the last one the tool: the same product."""
        n = len(self.dh)
        fixed = np.zeros((n, 4, 4))
        for i, (a, alpha, d, off) in enumerate(self.dh.tolist()):
            ct, st, ca, sa = math.cos(off), math.sin(off), math.cos(alpha), math.sin(alpha)
            fixed[i] = [
                [ct, -st * ca, st * sa, a * ct],
                [st, ct * ca, -ct * sa, a * st],
                [0.0, sa, ca, d],
                [0.0, 0.0, 0.0, 1.0],
            ]
        origins = np.concatenate([np.eye(4)[None], fixed[:-1]])
        axes = np.tile([0.0, 0.0, 1.0], (n, 1))
        prism = np.array([k == "prismatic" for k in self.joint_kinds])
        return np.ascontiguousarray(self.base), origins, axes, prism, fixed[-1].copy()
