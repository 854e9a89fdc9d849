"""The collision world: named FCL objects in groups, moved by explicit transforms.

This is the only module of the package that imports :mod:`fcl` (DESIGN.md
"Where the dependencies live"); everything else hands it numpy arrays and gets
plain records back.

* Objects are created once (:meth:`CollisionWorld.add_link_shape`,
  :meth:`CollisionWorld.add_primitive`, :meth:`CollisionWorld.add_arm`) and
  keyed by unique names; each belongs to one *group* (one per arm, one for
  static obstacles, one for zones, ...). Every group owns an FCL broadphase
  manager (``DynamicAABBTreeCollisionManager``).
* Objects move with explicit ``(4, 4)`` transforms
  (:meth:`CollisionWorld.set_transform`, or a whole group at once with
  :meth:`CollisionWorld.set_group_transforms`); the group's manager is
  updated lazily before its next query.
* Queries: any hit between two groups (or inside one, for self-collision),
  every colliding pair by name, the minimum distance, and one
  :class:`CollisionReport` record. Pairs listed with
  :meth:`CollisionWorld.allow` (an arm's ``allowed_pairs``) are never reported.
* :meth:`CollisionWorld.first_collision` checks a batch of configurations of
  one group against another group in one call (the motion planner's and the
  sweep reference's hot loop).

Examples
--------
>>> import numpy as np
>>> from workcell.arms.base import LinkShape
>>> w = CollisionWorld()
>>> w.add_link_shape("a", LinkShape("a", "sphere", (0.1,), 0), group="left")
>>> w.add_link_shape("b", LinkShape("b", "sphere", (0.1,), 0), group="right")
>>> T = np.eye(4)
>>> T[0, 3] = 0.5
>>> w.set_transform("b", T)
>>> w.collide("left", "right")
False
>>> round(w.min_distance("left", "right"), 6)
0.3
>>> T[0, 3] = 0.15
>>> w.set_transform("b", T)
>>> w.report("left", "right").pairs
(('a', 'b'),)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import fcl
import numpy as np

from multiarm.errors import UsageError, ValidationError
from multiarm.types import BoolArray, FloatArray, IntArray, Transform
from workcell.arms.base import Arm, LinkShape
from zones.geometry import Primitive

if TYPE_CHECKING:
    from workcell.arms.urdf import UrdfArm

__all__ = [
    "CollisionReport",
    "CollisionWorld",
    "link_geometry",
    "mesh_geometry",
    "primitive_geometry",
]


@dataclass(frozen=True, slots=True)
class CollisionReport:
    """What a collision query found.

    Attributes
    ----------
    pairs : tuple of (str, str)
        Colliding object pairs by name, each ordered as (object of the first
        group, object of the second group) — for a query inside one group,
        alphabetically — and sorted; allowed pairs are left out.
    min_distance : float
        Smallest distance between the two sides in metres; ``0.0`` when any
        (not allowed) pair touches or penetrates.
    """

    pairs: tuple[tuple[str, str], ...]
    min_distance: float

    @property
    def collision(self) -> bool:
        """True when at least one pair collides."""
        return bool(self.pairs)


def _check_size(what: str, size: Sequence[float], n: int) -> tuple[float, ...]:
    vals = tuple(float(v) for v in size)
    if len(vals) != n or not all(np.isfinite(vals)) or min(vals) < 0:
        raise ValidationError(f"{what}: expected {n} finite non-negative sizes, got {size!r}")
    return vals


def link_geometry(shape: LinkShape, padding: float = 0.0) -> Any:
    """The FCL geometry of an arm shape, grown by ``padding`` on every side.

    Parameters
    ----------
    shape : LinkShape
    padding : float, metres
        Capsules, spheres and cylinders grow their radius (cylinders also
        their height by ``2 padding``); boxes grow every side by ``2 padding``.
        The result always contains every point within ``padding`` of the
        shape (for a box it holds a little more, near the corners).

    Returns
    -------
    fcl.CollisionGeometry

    Raises
    ------
    multiarm.errors.ValidationError
        For an unknown kind, a wrong number of sizes or a negative padding.
    """
    if padding < 0 or not np.isfinite(padding):
        raise ValidationError(f"shape {shape.name!r}: padding must be >= 0, got {padding}")
    p = float(padding)
    what = f"shape {shape.name!r} ({shape.kind})"
    if shape.kind == "capsule":
        r, length = _check_size(what, shape.size, 2)
        return fcl.Capsule(r + p, length)
    if shape.kind == "sphere":
        (r,) = _check_size(what, shape.size, 1)
        return fcl.Sphere(r + p)
    if shape.kind == "box":
        sx, sy, sz = _check_size(what, shape.size, 3)
        return fcl.Box(sx + 2 * p, sy + 2 * p, sz + 2 * p)
    if shape.kind == "cylinder":
        r, h = _check_size(what, shape.size, 2)
        return fcl.Cylinder(r + p, h + 2 * p)
    raise ValidationError(f"{what}: unknown shape kind {shape.kind!r}")


def primitive_geometry(prim: Primitive) -> Any:
    """The FCL geometry of a zone solid (:class:`zones.geometry.Primitive`).

    Boxes, cylinders and spheres map to FCL primitives; ``convex`` to
    ``fcl.Convex`` (vertices in the cell frame); ``mesh`` to a ``BVHModel``
    (its *surface*: a shape entirely inside a mesh does not collide with it,
    see :func:`workcell.geometry.zone_sweep.reference_contacts`).

    Parameters
    ----------
    prim : zones.geometry.Primitive

    Returns
    -------
    fcl.CollisionGeometry

    Raises
    ------
    multiarm.errors.ValidationError
        For an unknown kind or missing vertices/faces.
    """
    if prim.kind == "box":
        sx, sy, sz = _check_size("box primitive", prim.extents, 3)
        return fcl.Box(sx, sy, sz)
    if prim.kind == "cylinder":
        r, h = _check_size("cylinder primitive", prim.extents, 2)
        return fcl.Cylinder(r, h)
    if prim.kind == "sphere":
        (r,) = _check_size("sphere primitive", prim.extents, 1)
        return fcl.Sphere(r)
    if prim.kind in ("convex", "mesh"):
        if prim.vertices is None or prim.faces is None:
            raise ValidationError(f"{prim.kind} primitive needs vertices and faces")
        v = np.ascontiguousarray(prim.vertices, dtype=np.float64)
        f = np.ascontiguousarray(prim.faces, dtype=np.int64)
        if prim.kind == "convex":
            flat = np.column_stack((np.full(len(f), 3, dtype=np.int64), f)).ravel()
            return fcl.Convex(v, len(f), flat)
        bvh = fcl.BVHModel()
        bvh.beginModel(len(v), len(f))
        bvh.addSubModel(v, f)
        bvh.endModel()
        return bvh
    raise ValidationError(f"unknown primitive kind {prim.kind!r}")


def mesh_geometry(vertices: FloatArray, faces: IntArray, name: str = "mesh") -> Any:
    """An FCL bounding-volume hierarchy (``BVHModel``, OBB-RSS) of a triangle mesh.

    Its *surface* collides: a shape entirely inside a closed mesh does not.

    Parameters
    ----------
    vertices : (V, 3) float
    faces : (F, 3) int
        Vertex indices.
    name : str
        Named in errors.

    Raises
    ------
    multiarm.errors.ValidationError
        For empty, non-finite or out-of-range data.
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.ascontiguousarray(faces, dtype=np.int64)
    if (
        v.ndim != 2
        or v.shape[1:] != (3,)
        or f.ndim != 2
        or f.shape[1:] != (3,)
        or len(v) == 0
        or len(f) == 0
        or not np.all(np.isfinite(v))
        or f.min() < 0
        or f.max() >= len(v)
    ):
        raise ValidationError(
            f"mesh {name!r}: needs finite (V, 3) vertices and (F, 3) faces indexing them"
        )
    bvh = fcl.BVHModel()
    bvh.beginModel(len(v), len(f))
    bvh.addSubModel(v, f)
    bvh.endModel()
    return bvh


