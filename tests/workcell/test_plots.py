"""Plots of plans and runs (workcell.viz.plots): lanes, bars, poses, frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from multiarm.errors import UsageError, ValidationError
from scheduler import Schedule, solve
from workcell import CompiledCell, compile_cell, load_example
from workcell.sim.trace import Trace
from workcell.viz import arm_joints, gantt, motion_frames, render_instants, zone_timeline


@pytest.fixture(scope="module")
def planned() -> tuple[CompiledCell, Schedule]:
    cc = compile_cell(load_example("supersigma"))
    r = solve(cc.problem, "greedy", time_limit=5.0, seed=0)
    assert r.schedule is not None
    return cc, r.schedule


def _gids(fig: object, prefix: str) -> list[str]:
    ax = fig.axes[0]  # type: ignore[attr-defined]
    return [p.get_gid() for p in ax.patches if (p.get_gid() or "").startswith(prefix)]


def test_gantt_has_a_lane_per_arm_zone_and_tool(planned: tuple[CompiledCell, Schedule]) -> None:
    cc, s = planned
    p = cc.problem
    fig = gantt(p, s)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    sdl = [z for z in p.zone_names if not z.startswith("grid_")]
    assert len(sdl) < p.n_zones  # the compile's space-grid zones share one lane
    assert labels == [
        *p.arm_names,
        *(f"zone {z}" for z in sdl),
        "zone space grid",
        *(f"tool {k}" for k in p.tool_names),
    ]
    assert sorted(_gids(fig, "planned:")) == sorted(f"planned:{t}" for t in p.task_names)
    n_waits = sum(int((w > 0).sum()) for w in s.waits)
    assert len(_gids(fig, "wait:")) == n_waits
    res = [r for r in s.reservations(p) if r.end > r.start]
    assert len(_gids(fig, "zone:")) == sum(r.kind != "tool" for r in res)
    assert len(_gids(fig, "tool:")) == sum(r.kind == "tool" for r in res)
    # each planned bar spans its task, in its arm's lane
    t0 = p.task_names[0]
    (bar,) = [b for b in ax.patches if b.get_gid() == f"planned:{t0}"]
    assert bar.get_x() == pytest.approx(s.start[0])
    assert bar.get_width() == pytest.approx(s.end[0] - s.start[0])
    assert len(gantt(p, s, lanes=False).axes[0].get_yticklabels()) == p.n_arms


def test_gantt_overlays_executed_and_failed_tasks(planned: tuple[CompiledCell, Schedule]) -> None:
    cc, s = planned
    p = cc.problem
    df = s.to_dataframe(p)
    df["start"] += 2.0
    df["end"] += 3.0
    df["status"] = "done"
    df.loc[1, "status"] = "failed"
    fig = gantt(p, s, df)
    assert len(_gids(fig, "executed:")) == p.n_tasks - 1
    assert _gids(fig, "failed:") == [f"failed:{df.loc[1, 'task']}"]
    (bar,) = [b for b in fig.axes[0].patches if b.get_gid() == f"executed:{df.loc[0, 'task']}"]
    assert bar.get_x() == pytest.approx(s.start[0] + 2.0)
    # the planned and the executed makespan are marked
    xs = sorted(float(line.get_xdata()[0]) for line in fig.axes[0].lines)
    done_end = float(df.loc[df["status"] == "done", "end"].max())
    assert xs == pytest.approx(sorted([s.makespan, done_end]))
    with pytest.raises(ValidationError, match="lacks the column 'end'"):
        gantt(p, s, df.drop(columns="end"))


def test_zone_timeline_lanes_and_bars(planned: tuple[CompiledCell, Schedule]) -> None:
    cc, s = planned
    p = cc.problem
    res = s.reservations(p)
    frame = pd.DataFrame(
        [(r.kind, r.resource, r.arm, r.task, r.start, r.end) for r in res],
        columns=["kind", "resource", "arm", "task", "start", "end"],
    )
    for data in (res, frame):
        fig = zone_timeline(data)
        labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
        zones = list(
            dict.fromkeys(
                "space grid" if r.resource.startswith("grid_") else r.resource
                for r in res
                if r.kind != "tool"
            )
        )
        tools = list(dict.fromkeys(r.resource for r in res if r.kind == "tool"))
        assert labels == [*(f"zone {z}" for z in zones), *(f"tool {k}" for k in tools)]
        assert len(fig.axes[0].patches) == sum(r.end > r.start for r in res)
        legend = fig.axes[0].get_legend()
        assert legend is not None
        assert [t.get_text() for t in legend.get_texts()] == list(dict.fromkeys(r.arm for r in res))
    no_tools = zone_timeline(res, tools=False)
    assert len(no_tools.axes[0].patches) == sum(r.end > r.start and r.kind != "tool" for r in res)
    with pytest.raises(ValidationError, match="Reservation records"):
        zone_timeline([1, 2])


def test_arm_joints_follow_the_plan(planned: tuple[CompiledCell, Schedule]) -> None:
    cc, s = planned
    p = cc.problem
    cell = cc.cell
    first = int(np.argmin(s.start))
    arm = p.arm_names[int(s.arms(p)[first])]
    a = p.arm_names.index(arm)
    cm = cc.modes[int(s.mode[first])]
    mid = float(s.start[first]) + 0.5 * cm.duration
    q = arm_joints(cc, s, [0.0, float(s.start[first]), mid, s.makespan + 10.0])
    assert set(q) == set(p.arm_names)
    assert q[arm].shape == (4, cell.arms[a].dof)
    # at time 0 every arm that does not start at once stands at its start joints
    for b, name in enumerate(p.arm_names):
        if float(np.min(s.start[s.arms(p) == b], initial=np.inf)) > 1.0:
            assert np.allclose(q[name][0], cell.start[b])
    assert np.allclose(q[arm][1], cm.q_start)
    if not (s.waits[first] > 0).any():  # the middle of the trajectory, as timed by the compile
        assert np.allclose(q[arm][2], cm.trajectory.sample(np.array([0.5 * cm.duration]))[0])
    last = max(
        (t for t in range(p.n_tasks) if p.arm_names[int(s.arms(p)[t])] == arm),
        key=lambda t: s.start[t],
    )
    assert np.allclose(q[arm][3], cc.modes[int(s.mode[last])].q_end)


def test_a_wait_at_a_border_stops_the_arm(planned: tuple[CompiledCell, Schedule]) -> None:
    cc, s = planned
    p = cc.problem
    t = next(t for t in range(p.n_tasks) if p.shapes[int(s.mode[t])].borders)
    m = int(s.mode[t])
    b = p.shapes[m].borders[0]
    waits = [w.copy() for w in s.waits]
    waits[t][:] = 0.0
    waits[t][0] = 5.0
    start = s.start.copy()
    late = Schedule.from_starts(p, s.mode, start, waits, s.blocking)
    arm = p.arm_names[int(p.mode_arm[m])]
    at = float(start[t]) + b
    q = arm_joints(cc, late, [at, at + 2.5, at + 4.99, at + 6.0])[arm]
    assert np.allclose(q[0], q[1]) and np.allclose(q[0], q[2])
    traj = cc.modes[m].trajectory
    assert np.allclose(q[0], traj.sample(np.array([b]))[0])
    assert np.allclose(q[3], traj.sample(np.array([b + 1.0]))[0])


def test_render_instants_one_panel_per_time(planned: tuple[CompiledCell, Schedule]) -> None:
    import matplotlib.pyplot as plt

    cc, s = planned
    before = plt.get_fignums()
    fig = render_instants(cc, s, [0.0, 10.0, 30.0])
    assert [ax.get_title() for ax in fig.axes] == [
        "supersigma at t = 0.0 s",
        "supersigma at t = 10.0 s",
        "supersigma at t = 30.0 s",
    ]
    shapes = sum(len(arm.shapes) for arm in cc.cell.arms)
    for ax in fig.axes:  # every arm shape drawn (plus the zones' solids)
        assert (
            sum(
                ":" in (pt.get_gid() or "") and not pt.get_gid().startswith("zone:")
                for pt in ax.patches
            )
            == shapes
        )
    assert plt.get_fignums() == before  # nothing left in pyplot's registry
    with pytest.raises(UsageError, match="needs the CompiledCell"):
        render_instants(cc.cell, s, [0.0])  # type: ignore[arg-type]
    with pytest.raises(ValidationError, match="view must be"):
        render_instants(cc, s, [0.0], view="side")  # type: ignore[arg-type]
    with pytest.raises(ValidationError, match="at least one time"):
        render_instants(cc, s, [])


def test_motion_frames_writes_a_numbered_sequence(
    planned: tuple[CompiledCell, Schedule], tmp_path: Path
) -> None:
    cc, s = planned
    paths = motion_frames(cc, s, tmp_path / "frames", n_frames=3)
    assert [p.name for p in paths] == ["frame_0000.png", "frame_0001.png", "frame_0002.png"]
    assert all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in paths)
    glbs = motion_frames(cc, s, tmp_path / "glb", times=[0.0, 5.0], glb=True)
    assert [p.suffix for p in glbs] == [".glb", ".glb"] and all(
        p.stat().st_size > 1000 for p in glbs
    )


class _Run:
    """The parts of a simulation result the plots read (a run in which a task failed)."""

    def __init__(self, cc: CompiledCell, s: Schedule, failed: int) -> None:
        self.problem = cc.problem
        self.executed = None
        self._frame = s.to_dataframe(cc.problem)
        self._frame["status"] = "done"
        self._frame.loc[failed, "status"] = "failed"
        self._frame.loc[failed, ["start", "end"]] = np.nan  # it never started
        self._res = s.reservations(cc.problem)
        self.trace = Trace()
        self.trace.add(3.0, "fault", arm=cc.problem.arm_names[0], detail="crash")

    def tasks_frame(self) -> pd.DataFrame:
        return self._frame

    def reservations_frame(self) -> pd.DataFrame:
        return pd.DataFrame(
            [(r.kind, r.resource, r.arm, r.task, r.start, r.end) for r in self._res],
            columns=["kind", "resource", "arm", "task", "start", "end"],
        )


def test_a_run_with_a_failed_task_is_drawn_from_its_tasks(
    planned: tuple[CompiledCell, Schedule],
) -> None:
    cc, s = planned
    p = cc.problem
    # the last task to start among those without waits
    failed = max(
        (t for t in range(p.n_tasks) if not (s.waits[t] > 0).any()), key=lambda t: s.start[t]
    )
    run = _Run(cc, s, failed)
    fig = gantt(p, s, run)
    assert len(_gids(fig, "executed:")) == p.n_tasks - 1
    assert _gids(fig, "failed:") == [f"failed:{p.task_names[failed]}"]
    (bar,) = [b for b in fig.axes[0].patches if b.get_gid() == f"failed:{p.task_names[failed]}"]
    assert bar.get_x() == pytest.approx(s.start[failed])  # unstarted: where it was planned
    (mark,) = [ln for ln in fig.axes[0].lines if ln.get_gid() == f"fault:{p.arm_names[0]}"]
    assert list(mark.get_xdata()) == [3.0] and list(mark.get_ydata()) == [0]
    # the run's zone use fills the lower half of the zone lanes
    executed_zones = [g for g in _gids(fig, "zone:") if g.endswith(":executed")]
    assert len(executed_zones) == sum(r.end > r.start and r.kind != "tool" for r in run._res)
    # poses come from the completed tasks: the failed one is never entered
    arm = p.arm_names[int(s.arms(p)[failed])]
    mid = 0.5 * (float(s.start[failed]) + float(s.end[failed]))
    q_run = arm_joints(cc, run, [mid])[arm][0]
    q_plan = arm_joints(cc, s, [mid])[arm][0]
    cm = cc.modes[int(s.mode[failed])]
    assert np.allclose(q_plan, cm.trajectory.sample(np.array([mid - float(s.start[failed])]))[0])
    assert not np.allclose(q_run, q_plan)
    # a run is drawn with the CompiledCell's trajectories
    panel = render_instants(cc, run, [mid])
    assert len(panel.axes) == 1
