"""Capsules fitted around point sets: conservative stand-ins for link meshes.

An arm described by URDF carries one collision mesh per link; the compiled
sweep and state checks (:mod:`workcell.geometry.zone_sweep`) work on capsules.
:func:`fit_capsule` finds a capsule that **contains** every given point (the
vertices of a mesh, so the whole mesh: a capsule is convex, and a mesh lies
in the convex hull of its vertices), with as little volume as a small search
finds:

* candidate axes: the three principal axes of the points and the three axes
  of their frame;
* for an axis, the segment's line goes through the centre of the smallest
  circle around the points projected on the plane across the axis
  (Welzl's algorithm, in a fixed order, so the result is deterministic);
* for a radius ``r`` at least the largest distance ``d_v`` of a point from
  that line, the shortest segment holding every point within ``r`` spans
  ``[max_v (t_v - s_v), min_v (t_v + s_v)]`` reversed, with ``t_v`` the point's
  position along the axis and ``s_v = sqrt(r^2 - d_v^2)``; a scan of radii
  picks the smallest volume.

The containment is exact by construction; the radius is then grown by a
relative ``1e-9`` (and ``1e-12`` m) so rounding cannot leave a vertex a hair
outside. :func:`capsule_contains` and :func:`capsule_volume` check and
measure it.

Examples
--------
>>> import numpy as np
>>> pts = np.array([[0, 0, -1], [0, 0, 1], [0.1, 0, 0], [-0.1, 0, 0]], float)
>>> cap = fit_capsule(pts)
>>> bool(capsule_contains(cap, pts).all()), round(cap.radius, 3)
(True, 0.1)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import BoolArray, FloatArray

__all__ = ["FittedCapsule", "capsule_contains", "capsule_volume", "fit_capsule"]

RADIUS_STEPS = 24
"""Radii scanned between the smallest possible one and twice it."""


@dataclass(frozen=True, slots=True)
class FittedCapsule:
    """A capsule: the points within ``radius`` of the segment ``p0``-``p1``.

    Attributes
    ----------
    p0, p1 : (3,) float
        Segment end points, in the frame of the fitted points (metres).
    radius : float, metres
    """

    p0: FloatArray
    p1: FloatArray
    radius: float

    @property
    def length(self) -> float:
        """Length of the straight segment (metres)."""
        return float(np.linalg.norm(self.p1 - self.p0))

    def pose(self) -> FloatArray:
        """(4, 4) pose of the capsule's centre, its local z along the segment."""
        d = self.p1 - self.p0
        n = float(np.linalg.norm(d))
        z = d / n if n > 1e-12 else np.array([0.0, 0.0, 1.0])
        helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        x = np.cross(helper, z)
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        out = np.eye(4)
        out[:3, 0], out[:3, 1], out[:3, 2], out[:3, 3] = x, y, z, (self.p0 + self.p1) / 2
        return out


def capsule_volume(cap: FittedCapsule) -> float:
    """Volume of the capsule, cubic metres."""
    r = cap.radius
    return math.pi * r * r * cap.length + 4.0 / 3.0 * math.pi * r**3


def capsule_contains(cap: FittedCapsule, points: FloatArray, tol: float = 0.0) -> BoolArray:
    """(N,) bool: whether each point lies within ``radius + tol`` of the segment."""
    p = np.atleast_2d(np.asarray(points, dtype=float))
    d = cap.p1 - cap.p0
    dd = float(d @ d)
    t = np.zeros(len(p)) if dd < 1e-300 else np.clip((p - cap.p0) @ d / dd, 0.0, 1.0)
    closest = cap.p0 + t[:, None] * d
    out: BoolArray = np.linalg.norm(p - closest, axis=1) <= cap.radius + tol
    return out


def _circle_two(a: FloatArray, b: FloatArray) -> tuple[FloatArray, float]:
    c = (a + b) / 2
    return c, float(np.linalg.norm(a - c))


