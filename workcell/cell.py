"""The cell: tasks, zones and arms in one record, and the TOML cell file.

A :class:`Cell` is what a researcher describes (DESIGN.md data flow, step 1):
a :class:`tasklib.TaskSet` (the robot-independent elementary tasks, their
parts, feeders and TDL trajectories), a :class:`zones.ZoneMap` (the SDL
zones and tools) and the arms with their placement and initial joint
vectors. :func:`workcell.compile_cell` turns it into a scheduling problem.

The cell file
-------------
A TOML file; paths are relative to the file; ``builtin:NAME`` names a
built-in task set or zone map (``supersigma``, ``scara4``, ``cell8``)::

    name = "twoarm"
    description = "two gantries over one table"
    zones = "cell.sdl"                 # SDL file (or "builtin:supersigma")
    tasks = "tasks.toml"               # task-set file, .toml or .json (or "builtin:...")
    tdl = ["extra.tdl"]                # optional: more TDL files merged into the task set

    [compile]                          # optional; these are the defaults
    plan_with = "nominal"              # or "worst": all insertion tries, the longest search
    releases = "expected"              # part arrivals -> release times: "expected", "sample", "none"
    seed = 0                           # for releases = "sample"
    padding = 0.005                    # sweep padding, metres (zone windows are conservative by it)
    park = "home"                      # after each task the arm returns to its start joints ("home"),
                                       # or stays at the task's last pose ("last")
    grid = 0.3                         # space-grid block side, metres (0: off): moving arms
                                       # never meet outside the SDL zones (workcell.geometry.reach)

    [arms.left]                        # one table per arm; see workcell.arms.arm_from_dict
    type = "gantry"
    start = [0.2, 0.3, 0.3, 0.0]       # optional initial joint vector (default: the arm's home)
    ...

Every error names the file and the field (``cell.toml: arms.left.start:
expected 4 numbers, got 3``); TOML syntax errors give ``file:line:col``.

Examples
--------
>>> cell = load_example("supersigma")
>>> cell.name, [a.name for a in cell.arms]
('supersigma', ['left', 'right'])
"""

from __future__ import annotations

import math
import tomllib
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from importlib import resources
from os import PathLike, fspath
from pathlib import Path
from typing import Any, Literal

import numpy as np

from multiarm.errors import MultiarmError, ValidationError
from multiarm.types import JointVector
from tasklib import TaskSet
from tasklib.examples import EXAMPLES as TASK_EXAMPLES
from tasklib.io import load_taskset, parse_toml, read_toml_source
from tasklib.tdl import load_tdl
from workcell.arms import DriveArm, arm_from_dict
from workcell.arms.spec import MAX_LENGTH
from workcell.compiled import SPACE_GRID
from zones import ZoneMap, load_sdl
from zones import examples as zone_examples

__all__ = ["EXAMPLES", "URDF_EXAMPLES", "Cell", "cell_from_dict", "load_cell", "load_example"]

PlanWith = Literal["nominal", "worst"]
Park = Literal["home", "last"]
Releases = Literal["expected", "sample", "none"]

EXAMPLES: tuple[str, ...] = ("supersigma", "scara4", "cell8", "urdf_cell", "parking")
"""Names of the built-in cells (:func:`load_example`)."""

URDF_EXAMPLES: tuple[str, ...] = ("urdf_cell",)
"""Built-in cells whose arms are read from URDF files (the ``urdf`` extra)."""


