"""The procedural ("C-style") task API of SEEDS.md S2.10.

The paper describes robot-independent elementary tasks with a C library: a
task is opened, steps and prerequisites are added with plain function calls,
and the task is closed. This module is that interface. Handles are small
mutable builders; what they produce are the immutable records of
:mod:`tasklib.model`, validated step by step (a bad step fails at the call
that adds it) and as a whole when the task set is closed.

Examples
--------
>>> from tasklib import capi as c
>>> ts = c.taskset_open("demo")
>>> c.feeder_add(ts, "tray", ["pin"], position=(0.1, 0.5, 0.0))
>>> c.part_add(ts, "pin")
>>> c.tdl_add(ts, "trajectory to_tray { taught { stop (0.1, 0.5, 0.05) } }")
>>> t = c.task_open(ts, "pick_pin")
>>> c.task_consume(t, "pin")
>>> c.task_move(t, trajectory="to_tray")
>>> c.task_grasp(t, "pin")
>>> c.task_depart(t, 0.1)
>>> task = c.task_close(t)
>>> [s.kind for s in task.steps]
['move', 'grasp', 'depart']
>>> c.taskset_close(ts).summary()["tasks"]
1
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from os import PathLike
from typing import Literal, TypeAlias

from multiarm.errors import UsageError, ValidationError
from tasklib.arrivals import ArrivalModel, Feeder, FixedArrivals
from tasklib.model import Part, PartGroup, Task, TaskSet
from tasklib.pose import Pose
from tasklib.steps import (
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
    Step,
    UseTool,
    WaitFlag,
)
from tasklib.tdl import TDLDocument, load_tdl, parse_tdl

__all__ = [
    "PoseLike",
    "TaskHandle",
    "TaskSetHandle",
    "feeder_add",
    "group_add",
    "part_add",
    "task_actuate",
    "task_approach",
    "task_close",
    "task_consume",
    "task_depart",
    "task_detect",
    "task_dwell",
    "task_grasp",
    "task_insert",
    "task_move",
    "task_open",
    "task_produce",
    "task_release",
    "task_require",
    "task_set_flag",
    "task_use_tool",
    "task_wait_flag",
    "taskset_close",
    "taskset_open",
    "tdl_add",
    "tdl_load",
]

PoseLike: TypeAlias = Pose | Sequence[float]
"""A Pose, ``(x, y, z)`` (tool pointing down) or ``(x, y, z, qw, qx, qy, qz)``."""


def as_pose(value: PoseLike) -> Pose:
    """A Pose from a Pose, a 3-sequence or a 7-sequence.

    ``(x, y, z)`` means the tool points down at that position (orientation
    :data:`tasklib.DOWN`, the one every arm kind reaches);
    ``(x, y, z, qw, qx, qy, qz)`` gives the orientation as a unit
    quaternion; :func:`tasklib.pose` builds other orientations by name.
    """
    if isinstance(value, Pose):
        return value
    if isinstance(value, str | bytes) or not hasattr(value, "__iter__"):
        raise ValidationError(
            f"a pose is a Pose or 3 (x, y, z) or 7 (x, y, z, qw, qx, qy, qz) numbers, got {value!r}"
        )
    vals = tuple(value)
    if len(vals) == 3:
        return Pose((vals[0], vals[1], vals[2]))
    if len(vals) == 7:
        return Pose((vals[0], vals[1], vals[2]), (vals[3], vals[4], vals[5], vals[6]))
    raise ValidationError(
        f"a pose is 3 (x, y, z: tool pointing down) or 7 (x, y, z, qw, qx, qy, qz) numbers, "
        f"got {len(vals)}"
    )


@dataclass(eq=False)
class TaskSetHandle:
    """An open task set (returned by :func:`taskset_open`)."""

    name: str
    description: str = ""
    feeders: list[Feeder] = field(default_factory=list)
    parts: dict[str, tuple[tuple[str, ...], str]] = field(default_factory=dict)
    groups: dict[str, tuple[tuple[str, ...], str]] = field(default_factory=dict)
    tdl: TDLDocument = field(default_factory=TDLDocument)
    tasks: list[Task] = field(default_factory=list)
    owners: dict[str, tuple[str, str]] = field(default_factory=dict)
    open_tasks: dict[str, TaskHandle] = field(default_factory=dict)
    closed: bool = False

    def _check_open(self) -> None:
        if self.closed:
            raise UsageError(f"task set {self.name!r} is already closed")


@dataclass(eq=False)
class TaskHandle:
    """An open task (returned by :func:`task_open`)."""

    taskset: TaskSetHandle
    id: str
    capabilities: tuple[str, ...]
    tool: str | None
    description: str
    steps: list[Step] = field(default_factory=list)
    prerequisites: list[str] = field(default_factory=list)
    consumes: list[str] = field(default_factory=list)
    produces: list[str] = field(default_factory=list)
    closed: bool = False

    def _add(self, make: Callable[[], Step]) -> None:
        if self.closed:
            raise UsageError(f"task {self.id!r} is already closed")
        try:
            step = make()
        except ValidationError as exc:
            raise ValidationError(f"task {self.id!r} step {len(self.steps) + 1}: {exc}") from None
        self.steps.append(step)


# ----------------------------------------------------------------- task set


def taskset_open(name: str, description: str = "") -> TaskSetHandle:
    """Start describing a task set."""
    if not isinstance(name, str) or not name:
        raise ValidationError(f"task set name must be a non-empty name, got {name!r}")
    return TaskSetHandle(name, description)


def taskset_close(ts: TaskSetHandle) -> TaskSet:
    """Validate and return the task set; the handle cannot be used afterwards.

    Raises
    ------
    UsageError
        If a task is still open.
    ValidationError, CycleError
        See :class:`~tasklib.model.TaskSet`.
    """
    ts._check_open()
    if ts.open_tasks:
        raise UsageError(f"task {next(iter(ts.open_tasks))!r} is still open: close it first")
    part_tasks: dict[str, list[str]] = {p: [] for p in ts.parts}
    group_tasks: dict[str, list[str]] = {g: [] for g in ts.groups}
    for tid, (kind, owner) in ts.owners.items():
        table = part_tasks if kind == "part" else group_tasks
        if owner not in table:
            raise ValidationError(f"task {tid!r} belongs to unknown {kind} {owner!r}")
        table[owner].append(tid)
    parts = tuple(
        Part(pid, prereq, tuple(part_tasks[pid]), desc) for pid, (prereq, desc) in ts.parts.items()
    )
    groups = tuple(
        PartGroup(gid, members, tuple(group_tasks[gid]), desc)
        for gid, (members, desc) in ts.groups.items()
    )
    result = TaskSet(
        ts.name, tuple(ts.tasks), parts, tuple(ts.feeders), groups, ts.tdl, ts.description
    )
    ts.closed = True
    return result


def feeder_add(
    ts: TaskSetHandle,
    id: str,
    parts: Sequence[str],
    position: Sequence[float] = (0.0, 0.0, 0.0),
    arrival: ArrivalModel | None = None,
    position_sigma: float = 0.0,
) -> None:
    """Declare a feeder supplying ``parts`` (all at time 0 unless ``arrival`` says otherwise)."""
    ts._check_open()
    if any(f.id == id for f in ts.feeders):
        raise ValidationError(f"duplicate feeder id {id!r}")
    ts.feeders.append(
        Feeder(
            id,
            tuple(parts),
            as_pose(position).position,
            arrival if arrival is not None else FixedArrivals(()),
            position_sigma,
        )
    )


def part_add(
    ts: TaskSetHandle, id: str, prerequisites: Sequence[str] = (), description: str = ""
) -> None:
    """Declare a part; ``prerequisites`` are parts assembled before it (S2.11)."""
    ts._check_open()
    if id in ts.parts:
        raise ValidationError(f"duplicate part id {id!r}")
    Part(id, tuple(prerequisites), (), description)  # validate now
    ts.parts[id] = (tuple(prerequisites), description)


def group_add(ts: TaskSetHandle, id: str, parts: Sequence[str], description: str = "") -> None:
    """Declare a set of independent parts whose group tasks run once all are assembled."""
    ts._check_open()
    if id in ts.groups:
        raise ValidationError(f"duplicate part group id {id!r}")
    PartGroup(id, tuple(parts), (), description)
    ts.groups[id] = (tuple(parts), description)


def tdl_add(ts: TaskSetHandle, text: str, filename: str | None = None) -> None:
    """Parse TDL text and add its frames and trajectories."""
    ts._check_open()
    ts.tdl = ts.tdl.merge(parse_tdl(text, filename))


def tdl_load(ts: TaskSetHandle, path: str | PathLike[str]) -> None:
    """Load a ``.tdl`` file and add its frames and trajectories."""
    ts._check_open()
    ts.tdl = ts.tdl.merge(load_tdl(path))


# --------------------------------------------------------------------- task


def task_open(
    ts: TaskSetHandle,
    id: str,
    capabilities: Sequence[str] = (),
    tool: str | None = None,
    *,
    part: str | None = None,
    group: str | None = None,
    description: str = "",
) -> TaskHandle:
    """Open a task. ``part`` (or ``group``) makes it one of that part's
    (group's) tasks, as in the part-driven description of S2.11."""
    ts._check_open()
    if part is not None and group is not None:
        raise ValidationError(f"task {id!r} cannot belong to both a part and a group")
    if any(t.id == id for t in ts.tasks) or id in ts.open_tasks:
        raise ValidationError(f"duplicate task id {id!r}")
    if part is not None:
        ts.owners[id] = ("part", part)
    elif group is not None:
        ts.owners[id] = ("group", group)
    handle = TaskHandle(ts, id, tuple(capabilities), tool, description)
    ts.open_tasks[id] = handle
    return handle


def task_close(t: TaskHandle) -> Task:
    """Close the task, validate it and add it to its task set."""
    if t.closed:
        raise UsageError(f"task {t.id!r} is already closed")
    task = Task(
        t.id,
        tuple(t.steps),
        t.capabilities,
        t.tool,
        tuple(t.prerequisites),
        tuple(t.consumes),
        tuple(t.produces),
        t.description,
    )
    t.closed = True
    t.taskset.open_tasks.pop(t.id, None)
    t.taskset.tasks.append(task)
    return task


def _mutable(t: TaskHandle) -> None:
    if t.closed:
        raise UsageError(f"task {t.id!r} is already closed")


def task_require(t: TaskHandle, *task_ids: str) -> None:
    """Tasks that must finish before ``t`` starts."""
    _mutable(t)
    t.prerequisites.extend(task_ids)


def task_consume(t: TaskHandle, *parts: str) -> None:
    """Parts ``t`` needs (it waits for their arrival or their producer)."""
    _mutable(t)
    t.consumes.extend(parts)


def task_produce(t: TaskHandle, *parts: str) -> None:
    """Parts (sub-assemblies) ``t`` makes."""
    _mutable(t)
    t.produces.extend(parts)


def task_move(
    t: TaskHandle,
    target: PoseLike | None = None,
    trajectory: str | None = None,
    interpolation: Literal["linear", "axis"] = "axis",
    speed: float = 1.0,
) -> None:
    """Move to ``target`` or along TDL ``trajectory``."""
    t._add(
        lambda: Move(
            target=as_pose(target) if target is not None else None,
            trajectory=trajectory,
            interpolation=interpolation,
            speed=speed,
        )
    )


def task_approach(
    t: TaskHandle, target: PoseLike, distance: float = 0.05, speed: float = 0.25
) -> None:
    """Come down onto ``target`` along its tool axis."""
    t._add(lambda: Approach(target=as_pose(target), distance=distance, speed=speed))


def task_depart(t: TaskHandle, distance: float = 0.05, speed: float = 0.5) -> None:
    """Back off along the tool axis."""
    t._add(lambda: Depart(distance=distance, speed=speed))


def task_grasp(t: TaskHandle, part: str | None = None, duration: float = 0.3) -> None:
    """Close the gripper."""
    t._add(lambda: Grasp(part=part, duration=duration))


def task_release(t: TaskHandle, part: str | None = None, duration: float = 0.2) -> None:
    """Open the gripper."""
    t._add(lambda: Release(part=part, duration=duration))


def task_insert(
    t: TaskHandle,
    part: str,
    target: PoseLike,
    depth: float = 0.01,
    speed: float = 0.05,
    *,
    max_tries: int = 9,
    step: float = 0.0005,
    pattern: Literal["spiral", "grid"] = "spiral",
    threshold: float = 20.0,
    try_time: float = 0.4,
) -> None:
    """Insert under force control with a search at offsets (S1.7)."""
    _mutable(t)
    try:
        search = ForceSearch(max_tries, step, pattern, threshold, try_time)
    except ValidationError as exc:
        raise ValidationError(f"task {t.id!r} step {len(t.steps) + 1}: {exc}") from None
    t._add(
        lambda: Insert(part=part, target=as_pose(target), depth=depth, speed=speed, search=search)
    )


def task_use_tool(t: TaskHandle, tool: str, duration: float) -> None:
    """Operate ``tool``; the first use declares the task's tool when none was given."""
    _mutable(t)
    if t.tool is None:
        t.tool = tool
    t._add(lambda: UseTool(tool=tool, duration=duration))


def task_actuate(t: TaskHandle, device: str, command: str = "on", duration: float = 0.0) -> None:
    """Command a non-robot device."""
    t._add(lambda: Actuate(device=device, command=command, duration=duration))


def task_detect(
    t: TaskHandle,
    start: PoseLike,
    end: PoseLike,
    mode: Literal["search", "measure"] = "search",
    speed: float = 0.2,
    part: str | None = None,
) -> None:
    """Scan with the object detector from ``start`` to ``end`` (S1.8)."""
    t._add(
        lambda: Detect(start=as_pose(start), end=as_pose(end), mode=mode, speed=speed, part=part)
    )


def task_set_flag(t: TaskHandle, flag: str) -> None:
    """Raise a synchronisation flag (S1.9)."""
    t._add(lambda: SetFlag(flag=flag))


def task_wait_flag(t: TaskHandle, flag: str, timeout: float | None = None) -> None:
    """Wait for a synchronisation flag (S1.9)."""
    t._add(lambda: WaitFlag(flag=flag, timeout=timeout))


def task_dwell(t: TaskHandle, duration: float) -> None:
    """Stay still for ``duration`` seconds."""
    t._add(lambda: Dwell(duration=duration))
