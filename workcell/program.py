"""A task's steps as a robot-independent motion program in the cell frame.

The first stage of compiling a task for an arm (DESIGN.md data flow, step
2): every step of a :class:`tasklib.Task` becomes Cartesian moves through
tool-flange poses (4x4, cell frame) and dwells, independent of any arm. The
arm-specific stage (:mod:`workcell.compile`) then solves the inverse
kinematics along the moves and times them with the arm's drives.

Step rules (SEEDS.md S1.7-S1.9, S2.10):

``move``
    To a target pose, or through the points of a TDL trajectory (each
    point's own interpolation and speed; a point without an orientation
    keeps the previous one, the first such point that of the previous step,
    or :data:`TOOL_DOWN`). ``axis`` interpolation moves every
    joint on its own (the cheap move of a Cartesian robot, S1.9); ``linear``
    follows the straight line in Cartesian space.
``approach`` / ``depart``
    A straight move along the tool axis onto the target from ``distance``
    away, first moving (per axis) to the point ``distance`` back along the
    tool axis; ``depart`` backs off by ``distance``.
``grasp``, ``release``, ``use_tool``, ``actuate``, ``dwell``
    Dwells of the step's duration at the current pose.
``insert``
    A straight move onto the target, then the force-guided search (S1.7):
    ``try_time`` per try, one try planned with ``"nominal"``, all
    ``max_tries`` with ``"worst"``; the lateral offsets (fractions of a
    millimetre) stay within the sweep padding and are not moved explicitly.
``detect`` (S1.8)
    A move to the line's start, then a straight scan to its end at the
    step's speed: a ``measure`` scan always runs the whole line; a
    ``search`` stops at the part, planned at half the line with
    ``"nominal"`` and the whole line with ``"worst"``.
``set_flag`` / ``wait_flag`` (S1.9)
    No motion: markers at their place in the program.

Examples
--------
>>> from tasklib.examples import load_example
>>> ts = load_example("supersigma")
>>> prog = expand_task(ts.task("insert_pin"), ts.trajectories)
>>> [s.label for s in prog.segments][:4]
['move', 'approach', 'approach', 'grasp']
>>> expand_task(ts.task("insert_pin"), ts.trajectories, "worst").dwell_time() > prog.dwell_time()
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, Transform
from tasklib.model import Task
from tasklib.pose import Pose, quat_to_matrix
from tasklib.steps import (
    Actuate,
    Approach,
    Depart,
    Detect,
    Dwell,
    Grasp,
    Insert,
    Move,
    Release,
    SetFlag,
    UseTool,
    WaitFlag,
)
from tasklib.tdl import TDLDocument

__all__ = ["Program", "ProgramSegment", "expand_task"]

Interp = Literal["axis", "linear"]


@dataclass(frozen=True, slots=True)
class ProgramSegment:
    """One piece of a motion program.

    Attributes
    ----------
    kind : {"move", "dwell"}
    target : (4, 4) float or None
        Flange pose at the end of a move (cell frame); None for a dwell.
    interpolation : {"axis", "linear"}
    speed : float
        Fraction (0, 1] of the arm's top speed.
    duration : float
        Seconds of a dwell (0 for a move: the arm's timing decides).
    label : str
        The step kind that made it (``"grasp"``, ``"insert"``, ...).
    step : int
        The step's number in the task (1-based).
    """

    kind: Literal["move", "dwell"]
    target: Transform | None
    interpolation: Interp
    speed: float
    duration: float
    label: str
    step: int


@dataclass(frozen=True, slots=True)
class Program:
    """A task's motion program.

    Attributes
    ----------
    task : str
    segments : tuple of ProgramSegment
    flags_set, flags_waited : tuple of (flag, segment index)
        Each flag marker and the index of the first segment after it.
    """

    task: str
    segments: tuple[ProgramSegment, ...]
    flags_set: tuple[tuple[str, int], ...]
    flags_waited: tuple[tuple[str, int], ...]

    def dwell_time(self) -> float:
        """Seconds of dwells in the program (motion excluded)."""
        return float(sum(s.duration for s in self.segments if s.kind == "dwell"))

    def targets(self) -> FloatArray:
        """(K, 4, 4) float: the move targets in order."""
        ts = [s.target for s in self.segments if s.target is not None]
        return np.stack(ts) if ts else np.zeros((0, 4, 4))


TOOL_DOWN: Transform = np.diag([1.0, -1.0, -1.0, 1.0])
"""Flange pose of a tool pointing down (a half turn about x): the orientation a
trajectory's first point takes when neither it nor an earlier step gives one."""


def _pose(p: Pose) -> Transform:
    return p.matrix()


def _along_tool(pose: Transform, distance: float) -> Transform:
    """``pose`` moved by ``distance`` along its own tool (z) axis."""
    out = pose.copy()
    out[:3, 3] = pose[:3, 3] + distance * pose[:3, 2]
    return out


def expand_task(
    task: Task, trajectories: TDLDocument, plan_with: Literal["nominal", "worst"] = "nominal"
) -> Program:
    """The motion program of ``task`` (see the module docstring for the rules).

    Parameters
    ----------
    task : tasklib.Task
    trajectories : tasklib.tdl.TDLDocument
        Where named trajectories are resolved.
    plan_with : {"nominal", "worst"}
        Nominal (one insertion try, half a search scan) or worst-case times.

    Returns
    -------
    Program

    Raises
    ------
    ValidationError
        A relative step (``depart``, ``approach``'s current pose) comes
        before any pose is known.
    """
    segs: list[ProgramSegment] = []
    sets: list[tuple[str, int]] = []
    waits: list[tuple[str, int]] = []
    current: Transform | None = None
    worst = plan_with == "worst"

    def move(target: Transform, interp: Interp, speed: float, label: str, i: int) -> None:
        nonlocal current
        segs.append(ProgramSegment("move", target, interp, speed, 0.0, label, i))
        current = target

    def dwell(seconds: float, label: str, i: int) -> None:
        if seconds > 0:
            segs.append(ProgramSegment("dwell", None, "axis", 1.0, float(seconds), label, i))

    for i, step in enumerate(task.steps, start=1):
        if isinstance(step, Move):
            if step.target is not None:
                move(_pose(step.target), step.interpolation, step.speed, "move", i)
            else:
                traj = trajectories.trajectory(str(step.trajectory))
                frame = trajectories.frame_matrix(traj.frame)
                for seg, wp in traj.waypoints():
                    t = np.eye(4)
                    if wp.orientation is not None:
                        t[:3, :3] = frame[:3, :3] @ quat_to_matrix(wp.orientation)
                    else:
                        t[:3, :3] = TOOL_DOWN[:3, :3] if current is None else current[:3, :3]
                    t[:3, 3] = frame[:3, :3] @ np.asarray(wp.position) + frame[:3, 3]
                    interp: Interp = "linear" if seg.interpolation == "linear" else "axis"
                    speed = wp.speed or seg.speed or traj.speed or 1.0
                    move(t, interp, float(min(1.0, speed * step.speed)), "move", i)
        elif isinstance(step, Approach):
            goal = _pose(step.target)
            move(_along_tool(goal, -step.distance), "axis", 1.0, "approach", i)
            move(goal, "linear", step.speed, "approach", i)
        elif isinstance(step, Depart):
            if current is None:
                raise ValidationError(f"task {task.id!r} step {i}: depart before any pose is known")
            move(_along_tool(current, -step.distance), "linear", step.speed, "depart", i)
        elif isinstance(step, Insert):
            goal = _pose(step.target)
            move(_along_tool(goal, -step.depth), "axis", 1.0, "insert", i)
            move(goal, "linear", step.speed, "insert", i)
            tries = step.search.max_tries if worst else 1
            dwell(tries * step.search.try_time, "insert", i)
        elif isinstance(step, Detect):
            a, b = _pose(step.start), _pose(step.end)
            move(a, "axis", 1.0, "detect", i)
            if step.mode == "search" and not worst:
                b = b.copy()
                b[:3, 3] = (a[:3, 3] + b[:3, 3]) / 2
            move(b, "linear", step.speed, "detect", i)
        elif isinstance(step, Grasp | Release):
            dwell(step.duration, step.kind, i)
        elif isinstance(step, UseTool):
            dwell(step.duration, "use_tool", i)
        elif isinstance(step, Actuate):
            dwell(step.duration, "actuate", i)
        elif isinstance(step, Dwell):
            dwell(step.duration, "dwell", i)
        elif isinstance(step, SetFlag):
            sets.append((step.flag, len(segs)))
        elif isinstance(step, WaitFlag):
            waits.append((step.flag, len(segs)))
        else:  # pragma: no cover - every step kind is handled above
            raise ValidationError(f"task {task.id!r} step {i}: unknown step {step!r}")
    return Program(task.id, tuple(segs), tuple(sets), tuple(waits))