@dataclass(frozen=True, eq=False)
class Cell:
    """An assembly cell: tasks, zones, arms.

    Parameters
    ----------
    name : str
    taskset : tasklib.TaskSet
    zone_map : zones.ZoneMap
    arms : tuple of workcell.arms.DriveArm
        Distinct names.
    start : tuple of (dof,) float
        Each arm's initial joint vector (default: its home).
    plan_with : {"nominal", "worst"}
        Which task durations the compile plans with: nominal (one insertion
        try, the expected detector search) or the worst case (every try).
    releases : {"expected", "sample", "none"}
        How part arrivals become task release times: expected arrival
        times, one sampled outcome (``seed``), or none (all parts present).
    seed : int
        Seed of ``releases="sample"``.
    padding : float
        Sweep padding in metres: zone windows hold whenever an arm's
        shapes come within this distance of a zone (conservative).
    park : {"home", "last"}
        Where an arm waits between tasks: ``"home"`` appends a move back to
        its start joints to every task (the arm never stands in another's
        way after its work, the usual practice of real cells); ``"last"``
        leaves it at the task's last pose, where it may block other arms
        (S2.6 geometric deadlock, answered by the blocking oracle) until it
        travels to its next task, and for good after its last one.
    grid : float
        Block side of the space grid, metres (:mod:`workcell.geometry.reach`):
        every block that modes of two arms touch becomes an implicit
        exclusive zone, so that two arms moving at the same time can never
        meet outside the SDL zones. ``0`` turns it off: arms are then kept
        apart only where the SDL zones and the parked-arm oracle keep them.
        Default :data:`workcell.compiled.SPACE_GRID`; a
        :class:`~workcell.CompileOptions` ``grid`` overrides it.
    description : str
    source : str or None
        The cell file it was read from.
    """

    name: str
    taskset: TaskSet
    zone_map: ZoneMap
    arms: tuple[DriveArm, ...]
    start: tuple[JointVector, ...] = ()
    plan_with: PlanWith = "nominal"
    releases: Releases = "expected"
    seed: int = 0
    padding: float = 0.005
    park: Park = "home"
    grid: float = SPACE_GRID
    description: str = ""
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not self.arms:
            raise ValidationError(f"cell {self.name!r} has no arm")
        names = [a.name for a in self.arms]
        for n in names:
            if not isinstance(n, str) or not n.strip() or "|" in n or "/" in n:
                raise ValidationError(
                    f"cell {self.name!r}: an arm's name must be non-empty text without '|' or "
                    f"'/', got {n!r}"
                )
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValidationError(f"cell {self.name!r} has two arms named {dup[0]!r}")
        if not self.start:
            object.__setattr__(self, "start", tuple(np.array(a.home, float) for a in self.arms))
        if len(self.start) != len(self.arms):
            raise ValidationError(
                f"cell {self.name!r}: {len(self.start)} start vectors for {len(self.arms)} arms"
            )
        starts = []
        for arm, q in zip(self.arms, self.start, strict=True):
            qa = np.array(q, dtype=float).reshape(-1)
            if qa.shape != (arm.dof,) or not np.all(np.isfinite(qa)):
                raise ValidationError(
                    f"cell {self.name!r}: arm {arm.name!r} start must be {arm.dof} finite numbers"
                )
            if not bool(arm.within_limits(qa[None])[0]):
                raise ValidationError(
                    f"cell {self.name!r}: arm {arm.name!r} start {qa.tolist()} is outside its "
                    "joint limits"
                )
            qa.setflags(write=False)
            starts.append(qa)
        object.__setattr__(self, "start", tuple(starts))
        if self.plan_with not in ("nominal", "worst"):
            raise ValidationError(
                f"cell {self.name!r}: plan_with must be 'nominal' or 'worst', not {self.plan_with!r}"
            )
        if self.releases not in ("expected", "sample", "none"):
            raise ValidationError(
                f"cell {self.name!r}: releases must be 'expected', 'sample' or 'none', "
                f"not {self.releases!r}"
            )
        if self.park not in ("home", "last"):
            raise ValidationError(
                f"cell {self.name!r}: park must be 'home' or 'last', not {self.park!r}"
            )
        g = self.grid
        if (
            isinstance(g, bool)
            or not isinstance(g, int | float)
            or not (g == 0 or MIN_GRID <= g <= MAX_LENGTH)
        ):
            raise ValidationError(
                f"cell {self.name!r}: grid must be 0 (off) or a number of metres in "
                f"[{MIN_GRID:g}, {MAX_LENGTH:g}], not {g!r}"
            )
        object.__setattr__(self, "grid", float(g))
        if not (math.isfinite(self.padding) and 1e-4 <= self.padding <= 0.1):
            raise ValidationError(
                f"cell {self.name!r}: padding must be in [0.0001, 0.1] metres, got {self.padding}"
            )

    def arm(self, name: str) -> DriveArm:
        """The arm called ``name``."""
        for a in self.arms:
            if a.name == name:
                return a
        raise ValidationError(
            f"cell {self.name!r} has no arm {name!r} (arms: {', '.join(a.name for a in self.arms)})"
        )

    def summary(self) -> dict[str, Any]:
        """Counts for a quick look."""
        return {
            "name": self.name,
            "arms": len(self.arms),
            "arm types": ", ".join(sorted({a.kind for a in self.arms})),
            "tasks": len(self.taskset.tasks),
            "zones": self.zone_map.n_zones,
            "tools": self.zone_map.n_tools,
        }

    def __repr__(self) -> str:
        return (
            f"Cell({self.name!r}: {len(self.arms)} arms, {len(self.taskset.tasks)} tasks, "
            f"{self.zone_map.n_zones} zones)"
        )


# ------------------------------------------------------------------ loader

_TOP_KEYS = {"name", "description", "zones", "tasks", "tdl", "compile", "arms"}
_COMPILE_KEYS = {"plan_with", "releases", "seed", "padding", "park", "grid", "separate_arms"}


