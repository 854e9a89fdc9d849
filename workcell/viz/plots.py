"""Plots of schedules and simulation runs (matplotlib, headless).

* :func:`gantt` -- one lane per arm (planned bars, executed bars beneath
  them), plus one lane per zone and per tool from the plan's reservations;
* :func:`zone_timeline` -- who holds which zone (and tool) when, from a
  reservations table (planned or executed);
* :func:`render_instants` -- the cell drawn at chosen instants of a plan or
  a run, side by side;
* :func:`motion_frames` -- the arms' motion as a sequence of PNG (or GLB)
  frames;
* :func:`arm_joints` -- every arm's joint vector at given times (what the
  two pictures above draw).

Every function builds a :class:`matplotlib.figure.Figure` directly (never
through ``pyplot``), so nothing is left open in pyplot's global registry and
the functions work without a display. Bars carry a ``gid`` naming what they
stand for (``"planned:TASK"``, ``"executed:TASK"``, ``"failed:TASK"``,
``"wait:TASK"``, ``"zone:ZONE:TASK"``, ``"tool:TOOL:TASK"``; a run's zone and
tool use adds ``":executed"``) and fault markers are lines with ``gid``
``"fault:ARM"``: that is what the tests count.

Poses between tasks: an arm stands at its last task's end joints (its start
joints before its first task) and travels to the next task's start joints
with one rest-to-rest move of its drives that ends at that task's start --
the travel (setup) time the scheduler plans with. Inside a task, a wait at a
zone border stops the arm at the border (SEEDS.md S2.6); a detour cost
charged by the blocking oracle (S2.12) is drawn as standing at the task's end
pose.

Examples
--------
>>> from scheduler.problem import Model
>>> from scheduler import Schedule
>>> m = Model()
>>> a, b = m.add_arm("a"), m.add_arm("b")
>>> t0, t1 = m.add_task("t0"), m.add_task("t1")
>>> m.add_mode(t0, a, 2.0); m.add_mode(t1, b, 3.0)
>>> p = m.build()
>>> fig = gantt(p, Schedule.from_starts(p, [0, 1], [0.0, 1.0]))
>>> [t.get_text() for t in fig.axes[0].get_yticklabels()]
['a', 'b']
>>> sorted(r.get_gid() for r in fig.axes[0].patches)
['planned:t0', 'planned:t1']
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from multiarm.errors import UsageError, ValidationError
from multiarm.types import FloatArray
from scheduler.schedule import Reservation, Schedule

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from scheduler.problem import Problem
    from workcell.cell import Cell
    from workcell.compile import CompiledCell

__all__ = ["arm_joints", "gantt", "motion_frames", "render_instants", "zone_timeline"]

_TASK_COLUMNS = ("task", "arm", "start", "end")
_RES_COLUMNS = ("kind", "resource", "arm", "task", "start", "end")


# ----------------------------------------------------------------- inputs


def _figure(ax: Axes | None, size: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is not None:
        fig = ax.get_figure()
        if fig is None:  # pragma: no cover - an Axes always belongs to a figure
            raise ValidationError("the Axes given belongs to no figure")
        return fig, ax  # type: ignore[return-value]
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    return fig, fig.add_subplot()


def _arm_colours(names: Sequence[str]) -> dict[str, Any]:
    from matplotlib import colormaps

    cmap = colormaps["tab10" if len(names) <= 10 else "tab20"]
    return {n: cmap(i % cmap.N) for i, n in enumerate(names)}


def _tasks_frame(problem: Problem | None, data: Any) -> pd.DataFrame:
    """Tasks (task, arm, start, end, status) from a tasks table, a Schedule or a run."""
    import pandas as pd

    if hasattr(data, "tasks_frame"):
        data = data.tasks_frame()
    if isinstance(data, Schedule):
        if problem is None:
            raise ValidationError("a Schedule needs its problem to be drawn")
        df = data.to_dataframe(problem)
        df["status"] = "done"
        return df
    if not isinstance(data, pd.DataFrame):
        raise ValidationError(
            f"expected a tasks DataFrame, a Schedule or a simulation result, "
            f"not {type(data).__name__}"
        )
    missing = [c for c in _TASK_COLUMNS if c not in data.columns]
    if missing:
        raise ValidationError(f"the tasks table lacks the column {missing[0]!r}")
    df = data.copy()
    if "status" not in df.columns:
        df["status"] = "done"
    return df


def _reservations_frame(data: Any, problem: Problem | None = None) -> pd.DataFrame:
    """Reservations (kind, resource, arm, task, start, end) from a table, records,
    a Schedule (with its problem) or a run."""
    import pandas as pd

    if hasattr(data, "reservations_frame"):
        data = data.reservations_frame()
    if isinstance(data, Schedule):
        if problem is None:
            raise ValidationError("a Schedule needs its problem for its reservations")
        data = data.reservations(problem)
    if isinstance(data, pd.DataFrame):
        missing = [c for c in _RES_COLUMNS if c not in data.columns]
        if missing:
            raise ValidationError(f"the reservations table lacks the column {missing[0]!r}")
        return data
    rows = list(data)
    bad = [r for r in rows if not isinstance(r, Reservation)]
    if bad:
        raise ValidationError(
            f"expected a reservations DataFrame or Reservation records, not {type(bad[0]).__name__}"
        )
    return pd.DataFrame(
        [(r.kind, r.resource, r.arm, r.task, r.start, r.end) for r in rows],
        columns=list(_RES_COLUMNS),
    )


GRID_LANE = "space grid"
"""The one lane of all the compile's space-grid zones (``grid_X_Y_Z``,
:mod:`workcell.geometry.reach`): there are tens to hundreds of them."""


def _lane_of(kind: str, resource: str) -> tuple[str, str]:
    """Zone reservations of every kind share one lane per zone (the space-grid
    zones one lane together); tools have their own."""
    if kind == "tool":
        return ("tool", str(resource))
    return ("zone", GRID_LANE if str(resource).startswith("grid_") else str(resource))


# ------------------------------------------------------------------ gantt


def _bar(
    ax: Axes,
    y: float,
    start: float,
    end: float,
    height: float,
    gid: str,
    **style: Any,
) -> None:
    (rect,) = ax.barh(y, end - start, left=start, height=height, align="edge", **style).patches
    rect.set_gid(gid)


def gantt(
    problem: Problem,
    schedule: Schedule,
    executed: Any = None,
    *,
    ax: Axes | None = None,
    lanes: bool = True,
    title: str | None = None,
) -> Figure:
    """A Gantt chart of a plan, and of what ran when ``executed`` is given.

    Lanes, top to bottom: one per arm (its tasks), then -- with ``lanes`` --
    one per zone of the problem (exclusive occupancy, movement in a shared
    zone and an arm's start-zone stay, from
    :meth:`scheduler.Schedule.reservations`) and one per tool. Bars are
    coloured by arm; waits at zone borders are hatched inside the planned
    bars. With ``executed``, each lane is split: the plan on top, what ran
    beneath (failed tasks red and hatched), and dashed lines mark both
    makespans.

    Parameters
    ----------
    problem : scheduler.Problem
    schedule : scheduler.Schedule
        The plan.
    executed : DataFrame or Schedule or simulation result, optional
        What ran: a tasks table with columns ``task, arm, start, end`` (and
        optionally ``status``, ``"done"`` or ``"failed"``) such as
        ``SimResult.tasks_frame()``, a :class:`~scheduler.Schedule`, or an
        object with ``tasks_frame()`` (and ``reservations_frame()``, whose
        zone and tool use then fills the lower half of those lanes, and whose
        ``trace`` faults on an arm are marked with a red cross). A failed task
        that never started is drawn at its planned time on its planned arm.
    ax : matplotlib Axes, optional
        Draw there (else a new figure).
    lanes : bool
        Draw the zone and tool lanes.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    n_lanes = problem.n_arms + len({_lane_of("zone", z) for z in problem.zone_names})
    fig, ax = _figure(ax, (11, 1.2 + 0.32 * (n_lanes + problem.n_tools)))
    colours = _arm_colours(problem.arm_names)
    lane_keys: list[tuple[str, str]] = [("arm", a) for a in problem.arm_names]
    if lanes:
        lane_keys += list(dict.fromkeys(_lane_of("zone", z) for z in problem.zone_names))
        lane_keys += [("tool", k) for k in problem.tool_names]
    y_of = {key: -i for i, key in enumerate(lane_keys)}
    split = executed is not None
    h = 0.4 if split else 0.8

    def top(key: tuple[str, str]) -> float:
        return y_of[key] + (0.0 if split else -0.4)

    def bottom(key: tuple[str, str]) -> float:
        return y_of[key] - 0.4

    arms = schedule.arms(problem)
    for t in range(schedule.n_tasks):
        arm = problem.arm_names[int(arms[t])]
        s, e = float(schedule.start[t]), float(schedule.end[t])
        name = problem.task_names[t]
        _bar(ax, top(("arm", arm)), s, e, h, f"planned:{name}", color=colours[arm], alpha=0.55)
        sh = problem.shapes[int(schedule.mode[t])]
        w = schedule.waits[t]
        for b, wait in zip(sh.borders, w.tolist(), strict=True):
            if wait > 0:
                ws = s + b + sh.shift(w, b, False)
                _bar(
                    ax,
                    top(("arm", arm)),
                    ws,
                    ws + wait,
                    h,
                    f"wait:{name}",
                    facecolor="white",
                    edgecolor=colours[arm],
                    hatch="///",
                    linewidth=0.5,
                )
    if lanes:
        for r in schedule.reservations(problem):
            key = _lane_of(r.kind, r.resource)
            if key in y_of and r.end > r.start:
                gid = f"{key[0]}:{r.resource}:{r.task or 'start'}"
                _bar(ax, top(key), r.start, r.end, h, gid, color=colours[r.arm], alpha=0.55)
    ax.axvline(schedule.makespan, color="black", linestyle="--", linewidth=0.8)
    if split:
        df = _tasks_frame(problem, executed)
        index = {n: t for t, n in enumerate(problem.task_names)}
        for row in df.itertuples(index=False):
            arm, s, e = str(row.arm), float(row.start), float(row.end)
            failed = str(row.status) != "done"
            ti = index.get(str(row.task))
            if failed and not np.isfinite(s) and ti is not None:
                # never started: drawn where it was planned, on its planned arm
                arm = problem.arm_names[int(arms[ti])]
                s, e = float(schedule.start[ti]), float(schedule.end[ti])
            if ("arm", arm) not in y_of or not np.isfinite(s):
                continue
            e = e if np.isfinite(e) else s
            if failed:
                _bar(
                    ax,
                    bottom(("arm", arm)),
                    s,
                    max(e, s),
                    h,
                    f"failed:{row.task}",
                    facecolor="white",
                    edgecolor="red",
                    hatch="xx",
                )
            else:
                _bar(ax, bottom(("arm", arm)), s, e, h, f"executed:{row.task}", color=colours[arm])
        trace: Any = getattr(executed, "trace", None)
        faults = trace.of_kind("fault") if hasattr(trace, "of_kind") else []
        for ev in faults:
            if ("arm", ev.arm) in y_of:
                ax.plot(
                    [ev.time],
                    [y_of[("arm", ev.arm)]],
                    marker="X",
                    color="red",
                    markersize=9,
                    linestyle="none",
                    gid=f"fault:{ev.arm}",
                )
        done_end = df.loc[df["status"] == "done", "end"]
        if len(done_end):
            ax.axvline(float(done_end.max()), color="black", linestyle=":", linewidth=1.0)
        if lanes and hasattr(executed, "reservations_frame"):
            res = _reservations_frame(executed)
            for row in res.itertuples(index=False):
                key = _lane_of(str(row.kind), str(row.resource))
                if key in y_of and float(row.end) > float(row.start):
                    _bar(
                        ax,
                        bottom(key),
                        float(row.start),
                        float(row.end),
                        h,
                        f"{key[0]}:{row.resource}:{row.task}:executed",
                        color=colours.get(str(row.arm), "grey"),
                    )
    from matplotlib.patches import Patch

    handles: list[Artist] = [
        Patch(facecolor="grey", alpha=0.55, label="planned"),
        Patch(facecolor="white", edgecolor="grey", hatch="///", label="wait at a zone border"),
    ]
    if split:
        handles += [
            Patch(facecolor="grey", label="executed"),
            Patch(
                facecolor="white",
                edgecolor="red",
                hatch="xx",
                label="failed (unstarted: as planned)",
            ),
        ]
        if any((ln.get_gid() or "").startswith("fault:") for ln in ax.lines):
            from matplotlib.lines import Line2D

            handles.append(
                Line2D([], [], marker="X", color="red", linestyle="none", label="fault on an arm")
            )
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    ax.set_xlim(left=0.0)
    ax.set_yticks([y_of[k] for k in lane_keys])
    ax.set_yticklabels([n if kind == "arm" else f"{kind} {n}" for kind, n in lane_keys])
    ax.set_ylim(-len(lane_keys) + 0.4, 0.6)
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", linewidth=0.3)
    ax.set_title(
        title
        or (
            f"{problem.name}: planned (top, makespan {schedule.makespan:.1f} s) vs executed (below)"
            if split
            else f"{problem.name}: planned schedule, makespan {schedule.makespan:.1f} s"
        )
    )
    return fig


