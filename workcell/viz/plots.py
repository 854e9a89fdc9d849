"""Plots of schedules and simulation runs (matplotlib, headless).

* :func:`gantt` -- one lane per arm (planned bars, executed bars beneath
  them), plus one lane per zone and per tool from the plan's reservations;
* :func:`zone_timeline` -- who holds which zone (and tool) when, from a
  reservations table (planned or executed);
* :func:`render_instants` -- the cell drawn at chosen instants of a plan or
  a run, side by side;
* :func:`motion_frames` -- the arms' motion as a sequence of PNG (or GLB)
  frames;
* :func:`joint_timeline` -- every arm's joints against time;
* :func:`arm_joints` -- every arm's joint vector at given times (what the
  pictures of the cell draw).

One look throughout (:mod:`workcell.style`): an arm has the same colour
in every plot of a run, keyed by its name in the problem's arm order
(:func:`~workcell.style.arm_colours`); a fault has the marker of its
kind (:data:`~workcell.style.FAULT_MARKS`); the compile's space-grid
zones share one lane, ``space grid (N blocks)`` (their coordinates:
:mod:`workcell.viz.waits`); axes carry their units (s, m, rad).

Every function builds a :class:`matplotlib.figure.Figure` directly (never
through ``pyplot``), so nothing is left open in pyplot's global registry and
the functions work without a display. Bars carry a ``gid`` naming what they
stand for (``"planned:TASK"``, ``"executed:TASK"``, ``"failed:TASK"``,
``"wait:TASK"``, ``"zone:ZONE:TASK"``, ``"tool:TOOL:TASK"``; a run's zone and
tool use adds ``":executed"``) and fault marks are lines with ``gid``
``"fault:KIND:ARM"``: that is what the tests count. In the space-grid lane a
task's block reservations that overlap or touch are one bar,
``"zone:space grid:TASK"`` (a task sweeps many blocks at once; drawn one per
block, ``cell8``'s charts had about 25,000 bars and took a minute to write).

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

from collections.abc import Iterable, Iterator, Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from multiarm.errors import UsageError, ValidationError
from multiarm.types import FloatArray
from scheduler.schedule import Reservation, Schedule
from workcell.style import FAULT_MARKS, arm_colours, arm_order, fault_kind
from workcell.viz.waits import grid_block, grid_lane_label

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from scheduler.problem import Problem
    from workcell.cell import Cell
    from workcell.compile import CompiledCell

__all__ = [
    "arm_joints",
    "gantt",
    "joint_timeline",
    "motion_frames",
    "render_instants",
    "zone_timeline",
]

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


LaneRow = tuple[tuple[str, str], str, str, str, str, float, float]
"""(lane key, resource, task, arm, kind, start, end) of one reservation drawn."""


def _lane_bars(rows: Iterable[LaneRow]) -> list[LaneRow]:
    """The bars of the zone and tool lanes: one per reservation, except in the
    space-grid lane, where one task's reservations (of one kind) that overlap or
    touch become one bar, its resource :data:`GRID_LANE` (a task sweeps many
    blocks at once: on ``cell8`` 7,033 of a plan's 8,271 reservations are
    blocks, 1,468 bars once merged, which look the same in the one lane).

    Rows with an empty or non-finite interval are dropped.

    Examples
    --------
    >>> g = ("zone", GRID_LANE)
    >>> rows = [(g, "grid_0_0_0", "t", "a", "zone", 0.0, 2.0),
    ...         (g, "grid_0_1_0", "t", "a", "zone", 1.0, 3.0),
    ...         (("zone", "z"), "z", "t", "a", "zone", 0.0, 1.0)]
    >>> [(r[1], r[5], r[6]) for r in _lane_bars(rows)]
    [('z', 0.0, 1.0), ('space grid', 0.0, 3.0)]
    """
    out: list[LaneRow] = []
    grid: dict[tuple[str, str, str], list[tuple[float, float]]] = {}
    for row in rows:
        key, _, task, arm, kind, s, e = row
        if not (np.isfinite(s) and np.isfinite(e)) or e <= s:
            continue
        if key[1] == GRID_LANE:
            grid.setdefault((task, arm, kind), []).append((s, e))
        else:
            out.append(row)
    merged: list[LaneRow] = []
    for (task, arm, kind), spans in grid.items():
        spans.sort()
        lo, hi = spans[0]
        for s, e in spans[1:]:
            if s > hi:
                merged.append((("zone", GRID_LANE), GRID_LANE, task, arm, kind, lo, hi))
                lo, hi = s, e
            else:
                hi = max(hi, e)
        merged.append((("zone", GRID_LANE), GRID_LANE, task, arm, kind, lo, hi))
    merged.sort(key=lambda r: (r[5], r[6], r[2]))
    return out + merged


def _frame_rows(df: Any) -> Iterator[LaneRow]:
    """The rows of a reservations frame as :data:`LaneRow` (a task of ``None``:
    an arm's start-zone stay, ``"start"``)."""
    for row in df.itertuples(index=False):
        task = row.task if isinstance(row.task, str) else "start"
        yield (
            _lane_of(str(row.kind), str(row.resource)),
            str(row.resource),
            task,
            str(row.arm),
            str(row.kind),
            float(row.start),
            float(row.end),
        )


# ------------------------------------------------------------------ gantt


def _problem(problem: Any) -> Problem:
    """The problem of a Problem or a CompiledCell."""
    if hasattr(problem, "arm_names") and hasattr(problem, "task_names"):
        return problem  # type: ignore[no-any-return]
    inner = getattr(problem, "problem", None)
    if inner is not None and hasattr(inner, "task_names"):
        return inner  # type: ignore[no-any-return]
    raise ValidationError(f"expected a Problem or a CompiledCell, not {type(problem).__name__}")


PLANNED_SHADE = 0.45
"""How much of its arm's colour a planned bar keeps (an executed bar keeps
all of it): the plan is the light shade, what ran the dark one."""


def _shade(colour: Any, keep: float) -> tuple[float, float, float, float]:
    """``colour`` mixed with white, keeping ``keep`` of it (opaque: what lies
    beneath never shows through)."""
    from matplotlib.colors import to_rgb

    r, g, b = to_rgb(colour)
    return (1 - keep * (1 - r), 1 - keep * (1 - g), 1 - keep * (1 - b), 1.0)


def _edge(colour: Any) -> tuple[float, float, float, float]:
    """A dark shade of ``colour``: the edge line that separates consecutive bars."""
    from matplotlib.colors import to_rgb

    r, g, b = to_rgb(colour)
    return (0.45 * r, 0.45 * g, 0.45 * b, 1.0)


EDGE_WIDTH = 0.8
"""Points: the edge line of every task bar (consecutive tasks of one arm
never merge into one bar)."""


def _bar(
    ax: Axes,
    y: float,
    start: float,
    end: float,
    height: float,
    gid: str,
    **style: Any,
) -> Rectangle:
    """A bar from ``start`` to ``end`` at ``y`` (its lower edge) with ``gid``: what
    ``ax.barh(..., align="edge")`` draws, without its cost per call (most of it
    the patch's data limits, here one corner update; a chart has thousands of
    bars). Axes that leave a limit to autoscaling call ``ax.autoscale_view()``
    once the bars are in."""
    from matplotlib.patches import Rectangle

    rect = Rectangle((start, y), end - start, height, gid=gid, **style)
    rect.sticky_edges.x.append(start)  # as barh: no margin left of a bar's start
    ax.add_artist(rect)  # in ax.patches (a view of the children by type)
    ax.update_datalim(((start, y), (end, y + height)))
    return rect


def _task_bar(
    ax: Axes, y: float, start: float, end: float, height: float, gid: str, colour: Any, keep: float
) -> Rectangle:
    """A task's bar in its arm's colour (shade ``keep``), edged, with its name if it fits."""
    from matplotlib.colors import to_rgb

    from workcell.viz.barlabel import BarLabel

    face = _shade(colour, keep)
    rect = _bar(
        ax,
        y,
        start,
        end,
        height,
        gid,
        facecolor=face,
        edgecolor=_edge(colour),
        linewidth=EDGE_WIDTH,
    )
    r, g, b = to_rgb(face)
    ink = "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.45 else "white"
    name = gid.split(":", 1)[1]
    ax.add_artist(BarLabel(rect, name, color=ink, gid=f"label:{gid}"))
    return rect


def _lane_label(key: tuple[str, str], n_blocks: int) -> str:
    kind, name = key
    if kind == "zone" and name == GRID_LANE:
        return grid_lane_label(n_blocks)
    return name if kind in ("arm", "cell") else f"{kind} {name}"


CELL_LANE = "whole cell"
"""The lane of a run's faults that concern no one arm (emergency stop, late
part, zone activation)."""


def _faults(trace: Any) -> list[tuple[str, str | None, float, float]]:
    """(kind, arm or None, time, end) of every fault of a run's trace; ``end``
    is the end of an emergency stop (else ``time``)."""
    out: list[tuple[str, str | None, float, float]] = []
    if trace is None:
        return out
    events = list(trace)
    for i, ev in enumerate(events):
        kind = fault_kind(ev)
        if kind is None:
            continue
        end = float(ev.time)
        if kind == "emergency_stop":
            end = next(
                (
                    float(e.time)
                    for e in events[i + 1 :]
                    if e.kind == "fault" and str(e.detail).startswith("emergency stop cleared")
                ),
                end,
            )
        arm = ev.arm if kind not in ("emergency_stop", "late_part", "zone_activation") else None
        out.append((kind, str(arm) if arm else None, float(ev.time), end))
    return out


def gantt(
    problem: Problem | CompiledCell,
    schedule: Schedule,
    executed: Any = None,
    *,
    ax: Axes | None = None,
    lanes: bool = True,
    title: str | None = None,
) -> Figure:
    """A Gantt chart of a plan, and of what ran when ``executed`` is given.

    Lanes, top to bottom: with a run whose faults concern no one arm, a
    ``whole cell`` lane; one lane per arm (its tasks); then -- with
    ``lanes`` -- one per SDL zone of the problem (exclusive occupancy,
    movement in a shared zone and an arm's start-zone stay, from
    :meth:`scheduler.Schedule.reservations`), one lane ``space grid (N
    blocks)`` for all the compile's space-grid zones
    (:mod:`workcell.viz.waits` gives their coordinates), and one per tool.

    Every bar has its arm's colour (:func:`workcell.style.arm_colours`,
    the same in every plot of the run) and a dark edge line, so consecutive
    tasks of one arm never merge; task bars carry the task's name where it
    fits (:class:`workcell.viz.barlabel.BarLabel`). Waits at zone borders are
    hatched inside the planned bars. With ``executed``, each lane is split:
    the plan on top in a light shade, what ran beneath in the full colour,
    failed tasks red and hatched; each fault of the run is a mark of its
    kind (:data:`workcell.style.FAULT_MARKS`) on its arm's lane (or the
    ``whole cell`` lane), an emergency stop also shades the time every arm
    stood. A dashed line marks the planned makespan, a dotted one the
    executed makespan. The legend names every colour, shade, hatch, mark
    and line drawn.

    Parameters
    ----------
    problem : scheduler.Problem or CompiledCell
    schedule : scheduler.Schedule
        The plan.
    executed : DataFrame or Schedule or simulation result, optional
        What ran: a tasks table with columns ``task, arm, start, end`` (and
        optionally ``status``, ``"done"`` or ``"failed"``) such as
        ``SimResult.tasks_frame()``, a :class:`~scheduler.Schedule`, or an
        object with ``tasks_frame()`` (and ``reservations_frame()``, whose
        zone and tool use then fills the lower half of those lanes, and
        ``trace``, whose faults are marked). A failed task that never
        started is drawn at its planned time on its planned arm.
    ax : matplotlib Axes, optional
        Draw there (else a new figure).
    lanes : bool
        Draw the zone and tool lanes.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Bars carry a ``gid`` (see the module docstring); task names are
        :class:`~workcell.viz.barlabel.BarLabel` texts with ``gid``
        ``"label:"`` and their bar's; fault marks are lines with ``gid``
        ``"fault:KIND:ARM"`` (``"fault:KIND:cell"`` on the whole-cell lane),
        the makespan lines ``"makespan:planned"`` and
        ``"makespan:executed"``, an emergency stop's shade
        ``"emergency_stop"``.
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    problem = _problem(problem)
    split = executed is not None
    trace: Any = getattr(executed, "trace", None) if split else None
    faults = _faults(trace)
    colours = arm_colours(problem.arm_names)
    lane_keys: list[tuple[str, str]] = []
    if any(arm is None or arm not in colours for _, arm, _, _ in faults):
        lane_keys.append(("cell", CELL_LANE))
    lane_keys += [("arm", a) for a in problem.arm_names]
    if lanes:
        lane_keys += list(dict.fromkeys(_lane_of("zone", z) for z in problem.zone_names))
        lane_keys += [("tool", k) for k in problem.tool_names]
    n_blocks = sum(grid_block(z) is not None for z in problem.zone_names)
    fig, ax = _figure(ax, (11, 1.6 + 0.34 * len(lane_keys) * (1.5 if split else 1.0)))
    y_of = {key: -i for i, key in enumerate(lane_keys)}
    h = 0.4 if split else 0.8
    plan_keep = PLANNED_SHADE if split else 0.75

    def top(key: tuple[str, str]) -> float:
        return y_of[key] + (0.0 if split else -0.4)

    def bottom(key: tuple[str, str]) -> float:
        return y_of[key] - 0.4

    arms = schedule.arms(problem)
    n_waits = 0
    for t in range(schedule.n_tasks):
        arm = problem.arm_names[int(arms[t])]
        s, e = float(schedule.start[t]), float(schedule.end[t])
        name = problem.task_names[t]
        _task_bar(ax, top(("arm", arm)), s, e, h, f"planned:{name}", colours[arm], plan_keep)
        sh = problem.shapes[int(schedule.mode[t])]
        w = schedule.waits[t]
        for b, wait in zip(sh.borders, w.tolist(), strict=True):
            if wait > 0:
                n_waits += 1
                ws = s + b + sh.shift(w, b, False)
                _bar(
                    ax,
                    top(("arm", arm)),
                    ws,
                    ws + wait,
                    h,
                    f"wait:{name}",
                    facecolor="white",
                    edgecolor=_edge(colours[arm]),
                    hatch="///",
                    linewidth=0.5,
                )
    if lanes:
        planned: Iterator[LaneRow] = (
            (
                _lane_of(r.kind, r.resource),
                r.resource,
                r.task or "start",
                r.arm,
                r.kind,
                float(r.start),
                float(r.end),
            )
            for r in schedule.reservations(problem)
        )
        for key, resource, task, arm, _, s, e in _lane_bars(planned):
            if key in y_of:
                c = colours[arm]
                _bar(
                    ax,
                    top(key),
                    s,
                    e,
                    h,
                    f"{key[0]}:{resource}:{task}",
                    facecolor=_shade(c, plan_keep),
                    edgecolor=_edge(c),
                    linewidth=0.4,
                )
    ends = [float(schedule.makespan)]
    ax.axvline(
        schedule.makespan, color="black", linestyle="--", linewidth=1.0, gid="makespan:planned"
    )
    handles: list[Artist] = [
        Patch(facecolor=colours[a], edgecolor=_edge(colours[a]), label=f"arm {a}")
        for a in problem.arm_names
    ]
    handles.append(
        Patch(
            facecolor=_shade("grey", plan_keep),
            edgecolor="black",
            linewidth=EDGE_WIDTH,
            label="planned (light, top half)" if split else "planned task (its name where it fits)",
        )
    )
    if n_waits:
        handles.append(
            Patch(facecolor="white", edgecolor="black", hatch="///", label="wait at a zone border")
        )
    n_failed = 0
    executed_mk: float | None = None
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
                n_failed += 1
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
                    linewidth=EDGE_WIDTH,
                )
            else:
                _task_bar(
                    ax, bottom(("arm", arm)), s, e, h, f"executed:{row.task}", colours[arm], 1.0
                )
            ends.append(max(e, s))
        done_end = df.loc[df["status"] == "done", "end"]
        if len(done_end):
            executed_mk = float(done_end.max())
            ax.axvline(
                executed_mk, color="black", linestyle=":", linewidth=1.3, gid="makespan:executed"
            )
        if lanes and hasattr(executed, "reservations_frame"):
            for key, resource, task, arm, _, s, e in _lane_bars(
                _frame_rows(_reservations_frame(executed))
            ):
                if key in y_of:
                    ink: Any = colours.get(arm, "grey")
                    _bar(
                        ax,
                        bottom(key),
                        s,
                        e,
                        h,
                        f"{key[0]}:{resource}:{task}:executed",
                        facecolor=ink,
                        edgecolor=_edge(ink),
                        linewidth=0.4,
                    )
                    ends.append(e)
        handles.append(
            Patch(
                facecolor="grey",
                edgecolor="black",
                linewidth=EDGE_WIDTH,
                label="executed (full colour, bottom half)",
            )
        )
        if n_failed:
            handles.append(
                Patch(
                    facecolor="white",
                    edgecolor="red",
                    hatch="xx",
                    label="failed task (unstarted: where planned)",
                )
            )
        # faults: one mark per kind, every time of a kind on one lane in one line
        groups: dict[tuple[str, str], list[float]] = {}
        for kind, who, time, end in faults:
            on_arm = who is not None and ("arm", who) in y_of
            groups.setdefault((kind, str(who) if on_arm else "cell"), []).append(time)
            if kind == "emergency_stop" and end > time:
                ax.axvspan(time, end, color="red", alpha=0.12, linewidth=0, gid="emergency_stop")
            ends.append(end)
        for (kind, where), times in groups.items():
            mark = FAULT_MARKS[kind]
            lane = ("cell", CELL_LANE) if where == "cell" else ("arm", where)
            ax.plot(
                times,
                [y_of[lane]] * len(times),
                marker=mark.marker,
                markersize=mark.size,
                markerfacecolor="black",
                markeredgecolor="white",
                markeredgewidth=0.6,
                linestyle="none",
                gid=f"fault:{kind}:{where}",
            )
        for kind in [k for k in FAULT_MARKS if any(f[0] == k for f in faults)]:
            mark = FAULT_MARKS[kind]
            handles.append(
                Line2D(
                    [],
                    [],
                    marker=mark.marker,
                    markersize=mark.size,
                    markerfacecolor="black",
                    markeredgecolor="white",
                    linestyle="none",
                    label=mark.label,
                )
            )
        if any(k == "emergency_stop" and e > t for k, _, t, e in faults):
            handles.append(
                Patch(facecolor="red", alpha=0.12, label="emergency stop: every arm stands")
            )
    handles.append(
        Line2D(
            [],
            [],
            color="black",
            linestyle="--",
            label=f"planned makespan {schedule.makespan:.1f} s",
        )
    )
    if executed_mk is not None:
        handles.append(
            Line2D(
                [],
                [],
                color="black",
                linestyle=":",
                linewidth=1.3,
                label=f"executed makespan {executed_mk:.1f} s",
            )
        )
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7.5)
    ax.set_xlim(0.0, 1.01 * max(ends))
    ax.set_yticks([y_of[k] for k in lane_keys])
    ax.set_yticklabels([_lane_label(k, n_blocks) for k in lane_keys])
    ax.set_ylim(-len(lane_keys) + 0.45, 0.55)
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", linewidth=0.3)
    ax.set_title(
        title
        or (
            f"{problem.name}: planned (top of each lane) vs executed (below)"
            if split
            else f"{problem.name}: planned schedule"
        )
    )
    return fig


def zone_timeline(
    reservations: Any,
    *,
    arms: Any = None,
    ax: Axes | None = None,
    title: str | None = None,
    tools: bool = True,
) -> Figure:
    """Who holds which zone (and tool) when: one lane per zone, bars by arm.

    Parameters
    ----------
    reservations : DataFrame or iterable of Reservation or simulation result
        Rows ``kind, resource, arm, task, start, end`` (kind ``"zone"``,
        ``"move"``, ``"start"`` or ``"tool"``), as from
        ``SimResult.reservations_frame()`` or
        :meth:`scheduler.Schedule.reservations`; or an object with
        ``reservations_frame()``.
    arms : Problem, CompiledCell, or sequence of arm names, optional
        The arms in the problem's order, which fixes their colours
        (:func:`workcell.style.arm_colours`) and names the space grid's
        block count. Default: the run's ``problem`` when ``reservations``
        is a run, else the arms in order of appearance (colours then match
        the other plots only if that is the problem's order).
    ax : matplotlib Axes, optional
    title : str, optional
    tools : bool
        Draw tool lanes too.

    Returns
    -------
    matplotlib.figure.Figure
        Lanes in the order the resources first appear, zones before tools;
        all space-grid blocks in one lane ``space grid (N blocks)``.

    Examples
    --------
    >>> from scheduler.schedule import Reservation
    >>> fig = zone_timeline([Reservation("zone", "fixture", "t0", "a", 0.0, 2.0),
    ...                      Reservation("move", "belt", "t1", "b", 1.0, 3.0)])
    >>> [t.get_text() for t in fig.axes[0].get_yticklabels()]
    ['zone fixture', 'zone belt']
    """
    from matplotlib.patches import Patch

    source = arms if arms is not None else reservations
    problem = getattr(source, "problem", source)
    df = _reservations_frame(reservations)
    keys: list[tuple[str, str]] = []
    for row in df.itertuples(index=False):
        key = _lane_of(str(row.kind), str(row.resource))
        if key not in keys and (tools or key[0] != "tool"):
            keys.append(key)
    keys.sort(key=lambda k: k[0] == "tool")  # stable: zones first, in order of appearance
    if arms is not None or hasattr(problem, "arm_names"):
        order = list(arm_order(problem))
        order += [a for a in dict.fromkeys(str(a) for a in df["arm"]) if a not in order]
    else:
        order = list(dict.fromkeys(str(a) for a in df["arm"]))
    colours = arm_colours(order)
    if hasattr(problem, "zone_names"):
        n_blocks = sum(grid_block(z) is not None for z in problem.zone_names)
    else:
        n_blocks = len({str(r) for r in df["resource"] if grid_block(str(r)) is not None})
    fig, ax = _figure(ax, (11, 1.4 + 0.34 * max(len(keys), 1)))
    y_of = {k: -i for i, k in enumerate(keys)}
    used: set[str] = set()
    moves = False
    for key, resource, task, arm, kind, s, e in _lane_bars(_frame_rows(df)):
        if key not in y_of:
            continue
        c = colours[arm]
        move = kind == "move"
        moves |= move
        used.add(arm)
        _bar(
            ax,
            y_of[key] - 0.4,
            s,
            e,
            0.8,
            f"{key[0]}:{resource}:{task}",
            # movement in a shared zone is drawn lighter than exclusive occupancy
            facecolor=_shade(c, PLANNED_SHADE) if move else c,
            edgecolor=_edge(c),
            linewidth=0.4,
        )
    handles: list[Artist] = [
        Patch(facecolor=colours[a], edgecolor=_edge(colours[a]), label=f"arm {a}")
        for a in order
        if a in used
    ]
    if moves:
        handles.append(
            Patch(
                facecolor=_shade("grey", PLANNED_SHADE),
                edgecolor="black",
                label="light: moving in a shared zone",
            )
        )
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=8)
    ax.autoscale_view()  # the bars' data limits (see _bar), before the left limit is fixed
    ax.set_xlim(left=0.0)
    ax.set_yticks([y_of[k] for k in keys])
    ax.set_yticklabels([_lane_label(k, n_blocks) for k in keys])
    ax.set_ylim(-len(keys) + 0.45, 0.55)
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", linewidth=0.3)
    ax.set_title(
        title or "zone occupancy (full colour: exclusive use; light: moving in a shared zone)"
    )
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


def _cell_meshes(cell: Cell, joints: Mapping[str, Sequence[float]]) -> list[tuple[str, Any]]:
    """(scene node name, mesh in world frame) of every zone solid and arm shape."""
    from workcell.viz.scene import cell_scene

    scene = cell_scene(cell, joints)
    out = []
    for node in scene.graph.nodes_geometry:
        tf, gname = scene.graph[node]
        mesh = scene.geometry[gname].copy()
        mesh.apply_transform(tf)
        out.append((str(node), mesh))
    return out


def _cell_bounds(cell: Cell, meshes: Sequence[tuple[str, Any]]) -> tuple[FloatArray, FloatArray]:
    """Lower and upper corner holding the cell's zones and every drawn solid, with a margin."""
    lo, hi = (np.asarray(b, dtype=float) for b in cell.zone_map.bounds)
    for _, mesh in meshes:
        lo = np.minimum(lo, mesh.vertices.min(axis=0))
        hi = np.maximum(hi, mesh.vertices.max(axis=0))
    pad = 0.04 * float(np.max(hi - lo)) + 1e-3
    return lo - pad, hi + pad


ZONE_COLOURS = {"exclusive": (0.86, 0.31, 0.24, 0.22), "shared": (0.24, 0.47, 0.86, 0.22)}
"""RGBA of an exclusive and a shared zone in the cell pictures (translucent)."""


def _draw_cell(
    ax: Axes,
    cell: Cell,
    joints: Mapping[str, Sequence[float]],
    meshes: Sequence[tuple[str, Any]],
    view: str,
    title: str,
    colours: Mapping[str, Any],
    bounds: tuple[FloatArray, FloatArray],
) -> None:
    """The cell at ``joints`` (``meshes``, from :func:`_cell_meshes`): zones
    translucent (red exclusive, blue shared) and labelled, arms in their
    colours and labelled, axes in metres, limits ``bounds``."""
    from scipy.spatial import ConvexHull, QhullError

    lo, hi = bounds
    zm = cell.zone_map
    policy = {
        n: "exclusive" if bool(e) else "shared"
        for n, e in zip(zm.zone_names(), zm.exclusive_mask(), strict=True)
    }
    zone_box: dict[str, tuple[FloatArray, FloatArray]] = {}
    for node, mesh in meshes:
        if node.startswith("zone:"):
            name = node.split(":")[1]
            a, b = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
            old = zone_box.get(name)
            zone_box[name] = (
                (a, b) if old is None else (np.minimum(old[0], a), np.maximum(old[1], b))
            )
    if view == "3d":
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # type: ignore[import-untyped]

        ax3: Any = ax  # an Axes3D
        for node, mesh in meshes:
            if node.startswith("zone:"):
                face: Any = ZONE_COLOURS[policy[node.split(":")[1]]]
            else:
                face = colours[node.split(":")[0]]
            ax.add_collection3d(  # type: ignore[attr-defined]
                Poly3DCollection(mesh.triangles, facecolor=face, edgecolor="none", gid=node)
            )
        for name, (a, b) in zone_box.items():
            c = 0.5 * (a + b)
            ax3.text(c[0], c[1], b[2], name, fontsize=6.5, ha="center", gid=f"zonelabel:{name}")
        for arm in cell.arms:
            x, y, z = arm.fk(np.asarray(joints[arm.name], dtype=float)[None])[0, :3, 3]
            ax3.text(x, y, z, arm.name, fontsize=7.5, weight="bold", gid=f"armlabel:{arm.name}")
        ax.set_zlim(lo[2], hi[2])  # type: ignore[attr-defined]
        ax.set_zlabel("z (m)")  # type: ignore[attr-defined]
    else:
        from matplotlib.patches import Polygon

        for node, mesh in meshes:
            xy = mesh.vertices[:, :2]
            try:
                hull = xy[ConvexHull(xy).vertices]
            except QhullError:  # a flat outline: its bounding box
                (x0, y0), (x1, y1) = xy.min(0), xy.max(0)
                hull = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
            if node.startswith("zone:"):
                zc = ZONE_COLOURS[policy[node.split(":")[1]]]
                patch = Polygon(hull, closed=True, facecolor=zc, edgecolor=zc[:3], linewidth=0.6)
            else:
                c = colours[node.split(":")[0]]
                patch = Polygon(hull, closed=True, facecolor=c, edgecolor=_edge(c), linewidth=0.5)
            patch.set_gid(node)
            ax.add_patch(patch)
        for name, (a, b) in zone_box.items():
            ax.annotate(
                name,
                (0.5 * (a[0] + b[0]), b[1]),
                xytext=(0, -2),
                textcoords="offset points",
                ha="center",
                va="top",
                fontsize=6.5,
                color=(0.25, 0.25, 0.25),
                gid=f"zonelabel:{name}",
                annotation_clip=True,
            )
        for arm in cell.arms:
            x, y = arm.fk(np.asarray(joints[arm.name], dtype=float)[None])[0, :2, 3]
            ax.annotate(
                arm.name,
                (x, y),
                xytext=(3, 3),
                textcoords="offset points",
                fontsize=7.5,
                weight="bold",
                color=_edge(colours[arm.name]),
                gid=f"armlabel:{arm.name}",
            )
        ax.set_aspect("equal")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title, fontsize=9)


def _cell_legend(fig: Figure, cell: Cell, colours: Mapping[str, Any]) -> None:
    """One legend for the figure: the arms' colours and the zones' shades."""
    from matplotlib.patches import Patch

    zm = cell.zone_map
    kinds = {"exclusive" if bool(e) else "shared" for e in zm.exclusive_mask()}
    handles = [Patch(facecolor=c, edgecolor=_edge(c), label=f"arm {a}") for a, c in colours.items()]
    handles += [
        Patch(facecolor=ZONE_COLOURS[k], edgecolor=ZONE_COLOURS[k][:3], label=f"{k} zone")
        for k in ("exclusive", "shared")
        if k in kinds
    ]
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 6), fontsize=8)


