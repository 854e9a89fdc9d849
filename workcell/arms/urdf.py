"""Serial arms read from URDF: real robot models (UR, Franka Panda, xArm, Kinova, ...).

A URDF file (the robot description format of ROS, MoveIt, pinocchio, PyBullet
and MuJoCo) is read with `yourdfpy <https://github.com/clemense/yourdfpy>`_
(an optional dependency: ``pip install 'multiarm[urdf]'``). From it,
:class:`UrdfArm` takes:

* the **serial chain** from the root link to ``tool_link``: each moving joint's
  origin (fixed joints folded into the next moving one), axis, kind
  (revolute, continuous, prismatic), position limits and velocity limit;
* the **collision geometry** of every link attached to the chain (the links
  on it, and the links hanging from them, such as a gripper's fingers). Each
  collision element (mesh, box, cylinder or sphere) becomes a capsule that
  contains it (:func:`workcell.arms.capsules.fit_capsule`), the arm's
  :attr:`~UrdfArm.shapes` for the compiled sweep and state checks; the
  triangle meshes themselves are kept in :attr:`UrdfArm.meshes` for an
  independent check with FCL (:meth:`workcell.geometry.CollisionWorld.add_arm_meshes`).
  A link hanging from a prismatic joint off the chain (a finger) is fitted at
  both ends of its travel, so the capsule holds it wherever it slides (a
  capsule is convex); its mesh is kept at the upper limit (fingers open).

Forward kinematics is one compiled loop (:mod:`workcell.arms._urdf_jit`);
inverse kinematics is damped least squares on the whole chain, started from
the hint (the branch choice: a hint in one elbow posture keeps that posture),
then the home joints, then fixed pseudo-random starts (seeded, so the same
call gives the same answer). Moves are timed with the servo profile
(:class:`~workcell.arms.profiles.ServoDrive`) at the URDF's velocity limits
times ``velocity_scale``.

Where files come from
---------------------
``urdf`` is a file path, or ``package:NAME/PATH`` for a file shipped in the
installed distribution ``NAME``: the ROS ``share`` directory a
`cmeel <https://github.com/cmake-wheel/cmeel>`_ wheel installs
(``site-packages/cmeel.prefix/share/NAME``; that is how the PyPI
distribution ``example-robot-data`` ships its robots) or, failing that, the
Python package's own directory. Mesh references ``package://NAME/PATH``
resolve the same way, and relative mesh paths relative to the URDF file.
Nothing is downloaded.

Examples
--------
>>> arm = UrdfArm("ur", UR5, tool_link="tool0")
>>> arm.dof, arm.joint_names[0], arm.kind
(6, 'shoulder_pan_joint', 'urdf')
"""

from __future__ import annotations

import functools
import importlib.metadata
import importlib.util
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from multiarm.errors import FormatError, ValidationError
from multiarm.types import FloatArray, IntArray, JointVector, Transform
from workcell.arms._common import DriveArm, numerical_ik
from workcell.arms._urdf_jit import chain_frames
from workcell.arms.base import JointKind, LinkShape
from workcell.arms.capsules import fit_capsule
from workcell.arms.profiles import ServoDrive

__all__ = [
    "PANDA",
    "UR5",
    "LinkMesh",
    "UrdfArm",
    "UrdfModel",
    "load_urdf",
    "resolve_urdf",
]

UR5 = "package:example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
"""The Universal Robots UR5 of the ``example-robot-data`` distribution."""

PANDA = "package:example-robot-data/robots/panda_description/urdf/panda.urdf"
"""The Franka Emika Panda (with its hand) of the ``example-robot-data`` distribution."""

IK_ITERATIONS = 400
"""Levenberg-Marquardt iterations per start (a converging start stops early).
At 100, 2 of 300 seeded random Panda poses near its joint limits stalled
short of the tolerance (tests/workcell/test_urdf.py); at 400, none."""
ACCELERATION_PER_VELOCITY = 5.0
"""Default joint acceleration limit, per second times the velocity limit
(URDF carries no acceleration limit): top speed is reached in 0.2 s."""

CONTINUOUS_RANGE = 2 * math.pi
"""Half range given to a ``continuous`` joint (radians)."""


# ------------------------------------------------------------------ files


