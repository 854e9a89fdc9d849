"""Cell pictures: GLB scenes and PNG views (workcell.viz)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from multiarm.errors import ValidationError
from workcell import load_example
from workcell.viz import cell_scene, export_glb, render_png


def test_glb_holds_every_arm_shape_and_zone(tmp_path: Path) -> None:
    cell = load_example("supersigma")
    path = export_glb(cell, tmp_path / "cell.glb", {"left": [0.5, 0.5, 0.3, 0.0]})
    back = trimesh.load(path)
    names = set(back.geometry)
    for arm in cell.arms:
        for shape in arm.shapes:
            assert f"{arm.name}:{shape.name}" in names
    assert {n.split(":")[1] for n in names if n.startswith("zone:")} == set(
        cell.zone_map.zone_names()
    )
    # the left hand stands where its joints put it
    scene = cell_scene(cell, {"left": [0.5, 0.5, 0.3, 0.0]})
    tf, _ = scene.graph["left:hand"]
    assert np.allclose(tf[:2, 3], [0.5, 0.5])


@pytest.mark.parametrize("view", ["top", "3d"])
def test_png_views_are_written(tmp_path: Path, view: str) -> None:
    path = render_png(load_example("scara4"), tmp_path / f"{view}.png", view=view)  # type: ignore[arg-type]
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_view_and_unknown_arm_are_errors(tmp_path: Path) -> None:
    cell = load_example("scara4")
    with pytest.raises(ValidationError, match="view must be 'top' or '3d'"):
        render_png(cell, tmp_path / "x.png", view="side")  # type: ignore[arg-type]
    with pytest.raises(ValidationError, match="has no arm 'zz'"):
        cell_scene(cell, {"zz": [0, 0, 0, 0]})
