"""Compiled kinematics of a serial chain read from URDF (numba, cached on disk).

The chain is the URDF's joints from the root link to the tool link, fixed
joints folded into the next moving joint's origin: joint ``k`` carries frame
``k`` (its child link) to ``frame[k] = frame[k - 1] @ origin[k] @ motion_k(q_k)``
where ``motion_k`` turns about the unit ``axis[k]`` (revolute) or slides
along it (prismatic). Frame 0 is the arm's base (the root link placed in the
cell); the last frame is the tool link, ``frame[n] @ tool``.

The inverse kinematics, :func:`chain_ik`, serves the URDF and the DH serial
arm (:mod:`workcell.arms.serial` writes its DH rows as such a chain):
Levenberg-Marquardt, damped least squares on the position and
rotation-vector error with the geometric Jacobian, adaptive damping, limits
enforced by clipping, several starts in a fixed order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["chain_frames", "chain_ik"]


@njit(cache=True)
def _motion(axis: np.ndarray, prismatic: bool, q: float, out: np.ndarray) -> None:
    """``out[:] =`` the (4, 4) joint motion: rotation about / slide along ``axis``."""
    for r in range(4):
        for k in range(4):
            out[r, k] = 1.0 if r == k else 0.0
    x, y, z = axis[0], axis[1], axis[2]
    if prismatic:
        out[0, 3], out[1, 3], out[2, 3] = x * q, y * q, z * q
        return
    c, s = math.cos(q), math.sin(q)
    t = 1.0 - c
    out[0, 0], out[0, 1], out[0, 2] = c + x * x * t, x * y * t - z * s, x * z * t + y * s
    out[1, 0], out[1, 1], out[1, 2] = y * x * t + z * s, c + y * y * t, y * z * t - x * s
    out[2, 0], out[2, 1], out[2, 2] = z * x * t - y * s, z * y * t + x * s, c + z * z * t


@njit(cache=True)
def _mul(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = a @ b`` for (4, 4) rigid transforms (last rows 0 0 0 1)."""
    for r in range(3):
        a0, a1, a2, a3 = a[r, 0], a[r, 1], a[r, 2], a[r, 3]
        for c in range(4):
            out[r, c] = a0 * b[0, c] + a1 * b[1, c] + a2 * b[2, c] + a3 * b[3, c]
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = 0.0, 0.0, 0.0, 1.0


@njit(cache=True)
def _frames_one(
    base: np.ndarray,
    origins: np.ndarray,
    axes: np.ndarray,
    prismatic: np.ndarray,
    tool: np.ndarray,
    q: np.ndarray,
    out: np.ndarray,
    tmp: np.ndarray,
    mot: np.ndarray,
) -> None:
    """Fill ``out`` (n + 2, 4, 4) with the frames for one joint vector
    (``tmp`` and ``mot``: (4, 4) scratch)."""
    n = origins.shape[0]
    out[0] = base
    for k in range(n):
        _mul(out[k], origins[k], tmp)
        _motion(axes[k], prismatic[k], q[k], mot)
        _mul(tmp, mot, out[k + 1])
    _mul(out[n], tool, out[n + 1])


@njit(cache=True)
def chain_frames(
    base: np.ndarray,
    origins: np.ndarray,
    axes: np.ndarray,
    prismatic: np.ndarray,
    tool: np.ndarray,
    q: np.ndarray,
) -> np.ndarray:
    """(N, n + 2, 4, 4) frames: the base, each joint's child link, the tool link.

    Parameters
    ----------
    base : (4, 4) float
        The root link's pose in the cell.
    origins : (n, 4, 4) float
        Each joint's origin in its parent's frame (fixed joints folded in).
    axes : (n, 3) float
        Unit joint axes in the joint frame.
    prismatic : (n,) bool
    tool : (4, 4) float
        The tool link in the last joint's child link frame.
    q : (N, n) float
    """
    n_q, n = q.shape[0], origins.shape[0]
    out = np.empty((n_q, n + 2, 4, 4))
    tmp = np.empty((4, 4))
    mot = np.empty((4, 4))
    for i in range(n_q):
        _frames_one(base, origins, axes, prismatic, tool, q[i], out[i], tmp, mot)
    return out


@njit(cache=True)
def _pose_error(cur: np.ndarray, target: np.ndarray, r: np.ndarray, e: np.ndarray) -> None:
    """Position error and rotation vector taking ``cur`` to ``target`` (world
    frame) into ``e`` (6,); ``r``: (3, 3) scratch."""
    for k in range(3):
        e[k] = target[k, 3] - cur[k, 3]
    for a in range(3):
        for b in range(3):
            r[a, b] = target[a, 0] * cur[b, 0] + target[a, 1] * cur[b, 1] + target[a, 2] * cur[b, 2]
    c = (r[0, 0] + r[1, 1] + r[2, 2] - 1.0) / 2.0
    c = min(1.0, max(-1.0, c))
    ang = math.acos(c)
    wx, wy, wz = r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]
    if ang < 1e-9:
        e[3], e[4], e[5] = wx / 2, wy / 2, wz / 2
    elif math.pi - ang < 1e-6:
        k = 0
        for i in range(3):
            if r[i, i] > r[k, k]:
                k = i
        a0 = (r[k, 0] + (1.0 if k == 0 else 0.0)) / 2.0
        a1 = (r[k, 1] + (1.0 if k == 1 else 0.0)) / 2.0
        a2 = (r[k, 2] + (1.0 if k == 2 else 0.0)) / 2.0
        norm = math.sqrt(a0**2 + a1**2 + a2**2)
        e[3], e[4], e[5] = a0 / norm * ang, a1 / norm * ang, a2 / norm * ang
    else:
        f = ang / (2.0 * math.sin(ang))
        e[3], e[4], e[5] = wx * f, wy * f, wz * f


