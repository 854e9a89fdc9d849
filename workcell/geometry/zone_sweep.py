"""Conservative sweep of an arm's collision shapes through the zones -> zone windows.

For a trajectory of one arm, :func:`zone_windows` finds every zone the arm's
shapes touch and, per zone, the **occupancy windows** (intervals of time,
from the trajectory's start, during which the arm may be inside) and the
**moving windows** (their intersection with the trajectory's motion
intervals): the data the scheduler needs for exclusive and
restricted-simultaneous zones (SEEDS.md S2.5, S2.12; DESIGN.md "Data flow").

Why it never misses a contact
-----------------------------
Samples start from the trajectory's knot times plus a uniform grid; every
sample interval ``[t_i, t_i+1]`` is bisected until
``arm.displacement_bound(q(t_i+1) - q(t_i)) <= padding``; at every sample the
arm's shapes grown by ``padding`` are tested against every zone.

Suppose some point of a shape lies inside zone ``Z`` at a time ``t`` in
``[t_i, t_i+1]``; call it ``x(t)``. The samples include every knot, so the
interval lies inside one knot segment, where every joint moves monotonically;
hence for every joint ``|q_j(t) - q_j(t_i)| <= |q_j(t_i+1) - q_j(t_i)|``. The
displacement bound is a sum of per-joint terms ``|dq_j| * reach_j`` that holds
along any monotone joint path (``workcell.arms.base``), so the same material
point moved at most ``bound(q(t) - q(t_i)) <= bound(q(t_i+1) - q(t_i)) <=
padding`` between ``t_i`` and ``t``: ``x(t_i)`` is a point of the shape at
``t_i`` within ``padding`` of ``x(t)``, so the shape grown by ``padding`` at
``t_i`` contains ``x(t)`` and touches ``Z``. The same argument from
``t_i+1`` backwards shows the grown shape touches ``Z`` at ``t_i+1`` too.
So a contact anywhere in an interval flags **both** of its end samples. We
mark an interval occupied when **either** end is flagged (more than needed,
which keeps every flagged sample inside a closed window), so the occupancy
windows cover every true contact time. The vectorised tests below replace
each grown shape by a superset (a bounding capsule) and each zone solid by a
superset of its ``padding``-neighbourhood, so they can only add contacts,
never lose one.

Geometry of the vectorised path
-------------------------------
Every arm shape is replaced by a *capsule* ``(segment, radius)`` that holds
it (capsules and spheres exactly; a cylinder by the capsule on its axis; a
box by the capsule along its longest side whose radius is the half-diagonal
of the other two sides). A capsule of radius ``R`` touches a solid iff its
segment meets the solid grown by ``R``; we test the segment against a
superset of that grown solid:

* sphere zone: exact (segment-point distance <= ``r + R``);
* box zone: the box with every half side grown by ``R`` (slab test);
* cylinder zone: radius and half height grown by ``R`` (exact segment vs
  finite cylinder);
* convex zone (``Hull``, walls): every face plane pushed out by ``R``
  (Cyrus-Beck clipping).

Mesh zones go through FCL (:mod:`workcell.geometry.world`), one sample at a
time: the grown shapes against the mesh surface, plus "shape centre inside
the mesh" and "a mesh vertex inside the shape's capsule" for containment.

The tests run over samples x shapes x zone solids in a compiled loop
(:mod:`workcell.geometry._zone_sweep_jit`, numba) that skips a zone once a sample
touches it; the vectorised numpy versions are kept as the reference the tests
compare it with.

Examples
--------
>>> import numpy as np
>>> from zones import AABox, Zone, ZoneMap
>>> from tests.workcell.geometry.fake_arm import PlanarArm, ProfileTrajectory
>>> arm = PlanarArm()           # two capsule links (0.4 m, 0.3 m) about z at the origin
>>> zm = ZoneMap(((-1, -1, 0), (1, 1, 1)), (Zone("bin", AABox((0.5, 0.3, 0), (0.8, 0.6, 0.3))),))
>>> traj = ProfileTrajectory(np.array([[0.0, 0.0], [1.2, 0.0], [1.2, 0.0]]), np.array([0, 2.0, 3.0]))
>>> w = zone_windows(arm, traj, zm)
>>> w.zones
('bin',)
>>> win = w["bin"]
>>> 0.0 < win.occupied[0][0] < win.occupied[0][1] < 2.0
True
>>> static_occupancy(arm, np.array([0.6, 0.0]), zm)
('bin',)
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from multiarm.errors import UsageError, ValidationError
from multiarm.types import BoolArray, FloatArray, IntArray
from workcell.arms.base import Arm, LinkShape, shape_frames
from workcell.geometry._zone_sweep_jit import capsules_touch, contacts_block, segment_points
from workcell.geometry.world import CollisionWorld
from zones.geometry import Primitive
from zones.model import ZoneMap

__all__ = [
    "JointTrajectoryLike",
    "ZoneWindow",
    "ZoneWindows",
    "aabbs_overlap",
    "arm_contacts",
    "reference_contacts",
    "sample_trajectory",
    "static_occupancy",
    "swept_aabb",
    "zone_contacts",
    "zone_windows",
]

_CHUNK = 2048
"""Samples per vectorised block (bounds the temporary arrays)."""

_MAX_ROUNDS = 60
"""Bisection rounds before a trajectory is declared discontinuous."""

_SAMPLES: dict[int, tuple[Any, list[tuple[Any, float, int, FloatArray, FloatArray]]]] = {}
"""The samples of live trajectories by ``id``: (a weak reference to the
trajectory, [(weak reference to the arm, padding, n_grid, t, q)]). The
compile's zone sweep, space grid and parking oracle ask for the same ones."""


