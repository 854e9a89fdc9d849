"""Poses: a bare (x, y, z) means the tool points down; the pose() helper."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import tasklib
from multiarm.errors import MultiarmError, ValidationError
from tasklib import (
    DOWN,
    UP,
    Approach,
    Dwell,
    ForceSearch,
    Move,
    Pose,
    capi,
    parse_tdl,
    pose,
    quat_from_rpy,
)
from tasklib.pose import quat_to_matrix

coords = st.floats(-5.0, 5.0, allow_nan=False)


def test_the_default_orientation_is_the_down_of_the_built_in_task_sets() -> None:
    from tasklib.examples import DOWN as EXAMPLES_DOWN

    assert DOWN == EXAMPLES_DOWN == Pose((0.0, 0.0, 0.0)).orientation
    # the tool axis (z of the tool frame) points along -z of the cell
    assert quat_to_matrix(DOWN)[:, 2].tolist() == [0.0, 0.0, -1.0]
    assert quat_to_matrix(UP)[:, 2].tolist() == [0.0, 0.0, 1.0]


@given(coords, coords, coords)
def test_a_three_tuple_means_tool_down_wherever_a_pose_is_accepted(
    x: float, y: float, z: float
) -> None:
    expected = Pose((x, y, z), DOWN)
    assert capi.as_pose((x, y, z)) == expected
    assert pose(x, y, z) == expected == tasklib.pose(x, y, z, tool="down")
    assert capi.as_pose((x, y, z, *UP)) == pose(x, y, z, tool="up")


@given(coords, coords, coords, st.floats(-10.0, 10.0))
def test_yaw_turns_the_tool_about_the_vertical_and_keeps_it_down(
    x: float, y: float, z: float, yaw: float
) -> None:
    m = pose(x, y, z, yaw=yaw).matrix()
    assert np.allclose(m[:3, 2], [0.0, 0.0, -1.0], atol=1e-12)
    expected = quat_to_matrix(quat_from_rpy(math.pi, 0.0, yaw))
    assert np.allclose(m[:3, :3], expected, atol=1e-9)
    assert m[:3, 3].tolist() == [x, y, z]


def test_pose_accepts_a_quaternion_and_refuses_bad_input_by_name() -> None:
    q = quat_from_rpy(0.3, 0.0, 0.0)
    assert pose(0, 0, 0, tool=q).orientation == q
    with pytest.raises(ValidationError, match="pose tool must be 'down', 'up' or a quaternion"):
        pose(0, 0, 0, tool="sideways")
    with pytest.raises(ValidationError, match="not a unit quaternion"):
        pose(0, 0, 0, tool=(2.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValidationError, match="yaw must be a finite angle"):
        pose(0, 0, 0, yaw=math.nan)
    with pytest.raises(ValidationError, match="non-finite coordinate"):
        pose(0, math.inf, 0)
    with pytest.raises(ValidationError, match=r"3 \(x, y, z: tool pointing down\) or 7"):
        capi.as_pose((0.0, 1.0))
    with pytest.raises(ValidationError, match="a pose is a Pose or 3"):
        capi.as_pose(0.5)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Move(target=pose(0, 0, 0), speed=1e-300), r"move speed must be at least 1e-06"),
        (lambda: Dwell(1e300), r"dwell duration must be at most 1e\+06"),
        (lambda: Approach(pose(0, 0, 0), 1e300), r"approach distance must be at most 1e\+06"),
        (lambda: ForceSearch(max_tries=10**9), r"max_tries in \[1, 100000\], got 1000000000"),
        (
            lambda: parse_tdl("trajectory t { taught speed 1e-300 { stop (0, 0, 1) } }"),
            r"speed must be at least 1e-06",
        ),
    ],
)
def test_extreme_step_numbers_are_refused_by_name(build, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(MultiarmError, match=message):  # ValidationError, or TDLError in TDL
        build()
