"""The zone map: cell bounds, walls, zones with their policy, tools, activation.

A :class:`ZoneMap` is what an SDL text describes (SEEDS.md S2.5, S2.10). It
is immutable; zones and tools get dense integer ids (their position), which
the run-time protocol and the scheduler use. Construction validates the whole
map and raises :class:`~multiarm.errors.SDLError` naming the element and,
when the map came from SDL text, its ``file:line:col``.

Policies (S2.5):

* ``exclusive``: one arm inside at a time;
* ``shared`` (simultaneous with restrictions): several arms may stand inside,
  only one may move there at a time.

Tools are always exclusive resources (S2.5).

Examples
--------
>>> from zones.geometry import AABox
>>> zm = ZoneMap(((0, 0, 0), (2, 1, 1)), (Zone("left", AABox((0, 0, 0), (1, 1, 1))),
...                                        Zone("mid", AABox((0.8, 0, 0), (1.2, 1, 1)), "shared")))
>>> zm.contains([[0.9, 0.5, 0.5], [1.5, 0.5, 0.5]]).tolist()
[[True, True], [False, False]]
>>> zm.zone_id("mid")
1
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal, NoReturn

import numpy as np

from multiarm.errors import SDLError
from multiarm.types import BoolArray, FloatArray, Point3
from zones.geometry import EPS, AABox, Bounds, HalfSpaces, Primitive, Shape, Union

__all__ = ["Phase", "Policy", "Tool", "Wall", "Zone", "ZoneMap"]

Policy = Literal["exclusive", "shared"]
"""Zone policy: ``"exclusive"`` or ``"shared"`` (simultaneous with restrictions)."""

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def _loc_fields() -> Any:
    return field(default=None, compare=False, repr=False)


@dataclass(frozen=True, slots=True)
class Wall:
    """A named plane through ``point`` with ``normal`` (S2.10 "subzone walls").

    A zone bounded by walls keeps, for each wall it names, the ``+`` side
    (where the normal points) or the ``-`` side.
    """

    name: str
    point: Point3
    normal: Point3
    line: int | None = _loc_fields()
    column: int | None = _loc_fields()

    def plane(self) -> tuple[FloatArray, float]:
        """(unit normal, offset) with the ``+`` side ``n . x >= offset``."""
        n = np.asarray(self.normal, dtype=float)
        n = n / np.linalg.norm(n)
        return n, float(n @ np.asarray(self.point, dtype=float))


@dataclass(frozen=True, slots=True)
class Zone:
    """A named zone: a volume, a policy and an optional speed limit (m/s)."""

    name: str
    shape: Shape
    policy: Policy = "exclusive"
    speed_limit: float | None = None
    line: int | None = _loc_fields()
    column: int | None = _loc_fields()

    @property
    def exclusive(self) -> bool:
        """True for an exclusive zone, False for a shared one."""
        return self.policy == "exclusive"


@dataclass(frozen=True, slots=True)
class Tool:
    """A tool, an exclusive resource, kept on a rack at ``rack`` (cell frame)."""

    name: str
    rack: Point3
    line: int | None = _loc_fields()
    column: int | None = _loc_fields()


@dataclass(frozen=True, slots=True)
class Phase:
    """A named activation set: switching to it makes exactly ``zones`` active."""

    name: str
    zones: tuple[str, ...]
    line: int | None = _loc_fields()
    column: int | None = _loc_fields()


@dataclass(frozen=True, slots=True)
class ZoneMap:
    """The cell's zones, walls, tools and activation sets.

    Parameters
    ----------
    bounds : ((3,), (3,)) float, metres
        The cell's axis-aligned bounds (lower corner, upper corner).
    zones : tuple of Zone
        Dense ids: a zone's id is its position.
    walls, tools, phases : tuples
    active : tuple of str or None
        Zones active at start; ``None`` means all.
    filename : str or None
        The SDL file it came from (error messages only; not compared).
    """

    bounds: Bounds
    zones: tuple[Zone, ...]
    walls: tuple[Wall, ...] = ()
    tools: tuple[Tool, ...] = ()
    active: tuple[str, ...] | None = None
    phases: tuple[Phase, ...] = ()
    filename: str | None = field(default=None, compare=False, repr=False)
    active_line: int | None = field(default=None, compare=False, repr=False)
    active_column: int | None = field(default=None, compare=False, repr=False)
    cell_line: int | None = field(default=None, compare=False, repr=False)
    cell_column: int | None = field(default=None, compare=False, repr=False)
    _zone_id: dict[str, int] = field(default_factory=dict, init=False, compare=False, repr=False)
    _tool_id: dict[str, int] = field(default_factory=dict, init=False, compare=False, repr=False)
    _fast: dict[str, Any] = field(default_factory=dict, init=False, compare=False, repr=False)

    # ------------------------------------------------------------ validation
    def _fail(self, message: str, where: Any = None) -> NoReturn:
        raise SDLError(
            message,
            filename=self.filename,
            line=getattr(where, "line", None),
            column=getattr(where, "column", None),
        )

    def __post_init__(self) -> None:
        at_cell = _At(self.cell_line, self.cell_column)
        at_active = _At(self.active_line, self.active_column)
        for attr in ("zones", "walls", "tools", "phases"):
            object.__setattr__(self, attr, tuple(getattr(self, attr)))
        if self.active is not None:
            object.__setattr__(self, "active", tuple(self.active))
        try:
            lo = tuple(float(v) for v in self.bounds[0])
            hi = tuple(float(v) for v in self.bounds[1])
        except (TypeError, ValueError, IndexError):
            self._fail(f"cell bounds must be two points, got {self.bounds!r}", at_cell)
        if len(lo) != 3 or len(hi) != 3:
            self._fail("cell bounds must be two 3-D points", at_cell)
        if not all(math.isfinite(v) for v in (*lo, *hi)):
            self._fail("cell bounds have a non-finite number", at_cell)
        if any(h - l <= EPS for l, h in zip(lo, hi, strict=True)):
            self._fail(f"cell bounds are empty or flat: {lo} to {hi}", at_cell)
        cell: Bounds = ((lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2]))
        object.__setattr__(self, "bounds", cell)

        walls: dict[str, Wall] = {}
        for w in self.walls:
            self._name(w.name, "wall", w)
            if w.name in walls:
                self._fail(f"wall {w.name!r} is defined twice", w)
            vals = (*w.point, *w.normal)
            if not all(math.isfinite(v) for v in vals):
                self._fail(f"wall {w.name!r} has a non-finite number", w)
            if math.sqrt(sum(c * c for c in w.normal)) <= EPS:
                self._fail(f"wall {w.name!r} has a zero normal", w)
            walls[w.name] = w

        resolved: list[Zone] = []
        for z in self.zones:
            self._name(z.name, "zone", z)
            if z.name in self._zone_id:
                self._fail(f"zone {z.name!r} is defined twice", z)
            if z.policy not in ("exclusive", "shared"):
                self._fail(f"zone {z.name!r} has unknown policy {z.policy!r}", z)
            if z.speed_limit is not None and not (
                math.isfinite(z.speed_limit) and z.speed_limit > 0
            ):
                self._fail(f"zone {z.name!r} speed_limit must be > 0 m/s, got {z.speed_limit}", z)
            shape = self._resolve(z.shape, z, walls, cell)
            try:
                shape.check()
            except ValueError as exc:
                self._fail(f"zone {z.name!r}: {exc}", z)
            zlo, zhi = shape.bounds()
            tol = 1e-9 * max(1.0, *map(abs, (*lo, *hi)))
            if any(a < b - tol for a, b in zip(zlo, lo, strict=True)) or any(
                a > b + tol for a, b in zip(zhi, hi, strict=True)
            ):
                self._fail(
                    f"zone {z.name!r} reaches outside the cell bounds "
                    f"(zone {tuple(round(v, 6) for v in zlo)} to {tuple(round(v, 6) for v in zhi)}, "
                    f"cell {lo} to {hi})",
                    z,
                )
            self._zone_id[z.name] = len(resolved)
            resolved.append(replace(z, shape=shape) if shape is not z.shape else z)
        object.__setattr__(self, "zones", tuple(resolved))

        for t in self.tools:
            self._name(t.name, "tool", t)
            if t.name in self._tool_id:
                self._fail(f"tool {t.name!r} is defined twice", t)
            if len(t.rack) != 3 or not all(math.isfinite(v) for v in t.rack):
                self._fail(f"tool {t.name!r} rack must be a finite 3-D point", t)
            if not all(l - EPS <= v <= h + EPS for v, l, h in zip(t.rack, lo, hi, strict=True)):
                self._fail(f"tool {t.name!r} rack {t.rack} lies outside the cell bounds", t)
            inside = self.contains(np.asarray([t.rack], dtype=float))[0]
            for zid in np.flatnonzero(inside):
                z = self.zones[zid]
                if z.exclusive:
                    self._fail(
                        f"tool {t.name!r} rack lies inside exclusive zone {z.name!r}: an arm "
                        f"bringing the tool back would wait for the zone while the arm inside "
                        f"waits for the tool (hold-and-wait deadlock, S2.6); put the rack in a "
                        f"shared zone or outside every exclusive zone",
                        t,
                    )
            self._tool_id[t.name] = len(self._tool_id)

        if self.active is not None:
            for name in self.active:
                if name not in self._zone_id:
                    self._fail(f"active set names unknown zone {name!r}", at_active)
            if len(set(self.active)) != len(self.active):
                self._fail("active set lists a zone twice", at_active)
        seen: set[str] = set()
        for ph in self.phases:
            self._name(ph.name, "phase", ph)
            if ph.name in seen:
                self._fail(f"phase {ph.name!r} is defined twice", ph)
            seen.add(ph.name)
            for name in ph.zones:
                if name not in self._zone_id:
                    self._fail(f"phase {ph.name!r} names unknown zone {name!r}", ph)
            if len(set(ph.zones)) != len(ph.zones):
                self._fail(f"phase {ph.name!r} lists a zone twice", ph)

    def _name(self, name: object, what: str, where: Any) -> None:
        if not isinstance(name, str) or not _NAME.match(name):
            self._fail(f"{what} name {name!r} is not a valid name", where)

    def _resolve(self, shape: Shape, zone: Zone, walls: dict[str, Wall], cell: Bounds) -> Shape:
        if isinstance(shape, HalfSpaces):
            planes = []
            used: set[str] = set()
            if not shape.sides:
                self._fail(f"zone {zone.name!r} names no wall", zone)
            for name, sign in shape.sides:
                if name not in walls:
                    self._fail(f"zone {zone.name!r} is bounded by unknown wall {name!r}", zone)
                if name in used:
                    self._fail(f"zone {zone.name!r} names wall {name!r} twice", zone)
                if sign not in (1, -1):
                    self._fail(f"zone {zone.name!r}: wall side must be + or -", zone)
                used.add(name)
                n, off = walls[name].plane()
                n, off = n * sign, off * sign
                planes.append(((float(n[0]), float(n[1]), float(n[2])), off))
            return HalfSpaces(shape.sides, tuple(planes), cell)
        if isinstance(shape, Union):
            return Union(tuple(self._resolve(p, zone, walls, cell) for p in shape.parts))
        return shape

    # --------------------------------------------------------------- lookup
    @property
    def n_zones(self) -> int:
        """Number of zones."""
        return len(self.zones)

    @property
    def n_tools(self) -> int:
        """Number of tools."""
        return len(self.tools)

    def zone_id(self, name: str | int) -> int:
        """Dense id of a zone (a name, or an id checked for range)."""
        if isinstance(name, int | np.integer) and not isinstance(name, bool):
            if 0 <= name < len(self.zones):
                return int(name)
            raise SDLError(f"zone id {name} out of range (0..{len(self.zones) - 1})")
        try:
            return self._zone_id[name]  # type: ignore[index]
        except KeyError:
            raise SDLError(f"unknown zone {name!r}", filename=self.filename) from None

    def tool_id(self, name: str | int) -> int:
        """Dense id of a tool."""
        if isinstance(name, int | np.integer) and not isinstance(name, bool):
            if 0 <= name < len(self.tools):
                return int(name)
            raise SDLError(f"tool id {name} out of range (0..{len(self.tools) - 1})")
        try:
            return self._tool_id[name]  # type: ignore[index]
        except KeyError:
            raise SDLError(f"unknown tool {name!r}", filename=self.filename) from None

    def zone(self, name: str | int) -> Zone:
        """The zone record by name or id."""
        return self.zones[self.zone_id(name)]

    def phase(self, name: str) -> Phase:
        """The phase called ``name``."""
        for ph in self.phases:
            if ph.name == name:
                return ph
        raise SDLError(f"unknown phase {name!r}", filename=self.filename)

    def zone_names(self) -> tuple[str, ...]:
        """Zone names by id."""
        return tuple(z.name for z in self.zones)

    def exclusive_mask(self) -> BoolArray:
        """(Z,) bool: True for exclusive zones."""
        return np.array([z.exclusive for z in self.zones], dtype=bool)

    def active_mask(self, phase: str | None = None) -> BoolArray:
        """(Z,) bool: zones active at start, or in ``phase``."""
        names: Iterable[str]
        if phase is not None:
            names = self.phase(phase).zones
        elif self.active is None:
            return np.ones(len(self.zones), dtype=bool)
        else:
            names = self.active
        mask = np.zeros(len(self.zones), dtype=bool)
        for n in names:
            mask[self._zone_id[n]] = True
        return mask

    # ------------------------------------------------------------- geometry
    def _prepare(self) -> dict[str, Any]:
        if not self._fast:
            boxes = [i for i, z in enumerate(self.zones) if isinstance(z.shape, AABox)]
            self._fast["box_ids"] = np.asarray(boxes, dtype=np.int64)
            if boxes:
                self._fast["lo"] = np.array([self.zones[i].shape.lo for i in boxes]) - EPS  # type: ignore[union-attr]
                self._fast["hi"] = np.array([self.zones[i].shape.hi for i in boxes]) + EPS  # type: ignore[union-attr]
            self._fast["other"] = [
                i for i, z in enumerate(self.zones) if not isinstance(z.shape, AABox)
            ]
        return self._fast

    def contains(self, points: Sequence[Sequence[float]] | FloatArray) -> BoolArray:
        """Which zones contain each point.

        Parameters
        ----------
        points : (N, 3) float, metres, cell frame

        Returns
        -------
        (N, Z) bool
            ``out[i, z]`` is True when point ``i`` lies in zone ``z``
            (boundaries included). Activation is not considered.
        """
        p = np.asarray(points, dtype=float)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"points must be an (N, 3) array, got shape {p.shape}")
        fast = self._prepare()
        out = np.zeros((len(p), len(self.zones)), dtype=bool)
        ids = fast["box_ids"]
        if len(ids):
            inside = (p[:, None, :] >= fast["lo"][None]) & (p[:, None, :] <= fast["hi"][None])
            out[:, ids] = inside.all(axis=2)
        for i in fast["other"]:
            out[:, i] = self.zones[i].shape.contains(p)
        return out

    def zones_at(self, point: Sequence[float]) -> tuple[str, ...]:
        """Names of the zones containing one point."""
        row = self.contains(np.asarray([point], dtype=float))[0]
        return tuple(self.zones[i].name for i in np.flatnonzero(row))

    def zone_bounds(self) -> FloatArray:
        """(Z, 2, 3) float: each zone's axis-aligned bounds (lower, upper corner)."""
        return np.array([z.shape.bounds() for z in self.zones], dtype=float).reshape(-1, 2, 3)

    def primitives(self, zone: str | int) -> tuple[Primitive, ...]:
        """The solids of a zone for the collision layer (see :class:`Primitive`)."""
        return self.zone(zone).shape.primitives()

    def summary(self) -> dict[str, Any]:
        """Counts: zones by policy, walls, tools, phases, active at start."""
        return {
            "zones": len(self.zones),
            "exclusive": int(self.exclusive_mask().sum()),
            "shared": int((~self.exclusive_mask()).sum()),
            "walls": len(self.walls),
            "tools": len(self.tools),
            "phases": len(self.phases),
            "active": int(self.active_mask().sum()),
        }


@dataclass(frozen=True, slots=True)
class _At:
    line: int | None
    column: int | None = None
