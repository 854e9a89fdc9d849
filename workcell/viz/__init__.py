"""Pictures of a cell: GLB scenes (trimesh) and PNG views (matplotlib, headless).

Never imported by the geometry or the simulation (DESIGN.md): plotting is a
leaf. Arms are drawn from their collision shapes, zones from their solids.
"""

from workcell.viz.scene import cell_scene, export_glb, render_png

__all__ = ["cell_scene", "export_glb", "render_png"]
