"""The compiled sweep loops give exactly the answers of the vectorised numpy reference."""

from __future__ import annotations

import numpy as np
import pytest

from workcell.arms import Scara
from workcell.geometry import zone_sweep
from workcell.geometry.zone_sweep import _arm_contacts_numpy, _contacts_block_numpy, arm_contacts


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def _solids(rng: np.random.Generator, n: int) -> zone_sweep._Solids:
    faces = 6
    cvx_n = np.zeros((n, faces + 2, 3))  # two zero rows: the padding of ragged hulls
    cvx_b = np.ones((n, faces + 2))
    for k in range(n):
        normals = rng.normal(size=(faces, 3))
        cvx_n[k, :faces] = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        cvx_b[k, :faces] = rng.uniform(0.05, 0.3, faces) + cvx_n[k, :faces] @ rng.uniform(-1, 1, 3)
    cvx_n[0, 0] = (1.0, 0.0, 0.0)  # an axis-aligned face: segments parallel to it are common
    zones = lambda: rng.integers(0, 5, n).astype(np.int64)  # noqa: E731
    return zone_sweep._Solids(
        sph_c=rng.uniform(-1, 1, (n, 3)),
        sph_r=rng.uniform(0.01, 0.3, n),
        sph_z=zones(),
        box_r=np.stack([_rotation(rng) for _ in range(n)]),
        box_c=rng.uniform(-1, 1, (n, 3)),
        box_h=rng.uniform(0.01, 0.3, (n, 3)),
        box_z=zones(),
        cyl_r=np.stack([np.eye(3) if k == 0 else _rotation(rng) for k in range(n)]),
        cyl_c=rng.uniform(-1, 1, (n, 3)),
        cyl_rad=rng.uniform(0.01, 0.3, n),
        cyl_h=rng.uniform(0.01, 0.3, n),
        cyl_z=zones(),
        cvx_n=cvx_n,
        cvx_b=cvx_b,
        cvx_z=zones(),
        mesh=(),
    )


@pytest.mark.parametrize("seed", range(4))
def test_compiled_zone_contacts_equal_the_numpy_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    solids = _solids(rng, 6)
    p0 = rng.uniform(-1.2, 1.2, (400, 3, 3))
    p1 = p0 + rng.normal(scale=0.3, size=p0.shape)
    p1[:50, 0] = p0[:50, 0]  # point-like capsules
    p1[50:100, 1, 2] = p0[50:100, 1, 2]  # segments flat along an axis
    rad = rng.uniform(0.0, 0.1, 3)
    want = _contacts_block_numpy(p0, p1, rad, solids, 5)
    got = zone_sweep._contacts_block(p0, p1, rad, solids, 5)
    assert want.any() and not want.all()  # the case discriminates
    np.testing.assert_array_equal(got, want)


def test_compiled_arm_contacts_equal_the_numpy_reference() -> None:
    rng = np.random.default_rng(7)
    mover = Scara("a", base=np.eye(4))
    other_base = np.eye(4)
    other_base[:3, 3] = (0.6, 0.0, 0.0)
    other = Scara("b", base=other_base)
    lo, hi = mover.joint_limits[:, 0], mover.joint_limits[:, 1]
    q = rng.uniform(lo, hi, (500, len(lo)))
    q_other = rng.uniform(lo, hi)
    want = _arm_contacts_numpy(mover, q, other, q_other, 0.01)
    got = arm_contacts(mover, q, other, q_other, 0.01)
    assert want.any() and not want.all()
    np.testing.assert_array_equal(got, want)
