"""A cell as a trimesh scene at given joint vectors; GLB export and PNG views.

Examples
--------
>>> import tempfile, pathlib
>>> from workcell import load_example
>>> cell = load_example("scara4")
>>> out = pathlib.Path(tempfile.mkdtemp())
>>> export_glb(cell, out / "scara4.glb").stat().st_size > 1000
True
>>> render_png(cell, out / "top.png", view="top").is_file()
True
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import Any, Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray
from workcell.arms.base import LinkShape
from workcell.cell import Cell

__all__ = ["cell_scene", "export_glb", "render_png"]

_ZONE_RGBA = {"exclusive": (220, 80, 60, 70), "shared": (60, 120, 220, 70)}
_ARM_RGBA = (90, 90, 90, 255)


def _shape_mesh(shape: LinkShape) -> Any:
    import trimesh

    if shape.kind == "box":
        return trimesh.creation.box(extents=shape.size)
    if shape.kind == "capsule":
        return trimesh.creation.capsule(height=shape.size[1], radius=shape.size[0], count=[10, 10])
    if shape.kind == "cylinder":
        return trimesh.creation.cylinder(radius=shape.size[0], height=shape.size[1], sections=16)
    return trimesh.creation.icosphere(subdivisions=1, radius=shape.size[0])


def _zone_meshes(cell: Cell) -> list[tuple[str, str, Any]]:
    """(zone name, policy, mesh) for every solid of every zone."""
    import trimesh

    out = []
    zm = cell.zone_map
    names, excl = zm.zone_names(), zm.exclusive_mask()
    for z, name in enumerate(names):
        for prim in zm.primitives(z):
            if prim.kind == "box":
                mesh = trimesh.creation.box(extents=prim.extents, transform=prim.transform)
            elif prim.kind == "cylinder":
                mesh = trimesh.creation.cylinder(
                    radius=prim.extents[0], height=prim.extents[1], transform=prim.transform
                )
            elif prim.kind == "sphere":
                mesh = trimesh.creation.icosphere(subdivisions=2, radius=prim.extents[0])
                mesh.apply_transform(prim.transform)
            else:
                mesh = trimesh.Trimesh(vertices=prim.vertices, faces=prim.faces, process=False)
            out.append((name, "exclusive" if bool(excl[z]) else "shared", mesh))
    return out


def _joints(cell: Cell, joints: Mapping[str, Sequence[float]] | None) -> list[FloatArray]:
    out = []
    joints = joints or {}
    unknown = set(joints) - {a.name for a in cell.arms}
    if unknown:
        raise ValidationError(f"cell {cell.name!r} has no arm {sorted(unknown)[0]!r}")
    for arm, q0 in zip(cell.arms, cell.start, strict=True):
        q = np.asarray(joints.get(arm.name, q0), dtype=float)
        if q.shape != (arm.dof,):
            raise ValidationError(f"arm {arm.name!r} needs {arm.dof} joint values, got {q.shape}")
        out.append(q)
    return out


def cell_scene(cell: Cell, joints: Mapping[str, Sequence[float]] | None = None) -> Any:
    """A ``trimesh.Scene`` of the cell: zones (translucent) and arms at ``joints``.

    Parameters
    ----------
    cell : Cell
    joints : mapping of arm name to (dof,) float, optional
        Joint vectors; arms not named stand at their start joints.
    """
    import trimesh

    scene = trimesh.Scene()
    for k, (name, policy, mesh) in enumerate(_zone_meshes(cell)):
        mesh.visual.face_colors = _ZONE_RGBA[policy]
        scene.add_geometry(mesh, node_name=f"zone:{name}:{k}", geom_name=f"zone:{name}:{k}")
    for arm, q in zip(cell.arms, _joints(cell, joints), strict=True):
        tfs = arm.shape_transforms(q[None])[0]
        for shape, tf in zip(arm.shapes, tfs, strict=True):
            mesh = _shape_mesh(shape)
            mesh.visual.face_colors = _ARM_RGBA
            node = f"{arm.name}:{shape.name}"
            scene.add_geometry(mesh, node_name=node, geom_name=node, transform=tf)
    return scene


def export_glb(
    cell: Cell,
    path: str | PathLike[str],
    joints: Mapping[str, Sequence[float]] | None = None,
) -> Path:
    """Write the cell (zones and arms at ``joints``) as a GLB file; returns the path."""
    p = Path(path)
    cell_scene(cell, joints).export(p)
    return p


def render_png(
    cell: Cell,
    path: str | PathLike[str],
    joints: Mapping[str, Sequence[float]] | None = None,
    *,
    view: Literal["top", "3d"] = "top",
) -> Path:
    """Draw the cell (matplotlib, headless) from the top or in 3D; returns the path.

    Zones are translucent (red: exclusive, blue: shared), arms grey and
    labelled.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # type: ignore[import-untyped]
    from scipy.spatial import ConvexHull, QhullError

    if view not in ("top", "3d"):
        raise ValidationError(f"view must be 'top' or '3d', not {view!r}")
    scene = cell_scene(cell, joints)
    lo, hi = (np.asarray(b, dtype=float) for b in cell.zone_map.bounds)
    fig = plt.figure(figsize=(7, 5))
    if view == "3d":
        ax = fig.add_subplot(projection="3d")
        for node in scene.graph.nodes_geometry:
            tf, gname = scene.graph[node]
            mesh = scene.geometry[gname].copy()
            mesh.apply_transform(tf)
            rgba = np.asarray(mesh.visual.face_colors[0], dtype=float) / 255
            ax.add_collection3d(Poly3DCollection(mesh.triangles, facecolor=rgba, edgecolor="none"))
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        ax.set_zlabel("z (m)")
    else:
        ax = fig.add_subplot()
        for node in scene.graph.nodes_geometry:
            tf, gname = scene.graph[node]
            mesh = scene.geometry[gname].copy()
            mesh.apply_transform(tf)
            rgba = np.asarray(mesh.visual.face_colors[0], dtype=float) / 255
            xy = mesh.vertices[:, :2]
            try:
                hull = xy[ConvexHull(xy).vertices]
            except QhullError:  # a flat outline: fall back to its bounding box
                (x0, y0), (x1, y1) = xy.min(0), xy.max(0)
                hull = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
            ax.add_patch(Polygon(hull, closed=True, color=rgba))
        for arm, q in zip(cell.arms, _joints(cell, joints), strict=True):
            x, y = arm.fk(q[None])[0, :2, 3]
            ax.annotate(arm.name, (x, y), fontsize=8, color="black")
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{cell.name} ({view} view)")
    p = Path(path)
    fig.savefig(p, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return p
