"""Step primitives (S1.7 force search, S1.8 detector, S1.9 flags and moves)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from multiarm.errors import ValidationError
from tasklib.pose import Pose, quat_from_rpy, quat_to_matrix
from tasklib.steps import (
    STEP_KINDS,
    Actuate,
    Approach,
    Depart,
    Detect,
    Dwell,
    ForceSearch,
    Grasp,
    Insert,
    Move,
    Release,
    SetFlag,
    UseTool,
    WaitFlag,
)

P = Pose((0.1, 0.2, 0.3))


def test_every_kind_is_registered() -> None:
    assert set(STEP_KINDS) == {
        "move",
        "approach",
        "depart",
        "grasp",
        "release",
        "insert",
        "use_tool",
        "actuate",
        "detect",
        "set_flag",
        "wait_flag",
        "dwell",
    }


def test_move_needs_exactly_one_target() -> None:
    assert Move(target=P).trajectory is None
    assert Move(trajectory="t").target is None
    with pytest.raises(ValidationError, match="exactly one"):
        Move()
    with pytest.raises(ValidationError, match="exactly one"):
        Move(target=P, trajectory="t")
    with pytest.raises(ValidationError, match="interpolation"):
        Move(target=P, interpolation="spline")  # type: ignore[arg-type]
    with pytest.raises(ValidationError, match="fraction"):
        Move(target=P, speed=1.5)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Approach(P, distance=-0.1), "approach distance"),
        (lambda: Approach(P, speed=0), "approach speed"),
        (lambda: Depart(distance=math.inf), "depart distance"),
        (lambda: Grasp(duration=-1), "grasp duration"),
        (lambda: Release(part=""), "release part"),
        (lambda: Insert("pin", P, depth=0), "insert depth"),
        (lambda: Insert("pin", (0, 0, 0)), "must be a Pose"),  # type: ignore[arg-type]
        (lambda: UseTool("screwdriver", 0), "use_tool duration"),
        (lambda: Actuate("", "on"), "actuate device"),
        (lambda: Detect(P, P, mode="guess"), "detect mode"),  # type: ignore[arg-type]
        (lambda: SetFlag(""), "set_flag flag"),
        (lambda: WaitFlag("f", timeout=0), "wait_flag timeout"),
        (lambda: Dwell(math.nan), "dwell duration"),
        (lambda: ForceSearch(max_tries=0), "max_tries"),
        (lambda: ForceSearch(max_tries=2.5), "max_tries"),  # type: ignore[arg-type]
        (lambda: ForceSearch(pattern="random"), "pattern"),  # type: ignore[arg-type]
        (lambda: ForceSearch(threshold=-1), "threshold"),
    ],
)
def test_bad_steps_are_rejected(make, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValidationError, match=message):
        make()


def test_capabilities_implied_by_steps() -> None:
    assert Grasp().capabilities == ("gripper",)
    assert Insert("pin", P).capabilities == ("force_sensor",)
    assert Detect(P, P).capabilities == ("object_detector",)
    assert Dwell(1.0).capabilities == ()


def test_detect_length() -> None:
    d = Detect(Pose((0, 0, 0)), Pose((3, 4, 0)), "measure")
    assert d.length == 5.0


@given(st.integers(1, 60), st.sampled_from(["spiral", "grid"]))
def test_force_search_offsets(n: int, pattern: str) -> None:
    fs = ForceSearch(max_tries=n, step=0.5, pattern=pattern)  # type: ignore[arg-type]
    off = fs.offsets()
    assert off.shape == (n, 2)
    assert off[0].tolist() == [0.0, 0.0] or pattern == "grid"
    # distinct tries, on the step lattice (grid may be offset by half a step)
    assert len({tuple(o) for o in off.tolist()}) == n
    if pattern == "spiral":
        assert np.allclose(off / 0.5, np.round(off / 0.5))
        # a spiral never jumps: consecutive tries are neighbours
        assert np.all(np.abs(np.diff(off, axis=0)).sum(axis=1) == pytest.approx(0.5))
    # nearer offsets come first (up to the ring structure): the first try is
    # the closest to nominal
    d = np.linalg.norm(off, axis=1)
    assert d[0] == d.min()


def test_pose_validation_and_matrix() -> None:
    with pytest.raises(ValidationError, match="unit quaternion"):
        Pose((0, 0, 0), (2, 0, 0, 0))
    with pytest.raises(ValidationError, match="non-finite"):
        Pose((0, math.inf, 0))
    q = quat_from_rpy(0.3, -0.2, 1.1)
    r = quat_to_matrix(q)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    cz, sz = math.cos(1.1), math.sin(1.1)
    cy, sy = math.cos(-0.2), math.sin(-0.2)
    cx, sx = math.cos(0.3), math.sin(0.3)
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    np.testing.assert_allclose(r, rz @ ry @ rx, atol=1e-12)
    m = Pose((1, 2, 3), q).matrix()
    assert m[:3, 3].tolist() == [1, 2, 3]
