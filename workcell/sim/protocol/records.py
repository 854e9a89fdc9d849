"""The motion records an arm controller publishes (S2.1: the monitor's only input).

Each controller owns one :class:`MotionLog` and appends to it; the safety
monitor, the metrics and :class:`~workcell.sim.harness.simulate.SimResult`
read the logs and nothing else of a controller: closed :class:`MotionRecord`
segments, the :class:`TaskRecord` of every task the arm started, when it
failed, and the segment in progress (``MotionLog.open_record``).

Examples
--------
>>> import numpy as np
>>> r = MotionRecord(0.0, 2.0, None, 0.0, False, np.zeros(2))
>>> r.joints_at(np.array([0.5, 1.5])).tolist()
[[0.0, 0.0], [0.0, 0.0]]
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from multiarm.types import FloatArray
from workcell.sim.protocol.messages import Leg

__all__ = ["MotionLog", "MotionRecord", "TaskRecord"]


@dataclass(frozen=True, slots=True)
class MotionRecord:
    """One segment of an arm's executed motion (frozen).

    Attributes
    ----------
    start, end : float
        Seconds.
    leg : Leg or None
        The leg followed; ``None`` while the arm stands idle.
    tau0 : float
        Progress in the leg at ``start``, seconds.
    moving : bool
        The leg's clock runs (else the arm stands at ``tau0``).
    joints : (dof,) float
        Idle: the standing joints. On a leg: the offset of the actual joints
        from the leg's (lost stepper steps, S1.6; zero otherwise).
    """

    start: float
    end: float
    leg: Leg | None
    tau0: float
    moving: bool
    joints: FloatArray

    def joints_at(self, times: FloatArray) -> FloatArray:
        """(N, dof) actual joints at ``times`` (seconds, within the record)."""
        if self.leg is None:
            return np.repeat(np.asarray(self.joints, dtype=float)[None, :], len(times), axis=0)
        tau = self.tau0 + (times - self.start) if self.moving else np.full(len(times), self.tau0)
        out: FloatArray = self.leg.trajectory.sample(tau) + self.joints
        return out


@dataclass(frozen=True, slots=True)
class TaskRecord:
    """A task as its arm executed it (frozen; replaced as the task goes on).

    Attributes
    ----------
    task, mode : int
    start : float
        When the arm left the task's start station, seconds.
    end : float
        When its trajectory ended; ``math.inf`` while it runs.
    waits : tuple of (int, float)
        ``(border, seconds)`` waited at the mode's zone borders.
    """

    task: int
    mode: int
    start: float
    end: float = math.inf
    waits: tuple[tuple[int, float], ...] = ()

    @property
    def finished(self) -> bool:
        """The trajectory ended."""
        return math.isfinite(self.end)


@dataclass(slots=True, eq=False)
class MotionLog:
    """One arm's publication: its motion and task records, append-only.

    Parameters
    ----------
    index : int
        Arm index.
    name : str
    home_q : (dof,) float
        The joints the arm starts at (and is taken to when it fails).
    open_record : callable
        ``open_record(now)`` -> the :class:`MotionRecord` in progress as it
        would be closed at ``now``.
    state : callable
        ``state()`` -> a hashable value that changes whenever the record in
        progress changes (the live monitor caches by it).
    moving : callable
        ``moving()`` -> whether the arm's trajectory clock runs now.

    Attributes
    ----------
    records : list of MotionRecord
        Closed segments in time order.
    tasks : dict of int -> TaskRecord
        The tasks the arm started.
    failed_at : float
        When the arm failed (``inf``: it did not).
    """

    index: int
    name: str
    home_q: FloatArray
    open_record: Callable[[float], MotionRecord]
    state: Callable[[], object]
    moving: Callable[[], bool]
    records: list[MotionRecord] = field(default_factory=list)
    tasks: dict[int, TaskRecord] = field(default_factory=dict)
    failed_at: float = math.inf

    @property
    def failed(self) -> bool:
        """The arm failed."""
        return math.isfinite(self.failed_at)

    def end_time(self) -> float:
        """End of the last closed record (0 without records)."""
        return self.records[-1].end if self.records else 0.0