def _fcl_transform(t: FloatArray) -> Any:
    return fcl.Transform(t[:3, :3], t[:3, 3])


class _Group:
    __slots__ = ("dirty", "manager", "names", "objects", "ready")

    def __init__(self) -> None:
        self.names: list[str] = []
        self.objects: list[Any] = []
        self.manager: Any = fcl.DynamicAABBTreeCollisionManager()
        self.dirty = False
        self.ready = False

    def sync(self) -> Any:
        if not self.ready:
            self.manager.registerObjects(self.objects)
            self.manager.setup()
            self.ready = True
            self.dirty = False
        elif self.dirty:
            self.manager.update()
            self.dirty = False
        return self.manager


class CollisionWorld:
    """Named FCL objects in groups, each group with a broadphase manager.

    Objects are built once and moved by transforms; no query rebuilds them.
    The world is not thread-safe (python-fcl holds the GIL and shares state
    between calls, ``notes/deps.md`` section 2).

    Examples
    --------
    >>> import numpy as np
    >>> from workcell.arms.base import LinkShape
    >>> w = CollisionWorld()
    >>> w.add_link_shape("l1", LinkShape("l1", "capsule", (0.05, 0.4), 0), group="arm")
    >>> w.add_link_shape("l2", LinkShape("l2", "capsule", (0.05, 0.4), 0), group="arm")
    >>> w.collide("arm")
    True
    >>> w.allow("l1", "l2")
    >>> w.collide("arm")
    False
    """

    def __init__(self) -> None:
        self._groups: dict[str, _Group] = {}
        self._where: dict[str, tuple[str, int]] = {}
        self._by_geom: dict[int, str] = {}
        self._geoms: list[Any] = []  # keeps geometries alive: their ids name objects
        self._allowed: set[frozenset[str]] = set()
        self._creq = fcl.CollisionRequest()
        self._creq_contact = fcl.CollisionRequest(num_max_contacts=1, enable_contact=True)
        self._dreq = fcl.DistanceRequest()

    # ------------------------------------------------------------- building
    def _add(self, name: str, geom: Any, group: str, transform: FloatArray | None) -> None:
        if not isinstance(name, str) or not name:
            raise ValidationError(f"object name must be a non-empty string, got {name!r}")
        if name in self._where:
            raise ValidationError(
                f"object {name!r} already exists in group {self._where[name][0]!r}"
            )
        t = np.eye(4) if transform is None else _as_transform(transform, name)
        obj = fcl.CollisionObject(geom, _fcl_transform(t))
        g = self._groups.get(group)
        if g is None:
            g = self._groups[group] = _Group()
        if g.ready:
            g.manager.registerObject(obj)
            g.dirty = True
        self._where[name] = (group, len(g.objects))
        g.names.append(name)
        g.objects.append(obj)
        self._by_geom[id(geom)] = name
        self._geoms.append(geom)

    def add_link_shape(
        self,
        name: str,
        shape: LinkShape,
        group: str,
        transform: FloatArray | None = None,
        padding: float = 0.0,
    ) -> None:
        """Add an arm shape (capsule, box, sphere, cylinder).

        Parameters
        ----------
        name : str
            Unique in the world.
        shape : LinkShape
            Only ``kind`` and ``size`` are used; the pose is ``transform``.
        group : str
        transform : (4, 4) float, optional
            World pose of the shape's centre (default identity).
        padding : float, metres
            Grow the shape (see :func:`link_geometry`).

        Raises
        ------
        multiarm.errors.ValidationError
            On a duplicate name or a bad shape.
        """
        self._add(name, link_geometry(shape, padding), group, transform)

    def add_primitive(self, name: str, prim: Primitive, group: str) -> None:
        """Add a zone solid at its own pose (see :func:`primitive_geometry`).

        Raises
        ------
        multiarm.errors.ValidationError
            On a duplicate name or a bad primitive.
        """
        self._add(name, primitive_geometry(prim), group, prim.transform)

    def add_arm(
        self,
        arm: Arm,
        group: str | None = None,
        q: FloatArray | None = None,
        padding: float = 0.0,
    ) -> tuple[str, ...]:
        """Add every shape of an arm as ``"<arm>/<shape>"`` and allow its allowed pairs.

        Parameters
        ----------
        arm : Arm
        group : str, optional
            Default: the arm's name.
        q : (dof,) float, optional
            Initial joint vector (default ``arm.home``).
        padding : float, metres

        Returns
        -------
        tuple of str
            The object names, in the order of ``arm.shapes`` (the order
            :meth:`set_group_transforms` expects).
        """
        grp = arm.name if group is None else group
        qq = np.asarray(arm.home if q is None else q, dtype=float)
        tfs = arm.shape_transforms(qq[None, :])[0]
        names = tuple(f"{arm.name}/{s.name}" for s in arm.shapes)
        for name, shape, t in zip(names, arm.shapes, tfs, strict=True):
            self.add_link_shape(name, shape, grp, t, padding)
        for pair in arm.allowed_pairs:
            a, b = sorted(pair)
            self.allow(f"{arm.name}/{a}", f"{arm.name}/{b}")
        return names

    def add_mesh(
        self,
        name: str,
        vertices: FloatArray,
        faces: IntArray,
        group: str,
        transform: FloatArray | None = None,
    ) -> None:
        """Add a triangle mesh as an FCL BVH object (:func:`mesh_geometry`).

        Raises
        ------
        multiarm.errors.ValidationError
            On a duplicate name or bad mesh data.
        """
        self._add(name, mesh_geometry(vertices, faces, name), group, transform)

    def add_arm_meshes(
        self, arm: UrdfArm, group: str | None = None, q: FloatArray | None = None
    ) -> tuple[str, ...]:
        """Add the collision meshes of a URDF arm as ``"<arm>/mesh/<link>"`` BVH objects.

        The meshes themselves, not the capsules fitted around them
        (:attr:`workcell.arms.urdf.UrdfArm.meshes`): an independent check of
        the capsule sweep. Move them with :meth:`set_group_transforms` and
        ``arm.mesh_transforms(q)``. Pairs of meshes on the same or adjacent
        frames are allowed (never reported), like the arm's shapes.

        Parameters
        ----------
        arm : UrdfArm
        group : str, optional
            Default: ``"<arm>/meshes"``.
        q : (dof,) float, optional
            Initial joint vector (default ``arm.home``).

        Returns
        -------
        tuple of str
            The object names, in the order of ``arm.meshes``.
        """
        grp = f"{arm.name}/meshes" if group is None else group
        qq = np.asarray(arm.home if q is None else q, dtype=float)
        tfs = arm.mesh_transforms(qq[None, :])[0]
        names = tuple(f"{arm.name}/mesh/{m.name}" for m in arm.meshes)
        for name, mesh, t in zip(names, arm.meshes, tfs, strict=True):
            self.add_mesh(name, mesh.vertices, mesh.faces, grp, t)
        for i, a in enumerate(arm.meshes):
            for j in range(i + 1, len(arm.meshes)):
                if abs(a.frame - arm.meshes[j].frame) <= 1:
                    self.allow(names[i], names[j])
        return names

    def allow(self, a: str, b: str) -> None:
        """Never report the pair ``(a, b)`` (e.g. adjacent links of one arm)."""
        self._allowed.add(frozenset((a, b)))

    # ------------------------------------------------------------- lookup
    def group_names(self, group: str) -> tuple[str, ...]:
        """Object names of a group, in insertion order."""
        return tuple(self._group(group).names)

    @property
    def groups(self) -> tuple[str, ...]:
        """Group names, in creation order."""
        return tuple(self._groups)

    def __contains__(self, name: object) -> bool:
        return name in self._where

    def _group(self, group: str) -> _Group:
        try:
            return self._groups[group]
        except KeyError:
            raise UsageError(
                f"unknown group {group!r} (known: {', '.join(self._groups) or 'none'})"
            ) from None

    def _object(self, name: str) -> tuple[_Group, Any]:
        try:
            grp, i = self._where[name]
        except KeyError:
            raise UsageError(f"unknown object {name!r}") from None
        g = self._groups[grp]
        return g, g.objects[i]

    # ------------------------------------------------------------- moving
    def set_transform(self, name: str, transform: FloatArray) -> None:
        """Move one object to a world pose ``(4, 4)``."""
        g, obj = self._object(name)
        obj.setTransform(_fcl_transform(_as_transform(transform, name)))
        g.dirty = True

    def set_group_transforms(self, group: str, transforms: FloatArray) -> None:
        """Move every object of a group: ``transforms`` is (n, 4, 4), insertion order."""
        g = self._group(group)
        ts = np.asarray(transforms, dtype=float)
        if ts.shape != (len(g.objects), 4, 4):
            raise ValidationError(
                f"group {group!r} has {len(g.objects)} objects; transforms have shape {ts.shape}"
            )
        for obj, t in zip(g.objects, ts, strict=True):
            obj.setTransform(fcl.Transform(t[:3, :3], t[:3, 3]))
        g.dirty = True

    def transform(self, name: str) -> Transform:
        """Current world pose ``(4, 4)`` of an object."""
        _, obj = self._object(name)
        t = np.eye(4)
        t[:3, :3] = obj.getRotation()
        t[:3, 3] = obj.getTranslation()
        return t

    # ------------------------------------------------------------- queries
    def _needs_filter(self, a: _Group, b: _Group | None) -> bool:
        if not self._allowed:
            return False
        na = set(a.names)
        nb = na if b is None else set(b.names)
        return any(len(p) == 2 and p <= (na | nb) and (p & na) and (p & nb) for p in self._allowed)

    def _all_contacts(self, a: str, b: str | None) -> list[tuple[str, str]]:
        ga = self._group(a)
        gb = None if b is None else self._group(b)
        req = self._creq_contact
        name = self._by_geom

        def cb(o1: Any, o2: Any, cdata: Any) -> bool:
            fcl.collide(o1, o2, req, cdata.result)
            return False

        cd = fcl.CollisionData(request=req)
        if gb is None:
            ga.sync().collide(cd, cb)
        else:
            ga.sync().collide(gb.sync(), cd, cb)
        out: list[tuple[str, str]] = []
        for c in cd.result.contacts:
            n1, n2 = name[id(c.o1)], name[id(c.o2)]
            out.append((n1, n2))
        return out

    def _pairs(self, a: str, b: str | None) -> tuple[tuple[str, str], ...]:
        in_a = set(self._group(a).names)
        found: set[tuple[str, str]] = set()
        for n1, n2 in self._all_contacts(a, b):
            if frozenset((n1, n2)) in self._allowed or n1 == n2:
                continue
            if b is None:
                found.add((min(n1, n2), max(n1, n2)))
            else:
                found.add((n1, n2) if n1 in in_a else (n2, n1))
        return tuple(sorted(found))

    def collide(self, a: str, b: str | None = None) -> bool:
        """Whether any object of group ``a`` touches any of group ``b``.

        Parameters
        ----------
        a : str
        b : str, optional
            Without it: pairs inside ``a`` (self-collision).

        Returns
        -------
        bool
            Allowed pairs never count.

        Raises
        ------
        multiarm.errors.UsageError
            For an unknown group.
        """
        ga = self._group(a)
        gb = None if b is None else self._group(b)
        if self._needs_filter(ga, gb) or gb is None:
            return bool(self._pairs(a, b))
        cd = fcl.CollisionData(request=self._creq)
        ga.sync().collide(gb.sync(), cd, fcl.defaultCollisionCallback)
        return bool(cd.result.is_collision)

    def colliding_pairs(self, a: str, b: str | None = None) -> tuple[tuple[str, str], ...]:
        """Every colliding pair of names (see :attr:`CollisionReport.pairs`).

        Raises
        ------
        multiarm.errors.UsageError
            For an unknown group.
        """
        return self._pairs(a, b)

    def min_distance(self, a: str, b: str | None = None) -> float:
        """Smallest distance between groups ``a`` and ``b`` (inside ``a`` without ``b``).

        Returns
        -------
        float, metres
            ``0.0`` when some pair that is not allowed touches; ``inf`` when
            there is no pair to measure.

        Raises
        ------
        multiarm.errors.UsageError
            For an unknown group.
        """
        ga = self._group(a)
        gb = None if b is None else self._group(b)
        if gb is not None and not self._needs_filter(ga, gb):
            if not ga.objects or not gb.objects:
                return float("inf")
            dd = fcl.DistanceData(request=self._dreq)
            ga.sync().distance(gb.sync(), dd, fcl.defaultDistanceCallback)
            return max(0.0, float(dd.result.min_distance))
        others = ga if gb is None else gb
        best = float("inf")
        for i, (n1, o1) in enumerate(zip(ga.names, ga.objects, strict=True)):
            start = i + 1 if gb is None else 0
            for n2, o2 in zip(others.names[start:], others.objects[start:], strict=True):
                if frozenset((n1, n2)) in self._allowed:
                    continue
                d = float(fcl.distance(o1, o2, self._dreq))
                best = min(best, max(0.0, d))
        return best

    def report(self, a: str, b: str | None = None) -> CollisionReport:
        """Colliding pairs and minimum distance in one record.

        Raises
        ------
        multiarm.errors.UsageError
            For an unknown group.
        """
        pairs = self._pairs(a, b)
        return CollisionReport(pairs, 0.0 if pairs else self.min_distance(a, b))

    def first_collision(
        self,
        group: str,
        transforms: FloatArray,
        against: str,
        order: Iterable[int] | None = None,
    ) -> int:
        """Move ``group`` through configurations and find the first that hits ``against``.

        For each configuration the group's objects are moved, the group's
        broadphase manager is refitted and queried against the other group's
        manager (first hit only). The group keeps the last configuration
        tested.
        Allowed pairs are not consulted: use it between groups of different
        owners (an arm against obstacles or zones).

        Parameters
        ----------
        group : str
        transforms : (N, n, 4, 4) float
            ``n`` = number of objects in ``group`` (insertion order).
        against : str
        order : iterable of int, optional
            The order to test configurations in (default ``0..N-1``).

        Returns
        -------
        int
            Index of the first colliding configuration found, or ``-1``.

        Raises
        ------
        multiarm.errors.UsageError
            For an unknown group.
        multiarm.errors.ValidationError
            When ``transforms`` does not match the group.
        """
        g = self._group(group)
        other = self._group(against).sync()
        ts = np.asarray(transforms, dtype=float)
        n = len(g.objects)
        if ts.ndim != 4 or ts.shape[1:] != (n, 4, 4):
            raise ValidationError(
                f"group {group!r} has {n} objects; transforms have shape {ts.shape}, "
                f"expected (N, {n}, 4, 4)"
            )
        objs = g.objects
        mine = g.sync()
        cb = fcl.defaultCollisionCallback
        idx: Iterable[int] = range(len(ts)) if order is None else order
        # One CollisionData serves the whole call: its result only changes on
        # the first hit, and then we return. Manager against manager (after a
        # refit of the small moving manager) is the cheapest query python-fcl
        # offers: object-against-manager calls inspect.isroutine on every call.
        cd = fcl.CollisionData(request=self._creq)
        if len(ts) <= 4:  # small batches: skip the vectorised quaternion set-up
            for k in idx:
                for j in range(n):
                    objs[j].setTransform(fcl.Transform(ts[k, j, :3, :3], ts[k, j, :3, 3]))
                mine.update()
                mine.collide(other, cd, cb)
                if cd.result.is_collision:
                    return int(k)
            return -1
        quat = _quaternions(ts[:, :, :3, :3]).tolist()  # lists: fcl reads them fastest
        trans = np.ascontiguousarray(ts[:, :, :3, 3])
        for k in idx:
            qk, tk = quat[k], trans[k]
            for j in range(n):
                obj = objs[j]
                obj.setQuatRotation(qk[j])
                obj.setTranslation(tk[j])
            mine.update()
            mine.collide(other, cd, cb)
            if cd.result.is_collision:
                return int(k)
        return -1

    def collide_configurations(
        self,
        a: str,
        transforms_a: FloatArray,
        b: str,
        transforms_b: FloatArray,
        pairs: IntArray,
    ) -> BoolArray:
        """Whether group ``a`` in configuration ``i`` touches group ``b`` in configuration ``j``.

        One call for many ``(i, j)`` pairs of two configuration lists (the
        timed check of two arms' motions, :mod:`workcell.exactcheck`): the
        FCL transforms of every configuration are built once, a group is
        moved only when its configuration changes (sort ``pairs`` by ``i``
        to move ``a`` least), and each pair is one broadphase query (first
        hit only). Allowed pairs are not consulted: use it between groups of
        different owners. Both groups keep the last configuration tested.

        Parameters
        ----------
        a, b : str
            Two different groups.
        transforms_a : (Na, n_a, 4, 4) float
        transforms_b : (Nb, n_b, 4, 4) float
            ``n_a``, ``n_b`` = objects in each group (insertion order).
        pairs : (P, 2) int
            Configuration indices ``(i, j)``.

        Returns
        -------
        (P,) bool

        Raises
        ------
        multiarm.errors.UsageError
            For an unknown group, or ``a == b``.
        multiarm.errors.ValidationError
            When the transforms do not match the groups or a pair is out of range.
        """
        if a == b:
            raise UsageError(f"collide_configurations needs two groups, got {a!r} twice")
        ga, gb = self._group(a), self._group(b)
        ta = np.asarray(transforms_a, dtype=float)
        tb = np.asarray(transforms_b, dtype=float)
        for g, name, ts in ((ga, a, ta), (gb, b, tb)):
            n = len(g.objects)
            if ts.ndim != 4 or ts.shape[1:] != (n, 4, 4):
                raise ValidationError(
                    f"group {name!r} has {n} objects; transforms have shape {ts.shape}, "
                    f"expected (N, {n}, 4, 4)"
                )
        pr = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        if len(pr) and (pr.min() < 0 or pr[:, 0].max() >= len(ta) or pr[:, 1].max() >= len(tb)):
            raise ValidationError(
                f"configuration pairs out of range ({len(ta)} and {len(tb)} configurations)"
            )
        out = np.zeros(len(pr), dtype=bool)
        if not len(pr):
            return out
        used_a, used_b = np.unique(pr[:, 0]), np.unique(pr[:, 1])
        fa = {int(i): [_fcl_transform(t) for t in ta[i]] for i in used_a.tolist()}
        fb = {int(j): [_fcl_transform(t) for t in tb[j]] for j in used_b.tolist()}
        ma, mb = ga.sync(), gb.sync()
        cb = fcl.defaultCollisionCallback
        cur_a, cur_b = -1, -1
        for k, (i, j) in enumerate(pr.tolist()):
            if i != cur_a:
                for obj, tf in zip(ga.objects, fa[i], strict=True):
                    obj.setTransform(tf)
                ma.update()
                cur_a = i
            if j != cur_b:
                for obj, tf in zip(gb.objects, fb[j], strict=True):
                    obj.setTransform(tf)
                mb.update()
                cur_b = j
            cd = fcl.CollisionData(request=self._creq)
            ma.collide(mb, cd, cb)
            out[k] = bool(cd.result.is_collision)
        ga.dirty = gb.dirty = False
        return out

    def hits(self, name: str, against: str) -> tuple[str, ...]:
        """Names of the objects of group ``against`` that object ``name`` touches.

        Allowed pairs are left out.
        """
        _, obj = self._object(name)
        g = self._group(against)
        out = []
        for n2, o2 in zip(g.names, g.objects, strict=True):
            if n2 == name or frozenset((name, n2)) in self._allowed:
                continue
            if fcl.collide(obj, o2, self._creq) > 0:
                out.append(n2)
        return tuple(out)