MIN_GRID = 0.01
"""Smallest block side of the space grid, metres (the arms' capsules are
centimetres thick; finer blocks only multiply the zones)."""


def _fail(where: str, message: str) -> ValidationError:
    return ValidationError(f"{where}: {message}")


def _str(data: Mapping[str, Any], key: str, where: str, default: str | None = None) -> str:
    if key not in data:
        if default is None:
            raise _fail(where, f"missing field {key!r}")
        return default
    value = data[key]
    if not isinstance(value, str) or not value:
        raise _fail(f"{where}.{key}", f"expected a non-empty string, got {value!r}")
    return value


def _resolve(ref: str, base: Path | None, where: str) -> Path | str:
    if ref.startswith("builtin:"):
        return ref
    p = Path(ref)
    if not p.is_absolute():
        if base is None:
            raise _fail(where, f"relative path {ref!r} needs the cell file's directory")
        p = base / p
    if not p.is_file():
        raise _fail(where, f"file {fspath(p)!r} does not exist")
    return p


def _load_zones(ref: str, base: Path | None, where: str) -> ZoneMap:
    target = _resolve(ref, base, where)
    if isinstance(target, str):
        name = target.removeprefix("builtin:")
        try:
            return zone_examples.load_example(name)
        except MultiarmError as exc:
            raise _fail(where, str(exc)) from None
    return load_sdl(target)


def _load_tasks(ref: str, base: Path | None, where: str) -> TaskSet:
    target = _resolve(ref, base, where)
    if isinstance(target, str):
        name = target.removeprefix("builtin:")
        if name not in TASK_EXAMPLES:
            raise _fail(
                where,
                f"unknown built-in task set {name!r} (known: {', '.join(sorted(TASK_EXAMPLES))})",
            )
        return TASK_EXAMPLES[name]()
    return load_taskset(target)


