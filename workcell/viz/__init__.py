"""Pictures of a cell: GLB scenes (trimesh) and PNG views (matplotlib, headless).

Never imported by the geometry or the simulation (DESIGN.md): plotting is a
leaf. Arms are drawn from their collision shapes, zones from their solids.
:mod:`workcell.viz.plots` draws schedules and simulation runs: Gantt charts
(planned vs executed), zone occupancy, the cell at chosen instants and
motion frames.
"""

from workcell.viz.plots import arm_joints, gantt, motion_frames, render_instants, zone_timeline
from workcell.viz.scene import cell_scene, export_glb, render_png

__all__ = [
    "arm_joints",
    "cell_scene",
    "export_glb",
    "gantt",
    "motion_frames",
    "render_instants",
    "render_png",
    "zone_timeline",
]