def _circle_three(a: FloatArray, b: FloatArray, c: FloatArray) -> tuple[FloatArray, float]:
    ax, ay = a
    bx, by = b
    cx, cy = c
    d = 2 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    if abs(d) < 1e-18:  # collinear: the widest pair
        pairs = [_circle_two(a, b), _circle_two(a, c), _circle_two(b, c)]
        return max(pairs, key=lambda p: p[1])
    ux = (
        (ax * ax + ay * ay) * (by - cy)
        + (bx * bx + by * by) * (cy - ay)
        + (cx * cx + cy * cy) * (ay - by)
    ) / d
    uy = (
        (ax * ax + ay * ay) * (cx - bx)
        + (bx * bx + by * by) * (ax - cx)
        + (cx * cx + cy * cy) * (bx - ax)
    ) / d
    centre = np.array([ux, uy])
    return centre, float(np.linalg.norm(a - centre))


def _min_circle(points: FloatArray) -> FloatArray:
    """Centre of the smallest circle holding the 2D points: Welzl's algorithm
    on the points' convex hull, in a seeded shuffled order (deterministic)."""
    from scipy.spatial import ConvexHull, QhullError

    pts = points
    if len(pts) > 3:
        try:
            pts = points[ConvexHull(points).vertices]
        except (QhullError, ValueError):  # collinear or repeated points
            pts = points
    pts = pts[np.random.default_rng(0).permutation(len(pts))]
    eps = 1e-12
    c, r = pts[0].copy(), 0.0
    for i in range(1, len(pts)):
        if np.linalg.norm(pts[i] - c) <= r + eps:
            continue
        c, r = pts[i].copy(), 0.0
        for j in range(i):
            if np.linalg.norm(pts[j] - c) <= r + eps:
                continue
            c, r = _circle_two(pts[i], pts[j])
            for k in range(j):
                if np.linalg.norm(pts[k] - c) > r + eps:
                    c, r = _circle_three(pts[i], pts[j], pts[k])
    out: FloatArray = c
    return out


def _fit_axis(pts: FloatArray, axis: FloatArray) -> FittedCapsule:
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    plane = np.column_stack((pts @ u, pts @ v))
    c2 = _min_circle(plane)
    t = pts @ axis
    d = np.linalg.norm(plane - c2, axis=1)
    r_min = float(d.max())
    best: tuple[float, float, float, float] | None = None
    scale = max(r_min, 1e-9)
    for k in range(RADIUS_STEPS + 1):
        r = r_min + scale * k / RADIUS_STEPS
        s = np.sqrt(np.maximum(r * r - d * d, 0.0))
        a, b = float(np.max(t - s)), float(np.min(t + s))
        lo, hi = (b, a) if b <= a else ((a + b) / 2, (a + b) / 2)
        vol = math.pi * r * r * (hi - lo) + 4.0 / 3.0 * math.pi * r**3
        if best is None or vol < best[0]:
            best = (vol, r, lo, hi)
    assert best is not None
    _, r, lo, hi = best
    origin = c2[0] * u + c2[1] * v
    return FittedCapsule(origin + lo * axis, origin + hi * axis, r)


def fit_capsule(points: FloatArray) -> FittedCapsule:
    """The smallest-volume capsule found that contains every point (module docstring).

    Parameters
    ----------
    points : (N, 3) float
        For a mesh, its vertices (its convex hull's suffice).

    Returns
    -------
    FittedCapsule
        In the points' frame; contains every point.

    Raises
    ------
    ValidationError
        For no points or non-finite coordinates.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(pts) == 0 or not np.all(np.isfinite(pts)):
        raise ValidationError("fit_capsule: needs at least one finite (x, y, z) point")
    pts = np.unique(pts, axis=0)
    centred = pts - pts.mean(axis=0)
    axes = [np.eye(3)[k] for k in range(3)]
    if len(pts) >= 3:
        _, _, vt = np.linalg.svd(centred, full_matrices=False)
        axes = [vt[k] / np.linalg.norm(vt[k]) for k in range(len(vt))] + axes
    best: FittedCapsule | None = None
    for ax in axes:
        cap = _fit_axis(pts, ax)
        if best is None or capsule_volume(cap) < capsule_volume(best):
            best = cap
    assert best is not None
    grown = best.radius * (1 + 1e-9) + 1e-12
    out = FittedCapsule(best.p0, best.p1, grown)
    if not bool(capsule_contains(out, pts).all()):  # pragma: no cover - exact by construction
        raise ValidationError("fit_capsule: internal containment check failed")
    return out
