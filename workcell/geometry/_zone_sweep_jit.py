"""Compiled inner loops of the conservative sweep (:mod:`workcell.geometry.zone_sweep`).

The same tests as the vectorised numpy path, one sample at a time, so no
(samples x shapes x primitives x faces) temporaries are built and a zone
already touched at a sample is not tested again. The maths (and its
conservative supersets) is described in the sweep module's docstring; the
numpy versions stay beside these as the reference the tests compare against.

Compiled with numba on first use and cached on disk (``cache=True``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["capsules_touch", "contacts_block", "pose_near", "segment_points"]

_FLAT = 1e-15

_MARGIN = 1e-9
"""Slack (metres) by which a lower bound must exceed the reach before a pair
is skipped, far above the rounding of the segment distance, so skipping never
changes an answer."""


@njit(cache=True)
def _slab_axis(p: float, d: float, h: float, lo: float, hi: float) -> tuple[float, float]:
    """Narrow [lo, hi] to the parameters of ``p + t d`` inside ``|x| <= h``."""
    if abs(d) < _FLAT:
        if abs(p) <= h:
            return lo, hi
        return math.inf, -math.inf
    a = (-h - p) / d
    b = (h - p) / d
    if a > b:
        a, b = b, a
    return max(lo, a), min(hi, b)


@njit(cache=True, inline="always")
def _to_local(
    ax: float,
    ay: float,
    az: float,
    dx: float,
    dy: float,
    dz: float,
    rot: np.ndarray,
    c: np.ndarray,
    lp: np.ndarray,
    ld: np.ndarray,
) -> None:
    """Segment start ``a`` and direction ``d`` in a solid's frame (rotation
    ``rot`` local -> world, centre ``c``): ``lp = (a - c) R``, ``ld = d R``,
    written into ``lp`` and ``ld``."""
    for j in range(3):
        lp[j] = (ax * rot[0, j] + ay * rot[1, j] + az * rot[2, j]) - (
            c[0] * rot[0, j] + c[1] * rot[1, j] + c[2] * rot[2, j]
        )
        ld[j] = dx * rot[0, j] + dy * rot[1, j] + dz * rot[2, j]


@njit(cache=True)
def contacts_block(
    p0: np.ndarray,
    p1: np.ndarray,
    rad: np.ndarray,
    sph_c: np.ndarray,
    sph_r: np.ndarray,
    sph_z: np.ndarray,
    box_r: np.ndarray,
    box_c: np.ndarray,
    box_h: np.ndarray,
    box_z: np.ndarray,
    cyl_r: np.ndarray,
    cyl_c: np.ndarray,
    cyl_rad: np.ndarray,
    cyl_h: np.ndarray,
    cyl_z: np.ndarray,
    cvx_n: np.ndarray,
    cvx_b: np.ndarray,
    cvx_z: np.ndarray,
    n_zones: int,
) -> np.ndarray:
    """(N, Z) bool: capsules ``(p0, p1, rad)`` (N, S, 3) touch zone solids.

    Boxes and cylinders are first compared by bounding spheres: the solid
    grown by ``r`` lies within ``R + sqrt(3) r`` of its centre (``R`` the
    solid's own bounding radius) and the segment is no nearer to the centre
    than its midpoint's distance less its half length. A primitive is
    skipped only when that bound exceeds the sphere by :data:`_MARGIN`, so
    the answer is that of the full test.
    """
    n, n_s = p0.shape[0], p0.shape[1]
    out = np.zeros((n, n_zones), dtype=np.bool_)
    lp = np.empty(3)
    ld = np.empty(3)
    box_big = np.empty(box_z.shape[0])
    for k in range(box_z.shape[0]):
        box_big[k] = math.sqrt(box_h[k, 0] ** 2 + box_h[k, 1] ** 2 + box_h[k, 2] ** 2)
    cyl_big = np.empty(cyl_z.shape[0])
    for k in range(cyl_z.shape[0]):
        cyl_big[k] = math.sqrt(cyl_rad[k] ** 2 + cyl_h[k] ** 2)
    root3 = math.sqrt(3.0)
    for i in range(n):
        for s in range(n_s):
            r = rad[s]
            # scalars, no per-sample temporaries
            ax, ay, az = p0[i, s, 0], p0[i, s, 1], p0[i, s, 2]
            dx, dy, dz = p1[i, s, 0] - ax, p1[i, s, 1] - ay, p1[i, s, 2] - az
            dd = dx * dx + dy * dy + dz * dz
            mx, my, mz = ax + 0.5 * dx, ay + 0.5 * dy, az + 0.5 * dz
            grow = 0.5 * math.sqrt(dd) + root3 * r + _MARGIN
            for k in range(sph_z.shape[0]):
                z = sph_z[k]
                if out[i, z]:
                    continue
                w0 = sph_c[k, 0] - ax
                w1 = sph_c[k, 1] - ay
                w2 = sph_c[k, 2] - az
                u = (w0 * dx + w1 * dy + w2 * dz) / (dd if dd > 0 else 1.0)
                u = min(max(u, 0.0), 1.0)
                e0 = ax + u * dx - sph_c[k, 0]
                e1 = ay + u * dy - sph_c[k, 1]
                e2 = az + u * dz - sph_c[k, 2]
                reach = r + sph_r[k]
                if e0 * e0 + e1 * e1 + e2 * e2 <= reach * reach:
                    out[i, z] = True
            for k in range(box_z.shape[0]):
                z = box_z[k]
                if out[i, z]:
                    continue
                fx, fy, fz = mx - box_c[k, 0], my - box_c[k, 1], mz - box_c[k, 2]
                if math.sqrt(fx * fx + fy * fy + fz * fz) > box_big[k] + grow:
                    continue
                _to_local(ax, ay, az, dx, dy, dz, box_r[k], box_c[k], lp, ld)
                lo, hi = -math.inf, math.inf
                for j in range(3):
                    lo, hi = _slab_axis(lp[j], ld[j], box_h[k, j] + r, lo, hi)
                if max(lo, 0.0) <= min(hi, 1.0):
                    out[i, z] = True
            for k in range(cyl_z.shape[0]):
                z = cyl_z[k]
                if out[i, z]:
                    continue
                fx, fy, fz = mx - cyl_c[k, 0], my - cyl_c[k, 1], mz - cyl_c[k, 2]
                if math.sqrt(fx * fx + fy * fy + fz * fz) > cyl_big[k] + grow:
                    continue
                _to_local(ax, ay, az, dx, dy, dz, cyl_r[k], cyl_c[k], lp, ld)
                lo, hi = _slab_axis(lp[2], ld[2], cyl_h[k] + r, -math.inf, math.inf)
                lo, hi = max(lo, 0.0), min(hi, 1.0)
                if lo > hi:
                    continue
                a = ld[0] * ld[0] + ld[1] * ld[1]
                b = lp[0] * ld[0] + lp[1] * ld[1]
                u = -b / (a if a > 0 else 1.0)
                u = min(max(u, lo), hi)
                x = lp[0] + u * ld[0]
                y = lp[1] + u * ld[1]
                reach = cyl_rad[k] + r
                if x * x + y * y <= reach * reach:
                    out[i, z] = True
            for k in range(cvx_z.shape[0]):
                z = cvx_z[k]
                if out[i, z]:
                    continue
                lo, hi = -math.inf, math.inf
                ok = True
                for f in range(cvx_n.shape[1]):
                    nx, ny, nz = cvx_n[k, f, 0], cvx_n[k, f, 1], cvx_n[k, f, 2]
                    num = (cvx_b[k, f] + r) - (ax * nx + ay * ny + az * nz)
                    den = dx * nx + dy * ny + dz * nz
                    if den > _FLAT:
                        hi = min(hi, num / den)
                    elif den < -_FLAT:
                        lo = max(lo, num / den)
                    elif num < 0:
                        ok = False
                        break
                    if lo > hi or lo > 1.0 or hi < 0.0:
                        # lo only grows and hi only shrinks: the final
                        # test would fail, stop early
                        ok = False
                        break
                if ok and max(lo, 0.0) <= min(hi, 1.0):
                    out[i, z] = True
    return out


@njit(cache=True)
def _segment_distance(
    a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray, eps: float
) -> float:
    """Distance between segments ``a0a1`` and ``b0b1`` (Ericson 2005, 5.1.9),
    in scalars (no temporaries)."""
    d1x, d1y, d1z = a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2]
    d2x, d2y, d2z = b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]
    rx, ry, rz = a0[0] - b0[0], a0[1] - b0[1], a0[2] - b0[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    if a <= eps and e <= eps:
        s = t = 0.0
    elif a <= eps:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= eps:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > eps else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    gx = rx + s * d1x - t * d2x
    gy = ry + s * d1y - t * d2y
    gz = rz + s * d1z - t * d2z
    return math.sqrt(gx * gx + gy * gy + gz * gz)


@njit(cache=True)
def capsules_touch(
    a0: np.ndarray,
    a1: np.ndarray,
    ra: np.ndarray,
    b0: np.ndarray,
    b1: np.ndarray,
    rb: np.ndarray,
    padding: float,
) -> np.ndarray:
    """(N,) bool: any capsule of sample i (``a0, a1`` (N, Sa, 3), radii ``ra``)
    within ``ra + rb + padding`` of a fixed capsule (``b0, b1`` (Sb, 3)).

    Two bounding-sphere bounds skip pairs that cannot touch: the distance of
    two segments is at least the distance of their midpoints less both half
    lengths (triangle inequality), and the same holds against one sphere
    around all of ``b``. A pair is skipped only when such a lower bound
    exceeds the reach by :data:`_MARGIN`, so the answer is that of the plain
    all-pairs test.
    """
    n = a0.shape[0]
    nb = b0.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    if nb == 0:
        return out
    mb = np.empty((nb, 3))
    hb = np.empty(nb)
    cx = cy = cz = 0.0
    for k in range(nb):
        for j in range(3):
            mb[k, j] = 0.5 * (b0[k, j] + b1[k, j])
        ex, ey, ez = b1[k, 0] - b0[k, 0], b1[k, 1] - b0[k, 1], b1[k, 2] - b0[k, 2]
        hb[k] = 0.5 * math.sqrt(ex * ex + ey * ey + ez * ez)
        cx += mb[k, 0]
        cy += mb[k, 1]
        cz += mb[k, 2]
    cx, cy, cz = cx / nb, cy / nb, cz / nb
    big = 0.0  # radius of one sphere around every b capsule
    for k in range(nb):
        ex, ey, ez = mb[k, 0] - cx, mb[k, 1] - cy, mb[k, 2] - cz
        big = max(big, math.sqrt(ex * ex + ey * ey + ez * ez) + hb[k] + rb[k])
    for i in range(n):
        for s in range(a0.shape[1]):
            if out[i]:
                break
            mx = 0.5 * (a0[i, s, 0] + a1[i, s, 0])
            my = 0.5 * (a0[i, s, 1] + a1[i, s, 1])
            mz = 0.5 * (a0[i, s, 2] + a1[i, s, 2])
            ex = a1[i, s, 0] - a0[i, s, 0]
            ey = a1[i, s, 1] - a0[i, s, 1]
            ez = a1[i, s, 2] - a0[i, s, 2]
            ha = 0.5 * math.sqrt(ex * ex + ey * ey + ez * ez)
            fx, fy, fz = mx - cx, my - cy, mz - cz
            if math.sqrt(fx * fx + fy * fy + fz * fz) - ha - big > ra[s] + padding + _MARGIN:
                continue
            for k in range(nb):
                reach = ra[s] + rb[k] + padding
                fx, fy, fz = mx - mb[k, 0], my - mb[k, 1], mz - mb[k, 2]
                if math.sqrt(fx * fx + fy * fy + fz * fz) - ha - hb[k] > reach + _MARGIN:
                    continue
                dist = _segment_distance(a0[i, s], a1[i, s], b0[k], b1[k], 1e-18)
                if dist <= reach:
                    out[i] = True
                    break
    return out


@njit(cache=True)
def segment_points(frames: np.ndarray, idx: np.ndarray, hw: np.ndarray) -> np.ndarray:
    """(2, N, S, 3) world end points of the shapes' capsule segments.

    ``frames`` (N, F, 4, 4) are the arm's frame poses, ``idx`` (S,) each
    shape's frame and ``hw`` (S, 2, 4) the homogeneous end points in that
    frame (the shape's offset already applied).
    """
    n, n_s = frames.shape[0], idx.shape[0]
    out = np.empty((2, n, n_s, 3))
    for i in range(n):
        for s in range(n_s):
            f = idx[s]
            for e in range(2):
                h0, h1, h2, h3 = hw[s, e, 0], hw[s, e, 1], hw[s, e, 2], hw[s, e, 3]
                for r in range(3):
                    out[e, i, s, r] = (
                        frames[i, f, r, 0] * h0
                        + frames[i, f, r, 1] * h1
                        + frames[i, f, r, 2] * h2
                        + frames[i, f, r, 3] * h3
                    )
    return out


@njit(cache=True)
def pose_near(
    frames: np.ndarray,
    idx: np.ndarray,
    hw: np.ndarray,
    ra: np.ndarray,
    b0: np.ndarray,
    b1: np.ndarray,
    rb: np.ndarray,
    padding: float,
) -> bool:
    """:func:`capsules_touch` of one pose given its frames (1, F, 4, 4), in one
    compiled call (the detour planner's single-state check)."""
    pts = segment_points(frames, idx, hw)
    return bool(capsules_touch(pts[0], pts[1], ra, b0, b1, rb, padding)[0])
