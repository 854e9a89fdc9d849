"""Which arms may ever meet (distributed coordination, S2.4, S2.12).

Every station holds the compiled cell, so every peer derives the same sets
once: the peers a peer tells where its arm is and asks before its arm sets
off (:mod:`.sight`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from multiarm.types import FloatArray

if TYPE_CHECKING:
    from workcell.compile import CompiledCell

__all__ = ["may_meet"]


def may_meet(compiled: CompiledCell, padding: float = 0.02) -> list[frozenset[int]]:
    """Per arm, the other arms it may ever touch (derived once from the cell).

    Each arm's shapes, at its start joints, lie in a ball (about its base's
    origin, or about the shapes' centroid, whichever is smaller). Any pose
    within the joint limits moves no shape point farther than the arm's
    :meth:`~workcell.arms.base.Arm.displacement_bound` of the largest joint
    change the limits allow, a revolute joint's counted at most 2 radians
    (a turn moves a point at most twice its distance from the axis, and
    every arm's bound is that distance times the turn, joint by joint). So
    every pose of the arm lies in the ball grown by that (and by
    ``padding``, the geometric check's). Two arms whose balls do not meet
    can never touch, whatever either does (a detour and a back-off stay
    within the limits too); an arm with a prismatic joint without finite
    limits may meet every arm.

    Returns
    -------
    list of frozenset of int
        Symmetric: ``b in out[a]`` iff ``a in out[b]``.
    """
    cell = compiled.cell
    balls: list[tuple[FloatArray, float]] = []
    for arm, q0 in zip(cell.arms, cell.start, strict=True):
        q = np.asarray(q0, dtype=float)
        lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
        span = np.maximum(np.abs(hi - q), np.abs(q - lo))
        turn = np.array([k == "revolute" for k in arm.joint_kinds], dtype=bool)
        span = np.where(turn, np.minimum(span, 2.0), span)
        grow = (
            float(arm.displacement_bound(span[None, :])[0])
            if np.all(np.isfinite(span))
            else math.inf
        )
        centres = arm.shape_transforms(q[None, :])[0][:, :3, 3]
        radii = np.array([s.radius() for s in arm.shapes], dtype=float)
        best: tuple[FloatArray, float] = (np.zeros(3), 0.0)
        if len(radii):
            options = [np.asarray(arm.base, dtype=float)[:3, 3], centres.mean(axis=0)]
            best = min(
                ((c, float(np.max(np.linalg.norm(centres - c, axis=1) + radii))) for c in options),
                key=lambda x: x[1],
            )
        balls.append((best[0], best[1] + grow + padding))
    n = len(balls)
    out: list[set[int]] = [set() for _ in range(n)]
    for a in range(n):
        for b in range(a + 1, n):
            (ca, ra), (cb, rb) = balls[a], balls[b]
            if float(np.linalg.norm(ca - cb)) <= ra + rb:
                out[a].add(b)
                out[b].add(a)
    return [frozenset(s) for s in out]
