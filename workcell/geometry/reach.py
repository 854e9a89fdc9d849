"""Where two arms can meet: the space-grid zones of the compile.

Zones (SDL) and the parked-arm oracle keep arms apart only where the cell's
author drew a zone or an arm stands still. Two arms *moving* at the same time
can still meet outside every zone (two gantry bridges on one rail, two SCARA
elbows over a shared table). To rule that out at planning time, the compile
cuts the space where at least two arms can reach into cubic **blocks** and
makes each block that two or more arms' modes touch an implicit exclusive
zone (named ``grid_i_j_k``, :func:`block_name`). Each mode gets the block's occupancy windows from
the same conservative sweep as the SDL zones
(:func:`workcell.geometry.zone_sweep.zone_contacts`). Two arms can only touch at a
point that lies in some block, and then both occupy that block at that time,
which the scheduler never allows: so two arms never meet, whatever they do
between samples (the sweep's guarantee). Coarser blocks give fewer zones and
a faster search but keep apart some modes that would pass each other: the
S2.12 speed/accuracy compromise of a coarser space grid (SEEDS.md S2.5,
S2.6, S2.12).

Examples
--------
>>> import numpy as np
>>> boxes = [np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.5]]), np.array([[0.8, 0.0, 0.0], [2.0, 1.0, 0.5]])]
>>> zm = shared_blocks(boxes, 0.25)
>>> zm.n_zones  # where both boxes reach, x in [0.8, 1.0]: 2 x 5 x 3 blocks
30
>>> zm.zone_names()[0]
'grid_3_0_0'
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import BoolArray, FloatArray
from workcell.arms.base import Arm
from workcell.geometry.zone_sweep import _runs, _segments, _shape_capsules
from zones.geometry import AABox
from zones.model import Zone, ZoneMap

__all__ = [
    "arm_capsules",
    "block_bounds",
    "block_name",
    "capsules_box",
    "grid_block",
    "shared_blocks",
    "windows_from_flags",
]

MAX_BLOCKS = 20_000
"""Refuse grids with more blocks than this (a block size far too small for the cell)."""


def arm_capsules(arm: Arm, q: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """World capsules of ``arm``'s shapes at each row of ``q`` (N, dof).

    Returns
    -------
    p0, p1 : (N, S, 3) float, metres
        Segment end points.
    rad : (S,) float, metres
        Radii (each shape's bounding capsule, as in the zone sweep).
    """
    local, rad = _shape_capsules(arm.shapes)
    p0, p1 = _segments(arm, np.atleast_2d(np.asarray(q, dtype=float)), local)
    return p0, p1, rad


def capsules_box(p0: FloatArray, p1: FloatArray, rad: FloatArray, grow: float) -> FloatArray:
    """(2, 3) lower/upper corner holding capsules ``(p0, p1, rad)`` grown by ``grow``."""
    g = (rad + grow)[None, :, None]
    lo = np.minimum(p0, p1) - g
    hi = np.maximum(p0, p1) + g
    return np.stack([lo.min(axis=(0, 1)), hi.max(axis=(0, 1))])


def windows_from_flags(t: FloatArray, flags: BoolArray) -> tuple[tuple[float, float], ...]:
    """Occupancy intervals from per-sample flags: an interval between two
    samples is in when either end is flagged (the sweep's rule)."""
    if len(t) == 1:
        return ((float(t[0]), float(t[0])),) if bool(flags[0]) else ()
    interval = flags[:-1] | flags[1:]
    return tuple((float(t[a]), float(t[b])) for a, b in _runs(interval))


def block_name(x: int, y: int, z: int) -> str:
    """The zone name of block ``(x, y, z)``: ``grid_X_Y_Z``, ``m`` for a minus sign.

    Examples
    --------
    >>> block_name(3, -1, 0)
    'grid_3_m1_0'
    """
    return f"grid_{x}_{y}_{z}".replace("-", "m")


_BLOCK = re.compile(r"grid_(m?\d+)_(m?\d+)_(m?\d+)")

Point = tuple[float, float, float]


def grid_block(name: str) -> tuple[int, int, int] | None:
    """The grid index ``(x, y, z)`` of a space-grid zone's name, None for any other zone.

    The inverse of :func:`workcell.geometry.reach.block_name` (``m`` is a minus sign).
    """
    m = _BLOCK.fullmatch(str(name))
    if m is None:
        return None
    x, y, z = (int(g.replace("m", "-")) for g in m.groups())
    return x, y, z


def _grid_size(size: float | None) -> float:
    if size is None:
        from workcell.compiled import SPACE_GRID

        return float(SPACE_GRID)
    if not (math.isfinite(size) and size > 0):
        raise ValidationError(f"space grid: block size must be > 0 m, got {size}")
    return float(size)


def block_bounds(name: str, size: float | None = None) -> tuple[Point, Point]:
    """Lower and upper corner (metres) of a space-grid block.

    Parameters
    ----------
    name : str
        ``grid_X_Y_Z``.
    size : float, optional
        Block side, metres (default :data:`workcell.compiled.SPACE_GRID`,
        the compile's; the grid is aligned with the origin).

    Raises
    ------
    multiarm.errors.ValidationError
        When ``name`` is not a space-grid block's.
    """
    idx = grid_block(name)
    if idx is None:
        raise ValidationError(f"{name!r} is not a space-grid block (grid_X_Y_Z)")
    s = _grid_size(size)
    lo = tuple(float(round(i * s, 9)) for i in idx)
    hi = tuple(float(round((i + 1) * s, 9)) for i in idx)
    return lo, hi  # type: ignore[return-value]


def shared_blocks(boxes: Sequence[FloatArray], size: float) -> ZoneMap:
    """Blocks of side ``size`` covering every region two of ``boxes`` share.

    Parameters
    ----------
    boxes : sequence of (2, 3) float
        Per arm, a box holding everything the arm may occupy (lower, upper
        corner), metres.
    size : float, metres
        Block side.

    Returns
    -------
    zones.ZoneMap
        One exclusive box zone per block that lies in the intersection of at
        least two of the boxes, named by its grid index (:func:`block_name`); the
        grid is aligned with the origin.

    Raises
    ------
    multiarm.errors.ValidationError
        For a size that is not positive or a grid of more than
        :data:`MAX_BLOCKS` blocks.
    """
    if not (math.isfinite(size) and size > 0):
        raise ValidationError(f"space grid: block size must be > 0 m, got {size}")
    keys: set[tuple[int, int, int]] = set()
    bs = [np.asarray(b, dtype=float) for b in boxes]
    for i in range(len(bs)):
        for j in range(i + 1, len(bs)):
            lo = np.maximum(bs[i][0], bs[j][0])
            hi = np.minimum(bs[i][1], bs[j][1])
            if np.any(hi < lo):
                continue
            with np.errstate(over="ignore", invalid="ignore"):  # in floats: no int64 overflow
                f0, f1 = np.floor(lo / size), np.floor(hi / size)
                span = float(np.prod(f1 - f0 + 1))
            if not len(keys) + span <= MAX_BLOCKS:
                raise ValidationError(
                    f"space grid: more than {MAX_BLOCKS} blocks of {size} m; use larger blocks"
                )
            k0, k1 = f0.astype(np.int64), f1.astype(np.int64)
            for x in range(int(k0[0]), int(k1[0]) + 1):
                for y in range(int(k0[1]), int(k1[1]) + 1):
                    for z in range(int(k0[2]), int(k1[2]) + 1):
                        keys.add((x, y, z))
    zones = []
    lows, highs = [], []
    for x, y, z in sorted(keys):
        lo3 = (x * size, y * size, z * size)
        hi3 = ((x + 1) * size, (y + 1) * size, (z + 1) * size)
        zones.append(Zone(block_name(x, y, z), AABox(lo3, hi3), "exclusive"))
        lows.append(lo3)
        highs.append(hi3)
    bounds: tuple[tuple[float, ...], tuple[float, ...]] = (
        (tuple(np.min(lows, axis=0).tolist()), tuple(np.max(highs, axis=0).tolist()))
        if zones
        else ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    )
    return ZoneMap(bounds, tuple(zones))  # type: ignore[arg-type]
