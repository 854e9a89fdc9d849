"""Zone volumes: containment against independent ground truth, bounds, primitives."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial import Delaunay

from zones.geometry import AABox, Cylinder, HalfSpaces, Hull, MeshShape, OBox, Sphere, Union

RNG = np.random.default_rng(0)
CLOUD = RNG.uniform(-2, 2, size=(4000, 3))


def test_aabox() -> None:
    b = AABox((0, 0, 0), (1, 2, 3))
    b.check()
    inside = b.contains(CLOUD)
    truth = np.all((CLOUD >= 0) & (CLOUD <= [1, 2, 3]), axis=1)
    assert np.array_equal(inside, truth)
    assert b.contains([[1, 2, 3], [0, 0, 0]]).all()  # closed
    prim = b.primitives()[0]
    assert prim.kind == "box" and prim.extents == (1, 2, 3)
    assert prim.transform[:3, 3].tolist() == [0.5, 1, 1.5]
    with pytest.raises(ValueError, match="flat"):
        AABox((0, 0, 0), (1, 0, 1)).check()


@given(st.floats(-math.pi, math.pi), st.floats(0.1, 2), st.floats(0.1, 2), st.floats(0.1, 2))
def test_obox_matches_rotated_frame(yaw: float, sx: float, sy: float, sz: float) -> None:
    b = OBox((0.1, -0.2, 0.3), (sx, sy, sz), yaw)
    c, s = math.cos(yaw), math.sin(yaw)
    local = CLOUD - [0.1, -0.2, 0.3]
    lx = c * local[:, 0] + s * local[:, 1]
    ly = -s * local[:, 0] + c * local[:, 1]
    truth = (
        (np.abs(lx) <= sx / 2 - 1e-7)
        & (np.abs(ly) <= sy / 2 - 1e-7)
        & (np.abs(local[:, 2]) <= sz / 2 - 1e-7)
    )
    got = b.contains(CLOUD)
    assert np.all(got[truth])  # everything clearly inside is inside
    outside = (
        (np.abs(lx) > sx / 2 + 1e-7)
        | (np.abs(ly) > sy / 2 + 1e-7)
        | (np.abs(local[:, 2]) > sz / 2 + 1e-7)
    )
    assert not np.any(got[outside])
    lo, hi = b.bounds()
    assert np.all(b.corners() >= np.asarray(lo) - 1e-12) and np.all(
        b.corners() <= np.asarray(hi) + 1e-12
    )


def test_cylinder_and_sphere() -> None:
    cyl = Cylinder((0, 0, -1), 0.5, 2)
    r = np.hypot(CLOUD[:, 0], CLOUD[:, 1])
    truth = (r <= 0.5) & (CLOUD[:, 2] >= -1) & (CLOUD[:, 2] <= 1)
    assert np.array_equal(cyl.contains(CLOUD), truth)
    assert cyl.bounds() == ((-0.5, -0.5, -1), (0.5, 0.5, 1))
    p = cyl.primitives()[0]
    assert p.kind == "cylinder" and p.extents == (0.5, 2) and p.transform[2, 3] == 0.0
    sph = Sphere((1, 1, 1), 0.7)
    assert np.array_equal(sph.contains(CLOUD), np.linalg.norm(CLOUD - 1, axis=1) <= 0.7)
    with pytest.raises(ValueError, match="radius"):
        Sphere((0, 0, 0), 0).check()
    with pytest.raises(ValueError, match="height"):
        Cylinder((0, 0, 0), 1, -1).check()
    with pytest.raises(ValueError, match="non-finite"):
        Sphere((0, math.nan, 0), 1).check()


@given(st.integers(0, 10_000))
def test_hull_matches_delaunay(seed: int) -> None:
    pts = np.random.default_rng(seed).uniform(-1, 1, size=(12, 3))
    h = Hull(tuple(map(tuple, pts)))
    h.check()
    truth = Delaunay(pts).find_simplex(CLOUD) >= 0
    got = h.contains(CLOUD)
    # away from the boundary the two agree exactly
    a, b = h._halfspaces()
    margin = np.max(CLOUD @ a.T - b, axis=1)
    clear = np.abs(margin) > 1e-9
    assert np.array_equal(got[clear], truth[clear])
    prim = h.primitives()[0]
    v, f = prim.vertices, prim.faces
    assert v is not None and f is not None
    # outward winding: every face normal points away from the centroid
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(np.einsum("ij,ij->i", n, tri[:, 0] - v.mean(axis=0)) > 0)


def test_degenerate_hulls() -> None:
    with pytest.raises(ValueError, match="at least 4"):
        Hull(((0, 0, 0), (1, 0, 0), (0, 1, 0))).check()
    with pytest.raises(ValueError, match="no volume"):
        Hull(((0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0))).check()


def test_halfspaces_clip_to_cell() -> None:
    cell = ((0.0, 0.0, 0.0), (4.0, 2.0, 1.0))
    hs = HalfSpaces((("w", 1),), (((1.0, 0.0, 0.0), 1.0),), cell)  # x >= 1
    hs.check()
    lo, hi = hs.bounds()
    assert np.allclose(lo, (1, 0, 0)) and np.allclose(hi, (4, 2, 1))
    pts = np.array([[0.5, 1, 0.5], [1.5, 1, 0.5], [1.5, 3, 0.5]])
    assert hs.contains(pts).tolist() == [False, True, False]
    assert hs.volume() == pytest.approx(6.0)
    empty = HalfSpaces((("a", 1), ("b", -1)), (((1.0, 0, 0), 2.0), ((-1.0, 0, 0), -1.0)), cell)
    with pytest.raises(ValueError, match="no volume"):
        empty.check()


def test_union() -> None:
    u = Union((AABox((0, 0, 0), (1, 1, 1)), Sphere((2, 2, 2), 0.5)))
    u.check()
    assert u.contains([[0.5, 0.5, 0.5], [2, 2, 2.4], [1.5, 1.5, 1.5]]).tolist() == [
        True,
        True,
        False,
    ]
    assert u.bounds() == ((0, 0, 0), (2.5, 2.5, 2.5))
    assert [p.kind for p in u.primitives()] == ["box", "sphere"]
    with pytest.raises(ValueError, match="at least one"):
        Union(()).check()


def test_mesh_shape(tmp_path: Path) -> None:
    import trimesh

    box = trimesh.creation.box(extents=(1, 1, 1))
    box.apply_translation((1, 1, 1))
    box.export(tmp_path / "box.stl")
    m = MeshShape("box.stl", str(tmp_path))
    m.check()
    assert m.contains([[1, 1, 1], [3, 3, 3]]).tolist() == [True, False]
    assert np.allclose(m.bounds(), ((0.5, 0.5, 0.5), (1.5, 1.5, 1.5)))
    assert m.primitives()[0].kind == "mesh"
    assert m.volume() == pytest.approx(1.0)
    open_mesh = trimesh.Trimesh(box.vertices, box.faces[:-2])
    open_mesh.export(tmp_path / "open.stl")
    with pytest.raises(ValueError, match="watertight"):
        MeshShape("open.stl", str(tmp_path)).check()
    with pytest.raises(ValueError, match="cannot load"):
        MeshShape("missing.stl", str(tmp_path)).check()
    assert MeshShape("box.stl", "elsewhere") == m  # loaded geometry is not compared
