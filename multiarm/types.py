"""Shared type aliases and small helpers used by every layer.

Conventions (DESIGN.md): SI units (metres, seconds, radians), the cell frame is
right-handed with z up, quaternions are ``(w, x, y, z)`` (the order of
python-fcl and ``trimesh.transformations``), and randomness only enters
through an explicit seed.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

__all__ = [
    "BoolArray",
    "FloatArray",
    "IntArray",
    "JointVector",
    "Point3",
    "Quaternion",
    "Seed",
    "Transform",
    "as_rng",
    "check_finite",
]

FloatArray: TypeAlias = npt.NDArray[np.float64]
"""Any float64 array."""

IntArray: TypeAlias = npt.NDArray[np.int64]
"""Any int64 array."""

BoolArray: TypeAlias = npt.NDArray[np.bool_]
"""Any bool array."""

Transform: TypeAlias = npt.NDArray[np.float64]
"""(4, 4) float homogeneous transform, metres."""

JointVector: TypeAlias = npt.NDArray[np.float64]
"""(J,) float joint values: radians for revolute joints, metres for prismatic."""

Point3: TypeAlias = tuple[float, float, float]
"""A point or vector in the cell frame, metres."""

Quaternion: TypeAlias = tuple[float, float, float, float]
"""A unit quaternion ``(w, x, y, z)``."""

Seed: TypeAlias = int | np.random.Generator | None
"""What every stochastic entry point accepts as its seed."""


def as_rng(seed: Seed) -> np.random.Generator:
    """Turn a seed into a numpy Generator, never touching global state.

    Parameters
    ----------
    seed : int, numpy.random.Generator or None
        An int seeds a new PCG64 generator; a Generator is returned as is;
        ``None`` draws fresh entropy (not reproducible, never the default of
        a library function).

    Examples
    --------
    >>> int(as_rng(3).integers(100)) == int(as_rng(3).integers(100))
    True
    """
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None or isinstance(seed, int | np.integer):
        return np.random.default_rng(seed)
    raise TypeError(f"seed must be an int, a numpy Generator or None, not {type(seed).__name__}")


def check_finite(values: Iterable[float]) -> bool:
    """True when every value is a finite real number."""
    return all(isinstance(v, int | float) and math.isfinite(v) for v in values)