def _package_dir(name: str, where: str) -> Path:
    pre = f"{where}: " if where else ""
    """The directory of the installed distribution or package ``name``."""
    try:
        dist = importlib.metadata.distribution(name)
    except importlib.metadata.PackageNotFoundError:
        dist = None
    if dist is not None:
        share = Path(str(dist.locate_file(f"cmeel.prefix/share/{name}")))
        if share.is_dir():
            return share
    module = name.replace("-", "_")
    # a top-level name only: finding "a.b" would import package "a" (and raise
    # ModuleNotFoundError when it is missing)
    spec = importlib.util.find_spec(module) if module.isidentifier() else None
    if spec is not None and spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations)))
    hint = " (pip install 'multiarm[urdf]')" if name == "example-robot-data" else ""
    raise ValidationError(f"{pre}package {name!r} is not installed{hint}")


def _resolve_package(ref: str, where: str) -> Path:
    rest = ref.split(":", 1)[1].lstrip("/")
    name, _, sub = rest.partition("/")
    if not name or not sub:
        pre = f"{where}: " if where else ""
        raise ValidationError(f"{pre}expected 'package:NAME/PATH', got {ref!r}")
    return _package_dir(name, where) / sub


def resolve_urdf(ref: str, base_dir: Path | None = None, where: str = "") -> Path:
    """The file a ``urdf`` reference names (module docstring, "Where files come from").

    Parameters
    ----------
    ref : str
        A path, or ``package:NAME/PATH``.
    base_dir : Path, optional
        Directory relative paths are relative to (the cell file's).
    where : str
        Prefix of error messages.

    Raises
    ------
    ValidationError
        When the package is not installed or the file does not exist.
    """
    pre = f"{where}: " if where else ""
    if not isinstance(ref, str) or not ref:
        raise ValidationError(f"{pre}expected a file path or 'package:NAME/PATH', got {ref!r}")
    if ref.startswith("package:"):
        path = _resolve_package(ref, where)
    else:
        path = Path(ref)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
    if not path.is_file():
        raise ValidationError(f"{pre}file {str(path)!r} does not exist")
    return path


# ------------------------------------------------------------------ model


@dataclass(frozen=True, slots=True, eq=False)
class LinkMesh:
    """One collision element of a link as a triangle mesh.

    Attributes
    ----------
    name : str
        The link's name (with ``#k`` for its k-th collision element, k >= 1).
    frame : int
        The kinematic frame it rides on (0 = the arm's base).
    vertices : (V, 3) float
        In that frame, metres.
    faces : (F, 3) int
    """

    name: str
    frame: int
    vertices: FloatArray
    faces: IntArray


@dataclass(frozen=True, slots=True, eq=False)
class UrdfModel:
    """The kinematic chain and collision geometry read from a URDF file.

    Attributes
    ----------
    source : str
        The file.
    robot : str
        The URDF's robot name.
    root, tool_link : str
        First and last link of the chain.
    joint_names : tuple of str
        The chain's moving joints, root to tool.
    joint_kinds : tuple of {"revolute", "prismatic"}
    origins : (n, 4, 4) float
        Each joint's origin in its parent frame (fixed joints folded in).
    axes : (n, 3) float
        Unit joint axes.
    limits : (n, 2) float
    velocity : (n,) float
        Velocity limits (rad/s or m/s).
    tool : (4, 4) float
        The tool link in the last joint's frame.
    meshes : tuple of LinkMesh
        Collision meshes of every attached link, in their frames.
    hulls : tuple of (V, 3) float
        Per mesh, the points a capsule must contain (the convex hull's
        vertices, at both ends of an off-chain slide).
    """

    source: str
    robot: str
    root: str
    tool_link: str
    joint_names: tuple[str, ...]
    joint_kinds: tuple[JointKind, ...]
    origins: FloatArray
    axes: FloatArray
    limits: FloatArray
    velocity: FloatArray
    tool: FloatArray
    meshes: tuple[LinkMesh, ...]
    hulls: tuple[FloatArray, ...]


def _yourdfpy() -> Any:
    try:
        import yourdfpy
    except ImportError:  # pragma: no cover - the extra is installed by make test
        raise ValidationError(
            "URDF arms need the optional dependency yourdfpy: pip install 'multiarm[urdf]'"
        ) from None
    return yourdfpy


