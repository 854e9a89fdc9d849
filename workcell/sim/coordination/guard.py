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
from workcell.geometry.zone_sweep import _shape_capsules
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


@njit(cache=True)
def _first_touch(
    a0: FloatArray,
    a1: FloatArray,
    ra: FloatArray,
    box: FloatArray,
    b0: FloatArray,
    b1: FloatArray,
    boxes: FloatArray,
    rb: FloatArray,
    padding: float,
    j0: int,
) -> tuple[int, Any]:
    """The first pose ``j >= j0`` of the other arm (capsule end points ``b0,
    b1`` (M, S, 3), boxes (M, 6)) whose box meets the mover's swept ``box``
    (6,) and which some sample of the mover (``a0, a1`` (N, S, 3)) touches
    (:func:`~workcell.geometry._zone_sweep_jit.capsules_touch`), with the
    samples that touch it ((N,) bool); ``(-1, empty)`` if none."""
    for j in range(j0, boxes.shape[0]):
        if (
            boxes[j, 0] <= box[3]
            and boxes[j, 1] <= box[4]
            and boxes[j, 2] <= box[5]
            and boxes[j, 3] >= box[0]
            and boxes[j, 4] >= box[1]
            and boxes[j, 5] >= box[2]
        ):
            hit = capsules_touch(a0, a1, ra, b0[j], b1[j], rb, padding)
            if hit.any():
                return j, hit
    return -1, np.zeros(0, dtype=np.bool_)


class GeometryGuard:
    """The coordinator's geometric check (S2.6, S2.12) before an arm moves.

    The coordinator knows every trajectory it sent and where every standing
    arm is (its book of the arms' reports,
    :class:`~workcell.sim.protocol.exchange.ArmView`). Before an arm sets off towards its next
    station it checks that motion, sampled every ``dt`` seconds, against
    every other arm, whatever the time (:meth:`blockers`): a standing arm
    where it stands, an arm that may be moving (its last report says so,
    or a departure cleared for it is not yet acknowledged) anywhere on what
    is left of its leg up to its next station (it cannot pass that station
    without being cleared again). The book is one medium delay old, so the
    check never relies on when an arm is where: the answer stays right
    whatever happened since (an arm stopped by a crash or an alarm stops on
    the stretch already reserved). The test is the conservative capsule test of
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
        self._radii = [np.ascontiguousarray(r, dtype=float) for _l, r in self.capsules]
        self._boxes: dict[int, tuple[FloatArray, Any, tuple[float, ...]]] = {}
        self._segments: dict[tuple[int, int, float], tuple[Any, Any]] = {}
        self._standing: dict[tuple[int, int, float], tuple[Any, Any]] = {}
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

    def blockers(
        self, mover: ArmView, arms: Sequence[ArmView], extra: Sequence[ArmView] = ()
    ) -> list[int]:
        """Arms in the way of ``mover``'s motion to its next station.

        ``arms``: every arm's view as the book has it, ``mover`` among them;
        ``extra``: further views the other arms may be in (the motions the
        coordination cleared and has not heard the start or the end of).
        A standing view is checked where it stands; a moving one
        (``running``) anywhere on what is left of its leg up to its next
        station, whatever the time (it may have stopped anywhere there, or
        be late, by the medium's delay). The mover's own motion is checked
        whatever the time too: its start is one medium delay away."""
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
        for o in (*arms, *extra):
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
        n = max(2, math.ceil(dur / self.dt) + 1)
        off = np.arange(n, dtype=float) * (dur / (n - 1))  # np.linspace(0, dur, n)
        off[-1] = dur
        qa = leg.trajectory.sample(np.minimum(tau0 + off, tau1))
        a0, a1 = self._ends(mover.index, qa)
        a0 = np.ascontiguousarray(a0)
        a1 = np.ascontiguousarray(a1)
        ra = self._radii[mover.index]
        out: list[int] = []
        reach = self._reach[mover.index] + self.padding
        box = _swept_box(a0, a1, reach)
        for other in near:
            if other.index in out:
                continue
            qb, b0, b1, boxes = self._poses(other)
            rb = self._radii[other.index]
            j = 0
            while True:
                j, hit = _first_touch(a0, a1, ra, box, b0, b1, boxes, rb, self.padding, j)
                if j < 0:
                    break
                if self._confirm(mover.index, qa[hit], other.index, qb[j]):
                    out.append(other.index)
                    break
                j += 1
        return out

    def _poses(self, view: ArmView) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Where arm ``view.index`` may be: its joints (M, dof), its capsule
        end points (M, S, 3) twice and each pose's box (M, 6) grown by its
        reach. A standing arm: one pose; a moving one: its leg from
        ``view.tau`` to its next station, every ``dt`` seconds (cached per
        leg, start and station)."""
        leg = view.leg
        if leg is None or not view.running:
            # standing: at ``q`` (idle) or at ``tau`` on its leg (cached per place)
            where: Any = view.q if leg is None else leg
            skey = (view.index, id(where), -1.0 if leg is None else view.tau)
            got = self._standing.get(skey)
            if got is not None and got[0] is where:
                standing: tuple[FloatArray, FloatArray, FloatArray, FloatArray] = got[1]
                return standing
            q = view.q[None, :] if leg is None else leg.trajectory.sample(np.array([view.tau]))
            out = self._pose_set(view.index, q)
            if len(self._standing) > 4096:
                self._standing.clear()
            self._standing[skey] = (where, out)
            return out
        key = (id(leg), view.k, view.tau)
        got = self._segments.get(key)
        if got is not None and got[0] is leg:
            cached: tuple[FloatArray, FloatArray, FloatArray, FloatArray] = got[1]
            return cached
        tau1 = float(leg.stations[view.k].tau)
        tau0 = min(float(view.tau), tau1)
        taus = np.append(np.arange(tau0, tau1, self.dt), tau1)
        out = self._pose_set(view.index, leg.trajectory.sample(taus))
        if len(self._segments) > 4096:
            self._segments.clear()
        self._segments[key] = (leg, out)
        return out

    def _pose_set(
        self, a: int, q: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        b0, b1 = self._ends(a, q)
        r = self._reach[a]
        lo = np.minimum(b0.min(axis=1), b1.min(axis=1)) - r
        hi = np.maximum(b0.max(axis=1), b1.max(axis=1)) + r
        return (
            q,
            np.ascontiguousarray(b0),
            np.ascontiguousarray(b1),
            np.ascontiguousarray(np.concatenate([lo, hi], axis=1)),
        )

    def _confirm(self, a: int, qa: FloatArray, b: int, qb: FloatArray) -> bool:
        """FCL (shapes grown by half the padding) on the capsule test's
        candidates: arm ``a`` at each of ``qa`` against arm ``b`` at ``qb``."""
        arm_a, arm_b = self.cell.arms[a], self.cell.arms[b]
        tfa = arm_a.shape_transforms(qa)
        self.world.set_group_transforms(arm_b.name, arm_b.shape_transforms(qb[None, :])[0])
        for i in range(len(qa)):
            self.world.set_group_transforms(arm_a.name, tfa[i])
            if self.world.collide(arm_a.name, arm_b.name):
                return True
        return False
