"""The coordinator's geometric check before an arm moves (S2.6, S2.12)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numba import njit

from multiarm.types import FloatArray
from workcell.arms.base import shape_frames
from workcell.compile import CompiledCell
from workcell.geometry import CollisionWorld
from workcell.geometry._zone_sweep_jit import capsules_touch, segment_points
from workcell.geometry.zone_sweep import _segment_distances, _shape_capsules
from workcell.sim.protocol.exchange import ArmView

__all__ = ["GeometryGuard"]


@njit(cache=True)
def _swept_box(p0: FloatArray, p1: FloatArray, grow: float) -> FloatArray:
    """(6,) ``lo, hi`` corners of the box around every end point of
    ``p0, p1`` (N, S, 3), grown by ``grow`` (the minima and maxima of
    ``np.minimum(p0.min((0, 1)), p1.min((0, 1)))`` and its max twin, exactly)."""
    out = np.empty(6)
    for r in range(3):
        out[r] = np.inf
        out[3 + r] = -np.inf
    n, m = p0.shape[0], p0.shape[1]
    for i in range(n):
        for j in range(m):
            for r in range(3):
                a, b = p0[i, j, r], p1[i, j, r]
                lo = a if a < b else b
                hi = a if a > b else b
                if lo < out[r]:
                    out[r] = lo
                if hi > out[3 + r]:
                    out[3 + r] = hi
    for r in range(3):
        out[r] -= grow
        out[3 + r] += grow
    return out


class GeometryGuard:
    """The coordinator's geometric check (S2.6, S2.12) before an arm moves.

    The coordinator knows every trajectory it sent and where every standing
    arm is (its book of the arms' reports,
    :class:`~workcell.sim.protocol.exchange.ArmView`). Before an arm sets off towards its next
    station it checks that motion, sampled every ``dt`` seconds, against
    every other arm: a standing arm where it stands, a moving arm along its
    trajectory until its own next station (where it may stop; it is checked
    again before it goes on), over the time until every one of them has
    reached its next station. The test is the conservative capsule test of
    the zone sweep (every shape inside a capsule, grown by ``padding``),
    whose candidates FCL decides with the shapes grown by ``padding / 2``.
    A contact means *stop*: the arm waits at its station until the way is
    clear.

    Parameters
    ----------
    compiled : CompiledCell
    dt : float
        Seconds between samples.
    padding : float
        Metres added around every shape.
    clock : callable
        ``clock()`` -> the simulated time now, seconds.
    answer : callable, optional
        ``answer(mover, book) -> indices`` (``mover`` and the book's
        entries :class:`~workcell.sim.protocol.exchange.ArmView`, the mover
        in its own place in the book), asked in place of the check
        (:attr:`~workcell.sim.harness.options.SimOptions.guard_answer`:
        an ablation for tests).
    """

    def __init__(
        self,
        compiled: CompiledCell,
        dt: float = 0.01,
        padding: float = 0.02,
        clock: Callable[[], float] = lambda: 0.0,
        answer: Callable[[ArmView, Sequence[ArmView]], Sequence[int]] | None = None,
    ) -> None:
        self.clock = clock
        self.answer = answer
        cell = compiled.cell
        self.cell = cell
        self.dt = float(dt)
        self.padding = float(padding)
        self.capsules = [_shape_capsules(arm.shapes) for arm in cell.arms]
        # per arm: each shape's frame and its capsule's homogeneous end points
        # in that frame (constant: computed once, as _segments would each time)
        self._frames_of: list[tuple[Any, FloatArray]] = []
        for arm, (local, _r) in zip(cell.arms, self.capsules, strict=True):
            idx, off = shape_frames(arm)
            hw = np.einsum(
                "sij,skj->ski", off, np.concatenate([local, np.ones((len(local), 2, 1))], 2)
            )
            self._frames_of.append((idx, np.ascontiguousarray(hw)))
        self._reach = [float(r.max()) if len(r) else 0.0 for _l, r in self.capsules]
        self._boxes: dict[int, tuple[FloatArray, Any, tuple[float, ...]]] = {}
        self.world = CollisionWorld()
        for arm, q in zip(cell.arms, cell.start, strict=True):
            self.world.add_arm(arm, q=q, padding=self.padding / 2)
        self.checks = 0

    def _box(self, ctl: ArmView) -> FloatArray:
        """(2, 3) box holding everything the arm may sweep on its current leg
        (or where it stands), grown by the padding; cached per leg."""
        leg = ctl.leg
        key = id(leg) if leg is not None else -1 - ctl.index
        got = self._boxes.get(key)
        if got is not None and (leg is not None or got[1] is ctl.q):
            return got[0]
        arm = self.cell.arms[ctl.index]
        if leg is None:
            q = ctl.q[None, :]
            margin = 0.0
        else:
            tr = leg.trajectory
            t = np.union1d(tr.knot_times, np.arange(0.0, tr.duration, 0.02))
            q = tr.sample(t)
            step = arm.displacement_bound(np.diff(q, axis=0)) if len(q) > 1 else np.zeros(1)
            margin = float(step.max()) / 2 if len(step) else 0.0
        p0, p1 = self._ends(ctl.index, q)
        r = float(self.capsules[ctl.index][1].max()) + self.padding + margin
        box = np.stack(
            [
                np.minimum(p0.min(axis=(0, 1)), p1.min(axis=(0, 1))) - r,
                np.maximum(p0.max(axis=(0, 1)), p1.max(axis=(0, 1))) + r,
            ]
        )
        self._boxes[key] = (box, leg if leg is not None else ctl.q, tuple(box.ravel().tolist()))
        return box

    def _box_floats(self, ctl: ArmView) -> tuple[float, ...]:
        """:meth:`_box` as six floats ``(x0, y0, z0, x1, y1, z1)``."""
        leg = ctl.leg
        got = self._boxes.get(id(leg) if leg is not None else -1 - ctl.index)
        if got is not None and (leg is not None or got[1] is ctl.q):
            return got[2]
        self._box(ctl)
        return self._boxes[id(leg) if leg is not None else -1 - ctl.index][2]

    def _ends(self, a: int, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """World end points (N, S, 3) of arm ``a``'s capsule segments at joints ``q``
        (:func:`workcell.geometry.zone_sweep._segments` with the constant part kept)."""
        idx, hw = self._frames_of[a]
        fr = np.ascontiguousarray(self.cell.arms[a].frames(np.atleast_2d(q)), dtype=float)
        pts = segment_points(fr, idx, hw)
        return pts[0], pts[1]

    def blockers(self, mover: ArmView, arms: Sequence[ArmView]) -> list[int]:
        """Arms in the way of ``mover``'s motion to its next station
        (``arms``: every arm's view, ``mover`` among them)."""
        if self.answer is not None:
            self.checks += 1
            return [int(b) for b in self.answer(mover, arms)]
        leg = mover.leg
        if leg is None:
            return []
        tau0 = mover.tau
        tau1 = leg.stations[mover.k].tau
        dur = tau1 - tau0
        if dur <= 0:
            return []
        self.checks += 1
        mx0, my0, mz0, mx1, my1, mz1 = self._box_floats(mover)
        near = []
        for o in arms:
            if o.index == mover.index:
                continue
            ox0, oy0, oz0, ox1, oy1, oz1 = self._box_floats(o)
            if (
                ox0 <= mx1
                and oy0 <= my1
                and oz0 <= mz1
                and ox1 >= mx0
                and oy1 >= my0
                and oz1 >= mz0
            ):
                near.append(o)
        if not near:
            return []
        now = self.clock()
        # until the mover and every moving arm near it reach their next stations
        horizon = max([dur] + [o.next_stop_time(now) - now for o in near if o.running])
        n = max(2, math.ceil(horizon / self.dt) + 1)
        off = np.arange(n, dtype=float) * (horizon / (n - 1))  # np.linspace(0, horizon, n)
        off[-1] = horizon
        times = now + off
        qa = leg.trajectory.sample(np.minimum(tau0 + off, tau1))
        a0, a1 = self._ends(mover.index, qa)
        ra = self.capsules[mover.index][1]
        out = []
        reach = self._reach[mover.index] + self.padding
        lx0, ly0, lz0, hx1, hy1, hz1 = _swept_box(a0, a1, reach).tolist()
        for other in near:
            # a standing arm is sampled once
            qb = other.predict(times if other.running else times[:1], now)
            b0, b1 = self._ends(other.index, qb)
            rb = self.capsules[other.index][1]
            bx0, by0, bz0, bx1, by1, bz1 = _swept_box(b0, b1, self._reach[other.index]).tolist()
            if bx0 > hx1 or by0 > hy1 or bz0 > hz1 or bx1 < lx0 or by1 < ly0 or bz1 < lz0:
                continue  # swept boxes apart
            if other.running:
                d = _segment_distances(
                    a0[:, :, None, :], a1[:, :, None, :], b0[:, None, :, :], b1[:, None, :, :]
                )
                hit = np.any(d <= ra[:, None] + rb[None, :] + self.padding, axis=(1, 2))
            else:  # a standing arm: the compiled test against fixed capsules
                hit = capsules_touch(
                    np.ascontiguousarray(a0),
                    np.ascontiguousarray(a1),
                    np.ascontiguousarray(ra, dtype=float),
                    np.ascontiguousarray(b0[0]),
                    np.ascontiguousarray(b1[0]),
                    np.ascontiguousarray(rb, dtype=float),
                    self.padding,
                )
            if hit.any() and self._confirm(mover.index, qa, other, times, now, hit):
                out.append(other.index)
        return out

    def _confirm(
        self,
        a: int,
        qa: FloatArray,
        other: ArmView,
        times: FloatArray,
        now: float,
        near: FloatArray,
    ) -> bool:
        """FCL (shapes grown by half the padding) on the capsule test's candidates."""
        idx = np.flatnonzero(near)
        arm_a, arm_b = self.cell.arms[a], self.cell.arms[other.index]
        tfa = arm_a.shape_transforms(qa[idx])
        tfb = arm_b.shape_transforms(other.predict(times[idx], now))
        if len(tfb) < len(idx):  # pragma: no cover - predict keeps the length
            tfb = np.repeat(tfb[:1], len(idx), axis=0)
        for i in range(len(idx)):
            self.world.set_group_transforms(arm_a.name, tfa[i])
            self.world.set_group_transforms(arm_b.name, tfb[i])
            if self.world.collide(arm_a.name, arm_b.name):
                return True
        return False