def zone_timeline(
    reservations: Any,
    *,
    ax: Axes | None = None,
    title: str | None = None,
    tools: bool = True,
) -> Figure:
    """Zone occupancy over time: one lane per zone (and per tool), bars coloured by arm.

    Parameters
    ----------
    reservations : DataFrame or sequence of scheduler.Reservation or simulation result
        Rows ``kind, resource, arm, task, start, end`` (kind ``"zone"``,
        ``"move"``, ``"start"`` or ``"tool"``), as from
        ``SimResult.reservations_frame()`` or
        :meth:`scheduler.Schedule.reservations`; or an object with
        ``reservations_frame()``.
    ax : matplotlib Axes, optional
    title : str, optional
    tools : bool
        Draw tool lanes too.

    Returns
    -------
    matplotlib.figure.Figure
        Lanes in the order the resources first appear, zones before tools.

    Examples
    --------
    >>> from scheduler.schedule import Reservation
    >>> fig = zone_timeline([Reservation("zone", "fixture", "t0", "a", 0.0, 2.0),
    ...                      Reservation("move", "belt", "t1", "b", 1.0, 3.0)])
    >>> [t.get_text() for t in fig.axes[0].get_yticklabels()]
    ['zone fixture', 'zone belt']
    """
    df = _reservations_frame(reservations)
    keys: list[tuple[str, str]] = []
    for row in df.itertuples(index=False):
        key = _lane_of(str(row.kind), str(row.resource))
        if key not in keys and (tools or key[0] != "tool"):
            keys.append(key)
    keys.sort(key=lambda k: k[0] == "tool")  # stable: zones first, in order of appearance
    arms = list(dict.fromkeys(str(a) for a in df["arm"]))
    colours = _arm_colours(arms)
    fig, ax = _figure(ax, (11, 1.2 + 0.32 * max(len(keys), 1)))
    y_of = {k: -i for i, k in enumerate(keys)}
    for row in df.itertuples(index=False):
        key = _lane_of(str(row.kind), str(row.resource))
        s, e = float(row.start), float(row.end)
        if key not in y_of or not (np.isfinite(s) and np.isfinite(e)) or e <= s:
            continue
        task = row.task if isinstance(row.task, str) else "start"
        _bar(
            ax,
            y_of[key] - 0.4,
            s,
            e,
            0.8,
            f"{key[0]}:{row.resource}:{task}",
            color=colours[str(row.arm)],
            # movement in a shared zone is drawn lighter than exclusive occupancy
            alpha=0.5 if row.kind == "move" else 0.9,
        )
    from matplotlib.patches import Patch

    ax.legend(
        handles=[Patch(color=colours[a], label=a) for a in arms],
        loc="upper left",
        bbox_to_anchor=(1.0, 1.0),
        fontsize=8,
        title="arm",
    )
    ax.set_xlim(left=0.0)
    ax.set_yticks([y_of[k] for k in keys])
    ax.set_yticklabels([f"{kind} {n}" for kind, n in keys])
    ax.set_ylim(-len(keys) + 0.4, 0.6)
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", linewidth=0.3)
    ax.set_title(title or "zone occupancy (light: movement in a shared zone)")
    return fig


