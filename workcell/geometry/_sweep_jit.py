"""Compiled inner loops of the conservative sweep (:mod:`workcell.geometry.sweep`).

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

__all__ = ["capsules_touch", "contacts_block"]

_FLAT = 1e-15


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
    """(N, Z) bool: capsules ``(p0, p1, rad)`` (N, S, 3) touch zone solids."""
    n, n_s = p0.shape[0], p0.shape[1]
    out = np.zeros((n, n_zones), dtype=np.bool_)
    lp = np.empty(3)
    ld = np.empty(3)
    for i in range(n):
        for s in range(n_s):
            r = rad[s]
            a0 = p0[i, s]
            d = p1[i, s] - a0
            dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
            for k in range(sph_z.shape[0]):
                z = sph_z[k]
                if out[i, z]:
                    continue
                w0 = sph_c[k, 0] - a0[0]
                w1 = sph_c[k, 1] - a0[1]
                w2 = sph_c[k, 2] - a0[2]
                u = (w0 * d[0] + w1 * d[1] + w2 * d[2]) / (dd if dd > 0 else 1.0)
                u = min(max(u, 0.0), 1.0)
                e0 = a0[0] + u * d[0] - sph_c[k, 0]
                e1 = a0[1] + u * d[1] - sph_c[k, 1]
                e2 = a0[2] + u * d[2] - sph_c[k, 2]
                reach = r + sph_r[k]
                if e0 * e0 + e1 * e1 + e2 * e2 <= reach * reach:
                    out[i, z] = True
            for k in range(box_z.shape[0]):
                z = box_z[k]
                if out[i, z]:
                    continue
                for j in range(3):
                    lp[j] = (
                        a0[0] * box_r[k, 0, j] + a0[1] * box_r[k, 1, j] + a0[2] * box_r[k, 2, j]
                    ) - (
                        box_c[k, 0] * box_r[k, 0, j]
                        + box_c[k, 1] * box_r[k, 1, j]
                        + box_c[k, 2] * box_r[k, 2, j]
                    )
                    ld[j] = d[0] * box_r[k, 0, j] + d[1] * box_r[k, 1, j] + d[2] * box_r[k, 2, j]
                lo, hi = -math.inf, math.inf
                for j in range(3):
                    lo, hi = _slab_axis(lp[j], ld[j], box_h[k, j] + r, lo, hi)
                if max(lo, 0.0) <= min(hi, 1.0):
                    out[i, z] = True
            for k in range(cyl_z.shape[0]):
                z = cyl_z[k]
                if out[i, z]:
                    continue
                for j in range(3):
                    lp[j] = (
                        a0[0] * cyl_r[k, 0, j] + a0[1] * cyl_r[k, 1, j] + a0[2] * cyl_r[k, 2, j]
                    ) - (
                        cyl_c[k, 0] * cyl_r[k, 0, j]
                        + cyl_c[k, 1] * cyl_r[k, 1, j]
                        + cyl_c[k, 2] * cyl_r[k, 2, j]
                    )
                    ld[j] = d[0] * cyl_r[k, 0, j] + d[1] * cyl_r[k, 1, j] + d[2] * cyl_r[k, 2, j]
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
                    num = (cvx_b[k, f] + r) - (a0[0] * nx + a0[1] * ny + a0[2] * nz)
                    den = d[0] * nx + d[1] * ny + d[2] * nz
                    if den > _FLAT:
                        hi = min(hi, num / den)
                    elif den < -_FLAT:
                        lo = max(lo, num / den)
                    elif num < 0:
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
    within ``ra + rb + padding`` of a fixed capsule (``b0, b1`` (Sb, 3))."""
    n = a0.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        for s in range(a0.shape[1]):
            if out[i]:
                break
            for k in range(b0.shape[0]):
                dist = _segment_distance(a0[i, s], a1[i, s], b0[k], b1[k], 1e-18)
                if dist <= ra[s] + rb[k] + padding:
                    out[i] = True
                    break
    return out
