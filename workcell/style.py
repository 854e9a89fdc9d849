"""One look for every plot of a run: arm colours and fault marks.

Every plot of :mod:`workcell.viz.plots` (Gantt chart, zone timeline, the
cell at chosen instants, joint curves, motion frames) colours an arm with
:func:`arm_colours`, keyed by arm name in the problem's arm order, so an arm
has the same colour everywhere. Faults read from a run's trace are drawn
with one marker per kind (:data:`FAULT_MARKS`, :func:`fault_kind`).

Examples
--------
>>> c = arm_colours(["left", "right"])
>>> list(c), c["left"] != c["right"]
(['left', 'right'], True)
>>> arm_colours(["right", "left"])["left"] == c["right"]  # by position in the arm order
True
>>> from workcell.sim.events.trace import TraceEvent
>>> fault_kind(TraceEvent(3.0, "fault", arm="left", detail="arm failure"))
'arm_failure'
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from multiarm.errors import ValidationError

__all__ = ["FAULT_MARKS", "FaultMark", "arm_colours", "arm_order", "fault_kind"]

RGBA = tuple[float, float, float, float]

# tab10 without its red (kept for faults and failed tasks) and grey (kept for
# "unknown arm"), then those two: arms 1-8 never look like a fault
_TAB10_ORDER = (0, 1, 2, 4, 5, 6, 8, 9, 3, 7)


def arm_order(source: Any) -> tuple[str, ...]:
    """Arm names, in the problem's order, from whatever a plot was given.

    Parameters
    ----------
    source : sequence of str, or an object with ``arm_names`` (a
        :class:`scheduler.Problem`), a ``problem`` (a
        :class:`~workcell.CompiledCell` or a simulation result), or ``arms``
        with names (a :class:`~workcell.Cell`)

    Returns
    -------
    tuple of str
    """
    if hasattr(source, "arm_names"):
        return tuple(str(a) for a in source.arm_names)
    if hasattr(source, "problem") and hasattr(source.problem, "arm_names"):
        return tuple(str(a) for a in source.problem.arm_names)
    if hasattr(source, "arms") and all(hasattr(a, "name") for a in source.arms):
        return tuple(str(a.name) for a in source.arms)
    if isinstance(source, str) or not isinstance(source, Sequence):
        raise ValidationError(
            f"expected arm names, a Problem, a CompiledCell, a Cell or a run, "
            f"not {type(source).__name__}"
        )
    names = tuple(str(a) for a in source)
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise ValidationError(f"arm {dup!r} is named twice")
    return names


def arm_colours(arms: Any) -> dict[str, RGBA]:
    """The colour of each arm, the same in every plot of a run.

    Parameters
    ----------
    arms : sequence of str, Problem, CompiledCell, Cell or simulation result
        The arms in the problem's order (see :func:`arm_order`): an arm's
        colour depends only on its position in that order.

    Returns
    -------
    dict of arm name -> RGBA (floats in [0, 1])
        Up to 8 arms: tab10 without its red and grey (red marks faults and
        failed tasks); up to 20: tab20; more: evenly spaced on ``turbo``.
    """
    from matplotlib import colormaps

    names = arm_order(arms)
    n = len(names)
    if n <= len(_TAB10_ORDER):
        cmap = colormaps["tab10"]
        cols = [cmap(_TAB10_ORDER[i]) for i in range(n)]
    elif n <= 20:
        cmap = colormaps["tab20"]
        cols = [cmap(i) for i in range(n)]
    else:
        cmap = colormaps["turbo"]
        cols = [cmap(0.05 + 0.9 * i / (n - 1)) for i in range(n)]
    return {name: tuple(float(v) for v in c) for name, c in zip(names, cols, strict=True)}  # type: ignore[misc]


@dataclass(frozen=True, slots=True)
class FaultMark:
    """How one kind of fault is drawn: a matplotlib marker and a legend label."""

    marker: str
    label: str
    size: float = 9.0


FAULT_MARKS: dict[str, FaultMark] = {
    "arm_failure": FaultMark("X", "arm failure"),
    "crash": FaultMark("*", "crash", 11.0),
    "lost_sync": FaultMark("D", "lost synchronism (steps lost)", 7.0),
    "message_loss": FaultMark("v", "message lost or dropped, sent again", 5.0),
    "late_part": FaultMark("s", "late part", 7.0),
    "emergency_stop": FaultMark("o", "emergency stop", 8.0),
    "zone_activation": FaultMark("^", "zone activation", 8.0),
    "other": FaultMark("P", "other fault", 8.0),
}
"""Marker and legend label per fault kind (the ``kind`` of the fault records
of :mod:`workcell.sim.harness.faults`, ``"zone_activation"`` for
``activate_zones``, ``"other"`` for a fault record the plots do not know)."""


def fault_kind(event: Any) -> str | None:
    """The kind of fault a trace record starts, or None.

    Parameters
    ----------
    event : workcell.sim.events.trace.TraceEvent
        A record of a run's trace.

    Returns
    -------
    str or None
        A key of :data:`FAULT_MARKS`; None for records that start no fault:
        the end of an emergency stop, the coordinator being told of a reflex
        stop after the fact, the homing that follows lost steps (they belong
        to a fault already marked), and records of other kinds than
        ``"fault"`` except a zone activation (a ``"grant"`` record of the
        active zones, S2.5).
    """
    detail = str(getattr(event, "detail", "") or "")
    kind = getattr(event, "kind", None)
    if kind == "grant":
        return "zone_activation" if detail.startswith("active zones") else None
    if kind != "fault":
        return None
    if detail == "arm failure":
        return "arm_failure"
    if detail.startswith("crash"):
        return "crash"
    if detail.startswith("axis ") and "lost" in detail:
        return "lost_sync"
    if detail.startswith(("message lost", "dropped by the medium")):
        return "message_loss"
    if detail.startswith("part "):
        return "late_part"
    if detail.startswith("emergency stop for"):
        return "emergency_stop"
    if detail.startswith(("emergency stop cleared", "coordinator told of", "position error")):
        return None
    return "other"
