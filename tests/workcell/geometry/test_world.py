"""The FCL collision world: hand-computed distances, broadphase updates, allowed pairs."""

from __future__ import annotations

import numpy as np
import pytest

from multiarm.errors import UsageError, ValidationError
from workcell.arms.base import LinkShape
from workcell.geometry import CollisionWorld
from workcell.geometry.world import _quaternions
from zones.geometry import Primitive

from .fake_arm import PlanarArm


def _at(x: float, y: float = 0.0, z: float = 0.0, rot_y: float = 0.0) -> np.ndarray:
    t = np.eye(4)
    c, s = np.cos(rot_y), np.sin(rot_y)
    t[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    t[:3, 3] = (x, y, z)
    return t


def test_two_parallel_capsules_distance_and_collision() -> None:
    w = CollisionWorld()
    w.add_link_shape("a", LinkShape("a", "capsule", (0.05, 0.4), 0), "A")
    w.add_link_shape("b", LinkShape("b", "capsule", (0.05, 0.4), 0), "B", _at(0.3))
    # parallel axes 0.3 apart, radii 0.05 each
    assert w.min_distance("A", "B") == pytest.approx(0.2, abs=1e-6)
    assert not w.collide("A", "B")
    w.set_transform("b", _at(0.09))
    rep = w.report("A", "B")
    assert rep.collision and rep.pairs == (("a", "b"),) and rep.min_distance == 0.0


def test_capsule_end_cap_against_box() -> None:
    # capsule along x (rotated about y), its cap tip at x = 0.2 + 0.05 = 0.25
    w = CollisionWorld()
    w.add_link_shape(
        "cap", LinkShape("cap", "capsule", (0.05, 0.4), 0), "arm", _at(0, rot_y=np.pi / 2)
    )
    box = Primitive("box", _at(0.5), (0.2, 0.2, 0.2))  # faces at x = 0.4 .. 0.6
    w.add_primitive("box", box, "zones")
    assert w.min_distance("arm", "zones") == pytest.approx(0.15, abs=1e-6)
    w.set_transform("cap", _at(0.16, rot_y=np.pi / 2))  # tip at 0.41: inside the box
    assert w.collide("arm", "zones")
    assert w.colliding_pairs("arm", "zones") == (("cap", "box"),)


def test_moving_an_object_updates_the_broadphase() -> None:
    w = CollisionWorld()
    for i in range(5):
        w.add_link_shape(f"s{i}", LinkShape("s", "sphere", (0.05,), 0), "obs", _at(i * 1.0))
    w.add_link_shape("probe", LinkShape("p", "sphere", (0.05,), 0), "arm", _at(0.5, 3.0))
    assert not w.collide("arm", "obs")  # builds and sets up both managers
    w.set_transform("s3", _at(0.5, 3.0))  # an obstacle moves onto the probe
    assert w.collide("arm", "obs")
    assert w.colliding_pairs("arm", "obs") == (("probe", "s3"),)
    w.set_group_transforms("arm", _at(10.0)[None])
    assert not w.collide("arm", "obs")
    assert w.min_distance("arm", "obs") == pytest.approx(10.0 - 4.0 - 0.1, abs=1e-6)


def test_allowed_pairs_are_never_reported() -> None:
    arm = PlanarArm()
    w = CollisionWorld()
    names = w.add_arm(arm, q=np.array([0.0, 0.0]))
    assert names == ("p/link1", "p/link2")
    assert w.colliding_pairs("p") == ()  # the touching links are an allowed pair
    w.add_link_shape("p/tool", LinkShape("tool", "sphere", (0.05,), 0), "p", _at(0.2, 0.0, 0.1))
    assert w.colliding_pairs("p") == (("p/link1", "p/tool"),)
    assert w.collide("p")
    w.allow("p/link1", "p/tool")
    assert not w.collide("p")
    assert w.report("p").min_distance > 0


def test_first_collision_finds_the_first_hitting_configuration() -> None:
    arm = PlanarArm()
    w = CollisionWorld()
    w.add_arm(arm, group="arm")
    w.add_link_shape(
        "post", LinkShape("post", "box", (0.05, 0.05, 0.4), 0), "obs", _at(0.0, 0.5, 0.1)
    )
    q = np.c_[np.linspace(-1.0, 1.6, 27), np.zeros(27)]
    tfs = arm.shape_transforms(q)
    k = w.first_collision("arm", tfs, "obs")
    assert k > 0
    # brute force: every earlier configuration is clear, k collides
    for i in range(k + 1):
        w.set_group_transforms("arm", tfs[i])
        assert w.collide("arm", "obs") == (i == k)
    # the vectorised (quaternion) path and the small-batch path agree
    assert w.first_collision("arm", tfs[k : k + 1], "obs") == 0
    assert w.first_collision("arm", tfs[:k], "obs") == -1


def test_quaternions_round_trip() -> None:
    rng = np.random.default_rng(3)
    q = rng.normal(size=(200, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    rot = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )
    got = _quaternions(rot)
    same = np.minimum(np.abs(got - q).max(axis=1), np.abs(got + q).max(axis=1))
    assert same.max() < 1e-9


def test_errors_name_the_culprit() -> None:
    w = CollisionWorld()
    w.add_link_shape("a", LinkShape("a", "sphere", (0.1,), 0), "A")
    with pytest.raises(ValidationError, match="'a' already exists"):
        w.add_link_shape("a", LinkShape("a", "sphere", (0.1,), 0), "B")
    with pytest.raises(UsageError, match="unknown group 'nope'"):
        w.collide("A", "nope")
    with pytest.raises(UsageError, match="unknown object 'zz'"):
        w.set_transform("zz", np.eye(4))
    with pytest.raises(ValidationError, match="transform must be a finite"):
        w.set_transform("a", np.eye(3))
    with pytest.raises(ValidationError, match="expected 2 finite"):
        w.add_link_shape("c", LinkShape("c", "capsule", (0.1,), 0), "A")
