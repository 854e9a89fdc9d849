"""Compiled small-matrix products of the arms' kinematics.

numpy's ``matmul`` on stacks of 4x4 matrices spends most of its time in
per-matrix overhead; these loops compute the same products element by
element (the same sums, so results agree with ``matmul`` up to the order of
floating additions). Compiled with numba on first use and cached on disk
(``cache=True``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["dh_frames", "frame_products", "gantry_frames", "piecewise_cubic", "scara_frames"]


@njit(cache=True)
def frame_products(frames: np.ndarray, idx: np.ndarray, off: np.ndarray) -> np.ndarray:
    """(N, S, 4, 4): ``frames[n, idx[s]] @ off[s]`` for every sample and shape.

    Parameters
    ----------
    frames : (N, F, 4, 4) float
    idx : (S,) int
    off : (S, 4, 4) float
    """
    n, n_s = frames.shape[0], idx.shape[0]
    out = np.empty((n, n_s, 4, 4))
    for i in range(n):
        for s in range(n_s):
            f = idx[s]
            for r in range(4):
                f0, f1, f2, f3 = (
                    frames[i, f, r, 0],
                    frames[i, f, r, 1],
                    frames[i, f, r, 2],
                    frames[i, f, r, 3],
                )
                for c in range(4):
                    out[i, s, r, c] = (
                        f0 * off[s, 0, c]
                        + f1 * off[s, 1, c]
                        + f2 * off[s, 2, c]
                        + f3 * off[s, 3, c]
                    )
    return out


@njit(cache=True)
def _chain(base: np.ndarray, local: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = base @ local`` for (4, 4) matrices (base's last row is 0 0 0 1)."""
    for r in range(4):
        b0, b1, b2, b3 = base[r, 0], base[r, 1], base[r, 2], base[r, 3]
        for c in range(4):
            out[r, c] = b0 * local[0, c] + b1 * local[1, c] + b2 * local[2, c] + b3 * local[3, c]


@njit(cache=True)
def scara_frames(base: np.ndarray, l1: float, l2: float, q: np.ndarray) -> np.ndarray:
    """(N, 4, 4, 4) SCARA frames (base, link 1, link 2, flange) for ``q`` (N, 4).

    The same poses as :meth:`workcell.arms.scara.Scara.frames`: link 1 turned
    by ``t1``, link 2 at the elbow ``l1`` along link 1 turned by ``t1 + t2``,
    the flange tool-down (a half turn about x) at the tip, yawed by
    ``t1 + t2 + t4`` and at height ``z``.
    """
    n = q.shape[0]
    out = np.empty((n, 4, 4, 4))
    loc = np.zeros((4, 4))
    for i in range(n):
        t1, t2, z, t4 = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        c1, s1 = math.cos(t1), math.sin(t1)
        c2, s2 = math.cos(t2), math.sin(t2)
        out[i, 0] = base
        loc[:] = 0.0
        loc[0, 0], loc[0, 1], loc[1, 0], loc[1, 1] = c1, -s1, s1, c1
        loc[2, 2] = loc[3, 3] = 1.0
        _chain(base, loc, out[i, 1])
        # rot_z(t1) @ translate(l1, 0, 0) @ rot_z(t2)
        loc[0, 0] = c1 * c2 + (-s1) * s2
        loc[0, 1] = c1 * (-s2) + (-s1) * c2
        loc[1, 0] = s1 * c2 + c1 * s2
        loc[1, 1] = s1 * (-s2) + c1 * c2
        loc[0, 3] = c1 * l1
        loc[1, 3] = s1 * l1
        _chain(base, loc, out[i, 2])
        # rot_z(t1 + t2 + t4) @ diag(1, -1, -1, 1), at the tip
        t = t1 + t2 + t4
        c, s = math.cos(t), math.sin(t)
        loc[0, 0], loc[0, 1], loc[0, 2] = c, s, 0.0
        loc[1, 0], loc[1, 1], loc[1, 2] = s, -c, 0.0
        loc[2, 0], loc[2, 1], loc[2, 2] = 0.0, 0.0, -1.0
        loc[0, 3] = l1 * c1 + l2 * math.cos(t1 + t2)
        loc[1, 3] = l1 * s1 + l2 * math.sin(t1 + t2)
        loc[2, 3] = z
        _chain(base, loc, out[i, 3])
    return out