# ------------------------------------------------------------------ poses


def _compiled(cell_or_compiled: Any, plan: Any) -> CompiledCell:
    from workcell.compile import CompiledCell

    if isinstance(cell_or_compiled, CompiledCell):
        return cell_or_compiled
    raise UsageError(
        "drawing the arms needs the CompiledCell that workcell.compile_cell returned "
        f"(its trajectories), not a {type(cell_or_compiled).__name__}"
    )


def _rows(cc: CompiledCell, plan: Any) -> list[tuple[int, int, float, float, FloatArray]]:
    """(arm, mode, start, end, waits) of every task that ran or is planned."""
    p = cc.problem
    sched: Schedule | None
    if isinstance(plan, Schedule):
        sched = plan
    elif hasattr(plan, "executed"):
        sched = plan.executed
    else:
        raise ValidationError(
            f"expected a Schedule or a simulation result, not {type(plan).__name__}"
        )
    if sched is not None:
        if sched.n_tasks != p.n_tasks:
            raise ValidationError(
                f"the schedule covers {sched.n_tasks} tasks, the problem has {p.n_tasks}"
            )
        arms = sched.arms(p)
        return [
            (int(arms[t]), int(sched.mode[t]), float(sched.start[t]), float(sched.end[t]), w)
            for t, w in enumerate(sched.waits)
        ]
    # a run in which some task failed: what did run, without its waits
    out = []
    df = _tasks_frame(p, plan)
    for row in df.itertuples(index=False):
        if str(row.status) != "done":
            continue
        a, t = p.arm_names.index(str(row.arm)), p.task_names.index(str(row.task))
        m = int(p.mode_of[a, t])
        out.append((a, m, float(row.start), float(row.end), np.zeros(len(p.shapes[m].borders))))
    return out


