"""SDL, the subzone description language: parse, load and print zone maps.

An SDL text (``.sdl``) describes the cell bounds, named walls, zones (volume +
policy + optional speed limit), tools with their rack, the zones active at
start and named activation sets (phases). The language reference with
examples is ``docs/sdl.md``.

Examples
--------
>>> zm = parse_sdl('''
... cell (0, 0, 0) (2, 1.2, 1)
... wall mid_left x = 0.8
... wall mid_right x = 1.2
... zone left_feeder exclusive box (0, 0, 0) (0.4, 0.6, 0.5)
... zone fixture shared walls { +mid_left, -mid_right } speed_limit 0.25
... tool screwdriver rack (1.0, 1.1, 0.2)
... phase assembly { fixture }
... ''')
>>> zm.zone_names(), zm.zone("fixture").policy
(('left_feeder', 'fixture'), 'shared')
>>> zm.zones_at((1.0, 0.5, 0.5))
('fixture',)
>>> parse_sdl(print_sdl(zm)) == zm
True
"""

from __future__ import annotations

import math
import os
from functools import cache
from importlib import resources
from os import PathLike, fspath
from typing import Any

import lark

from multiarm.errors import SDLError, SDLSyntaxError, ValidationError
from multiarm.text import fmt_float, meta_location, parse_text, quote, read_source, unquote
from multiarm.types import Point3
from zones.geometry import (
    AABox,
    Cylinder,
    HalfSpaces,
    Hull,
    MeshShape,
    OBox,
    Shape,
    Sphere,
    Union,
)
from zones.model import Phase, Tool, Wall, Zone, ZoneMap

__all__ = ["load_sdl", "parse_sdl", "print_sdl"]


@cache
def _parser() -> lark.Lark:
    grammar = resources.files("zones").joinpath("sdl.lark").read_text(encoding="utf-8")
    return lark.Lark(grammar, parser="lalr", propagate_positions=True, maybe_placeholders=True)


class _Located:
    """A shape or statement with its source position."""

    __slots__ = ("column", "line", "value")

    def __init__(self, value: Any, meta: Any) -> None:
        self.value = value
        self.line, self.column = meta_location(meta)