def _mesh_handler(urdf_path: Path, where: str) -> Any:
    def handler(fname: str) -> str:
        if fname.startswith("package://"):
            return str(_resolve_package("package:" + fname[len("package://") :], where))
        if fname.startswith("file://"):
            fname = fname[len("file://") :]
        p = Path(fname)
        return str(p if p.is_absolute() else urdf_path.parent / p)

    return handler


def _element_mesh(geometry: Any, handler: Any, where: str) -> tuple[FloatArray, IntArray]:
    import trimesh

    if geometry.mesh is not None:
        fname = handler(geometry.mesh.filename)
        try:
            loaded = trimesh.load(fname, force="mesh")
        except Exception as exc:  # trimesh raises many kinds on unreadable files
            raise FormatError(f"{where}: cannot read mesh {fname!r}: {exc}") from None
        mesh: Any = loaded
        scale = geometry.mesh.scale
        v = np.asarray(mesh.vertices, dtype=float)
        if scale is not None:
            v = v * np.broadcast_to(np.asarray(scale, dtype=float), (3,))
        return v, np.asarray(mesh.faces, dtype=np.int64)
    if geometry.box is not None:
        prim = trimesh.creation.box(extents=np.asarray(geometry.box.size, dtype=float))
    elif geometry.cylinder is not None:
        # a polygon's sides cut inside the circle: circumscribe it
        sections = 32
        prim = trimesh.creation.cylinder(
            radius=float(geometry.cylinder.radius) / math.cos(math.pi / sections),
            height=float(geometry.cylinder.length),
            sections=sections,
        )
    elif geometry.sphere is not None:
        # an icosphere's faces cut inside the sphere: scale it to circumscribe it
        prim = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        inner = float(np.min(np.abs(np.sum(prim.face_normals * prim.triangles[:, 0], axis=1))))
        prim.apply_scale(float(geometry.sphere.radius) / inner)
    else:
        raise ValidationError(f"{where}: collision element without geometry")
    return np.asarray(prim.vertices, dtype=float), np.asarray(prim.faces, dtype=np.int64)


def _hull_points(v: FloatArray) -> FloatArray:
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(v)
    except (QhullError, ValueError):  # flat or tiny: every vertex
        return v
    out: FloatArray = v[hull.vertices]
    return out


def _apply(t: FloatArray, v: FloatArray) -> FloatArray:
    out: FloatArray = v @ t[:3, :3].T + t[:3, 3]
    return out


