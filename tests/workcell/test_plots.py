"""Plots of plans and runs (workcell.viz.plots): lanes, bars, poses, frames."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from multiarm.errors import UsageError, ValidationError
from scheduler import Schedule, solve
from workcell import CompiledCell, compile_cell, load_example, simulate
from workcell.sim.events.trace import Trace
from workcell.viz import (
    arm_colours,
    arm_joints,
    gantt,
    joint_timeline,
    motion_frames,
    render_instants,
    zone_timeline,
)
from workcell.viz.plots import PLANNED_SHADE


@pytest.fixture(scope="module")
def compiled() -> CompiledCell:
    """The one place that compiles (the compile's entry point may be renamed)."""
    return compile_cell(load_example("supersigma"))


@pytest.fixture(scope="module")
def planned(compiled: CompiledCell) -> tuple[CompiledCell, Schedule]:
    r = solve(compiled.problem, "greedy", time_limit=5.0, seed=0)
    assert r.schedule is not None
    return compiled, r.schedule


def _gids(fig: object, prefix: str) -> list[str]:
    ax = fig.axes[0]  # type: ignore[attr-defined]
    return [p.get_gid() for p in ax.patches if (p.get_gid() or "").startswith(prefix)]


def _union(spans: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The disjoint intervals covering ``spans`` (touching ones joined)."""
    out: list[list[float]] = []
    for a, b in sorted(spans):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def _check_zone_bars(fig: object, res: Sequence[Any], suffix: str = "") -> None:
    """The zone bars of ``fig`` (gids ending with ``suffix``) stand for the
    reservations ``res``: one bar per reservation of an SDL zone, and in the
    space-grid lane, per task, bars that cover exactly the union of the task's
    block reservations (one bar per disjoint stretch)."""
    ax = fig.axes[0]  # type: ignore[attr-defined]
    res = [r for r in res if r.end > r.start and r.kind != "tool"]
    bars = [
        b
        for b in ax.patches
        if (b.get_gid() or "").startswith("zone:") and b.get_gid().endswith(suffix)
    ]
    sdl = [r for r in res if not r.resource.startswith("grid_")]
    assert sum(not b.get_gid().startswith("zone:space grid:") for b in bars) == len(sdl)
    want: dict[str, list[tuple[float, float]]] = {}
    for r in res:
        if r.resource.startswith("grid_"):
            want.setdefault(f"zone:space grid:{r.task or 'start'}{suffix}", []).append(
                (float(r.start), float(r.end))
            )
    got: dict[str, list[tuple[float, float]]] = {}
    for b in bars:
        if b.get_gid().startswith("zone:space grid:"):
            got.setdefault(b.get_gid(), []).append((b.get_x(), b.get_x() + b.get_width()))
    assert want, "the fixture's plan holds no grid block: the check would prove nothing"
    assert sorted(got) == sorted(want)
    for gid, spans in want.items():
        flat = [x for span in sorted(got[gid]) for x in span]
        assert flat == pytest.approx([x for span in _union(spans) for x in span]), gid
    # merging pays: fewer bars than block reservations
    assert len(bars) < len(res)


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
        f"space grid ({p.n_zones - len(sdl)} blocks)",
        *(f"tool {k}" for k in p.tool_names),
    ]
    assert sorted(_gids(fig, "planned:")) == sorted(f"planned:{t}" for t in p.task_names)
    n_waits = sum(int((w > 0).sum()) for w in s.waits)
    assert len(_gids(fig, "wait:")) == n_waits
    res = [r for r in s.reservations(p) if r.end > r.start]
    _check_zone_bars(fig, res)
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
    xs = sorted(
        float(line.get_xdata()[0])
        for line in fig.axes[0].lines
        if (line.get_gid() or "").startswith("makespan:")
    )
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
        n_grid = len({r.resource for r in res if r.resource.startswith("grid_")})
        zones = list(
            dict.fromkeys(
                f"space grid ({n_grid} blocks)"
                if r.resource.startswith("grid_")
                else f"zone {r.resource}"
                for r in res
                if r.kind != "tool"
            )
        )
        tools = list(dict.fromkeys(r.resource for r in res if r.kind == "tool"))
        assert labels == [*zones, *(f"tool {k}" for k in tools)]
        _check_zone_bars(fig, res)
        assert len(_gids(fig, "tool:")) == sum(r.end > r.start and r.kind == "tool" for r in res)
        legend = fig.axes[0].get_legend()
        assert legend is not None
        texts = [t.get_text() for t in legend.get_texts()]
        assert texts[: p.n_arms] == [f"arm {a}" for a in dict.fromkeys(r.arm for r in res)]
    no_tools = zone_timeline(res, tools=False)
    _check_zone_bars(no_tools, res)
    assert not _gids(no_tools, "tool:")
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
        self.trace.add(3.0, "fault", arm=cc.problem.arm_names[0], detail="crash: reflex-arc stop")

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
    (mark,) = [ln for ln in fig.axes[0].lines if ln.get_gid() == f"fault:crash:{p.arm_names[0]}"]
    assert list(mark.get_xdata()) == [3.0] and list(mark.get_ydata()) == [0]
    # the run's zone use fills the lower half of the zone lanes
    _check_zone_bars(fig, run._res, ":executed")
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


# ------------------------------------------------- one look, faults, grid

FAULTS: list[dict[str, object]] = [
    {"kind": "late_part", "part": "pin", "delay": 6.0},
    {"kind": "crash", "arm": "left", "at": 4.0},
    {"kind": "lost_sync", "arm": "right", "axis": 0, "at": 3.0, "steps": 80},
    {"kind": "message_loss", "probability": 0.02},
    {"kind": "emergency_stop", "at": 14.0, "duration": 3.0},
    {"kind": "activate_zones", "at": 22.0, "zones": "ALL"},
    {"kind": "arm_failure", "arm": "right", "at": 90.0},
]
"""One fault of every kind (the zone activation keeps every zone active)."""


@pytest.fixture(scope="module")
def faulty(planned: tuple[CompiledCell, Schedule]) -> tuple[CompiledCell, Schedule, Any]:
    cc, s = planned
    zones = list(cc.cell.zone_map.zone_names())
    faults = [{**f, "zones": zones} if f.get("zones") == "ALL" else f for f in FAULTS]
    return cc, s, simulate(cc, s, seed=0, faults=faults)


def _rgba(c: object) -> np.ndarray:
    from matplotlib.colors import to_rgba

    return np.asarray(to_rgba(c))  # type: ignore[arg-type]


def test_one_colour_per_arm_in_every_plot(
    faulty: tuple[CompiledCell, Schedule, Any], tmp_path: Path
) -> None:
    cc, s, run = faulty
    p = cc.problem
    colours = {a: _rgba(c) for a, c in arm_colours(p).items()}
    assert list(colours) == list(p.arm_names)
    assert len({tuple(c) for c in colours.values()}) == p.n_arms
    arm_of = dict(zip(run.tasks_frame()["task"], run.tasks_frame()["arm"], strict=True))
    plan_arm = dict(zip(p.task_names, (p.arm_names[a] for a in s.arms(p)), strict=True))
    ax = gantt(cc, s, run).axes[0]  # a CompiledCell is accepted for the problem
    seen = set()
    for bar in ax.patches:
        kind, _, rest = (bar.get_gid() or "").partition(":")
        face = _rgba(bar.get_facecolor())
        if kind == "executed":
            assert np.allclose(face, colours[arm_of[rest]]), rest
            seen.add(arm_of[rest])
        elif kind == "planned":
            # the light shade of the same colour: colour mixed with white
            c = colours[plan_arm[rest]]
            assert np.allclose(1 - face[:3], PLANNED_SHADE * (1 - c[:3])), rest
    assert seen == set(p.arm_names)
    # the zone timeline, given the records in reverse (right's first): same colours
    records = list(reversed(s.reservations(p)))
    for data, arms in ((run, None), (records, cc)):
        ax = zone_timeline(data, arms=arms).axes[0]
        n = 0
        for bar in ax.patches:
            _, _, task = (bar.get_gid() or "").split(":")
            if task == "start" or _rgba(bar.get_facecolor())[0] > 0.9:
                continue
            who = arm_of[task] if data is run else plan_arm[task]
            n += np.allclose(_rgba(bar.get_facecolor()), colours[who])
        assert n > 10
    # the cell at instants, and the joints
    fig = render_instants(cc, run, [0.0, 50.0])
    for axi in fig.axes:
        arms = [pt for pt in axi.patches if not (pt.get_gid() or "zone:").startswith("zone:")]
        assert arms
        for pt in arms:
            assert np.allclose(_rgba(pt.get_facecolor()), colours[pt.get_gid().split(":")[0]])
    lines = (
        joint_timeline(cc, run, n_samples=50)
        .axes[0]
        .figure.findobj(
            lambda a: (getattr(a, "get_gid", lambda: None)() or "").startswith("joint:")
        )
    )
    assert {ln.get_gid().split(":")[1] for ln in lines} == set(p.arm_names)
    for ln in lines:
        assert np.allclose(_rgba(ln.get_color()), colours[ln.get_gid().split(":")[1]])
    # motion frames: every arm's colour is in the picture
    from matplotlib.image import imread

    (frame,) = motion_frames(cc, run, tmp_path, times=[30.0])
    img = imread(frame)[:, :, :3]
    for a, c in colours.items():
        assert np.sum(np.all(np.abs(img - c[:3]) < 0.02, axis=2)) > 30, a


@pytest.mark.parametrize("width", [5.0, 24.0])
def test_task_names_show_only_where_they_fit(
    planned: tuple[CompiledCell, Schedule], width: float
) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.text import Text

    from workcell.viz.barlabel import BarLabel

    cc, s = planned
    p = cc.problem
    fig = Figure(figsize=(width, 3.0), layout="constrained")
    ax = fig.add_subplot()
    gantt(p, s, ax=ax, lanes=False)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    labels = [a for a in ax.texts if isinstance(a, BarLabel)]
    assert sorted(lb.get_text() for lb in labels) == sorted(p.task_names)
    shown = 0
    for lb in labels:
        assert lb.get_gid() == f"label:{lb.bar.get_gid()}"
        tb = Text.get_window_extent(lb, renderer)
        bb = lb.bar.get_window_extent(renderer)
        inside = bb.x0 < tb.x0 and tb.x1 < bb.x1 and bb.y0 <= tb.y0 and tb.y1 <= bb.y1
        assert lb.shown == inside, (lb.get_text(), width)
        shown += bool(lb.shown)
    # a narrow chart hides some names, a wide one shows them all
    assert (shown < len(labels)) if width < 8 else (shown == len(labels))


def test_consecutive_tasks_have_visible_boundaries(planned: tuple[CompiledCell, Schedule]) -> None:
    cc, s = planned
    p = cc.problem
    ax = gantt(p, s).axes[0]
    bars = [b for b in ax.patches if (b.get_gid() or "").startswith("planned:")]
    touching = 0
    for a in range(p.n_arms):
        mine = [
            b
            for b in bars
            if p.arm_names[int(s.arms(p)[p.task_names.index(b.get_gid()[8:])])] == p.arm_names[a]
        ]
        mine.sort(key=lambda b: b.get_x())
        for b0, b1 in itertools.pairwise(mine):
            touching += abs(b0.get_x() + b0.get_width() - b1.get_x()) < 1e-6
    assert touching > 0  # the plan has tasks back to back: they must not merge
    for b in bars:
        assert b.get_linewidth() > 0
        assert not np.allclose(_rgba(b.get_edgecolor()), _rgba(b.get_facecolor()))


def test_each_fault_kind_has_its_own_mark_and_the_legend_explains_all(
    faulty: tuple[CompiledCell, Schedule, Any],
) -> None:
    from workcell.style import FAULT_MARKS

    cc, s, run = faulty
    fig = gantt(cc, s, run)
    ax = fig.axes[0]
    marks = {ln.get_gid(): ln for ln in ax.lines if (ln.get_gid() or "").startswith("fault:")}
    kinds = {g.split(":")[1] for g in marks}
    assert kinds == {
        "arm_failure",
        "crash",
        "lost_sync",
        "message_loss",
        "late_part",
        "emergency_stop",
        "zone_activation",
    }
    by_kind = {g.split(":")[1]: ln.get_marker() for g, ln in marks.items()}
    assert len(set(by_kind.values())) == len(by_kind)  # distinct markers
    assert marks["fault:arm_failure:right"].get_xdata()[0] == pytest.approx(90.0)
    # cell-wide faults sit on the whole-cell lane, the top one
    ticks = {t.get_text(): y for t, y in zip(ax.get_yticklabels(), ax.get_yticks(), strict=True)}
    assert ticks["whole cell"] == max(ticks.values())
    for kind in ("late_part", "emergency_stop", "zone_activation"):
        assert list(marks[f"fault:{kind}:cell"].get_ydata()) == [ticks["whole cell"]]
    # the legend explains every mark, shade and line drawn
    legend = ax.get_legend()
    texts = [t.get_text() for t in legend.get_texts()]
    handles = legend.legend_handles
    for ln in marks.values():
        kind = ln.get_gid().split(":")[1]
        (h,) = [h for h, t in zip(handles, texts, strict=True) if t == FAULT_MARKS[kind].label]
        assert h.get_marker() == ln.get_marker()
    for gid, style, word in (
        ("makespan:planned", "--", "planned makespan"),
        ("makespan:executed", ":", "executed makespan"),
    ):
        (line,) = [ln for ln in ax.lines if ln.get_gid() == gid]
        assert line.get_linestyle() == style
        (h,) = [h for h, t in zip(handles, texts, strict=True) if t.startswith(word)]
        assert h.get_linestyle() == style
    drawn = {(b.get_gid() or "").split(":")[0] for b in ax.patches}
    assert {"planned", "executed", "emergency_stop"} <= drawn
    for gid, word in (
        ("planned", "planned (light"),
        ("executed", "executed (full"),
        ("wait", "wait at a zone border"),
        ("failed", "failed task"),
        ("emergency_stop", "emergency stop:"),
    ):
        assert (gid in drawn) == any(t.startswith(word) for t in texts), gid
    assert [f"arm {a}" for a in cc.problem.arm_names] == texts[: cc.problem.n_arms]


def test_every_fault_record_of_a_run_is_classified(
    faulty: tuple[CompiledCell, Schedule, Any],
) -> None:
    from workcell.style import fault_kind

    _, _, run = faulty
    found = {}
    for ev in run.trace:
        kind = fault_kind(ev)
        if ev.kind == "fault":
            assert kind != "other", ev.detail  # the plots know every fault the simulator writes
        if kind is None and ev.kind == "fault":
            assert ev.detail.startswith(("emergency stop cleared", "coordinator told", "position"))
        if kind is not None:
            found.setdefault(kind, ev.time)
    assert found["crash"] == pytest.approx(4.0) and found["lost_sync"] == pytest.approx(3.0)
    assert found["emergency_stop"] == pytest.approx(14.0)
    assert found["zone_activation"] >= 22.0
    assert len(found) == 7


def test_space_grid_blocks_and_the_wait_summary(
    faulty: tuple[CompiledCell, Schedule, Any],
) -> None:
    from workcell.compiled import SPACE_GRID
    from workcell.geometry.reach import block_name
    from workcell.viz import space_grid_table, wait_summary
    from workcell.viz.waits import block_bounds

    cc, _, run = faulty
    p = cc.problem
    grid = [z for z in p.zone_names if z.startswith("grid_")]
    table = space_grid_table(cc, run)
    assert list(table["block"]) == grid
    for row in table.itertuples(index=False):
        assert block_name(row.i, row.j, row.k) == row.block
        assert row.x_min == pytest.approx(row.i * SPACE_GRID)
        assert row.z_max - row.z_min == pytest.approx(SPACE_GRID)
        assert row.wait == run.metrics.zone_wait.get(row.block, 0.0)
    assert table["occupied"].sum() > 0
    rows = wait_summary(run, cc)
    assert rows == wait_summary(run)  # the run's own problem by default
    rank = {"zone": 0, "tool": 1, "grid": 2}
    assert [rank[r.kind] for r in rows] == sorted(rank[r.kind] for r in rows)
    zones = [r for r in rows if r.kind == "zone"]
    assert zones and all(not r.label.startswith("grid_") for r in zones)
    for r in zones:
        assert r.seconds == pytest.approx(run.metrics.zone_wait[r.label])
    assert [r.seconds for r in zones] == sorted((r.seconds for r in zones), reverse=True)
    (g,) = [r for r in rows if r.kind == "grid"]
    waits = {z: w for z, w in run.metrics.zone_wait.items() if z.startswith("grid_")}
    assert g.label == f"space grid ({len(grid)} blocks)"
    assert g.worst == max(waits, key=waits.__getitem__)
    assert g.seconds == pytest.approx(waits[g.worst])
    assert g.worst_bounds == block_bounds(g.worst)
    lo, hi = g.worst_bounds
    assert f"x {lo[0]:.2f}..{hi[0]:.2f}" in str(g) and g.worst in str(g)
    assert not any("grid_" in str(r) for r in rows if r.kind != "grid")


@given(
    st.integers(-50, 50),
    st.integers(-50, 50),
    st.integers(-50, 50),
    st.floats(0.01, 2.0),
)
def test_block_names_and_bounds_round_trip(x: int, y: int, z: int, size: float) -> None:
    from workcell.geometry.reach import block_name
    from workcell.viz.waits import block_bounds, grid_block

    name = block_name(x, y, z)
    assert grid_block(name) == (x, y, z)
    lo, hi = block_bounds(name, size)
    # the block the compile puts a point in (floor of point / size) is this one
    centre = 0.5 * (np.asarray(lo) + np.asarray(hi))
    assert tuple(np.floor(centre / size).astype(int)) == (x, y, z)
    assert np.allclose(np.asarray(hi) - np.asarray(lo), size)


def test_instants_label_zones_carry_units_and_clip_nothing(
    planned: tuple[CompiledCell, Schedule],
) -> None:
    cc, s = planned
    zones = set(cc.cell.zone_map.zone_names())
    fig = render_instants(cc, s, [0.0, 40.0, 80.0])
    for ax in fig.axes:
        assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
        assert {
            t.get_gid().split(":")[1]
            for t in ax.texts
            if (t.get_gid() or "").startswith("zonelabel:")
        } == zones
        assert {
            t.get_text() for t in ax.texts if (t.get_gid() or "").startswith("armlabel:")
        } == set(cc.problem.arm_names)
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        for pt in ax.patches:  # every link and every zone inside the axes
            v = pt.get_path().vertices
            assert x0 < v[:, 0].min() and v[:, 0].max() < x1, pt.get_gid()
            assert y0 < v[:, 1].min() and v[:, 1].max() < y1, pt.get_gid()
    (legend,) = fig.legends
    texts = [t.get_text() for t in legend.get_texts()]
    assert texts[:2] == [f"arm {a}" for a in cc.problem.arm_names]
    assert set(texts[2:]) <= {"exclusive zone", "shared zone"} and texts[2:]
    (ax3,) = render_instants(cc, s, [10.0], view="3d").axes
    assert ax3.get_zlabel() == "z (m)"  # type: ignore[attr-defined]


def test_joint_timeline_has_units_and_every_joint(planned: tuple[CompiledCell, Schedule]) -> None:
    cc, s = planned
    fig = joint_timeline(cc, s, n_samples=40)
    arms = cc.cell.arms
    lines = [ln for ax in fig.axes for ln in ax.lines]
    assert sorted(ln.get_gid() for ln in lines) == sorted(
        f"joint:{a.name}:{j}" for a in arms for j in a.joint_names
    )
    for ax in fig.axes:
        for ln in ax.lines:
            arm = next(a for a in arms if a.name == ln.get_gid().split(":")[1])
            kind = arm.joint_kinds[arm.joint_names.index(ln.get_gid().split(":")[2])]
            assert ax.get_ylabel().endswith("(m)" if kind == "prismatic" else "(rad)")
    assert fig.axes[-1].get_xlabel() == "time (s)"
    q = arm_joints(cc, s, [25.0])
    (ln,) = [ln for ln in lines if ln.get_gid() == f"joint:{arms[0].name}:{arms[0].joint_names[0]}"]
    xs = np.asarray(ln.get_xdata())
    i = int(np.argmin(np.abs(xs - 25.0)))
    assert (
        np.asarray(ln.get_ydata())[i]
        == pytest.approx(arm_joints(cc, s, [xs[i]])[arms[0].name][0, 0])
        and q
    )


def test_the_docs_show_every_image_they_generate() -> None:
    import re

    docs = Path(__file__).resolve().parents[2] / "docs"
    page = (docs / "plots.md").read_text()
    shown = set(re.findall(r"\]\(images/([\w.-]+\.png)\)", page))
    everywhere = set(
        re.findall(
            r"\]\(images/([\w.-]+\.png)\)", "".join(p.read_text() for p in docs.glob("*.md"))
        )
    )
    assert everywhere == {p.name for p in (docs / "images").glob("*.png")}
    script = (docs / "make_images.py").read_text()
    assert all(f'"{name}"' in script for name in shown)