class JointTrajectoryLike(Protocol):
    """What the sweep needs of a joint trajectory (``workcell.arms.JointTrajectory``).

    Between two consecutive ``knot_times`` every joint moves monotonically.
    """

    @property
    def duration(self) -> float:
        """Total time, seconds."""
        ...

    @property
    def knot_times(self) -> FloatArray:
        """(K,) float segment boundaries, seconds, including 0 and ``duration``."""
        ...

    def sample(self, t: FloatArray) -> FloatArray:
        """(N, dof) joint vectors at times ``t`` (N,)."""
        ...

    def motion_intervals(self) -> FloatArray:
        """(M, 2) sorted disjoint intervals in which some joint moves."""
        ...


# ------------------------------------------------------------------ records


@dataclass(frozen=True, slots=True)
class ZoneWindow:
    """When one arm may be inside one zone during one trajectory.

    Attributes
    ----------
    zone : str
    zone_id : int
        The zone's dense id in its :class:`zones.ZoneMap`.
    occupied : tuple of (float, float)
        Sorted disjoint closed intervals, seconds from the trajectory's start,
        that hold every instant at which an arm shape touches the zone.
    moving : tuple of (float, float)
        The parts of ``occupied`` inside the trajectory's motion intervals
        (the arm moves inside the zone); dwells are left out.
    """

    zone: str
    zone_id: int
    occupied: tuple[tuple[float, float], ...]
    moving: tuple[tuple[float, float], ...]

    @property
    def start(self) -> float:
        """Start of the first occupancy window, seconds."""
        return self.occupied[0][0]

    @property
    def end(self) -> float:
        """End of the last occupancy window, seconds."""
        return self.occupied[-1][1]


@dataclass(frozen=True, slots=True)
class ZoneWindows:
    """The zone windows of one trajectory (see :func:`zone_windows`).

    Attributes
    ----------
    arm : str
    duration : float
        Trajectory duration, seconds.
    padding : float
        The sweep's padding, metres.
    windows : tuple of ZoneWindow
        One per zone touched, by zone id.
    n_samples : int
        Number of samples the sweep tested.
    """

    arm: str
    duration: float
    padding: float
    windows: tuple[ZoneWindow, ...]
    n_samples: int

    @property
    def zones(self) -> tuple[str, ...]:
        """Names of the zones touched, by zone id."""
        return tuple(w.zone for w in self.windows)

    def get(self, zone: str) -> ZoneWindow | None:
        """The window of ``zone``, or None when the arm never touches it."""
        for w in self.windows:
            if w.zone == zone:
                return w
        return None

    def __getitem__(self, zone: str) -> ZoneWindow:
        w = self.get(zone)
        if w is None:
            raise UsageError(f"arm {self.arm!r} never touches zone {zone!r}")
        return w


# ---------------------------------------------------------------- sampling


def sample_trajectory(
    arm: Arm, traj: JointTrajectoryLike, padding: float = 0.005, n_grid: int = 32
) -> tuple[FloatArray, FloatArray]:
    """Times and joint vectors fine enough for the padding argument.

    Parameters
    ----------
    arm : Arm
    traj : JointTrajectoryLike
    padding : float, metres
        Largest displacement bound allowed between consecutive samples (> 0).
    n_grid : int
        Intervals of the uniform grid added to the knot times.

    Returns
    -------
    t : (M,) float, seconds
        Sorted; includes every knot time.
    q : (M, dof) float
        Both read-only: kept while the trajectory lives and handed to the
        next call with the same trajectory, arm, padding and grid.

    Raises
    ------
    multiarm.errors.ValidationError
        For a non-positive padding, knots outside ``[0, duration]``, or a
        trajectory whose bound does not shrink under bisection (a jump).
    """
    if not (np.isfinite(padding) and padding > 0):
        raise ValidationError(f"arm {arm.name!r}: sweep padding must be > 0 m, got {padding}")
    entry = _SAMPLES.get(id(traj))
    if entry is not None and entry[0]() is traj:
        for arm_ref, pad, grid, t_got, q_got in entry[1]:
            if arm_ref() is arm and pad == padding and grid == n_grid:
                return t_got, q_got
    t, q = _sample(arm, traj, padding, n_grid)
    t.setflags(write=False)
    q.setflags(write=False)
    key = id(traj)
    try:
        traj_ref = weakref.ref(traj, lambda ref: _forget(key, ref))
        arm_ref = weakref.ref(arm)
    except TypeError:  # not weakly referenceable: not kept
        return t, q
    if entry is None or entry[0]() is not traj:
        entry = (traj_ref, [])
        _SAMPLES[key] = entry
    entry[1].append((arm_ref, float(padding), int(n_grid), t, q))
    return t, q


