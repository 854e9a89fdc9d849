"""What the setup and timing modules read of a problem, as a structural type.

:class:`scheduler.Problem` holds a :class:`~scheduler.setup.Setup` and the
:class:`~scheduler.timing.Shapes` of its modes; both of those read the
problem back. Typing them against :class:`ProblemView` instead of the
``Problem`` class keeps the import graph free of circles (the problem
imports setup and timing, never the other way round); ``Problem``
satisfies the protocol structurally (checked by mypy wherever a problem is
passed, and by ``tests/test_no_cycles.py``).
"""

from __future__ import annotations

from typing import Protocol

from multiarm.types import BoolArray, FloatArray, IntArray

__all__ = ["ProblemView"]


class ProblemView(Protocol):
    """The read-only part of :class:`scheduler.Problem` that setups and mode
    shapes use (arrays indexed by task, arm, mode, window, zone, tool)."""

    @property
    def n_arms(self) -> int: ...

    @property
    def n_tasks(self) -> int: ...

    @property
    def n_modes(self) -> int: ...

    @property
    def n_zones(self) -> int: ...

    @property
    def mode_task(self) -> IntArray: ...

    @property
    def mode_arm(self) -> IntArray: ...

    @property
    def mode_duration(self) -> FloatArray: ...

    @property
    def mode_of(self) -> IntArray: ...

    @property
    def mode_windows(self) -> tuple[tuple[int, ...], ...]: ...

    @property
    def mode_tools(self) -> tuple[tuple[int, ...], ...]: ...

    @property
    def win_zone(self) -> IntArray: ...

    @property
    def win_start(self) -> FloatArray: ...

    @property
    def win_end(self) -> FloatArray: ...

    @property
    def win_move(self) -> BoolArray: ...

    @property
    def zone_names(self) -> tuple[str, ...]: ...

    @property
    def zone_exclusive(self) -> BoolArray: ...

    @property
    def tool_names(self) -> tuple[str, ...]: ...

    @property
    def task_names(self) -> tuple[str, ...]: ...

    @property
    def arm_names(self) -> tuple[str, ...]: ...

    def setup_row(self, arm: int, prev: int) -> FloatArray:
        """Setup times from ``prev`` (-1: the arm's start) to every task."""
        ...

    def mode_borders(self, m: int) -> tuple[float, ...]:
        """Offsets of mode ``m``'s zone borders, seconds from its start."""
        ...