@functools.lru_cache(maxsize=16)
def _load(path: str, tool_link: str) -> UrdfModel:
    where = path
    yd = _yourdfpy()
    try:
        urdf = yd.URDF.load(
            path,
            load_meshes=False,
            load_collision_meshes=False,
            build_scene_graph=False,
            build_collision_scene_graph=False,
        )
    except Exception as exc:  # lxml and yourdfpy raise many kinds on bad files
        raise FormatError(f"{where}: not a readable URDF file: {exc}") from None
    robot = urdf.robot
    links = {ln.name: ln for ln in robot.links}
    by_child = {j.child: j for j in robot.joints}
    children: dict[str, list[Any]] = {}
    for j in robot.joints:
        children.setdefault(j.parent, []).append(j)
    if tool_link not in links:
        raise ValidationError(
            f"{where}: no link {tool_link!r} for tool_link (links: {', '.join(sorted(links))})"
        )
    chain_joints: list[Any] = []
    link = tool_link
    while link in by_child:
        j = by_child[link]
        chain_joints.append(j)
        link = j.parent
    root = link
    chain_joints.reverse()
    chain_links = [root] + [j.child for j in chain_joints]

    def origin(j: Any) -> FloatArray:
        return np.eye(4) if j.origin is None else np.asarray(j.origin, dtype=float)

    names: list[str] = []
    kinds: list[JointKind] = []
    origins: list[FloatArray] = []
    axes: list[FloatArray] = []
    limits: list[tuple[float, float]] = []
    velocity: list[float] = []
    frame_of: dict[str, tuple[int, FloatArray]] = {root: (0, np.eye(4))}
    for j in chain_joints:
        jw = f"{where}: joint {j.name!r}"
        if j.type == "fixed":
            frame, off = frame_of[j.parent]
            frame_of[j.child] = (frame, off @ origin(j))
            continue
        if j.type not in ("revolute", "continuous", "prismatic"):
            raise ValidationError(f"{jw}: joint type {j.type!r} is not supported in a serial chain")
        if j.mimic is not None:
            raise ValidationError(f"{jw}: a mimic joint cannot be on the serial chain")
        axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else np.asarray(j.axis, dtype=float)
        if not np.all(np.isfinite(axis)) or np.linalg.norm(axis) < 1e-12:
            raise ValidationError(f"{jw}: axis {axis.tolist()} is not a direction")
        lim = j.limit
        if j.type == "continuous":
            lo, hi = -CONTINUOUS_RANGE, CONTINUOUS_RANGE
        elif lim is None or lim.lower is None or lim.upper is None or not lim.lower < lim.upper:
            raise ValidationError(f"{jw}: needs <limit lower=... upper=...> with lower < upper")
        else:
            lo, hi = float(lim.lower), float(lim.upper)
        vel = None if lim is None or lim.velocity is None else float(lim.velocity)
        if vel is None or not (math.isfinite(vel) and vel > 0):
            raise ValidationError(f"{jw}: needs a positive velocity limit, got {vel!r}")
        # the fixed joints before it ride on the previous moving frame
        t_parent = frame_of[j.parent][1]
        origins.append(t_parent @ origin(j))
        axes.append(axis / np.linalg.norm(axis))
        kinds.append("prismatic" if j.type == "prismatic" else "revolute")
        names.append(j.name)
        limits.append((lo, hi))
        velocity.append(vel)
        frame_of[j.child] = (len(names), np.eye(4))
    if not names:
        raise ValidationError(f"{where}: no moving joint between {root!r} and {tool_link!r}")
    tool = frame_of[tool_link][1]

    # every link attached to the chain: (link, frame, pose in frame, slide)
    attached: list[tuple[str, int, FloatArray, FloatArray | None]] = []
    stack: list[tuple[str, int, FloatArray, FloatArray | None]] = [
        (ln, *frame_of[ln], None) for ln in chain_links
    ]
    on_chain = set(chain_links)
    while stack:
        ln, frame, pose, slide = stack.pop(0)
        attached.append((ln, frame, pose, slide))
        for j in children.get(ln, []):
            if j.child in on_chain:
                continue
            jw = f"{where}: joint {j.name!r}"
            o = pose @ origin(j)
            if j.type == "fixed":
                stack.append((j.child, frame, o, slide))
            elif j.type == "prismatic":
                if slide is not None:
                    raise ValidationError(f"{jw}: two slides off the chain are not supported")
                lim = j.limit
                if lim is None or lim.lower is None or lim.upper is None:
                    raise ValidationError(f"{jw}: needs <limit lower=... upper=...>")
                axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else np.asarray(j.axis, float)
                axis = axis / np.linalg.norm(axis)
                lo_t, hi_t = np.eye(4), np.eye(4)
                lo_t[:3, 3] = axis * float(lim.lower)
                hi_t[:3, 3] = axis * float(lim.upper)
                # the pose at the upper limit; the slide back to the lower one
                stack.append((j.child, frame, o @ hi_t, (o @ lo_t) @ np.linalg.inv(o @ hi_t)))
            else:
                raise ValidationError(
                    f"{jw}: a {j.type} joint off the chain to {tool_link!r} is not supported "
                    "(choose a tool_link beyond it)"
                )

    handler = _mesh_handler(Path(path), where)
    meshes: list[LinkMesh] = []
    hulls: list[FloatArray] = []
    for ln, frame, pose, slide in attached:
        for k, col in enumerate(links[ln].collisions):
            lw = f"{where}: link {ln!r} collision {k}"
            v, f = _element_mesh(col.geometry, handler, lw)
            if len(v) == 0:
                continue
            t = pose @ (np.eye(4) if col.origin is None else np.asarray(col.origin, float))
            vv = _apply(t, v)
            hull = _hull_points(vv)
            if slide is not None:
                hull = np.vstack([hull, _apply(slide, hull)])
            label = ln if k == 0 else f"{ln}#{k}"
            meshes.append(LinkMesh(label, frame, vv, f))
            hulls.append(hull)
    return UrdfModel(
        source=path,
        robot=str(robot.name),
        root=root,
        tool_link=tool_link,
        joint_names=tuple(names),
        joint_kinds=tuple(kinds),
        origins=np.ascontiguousarray(np.stack(origins)),
        axes=np.ascontiguousarray(np.stack(axes)),
        limits=np.array(limits, dtype=float),
        velocity=np.array(velocity, dtype=float),
        tool=np.ascontiguousarray(tool),
        meshes=tuple(meshes),
        hulls=tuple(hulls),
    )


