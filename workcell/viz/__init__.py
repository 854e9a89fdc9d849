"""Pictures of a cell: GLB scenes (trimesh) and PNG views (matplotlib, headless).

Never imported by the geometry or the simulation (DESIGN.md): plotting is a
leaf. Arms are drawn from their collision shapes, zones from their solids.
:mod:`workcell.viz.plots` draws schedules and simulation runs: Gantt charts
(planned vs executed), zone occupancy, the cell at chosen instants and
motion frames, joint curves. :mod:`workcell.style` keeps one look
across them (an arm's colour, a fault's marker); :mod:`workcell.viz.waits`
locates the space-grid blocks and summarises a run's waits by zone.
"""

from workcell.style import arm_colours
from workcell.viz.plots import (
    arm_joints,
    gantt,
    joint_timeline,
    motion_frames,
    render_instants,
    zone_timeline,
)
from workcell.viz.scene import cell_scene, export_glb, render_png
from workcell.viz.waits import ZoneWait, space_grid_table, wait_summary

__all__ = [
    "ZoneWait",
    "arm_colours",
    "arm_joints",
    "cell_scene",
    "export_glb",
    "gantt",
    "joint_timeline",
    "motion_frames",
    "render_instants",
    "render_png",
    "space_grid_table",
    "wait_summary",
    "zone_timeline",
]
