"""Zone volumes: the shapes SDL can describe, with vectorised point queries.

Every shape is an immutable record in the cell frame (metres) that answers

* ``contains(points)``: (N, 3) float → (N,) bool, closed sets (a point on the
  boundary is inside, up to ``EPS``);
* ``bounds()``: the axis-aligned box around it, ``(min, max)``;
* ``primitives()``: what ``workcell`` turns into FCL objects
  (:class:`Primitive`: box, cylinder, sphere, convex polytope or mesh with
  a pose), so that FCL stays out of this package;
* ``check()``: raises :class:`ValueError` when the volume is empty or
  degenerate (called by the zone map, which turns it into a located error).

Shapes: :class:`AABox` (axis-aligned, by corners), :class:`OBox` (centre,
size, yaw), :class:`Cylinder` (vertical), :class:`Sphere`, :class:`Hull`
(convex hull of points), :class:`HalfSpaces` (the region between named walls,
clipped to the cell), :class:`Union` and :class:`MeshShape` (a closed mesh
file, via trimesh).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal, TypeAlias

import numpy as np

from multiarm.types import BoolArray, FloatArray, IntArray, Point3, Transform

__all__ = [
    "EPS",
    "AABox",
    "Cylinder",
    "HalfSpaces",
    "Hull",
    "MeshShape",
    "OBox",
    "Primitive",
    "Shape",
    "Sphere",
    "Union",
]

EPS = 1e-9
"""Boundary tolerance of containment tests, metres."""

Bounds: TypeAlias = tuple[Point3, Point3]


def _pts(points: Any) -> FloatArray:
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points must be an (N, 3) array, got shape {p.shape}")
    return p


def _finite(values: Any, what: str) -> None:
    arr = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} has a non-finite number")


@dataclass(frozen=True, slots=True)
class Primitive:
    """A solid for the collision layer, FCL's conventions.

    Attributes
    ----------
    kind : {"box", "cylinder", "sphere", "convex", "mesh"}
    transform : (4, 4) float
        Pose of the solid's centre (box, cylinder, sphere); identity for
        ``convex`` and ``mesh``, whose vertices are in the cell frame.
    extents : tuple of float
        ``box``: full sides (sx, sy, sz); ``cylinder``: (radius, height),
        axis along the local z, centred; ``sphere``: (radius,); else ().
    vertices : (V, 3) float or None
    faces : (F, 3) int or None
        Triangles (outward winding for ``convex``).
    """

    kind: Literal["box", "cylinder", "sphere", "convex", "mesh"]
    transform: Transform
    extents: tuple[float, ...] = ()
    vertices: FloatArray | None = None
    faces: IntArray | None = None


def _translation(p: Any) -> Transform:
    t = np.eye(4)
    t[:3, 3] = p
    return t


@dataclass(frozen=True, slots=True)
class AABox:
    """Axis-aligned box from corner ``lo`` to corner ``hi``."""

    kind = "box"
    lo: Point3
    hi: Point3

    def check(self) -> None:
        _finite((*self.lo, *self.hi), "box")
        if any(h - l <= EPS for l, h in zip(self.lo, self.hi, strict=True)):
            raise ValueError(f"box is empty or flat: corners {self.lo} and {self.hi}")

    def contains(self, points: Any) -> BoolArray:
        p = _pts(points)
        lo = np.asarray(self.lo) - EPS
        hi = np.asarray(self.hi) + EPS
        out: BoolArray = np.all((p >= lo) & (p <= hi), axis=1)
        return out

    def bounds(self) -> Bounds:
        return self.lo, self.hi

    def primitives(self) -> tuple[Primitive, ...]:
        lo, hi = np.asarray(self.lo), np.asarray(self.hi)
        return (Primitive("box", _translation((lo + hi) / 2), tuple((hi - lo).tolist())),)

    def volume(self) -> float:
        return float(np.prod(np.subtract(self.hi, self.lo)))


@dataclass(frozen=True, slots=True)
class OBox:
    """Box of full sides ``size`` centred at ``center``, turned by ``yaw`` about z."""

    kind = "obox"
    center: Point3
    size: Point3
    yaw: float = 0.0

    def check(self) -> None:
        _finite((*self.center, *self.size, self.yaw), "box")
        if min(self.size) <= EPS:
            raise ValueError(f"box size must be positive on every axis, got {self.size}")

    def _rotation(self) -> FloatArray:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def contains(self, points: Any) -> BoolArray:
        local = (_pts(points) - np.asarray(self.center)) @ self._rotation()
        out: BoolArray = np.all(np.abs(local) <= np.asarray(self.size) / 2 + EPS, axis=1)
        return out

    def corners(self) -> FloatArray:
        half = np.asarray(self.size) / 2
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        out: FloatArray = (signs * half) @ self._rotation().T + np.asarray(self.center)
        return out

    def bounds(self) -> Bounds:
        c = self.corners()
        lo, hi = c.min(axis=0), c.max(axis=0)
        return (lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2])

    def primitives(self) -> tuple[Primitive, ...]:
        t = np.eye(4)
        t[:3, :3] = self._rotation()
        t[:3, 3] = self.center
        return (Primitive("box", t, tuple(float(v) for v in self.size)),)

    def volume(self) -> float:
        return float(np.prod(self.size))


@dataclass(frozen=True, slots=True)
class Cylinder:
    """Vertical cylinder: base disk centred at ``base``, ``radius``, ``height`` up."""

    kind = "cylinder"
    base: Point3
    radius: float
    height: float

    def check(self) -> None:
        _finite((*self.base, self.radius, self.height), "cylinder")
        if self.radius <= EPS or self.height <= EPS:
            raise ValueError(
                f"cylinder needs radius > 0 and height > 0, got {self.radius} and {self.height}"
            )

    def contains(self, points: Any) -> BoolArray:
        p = _pts(points)
        bx, by, bz = self.base
        d2 = (p[:, 0] - bx) ** 2 + (p[:, 1] - by) ** 2
        r = self.radius + EPS
        return (d2 <= r * r) & (p[:, 2] >= bz - EPS) & (p[:, 2] <= bz + self.height + EPS)

    def bounds(self) -> Bounds:
        bx, by, bz = self.base
        r = self.radius
        return (bx - r, by - r, bz), (bx + r, by + r, bz + self.height)

    def primitives(self) -> tuple[Primitive, ...]:
        bx, by, bz = self.base
        return (
            Primitive(
                "cylinder", _translation((bx, by, bz + self.height / 2)), (self.radius, self.height)
            ),
        )

    def volume(self) -> float:
        return math.pi * self.radius**2 * self.height


@dataclass(frozen=True, slots=True)
class Sphere:
    """Ball of ``radius`` around ``center``."""

    kind = "sphere"
    center: Point3
    radius: float

    def check(self) -> None:
        _finite((*self.center, self.radius), "sphere")
        if self.radius <= EPS:
            raise ValueError(f"sphere needs radius > 0, got {self.radius}")

    def contains(self, points: Any) -> BoolArray:
        d = _pts(points) - np.asarray(self.center)
        r = self.radius + EPS
        out: BoolArray = np.einsum("ij,ij->i", d, d) <= r * r
        return out

    def bounds(self) -> Bounds:
        c, r = self.center, self.radius
        return (c[0] - r, c[1] - r, c[2] - r), (c[0] + r, c[1] + r, c[2] + r)

    def primitives(self) -> tuple[Primitive, ...]:
        return (Primitive("sphere", _translation(self.center), (self.radius,)),)

    def volume(self) -> float:
        return 4.0 / 3.0 * math.pi * self.radius**3


class _Polytope:
    """Shared code of convex polytopes given as ``A x <= b``."""

    def _halfspaces(self) -> tuple[FloatArray, FloatArray]:
        raise NotImplementedError

    def _vertices_faces(self) -> tuple[FloatArray, IntArray]:
        raise NotImplementedError

    def contains(self, points: Any) -> BoolArray:
        a, b = self._halfspaces()
        out: BoolArray = np.all(_pts(points) @ a.T <= b + EPS, axis=1)
        return out

    def bounds(self) -> Bounds:
        v, _ = self._vertices_faces()
        lo, hi = v.min(axis=0), v.max(axis=0)
        return (float(lo[0]), float(lo[1]), float(lo[2])), (
            float(hi[0]),
            float(hi[1]),
            float(hi[2]),
        )

    def primitives(self) -> tuple[Primitive, ...]:
        v, f = self._vertices_faces()
        return (Primitive("convex", np.eye(4), (), v, f),)


def _hull_of(vertices: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, IntArray]:
    """(A, b, vertices, faces) of the convex hull of points, faces outward."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(vertices)
    except (QhullError, ValueError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(f"points span no volume (flat or too few): {first}") from None
    if hull.volume <= EPS**2:
        raise ValueError(f"points span no volume (hull volume {hull.volume:.3g} m^3)")
    eq = hull.equations  # n . x + d <= 0 inside
    used = np.unique(hull.simplices)
    remap = -np.ones(len(vertices), dtype=np.int64)
    remap[used] = np.arange(len(used))
    verts = vertices[used]
    faces = remap[hull.simplices].astype(np.int64)
    # orient every triangle outward (qhull does not guarantee the winding)
    centre = verts.mean(axis=0)
    tri = verts[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flip = np.einsum("ij,ij->i", normals, tri[:, 0] - centre) < 0
    faces[flip] = faces[flip][:, ::-1]
    return eq[:, :3], -eq[:, 3], verts, faces


@dataclass(frozen=True, slots=True)
class Hull(_Polytope):
    """Convex hull of ``points`` (at least four, not all in one plane)."""

    kind = "hull"
    points: tuple[Point3, ...]
    _cache: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def check(self) -> None:
        _finite(self.points, "hull")
        if len(self.points) < 4:
            raise ValueError(f"a hull needs at least 4 points, got {len(self.points)}")
        self._computed()

    def _computed(self) -> tuple[FloatArray, FloatArray, FloatArray, IntArray]:
        if "hull" not in self._cache:
            self._cache["hull"] = _hull_of(np.asarray(self.points, dtype=float))
        result: tuple[FloatArray, FloatArray, FloatArray, IntArray] = self._cache["hull"]
        return result

    def _halfspaces(self) -> tuple[FloatArray, FloatArray]:
        a, b, _, _ = self._computed()
        return a, b

    def _vertices_faces(self) -> tuple[FloatArray, IntArray]:
        _, _, v, f = self._computed()
        return v, f

    def volume(self) -> float:
        from scipy.spatial import ConvexHull

        return float(ConvexHull(np.asarray(self.points, dtype=float)).volume)


@dataclass(frozen=True, slots=True)
class HalfSpaces(_Polytope):
    """The region on given sides of named walls, clipped to the cell bounds (S2.10).

    Parameters
    ----------
    sides : tuple of (str, int)
        ``(wall name, +1 or -1)``: +1 keeps the side the wall's normal points
        to, -1 the other side.
    planes : tuple of ((3,) normal, offset)
        Resolved by the zone map: ``normal . x >= offset`` for every kept
        side, already signed; not compared.
    cell : ((3,), (3,))
        The cell bounds; not compared.
    """

    kind = "walls"
    sides: tuple[tuple[str, int], ...]
    planes: tuple[tuple[Point3, float], ...] = field(default=(), compare=False, repr=False)
    cell: Bounds = field(default=((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), compare=False, repr=False)
    _cache: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def _halfspaces(self) -> tuple[FloatArray, FloatArray]:
        if "ab" not in self._cache:
            rows = [(-np.asarray(n, dtype=float), -float(o)) for n, o in self.planes]
            lo, hi = np.asarray(self.cell[0]), np.asarray(self.cell[1])
            for axis in range(3):
                e = np.zeros(3)
                e[axis] = 1.0
                rows.append((e, hi[axis]))
                rows.append((-e, -lo[axis]))
            a = np.array([r[0] for r in rows])
            b = np.array([r[1] for r in rows])
            self._cache["ab"] = (a, b)
        result: tuple[FloatArray, FloatArray] = self._cache["ab"]
        return result

    def check(self) -> None:
        self._vertices_faces()

    def _vertices_faces(self) -> tuple[FloatArray, IntArray]:
        if "vf" not in self._cache:
            from scipy.optimize import linprog
            from scipy.spatial import HalfspaceIntersection, QhullError

            a, b = self._halfspaces()
            norms = np.linalg.norm(a, axis=1)
            # Chebyshev centre: the deepest interior point, by linear programming.
            res = linprog(
                np.r_[np.zeros(3), -1.0],
                A_ub=np.c_[a, norms],
                b_ub=b,
                bounds=[(None, None)] * 3 + [(0, None)],
                method="highs",
            )
            if res.status != 0 or res.x[3] <= 1e-6:
                raise ValueError("the walls leave no volume inside the cell")
            try:
                hs = HalfspaceIntersection(np.c_[a, -b], res.x[:3])
            except QhullError as exc:  # numerically degenerate walls
                why = str(exc).strip().splitlines()[0] if str(exc).strip() else "qhull failed"
                raise ValueError(
                    f"the walls leave no usable volume inside the cell ({why})"
                ) from None
            _, _, v, f = _hull_of(hs.intersections)
            self._cache["vf"] = (v, f)
        result: tuple[FloatArray, IntArray] = self._cache["vf"]
        return result

    def volume(self) -> float:
        from scipy.spatial import ConvexHull

        v, _ = self._vertices_faces()
        return float(ConvexHull(v).volume)


@dataclass(frozen=True, slots=True)
class MeshShape:
    """A closed triangle mesh read from a file (any format trimesh reads).

    ``path`` is kept as written in the SDL text (relative paths are relative
    to the SDL file's folder, recorded in ``base``); the loaded geometry is
    not compared.
    """

    kind = "mesh"
    path: str
    base: str = field(default="", compare=False, repr=False)
    _cache: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def _mesh(self) -> Any:
        if "mesh" not in self._cache:
            import os

            import trimesh

            full = self.path if os.path.isabs(self.path) else os.path.join(self.base, self.path)
            try:
                mesh: Any = trimesh.load(full, force="mesh")
            except Exception as exc:  # trimesh raises many kinds
                raise ValueError(f"cannot load mesh {self.path!r}: {exc}") from None
            if len(mesh.faces) == 0:
                raise ValueError(f"mesh {self.path!r} has no faces")
            if not mesh.is_watertight:
                raise ValueError(f"mesh {self.path!r} is not closed (watertight)")
            if mesh.volume <= EPS**2:
                raise ValueError(f"mesh {self.path!r} encloses no volume")
            self._cache["mesh"] = mesh
        return self._cache["mesh"]

    def check(self) -> None:
        self._mesh()

    def contains(self, points: Any) -> BoolArray:
        p = _pts(points)
        if len(p) == 0:
            return np.zeros(0, dtype=bool)
        return np.asarray(self._mesh().contains(p), dtype=bool)

    def bounds(self) -> Bounds:
        b = self._mesh().bounds
        return (float(b[0, 0]), float(b[0, 1]), float(b[0, 2])), (
            float(b[1, 0]),
            float(b[1, 1]),
            float(b[1, 2]),
        )

    def primitives(self) -> tuple[Primitive, ...]:
        m = self._mesh()
        return (
            Primitive(
                "mesh",
                np.eye(4),
                (),
                np.asarray(m.vertices, dtype=float),
                np.asarray(m.faces, dtype=np.int64),
            ),
        )

    def volume(self) -> float:
        return float(self._mesh().volume)


@dataclass(frozen=True, slots=True)
class Union:
    """Points in any of ``parts``."""

    kind = "union"
    parts: tuple[Shape, ...]

    def check(self) -> None:
        if not self.parts:
            raise ValueError("a union needs at least one shape")
        for p in self.parts:
            p.check()

    def contains(self, points: Any) -> BoolArray:
        p = _pts(points)
        out = np.zeros(len(p), dtype=bool)
        for part in self.parts:
            out |= part.contains(p)
        return out

    def bounds(self) -> Bounds:
        bs = [p.bounds() for p in self.parts]
        lo = np.min([b[0] for b in bs], axis=0)
        hi = np.max([b[1] for b in bs], axis=0)
        return (float(lo[0]), float(lo[1]), float(lo[2])), (
            float(hi[0]),
            float(hi[1]),
            float(hi[2]),
        )

    def primitives(self) -> tuple[Primitive, ...]:
        return tuple(q for p in self.parts for q in p.primitives())

    def volume(self) -> float:
        """Sum of the parts' volumes (an upper bound when they overlap)."""
        return float(sum(p.volume() for p in self.parts))


Shape: TypeAlias = AABox | OBox | Cylinder | Sphere | Hull | HalfSpaces | MeshShape | Union
"""Any zone volume."""