@njit(cache=True)
def _werr(e: np.ndarray, w: np.ndarray) -> float:
    s = 0.0
    for k in range(6):
        s += (e[k] * w[k]) ** 2
    return math.sqrt(s)


@njit(cache=True)
def _damped_step(
    jj: np.ndarray, ew: np.ndarray, lam: float, chol: np.ndarray, y: np.ndarray
) -> bool:
    """``y = (jj + lam I)^-1 ew`` by Cholesky (jj = jac jac^T, 6 x 6, symmetric
    positive semi-definite); False when rounding leaves the matrix not
    positive definite (the caller then raises the damping)."""
    for i in range(6):
        for j in range(i + 1):
            s = jj[i, j] + (lam if i == j else 0.0)
            for k in range(j):
                s -= chol[i, k] * chol[j, k]
            if i == j:
                if not s > 0.0:
                    return False
                chol[i, i] = math.sqrt(s)
            else:
                chol[i, j] = s / chol[j, j]
    for i in range(6):
        s = ew[i]
        for k in range(i):
            s -= chol[i, k] * y[k]
        y[i] = s / chol[i, i]
    for i in range(5, -1, -1):
        s = y[i]
        for k in range(i + 1, 6):
            s -= chol[k, i] * y[k]
        y[i] = s / chol[i, i]
    return True


@njit(cache=True)
def chain_ik(
    base: np.ndarray,
    origins: np.ndarray,
    axes: np.ndarray,
    prismatic: np.ndarray,
    tool: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    target: np.ndarray,
    starts: np.ndarray,
    w: np.ndarray,
    tol: float,
    iters: int,
) -> tuple[np.ndarray, float, bool]:
    """Damped least squares IK of the tool link, tried from each start in order.

    Returns the first converged joint vector (position and orientation errors
    both below ``tol``), its error 0.0 and True; or the best vector found,
    its weighted error and False. The loop allocates nothing: the 6 x 6
    damped system is solved by Cholesky in place.
    """
    n = origins.shape[0]
    fr = np.empty((n + 2, 4, 4))
    fr_new = np.empty((n + 2, 4, 4))
    tmp = np.empty((4, 4))
    mot = np.empty((4, 4))
    r3 = np.empty((3, 3))
    e = np.empty(6)
    e_new = np.empty(6)
    ew = np.empty(6)
    y = np.empty(6)
    jac = np.empty((6, n))
    jj = np.empty((6, 6))
    chol = np.empty((6, 6))
    q = np.empty(n)
    q_new = np.empty(n)
    best_err = np.inf
    best_q = starts[0].copy()
    for s in range(starts.shape[0]):
        for k in range(n):
            q[k] = min(max(starts[s, k], lo[k]), hi[k])
        _frames_one(base, origins, axes, prismatic, tool, q, fr, tmp, mot)
        _pose_error(fr[n + 1], target, r3, e)
        err = _werr(e, w)
        lam = 1e-2
        for _ in range(iters):
            if (
                math.sqrt(e[0] ** 2 + e[1] ** 2 + e[2] ** 2) < tol
                and math.sqrt(e[3] ** 2 + e[4] ** 2 + e[5] ** 2) < tol
            ):
                return q.copy(), 0.0, True
            pe0, pe1, pe2 = fr[n + 1, 0, 3], fr[n + 1, 1, 3], fr[n + 1, 2, 3]
            for k in range(n):
                f = fr[k + 1]
                ax = axes[k]
                z0 = f[0, 0] * ax[0] + f[0, 1] * ax[1] + f[0, 2] * ax[2]
                z1 = f[1, 0] * ax[0] + f[1, 1] * ax[1] + f[1, 2] * ax[2]
                z2 = f[2, 0] * ax[0] + f[2, 1] * ax[1] + f[2, 2] * ax[2]
                if prismatic[k]:
                    jac[0, k], jac[1, k], jac[2, k] = z0 * w[0], z1 * w[1], z2 * w[2]
                    jac[3, k], jac[4, k], jac[5, k] = 0.0, 0.0, 0.0
                else:
                    r0, r1, r2 = pe0 - f[0, 3], pe1 - f[1, 3], pe2 - f[2, 3]
                    jac[0, k] = (z1 * r2 - z2 * r1) * w[0]
                    jac[1, k] = (z2 * r0 - z0 * r2) * w[1]
                    jac[2, k] = (z0 * r1 - z1 * r0) * w[2]
                    jac[3, k], jac[4, k], jac[5, k] = z0 * w[3], z1 * w[4], z2 * w[5]
            for a in range(6):
                ew[a] = e[a] * w[a]
                for b in range(a + 1):
                    acc = 0.0
                    for k in range(n):
                        acc += jac[a, k] * jac[b, k]
                    jj[a, b] = acc
                    jj[b, a] = acc
            moved = False
            for _t in range(8):
                if _damped_step(jj, ew, lam, chol, y):
                    for k in range(n):
                        st = 0.0
                        for a in range(6):
                            st += jac[a, k] * y[a]
                        q_new[k] = min(max(q[k] + st, lo[k]), hi[k])
                    _frames_one(base, origins, axes, prismatic, tool, q_new, fr_new, tmp, mot)
                    _pose_error(fr_new[n + 1], target, r3, e_new)
                    err_new = _werr(e_new, w)
                    if err_new < err:
                        q[:] = q_new
                        fr[:] = fr_new
                        e[:] = e_new
                        err = err_new
                        lam = max(lam / 3.0, 1e-9)
                        moved = True
                        break
                lam *= 4.0
            if not moved:
                break
        if err < best_err:
            best_err = err
            best_q = q.copy()
    return best_q, best_err, False
