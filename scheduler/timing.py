"""How a mode unfolds in time, with waits at zone borders (S2.6, S2.12).

A mode's *borders* are the offsets in ``(0, duration)`` where one of its
windows starts. A schedule may make the arm wait ``w_b >= 0`` at each border
``b``: in the cell, an arm refused a zone stops at its border and goes on when
woken. With ``W<=(x)`` the sum of the waits at borders ``<= x`` and ``W<(x)``
at borders ``< x``, a task started at ``S``:

* holds an **exclusive** zone over ``[S + s + W<=(s), S + e + W<(e))`` for
  each window ``[s, e)`` in it — waiting inside the zone keeps it occupied
  (every window in an exclusive zone, ``occupy`` or ``move``, counts as
  presence);
* moves in a **shared** zone over the pieces of each ``move`` window between
  the borders inside it, *without* the waits: a waiting arm does not move,
  so it holds no movement right there;
* holds its **tools** from ``S`` to its end;
* ends at ``S + duration + sum(w) + c``, where ``c`` is the detour cost the
  blocking oracle charged (S2.6 geometric conflicts, added at the end).

The windows of one mode in one zone are merged first, so a mode reserves
each resource over disjoint intervals. Resources are numbered for the
solvers: exclusive zone ``z`` -> ``z``, movement of shared zone ``z`` ->
``Z + z``, tool ``k`` -> ``2Z + k``.
"""

from __future__ import annotations

import bisect
import itertools
from dataclasses import dataclass
from functools import cached_property

from multiarm.errors import InternalError
from multiarm.types import FloatArray
from scheduler.view import ProblemView

__all__ = ["ModeShape", "Shapes", "merge_intervals"]


def merge_intervals(iv: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Union of half-open intervals, sorted (touching intervals are joined)."""
    out: list[tuple[float, float]] = []
    for s, e in sorted(iv):
        if out and s <= out[-1][1]:
            if e > out[-1][1]:
                out[-1] = (out[-1][0], e)
        else:
            out.append((s, e))
    return out


@dataclass(frozen=True, slots=True)
class ModeShape:
    """The static structure of one mode, for timing it.

    Attributes
    ----------
    duration : float
    borders : tuple of float
        Wait points, increasing, in ``(0, duration)``.
    exclusive : tuple of (resource, s, e)
        Merged windows in exclusive zones (presence).
    moves : tuple of (resource, s, e)
        Merged move windows in shared zones.
    tools : tuple of int
        Tool resources held from start to end.
    """

    duration: float
    borders: tuple[float, ...]
    exclusive: tuple[tuple[int, float, float], ...]
    moves: tuple[tuple[int, float, float], ...]
    tools: tuple[int, ...]

    def shift(self, waits: FloatArray | None, x: float, inclusive: bool) -> float:
        """Sum of the waits at borders ``<= x`` (inclusive) or ``< x``."""
        if waits is None or not len(self.borders):
            return 0.0
        total = 0.0
        for b, w in zip(self.borders, waits, strict=True):
            if b < x or (inclusive and b == x):
                total += w
        return total

    def intervals(
        self, start: float, waits: FloatArray | None = None
    ) -> list[tuple[int, float, float]]:
        """Actual ``(resource, start, end)`` reservations of zones (tools excluded)."""
        if waits is None or not self.borders or not any(waits.tolist()):  # no wait: as they are
            return [(r, start + s, start + e) for r, s, e in self.exclusive] + [
                (r, start + s, start + e) for r, s, e in self.moves
            ]
        # W<=(x) and W<(x) from prefix sums of the waits (borders increase):
        # the same additions in the same order as :meth:`shift`, in log time
        wl = waits.tolist()
        if len(wl) != len(self.borders):
            raise InternalError(f"{len(wl)} waits given for {len(self.borders)} borders")
        cw = [0.0]
        for w in wl:
            cw.append(cw[-1] + w)
        borders = self.borders
        out: list[tuple[int, float, float]] = []
        for r, s, e in self.exclusive:
            out.append(
                (
                    r,
                    start + s + cw[bisect.bisect_right(borders, s)],
                    start + e + cw[bisect.bisect_left(borders, e)],
                )
            )
        if not self.moves:
            return out
        wait_at = dict(zip(borders, wl, strict=True))
        for r, s, e in self.moves:
            cuts = [b for b in borders if s < b < e and wait_at[b] > 0]
            points = [s, *cuts, e]
            for p0, p1 in itertools.pairwise(points):
                out.append(
                    (
                        r,
                        start + p0 + cw[bisect.bisect_right(borders, p0)],
                        start + p1 + cw[bisect.bisect_left(borders, p1)],
                    )
                )
        return out

    def length(self, waits: FloatArray | None) -> float:
        """Duration plus waits (blocking cost excluded)."""
        return self.duration + (sum(waits.tolist()) if waits is not None and len(waits) else 0.0)


class Shapes:
    """The :class:`ModeShape` of every mode of a problem (computed once)."""

    def __init__(self, problem: ProblemView) -> None:
        self.problem = problem

    @cached_property
    def modes(self) -> tuple[ModeShape, ...]:
        p = self.problem
        Z = p.n_zones
        out = []
        for m in range(p.n_modes):
            d = float(p.mode_duration[m])
            excl: dict[int, list[tuple[float, float]]] = {}
            moves: dict[int, list[tuple[float, float]]] = {}
            for w in p.mode_windows[m]:
                z = int(p.win_zone[w])
                iv = (float(p.win_start[w]), float(p.win_end[w]))
                if p.zone_exclusive[z]:
                    excl.setdefault(z, []).append(iv)
                elif p.win_move[w]:
                    moves.setdefault(Z + z, []).append(iv)
            out.append(
                ModeShape(
                    d,
                    p.mode_borders(m),
                    tuple((r, s, e) for r in sorted(excl) for s, e in merge_intervals(excl[r])),
                    tuple((r, s, e) for r in sorted(moves) for s, e in merge_intervals(moves[r])),
                    tuple(2 * Z + k for k in p.mode_tools[m]),
                )
            )
        return tuple(out)

    def __getitem__(self, m: int) -> ModeShape:
        return self.modes[m]

    def resource_name(self, r: int) -> tuple[str, str]:
        """("zone" | "move" | "tool", name) of a resource number."""
        p = self.problem
        Z = p.n_zones
        if r < Z:
            return ("zone", p.zone_names[r])
        if r < 2 * Z:
            return ("move", p.zone_names[r - Z])
        return ("tool", p.tool_names[r - 2 * Z])
