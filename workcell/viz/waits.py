"""Where arms waited, and where the space-grid blocks are.

The compile cuts the space two or more arms can reach into cubic blocks,
each an implicit exclusive zone named ``grid_X_Y_Z`` (:mod:`workcell.geometry.reach`,
SEEDS.md S2.5, S2.12): a cell has tens to hundreds of them. The plots draw
them as one lane, ``space grid (N blocks)``; this module gives their
coordinates (:func:`block_bounds`, :func:`space_grid_table`) and a summary of
a run's waits that names the SDL zones first, then the tools, then the space
grid as one row with its worst block's coordinates (:func:`wait_summary`).

Examples
--------
>>> grid_block("grid_3_m1_0")
(3, -1, 0)
>>> block_bounds("grid_3_m1_0", size=0.5)
((1.5, -0.5, 0.0), (2.0, 0.0, 0.5))
>>> grid_block("fixture") is None
True
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from multiarm.errors import ValidationError
from workcell.geometry.reach import Point, block_bounds, grid_block

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "ZoneWait",
    "block_bounds",
    "grid_block",
    "grid_lane_label",
    "space_grid_table",
    "wait_summary",
]


def _zone_names(source: Any) -> tuple[str, ...]:
    p = getattr(source, "problem", source)
    names = getattr(p, "zone_names", None)
    if names is None:
        raise ValidationError(
            f"expected a Problem, a CompiledCell or a run, not {type(source).__name__}"
        )
    return tuple(str(z) for z in names)


def grid_lane_label(n_blocks: int) -> str:
    """The label of the one lane (or row) of all space-grid blocks."""
    return f"space grid ({n_blocks} block{'s' if n_blocks != 1 else ''})"


def space_grid_table(source: Any, result: Any = None, *, size: float | None = None) -> pd.DataFrame:
    """One row per space-grid block: where it is, and how it was used.

    Parameters
    ----------
    source : Problem, CompiledCell or simulation result
        Whose zones to list.
    result : simulation result, optional
        A run: adds each block's executed occupancy and the waits at its
        borders (from ``reservations_frame()`` and ``metrics.zone_wait``).
    size : float, optional
        Block side, metres (default the compile's).

    Returns
    -------
    pandas.DataFrame
        Columns ``block, i, j, k, x_min, x_max, y_min, y_max, z_min, z_max``
        (metres), and with ``result`` ``occupied`` and ``wait`` (seconds);
        in the problem's zone order (empty when the cell has no space grid).
    """
    import pandas as pd

    if size is None:  # the grid the cell was compiled with, when the source says
        g = getattr(getattr(source, "options", None), "grid", None)
        if g is None:
            g = getattr(getattr(source, "cell", None), "grid", None)
        size = float(g) if isinstance(g, int | float) and g > 0 else None
    rows = []
    for name in _zone_names(source):
        idx = grid_block(name)
        if idx is None:
            continue
        lo, hi = block_bounds(name, size)
        rows.append(
            {
                "block": name,
                "i": idx[0],
                "j": idx[1],
                "k": idx[2],
                "x_min": lo[0],
                "x_max": hi[0],
                "y_min": lo[1],
                "y_max": hi[1],
                "z_min": lo[2],
                "z_max": hi[2],
            }
        )
    cols = ["block", "i", "j", "k", "x_min", "x_max", "y_min", "y_max", "z_min", "z_max"]
    df = pd.DataFrame(rows, columns=cols)
    if result is not None:
        res = result.reservations_frame()
        res = res[res["resource"].isin(set(df["block"]))]
        held = (res["end"] - res["start"]).groupby(res["resource"]).sum()
        waits: Mapping[str, float] = result.metrics.zone_wait
        df["occupied"] = [float(held.get(b, 0.0)) for b in df["block"]]
        df["wait"] = [float(waits.get(b, 0.0)) for b in df["block"]]
    return df


@dataclass(frozen=True, slots=True)
class ZoneWait:
    """Waits at the borders of one SDL zone, one tool, or the whole space grid.

    Attributes
    ----------
    kind : {"zone", "tool", "grid"}
    label : str
        The zone's or tool's name, or ``"space grid (N blocks)"``.
    seconds : float
        Seconds stopped at borders needing it; for the grid, at its worst
        block (a stop where several blocks are entered counts for each of
        them in ``Metrics.zone_wait``, so a sum over blocks would count it
        many times; the worst block's wait is a lower bound of the time
        stopped for the grid).
    blocks : int
        For the grid, how many of its blocks were waited at (else 0).
    worst : str or None
        For the grid, the block waited at longest.
    worst_bounds : ((3,) float, (3,) float) or None
        Lower and upper corner of ``worst``, metres.
    """

    kind: Literal["zone", "tool", "grid"]
    label: str
    seconds: float
    blocks: int = 0
    worst: str | None = None
    worst_bounds: tuple[Point, Point] | None = None

    def __str__(self) -> str:
        if self.kind != "grid":
            prefix = "tool " if self.kind == "tool" else ""
            return f"{prefix}{self.label}: {self.seconds:.2f} s"
        lo, hi = self.worst_bounds or ((0.0,) * 3, (0.0,) * 3)
        where = ", ".join(f"{c} {a:.2f}..{b:.2f}" for c, a, b in zip("xyz", lo, hi, strict=True))
        return (
            f"{self.label}: waits at {self.blocks} block{'s' if self.blocks != 1 else ''}, "
            f"longest {self.seconds:.2f} s at {self.worst} ({where} m)"
        )


def wait_summary(
    result: Any,
    problem: Any = None,
    *,
    size: float | None = None,
    min_seconds: float = 0.005,
) -> tuple[ZoneWait, ...]:
    """A run's waits at zone borders: SDL zones first, then tools, then the space grid.

    Parameters
    ----------
    result : simulation result
        Read through ``metrics.zone_wait`` (seconds per zone and tool).
    problem : Problem or CompiledCell, optional
        Names the zones and tools and counts the grid's blocks (default: the
        run's own ``problem``).
    size : float, optional
        Space-grid block side, metres (default the compile's).
    min_seconds : float
        Leave out waits shorter than this (the summary prints hundredths).

    Returns
    -------
    tuple of ZoneWait
        SDL zones by decreasing wait, then tools likewise, then one row for
        all space-grid blocks (``"space grid (N blocks)"``, N the blocks of
        the problem) with how many were waited at, the worst block, its wait
        and its coordinates, when any block was waited at. ``str()`` of a row is one line of text.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> run = NS(metrics=NS(zone_wait={"grid_1_0_0": 2.0, "fixture": 1.5, "grid_0_0_0": 0.5}))
    >>> p = NS(zone_names=("fixture", "grid_0_0_0", "grid_1_0_0", "grid_2_0_0"), tool_names=())
    >>> for row in wait_summary(run, p, size=0.3):
    ...     print(row)
    fixture: 1.50 s
    space grid (3 blocks): waits at 2 blocks, longest 2.00 s at grid_1_0_0 (x 0.30..0.60, y 0.00..0.30, z 0.00..0.30 m)
    """
    src = problem if problem is not None else result
    zone_names = _zone_names(src)
    p = getattr(src, "problem", src)
    tool_names = {str(k) for k in getattr(p, "tool_names", ())}
    waits = {str(z): float(w) for z, w in result.metrics.zone_wait.items()}
    unknown = sorted(set(waits) - set(zone_names) - tool_names)
    if unknown:
        raise ValidationError(f"the run waited at {unknown[0]!r}, which the problem does not have")
    n_blocks = sum(grid_block(z) is not None for z in zone_names)
    zones = [
        ZoneWait("zone", z, w)
        for z, w in waits.items()
        if z in zone_names and grid_block(z) is None and w >= min_seconds
    ]
    tools = [
        ZoneWait("tool", k, w) for k, w in waits.items() if k in tool_names and w >= min_seconds
    ]
    out = sorted(zones, key=lambda r: (-r.seconds, r.label))
    out += sorted(tools, key=lambda r: (-r.seconds, r.label))
    grid = {z: w for z, w in waits.items() if grid_block(z) is not None and w >= min_seconds}
    if grid:
        worst = min(grid, key=lambda z: (-grid[z], z))
        out.append(
            ZoneWait(
                "grid",
                grid_lane_label(n_blocks),
                grid[worst],
                blocks=len(grid),
                worst=worst,
                worst_bounds=block_bounds(worst, size),
            )
        )
    return tuple(out)
