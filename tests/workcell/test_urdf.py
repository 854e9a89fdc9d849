"""URDF arms (workcell.arms.urdf): kinematics against yourdfpy's own, IK, the
fitted capsules against the meshes, the FCL mesh objects, the cell-file
fields and the built-in cell urdf_cell."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from multiarm.errors import MultiarmError, Unreachable, ValidationError
from workcell.arms import arm_from_dict
from workcell.arms.capsules import (
    FittedCapsule,
    capsule_contains,
    capsule_volume,
    fit_capsule,
)
from workcell.arms.urdf import PANDA, UR5, UrdfArm, resolve_urdf
from workcell.geometry import CollisionWorld

yourdfpy = pytest.importorskip("yourdfpy")
trimesh = pytest.importorskip("trimesh")

ARMS = {"ur5": (UR5, "tool0"), "panda": (PANDA, "panda_hand_tcp")}


@pytest.fixture(scope="module")
def arms() -> dict[str, UrdfArm]:
    """The UR5 and the Panda, read once for the module."""
    return {k: UrdfArm(k, ref, tool_link=tool) for k, (ref, tool) in ARMS.items()}


def _random_q(arm: UrdfArm, rng: np.random.Generator, n: int) -> Any:
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    return lo + (hi - lo) * rng.random((n, arm.dof))


def _shape_capsule(shape: Any) -> FittedCapsule:
    """The shape as a capsule in its frame (the fitted shapes are capsules or spheres)."""
    off = np.asarray(shape.offset)
    if shape.kind == "sphere":
        return FittedCapsule(off[:3, 3], off[:3, 3], shape.size[0])
    half = shape.size[1] / 2
    return FittedCapsule(
        off[:3, 3] - half * off[:3, 2], off[:3, 3] + half * off[:3, 2], shape.size[0]
    )


@pytest.mark.parametrize("name", sorted(ARMS))
def test_forward_kinematics_matches_yourdfpy(arms: dict[str, UrdfArm], name: str) -> None:
    """The compiled chain gives the tool link's pose yourdfpy computes from the
    same file (its own scene graph, mimic fingers included), for seeded random
    joint vectors."""
    arm = arms[name]
    ref, tool = ARMS[name]
    robot = yourdfpy.URDF.load(
        str(resolve_urdf(ref)), load_meshes=False, load_collision_meshes=False
    )
    rng = np.random.default_rng(7)
    qs = _random_q(arm, rng, 20)
    ours = arm.fk(qs)
    for q, t in zip(qs, ours, strict=True):
        cfg = dict(zip(arm.joint_names, q, strict=True))
        robot.update_cfg(cfg)
        want = robot.get_transform(tool, arm.model.root)
        np.testing.assert_allclose(t, want, atol=1e-9)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_ik_reaches_random_reachable_poses_within_limits(
    arms: dict[str, UrdfArm], name: str
) -> None:
    """Poses of seeded random joint vectors are reached (1e-8) within the
    limits from a nearby hint, and the same call gives the same answer."""
    arm = arms[name]
    rng = np.random.default_rng(11)
    for q in _random_q(arm, rng, 15):
        pose = arm.fk(q[None])[0]
        hint = np.clip(q + rng.normal(0, 0.2, arm.dof), *arm.joint_limits.T)
        sol = arm.ik(pose, hint)
        assert bool(arm.within_limits(sol[None])[0])
        np.testing.assert_allclose(arm.fk(sol[None])[0], pose, atol=1e-8)
        np.testing.assert_array_equal(arm.ik(pose, hint), sol)


def test_ik_hint_picks_the_branch(arms: dict[str, UrdfArm]) -> None:
    """Two UR5 postures reaching one pose (shoulder turned the other way): the
    hint near each gives back that posture."""
    arm = arms["ur5"]
    q_a = np.array([0.3, -1.2, 1.5, -1.9, -1.57, 0.2])
    pose = arm.fk(q_a[None])[0]
    sol_a = arm.ik(pose, q_a + 0.05)
    np.testing.assert_allclose(sol_a, q_a, atol=1e-6)
    # the elbow-down solution of the same pose, found from a far start
    q_b = None
    for start in _random_q(arm, np.random.default_rng(3), 40):
        try:
            s = arm.ik(pose, start)
        except Unreachable:
            continue
        if np.linalg.norm(s - q_a) > 0.5:
            q_b = s
            break
    assert q_b is not None
    np.testing.assert_allclose(arm.ik(pose, q_b + 0.05), q_b, atol=1e-6)


def test_ik_refuses_a_point_out_of_reach(arms: dict[str, UrdfArm]) -> None:
    arm = arms["ur5"]
    far = np.eye(4)
    far[:3, 3] = (2.0, 0.0, 0.5)
    with pytest.raises(Unreachable, match="beyond the reach"):
        arm.ik(far)


@pytest.mark.parametrize("seed", range(3))
def test_ik_names_the_arm_for_a_bad_hint(arms: dict[str, UrdfArm], seed: int) -> None:
    """The shared IK of the URDF and the DH serial arm: a hint of the wrong
    length, not finite, or not numbers is refused naming the arm."""
    from workcell.arms import SerialArm

    rng = np.random.default_rng(seed)
    for arm in (arms["panda"], SerialArm.example_6dof("dh")):
        q = arm.home + rng.normal(0, 0.05, arm.dof)
        pose = arm.fk(q[None])[0]
        np.testing.assert_allclose(arm.fk(arm.ik(pose, q)[None])[0], pose, atol=1e-8)
        bad_nan = q.copy()
        bad_nan[rng.integers(arm.dof)] = np.nan
        for hint in (q[: 1 + rng.integers(arm.dof - 1)], bad_nan, ["x"] * arm.dof, [q, q]):
            with pytest.raises(ValidationError, match=f"arm {arm.name!r}: the IK hint"):
                arm.ik(pose, hint)


def test_limits_and_velocities_come_from_the_urdf(arms: dict[str, UrdfArm]) -> None:
    panda = arms["panda"]
    assert panda.dof == 7
    np.testing.assert_allclose(panda.joint_limits[3], (-3.0718, -0.0698))
    np.testing.assert_allclose([d.max_velocity for d in panda.drives], [2.175] * 4 + [2.61] * 3)
    slow = UrdfArm("s", UR5, tool_link="tool0", velocity_scale=0.5)
    assert [d.max_velocity for d in slow.drives] == [1.575] * 3 + [1.6] * 3
    # the servo profile times a move by its slowest joint
    q0, q1 = np.zeros(6), np.array([1.0, 0, 0, 0, 0, 0])
    assert slow.move_time(q0, q1) > arms["ur5"].move_time(q0, q1)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_fitted_capsules_contain_their_meshes(arms: dict[str, UrdfArm], name: str) -> None:
    """Every mesh vertex and seeded samples of every mesh surface lie inside
    the capsule fitted to it (conservative), and the capsule is not absurdly
    larger than the convex hull it was fitted to (for a finger, the hull of
    both ends of its slide)."""
    arm = arms[name]
    assert len(arm.shapes) == len(arm.meshes) > 0
    for shape, mesh, fitted in zip(arm.shapes, arm.meshes, arm.model.hulls, strict=True):
        assert shape.frame == mesh.frame
        cap = _shape_capsule(shape)
        tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
        surface, _ = trimesh.sample.sample_surface(tm, 2000, seed=5)
        assert capsule_contains(cap, mesh.vertices, tol=1e-9).all(), shape.name
        assert capsule_contains(cap, surface, tol=1e-9).all(), shape.name
        hull = trimesh.convex.convex_hull(fitted).volume
        assert capsule_volume(cap) < 8 * hull, shape.name  # flat fingers: about 6x


def test_fit_capsule_contains_random_point_clouds() -> None:
    """Seeded campaign: anisotropic random clouds, rotated; every point inside,
    and for points on a known capsule's surface the fit is within 15 % of its
    volume (the search scans radii in steps of 1/24 of the smallest)."""
    rng = np.random.default_rng(2)
    for _ in range(30):
        pts = rng.normal(size=(200, 3)) * rng.uniform(0.01, 0.3, 3)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        pts = pts @ q.T + rng.normal(size=3)
        cap = fit_capsule(pts)
        assert capsule_contains(cap, pts).all()
    # a capsule's own surface: radius 0.05, segment 0.4 along a tilted axis
    axis = np.array([1.0, 2.0, 2.0]) / 3
    t = rng.uniform(-0.2, 0.2, 500)
    d = rng.normal(size=(500, 3))
    d -= (d @ axis)[:, None] * axis
    d /= np.linalg.norm(d, axis=1)[:, None]
    pts = t[:, None] * axis + 0.05 * d
    cap = fit_capsule(np.vstack([pts, [0.25 * axis, -0.25 * axis]]))
    truth = FittedCapsule(-0.2 * axis, 0.2 * axis, 0.05)
    assert capsule_volume(cap) <= capsule_volume(truth) * 1.15


def test_fit_capsule_rejects_bad_input() -> None:
    with pytest.raises(ValidationError, match="finite"):
        fit_capsule(np.array([[0.0, np.nan, 0.0]]))
    with pytest.raises(ValidationError, match="at least one"):
        fit_capsule(np.zeros((0, 3)))


@pytest.mark.parametrize("name", sorted(ARMS))
def test_displacement_bound_holds_along_joint_segments(arms: dict[str, UrdfArm], name: str) -> None:
    """The sweep's premise (workcell.arms.base): no point of any shape moves
    farther than displacement_bound(dq) along a straight joint segment."""
    arm = arms[name]
    rng = np.random.default_rng(4)
    s = np.linspace(0.0, 1.0, 11)
    for q0 in _random_q(arm, rng, 10):
        dq = rng.normal(0, 0.3, arm.dof)
        q1 = np.clip(q0 + dq, *arm.joint_limits.T)
        bound = float(arm.displacement_bound((q1 - q0)[None])[0])
        path = q0 + s[:, None] * (q1 - q0)
        tf = arm.shape_transforms(path)  # (11, S, 4, 4)
        for k, shape in enumerate(arm.shapes):
            cap = _shape_capsule(shape)
            inv = np.linalg.inv(np.asarray(shape.offset))
            ends = [inv @ np.append(p, 1.0) for p in (cap.p0, cap.p1)]
            for e in ends:
                for u in np.eye(3):
                    local = e.copy()
                    local[:3] += cap.radius * u
                    pts = tf[:, k] @ local
                    moved = np.linalg.norm(pts[:, :3] - pts[0, :3], axis=1)
                    assert moved.max() <= bound + 1e-9, (shape.name, moved.max(), bound)


def test_meshes_as_fcl_objects_never_hit_where_the_capsules_do_not(
    arms: dict[str, UrdfArm],
) -> None:
    """Two UR5 facing each other, seeded random joints: whenever the meshes
    (FCL BVH objects) touch, the fitted capsules touch too (the capsules are
    conservative); and both do happen."""
    a = UrdfArm("a", UR5, tool_link="tool0")
    base_b = np.eye(4)
    base_b[:3, :3] = np.diag([-1.0, -1.0, 1.0])
    base_b[0, 3] = 0.6
    b = UrdfArm("b", UR5, tool_link="tool0", base=base_b)
    world = CollisionWorld()
    names = world.add_arm_meshes(a, "a_mesh")
    assert names[0] == f"a/mesh/{a.meshes[0].name}"
    world.add_arm_meshes(b, "b_mesh")
    world.add_arm(a, "a_caps")
    world.add_arm(b, "b_caps")
    rng = np.random.default_rng(9)
    mesh_hits = cap_hits = 0
    for _ in range(300):
        qa, qb = _random_q(a, rng, 1)[0], _random_q(b, rng, 1)[0]
        world.set_group_transforms("a_mesh", a.mesh_transforms(qa[None])[0])
        world.set_group_transforms("b_mesh", b.mesh_transforms(qb[None])[0])
        world.set_group_transforms("a_caps", a.shape_transforms(qa[None])[0])
        world.set_group_transforms("b_caps", b.shape_transforms(qb[None])[0])
        m = world.collide("a_mesh", "b_mesh")
        c = world.collide("a_caps", "b_caps")
        assert c or not m
        mesh_hits += m
        cap_hits += c
    assert 0 < mesh_hits <= cap_hits


def test_mesh_objects_validate_their_data() -> None:
    world = CollisionWorld()
    with pytest.raises(ValidationError, match="mesh 'm'"):
        world.add_mesh("m", np.zeros((3, 3)), np.array([[0, 1, 5]]), "g")


def test_cell_file_fields_and_errors(tmp_path: Path) -> None:
    """The ``urdf`` arm kind's table: a relative path resolves against the
    cell's directory; every error names the field."""
    good = {"type": "urdf", "urdf": UR5, "tool_link": "tool0", "base": [0.1, 0.0, 0.0, 0.0]}
    arm = arm_from_dict("u", good, "c.toml: arms.u")
    assert arm.kind == "urdf" and arm.dof == 6
    assert arm.fk(np.zeros((1, 6)))[0, 0, 3] == pytest.approx(
        UrdfArm("v", UR5, tool_link="tool0").fk(np.zeros((1, 6)))[0, 0, 3] + 0.1
    )
    src = resolve_urdf(UR5)
    (tmp_path / "robot.urdf").write_text(
        src.read_text(encoding="utf-8").replace(
            "package://example-robot-data/robots/ur_description/",
            str(src.parent.parent) + "/",
        ),
        encoding="utf-8",
    )
    local = arm_from_dict("w", {**good, "urdf": "robot.urdf"}, "c.toml: arms.w", base_dir=tmp_path)
    assert len(local.shapes) == len(arm.shapes)
    cases = [
        ({"urdf": "nope.urdf"}, r"arms\.u\.urdf: file .*nope\.urdf' does not exist"),
        ({"urdf": "package:no-such-dist/x.urdf"}, r"arms\.u\.urdf: package 'no-such-dist'"),
        ({"tool_link": "hand"}, r"arms\.u\.tool_link: .*no link 'hand'"),
        ({"joint_limits": [[-1.0, 1.0]] * 5}, r"arms\.u\.joint_limits: .*6 \(low < high\)"),
        ({"joint_limits": [[-7.0, 1.0]] * 6}, r"arms\.u\.joint_limits: .*beyond the URDF"),
        ({"velocity_scale": 1.5}, r"arms\.u\.velocity_scale: 1\.5 is out of range"),
        ({"max_acceleration": [1.0]}, r"arms\.u\.max_acceleration: .*6 positive"),
        ({"radius": 0.1}, r"arms\.u: unknown field 'radius'"),
    ]
    for change, msg in cases:
        with pytest.raises(ValidationError, match=msg):
            arm_from_dict("u", {**good, **change}, "c.toml: arms.u")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/>", encoding="utf-8")
    with pytest.raises(MultiarmError, match=r"bad\.urdf"):
        arm_from_dict("u", {**good, "urdf": str(bad)}, "c.toml: arms.u")


def test_urdf_cell_compiles_schedules_and_simulates_cleanly() -> None:
    """The built-in cell: two UR5 and a Panda; the tree search's plan runs
    with every task done, at its planned makespan, the safety monitor on
    (it raises on any collision or zone violation), every arm at work."""
    import workcell
    from scheduler import solve
    from workcell.cell import load_example

    cell = load_example("urdf_cell")
    assert [a.kind for a in cell.arms] == ["urdf"] * 3
    cc = workcell.compile_cell(cell)
    result = solve(cc.problem, "tree", seed=0, time_limit=10.0)
    schedule = result.schedule
    assert schedule is not None
    sim = workcell.simulate(cc, schedule, seed=0)
    assert sim.metrics.failed_tasks == 0
    assert sim.metrics.done_tasks == cc.problem.n_tasks == 8
    assert abs(sim.metrics.executed_makespan - schedule.makespan) < 1e-6
    assert all(u > 0 for u in sim.metrics.utilisation.values())
