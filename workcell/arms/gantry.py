"""The Cartesian gantry arm (SUPERSIGMA-like, SEEDS.md S1).

Three prismatic axes x, y, z and an optional wrist yaw, each driven by a
stepper axis with the S1.5 controller. In the arm's base frame the flange is
at ``(x, y, z)`` pointing its tool down, turned by the yaw about the vertical.
A bridge beam spans the y rail at the gantry's height and rides the x rail; a
carriage rides the bridge; a vertical column carries the hand. Two gantries
on one x rail therefore collide through their bridges, as in the real cell.

Moves are independent per axis by default (S1.9: a Cartesian structure lets
most moves be split per axis with no coordination).

Examples
--------
>>> import numpy as np
>>> g = CartesianGantry("left", rails={"x": (0.0, 1.2), "y": (0.0, 1.2), "z": (0.0, 0.6)})
>>> q = g.ik(g.fk(np.array([[0.3, 0.4, 0.2, 0.5]]))[0])
>>> np.round(q, 9).tolist()
[0.3, 0.4, 0.2, 0.5]
>>> round(g.drives[0].top_speed, 4)
0.5625
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np

from multiarm.errors import Unreachable, ValidationError
from multiarm.types import FloatArray, JointVector, Transform
from workcell.arms._common import FLIP_X, DriveArm, rot_z, vertical_tool_yaw, wrap_near
from workcell.arms._kinematics_jit import gantry_frames
from workcell.arms.base import JointKind, LinkShape
from workcell.arms.profiles import StepperDrive

__all__ = ["CartesianGantry"]


def _box(name: str, size: tuple[float, float, float], frame: int, at: Iterable[float]) -> LinkShape:
    off = np.eye(4)
    off[:3, 3] = list(at)
    return LinkShape(name, "box", size, frame, off)


class CartesianGantry(DriveArm):
    """A Cartesian gantry: x, y, z stepper axes (+ wrist yaw).

    Parameters
    ----------
    name : str
    rails : mapping {"x", "y", "z"} -> (low, high)
        Axis travel in metres (flange position in the base frame).
    base : (4, 4) float
        Pose of the base frame in the cell.
    wrist : bool
        With a wrist yaw joint (limits ``yaw_limits``).
    height : float
        Height of the bridge above the base, metres (above the z rail).
    stepper : StepperDrive
        The axis drive (S1.5 defaults); the wrist uses a servo-like stepper
        with the same rates on radians (0.9 degree per step).
    capabilities, tools, payload
        See :class:`~workcell.arms.base.Arm`.
    hand : (3,) float
        Size of the hand box (x, y, z), metres.
    """

    kind = "gantry"
    interpolation = "axis"

    def __init__(
        self,
        name: str,
        *,
        rails: Mapping[str, tuple[float, float]],
        base: Transform | None = None,
        wrist: bool = True,
        yaw_limits: tuple[float, float] = (-math.pi, math.pi),
        height: float | None = None,
        stepper: StepperDrive | None = None,
        capabilities: Iterable[str] = ("gripper",),
        tools: Iterable[str] = (),
        payload: float = 2.0,
        hand: tuple[float, float, float] = (0.06, 0.06, 0.1),
        home: JointVector | None = None,
    ) -> None:
        self.name = name
        self.base = np.eye(4) if base is None else np.array(base, dtype=float)
        self.base_inv = np.linalg.inv(self.base)
        lim = []
        for axis in ("x", "y", "z"):
            if axis not in rails:
                raise ValidationError(f"gantry {name!r}: missing rail {axis!r}")
            lo, hi = (float(v) for v in rails[axis])
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ValidationError(
                    f"gantry {name!r}: rail {axis} needs low < high, got {rails[axis]}"
                )
            lim.append((lo, hi))
        self.wrist = bool(wrist)
        if self.wrist:
            lim.append((float(yaw_limits[0]), float(yaw_limits[1])))
        self.joint_limits = np.array(lim)
        self.joint_names = ("x", "y", "z", "yaw")[: len(lim)]
        kinds: tuple[JointKind, ...] = ("prismatic", "prismatic", "prismatic")
        self.joint_kinds = kinds + (("revolute",) if self.wrist else ())
        self.capabilities = frozenset(capabilities)
        self.tools = tuple(tools)
        self.payload = float(payload)
        step = stepper or StepperDrive()
        wrist_drive = StepperDrive(
            step_length=2 * math.pi / step.steps_per_turn,
            max_rate=step.max_rate / 3,
            low_rate=step.low_rate,
            curves={"light": 30.0, "loaded": 15.0},
            stop_accel=60.0,
        )
        self.drives = (step, step, step, *((wrist_drive,) if self.wrist else ()))
        (x0, _x1), (y0, y1), (z0, z1) = lim[:3]
        self.height = float(height) if height is not None else z1 + 0.15
        hx, hy, hz = (float(v) for v in hand)
        self.hand_size = (hx, hy, hz)
        ylen = y1 - y0 + 0.2
        col = max(self.height - z0 - hz, 0.01)
        # frames: 0 base, 1 bridge (x), 2 carriage (x, y), 3 flange (x, y, z, yaw)
        self.shapes = (
            _box("bridge", (0.08, ylen, 0.08), 1, (0.0, (y0 + y1) / 2, self.height)),
            _box("carriage", (0.12, 0.12, 0.1), 2, (0.0, 0.0, self.height)),
            # a fixed-length tube sliding through the carriage: it reaches the
            # bridge with the hand at its lowest and sticks up above it higher
            LinkShape("column", "capsule", (0.03, col), 3, _shift(0.0, 0.0, -(hz + col / 2))),
            _box("hand", (hx, hy, hz), 3, (0.0, 0.0, -hz / 2)),
        )
        self.allowed_pairs = frozenset(
            {
                frozenset({"bridge", "carriage"}),
                frozenset({"carriage", "column"}),
                frozenset({"bridge", "column"}),
                frozenset({"column", "hand"}),
            }
        )
        self._reach_yaw = math.hypot(hx, hy) / 2
        default_home = [x0, (y0 + y1) / 2, z1] + ([0.0] if self.wrist else [])
        self.home = np.array(default_home if home is None else home, dtype=float)
        if self.home.shape != (self.dof,) or not bool(self.within_limits(self.home[None])[0]):
            raise ValidationError(
                f"gantry {name!r}: home {self.home.tolist()} is outside its limits"
            )

    def frames(self, q: FloatArray) -> FloatArray:
        qq = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=float)))
        if qq.shape[1] < 4:  # no wrist joint: a zero yaw column
            qq = np.concatenate([qq, np.zeros((len(qq), 4 - qq.shape[1]))], axis=1)
        out: FloatArray = gantry_frames(
            np.ascontiguousarray(self.base, dtype=float), bool(self.wrist), qq
        )
        return out

    def _frames_numpy(self, q: FloatArray) -> FloatArray:
        """The numpy version of :meth:`frames` (the tests' reference)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        n = len(q)
        out = np.repeat(np.repeat(self.base[None, None], n, axis=0), 4, axis=1)
        t1 = np.repeat(np.eye(4)[None], n, axis=0)
        t1[:, 0, 3] = q[:, 0]
        t2 = t1.copy()
        t2[:, 1, 3] = q[:, 1]
        yaw = q[:, 3] if self.wrist else np.zeros(n)
        t3 = rot_z(yaw) @ FLIP_X
        t3[:, :3, 3] = q[:, :3]
        out[:, 1] = self.base @ t1
        out[:, 2] = self.base @ t2
        out[:, 3] = self.base @ t3
        return out

    def ik(self, pose: Transform, q_hint: JointVector | None = None) -> JointVector:
        local = self.base_inv @ np.asarray(pose, dtype=float)
        yaw = vertical_tool_yaw(local, self.name)
        hint = self.home if q_hint is None else np.asarray(q_hint, dtype=float)
        q = list(local[:3, 3])
        if self.wrist:
            lo, hi = self.joint_limits[3]
            cands = [wrap_near(yaw, float(hint[3])) + k * 2 * math.pi for k in (-1, 0, 1)]
            ok = [c for c in cands if lo - 1e-9 <= c <= hi + 1e-9]
            if not ok:
                raise Unreachable(
                    f"arm {self.name!r}: yaw {math.degrees(yaw):.4g} degrees is outside the "
                    "wrist limits"
                )
            q.append(min(ok, key=lambda c: abs(c - float(hint[3]))))
        elif abs(wrap_near(yaw, 0.0)) > 1e-6:
            raise Unreachable(f"arm {self.name!r} has no wrist: it cannot turn the tool")
        return self.check_limits(np.array(q), "the pose")

    def displacement_bound(self, dq: FloatArray) -> FloatArray:
        dq = np.abs(np.atleast_2d(dq))
        out = dq[:, 0] + dq[:, 1] + dq[:, 2]
        if self.wrist:
            out = out + dq[:, 3] * self._reach_yaw
        res: FloatArray = out
        return res


def _shift(x: float, y: float, z: float) -> Transform:
    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t
