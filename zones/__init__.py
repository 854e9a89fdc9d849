"""zones: SDL, the zone model and the run-time zone protocol (SEEDS.md S2.5-S2.7, S2.10).

* :func:`parse_sdl` / :func:`load_sdl` / :func:`print_sdl`: the subzone
  description language (``docs/sdl.md``), giving an immutable :class:`ZoneMap`
  with dense zone and tool ids and vectorised geometry queries;
* :class:`ZoneManager`: the run-time protocol (grant / sleep / wake, tools,
  activation changes, deadlock detection and resolution, geometric blocks),
  a pure state machine (``docs/zones.md``);
* :mod:`zones.examples`: the built-in SDL files of the reference cells.
"""

from zones.geometry import (
    AABox,
    Cylinder,
    HalfSpaces,
    Hull,
    MeshShape,
    OBox,
    Primitive,
    Shape,
    Sphere,
    Union,
)
from zones.manager import (
    BackOff,
    Blocked,
    Deadlock,
    LowestPriorityBacksOff,
    ReportOnly,
    Response,
    Wake,
    YoungestBacksOff,
    ZoneManager,
)
from zones.model import Phase, Policy, Tool, Wall, Zone, ZoneMap
from zones.sdl import load_sdl, parse_sdl, print_sdl

__all__ = [
    "AABox",
    "BackOff",
    "Blocked",
    "Cylinder",
    "Deadlock",
    "HalfSpaces",
    "Hull",
    "LowestPriorityBacksOff",
    "MeshShape",
    "OBox",
    "Phase",
    "Policy",
    "Primitive",
    "ReportOnly",
    "Response",
    "Shape",
    "Sphere",
    "Tool",
    "Union",
    "Wake",
    "Wall",
    "YoungestBacksOff",
    "Zone",
    "ZoneManager",
    "ZoneMap",
    "load_sdl",
    "parse_sdl",
    "print_sdl",
]