class _Build(lark.Transformer[lark.Token, ZoneMap]):
    def __init__(self, filename: str | None, base: str) -> None:
        super().__init__()
        self.filename = filename
        self.base = base

    def _err(self, message: str, meta: Any) -> SDLError:
        line, column = meta_location(meta)
        return SDLError(message, filename=self.filename, line=line, column=column)

    def number(self, items: list[lark.Token]) -> float:
        return float(items[0])

    def vec(self, items: list[float]) -> Point3:
        return (items[0], items[1], items[2])

    @lark.v_args(meta=True)
    def cell(self, meta: Any, items: list[Point3]) -> _Located:
        return _Located(("cell", items[0], items[1]), meta)

    @lark.v_args(meta=True)
    def wall_plane(self, meta: Any, items: list[Any]) -> Wall:
        line, column = meta_location(meta)
        normal = items[2]
        if all(map(math.isfinite, normal)) and not math.isfinite(sum(c * c for c in normal)):
            # its length overflows: the unit normal would come out as zero
            raise self._err(
                f"wall {str(items[0])!r}: the normal is too long to normalise (give a unit vector)",
                meta,
            )
        return Wall(str(items[0]), items[1], items[2], line=line, column=column)

    @lark.v_args(meta=True)
    def wall_axis(self, meta: Any, items: list[Any]) -> Wall:
        line, column = meta_location(meta)
        axis = "xyz".index(str(items[1]))
        point = [0.0, 0.0, 0.0]
        normal = [0.0, 0.0, 0.0]
        point[axis] = items[2]
        normal[axis] = 1.0
        return Wall(str(items[0]), tuple(point), tuple(normal), line=line, column=column)  # type: ignore[arg-type]

    def yaw(self, items: list[float]) -> float:
        return items[0]

    def speed_limit(self, items: list[float]) -> float:
        return items[0]

    def box(self, items: list[Point3]) -> Shape:
        return AABox(items[0], items[1])

    def obox(self, items: list[Any]) -> Shape:
        return OBox(items[0], items[1], items[2] if items[2] is not None else 0.0)

    def cylinder(self, items: list[Any]) -> Shape:
        return Cylinder(items[0], items[1], items[2])

    def sphere(self, items: list[Any]) -> Shape:
        return Sphere(items[0], items[1])

    def hull(self, items: list[Any]) -> Shape:
        return Hull(tuple(i for i in items if i is not None))

    def side(self, items: list[lark.Token]) -> tuple[str, int]:
        return (str(items[1]), 1 if str(items[0]) == "+" else -1)

    def walls(self, items: list[Any]) -> Shape:
        return HalfSpaces(tuple(i for i in items if i is not None))

    def union(self, items: list[Shape]) -> Shape:
        return Union(tuple(items))

    def mesh(self, items: list[lark.Token]) -> Shape:
        return MeshShape(unquote(str(items[0])), self.base)

    @lark.v_args(meta=True)
    def zone(self, meta: Any, items: list[Any]) -> Zone:
        name, policy, shape, speed = items
        line, column = meta_location(meta)
        return Zone(str(name), shape, str(policy), speed, line=line, column=column)  # type: ignore[arg-type]

    @lark.v_args(meta=True)
    def tool(self, meta: Any, items: list[Any]) -> Tool:
        line, column = meta_location(meta)
        return Tool(str(items[0]), items[1], line=line, column=column)

    @lark.v_args(meta=True)
    def active(self, meta: Any, items: list[Any]) -> _Located:
        return _Located(("active", tuple(str(i) for i in items if i is not None)), meta)

    @lark.v_args(meta=True)
    def phase(self, meta: Any, items: list[Any]) -> Phase:
        line, column = meta_location(meta)
        return Phase(
            str(items[0]),
            tuple(str(i) for i in items[1:] if i is not None),
            line=line,
            column=column,
        )

    def start(self, items: list[Any]) -> ZoneMap:
        cell = None
        cell_at: tuple[int | None, int | None] = (None, None)
        active = None
        active_at: tuple[int | None, int | None] = (None, None)
        walls, zones, tools, phases = [], [], [], []
        for it in items:
            if isinstance(it, Wall):
                walls.append(it)
            elif isinstance(it, Zone):
                zones.append(it)
            elif isinstance(it, Tool):
                tools.append(it)
            elif isinstance(it, Phase):
                phases.append(it)
            elif it.value[0] == "cell":
                if cell is not None:
                    raise SDLError(
                        "the cell bounds are given twice",
                        filename=self.filename,
                        line=it.line,
                        column=it.column,
                    )
                cell = (it.value[1], it.value[2])
                cell_at = (it.line, it.column)
            else:
                if active is not None:
                    raise SDLError(
                        "the active set is given twice",
                        filename=self.filename,
                        line=it.line,
                        column=it.column,
                    )
                active = it.value[1]
                active_at = (it.line, it.column)
        if cell is None:
            raise SDLError(
                "no cell bounds: start with 'cell (xmin, ymin, zmin) (xmax, ymax, zmax)'",
                filename=self.filename,
                line=1,
                column=1,
            )
        return ZoneMap(
            cell,
            tuple(zones),
            tuple(walls),
            tuple(tools),
            active,
            tuple(phases),
            filename=self.filename,
            active_line=active_at[0],
            active_column=active_at[1],
            cell_line=cell_at[0],
            cell_column=cell_at[1],
        )


