"""The records of a compile: its options and one compiled mode.

:class:`CompileOptions` are the settings of :func:`workcell.compile_cell`
(the space grid, detours, sampling and the detour planner's limits);
:class:`CompiledMode` is one (task, arm) mode with everything the simulator
needs to execute it. Both live here, apart from :mod:`workcell.compile` and
:mod:`workcell.oracle`, so that the oracle can read compiled modes without
importing the compile that builds it.

Examples
--------
>>> CompileOptions(grid=0.45).grid
0.45
>>> CompileOptions(grid=-1.0)
Traceback (most recent call last):
...
multiarm.errors.UsageError: CompileOptions.grid must be a finite number >= 0 (0: off) or None (the cell's own), got -1.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal

from multiarm.errors import UsageError
from multiarm.types import JointVector
from scheduler import Window
from workcell.arms import JointTrajectory

__all__ = ["GRID_PADDING", "LINEAR_STEP", "SPACE_GRID", "CompileOptions", "CompiledMode"]

SPACE_GRID = 0.3
"""Default block side (metres) of the space-grid zones that keep arms apart
(:mod:`workcell.geometry.reach`), the cell file's ``[compile] grid``: coarser
blocks give fewer zones and a faster search but keep apart more pairs of
modes than needed (S2.12). docs/workcell.md gives the measured trade-off."""

GRID_PADDING = 0.02
"""Default sweep padding (metres) against the space-grid blocks, when the
cell's own padding is finer: fewer samples, windows conservative by this much."""

LINEAR_STEP = 0.02
"""Default longest Cartesian step (metres) between inverse-kinematics
solutions on a straight-line move: the joint path between them is
interpolated in joint space, so the tool leaves the line by a small fraction
of this."""


def _number(name: str, value: object, *, low: float, strict: bool) -> None:
    ok = (
        not isinstance(value, bool)
        and isinstance(value, int | float)
        and math.isfinite(value)
        and (value > low if strict else value >= low)
    )
    if not ok:
        rel = ">" if strict else ">="
        raise UsageError(
            f"CompileOptions.{name} must be a finite number {rel} {low}, got {value!r}"
        )


@dataclass(frozen=True, slots=True)
class CompileOptions:
    """Settings of :func:`workcell.compile_cell`.

    ``None`` in :attr:`grid` and :attr:`plan_with` means the cell's own
    choice (its file's ``[compile]`` table); every other field applies to
    any cell. The progress callback is not an option: it is the separate
    ``progress=`` keyword of :func:`~workcell.compile_cell`, so that options
    stay plain, comparable values that can be recorded with a result.

    Attributes
    ----------
    grid : float or None
        Space-grid block side, metres (:mod:`workcell.geometry.reach`):
        every block that modes of two arms touch becomes an exclusive zone,
        so moving arms never meet outside the SDL zones. ``0`` turns the
        grid off (arms are then kept apart only by the SDL zones and the
        parked-arm oracle: a plan may let two moving arms collide).
        ``None``: the cell's ``[compile] grid`` (default :data:`SPACE_GRID`).
    detours : bool
        Whether the blocking oracle plans OMPL detours around a parked arm
        (S2.6). ``False``: a mode that touches a parked arm costs ``inf``
        (blocked) without any planning.
    plan_with : {"nominal", "worst"} or None
        Mode durations from nominal or worst-case insertions; ``None``: the
        cell's own choice.
    linear_step : float
        :data:`LINEAR_STEP`, metres (> 0).
    grid_padding : float
        :data:`GRID_PADDING`, metres (> 0).
    contact_padding : float
        Contact padding and sampling step of the blocking oracle's checks,
        metres (> 0; at least the cell's padding is used).
    detour_budget : float
        Wall-clock limit of one detour search, seconds (> 0).
    detour_max_checks : int
        Work limit of one detour search, configurations checked (>= 1): the
        binding limit on any machine, so answers are reproducible.
    detour_seed : int
        Seed of the detour planner (>= 0).

    Raises
    ------
    UsageError
        A field out of range, naming it.
    """

    grid: float | None = None
    detours: bool = True
    plan_with: Literal["nominal", "worst"] | None = None
    linear_step: float = LINEAR_STEP
    grid_padding: float = GRID_PADDING
    contact_padding: float = 0.02
    detour_budget: float = 2.0
    detour_max_checks: int = 2_000
    detour_seed: int = 0

    def __post_init__(self) -> None:
        g = self.grid
        if g is not None and (
            isinstance(g, bool)
            or not isinstance(g, int | float)
            or not (math.isfinite(g) and g >= 0)
        ):
            raise UsageError(
                "CompileOptions.grid must be a finite number >= 0 (0: off) or None "
                f"(the cell's own), got {g!r}"
            )
        if not isinstance(self.detours, bool):
            raise UsageError(f"CompileOptions.detours must be a bool, got {self.detours!r}")
        if self.plan_with not in (None, "nominal", "worst"):
            raise UsageError(
                "CompileOptions.plan_with must be 'nominal', 'worst' or None, "
                f"got {self.plan_with!r}"
            )
        for name in ("linear_step", "grid_padding", "contact_padding", "detour_budget"):
            _number(name, getattr(self, name), low=0.0, strict=True)
        for name in ("detour_max_checks", "detour_seed"):
            v = getattr(self, name)
            low = 1 if name == "detour_max_checks" else 0
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise UsageError(f"CompileOptions.{name} must be an int >= {low}, got {v!r}")

    def to_dict(self) -> dict[str, object]:
        """The fields as plain values (for provenance records)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True, slots=True)
class CompiledMode:
    """One (task, arm) mode with everything the simulator needs to execute it.

    Attributes
    ----------
    task, arm : str
    trajectory : JointTrajectory
        The timed joint path, from the task's start.
    q_start, q_end : (dof,) float
        Joint vectors at the task's start and end.
    windows : tuple of scheduler.Window
    tools : tuple of str
    flags_set, flags_waited : tuple of (flag, offset seconds)
    """

    task: str
    arm: str
    trajectory: JointTrajectory
    q_start: JointVector
    q_end: JointVector
    windows: tuple[Window, ...]
    tools: tuple[str, ...]
    flags_set: tuple[tuple[str, float], ...] = ()
    flags_waited: tuple[tuple[str, float], ...] = ()

    @property
    def duration(self) -> float:
        """Seconds from the task's start to its end."""
        return float(self.trajectory.duration)
