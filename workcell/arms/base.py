"""The arm contract every arm model implements (DESIGN.md ``workcell/arms``).

Everything above this module (the collision world, the sweep, the OMPL
planner, the compile, the simulation) sees an arm only through
:class:`Arm` and the records here, as numpy arrays in SI units (metres,
seconds, radians; cell frame right-handed, z up).

Conventions
-----------
* ``q`` is a joint vector ``(dof,)`` or a batch ``(N, dof)``; batches are the
  normal case (vectorised kinematics, DESIGN.md "Performance posture").
* Every collision shape is an FCL primitive attached to one kinematic frame
  (``LinkShape.frame``; frame 0 is the arm's base, fixed in the cell).
  :meth:`Arm.shape_transforms` returns the world pose of every shape's centre.
* :meth:`Arm.displacement_bound` is the basis of the conservative sweep: for
  any joint change ``dq`` it bounds from above how far any point of any shape
  moves. Revolute joint ``j`` contributes ``|dq_j| * reach_j`` (``reach_j`` =
  the largest distance from joint ``j``'s axis of any shape point distal to
  it, shape radius included); prismatic joint ``j`` contributes ``|dq_j|``.
  Because the bound is a sum of per-joint terms it holds along any path whose
  joints move monotonically between two samples.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from multiarm.types import BoolArray, FloatArray, IntArray, JointVector, Transform
from workcell.arms._kinematics_jit import frame_products

__all__ = ["Arm", "JointKind", "LinkShape", "ShapeKind"]

_SHAPE_FRAMES: dict[int, tuple[tuple[LinkShape, ...], IntArray, FloatArray]] = {}
"""Frame index (S,) and offsets (S, 4, 4) by ``id`` of an arm's shapes tuple
(the tuple is kept so the id stays its)."""

_SHAPE_FRAMES_SIZE = 64


def shape_frames(arm: Arm) -> tuple[IntArray, FloatArray]:
    """Frame index (S,) and centre offsets (S, 4, 4) of the arm's shapes, built once."""
    shapes = arm.shapes
    hit = _SHAPE_FRAMES.get(id(shapes))
    if hit is not None and hit[0] is shapes:
        return hit[1], hit[2]
    idx = np.array([s.frame for s in shapes], dtype=np.int64)
    off = np.ascontiguousarray(
        np.stack([np.asarray(s.offset, dtype=float) for s in shapes]).reshape(-1, 4, 4)
    )
    if len(_SHAPE_FRAMES) >= _SHAPE_FRAMES_SIZE:
        _SHAPE_FRAMES.pop(next(iter(_SHAPE_FRAMES)))
    _SHAPE_FRAMES[id(shapes)] = (shapes, idx, off)
    return idx, off


ShapeKind = Literal["capsule", "box", "sphere", "cylinder"]
"""Collision primitive kinds (python-fcl's conventions)."""

JointKind = Literal["revolute", "prismatic"]


@dataclass(frozen=True, slots=True)
class LinkShape:
    """One collision primitive of an arm.

    Attributes
    ----------
    name : str
        Unique within the arm (used in collision reports and allowed pairs).
    kind : {"capsule", "box", "sphere", "cylinder"}
    size : tuple of float
        ``capsule``: (radius, length of the straight segment along the local
        z axis, centred; total length = length + 2 radius); ``box``: full
        sides (sx, sy, sz); ``sphere``: (radius,); ``cylinder``: (radius,
        height along local z, centred).
    frame : int
        The kinematic frame the shape is attached to (0 = the arm's base).
    offset : (4, 4) float
        Pose of the shape's centre in that frame.
    """

    name: str
    kind: ShapeKind
    size: tuple[float, ...]
    frame: int
    offset: Transform = field(default_factory=lambda: np.eye(4))

    def radius(self) -> float:
        """Radius of the smallest sphere about the centre holding the shape, metres."""
        if self.kind == "capsule":
            return self.size[0] + self.size[1] / 2
        if self.kind == "box":
            return float(np.linalg.norm(self.size)) / 2
        if self.kind == "sphere":
            return self.size[0]
        return float(np.hypot(self.size[0], self.size[1] / 2))


class Arm(ABC):
    """An arm model: kinematics, limits, collision geometry, drives.

    Subclasses: the Cartesian gantry (S1, stepper axes), the SCARA (S2) and
    the generic serial arm from DH parameters.

    Attributes
    ----------
    name : str
    kind : str
        ``"gantry"``, ``"scara"`` or ``"serial"``.
    base : (4, 4) float
        Pose of the base frame in the cell.
    joint_names : tuple of str
    joint_kinds : tuple of {"revolute", "prismatic"}
    joint_limits : (dof, 2) float
        Lower and upper limit of each joint.
    capabilities : frozenset of str
        What the arm can do (matched against ``tasklib.Task`` requirements).
    tools : tuple of str
        Tool mounts (tool names it can hold).
    payload : float
        Largest payload, kilograms.
    shapes : tuple of LinkShape
    allowed_pairs : frozenset of frozenset of str
        Pairs of shape names never checked against each other (self-collision).
    home : (dof,) float
        The joint vector the arm rests at.
    """

    name: str
    kind: str
    base: Transform
    joint_names: tuple[str, ...]
    joint_kinds: tuple[JointKind, ...]
    joint_limits: FloatArray
    capabilities: frozenset[str]
    tools: tuple[str, ...]
    payload: float
    shapes: tuple[LinkShape, ...]
    allowed_pairs: frozenset[frozenset[str]]
    home: JointVector

    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    @abstractmethod
    def frames(self, q: FloatArray) -> FloatArray:
        """World poses of the kinematic frames.

        Parameters
        ----------
        q : (N, dof) float

        Returns
        -------
        (N, F, 4, 4) float
            Frame 0 is the base; the last frame is the tool flange.
        """

    @abstractmethod
    def ik(self, pose: Transform, q_hint: JointVector | None = None) -> JointVector:
        """A joint vector reaching ``pose`` (tool flange, world frame).

        The solution nearest ``q_hint`` (default :attr:`home`) among the
        arm's closed-form branches, or a numerical solution started there.

        Raises
        ------
        multiarm.errors.Unreachable
            When no joint vector within the limits reaches the pose (the
            message says why: out of reach, joint limit, orientation).
        """

    @abstractmethod
    def displacement_bound(self, dq: FloatArray) -> FloatArray:
        """Upper bound of any shape point's displacement for joint changes ``dq``.

        Parameters
        ----------
        dq : (N, dof) float

        Returns
        -------
        (N,) float, metres
        """

    def fk(self, q: FloatArray) -> FloatArray:
        """(N, 4, 4) world pose of the tool flange for ``q`` (N, dof)."""
        return self.frames(np.atleast_2d(q))[:, -1]

    def shape_transforms(self, q: FloatArray) -> FloatArray:
        """(N, S, 4, 4) world pose of every shape's centre for ``q`` (N, dof)."""
        fr = np.ascontiguousarray(self.frames(np.atleast_2d(q)), dtype=float)
        idx, off = shape_frames(self)
        out: FloatArray = frame_products(fr, idx, off)
        return out

    def within_limits(self, q: FloatArray, tol: float = 1e-9) -> BoolArray:
        """(N,) bool: whether each row of ``q`` respects the joint limits."""
        q = np.atleast_2d(q)
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        ok: BoolArray = np.all((q >= lo - tol) & (q <= hi + tol), axis=1)
        return ok
