"""The S2.3 pipeline: offset, ring buffer, and the sampling-period loop.

Computing, checking and executing are pipelined: while point ``i`` is
computed, point ``i - 1`` is checked and point ``i - offset`` is executed,
in a ring buffer of ``offset + 2`` points at the sampling period ``T``.
``offset`` is derived from the arm's top speed and its steepest allowed
stop: ``offset = ceil(t_stop / T)`` with ``t_stop`` the longest time any
joint needs to stop from its top speed (stepper: along ``stop_accel``,
S1.5; servo: at its acceleration limit). So a conflict seen at the checked
point leaves the arm time to stop before it executes that point: the
controller asks for a zone ``offset * T`` seconds (the *lookahead*) before
it reaches the zone's border, and an arm not granted the zone by then stops
at the border (S2.6) until woken.

At event level (the default) only the points that matter are events: the
lookahead point of each border, the border, the ends of zone windows and
the end of the trajectory; idle time is skipped. With a sampling period
(``tick``), a :class:`Ticker` runs the pipeline every tick for every moving
arm (one kernel event per tick for the whole cell, as the centralized
controller of S2.2 would), computing each point, checking it, and keeping
the ring buffer; the decisions are the same as at event level.

Motion between events follows the compiled trajectories exactly (closed-form
drive profiles, never a stepper pulse per event). Stops are modelled as
pauses of the trajectory clock at the stopping point.

Examples
--------
>>> from workcell.arms.profiles import StepperDrive
>>> pipeline_offset([StepperDrive()], 1e-3)
132
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray
from workcell.arms.profiles import Drive, ServoDrive, StepperDrive
from workcell.sim.events.loop import EventLoop, Handle

_Self = Any
"""The :class:`~workcell.sim.control.controller.ArmController` whose method
:func:`pipeline_step` is (bound in its class body; typed loosely here: the
controller imports this module, never the reverse)."""


class Stepped(Protocol):
    """What the tick loop drives: an arm that may be moving and steps its pipeline."""

    running: bool

    def pipeline_step(self) -> None:
        """One sampling period of the pipeline."""


__all__ = [
    "INTERNAL_MESSAGES",
    "Ticker",
    "flush_ring",
    "pipeline_offset",
    "pipeline_step",
    "ring_points",
    "stop_time",
]


INTERNAL_MESSAGES: tuple[str, ...] = (
    "STOP_D",
    "TRAJECTORY_END",
    "TRAJECTORY_POINT",
    "STOP_C",
    "TRAJECTORY",
    "CONTINUE",
)
"""The six messages between an arm's two processors (S2.3)."""


def stop_time(drive: Drive) -> float:
    """Seconds a joint needs to stop from its top speed along its steepest
    allowed deceleration (stepper: ``stop_accel``, S1.5; servo: its
    acceleration limit).

    Examples
    --------
    >>> round(stop_time(StepperDrive()), 6)
    0.13125
    >>> stop_time(ServoDrive(1.0, 4.0))
    0.25
    """
    if isinstance(drive, StepperDrive):
        return drive.stop_time(drive.max_rate)
    if isinstance(drive, ServoDrive):
        return drive.max_velocity / drive.max_acceleration
    return 0.0


def pipeline_offset(drives: Sequence[Drive], period: float) -> int:
    """The pipeline offset (points) of S2.3: ``ceil(t_stop / period)``, at least 1.

    Parameters
    ----------
    drives : sequence of Drive
    period : float
        Sampling period, seconds (> 0).

    Returns
    -------
    int

    Raises
    ------
    ValidationError
        For a non-positive period.
    """
    if not (period > 0 and math.isfinite(period)):
        raise ValidationError(f"sampling period must be > 0 seconds, got {period!r}")
    t = max((stop_time(d) for d in drives), default=0.0)
    return max(1, math.ceil(t / period - 1e-9))


class Ticker:
    """The sampling-period loop (S2.2, S2.3): every tick while any arm
    moves, running every moving arm's compute/check/execute step (the ticks
    between two other callbacks in one kernel callback:
    :meth:`~workcell.sim.events.loop.EventLoop.advance`).

    Parameters
    ----------
    kernel : EventLoop
    period : float
        Seconds.
    """

    def __init__(self, kernel: EventLoop, period: float) -> None:
        self.kernel = kernel
        self.period = float(period)
        self.arms: list[Stepped] = []
        self.ticks = 0
        self._handle: Handle | None = None

    def wake(self) -> None:
        """Make sure the loop runs (an arm started moving)."""
        if self._handle is None:
            now = self.kernel.now
            k = math.floor(now / self.period + 1e-9) + 1
            self._handle = self.kernel.schedule(k * self.period, self._tick, k, absolute=True)

    def _tick(self, k: int) -> None:
        # the ticks up to the next other callback run here, one after the
        # other (EventLoop.advance), the rest through the heap
        self._handle = None
        arms = self.arms
        kernel = self.kernel
        period = self.period
        while True:
            any_moving = False
            for arm in arms:
                if arm.running:
                    arm.pipeline_step()
                    any_moving = True
            if not any_moving:
                return
            self.ticks += 1
            k += 1
            if not kernel.advance(k * period):
                self._handle = kernel.schedule(k * period, self._tick, k, absolute=True)
                return


def pipeline_step(self: _Self) -> None:
    """One sampling period (S2.3): compute point i, check point i - 1,
    execute point i - offset (the ring buffer holds offset + 2 points).

    The points are computed a chunk at a time (one trajectory sample call
    for the next 64 ticks) and enter the ring buffer when a chunk is done or
    the ring is read (:func:`ring_points`): per tick, only the pipeline's
    counters move."""
    leg = self.leg
    if leg is None:
        return
    i = self._chunk_i
    if i >= len(self._chunk):
        flush_ring(self)
        tau = self.current_tau() + self.lookahead
        self._chunk = leg.trajectory.sample(tau + self.period * np.arange(64, dtype=np.float64))
        self._chunk_at = self._pipe_i
        self._chunk_done = 0
        i = 0
    self._chunk_i = i + 1
    self._pipe_i += 1
    self.points_checked += 1


def flush_ring(self: _Self) -> None:
    """Put the points computed since the last flush into the ring buffer
    (point ``j`` at slot ``j % len(ring)``), as the ticks would have one by one."""
    ring = self._ring
    size = len(ring)
    done = self._chunk_done
    upto = min(self._chunk_i, len(self._chunk))
    if upto <= done:
        return
    lo = max(done, upto - size)  # earlier points are overwritten anyway
    j = self._chunk_at + np.arange(lo, upto)
    ring[j % size] = self._chunk[lo:upto]
    self._chunk_done = upto


def ring_points(self: _Self) -> FloatArray:
    """The ring buffer (offset + 2 points, point ``i`` at slot ``i % len``) as
    the ticks so far have filled it."""
    flush_ring(self)
    ring: FloatArray = self._ring
    return ring