def load_urdf(ref: str, tool_link: str, base_dir: Path | None = None) -> UrdfModel:
    """Read the chain from the root link to ``tool_link`` and its collision meshes.

    Read once per file and tool link (cached); the meshes are loaded with
    trimesh from local files only.

    Parameters
    ----------
    ref : str
        A path or ``package:NAME/PATH`` (:func:`resolve_urdf`).
    tool_link : str
        The link whose frame is the arm's flange.
    base_dir : Path, optional
        Directory relative paths are relative to.

    Raises
    ------
    ValidationError
        Missing file or package, unknown link, unsupported joint.
    FormatError
        An unreadable URDF or mesh file.
    """
    path = resolve_urdf(ref, base_dir)
    return _load(str(path.resolve()), tool_link)


# ------------------------------------------------------------------ the arm


def _shape_from(name: str, frame: int, hull: FloatArray) -> LinkShape:
    cap = fit_capsule(hull)
    if cap.length < 1e-9:
        off = np.eye(4)
        off[:3, 3] = cap.p0
        return LinkShape(name, "sphere", (cap.radius,), frame, off)
    return LinkShape(name, "capsule", (cap.radius, cap.length), frame, cap.pose())


@functools.lru_cache(maxsize=16)
def _fitted(model: UrdfModel) -> tuple[LinkShape, ...]:
    return tuple(
        _shape_from(m.name, m.frame, h) for m, h in zip(model.meshes, model.hulls, strict=True)
    )