def arm_joints(
    compiled: CompiledCell, plan: Any, times: Sequence[float] | FloatArray
) -> dict[str, FloatArray]:
    """Every arm's joint vector at ``times`` under a plan or a run.

    Parameters
    ----------
    compiled : CompiledCell
        From :func:`workcell.compile_cell` (its modes' trajectories).
    plan : scheduler.Schedule or simulation result
        A schedule of ``compiled.problem``; or a run, whose executed schedule
        is used (or, when some task failed, its completed tasks without their
        waits).
    times : (N,) float, seconds

    Returns
    -------
    dict of arm name -> (N, dof) float, radians or metres per joint
        See the module docstring for the poses between and inside tasks.
    """
    cc = compiled
    cell = cc.cell
    ts = np.asarray(times, dtype=float).reshape(-1)
    if not np.all(np.isfinite(ts)):
        raise ValidationError("times must be finite")
    per_arm: list[list[tuple[int, float, float, FloatArray]]] = [[] for _ in cell.arms]
    for a, m, s, e, w in _rows(cc, plan):
        per_arm[a].append((m, s, e, w))
    out: dict[str, FloatArray] = {}
    for a, (arm, q0) in enumerate(zip(cell.arms, cell.start, strict=True)):
        seq = sorted(per_arm[a], key=lambda r: r[1])
        q = np.empty((len(ts), arm.dof))
        for i, t in enumerate(ts.tolist()):
            q[i] = _pose(cc, arm, np.asarray(q0, dtype=float), seq, t)
        out[arm.name] = q
    return out