def _forget(key: int, ref: Any) -> None:
    """Drop the samples of a trajectory that died (unless its id is taken anew)."""
    entry = _SAMPLES.get(key)
    if entry is not None and entry[0] is ref:
        del _SAMPLES[key]


def _sample(
    arm: Arm, traj: JointTrajectoryLike, padding: float, n_grid: int
) -> tuple[FloatArray, FloatArray]:
    duration = float(traj.duration)
    knots = np.asarray(traj.knot_times, dtype=float)
    if not np.isfinite(duration) or duration < 0:
        raise ValidationError(f"arm {arm.name!r}: trajectory duration {duration} is not >= 0")
    if knots.size and (knots.min() < -1e-12 or knots.max() > duration + 1e-12):
        raise ValidationError(f"arm {arm.name!r}: knot times leave [0, {duration}]")
    t = np.unique(np.concatenate([knots, np.linspace(0.0, duration, max(1, n_grid) + 1)]))
    t = np.clip(t, 0.0, duration)
    t = np.unique(t)
    q = np.asarray(traj.sample(t), dtype=float)
    for _ in range(_MAX_ROUNDS):
        if len(t) < 2:
            break
        bad = np.flatnonzero(arm.displacement_bound(np.diff(q, axis=0)) > padding)
        if bad.size == 0:
            return t, q
        mids = 0.5 * (t[bad] + t[bad + 1])
        qm = np.asarray(traj.sample(mids), dtype=float)
        t = np.insert(t, bad + 1, mids)
        q = np.insert(q, bad + 1, qm, axis=0)
    else:
        step = arm.displacement_bound(np.diff(q, axis=0))
        i = int(np.argmax(step))
        dq = np.abs(q[i + 1] - q[i])
        j = int(np.argmax(dq))
        raise ValidationError(
            f"arm {arm.name!r}: trajectory does not get finer under bisection "
            f"after {_MAX_ROUNDS} rounds: it jumps by up to {step[i]:.3g} m (more than the "
            f"padding {padding:g} m) at t = {t[i]:.9g} s, joint {j} by {dq[j]:.3g}"
        )
    return t, q


# ---------------------------------------------------------------- geometry


_CAPSULES: dict[int, tuple[tuple[LinkShape, ...], FloatArray, FloatArray]] = {}
"""Bounding capsules by ``id`` of an arm's shapes tuple (the tuple is kept so
the id stays its)."""

_CAPSULES_SIZE = 64


def _shape_capsules(shapes: Sequence[LinkShape]) -> tuple[FloatArray, FloatArray]:
    """Local segment end points (S, 2, 3) and radii (S,) of capsules holding the shapes.

    Built once per shapes tuple (an arm's ``shapes``); the caller gets copies.
    """
    if not isinstance(shapes, tuple):
        return _build_capsules(shapes)
    hit = _CAPSULES.get(id(shapes))
    if hit is None or hit[0] is not shapes:
        ends, rad = _build_capsules(shapes)
        if len(_CAPSULES) >= _CAPSULES_SIZE:
            _CAPSULES.pop(next(iter(_CAPSULES)))
        hit = (shapes, ends, rad)
        _CAPSULES[id(shapes)] = hit
    return hit[1].copy(), hit[2].copy()


def _build_capsules(shapes: Sequence[LinkShape]) -> tuple[FloatArray, FloatArray]:
    ends = np.zeros((len(shapes), 2, 3))
    rad = np.zeros(len(shapes))
    for i, s in enumerate(shapes):
        if s.kind in ("capsule", "cylinder"):
            ends[i, :, 2] = (-s.size[1] / 2, s.size[1] / 2)
            rad[i] = s.size[0]
        elif s.kind == "sphere":
            rad[i] = s.size[0]
        elif s.kind == "box":
            size = np.asarray(s.size, dtype=float)
            k = int(np.argmax(size))
            ends[i, :, k] = (-size[k] / 2, size[k] / 2)
            rad[i] = float(np.linalg.norm(np.delete(size, k))) / 2
        else:
            raise ValidationError(f"shape {s.name!r}: unknown shape kind {s.kind!r}")
    return ends, rad


def _segments(arm: Arm, q: FloatArray, local: FloatArray) -> tuple[FloatArray, FloatArray]:
    """World end points p0, p1 (N, S, 3) of the shapes' capsule segments.

    The end points are carried into their frames once (``offset @ [p, 1]``)
    and moved by the frames in one compiled loop; equal to
    :func:`_segments_numpy` up to the order of floating additions.
    """
    fr = np.ascontiguousarray(arm.frames(np.atleast_2d(q)), dtype=float)
    idx, off = shape_frames(arm)
    hw = np.einsum("sij,skj->ski", off, np.concatenate([local, np.ones((len(local), 2, 1))], 2))
    pts = segment_points(fr, idx, np.ascontiguousarray(hw))
    return pts[0], pts[1]


