"""Properties of the replay document: any run, through the RunLike protocol,
and a run in which tasks fail."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from workcell import load_example
from workcell.replay import build_replay

SCARA4 = load_example("scara4")


class PathRun:
    """A run that is only joint paths: each arm moves piecewise linearly
    through random joint vectors within its limits (seeded)."""

    def __init__(self, cell: Any, duration: float, seed: int) -> None:
        rng = np.random.default_rng(seed)
        self.cell = cell
        self._knots = np.linspace(0.0, duration, 6)
        self._q = {
            a.name: rng.uniform(a.joint_limits[:, 0], a.joint_limits[:, 1], (6, a.dof))
            for a in cell.arms
        }
        self.trace: list[Any] = []
        self.metrics = SimpleNamespace(
            planned_makespan=duration, executed_makespan=duration, done_tasks=0, failed_tasks=0
        )
        self.problem = SimpleNamespace(arm_names=tuple(a.name for a in cell.arms))

    def joints(self, times: Any) -> dict[str, Any]:
        t = np.asarray(times, dtype=float)
        return {
            name: np.stack([np.interp(t, self._knots, q[:, j]) for j in range(q.shape[1])], 1)
            for name, q in self._q.items()
        }

    def tasks_frame(self) -> Any:
        cols = ["task", "arm", "planned_start", "planned_end", "start", "end", "status", "cause"]
        return pd.DataFrame(columns=cols)

    def reservations_frame(self) -> Any:
        return pd.DataFrame(columns=["kind", "resource", "task", "arm", "start", "end"])


@settings(max_examples=15, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    duration=st.floats(0.5, 60.0),
    rate=st.floats(1.0, 60.0),
    max_frames=st.integers(2, 400),
)
def test_any_path_is_stored_to_the_quantisation(
    seed: int, duration: float, rate: float, max_frames: int
) -> None:
    run = PathRun(SCARA4, duration, seed)
    data = build_replay(run, None, rate=rate, max_frames=max_frames)  # the run keeps its cell
    n = min(max_frames, max(2, math.ceil(duration * rate) + 1))
    assert data.n_frames == n and data.duration == pytest.approx(duration)
    times = data.times()
    joints = run.joints(times)
    want = np.concatenate([a.shape_transforms(joints[a.name]) for a in SCARA4.arms], axis=1)
    got = data.poses()
    step = np.asarray(data.document["frames"]["scale"])
    assert np.all(np.abs(got[..., :3] - want[..., :3, 3]) <= step * 0.51 + 1e-9)
    err = Rotation.from_quat(got[..., 3:].reshape(-1, 4)).inv() * Rotation.from_matrix(
        want[..., :3, :3].reshape(-1, 3, 3)
    )
    assert np.max(err.magnitude()) < 1e-4
    q = got[..., 3:]
    assert np.all(np.einsum("nbk,nbk->nb", q[1:], q[:-1]) >= 0)


def test_a_run_with_failed_tasks(scara4_cc: Any, scara4_failed_run: Any) -> None:
    """Failed tasks that never ran keep their planned slot; the replay ends
    with the last thing that happened in the cell or was planned, not when the
    failures were logged; an arm that failed waits at no border after it."""
    data = build_replay(scara4_failed_run, scara4_cc, max_frames=100)
    doc = data.document
    tasks = doc["tasks"]
    never = [t for t in tasks if t["status"] == "failed" and t["start"] is None]
    assert len([t for t in tasks if t["status"] == "failed"]) == 15 and never
    assert all(t["planned_end"] > t["planned_start"] for t in never)
    planned = max(t["planned_end"] for t in never)
    assert data.duration == pytest.approx(max(planned, scara4_failed_run.metrics.executed_makespan))
    assert data.duration < 200.0
    se = data.arm_names.index("se")
    waits = [s for s in doc["zone_states"] if s["state"] == "waiting" and s["arm"] == se]
    assert all(s["end"] <= 30.0 for s in waits)
    assert [(f["kind"], f["arm"], f["time"]) for f in doc["faults"]] == [("arm_failure", se, 30.0)]