class UrdfArm(DriveArm):
    """A serial arm from a URDF file (module docstring).

    Parameters
    ----------
    name : str
    urdf : str
        A path or ``package:NAME/PATH``.
    tool_link : str
        The link whose frame is the flange (the pose :meth:`ik` reaches).
    base : (4, 4) float, optional
        Pose of the URDF's root link in the cell.
    joint_limits : (n, 2) float, optional
        Narrower limits than the URDF's (each within them).
    velocity_scale : float
        Fraction (0, 1] of the URDF's velocity limits the drives use.
    max_acceleration : (n,) float, optional
        Default: :data:`ACCELERATION_PER_VELOCITY` times the velocity limits.
    base_dir : Path, optional
        Directory relative ``urdf`` paths are relative to.

    Raises
    ------
    ValidationError
        Naming the arm and the field.
    """

    kind = "urdf"
    interpolation = "sync"

    def __init__(
        self,
        name: str,
        urdf: str,
        *,
        tool_link: str,
        base: Transform | None = None,
        joint_limits: Sequence[Sequence[float]] | None = None,
        velocity_scale: float = 1.0,
        max_acceleration: Sequence[float] | None = None,
        capabilities: Iterable[str] = ("gripper",),
        tools: Iterable[str] = (),
        payload: float = 3.0,
        home: JointVector | None = None,
        base_dir: Path | None = None,
    ) -> None:
        self.name = name
        where = f"urdf arm {name!r}"
        model = load_urdf(urdf, tool_link, base_dir)
        self.model = model
        n = len(model.joint_names)
        self.joint_names = model.joint_names
        self.joint_kinds = model.joint_kinds
        lim = model.limits.copy()
        if joint_limits is not None:
            jl = np.array(joint_limits, dtype=float)
            if jl.shape != (n, 2) or not np.all(jl[:, 0] < jl[:, 1]):
                raise ValidationError(f"{where}: joint_limits must be {n} (low < high) pairs")
            bad = np.flatnonzero((jl[:, 0] < lim[:, 0] - 1e-12) | (jl[:, 1] > lim[:, 1] + 1e-12))
            if len(bad):
                j = int(bad[0])
                raise ValidationError(
                    f"{where}: joint_limits of {model.joint_names[j]!r} {jl[j].tolist()} go "
                    f"beyond the URDF's [{lim[j, 0]:.6g}, {lim[j, 1]:.6g}]"
                )
            lim = jl
        self.joint_limits = lim
        if not (math.isfinite(velocity_scale) and 0 < velocity_scale <= 1):
            raise ValidationError(
                f"{where}: velocity_scale must be in (0, 1], got {velocity_scale!r}"
            )
        vel = model.velocity * float(velocity_scale)
        acc = (
            model.velocity * ACCELERATION_PER_VELOCITY
            if max_acceleration is None
            else np.array(max_acceleration, dtype=float)
        )
        if acc.shape != (n,) or not np.all(np.isfinite(acc) & (acc > 0)):
            raise ValidationError(f"{where}: max_acceleration must be {n} positive numbers")
        self.drives = tuple(ServoDrive(float(v), float(a)) for v, a in zip(vel, acc, strict=True))
        self.base = np.eye(4) if base is None else np.array(base, dtype=float)
        self.capabilities = frozenset(capabilities)
        self.tools = tuple(tools)
        self.payload = float(payload)
        self.shapes = _fitted(model)
        self.meshes = model.meshes
        self.allowed_pairs = frozenset(
            frozenset({a.name, b.name})
            for i, a in enumerate(self.shapes)
            for b in self.shapes[i + 1 :]
            if abs(a.frame - b.frame) <= 1
        )
        if home is None:
            home = np.clip(np.zeros(n), lim[:, 0], lim[:, 1])
        self.home = np.array(home, dtype=float)
        if self.home.shape != (n,) or not bool(self.within_limits(self.home[None])[0]):
            raise ValidationError(f"{where}: home {self.home.tolist()} is outside its limits")
        self._prism = np.array([k == "prismatic" for k in self.joint_kinds])
        self._reach = self._reaches()
        steps = np.linalg.norm(model.origins[:, :3, 3], axis=1)
        travel = np.where(self._prism, np.max(np.abs(lim), axis=1), 0.0)
        self._base_c = np.ascontiguousarray(self.base)
        self._shoulder = (self.base @ model.origins[0])[:3, 3]
        self._max_reach = (
            math.inf
            if self._prism[0]
            else float(steps[1:].sum() + travel.sum() + np.linalg.norm(model.tool[:3, 3])) + 1e-9
        )

    # ------------------------------------------------------- kinematics
    def frames(self, q: FloatArray) -> FloatArray:
        """(N, n + 2, 4, 4): the base, each joint's child link, the tool link."""
        qq = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=float)))
        m = self.model
        out: FloatArray = chain_frames(
            np.ascontiguousarray(self.base), m.origins, m.axes, self._prism, m.tool, qq
        )
        return out

    def _reaches(self) -> FloatArray:
        """Per joint, a bound over the whole joint space on the distance of any
        distal shape point from its axis (a point on the axis, the joint
        frame's origin, to the shape's farthest point through the chain)."""
        m = self.model
        n = len(m.joint_names)
        steps = np.linalg.norm(m.origins[:, :3, 3], axis=1)
        travel = np.where(self._prism, np.max(np.abs(self.joint_limits), axis=1), 0.0)
        out = np.zeros(n)
        for s in self.shapes:
            far = float(np.linalg.norm(s.offset[:3, 3])) + s.radius()
            for k in range(s.frame):  # joint k moves frame k + 1 and beyond
                if self._prism[k]:
                    out[k] = 1.0
                    continue
                lever = float(steps[k + 1 : s.frame].sum() + travel[k + 1 : s.frame].sum()) + far
                out[k] = max(out[k], lever)
        return out

    def displacement_bound(self, dq: FloatArray) -> FloatArray:
        out: FloatArray = np.abs(np.atleast_2d(dq)) @ self._reach
        return out

    def ik(self, pose: Transform, q_hint: JointVector | None = None) -> JointVector:
        m = self.model
        chain = (self._base_c, m.origins, m.axes, self._prism, m.tool)
        return numerical_ik(
            self, pose, q_hint, self._shoulder, self._max_reach, chain, IK_ITERATIONS
        )

    def mesh_transforms(self, q: FloatArray) -> FloatArray:
        """(N, M, 4, 4) world pose of every collision mesh's frame for ``q`` (N, dof)."""
        fr = self.frames(np.atleast_2d(q))
        idx = np.array([mm.frame for mm in self.meshes], dtype=np.int64)
        out: FloatArray = fr[:, idx]
        return out
