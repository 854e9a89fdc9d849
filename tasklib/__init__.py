"""tasklib: robot-independent elementary tasks (SEEDS.md S2.10, S2.11, S1.7-S1.9).

The programming layer's task library. It describes *what* an assembly needs
done, never *which arm* does it:

* records: :class:`Task` (ordered steps, capabilities, tool, prerequisites,
  parts consumed and produced), :class:`Part` and :class:`PartGroup` (the
  part-driven description), :class:`Feeder` with arrival models, and the
  step primitives of :mod:`tasklib.steps`; all immutable, validated by
  :class:`TaskSet`;
* the procedural, C-style API of the paper's task library:
  :mod:`tasklib.capi` (``task_open``, ``task_move``, ..., ``task_close``);
* poses: :class:`Pose` and :func:`pose` (``pose(x, y, z)``: the tool points
  :data:`DOWN`, as a bare ``(x, y, z)`` does wherever a pose is accepted);
* TDL, the trajectory description language: :func:`parse_tdl`,
  :func:`load_tdl`, :func:`print_tdl`;
* files: :func:`load_taskset` / :func:`save_taskset` (TOML or JSON, exact
  round trip);
* built-in examples: :func:`load_example` (``"supersigma"``, ``"scara4"``,
  ``"cell8"``) and :func:`generate_taskset`.
"""

from tasklib import capi
from tasklib.arrivals import (
    ArrivalModel,
    Feeder,
    FixedArrivals,
    PartArrival,
    PoissonArrivals,
    TraceArrivals,
    UniformArrivals,
)
from tasklib.examples import EXAMPLES, generate_taskset, load_example
from tasklib.io import load_taskset, save_taskset, taskset_from_dict, taskset_to_dict
from tasklib.model import Part, PartGroup, Task, TaskSet
from tasklib.pose import DOWN, UP, Pose, pose, quat_from_rpy
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
from tasklib.tdl import (
    Frame,
    ResolvedTrajectory,
    Segment,
    TDLDocument,
    Trajectory,
    Waypoint,
    load_tdl,
    parse_tdl,
    print_tdl,
)

__all__ = [
    "DOWN",
    "EXAMPLES",
    "UP",
    "Actuate",
    "Approach",
    "ArrivalModel",
    "Depart",
    "Detect",
    "Dwell",
    "Feeder",
    "FixedArrivals",
    "ForceSearch",
    "Frame",
    "Grasp",
    "Insert",
    "Move",
    "Part",
    "PartArrival",
    "PartGroup",
    "PoissonArrivals",
    "Pose",
    "Release",
    "ResolvedTrajectory",
    "Segment",
    "SetFlag",
    "Step",
    "TDLDocument",
    "Task",
    "TaskSet",
    "TraceArrivals",
    "Trajectory",
    "UniformArrivals",
    "UseTool",
    "WaitFlag",
    "Waypoint",
    "capi",
    "generate_taskset",
    "load_example",
    "load_taskset",
    "load_tdl",
    "parse_tdl",
    "pose",
    "print_tdl",
    "quat_from_rpy",
    "save_taskset",
    "taskset_from_dict",
    "taskset_to_dict",
]
