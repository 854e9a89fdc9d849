"""OMPL detours around a parked arm (S2.6 geometric deadlock, S2.12 alternative trajectory)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from multiarm.errors import ValidationError
from workcell.arms.base import LinkShape
from workcell.geometry import (
    ObstacleSet,
    check_path,
    first_contact,
    plan_detour,
    write_ompl_benchmark_log,
)
from workcell.geometry.planner import DetourPlanner

from .fake_arm import PlanarArm

ARM = PlanarArm()
# a second arm parked with its links reaching toward ours along -x (tip at x = 0.5)
PARKED = ObstacleSet.from_arm(PlanarArm("o", base_xy=(1.2, 0.0)), np.array([np.pi, 0.0]))
START, GOAL = np.array([-1.0, 0.3]), np.array([1.0, -0.3])


def test_detour_around_a_parked_arm_is_collision_free() -> None:
    # the straight joint segment sweeps the extended arm through the parked one
    assert not check_path(ARM, np.stack([START, GOAL]), PARKED, step=0.002)
    res = plan_detour(ARM, START, GOAL, PARKED, budget=5.0, seed=0, max_checks=200_000)
    assert res.status == "solved" and res.solved
    assert np.array_equal(res.path[0], START) and np.array_equal(res.path[-1], GOAL)
    assert len(res.path) >= 3 and res.n_checks > 0
    assert check_path(ARM, res.path, PARKED, step=0.001)  # finer than the planner's check


def test_same_seed_same_path_whatever_ran_before() -> None:
    a = plan_detour(ARM, START, GOAL, PARKED, budget=5.0, seed=3, max_checks=200_000)
    b = plan_detour(ARM, START, GOAL, PARKED, budget=5.0, seed=4, max_checks=200_000)
    c = plan_detour(ARM, START, GOAL, PARKED, budget=5.0, seed=3, max_checks=200_000)
    assert a.status == b.status == c.status == "solved"
    assert np.array_equal(a.path, c.path) and a.n_checks == c.n_checks
    assert not (a.path.shape == b.path.shape and np.array_equal(a.path, b.path))


def test_start_or_goal_in_collision_is_declared_at_once() -> None:
    # the tip of the parked arm is at x = 0.5; our extended arm along +x hits it
    hit = np.array([0.0, 0.0])
    res = plan_detour(ARM, hit, GOAL, PARKED)
    assert res.status == "start_in_collision" and res.path.shape == (0, 2)
    assert res.n_checks == 1
    res = plan_detour(ARM, START, hit, PARKED)
    assert res.status == "goal_in_collision" and res.n_checks == 2
    assert not res.solved and res.length() == 0.0


def test_direct_when_the_straight_segment_is_free() -> None:
    res = plan_detour(ARM, np.array([-1.0, 0.0]), np.array([-2.0, 1.0]), PARKED)
    assert res.status == "direct"
    assert np.array_equal(res.path, [[-1.0, 0.0], [-2.0, 1.0]])


def test_work_limit_gives_timeout() -> None:
    res = plan_detour(ARM, START, GOAL, PARKED, budget=5.0, seed=0, max_checks=50)
    assert res.status == "timeout" and res.path.shape == (0, 2)


def test_plain_obstacle_list_and_bad_input() -> None:
    post = np.eye(4)
    post[:3, 3] = (0.45, 0.2, 0.1)
    obstacles = [(LinkShape("post", "box", (0.05, 0.05, 0.4), 0), post)]
    res = plan_detour(
        ARM, np.zeros(2), np.array([1.2, 0.0]), obstacles, budget=5.0, max_checks=100_000
    )
    assert res.status == "solved"
    assert check_path(ARM, res.path, obstacles, step=0.001)
    with pytest.raises(ValidationError, match="joint 'j1' = 5 is outside its limits"):
        plan_detour(ARM, np.array([5.0, 0.0]), GOAL, PARKED)
    with pytest.raises(ValidationError, match="unknown OMPL planner 'Nope'"):
        plan_detour(ARM, START, GOAL, PARKED, planner="Nope")
    with pytest.raises(ValidationError, match="must be a"):
        ObstacleSet([("not a pair",)])  # type: ignore[list-item]


def test_edge_states_respect_the_resolution() -> None:
    ctx = DetourPlanner(ARM, PARKED, resolution=0.01)
    states = ctx.edge_states(START, GOAL)
    assert np.array_equal(states[0], GOAL)
    pts = np.vstack([START, states[1:], GOAL])
    assert ARM.displacement_bound(np.diff(pts, axis=0)).max() <= 0.01 + 1e-12


def test_benchmark_log_in_ompl_format(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    log = tmp_path / "detour.log"
    summary = write_ompl_benchmark_log(
        log, ARM, START, GOAL, PARKED, planners=("RRTConnect", "RRT"), runs=2, budget=1.0
    )
    assert set(summary) == {"geometric_RRTConnect", "geometric_RRT"}
    text = log.read_text()
    assert "Experiment detour" in text and "2 planners" in text
    assert [p.name for p in tmp_path.iterdir()] == ["detour.log"]  # no console dump


@pytest.mark.slow
def test_planners_without_the_batched_validator_work_too() -> None:
    # KPIECE1 asks for the last valid state of an edge: OMPL's own validator
    post = np.eye(4)
    post[:3, 3] = (0.45, 0.2, 0.1)
    obstacles = ObstacleSet([(LinkShape("post", "box", (0.05, 0.05, 0.4), 0), post)])
    res = plan_detour(
        ARM, np.zeros(2), np.array([1.2, 0.0]), obstacles, planner="KPIECE1", budget=20.0
    )
    assert res.status == "solved"
    assert check_path(ARM, res.path, obstacles, step=0.001)


def test_first_contact_is_never_late() -> None:
    from .fake_arm import ProfileTrajectory

    traj = ProfileTrajectory(np.array([START, [0.0, 0.3], GOAL]), np.array([0.0, 1.0, 2.0]))
    t_hit = first_contact(ARM, traj, PARKED)
    assert t_hit is not None
    t = np.linspace(0.0, 2.0, 4001)
    ok = np.array([check_path(ARM, q[None], PARKED) for q in traj.sample(t)])
    true_first = t[np.argmin(ok)]
    assert not ok.all() and t_hit <= true_first < t_hit + 0.05
    away = ProfileTrajectory(np.array([START, [-2.5, 0.3]]), np.array([0.0, 1.0]))
    assert first_contact(ARM, away, PARKED) is None


def test_a_coarse_resolution_never_raises_and_every_path_passes_the_edge_check() -> None:
    # A seeded campaign over planner seeds and coarse resolutions, where
    # OMPL's shortcuts (pieces of checked edges taken as free) are most
    # likely to miss the sampled edge check: every answer is a path that
    # passes it, or no path ("unverified", "timeout"), never an exception.
    rng = np.random.default_rng(5)
    statuses = set()
    for _ in range(24):
        seed = int(rng.integers(0, 10_000))
        resolution = float(rng.choice([0.01, 0.05, 0.2]))
        planner = DetourPlanner(ARM, PARKED, resolution=resolution)
        res = planner.plan(START, GOAL, budget=5.0, seed=seed, max_checks=50_000)
        statuses.add(res.status)
        assert res.status in ("solved", "unverified", "timeout")
        if res.status == "solved":
            assert planner.path_free(res.path)
        else:
            assert res.path.shape == (0, ARM.dof)
    assert "solved" in statuses
