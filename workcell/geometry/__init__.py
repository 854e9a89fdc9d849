"""Geometry for the workcell: the FCL collision world, zone sweeps, OMPL detours.

* :mod:`workcell.geometry.world`: :class:`CollisionWorld`, named FCL objects in
  groups with broadphase managers (the only module importing ``fcl``);
* :mod:`workcell.geometry.zone_sweep`: :func:`zone_windows`, the conservative sweep
  of an arm's shapes through the zones (occupancy and moving windows, S2.5),
  :func:`static_occupancy`, :func:`swept_aabb`;
* :mod:`workcell.geometry.planner`: :func:`plan_detour`, collision-free
  joint-space detours around a parked arm (S2.6, S2.12; the only module
  importing ``ompl``), :func:`first_contact` (when a trajectory meets a parked
  arm), :func:`check_path`, :func:`write_ompl_benchmark_log`.
"""

from workcell.geometry.planner import (
    DetourPlanner,
    DetourResult,
    DetourStatus,
    ObstacleSet,
    check_path,
    first_contact,
    plan_detour,
    write_ompl_benchmark_log,
)
from workcell.geometry.world import CollisionReport, CollisionWorld
from workcell.geometry.zone_sweep import (
    JointTrajectoryLike,
    ZoneWindow,
    ZoneWindows,
    aabbs_overlap,
    arm_contacts,
    reference_contacts,
    sample_trajectory,
    static_occupancy,
    swept_aabb,
    zone_contacts,
    zone_windows,
)

__all__ = [
    "CollisionReport",
    "CollisionWorld",
    "DetourPlanner",
    "DetourResult",
    "DetourStatus",
    "JointTrajectoryLike",
    "ObstacleSet",
    "ZoneWindow",
    "ZoneWindows",
    "aabbs_overlap",
    "arm_contacts",
    "check_path",
    "first_contact",
    "plan_detour",
    "reference_contacts",
    "sample_trajectory",
    "static_occupancy",
    "swept_aabb",
    "write_ompl_benchmark_log",
    "zone_contacts",
    "zone_windows",
]