def _pose(
    cc: CompiledCell,
    arm: Any,
    q0: FloatArray,
    seq: list[tuple[int, float, float, FloatArray]],
    t: float,
) -> FloatArray:
    prev = q0
    for m, s, e, w in seq:
        cm = cc.modes[m]
        if t < s:  # before this task: parked, or travelling to its start
            travel = float(arm.move_time(prev, cm.q_start))
            if travel > 0 and t >= s - travel:
                traj = arm.move(prev, cm.q_start, arm.interpolation)
                sample: FloatArray = traj.sample(np.array([t - (s - travel)]))[0]
                return sample
            return prev
        if t < e:  # inside: walk the waits at the borders
            local = t - s
            for b, wait in zip(cc.problem.shapes[m].borders, w.tolist(), strict=True):
                if local < b:
                    break
                local = b if local < b + wait else local - wait
            inside: FloatArray = cm.trajectory.sample(np.array([local]))[0]
            return inside
        prev = np.asarray(cm.q_end, dtype=float)
    return prev


# ------------------------------------------------------------------ cells


def _draw_cell(
    ax: Axes, cell: Cell, joints: Mapping[str, Sequence[float]], view: str, title: str
) -> None:
    from scipy.spatial import ConvexHull, QhullError

    from workcell.viz.scene import cell_scene

    scene = cell_scene(cell, joints)
    lo, hi = (np.asarray(b, dtype=float) for b in cell.zone_map.bounds)
    if view == "3d":
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # type: ignore[import-untyped]

        for node in scene.graph.nodes_geometry:
            tf, gname = scene.graph[node]
            mesh = scene.geometry[gname].copy()
            mesh.apply_transform(tf)
            rgba = np.asarray(mesh.visual.face_colors[0], dtype=float) / 255
            ax.add_collection3d(  # type: ignore[attr-defined]
                Poly3DCollection(mesh.triangles, facecolor=rgba, edgecolor="none")
            )
        ax.set_zlim(lo[2], hi[2])  # type: ignore[attr-defined]
    else:
        from matplotlib.patches import Polygon

        for node in scene.graph.nodes_geometry:
            tf, gname = scene.graph[node]
            mesh = scene.geometry[gname].copy()
            mesh.apply_transform(tf)
            rgba = np.asarray(mesh.visual.face_colors[0], dtype=float) / 255
            xy = mesh.vertices[:, :2]
            try:
                hull = xy[ConvexHull(xy).vertices]
            except QhullError:  # a flat outline: its bounding box
                (x0, y0), (x1, y1) = xy.min(0), xy.max(0)
                hull = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
            ax.add_patch(Polygon(hull, closed=True, color=rgba, gid=node))
        for arm in cell.arms:
            x, y = arm.fk(np.asarray(joints[arm.name], dtype=float)[None])[0, :2, 3]
            ax.annotate(arm.name, (x, y), fontsize=7, color="black")
        ax.set_aspect("equal")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_title(title, fontsize=9)


