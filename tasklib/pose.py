"""Cartesian poses in the cell frame (position in metres, unit quaternion)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, Point3, Quaternion, Transform, check_finite

__all__ = ["DOWN", "IDENTITY", "UP", "Pose", "pose", "quat_from_rpy", "quat_to_matrix"]

IDENTITY: Quaternion = (1.0, 0.0, 0.0, 0.0)
"""The identity quaternion ``(w, x, y, z)``: the tool axis (z) points *up*."""

DOWN: Quaternion = (0.0, 1.0, 0.0, 0.0)
"""Tool pointing down: a half turn about x. The one orientation every arm kind
reaches (gantries and SCARAs keep their tool vertical, pointing down), and the
default of :class:`Pose`."""

UP: Quaternion = IDENTITY
"""Tool pointing up (the identity): only a 6-DOF serial arm may reach it."""

_UNIT_TOL = 1e-6


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> Quaternion:
    """Quaternion ``(w, x, y, z)`` of the extrinsic x-y-z (roll, pitch, yaw) rotation.

    ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``, angles in radians.

    Examples
    --------
    >>> w, x, y, z = quat_from_rpy(0.0, 0.0, math.pi)
    >>> round(w, 12), round(z, 12)
    (0.0, 1.0)
    """
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def quat_to_matrix(q: Quaternion) -> FloatArray:
    """(3, 3) rotation matrix of a quaternion ``(w, x, y, z)`` (normalised first)."""
    w, x, y, z = np.asarray(q, dtype=float) / math.sqrt(sum(c * c for c in q))
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _as_point(value: object, what: str) -> Point3:
    try:
        seq = tuple(float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ValidationError(f"{what} must be three numbers, got {value!r}") from None
    if len(seq) != 3:
        raise ValidationError(f"{what} must have 3 coordinates, got {len(seq)}")
    if not check_finite(seq):
        raise ValidationError(f"{what} has a non-finite coordinate: {seq}")
    return (seq[0], seq[1], seq[2])


def _as_quat(value: object, what: str) -> Quaternion:
    try:
        seq = tuple(float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ValidationError(f"{what} must be four numbers (w, x, y, z), got {value!r}") from None
    if len(seq) != 4:
        raise ValidationError(f"{what} must have 4 components (w, x, y, z), got {len(seq)}")
    if not check_finite(seq):
        raise ValidationError(f"{what} has a non-finite component: {seq}")
    norm = math.sqrt(sum(c * c for c in seq))
    if abs(norm - 1.0) > _UNIT_TOL:
        raise ValidationError(f"{what} is not a unit quaternion (norm {norm:.9g}): {seq}")
    return (seq[0], seq[1], seq[2], seq[3])


@dataclass(frozen=True, slots=True)
class Pose:
    """A position and orientation in the cell frame.

    Parameters
    ----------
    position : (3,) float, metres
    orientation : (4,) float
        Unit quaternion ``(w, x, y, z)``; :data:`DOWN` (tool pointing down,
        reachable by every arm kind) by default. Stored as given (not
        re-normalised) so that files round-trip bit for bit; it must be of
        unit norm within 1e-6.

    Examples
    --------
    >>> p = Pose((0.5, 0.2, 0.1))
    >>> p.matrix()[:3, 3].tolist(), p.orientation == DOWN
    ([0.5, 0.2, 0.1], True)
    """

    position: Point3
    orientation: Quaternion = DOWN

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _as_point(self.position, "pose position"))
        object.__setattr__(self, "orientation", _as_quat(self.orientation, "pose orientation"))

    def matrix(self) -> Transform:
        """(4, 4) homogeneous transform."""
        t = np.eye(4)
        t[:3, :3] = quat_to_matrix(self.orientation)
        t[:3, 3] = self.position
        return t

    def as_array(self) -> FloatArray:
        """(7,) float: ``x, y, z, qw, qx, qy, qz``."""
        return np.array([*self.position, *self.orientation])


_TOOL = {"down": DOWN, "up": UP}


def pose(x: float, y: float, z: float, tool: str | Quaternion = "down", yaw: float = 0.0) -> Pose:
    """A tool pose at ``(x, y, z)`` metres in the cell frame.

    Parameters
    ----------
    x, y, z : float
        Position of the tool point, metres.
    tool : {"down", "up"} or (4,) float
        Where the tool points: ``"down"`` (the default, and what a bare
        ``(x, y, z)`` means wherever a pose is accepted; every arm kind
        reaches it), ``"up"``, or a unit quaternion ``(w, x, y, z)``.
    yaw : float
        Rotation of the tool about the vertical axis of the cell, radians,
        applied after ``tool`` (a SCARA or a gantry wrist turns the part by
        it).

    Returns
    -------
    Pose

    Raises
    ------
    ValidationError
        For an unknown ``tool`` name, a non-unit quaternion or a non-finite
        number.

    Examples
    --------
    >>> pose(0.5, 0.2, 0.1) == Pose((0.5, 0.2, 0.1), DOWN)
    True
    >>> [round(c, 12) for c in pose(0.5, 0.2, 0.1, yaw=math.pi).orientation]
    [0.0, 0.0, 1.0, 0.0]
    """
    if isinstance(tool, str):
        if tool not in _TOOL:
            raise ValidationError(
                f"pose tool must be 'down', 'up' or a quaternion (w, x, y, z), got {tool!r}"
            )
        q = _TOOL[tool]
    else:
        q = _as_quat(tool, "pose tool")
    yaw_f = float(yaw)
    if not math.isfinite(yaw_f):
        raise ValidationError(f"pose yaw must be a finite angle in radians, got {yaw!r}")
    if yaw_f != 0.0:
        c, s = math.cos(yaw_f / 2), math.sin(yaw_f / 2)
        w, qx, qy, qz = q
        # Rz(yaw) * q (Hamilton product): turn about the cell's vertical axis.
        q = (c * w - s * qz, c * qx - s * qy, c * qy + s * qx, c * qz + s * w)
    return Pose((x, y, z), q)
