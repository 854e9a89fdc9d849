"""The coordinator's geometric check before an arm moves (S2.6, S2.12)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from multiarm.types import FloatArray
from workcell.compile import CompiledCell
from workcell.geometry import CollisionWorld
from workcell.geometry._zone_sweep_jit import capsules_touch
from workcell.geometry.zone_sweep import _segment_distances, _segments, _shape_capsules
from workcell.sim.protocol.ports import ArmPort

__all__ = ["GeometryGuard"]


class GeometryGuard:
    """The coordinator's geometric check (S2.6, S2.12) before an arm moves.

    The coordinator knows every trajectory it sent and where every standing
    arm is (position reports). Before an arm sets off towards its next
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
        ``answer(mover, arms) -> indices``, asked in place of the check
        (:attr:`~workcell.sim.harness.options.SimOptions.guard_answer`:
        an ablation for tests).
    """

    def __init__(
        self,
        compiled: CompiledCell,
        dt: float = 0.01,
        padding: float = 0.02,
        clock: Callable[[], float] = lambda: 0.0,
        answer: Callable[[ArmPort, Sequence[ArmPort]], Sequence[int]] | None = None,
    ) -> None:
        self.clock = clock
        self.answer = answer
        cell = compiled.cell
        self.cell = cell
        self.dt = float(dt)
        self.padding = float(padding)
        self.capsules = [_shape_capsules(arm.shapes) for arm in cell.arms]
        self._boxes: dict[int, tuple[FloatArray, Any]] = {}
        self.world = CollisionWorld()
        for arm, q in zip(cell.arms, cell.start, strict=True):
            self.world.add_arm(arm, q=q, padding=self.padding / 2)
        self.checks = 0

    def _box(self, ctl: ArmPort) -> FloatArray:
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
        self._boxes[key] = (box, leg if leg is not None else ctl.q)
        return box

    def _ends(self, a: int, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        return _segments(self.cell.arms[a], q, self.capsules[a][0])

    def blockers(self, mover: ArmPort, arms: list[ArmPort]) -> list[int]:
        """Arms in the way of ``mover``'s motion to its next station."""
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
        (mx0, my0, mz0), (mx1, my1, mz1) = self._box(mover).tolist()
        near = []
        for o in arms:
            if o is mover:
                continue
            (ox0, oy0, oz0), (ox1, oy1, oz1) = self._box(o).tolist()
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
        horizon = max([dur] + [o.next_stop_time() - now for o in near if o.running])
        n = max(2, math.ceil(horizon / self.dt) + 1)
        off = np.linspace(0.0, horizon, n)
        times = now + off
        qa = leg.trajectory.sample(np.minimum(tau0 + off, tau1))
        a0, a1 = self._ends(mover.index, qa)
        ra = self.capsules[mover.index][1]
        out = []
        reach = float(ra.max()) + self.padding
        lo = np.minimum(a0.min(axis=(0, 1)), a1.min(axis=(0, 1))) - reach
        hi = np.maximum(a0.max(axis=(0, 1)), a1.max(axis=(0, 1))) + reach
        for other in near:
            # a standing arm is sampled once
            qb = other.predict(times if other.running else times[:1])
            b0, b1 = self._ends(other.index, qb)
            rb = self.capsules[other.index][1]
            rmax = float(rb.max())
            blo = np.minimum(b0.min(axis=(0, 1)), b1.min(axis=(0, 1))) - rmax
            bhi = np.maximum(b0.max(axis=(0, 1)), b1.max(axis=(0, 1))) + rmax
            if np.any(blo > hi) or np.any(bhi < lo):
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
            if hit.any() and self._confirm(mover.index, qa, other.index, other, times, hit):
                out.append(other.index)
        return out

    def _confirm(
        self,
        a: int,
        qa: FloatArray,
        b: int,
        other: ArmPort,
        times: FloatArray,
        near: FloatArray,
    ) -> bool:
        """FCL (shapes grown by half the padding) on the capsule test's candidates."""
        idx = np.flatnonzero(near)
        arm_a, arm_b = self.cell.arms[a], self.cell.arms[b]
        tfa = arm_a.shape_transforms(qa[idx])
        tfb = arm_b.shape_transforms(other.predict(times[idx]))
        if len(tfb) < len(idx):  # pragma: no cover - predict keeps the length
            tfb = np.repeat(tfb[:1], len(idx), axis=0)
        for i in range(len(idx)):
            self.world.set_group_transforms(arm_a.name, tfa[i])
            self.world.set_group_transforms(arm_b.name, tfb[i])
            if self.world.collide(arm_a.name, arm_b.name):
                return True
        return False