def render_instants(
    cell_or_compiled: CompiledCell,
    result_or_schedule: Any,
    times: Sequence[float] | FloatArray,
    *,
    view: Literal["top", "3d"] = "top",
    ncols: int | None = None,
) -> Figure:
    """The cell at chosen instants of a plan or a run, one panel per instant.

    Parameters
    ----------
    cell_or_compiled : CompiledCell
        From :func:`workcell.compile_cell` (its modes' trajectories); a
        plain Cell or Problem raises :class:`~multiarm.errors.UsageError`.
    result_or_schedule : simulation result or scheduler.Schedule
    times : sequence of float, seconds
    view : {"top", "3d"}
    ncols : int, optional
        Panels per row (default: up to 4).

    Returns
    -------
    matplotlib.figure.Figure
        One Axes per instant, titled with its time; arms grey and labelled,
        zones translucent (red: exclusive, blue: shared).
    """
    from matplotlib.figure import Figure

    if view not in ("top", "3d"):
        raise ValidationError(f"view must be 'top' or '3d', not {view!r}")
    ts = np.asarray(times, dtype=float).reshape(-1)
    if len(ts) == 0:
        raise ValidationError("render_instants needs at least one time")
    cc = _compiled(cell_or_compiled, result_or_schedule)
    joints = arm_joints(cc, result_or_schedule, ts)
    n = len(ts)
    cols = ncols or min(n, 4)
    if cols < 1:
        raise ValidationError(f"ncols must be >= 1, got {ncols}")
    rows = -(-n // cols)
    fig = Figure(figsize=(3.6 * cols, 3.2 * rows), layout="constrained")
    for i, t in enumerate(ts.tolist()):
        kw = {"projection": "3d"} if view == "3d" else {}
        ax = fig.add_subplot(rows, cols, i + 1, **kw)
        at = {name: q[i] for name, q in joints.items()}
        _draw_cell(ax, cc.cell, at, view, f"{cc.cell.name} at t = {t:.1f} s")
    return fig


def motion_frames(
    cell_or_compiled: CompiledCell,
    result_or_schedule: Any,
    directory: str | PathLike[str],
    *,
    times: Iterable[float] | None = None,
    n_frames: int = 24,
    view: Literal["top", "3d"] = "top",
    glb: bool = False,
) -> list[Path]:
    """The arms' motion as a numbered sequence of frames in ``directory``.

    PNG frames (``frame_0000.png``, ...) drawn like :func:`render_instants`,
    or with ``glb`` one GLB scene per frame (``frame_0000.glb``, ...; trimesh
    writes no animation channels, so an animated GLB is left to tools that
    join frames).

    Parameters
    ----------
    cell_or_compiled, result_or_schedule
        As for :func:`render_instants`.
    directory : path
        Created if missing.
    times : iterable of float, optional
        Frame times; default ``n_frames`` evenly spaced from 0 to the makespan.
    n_frames : int
    view : {"top", "3d"}
    glb : bool

    Returns
    -------
    list of Path
        The frames, in time order.
    """
    from workcell.viz.scene import export_glb

    if view not in ("top", "3d"):
        raise ValidationError(f"view must be 'top' or '3d', not {view!r}")
    cc = _compiled(cell_or_compiled, result_or_schedule)
    if times is None:
        if n_frames < 1:
            raise ValidationError(f"n_frames must be >= 1, got {n_frames}")
        end = max((e for _, _, _, e, _ in _rows(cc, result_or_schedule)), default=0.0)
        ts = np.linspace(0.0, end, n_frames)
    else:
        ts = np.asarray(list(times), dtype=float)
    joints = arm_joints(cc, result_or_schedule, ts)
    out_dir = Path(directory)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    from matplotlib.figure import Figure

    for i, t in enumerate(ts.tolist()):
        at = {name: q[i] for name, q in joints.items()}
        if glb:
            paths.append(export_glb(cc.cell, out_dir / f"frame_{i:04d}.glb", at))
            continue
        fig = Figure(figsize=(6, 5), layout="constrained")
        ax = fig.add_subplot(**({"projection": "3d"} if view == "3d" else {}))
        _draw_cell(ax, cc.cell, at, view, f"{cc.cell.name} at t = {t:.2f} s")
        path = out_dir / f"frame_{i:04d}.png"
        fig.savefig(path, dpi=90)
        paths.append(path)
    return paths
