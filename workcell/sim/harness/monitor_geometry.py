"""The safety monitor's geometry: every arm shape inside a capsule, the
compiled (numba) capsule tests, FCL on their candidates."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from numba import njit

from multiarm.types import FloatArray
from workcell.compile import CompiledCell
from workcell.geometry import CollisionWorld

__all__ = [
    "MonitorGeometry",
    "first_touching_sample",
    "pair_touches",
    "segment_dist2",
    "touching_pairs",
]


_SLACK = 1e-4
"""Metres added to the capsules' reach in the pre-test, far above the rounding
of the segment distance (about 1e-6 m for nearly parallel segments a metre
long), so the pre-test never skips a pair FCL would find touching."""


class MonitorGeometry:
    """The monitor's own collision world and bounding spheres of every shape."""

    def __init__(self, compiled: CompiledCell) -> None:
        cell = compiled.cell
        self.arms = list(cell.arms)
        self.names = [arm.name for arm in cell.arms]
        # No allowed pairs: the monitor asks only about pairs of arms, never
        # about one arm's own links (which FCL would then have to filter).
        self.world = CollisionWorld()
        for arm, q in zip(cell.arms, cell.start, strict=True):
            tfs = arm.shape_transforms(np.asarray(q, dtype=float)[None, :])[0]
            for shape, tf in zip(arm.shapes, tfs, strict=True):
                self.world.add_link_shape(f"{arm.name}/{shape.name}", shape, arm.name, tf)
        self.radii = [np.array([s.radius() for s in arm.shapes]) for arm in cell.arms]
        sizes = [len(r) for r in self.radii]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.arm_of = np.repeat(np.arange(len(sizes), dtype=np.int64), sizes)
        r = np.concatenate(self.radii) if sizes else np.zeros(0)
        self.r2 = (r[:, None] + r[None, :]) ** 2
        self.r2[self.arm_of[:, None] == self.arm_of[None, :]] = -1.0  # one arm's own shapes
        # every shape inside a capsule: a segment along a local axis, a radius
        axes, half, rc = [], [], []
        for arm in cell.arms:
            for sh in arm.shapes:
                u, h, r_ = _enclosing_capsule(sh.kind, sh.size)
                axes.append(u)
                half.append(h)
                rc.append(r_)
        self.axis = np.array(axes, dtype=float).reshape(-1, 3)
        self.half = np.array(half, dtype=float)
        # each capsule's axis is a local coordinate axis: its column of the pose
        self._col = np.argmax(self.axis, axis=1).astype(np.int64)
        assert np.array_equal(self.axis, np.eye(3)[self._col])
        self.rc = np.array(rc, dtype=float)
        self.fcl_checks = 0

    def ends(self, a: int, tfs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(..., n, 3) ends of arm ``a``'s shapes' capsules for shape poses ``tfs``."""
        lo, hi = int(self.offsets[a]), int(self.offsets[a + 1])
        n = hi - lo
        flat = tfs.reshape(-1, n, 4, 4)
        # the axis column of each shape's rotation (what the rotation does to
        # the local unit axis, exactly), times the half-length
        cols = np.moveaxis(flat[:, np.arange(n), :3, self._col[lo:hi]], 0, 1)
        w = cols.reshape(*tfs.shape[:-2], 3) * self.half[lo:hi, None]
        c = tfs[..., :3, 3]
        return np.ascontiguousarray(c - w), np.ascontiguousarray(c + w)

    def collide(self, a: int, b: int) -> bool:
        self.fcl_checks += 1
        return bool(self.world.collide(self.names[a], self.names[b]))

    def violation(self, a: int, b: int, t: float) -> str:
        na, nb = self.names[a], self.names[b]
        pairs = self.world.colliding_pairs(na, nb)
        return (
            f"arms {na!r} and {nb!r} collide at t = {t:.6g} s "
            f"({', '.join(f'{x} - {y}' for x, y in pairs)})"
        )


def _enclosing_capsule(kind: str, size: Sequence[float]) -> tuple[FloatArray, float, float]:
    """A capsule holding a shape: (local unit axis, half-length, radius)."""
    z = np.array([0.0, 0.0, 1.0])
    if kind in ("capsule", "cylinder"):
        r, h = float(size[0]), float(size[1])
        return z, h / 2, r  # a cylinder lies inside the capsule of its axis and radius
    if kind == "box":
        dims = np.abs(np.asarray(size, dtype=float)) / 2
        i = int(np.argmax(dims))
        u = np.zeros(3)
        u[i] = 1.0
        others = np.delete(dims, i)
        return u, float(dims[i]), float(np.hypot(others[0], others[1]))
    return z, 0.0, float(size[0])  # sphere


@njit(cache=True, inline="always")
def segment_dist2(p0: FloatArray, p1: FloatArray, q0: FloatArray, q1: FloatArray) -> float:
    """Squared distance between the segments ``p0 p1`` and ``q0 q1`` (3-vectors;
    the closest points of two segments after Ericson, Real-Time Collision
    Detection, 5.1.9)."""
    d1x, d1y, d1z = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    d2x, d2y, d2z = q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]
    rx, ry, rz = p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-18
    s = 0.0
    t = 0.0
    if a <= eps and e <= eps:
        pass
    elif a <= eps:
        t = min(1.0, max(0.0, f / e))
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= eps:
            s = min(1.0, max(0.0, -c / a))
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            den = a * e - b * b
            if den > 1e-12 * a * e:
                s = min(1.0, max(0.0, (b * f - c * e) / den))
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(1.0, max(0.0, -c / a))
            elif t > 1.0:
                t = 1.0
                s = min(1.0, max(0.0, (b - c) / a))
    dx = rx + d1x * s - d2x * t
    dy = ry + d1y * s - d2y * t
    dz = rz + d1z * s - d2z * t
    out: float = dx * dx + dy * dy + dz * dz
    return out


@njit(cache=True)
def touching_pairs(
    c: FloatArray,
    p0: FloatArray,
    p1: FloatArray,
    rows: npt.NDArray[np.int64],
    r2: FloatArray,
    rc: FloatArray,
    arm_of: npt.NDArray[np.int64],
    out: npt.NDArray[np.bool_],
) -> int:
    """Mark in ``out[a, b]`` (``a < b``) the arm pairs with a shape of ``rows``
    whose bounding spheres meet and whose capsules touch (within ``_SLACK``);
    returns how many pairs were marked."""
    found = 0
    for ii in range(rows.shape[0]):
        i = rows[ii]
        ai = arm_of[i]
        for j in range(c.shape[0]):
            aj = arm_of[j]
            if aj == ai:
                continue
            lo, hi = (ai, aj) if ai < aj else (aj, ai)
            if out[lo, hi]:
                continue
            dx, dy, dz = c[i, 0] - c[j, 0], c[i, 1] - c[j, 1], c[i, 2] - c[j, 2]
            if dx * dx + dy * dy + dz * dz > r2[i, j]:
                continue
            reach = rc[i] + rc[j] + _SLACK
            if segment_dist2(p0[i], p1[i], p0[j], p1[j]) <= reach * reach:
                out[lo, hi] = True
                found += 1
    return found


@njit(cache=True)
def pair_touches(
    ca: FloatArray,
    a0: FloatArray,
    a1: FloatArray,
    cb: FloatArray,
    b0: FloatArray,
    b1: FloatArray,
    r2: FloatArray,
    rca: FloatArray,
    rcb: FloatArray,
    out: npt.NDArray[np.bool_],
) -> None:
    """``out[k]``: at sample ``k`` a shape of arm a (centres ``ca``, capsule
    ends ``a0 a1``; (n, shapes, 3)) and a shape of arm b have meeting
    bounding spheres (squared radius sums ``r2``) and touching capsules
    (radii ``rca``, ``rcb``; within ``_SLACK``)."""
    for k in range(ca.shape[0]):
        hit = False
        for x in range(ca.shape[1]):
            for y in range(cb.shape[1]):
                dx = ca[k, x, 0] - cb[k, y, 0]
                dy = ca[k, x, 1] - cb[k, y, 1]
                dz = ca[k, x, 2] - cb[k, y, 2]
                if dx * dx + dy * dy + dz * dz > r2[x, y]:
                    continue
                reach = rca[x] + rcb[y] + _SLACK
                if segment_dist2(a0[k, x], a1[k, x], b0[k, y], b1[k, y]) <= reach * reach:
                    hit = True
                    break
            if hit:
                break
        out[k] = hit


@njit(cache=True)
def first_touching_sample(
    c: FloatArray,
    p0: FloatArray,
    p1: FloatArray,
    rows: npt.NDArray[np.int64],
    r2: FloatArray,
    rc: FloatArray,
    arm_of: npt.NDArray[np.int64],
) -> int:
    """The first of ``n`` samples (shape centres ``c`` and capsule ends ``p0
    p1``, each (n, shapes, 3)) at which a shape of ``rows`` and a shape of
    another arm pass the pre-tests of :func:`touching_pairs` (the same
    arithmetic: meeting bounding spheres, capsules within ``_SLACK``); -1
    when none does."""
    for k in range(c.shape[0]):
        for ii in range(rows.shape[0]):
            i = rows[ii]
            ai = arm_of[i]
            for j in range(c.shape[1]):
                if arm_of[j] == ai:
                    continue
                dx, dy, dz = (
                    c[k, i, 0] - c[k, j, 0],
                    c[k, i, 1] - c[k, j, 1],
                    c[k, i, 2] - c[k, j, 2],
                )
                if dx * dx + dy * dy + dz * dz > r2[i, j]:
                    continue
                reach = rc[i] + rc[j] + _SLACK
                if segment_dist2(p0[k, i], p1[k, i], p0[k, j], p1[k, j]) <= reach * reach:
                    return k
    return -1
