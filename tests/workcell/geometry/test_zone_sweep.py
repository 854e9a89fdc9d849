"""The conservative zone sweep (S2.5 zone windows) against a dense FCL reference."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import UsageError, ValidationError
from workcell.geometry import (
    reference_contacts,
    sample_trajectory,
    static_occupancy,
    swept_aabb,
    zone_contacts,
    zone_windows,
)
from zones import AABox, MeshShape, Zone, ZoneMap, parse_sdl

from .fake_arm import PlanarArm, ProfileTrajectory

# Zones placed where the test arm (reach 0.73 m at z = 0.1) passes: a 2 mm
# thin wall, a box whose top corner sits 3 cm above the link axis, a small
# ball, a short can, a hull and a turned box.
SDL = """cell (-1, -1, 0) (1, 1, 1)
zone thin    exclusive box (0.3, -0.6, 0) (0.302, 0.6, 0.5)
zone corner  exclusive box (-0.6, 0.2, 0.0) (-0.3, 0.5, 0.13)
zone ball    shared sphere (0.0, -0.5, 0.1) radius 0.05
zone can     exclusive cylinder (-0.4, -0.4, 0) radius 0.05 height 0.08
zone tri     exclusive hull { (0.4, 0.4, 0.0), (0.6, 0.4, 0.0), (0.5, 0.6, 0.0), (0.5, 0.5, 0.2) }
zone turned  shared box center (0.5, -0.3, 0.16) size (0.1, 0.02, 0.3) yaw 0.7
"""


def _random_trajectory(rng: np.random.Generator) -> ProfileTrajectory:
    k = int(rng.integers(2, 5))
    q = np.c_[rng.uniform(-3.0, 3.0, k), rng.uniform(-2.6, 2.6, k)]
    if rng.random() < 0.5:  # a dwell
        q = np.insert(q, 1, q[1], axis=0)
    times = np.r_[0.0, np.cumsum(rng.uniform(0.2, 1.5, len(q) - 1))]
    return ProfileTrajectory(q, times)


def _missed(arm: PlanarArm, traj: ProfileTrajectory, zm: ZoneMap, n: int = 3000) -> int:
    """Dense reference contact times that no occupancy window covers."""
    w = zone_windows(arm, traj, zm, n_grid=4)
    t = np.linspace(0.0, traj.duration, n)
    ref = reference_contacts(arm, traj.sample(t), zm)
    missed = 0
    for z, name in enumerate(zm.zone_names()):
        hit = t[ref[:, z]]
        win = w.get(name)
        covered = np.zeros(len(hit), dtype=bool)
        for a, b in win.occupied if win is not None else ():
            covered |= (hit >= a) & (hit <= b)
        missed += int((~covered).sum())
    return missed


def test_sweep_never_misses_a_contact_of_the_dense_reference() -> None:
    zm = parse_sdl(SDL)
    arm = PlanarArm()
    rng = np.random.default_rng(2026)
    contacts = 0
    for _ in range(12):
        traj = _random_trajectory(rng)
        assert _missed(arm, traj, zm) == 0
        t = np.linspace(0.0, traj.duration, 300)
        contacts += int(reference_contacts(arm, traj.sample(t), zm).sum())
    assert contacts > 100  # the trajectories do meet the zones


def test_box_cylinder_and_sphere_links_are_covered_too() -> None:
    zm = parse_sdl(SDL)
    arm = PlanarArm(mixed=True)
    rng = np.random.default_rng(7)
    for _ in range(6):
        assert _missed(arm, _random_trajectory(rng), zm, n=1500) == 0


@settings(max_examples=25)
@given(
    st.lists(st.tuples(st.floats(-3.0, 3.0), st.floats(-2.6, 2.6)), min_size=2, max_size=4),
    st.floats(0.05, 2.0),
)
def test_sweep_covers_the_reference_for_any_trajectory(
    knots: list[tuple[float, float]], step: float
) -> None:
    traj = ProfileTrajectory(np.array(knots), step * np.arange(len(knots), dtype=np.float64))
    assert _missed(PlanarArm(), traj, parse_sdl(SDL), n=800) == 0


def test_thin_wall_crossed_fast_is_caught() -> None:
    # a 2 mm radial wall on the x axis; the extended arm sweeps across it and
    # the two knots (the only grid points) are both 0.3 rad away from it
    zm = ZoneMap(
        ((-1, -1, 0), (1, 1, 1)), (Zone("wall", AABox((0.35, -0.001, 0), (0.7, 0.001, 0.5))),)
    )
    arm = PlanarArm()
    traj = ProfileTrajectory(np.array([[-0.3, 0.0], [0.3, 0.0]]), np.array([0.0, 0.05]))
    assert not zone_contacts(arm, traj.sample(np.array([0.0, 0.05])), zm, padding=0.005).any()
    w = zone_windows(arm, traj, zm, n_grid=1)
    assert w.zones == ("wall",)
    assert _missed(arm, traj, zm, n=4000) == 0


def test_mesh_zone_goes_through_fcl(tmp_path: Path) -> None:
    import trimesh

    mesh = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    mesh.apply_translation((0.55, 0.3, 0.1))
    mesh.export(tmp_path / "jig.stl")
    zm = ZoneMap(
        ((-1, -1, 0), (1, 1, 1)),
        (
            Zone("jig", MeshShape("jig.stl", base=str(tmp_path))),
            Zone("b", AABox((0, 0, 0), (0.1, 0.1, 0.1))),
        ),
    )
    arm = PlanarArm()
    rng = np.random.default_rng(5)
    for _ in range(3):
        assert _missed(arm, _random_trajectory(rng), zm, n=600) == 0
    # the arm standing straight through the jig: centre of link2 inside the mesh
    q = np.array([np.arctan2(0.3, 0.55), 0.0])
    assert zone_contacts(arm, q[None], zm)[0, 0]
    assert not zone_contacts(arm, np.array([[-2.0, 0.0]]), zm)[0, 0]


def test_windows_of_a_pass_through_one_box() -> None:
    # extended arm sweeps j1 from -0.6 to 0.6 rad in 2 s and rests 1 s:
    # it crosses the box around the x axis once, while moving.
    zm = ZoneMap(((-1, -1, 0), (1, 1, 1)), (Zone("bin", AABox((0.5, -0.05, 0), (0.8, 0.05, 0.3))),))
    arm = PlanarArm()
    traj = ProfileTrajectory(
        np.array([[-0.6, 0.0], [0.6, 0.0], [0.6, 0.0]]), np.array([0.0, 2.0, 3.0])
    )
    w = zone_windows(arm, traj, zm, padding=0.002)
    assert w.zones == ("bin",)
    (win,) = w.windows
    t = np.linspace(0.0, 3.0, 30001)
    ref_t = t[reference_contacts(arm, traj.sample(t), zm)[:, 0]]
    true_start, true_end = ref_t.min(), ref_t.max()
    assert 0.6 < true_start < 1.0 < true_end < 1.4  # the crossing, symmetric about t = 1
    assert len(win.occupied) == 1
    start, end = win.occupied[0]
    assert start <= true_start and end >= true_end
    assert start > true_start - 0.05 and end < true_end + 0.05  # tight, not everything
    assert win.moving == win.occupied  # the crossing happens while moving
    assert w["bin"] is win
    with pytest.raises(UsageError, match="never touches zone 'other'"):
        w["other"]


def test_moving_windows_leave_out_the_dwell() -> None:
    # into the box (0..1 s), rest inside (1..2 s), out again (2..3 s)
    zm = ZoneMap(((-1, -1, 0), (1, 1, 1)), (Zone("bin", AABox((0.5, -0.05, 0), (0.8, 0.05, 0.3))),))
    arm = PlanarArm()
    q = np.array([[-0.6, 0.0], [0.0, 0.0], [0.0, 0.0], [0.6, 0.0]])
    traj = ProfileTrajectory(q, np.array([0.0, 1.0, 2.0, 3.0]))
    win = zone_windows(arm, traj, zm)["bin"]
    assert len(win.occupied) == 1
    start, end = win.occupied[0]
    assert 0.0 < start < 1.0 and 2.0 < end < 3.0
    assert win.moving == ((start, 1.0), (2.0, end))


def test_static_occupancy_and_swept_box() -> None:
    zm = parse_sdl(SDL)
    arm = PlanarArm()
    assert static_occupancy(arm, np.array([0.0, 0.0]), zm) == ("thin",)
    assert static_occupancy(arm, np.array([-np.pi / 2, 0.0]), zm) == ("ball",)
    rng = np.random.default_rng(1)
    traj = _random_trajectory(rng)
    box = swept_aabb(arm, traj)
    t = np.linspace(0.0, traj.duration, 2000)
    centres = arm.shape_transforms(traj.sample(t))[..., :3, 3].reshape(-1, 3)
    assert np.all(centres >= box[0]) and np.all(centres <= box[1])


def test_samples_respect_the_padding_and_keep_the_knots() -> None:
    arm = PlanarArm()
    traj = ProfileTrajectory(
        np.array([[0.0, 0.0], [2.0, -1.0], [2.0, 1.0]]), np.array([0.0, 0.7, 1.9])
    )
    t, q = sample_trajectory(arm, traj, padding=0.004, n_grid=2)
    assert set(traj.knot_times) <= set(t)
    assert np.all(np.diff(t) > 0)
    assert arm.displacement_bound(np.diff(q, axis=0)).max() <= 0.004
    with pytest.raises(ValidationError, match="padding must be > 0"):
        sample_trajectory(arm, traj, padding=0.0)