def parse_sdl(text: str, filename: str | None = None) -> ZoneMap:
    """Parse an SDL text into a :class:`ZoneMap`.

    Parameters
    ----------
    text : str
        The SDL source.
    filename : str, optional
        Shown in error messages; its folder is where relative mesh paths are
        looked up (the current folder when not given).

    Returns
    -------
    ZoneMap

    Raises
    ------
    SDLSyntaxError
        The text does not follow the grammar (``filename``, ``line``,
        ``column`` and the ``expected`` tokens).
    SDLError
        A grammatical text with a wrong element (duplicate or unknown name,
        empty or degenerate volume, zone outside the cell, non-finite number,
        tool rack inside an exclusive zone...), located at the element.

    Examples
    --------
    >>> parse_sdl("cell (0,0,0) (1,1,1)\\nzone a exclusive box (0,0,0) (1,1)", "c.sdl")
    Traceback (most recent call last):
    ...
    multiarm.errors.SDLSyntaxError: c.sdl:2:34: unexpected ')' (expected ',')
    """
    base = os.path.dirname(os.path.abspath(filename)) if filename else os.getcwd()
    try:
        zm = parse_text(_parser(), text, filename, SDLSyntaxError, _Build(filename, base))
    except ValidationError as exc:  # pragma: no cover - records raise SDLError
        raise SDLError(str(exc), filename=filename) from None
    assert isinstance(zm, ZoneMap)
    return zm


def load_sdl(path: str | PathLike[str]) -> ZoneMap:
    """Read and parse an ``.sdl`` file (errors name the file)."""
    text = read_source(path, SDLError, "SDL")
    return parse_sdl(text, fspath(path))


# ----------------------------------------------------------------- printing


def _vec(v: Point3) -> str:
    return "(" + ", ".join(fmt_float(x) for x in v) + ")"


def _shape(s: Shape, indent: str) -> str:
    if isinstance(s, AABox):
        return f"box {_vec(s.lo)} {_vec(s.hi)}"
    if isinstance(s, OBox):
        text = f"box center {_vec(s.center)} size {_vec(s.size)}"
        if s.yaw != 0.0:
            text += f" yaw {fmt_float(s.yaw)}"
        return text
    if isinstance(s, Cylinder):
        return f"cylinder {_vec(s.base)} radius {fmt_float(s.radius)} height {fmt_float(s.height)}"
    if isinstance(s, Sphere):
        return f"sphere {_vec(s.center)} radius {fmt_float(s.radius)}"
    if isinstance(s, Hull):
        return "hull { " + ", ".join(_vec(p) for p in s.points) + " }"
    if isinstance(s, HalfSpaces):
        return "walls { " + ", ".join(("+" if sg > 0 else "-") + n for n, sg in s.sides) + " }"
    if isinstance(s, MeshShape):
        return f"mesh {quote(s.path)}"
    inner = indent + "    "
    parts = "\n".join(inner + _shape(p, inner) for p in s.parts)
    return "union {\n" + parts + "\n" + indent + "}"


def _wall(w: Wall) -> str:
    for axis, name in enumerate("xyz"):
        unit = [0.0, 0.0, 0.0]
        unit[axis] = 1.0
        others = [w.point[i] for i in range(3) if i != axis]
        if tuple(w.normal) == tuple(unit) and others == [0.0, 0.0]:
            return f"wall {w.name} {name} = {fmt_float(w.point[axis])}"
    return f"wall {w.name} point {_vec(w.point)} normal {_vec(w.normal)}"


def print_sdl(zm: ZoneMap) -> str:
    """SDL text for ``zm``; ``parse_sdl(print_sdl(zm)) == zm``."""
    out = [f"cell {_vec(zm.bounds[0])} {_vec(zm.bounds[1])}"]
    if zm.walls:
        out.append("")
        out.extend(_wall(w) for w in zm.walls)
    if zm.zones:
        out.append("")
    for z in zm.zones:
        line = f"zone {z.name} {z.policy} {_shape(z.shape, '')}"
        if z.speed_limit is not None:
            line += f" speed_limit {fmt_float(z.speed_limit)}"
        out.append(line)
    if zm.tools:
        out.append("")
        out.extend(f"tool {t.name} rack {_vec(t.rack)}" for t in zm.tools)
    if zm.active is not None:
        out.append("")
        out.append(f"active {{ {', '.join(zm.active)} }}" if zm.active else "active { }")
    if zm.phases:
        out.append("")
        out.extend(
            f"phase {ph.name} {{ {', '.join(ph.zones)} }}" if ph.zones else f"phase {ph.name} {{ }}"
            for ph in zm.phases
        )
    return "\n".join(out) + "\n"
