"""Built-in SDL zone maps of the reference cells.

* ``"supersigma"``: the two-arm Cartesian cell (shared fixture band between
  subzone walls, exclusive feeders, the screwdriver rack over the fixture);
* ``"scara4"``: four SCARA arms around a shared central assembly zone;
* ``"cell8"``: the 8-arm scale cell (12 active zones of both policies, walls,
  a union, three tools, two phases; 11 zones active at start);
* ``"urdf_cell"``: two UR5 and a Panda around a shared fixture, with a
  conveyor, a pin tray and a tool rack.

Examples
--------
>>> load_example("cell8").summary()["zones"]
12
"""

from __future__ import annotations

from importlib import resources

from multiarm.errors import ValidationError
from zones.model import ZoneMap
from zones.sdl import parse_sdl

__all__ = ["EXAMPLES", "example_path", "load_example"]

EXAMPLES = ("supersigma", "scara4", "cell8", "urdf_cell")


def example_path(name: str) -> str:
    """File path of a built-in SDL file."""
    if name not in EXAMPLES:
        raise ValidationError(f"unknown example {name!r} (known: {', '.join(EXAMPLES)})")
    return str(resources.files(__name__).joinpath(f"{name}.sdl"))


def load_example(name: str) -> ZoneMap:
    """The built-in zone map ``name``."""
    path = example_path(name)
    with open(path, encoding="utf-8") as fh:
        return parse_sdl(fh.read(), f"{name}.sdl")
