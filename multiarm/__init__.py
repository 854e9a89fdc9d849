"""multiarm: scheduling and coordinating several robot arms in one assembly cell.

The distribution installs five packages, stacked in one import direction
(DESIGN.md): ``multiarm`` (this one: the exception root, shared types, the
version) at the bottom; ``tasklib`` (elementary tasks, parts, TDL) and
``zones`` (SDL, the zone model, the run-time zone protocol) above it;
``scheduler`` above those; ``workcell`` (the cell model, geometry, simulation,
the command line) on top.
"""

from multiarm._version import __version__
from multiarm.errors import (
    CycleError,
    FormatError,
    InfeasibleError,
    InputError,
    InternalError,
    MultiarmError,
    NoFeasibleSchedule,
    ParseError,
    PlanningFailed,
    ScheduleError,
    SDLError,
    SDLSyntaxError,
    SourceError,
    TDLError,
    TDLSyntaxError,
    UsageError,
    ValidationError,
)

__all__ = [
    "CycleError",
    "FormatError",
    "InfeasibleError",
    "InputError",
    "InternalError",
    "MultiarmError",
    "NoFeasibleSchedule",
    "ParseError",
    "PlanningFailed",
    "SDLError",
    "SDLSyntaxError",
    "ScheduleError",
    "SourceError",
    "TDLError",
    "TDLSyntaxError",
    "UsageError",
    "ValidationError",
    "__version__",
]