def _as_transform(t: Any, name: str) -> FloatArray:
    arr = np.asarray(t, dtype=float)
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise ValidationError(f"object {name!r}: transform must be a finite (4, 4) array")
    return arr


_QROWS = np.array([[0, 4, 5, 6], [4, 1, 7, 8], [5, 7, 2, 9], [6, 8, 9, 3]])
"""Gather table of the symmetric matrix ``4 q q^T`` from its 10 distinct entries."""

_QLIN = np.zeros((9, 10))
_QLIN[[0, 4, 8], 0] = 1, 1, 1  # 4 w^2 - 1 = m00 + m11 + m22
_QLIN[[0, 4, 8], 1] = 1, -1, -1  # 4 x^2 - 1
_QLIN[[0, 4, 8], 2] = -1, 1, -1  # 4 y^2 - 1
_QLIN[[0, 4, 8], 3] = -1, -1, 1  # 4 z^2 - 1
_QLIN[[7, 5], 4] = 1, -1  # 4 w x = m21 - m12
_QLIN[[2, 6], 5] = 1, -1  # 4 w y = m02 - m20
_QLIN[[3, 1], 6] = 1, -1  # 4 w z = m10 - m01
_QLIN[[1, 3], 7] = 1, 1  # 4 x y = m01 + m10
_QLIN[[2, 6], 8] = 1, 1  # 4 x z = m02 + m20
_QLIN[[5, 7], 9] = 1, 1  # 4 y z = m12 + m21
_QCONST = np.array([1.0, 1.0, 1.0, 1.0, 0, 0, 0, 0, 0, 0])


def _quaternions(rot: FloatArray) -> FloatArray:
    """(..., 4) unit quaternions ``(w, x, y, z)`` of rotation matrices (..., 3, 3).

    Every row of ``4 q q^T`` is proportional to ``q``, and its ten distinct
    entries are linear in the matrix (``4 w^2 = 1 + trace``, ``4 w x = m21 -
    m12``, ...: one matrix product). The row with the largest diagonal entry
    is the best conditioned (Shepperd's rule); normalising it gives ``q`` up
    to sign.
    """
    r = np.asarray(rot, dtype=float)
    ent = r.reshape(*r.shape[:-2], 9) @ _QLIN + _QCONST
    pick = np.argmax(ent[..., :4], axis=-1)
    q = np.take_along_axis(ent, _QROWS[pick], axis=-1)
    out: FloatArray = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return out