def cell_from_dict(
    data: Mapping[str, Any], *, filename: str | None = None, base_dir: Path | None = None
) -> Cell:
    """Build a :class:`Cell` from plain data (a parsed cell file).

    Parameters
    ----------
    data : mapping
        The cell file's content (see the module docstring).
    filename : str, optional
        Named in every error message.
    base_dir : Path, optional
        Directory that relative paths are relative to.

    Raises
    ------
    ValidationError
        Naming the file and the field path.
    SDLError, TDLError, FormatError
        From the referenced files (located in those files).
    """
    top = filename or "cell"
    if not isinstance(data, Mapping):
        raise _fail(top, f"a cell must be a table, got {type(data).__name__}")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise _fail(top, f"unknown field {unknown[0]!r} (known: {', '.join(sorted(_TOP_KEYS))})")
    name = _str(data, "name", top)
    description = data.get("description", "")
    if not isinstance(description, str):
        raise _fail(f"{top}: description", f"expected a string, got {description!r}")
    zone_map = _load_zones(_str(data, "zones", top), base_dir, f"{top}: zones")
    taskset = _load_tasks(_str(data, "tasks", top), base_dir, f"{top}: tasks")
    tdl = data.get("tdl", [])
    if not isinstance(tdl, list) or not all(isinstance(x, str) for x in tdl):
        raise _fail(f"{top}: tdl", f"expected a list of file names, got {tdl!r}")
    if tdl:
        doc = taskset.trajectories
        for i, ref in enumerate(tdl):
            path = _resolve(ref, base_dir, f"{top}: tdl[{i}]")
            if isinstance(path, str):
                raise _fail(f"{top}: tdl[{i}]", "TDL files cannot be built-in references")
            doc = doc.merge(load_tdl(path))
        taskset = replace(taskset, trajectories=doc)
    comp = data.get("compile", {})
    if not isinstance(comp, Mapping):
        raise _fail(f"{top}: compile", f"expected a table, got {comp!r}")
    unknown = sorted(set(comp) - _COMPILE_KEYS)
    if unknown:
        raise _fail(
            f"{top}: compile",
            f"unknown field {unknown[0]!r} (known: {', '.join(sorted(_COMPILE_KEYS))})",
        )
    plan_with = comp.get("plan_with", "nominal")
    if plan_with not in ("nominal", "worst"):
        raise _fail(
            f"{top}: compile.plan_with", f"expected 'nominal' or 'worst', got {plan_with!r}"
        )
    releases = comp.get("releases", "expected")
    if releases not in ("expected", "sample", "none"):
        raise _fail(
            f"{top}: compile.releases", f"expected 'expected', 'sample' or 'none', got {releases!r}"
        )
    seed = comp.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise _fail(f"{top}: compile.seed", f"expected a non-negative integer, got {seed!r}")
    padding = comp.get("padding", 0.005)
    if isinstance(padding, bool) or not isinstance(padding, int | float):
        raise _fail(f"{top}: compile.padding", f"expected a number, got {padding!r}")
    if not (math.isfinite(padding) and 1e-4 <= padding <= 0.1):
        raise _fail(f"{top}: compile.padding", f"must be in [0.0001, 0.1] metres, got {padding!r}")
    park = comp.get("park", "home")
    if park not in ("home", "last"):
        raise _fail(f"{top}: compile.park", f"expected 'home' or 'last', got {park!r}")
    grid = comp.get("grid", SPACE_GRID)
    if isinstance(grid, bool) or not isinstance(grid, int | float):
        raise _fail(f"{top}: compile.grid", f"expected a number of metres, got {grid!r}")
    if not (grid == 0 or MIN_GRID <= grid <= MAX_LENGTH):
        raise _fail(
            f"{top}: compile.grid",
            f"must be 0 (off) or in [{MIN_GRID:g}, {MAX_LENGTH:g}] metres, got {grid!r}",
        )
    if "separate_arms" in comp:
        # the former switch: false is grid = 0, true the grid as set
        separate = comp["separate_arms"]
        if not isinstance(separate, bool):
            raise _fail(
                f"{top}: compile.separate_arms", f"expected true or false, got {separate!r}"
            )
        if not separate and "grid" in comp and grid > 0:
            raise _fail(
                f"{top}: compile.separate_arms",
                f"false contradicts grid = {grid!r} (write grid = 0 alone)",
            )
        warnings.warn(
            f"{top}: compile.separate_arms is deprecated: write grid = 0 (off) or a block "
            "side in metres",
            DeprecationWarning,
            stacklevel=3,
        )
        if not separate:
            grid = 0.0
    arms_data = data.get("arms")
    if not isinstance(arms_data, Mapping) or not arms_data:
        raise _fail(f"{top}: arms", "expected a table with at least one [arms.NAME] table")
    arms: list[DriveArm] = []
    starts: list[JointVector] = []
    for arm_name, spec in arms_data.items():
        where = f"{top}: arms.{arm_name}"
        if not isinstance(spec, Mapping):
            raise _fail(where, f"expected a table, got {spec!r}")
        spec = dict(spec)
        start = spec.pop("start", None)
        arm = arm_from_dict(str(arm_name), spec, where, base_dir=base_dir)
        if start is None:
            q = np.array(arm.home, dtype=float)
        else:
            if (
                not isinstance(start, list)
                or len(start) != arm.dof
                or not all(
                    isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                    for v in start
                )
            ):
                raise _fail(f"{where}.start", f"expected {arm.dof} numbers, got {start!r}")
            q = np.array(start, dtype=float)
            if not bool(arm.within_limits(q[None])[0]):
                raise _fail(f"{where}.start", f"{start} is outside the joint limits")
        arms.append(arm)
        starts.append(q)
    try:
        return Cell(
            name,
            taskset,
            zone_map,
            tuple(arms),
            tuple(starts),
            plan_with=plan_with,
            releases=releases,
            seed=seed,
            padding=float(padding),
            park=park,
            grid=float(grid),
            description=description,
            source=filename,
        )
    except ValidationError as exc:
        raise _fail(top, str(exc)) from None


def load_cell(path: str | PathLike[str]) -> Cell:
    """Read a cell file (TOML, see the module docstring).

    Raises
    ------
    FormatError
        Unreadable file or TOML syntax error (``file:line:col``).
    ValidationError
        A field is wrong (``file: field.path: message``).
    SDLError, TDLError
        From the referenced SDL and TDL files.
    """
    p = Path(path)
    name = fspath(path)
    text = read_toml_source(path, "cell")
    data = parse_toml(text, name)
    return cell_from_dict(data, filename=name, base_dir=p.parent)


def _example_text(name: str) -> str:
    return resources.files("workcell.examples").joinpath(f"{name}.toml").read_text("utf-8")


def load_example(name: str) -> Cell:
    """The built-in cell ``name``: ``"supersigma"``, ``"scara4"``, ``"cell8"``,
    ``"urdf_cell"`` (two UR5 and a Panda from URDF: the ``urdf`` extra) or
    ``"parking"`` (S2.6: an arm parked in another's way, and the OMPL detour
    around it; :mod:`workcell.detours`).

    Read from the package's data, so it works from an installed wheel.

    Examples
    --------
    >>> load_example("scara4").summary()["arms"]
    4
    """
    known = EXAMPLES
    if name not in known:
        raise ValidationError(f"unknown example cell {name!r} (known: {', '.join(known)})")
    data = tomllib.loads(_example_text(name))
    # a built-in cell may name files of its own next to it (the parking cell)
    with resources.as_file(resources.files("workcell.examples")) as folder:
        return cell_from_dict(data, filename=f"{name}.toml", base_dir=Path(folder))
