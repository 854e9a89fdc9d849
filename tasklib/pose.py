"""Cartesian poses in the cell frame (position in metres, unit quaternion)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, Point3, Quaternion, Transform, check_finite

__all__ = ["IDENTITY", "Pose", "quat_from_rpy", "quat_to_matrix"]

IDENTITY: Quaternion = (1.0, 0.0, 0.0, 0.0)

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
        Unit quaternion ``(w, x, y, z)``; identity by default. Stored as
        given (not re-normalised) so that files round-trip bit for bit; it
        must be of unit norm within 1e-6.

    Examples
    --------
    >>> Pose((0.5, 0.2, 0.1)).matrix()[:3, 3].tolist()
    [0.5, 0.2, 0.1]
    """

    position: Point3
    orientation: Quaternion = IDENTITY

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