@njit(cache=True)
def gantry_frames(base: np.ndarray, wrist: bool, q: np.ndarray) -> np.ndarray:
    """(N, 4, 4, 4) gantry frames (base, x carriage, y carriage, flange) for ``q``.

    The same poses as :meth:`workcell.arms.gantry.Gantry.frames`: the
    carriages translated by ``x`` and ``(x, y)``, the flange tool-down at
    ``(x, y, z)`` and yawed by the wrist (if any).
    """
    n = q.shape[0]
    out = np.empty((n, 4, 4, 4))
    loc = np.zeros((4, 4))
    for i in range(n):
        out[i, 0] = base
        loc[:] = 0.0
        for k in range(4):
            loc[k, k] = 1.0
        loc[0, 3] = q[i, 0]
        _chain(base, loc, out[i, 1])
        loc[1, 3] = q[i, 1]
        _chain(base, loc, out[i, 2])
        yaw = q[i, 3] if wrist else 0.0
        c, s = math.cos(yaw), math.sin(yaw)
        loc[0, 0], loc[0, 1], loc[0, 2] = c, s, 0.0
        loc[1, 0], loc[1, 1], loc[1, 2] = s, -c, 0.0
        loc[2, 0], loc[2, 1], loc[2, 2] = 0.0, 0.0, -1.0
        loc[2, 3] = q[i, 2]
        _chain(base, loc, out[i, 3])
    return out


@njit(cache=True)
def dh_frames(base: np.ndarray, dh: np.ndarray, prismatic: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N, n + 1, 4, 4) frames of a DH serial arm (``dh`` rows ``a, alpha, d,
    offset``; standard convention), as :meth:`workcell.arms.serial.SerialArm.frames`."""
    n_q, n = q.shape[0], dh.shape[0]
    out = np.empty((n_q, n + 1, 4, 4))
    jt = np.zeros((4, 4))
    jt[3, 3] = 1.0
    for i in range(n_q):
        out[i, 0] = base
        for k in range(n):
            a, alpha, d, off = dh[k, 0], dh[k, 1], dh[k, 2], dh[k, 3]
            theta = off + (0.0 if prismatic[k] else q[i, k])
            dd = d + (q[i, k] if prismatic[k] else 0.0)
            ct, st = math.cos(theta), math.sin(theta)
            ca, sa = math.cos(alpha), math.sin(alpha)
            jt[0, 0], jt[0, 1], jt[0, 2], jt[0, 3] = ct, -st * ca, st * sa, a * ct
            jt[1, 0], jt[1, 1], jt[1, 2], jt[1, 3] = st, ct * ca, -ct * sa, a * st
            jt[2, 0], jt[2, 1], jt[2, 2], jt[2, 3] = 0.0, sa, ca, dd
            _chain(out[i, k], jt, out[i, k + 1])
    return out


@njit(cache=True)
def piecewise_cubic(
    breaks: np.ndarray, coef: np.ndarray, counts: np.ndarray, t: np.ndarray, duration: float
) -> np.ndarray:
    """(N, dof) joint values of a piecewise-cubic trajectory at times ``t``.

    Per joint ``j``, ``breaks[j, :counts[j]]`` are the piece start times and
    ``coef[j, k]`` the cubic's coefficients in the time since piece ``k``
    starts; times are clipped to ``[0, duration]`` and the piece is the last
    one starting at or before the time (the first piece for earlier times),
    as ``numpy.searchsorted(..., side="right") - 1`` clipped.
    """
    n, dof = t.shape[0], breaks.shape[0]
    out = np.empty((n, dof))
    for i in range(n):
        tt = min(max(t[i], 0.0), duration)
        for j in range(dof):
            lo, hi = 0, counts[j]
            while lo < hi:  # first break > tt
                mid = (lo + hi) // 2
                if breaks[j, mid] <= tt:
                    lo = mid + 1
                else:
                    hi = mid
            k = min(max(lo - 1, 0), counts[j] - 1)
            tau = tt - breaks[j, k]
            c = coef[j, k]
            out[i, j] = c[0] + tau * (c[1] + tau * (c[2] + tau * c[3]))
    return out