def _segments_numpy(arm: Arm, q: FloatArray, local: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The numpy version of :func:`_segments` (the tests' reference)."""
    fr = arm.frames(np.atleast_2d(q))
    idx, off = shape_frames(arm)
    tf = np.matmul(fr[:, idx], off)
    rot, trans = tf[..., :3, :3], tf[..., :3, 3]
    p0 = np.matmul(rot, local[:, 0, :, None])[..., 0] + trans
    p1 = np.matmul(rot, local[:, 1, :, None])[..., 0] + trans
    return p0, p1


def _slab(p0: FloatArray, d: FloatArray, half: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Parameter range [lo, hi] of ``p0 + t d`` inside ``|x_k| <= half_k`` (t free)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        inv = 1.0 / d
        a = (-half - p0) * inv
        b = (half - p0) * inv
    flat = np.abs(d) < 1e-15
    inside = np.abs(p0) <= half
    lo = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(a, b))
    hi = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(a, b))
    return lo.max(axis=-1), hi.min(axis=-1)


@dataclass(frozen=True, slots=True)
class _Solids:
    """Zone solids grouped by kind, in arrays (one row per primitive)."""

    sph_c: FloatArray  # (Ps, 3)
    sph_r: FloatArray  # (Ps,)
    sph_z: IntArray
    box_r: FloatArray  # (Pb, 3, 3) rotation (local -> world)
    box_c: FloatArray  # (Pb, 3)
    box_h: FloatArray  # (Pb, 3) half sides
    box_z: IntArray
    cyl_r: FloatArray
    cyl_c: FloatArray
    cyl_rad: FloatArray
    cyl_h: FloatArray  # half heights
    cyl_z: IntArray
    cvx_n: FloatArray  # (Pc, F, 3) unit outward normals (zero rows pad)
    cvx_b: FloatArray  # (Pc, F) offsets, n . x <= b inside
    cvx_z: IntArray
    mesh: tuple[tuple[int, Primitive], ...]


def _planes(prim: Primitive) -> tuple[FloatArray, FloatArray]:
    if prim.vertices is None or prim.faces is None:
        raise ValidationError("convex zone primitive has no vertices/faces")
    v = np.asarray(prim.vertices, dtype=float)
    f = np.asarray(prim.faces, dtype=np.int64)
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(n, axis=1)
    keep = norm > 1e-12 * max(1.0, float(np.abs(v).max()) ** 2)
    n = n[keep] / norm[keep, None]
    b = np.einsum("ij,ij->i", n, tri[keep, 0])
    # outward check: the centroid must satisfy every plane
    centre = v.mean(axis=0)
    flip = n @ centre > b
    n[flip], b[flip] = -n[flip], -b[flip]
    # merge coplanar triangles: identical (normal, offset) rows
    key = np.round(np.c_[n, b], 9)
    _, first = np.unique(key, axis=0, return_index=True)
    first = np.sort(first)
    # every vertex lies inside every plane (up to rounding): a hull, not a mesh
    slack = v @ n[first].T - b[first]
    if slack.max(initial=0.0) > 1e-6:
        raise ValidationError("convex zone primitive is not convex")
    return n[first], b[first]


_SOLIDS: dict[int, tuple[ZoneMap, _Solids]] = {}
"""Zone solids by ``id`` of their (immutable) zone map; the map is kept so the id stays its."""

_SOLIDS_SIZE = 16


def _solids(zone_map: ZoneMap) -> _Solids:
    """The zone map's solids in arrays, built once per zone map."""
    hit = _SOLIDS.get(id(zone_map))
    if hit is not None and hit[0] is zone_map:
        return hit[1]
    out = _build_solids(zone_map)
    if len(_SOLIDS) >= _SOLIDS_SIZE:
        _SOLIDS.pop(next(iter(_SOLIDS)))
    _SOLIDS[id(zone_map)] = (zone_map, out)
    return out


def _build_solids(zone_map: ZoneMap) -> _Solids:
    sph: list[tuple[FloatArray, float, int]] = []
    box: list[tuple[FloatArray, FloatArray, FloatArray, int]] = []
    cyl: list[tuple[FloatArray, FloatArray, float, float, int]] = []
    cvx: list[tuple[FloatArray, FloatArray, int]] = []
    mesh: list[tuple[int, Primitive]] = []
    for z in range(zone_map.n_zones):
        for p in zone_map.primitives(z):
            t = np.asarray(p.transform, dtype=float)
            if p.kind == "sphere":
                sph.append((t[:3, 3], float(p.extents[0]), z))
            elif p.kind == "box":
                box.append((t[:3, :3], t[:3, 3], np.asarray(p.extents, dtype=float) / 2, z))
            elif p.kind == "cylinder":
                cyl.append((t[:3, :3], t[:3, 3], float(p.extents[0]), p.extents[1] / 2, z))
            elif p.kind == "convex":
                n, b = _planes(p)
                cvx.append((n, b, z))
            else:
                mesh.append((z, p))
    f_max = max((len(c[1]) for c in cvx), default=1)
    cvx_n = np.zeros((len(cvx), f_max, 3))
    cvx_b = np.ones((len(cvx), f_max))
    for i, (n, b, _) in enumerate(cvx):
        cvx_n[i, : len(b)] = n
        cvx_b[i, : len(b)] = b

    def ids(rows: Sequence[tuple[object, ...]]) -> IntArray:
        return np.array([r[-1] for r in rows], dtype=np.int64)

    return _Solids(
        sph_c=np.array([s[0] for s in sph]).reshape(-1, 3),
        sph_r=np.array([s[1] for s in sph], dtype=float),
        sph_z=ids(sph),
        box_r=np.array([b[0] for b in box]).reshape(-1, 3, 3),
        box_c=np.array([b[1] for b in box]).reshape(-1, 3),
        box_h=np.array([b[2] for b in box]).reshape(-1, 3),
        box_z=ids(box),
        cyl_r=np.array([c[0] for c in cyl]).reshape(-1, 3, 3),
        cyl_c=np.array([c[1] for c in cyl]).reshape(-1, 3),
        cyl_rad=np.array([c[2] for c in cyl], dtype=float),
        cyl_h=np.array([c[3] for c in cyl], dtype=float),
        cyl_z=ids(cyl),
        cvx_n=cvx_n,
        cvx_b=cvx_b,
        cvx_z=ids(cvx),
        mesh=tuple(mesh),
    )


def _scatter(out: BoolArray, hit: BoolArray, zone_ids: IntArray) -> None:
    """out (N, Z) |= any over shapes of hit (N, S, P) for primitive p's zone."""
    per_prim: BoolArray = np.any(hit, axis=1)  # (N, P)
    for p, z in enumerate(zone_ids):
        out[:, z] |= per_prim[:, p]


def _contacts_block(
    p0: FloatArray, p1: FloatArray, rad: FloatArray, solids: _Solids, n_zones: int
) -> BoolArray:
    """(N, Z) bool: capsules (p0, p1, rad) touch zone solids (conservative supersets).

    The compiled loop of :mod:`workcell.geometry._zone_sweep_jit`; it gives the
    same answers as :func:`_contacts_block_numpy`, the vectorised reference.
    """
    out: BoolArray = contacts_block(
        np.ascontiguousarray(p0),
        np.ascontiguousarray(p1),
        np.ascontiguousarray(rad, dtype=float),
        solids.sph_c,
        solids.sph_r,
        solids.sph_z,
        solids.box_r,
        solids.box_c,
        solids.box_h,
        solids.box_z,
        solids.cyl_r,
        solids.cyl_c,
        solids.cyl_rad,
        solids.cyl_h,
        solids.cyl_z,
        solids.cvx_n,
        solids.cvx_b,
        solids.cvx_z,
        n_zones,
    )
    return out


def _contacts_block_numpy(
    p0: FloatArray, p1: FloatArray, rad: FloatArray, solids: _Solids, n_zones: int
) -> BoolArray:
    """Vectorised numpy version of :func:`_contacts_block` (the tests' reference)."""
    n = p0.shape[0]
    out = np.zeros((n, n_zones), dtype=bool)
    d = p1 - p0  # (N, S, 3)
    big_r = rad[None, :, None]  # (1, S, 1)
    if solids.sph_z.size:
        c = solids.sph_c[None, None]  # (1, 1, P, 3)
        dd = np.einsum("nsk,nsk->ns", d, d)[..., None]
        w = c - p0[:, :, None, :]
        u = np.einsum("nspk,nsk->nsp", w, d) / np.where(dd > 0, dd, 1.0)
        u = np.clip(u, 0.0, 1.0)
        closest = p0[:, :, None, :] + u[..., None] * d[:, :, None, :]
        dist2 = np.sum((closest - c) ** 2, axis=-1)
        reach = big_r + solids.sph_r[None, None, :]
        _scatter(out, dist2 <= reach * reach, solids.sph_z)
    if solids.box_z.size:
        # local coordinates: (p - c) R
        lp0 = np.tensordot(p0, solids.box_r, axes=([2], [1])) - np.einsum(
            "pk,pkj->pj", solids.box_c, solids.box_r
        )
        ld = np.tensordot(d, solids.box_r, axes=([2], [1]))
        half = solids.box_h[None, None] + big_r[..., None]
        lo, hi = _slab(lp0, ld, half)
        _scatter(out, np.maximum(lo, 0.0) <= np.minimum(hi, 1.0), solids.box_z)
    if solids.cyl_z.size:
        lp0 = np.tensordot(p0, solids.cyl_r, axes=([2], [1])) - np.einsum(
            "pk,pkj->pj", solids.cyl_c, solids.cyl_r
        )
        ld = np.tensordot(d, solids.cyl_r, axes=([2], [1]))
        hz = solids.cyl_h[None, None] + big_r
        lo, hi = _slab(lp0[..., 2:], ld[..., 2:], hz[..., None])
        lo, hi = np.maximum(lo, 0.0), np.minimum(hi, 1.0)
        a = np.sum(ld[..., :2] ** 2, axis=-1)
        b = np.sum(lp0[..., :2] * ld[..., :2], axis=-1)
        # an empty slab (lo > hi) gives u = -inf and NaN below: never a hit
        with np.errstate(invalid="ignore"):
            u = np.clip(-b / np.where(a > 0, a, 1.0), lo, hi)
            xy = lp0[..., :2] + u[..., None] * ld[..., :2]
        reach = solids.cyl_rad[None, None] + big_r
        hit = (lo <= hi) & (np.sum(xy * xy, axis=-1) <= reach * reach)
        _scatter(out, hit, solids.cyl_z)
    if solids.cvx_z.size:
        nrm = solids.cvx_n  # (P, F, 3)
        num = (solids.cvx_b[None, None] + big_r[..., None]) - np.tensordot(p0, nrm, axes=([2], [2]))
        den = np.tensordot(d, nrm, axes=([2], [2]))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            ratio = num / den
        pos, neg = den > 1e-15, den < -1e-15
        hi = np.where(pos, ratio, np.inf).min(axis=-1)
        lo = np.where(neg, ratio, -np.inf).max(axis=-1)
        flat_ok = np.all(pos | neg | (num >= 0), axis=-1)
        hit = flat_ok & (np.maximum(lo, 0.0) <= np.minimum(hi, 1.0))
        _scatter(out, hit, solids.cvx_z)
    return out


def _mesh_contacts(
    arm: Arm,
    q: FloatArray,
    zone_map: ZoneMap,
    mesh: Sequence[tuple[int, Primitive]],
    padding: float,
    p0: FloatArray,
    p1: FloatArray,
    rad: FloatArray,
) -> BoolArray:
    """(N, Z) bool for mesh zones, through FCL one sample at a time."""
    out = np.zeros((len(q), zone_map.n_zones), dtype=bool)
    world = CollisionWorld()
    for s in arm.shapes:
        world.add_link_shape(s.name, s, "arm", padding=padding)
    owner: dict[str, int] = {}
    for k, (z, prim) in enumerate(mesh):
        name = f"mesh{k}"
        world.add_primitive(name, prim, "zones")
        owner[name] = z
    tfs = arm.shape_transforms(q)
    centres = tfs[..., :3, 3].reshape(-1, 3)
    mesh_zones = sorted({z for z, _ in mesh})
    for z in mesh_zones:  # shape centre inside the mesh (containment)
        inside = zone_map.zone(z).shape.contains(centres).reshape(len(q), -1)
        out[:, z] |= inside.any(axis=1)
    for z, prim in mesh:  # mesh inside a shape: its first vertex in the capsule
        if prim.vertices is None or len(prim.vertices) == 0:
            continue
        v = np.asarray(prim.vertices[0], dtype=float)
        d = p1 - p0
        dd = np.einsum("nsk,nsk->ns", d, d)
        u = np.clip(np.einsum("nsk,nsk->ns", v - p0, d) / np.where(dd > 0, dd, 1.0), 0, 1)
        dist2 = np.sum((p0 + u[..., None] * d - v) ** 2, axis=-1)
        out[:, z] |= np.any(dist2 <= rad[None] ** 2, axis=1)
    names = world.group_names("arm")
    for i in range(len(q)):
        world.set_group_transforms("arm", tfs[i])
        for name in names:
            for hit in world.hits(name, "zones"):
                out[i, owner[hit]] = True
    return out


def zone_contacts(arm: Arm, q: FloatArray, zone_map: ZoneMap, padding: float = 0.0) -> BoolArray:
    """Which zones the arm's shapes, grown by ``padding``, may touch at each ``q``.

    Conservative: a True may be a near miss (within the bounding-capsule
    and grown-solid slack described in the module docstring); a False is
    always a true miss.

    Parameters
    ----------
    arm : Arm
    q : (N, dof) float
    zone_map : zones.ZoneMap
    padding : float, metres

    Returns
    -------
    (N, Z) bool
        By zone id; activation is not considered.

    Raises
    ------
    multiarm.errors.ValidationError
        For a negative padding or an unknown shape kind.
    """
    if not (np.isfinite(padding) and padding >= 0):
        raise ValidationError(f"arm {arm.name!r}: padding must be >= 0 m, got {padding}")
    qq = np.atleast_2d(np.asarray(q, dtype=float))
    local, rad = _shape_capsules(arm.shapes)
    rad = rad + padding
    solids = _solids(zone_map)
    out = np.zeros((len(qq), zone_map.n_zones), dtype=bool)
    for start in range(0, len(qq), _CHUNK):
        block = qq[start : start + _CHUNK]
        p0, p1 = _segments(arm, block, local)
        out[start : start + len(block)] = _contacts_block(p0, p1, rad, solids, zone_map.n_zones)
        if solids.mesh:
            out[start : start + len(block)] |= _mesh_contacts(
                arm, block, zone_map, solids.mesh, padding, p0, p1, rad
            )
    return out


def static_occupancy(
    arm: Arm, q: FloatArray, zone_map: ZoneMap, padding: float = 0.0
) -> tuple[str, ...]:
    """Names of the zones an arm standing at ``q`` is in (conservative).

    Parameters
    ----------
    arm : Arm
    q : (dof,) float
    zone_map : zones.ZoneMap
    padding : float, metres

    Returns
    -------
    tuple of str
        By zone id.
    """
    row = zone_contacts(arm, np.asarray(q, dtype=float)[None, :], zone_map, padding)[0]
    names = zone_map.zone_names()
    return tuple(names[i] for i in np.flatnonzero(row))


def _runs(mask: BoolArray) -> IntArray:
    """(R, 2) [start, stop) index pairs of the True runs of a 1-D mask."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1)
    return np.stack([starts, stops], axis=1).astype(np.int64)


def _intersect(a: Sequence[tuple[float, float]], b: FloatArray) -> tuple[tuple[float, float], ...]:
    out: list[tuple[float, float]] = []
    i = j = 0
    while i < len(a) and j < len(b):
        lo = max(a[i][0], float(b[j][0]))
        hi = min(a[i][1], float(b[j][1]))
        if hi > lo:
            out.append((lo, hi))
        if a[i][1] < b[j][1]:
            i += 1
        else:
            j += 1
    return tuple(out)


def zone_windows(
    arm: Arm,
    traj: JointTrajectoryLike,
    zone_map: ZoneMap,
    padding: float = 0.005,
    n_grid: int = 32,
) -> ZoneWindows:
    """Conservative occupancy and moving windows of every zone the arm touches.

    See the module docstring for the sampling rule and why no contact is
    missed (a contact between two samples flags both of them).

    Parameters
    ----------
    arm : Arm
    traj : JointTrajectoryLike
        Times are seconds from the trajectory's start.
    zone_map : zones.ZoneMap
    padding : float, metres
        Growth of the shapes and the largest displacement bound between
        consecutive samples: smaller is tighter and costs more samples.
    n_grid : int
        Intervals of the initial uniform grid.

    Returns
    -------
    ZoneWindows

    Raises
    ------
    multiarm.errors.ValidationError
        For a bad padding or trajectory (see :func:`sample_trajectory`).
    """
    t, q = sample_trajectory(arm, traj, padding, n_grid)
    flags = zone_contacts(arm, q, zone_map, padding)
    motion = np.asarray(traj.motion_intervals(), dtype=float).reshape(-1, 2)
    names = zone_map.zone_names()
    windows: list[ZoneWindow] = []
    for z in np.flatnonzero(flags.any(axis=0)):
        f = flags[:, z]
        if len(t) == 1:
            occ: tuple[tuple[float, float], ...] = ((float(t[0]), float(t[0])),)
        else:
            interval = f[:-1] | f[1:]
            occ = tuple((float(t[a]), float(t[b])) for a, b in _runs(interval))
        windows.append(ZoneWindow(names[z], int(z), occ, _intersect(occ, motion)))
    return ZoneWindows(arm.name, float(traj.duration), float(padding), tuple(windows), len(t))


# ------------------------------------------------------------ pre-tests


def swept_aabb(arm: Arm, traj: JointTrajectoryLike, padding: float = 0.005) -> FloatArray:
    """An axis-aligned box holding every arm shape during the whole trajectory.

    Every shape's bounding capsule at every sample (:func:`sample_trajectory`)
    plus ``padding`` (no point moves farther than that between samples).
    Cheap conservative pre-test between two arms: disjoint boxes mean the
    two trajectories can never collide (:func:`aabbs_overlap`).

    Returns
    -------
    (2, 3) float, metres
        Lower and upper corner.
    """
    _, q = sample_trajectory(arm, traj, padding)
    local, rad = _shape_capsules(arm.shapes)
    p0, p1 = _segments(arm, q, local)
    grow = (rad + padding)[None, :, None]
    lo = np.minimum(p0, p1) - grow
    hi = np.maximum(p0, p1) + grow
    return np.stack([lo.min(axis=(0, 1)), hi.max(axis=(0, 1))])


def aabbs_overlap(a: FloatArray, b: FloatArray) -> bool:
    """Whether two (2, 3) boxes (lower, upper corner) intersect (touching counts).

    Examples
    --------
    >>> import numpy as np
    >>> aabbs_overlap(np.array([[0, 0, 0], [1, 1, 1.0]]), np.array([[1, 0, 0], [2, 1, 1.0]]))
    True
    """
    return bool(np.all(a[0] <= b[1]) and np.all(b[0] <= a[1]))


# ------------------------------------------------------------- reference


def reference_contacts(arm: Arm, q: FloatArray, zone_map: ZoneMap) -> BoolArray:
    """Brute-force check for tests: exact (unpadded) shapes vs zones with FCL.

    One FCL query per sample and zone solid: every arm shape as its own
    primitive (no bounding capsules), zone solids as FCL primitives, convex
    polytopes or mesh surfaces (with "shape centre inside" for meshes).

    Parameters
    ----------
    arm : Arm
    q : (N, dof) float
    zone_map : zones.ZoneMap

    Returns
    -------
    (N, Z) bool
    """
    qq = np.atleast_2d(np.asarray(q, dtype=float))
    world = CollisionWorld()
    for s in arm.shapes:
        world.add_link_shape(s.name, s, "arm")
    owner: dict[str, int] = {}
    meshes: set[int] = set()
    for z in range(zone_map.n_zones):
        for k, prim in enumerate(zone_map.primitives(z)):
            name = f"{z}#{k}"
            world.add_primitive(name, prim, "zones")
            owner[name] = z
            if prim.kind == "mesh":
                meshes.add(z)
    tfs = arm.shape_transforms(qq)
    out = np.zeros((len(qq), zone_map.n_zones), dtype=bool)
    for i in range(len(qq)):
        world.set_group_transforms("arm", tfs[i])
        for _, zname in world.colliding_pairs("arm", "zones"):
            out[i, owner[zname]] = True
    centres = tfs[..., :3, 3].reshape(-1, 3)
    for z in meshes:
        out[:, z] |= zone_map.zone(z).shape.contains(centres).reshape(len(qq), -1).any(axis=1)
    return out


def _segment_distances(
    a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray
) -> FloatArray:
    """Distances between segments ``a0a1`` and ``b0b1`` (broadcast over leading axes),
    by the closest-point method of C. Ericson, *Real-Time Collision Detection*
    (2005), section 5.1.9, vectorised."""
    d1, d2, r = a1 - a0, b1 - b0, a0 - b0
    a = np.sum(d1 * d1, axis=-1)
    e = np.sum(d2 * d2, axis=-1)
    f = np.sum(d2 * r, axis=-1)
    c = np.sum(d1 * r, axis=-1)
    b = np.sum(d1 * d2, axis=-1)
    eps = 1e-18
    pa_, pe_ = a > eps, e > eps
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = a * e - b * b
        s_gen = np.where(denom > eps, np.clip((b * f - c * e) / denom, 0.0, 1.0), 0.0)
        t_gen = (b * s_gen + f) / np.where(pe_, e, 1.0)
        s_lo = np.clip(-c / np.where(pa_, a, 1.0), 0.0, 1.0)  # t clamped to 0
        s_hi = np.clip((b - c) / np.where(pa_, a, 1.0), 0.0, 1.0)  # t clamped to 1
        s = np.where(t_gen < 0.0, s_lo, np.where(t_gen > 1.0, s_hi, s_gen))
        t = np.clip(t_gen, 0.0, 1.0)
        # degenerate segments (points)
        t_pt = np.clip(f / np.where(pe_, e, 1.0), 0.0, 1.0)
        s = np.where(pa_ & pe_, s, np.where(pa_, s_lo, 0.0))
        t = np.where(pa_ & pe_, t, np.where(pe_, t_pt, 0.0))
    pa = a0 + s[..., None] * d1
    pb = b0 + t[..., None] * d2
    out: FloatArray = np.linalg.norm(pa - pb, axis=-1)
    return out


def arm_contacts(
    arm: Arm, q: FloatArray, other: Arm, q_other: FloatArray, padding: float = 0.0
) -> BoolArray:
    """(N,) bool: whether ``arm`` at each row of ``q`` may touch ``other`` standing at ``q_other``.

    Conservative and vectorised over samples x shapes x shapes: every shape
    is replaced by a capsule holding it (as in the zone sweep) and two
    capsules touch when their segments come within the sum of their radii
    plus ``padding``. ``True`` may be a near miss; ``False`` is never a contact.
    """
    la, ra = _shape_capsules(arm.shapes)
    lb, rb = _shape_capsules(other.shapes)
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    a0, a1 = _segments(arm, qa, la)  # (N, Sa, 3)
    b0, b1 = _segments(other, np.asarray(q_other, dtype=float)[None, :], lb)  # (1, Sb, 3)
    out: BoolArray = capsules_touch(
        np.ascontiguousarray(a0),
        np.ascontiguousarray(a1),
        np.ascontiguousarray(ra),
        np.ascontiguousarray(b0[0]),
        np.ascontiguousarray(b1[0]),
        np.ascontiguousarray(rb),
        float(padding),
    )
    return out


def _arm_contacts_numpy(
    arm: Arm, q: FloatArray, other: Arm, q_other: FloatArray, padding: float = 0.0
) -> BoolArray:
    """Vectorised numpy version of :func:`arm_contacts` (the tests' reference)."""
    la, ra = _shape_capsules(arm.shapes)
    lb, rb = _shape_capsules(other.shapes)
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    a0, a1 = _segments(arm, qa, la)
    b0, b1 = _segments(other, np.asarray(q_other, dtype=float)[None, :], lb)
    dist = _segment_distances(
        a0[:, :, None, :], a1[:, :, None, :], b0[:, None, :, :], b1[:, None, :, :]
    )  # (N, Sa, Sb)
    reach = ra[:, None] + rb[None, :] + padding
    out: BoolArray = np.any(dist <= reach[None], axis=(1, 2))
    return out