def _union(boxes: Sequence[tuple[FloatArray, FloatArray]]) -> tuple[FloatArray, FloatArray]:
    """One box holding ``boxes`` (panels of one figure share their limits)."""
    return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


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
        One Axes per instant, titled with its time, axes in metres; arms in
        their colours (:func:`workcell.style.arm_colours`) and
        labelled, zones translucent (red: exclusive, blue: shared) and
        labelled; every panel's limits hold every zone and every link at
        every instant drawn (nothing clipped), and one legend below the
        panels names the arms' colours and the zones' shades. Patches carry
        their scene node's name as ``gid`` (``"ARM:SHAPE"``,
        ``"zone:ZONE:K"``), zone and arm names are texts with ``gid``
        ``"zonelabel:ZONE"`` and ``"armlabel:ARM"``.
    """
    from matplotlib.figure import Figure

    if view not in ("top", "3d"):
        raise ValidationError(f"view must be 'top' or '3d', not {view!r}")
    ts = np.asarray(times, dtype=float).reshape(-1)
    if len(ts) == 0:
        raise ValidationError("render_instants needs at least one time")
    if ncols is not None and ncols < 1:
        raise ValidationError(f"ncols must be >= 1, got {ncols}")
    cc = _compiled(cell_or_compiled, result_or_schedule)
    joints = arm_joints(cc, result_or_schedule, ts)
    colours = arm_colours(cc.problem.arm_names)
    n = len(ts)
    cols = ncols or min(n, 4)
    rows = -(-n // cols)
    poses = [{name: q[i] for name, q in joints.items()} for i in range(n)]
    meshes = [_cell_meshes(cc.cell, at) for at in poses]
    bounds = _union([_cell_bounds(cc.cell, m) for m in meshes])
    fig = Figure(figsize=(3.8 * cols, 3.4 * rows + 0.5), layout="constrained")
    for i, t in enumerate(ts.tolist()):
        kw = {"projection": "3d"} if view == "3d" else {}
        ax = fig.add_subplot(rows, cols, i + 1, **kw)
        title = f"{cc.cell.name} at t = {t:.1f} s"
        _draw_cell(ax, cc.cell, poses[i], meshes[i], view, title, colours, bounds)
    _cell_legend(fig, cc.cell, colours)
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

    PNG frames (``frame_0000.png``, ...) drawn like :func:`render_instants`
    (the same arm colours, and the same limits in every frame, holding every
    zone and link of the whole sequence), or with ``glb`` one GLB scene per
    frame (``frame_0000.glb``, ...; trimesh writes no animation channels, so
    an animated GLB is left to tools that join frames).

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
    poses = [{name: q[i] for name, q in joints.items()} for i in range(len(ts))]
    if glb:
        return [
            export_glb(cc.cell, out_dir / f"frame_{i:04d}.glb", at) for i, at in enumerate(poses)
        ]
    from matplotlib.figure import Figure

    colours = arm_colours(cc.problem.arm_names)
    meshes = [_cell_meshes(cc.cell, at) for at in poses]
    bounds = _union([_cell_bounds(cc.cell, m) for m in meshes]) if meshes else None
    paths: list[Path] = []
    if bounds is None:  # no frame asked for
        return paths
    for i, t in enumerate(ts.tolist()):
        fig = Figure(figsize=(6, 5.4), layout="constrained")
        ax = fig.add_subplot(**({"projection": "3d"} if view == "3d" else {}))
        title = f"{cc.cell.name} at t = {t:.2f} s"
        _draw_cell(ax, cc.cell, poses[i], meshes[i], view, title, colours, bounds)
        _cell_legend(fig, cc.cell, colours)
        path = out_dir / f"frame_{i:04d}.png"
        fig.savefig(path, dpi=90)
        paths.append(path)
    return paths


# ----------------------------------------------------------------- joints

JOINT_UNITS = {"prismatic": "position (m)", "revolute": "angle (rad)"}
"""Axis label of each kind of joint in :func:`joint_timeline`."""


def joint_timeline(
    compiled: CompiledCell,
    plan: Any,
    *,
    times: Sequence[float] | FloatArray | None = None,
    n_samples: int = 400,
) -> Figure:
    """Every arm's joints against time under a plan or a run (:func:`arm_joints`).

    One row of panels per arm, one column per kind of joint (prismatic
    joints in metres, revolute joints in radians); an arm's curves have its
    colour (:func:`workcell.style.arm_colours`) and one line style per
    joint, named in the panel's legend.

    Parameters
    ----------
    compiled : CompiledCell
    plan : scheduler.Schedule or simulation result
        As for :func:`arm_joints`.
    times : sequence of float, seconds, optional
        Default ``n_samples`` evenly spaced from 0 to the last task's end.
    n_samples : int

    Returns
    -------
    matplotlib.figure.Figure
        Curves are lines with ``gid`` ``"joint:ARM:JOINT"``.
    """
    from matplotlib.figure import Figure

    cc = compiled
    if times is None:
        if n_samples < 2:
            raise ValidationError(f"n_samples must be >= 2, got {n_samples}")
        end = max((e for _, _, _, e, _ in _rows(cc, plan)), default=0.0)
        ts = np.linspace(0.0, max(end, 1e-9), n_samples)
    else:
        ts = np.asarray(times, dtype=float).reshape(-1)
        if len(ts) == 0:
            raise ValidationError("joint_timeline needs at least one time")
    joints = arm_joints(cc, plan, ts)
    colours = arm_colours(cc.problem.arm_names)
    arms = list(cc.cell.arms)
    kinds = [k for k in ("prismatic", "revolute") if any(k in a.joint_kinds for a in arms)]
    fig = Figure(figsize=(5.5 * len(kinds), 1.9 * len(arms) + 0.6), layout="constrained")
    axes = fig.subplots(len(arms), len(kinds), sharex=True, squeeze=False)
    styles = ("-", "--", ":", "-.")
    for r, arm in enumerate(arms):
        q = joints[arm.name]
        for c, kind in enumerate(kinds):
            ax = axes[r][c]
            idx = [j for j, k in enumerate(arm.joint_kinds) if k == kind]
            for n, j in enumerate(idx):
                ax.plot(
                    ts,
                    q[:, j],
                    color=colours[arm.name],
                    linestyle=styles[n % len(styles)],
                    linewidth=1.2,
                    label=arm.joint_names[j],
                    gid=f"joint:{arm.name}:{arm.joint_names[j]}",
                )
            if idx:
                ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7)
            else:
                ax.text(
                    0.5, 0.5, f"no {kind} joint", ha="center", va="center", transform=ax.transAxes
                )
            ax.set_ylabel(f"{arm.name}\n{JOINT_UNITS[kind]}", fontsize=8)
            ax.grid(linewidth=0.3)
            if r == len(arms) - 1:
                ax.set_xlabel("time (s)")
    fig.suptitle(f"{cc.cell.name}: joints against time")
    return fig
