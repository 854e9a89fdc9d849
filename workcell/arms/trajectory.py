"""Timed joint trajectories: rest-to-rest moves through joint waypoints, and dwells.

A :class:`JointTrajectory` is a sequence of **segments**, each starting and
ending at rest:

* a **move** between two joint vectors, either *synchronised* (every joint
  starts and stops together: the slowest joint's own profile sets the
  duration and the others are stretched in time; interpolated moves, S1.9)
  or *independent per axis* (every joint runs its drive's own fastest
  profile and the segment ends when the last one stops: the cheap moves of
  a Cartesian robot, S1.9);
* a **dwell**: no motion for a given time (grasp, release, tool use, ...).

Between two consecutive knot times (segment boundaries) every joint moves
monotonically from its start value to its end value, because every profile
is rest to rest with a non-negative speed. The conservative zone sweep
(:mod:`workcell.geometry.zone_sweep`) relies on this.

Examples
--------
>>> import numpy as np
>>> from workcell.arms.profiles import ServoDrive
>>> drives = (ServoDrive(1.0, 2.0), ServoDrive(1.0, 2.0))
>>> tr = JointTrajectory.from_waypoints(drives, np.array([[0.0, 0.0], [2.0, 0.5]]), "sync")
>>> tr.duration, tr.knot_times.tolist()
(2.5, [0.0, 2.5])
>>> tr.sample(np.array([0.0, 2.5])).tolist()
[[0.0, 0.0], [2.0, 0.5]]
>>> tr.append_dwell(1.0).motion_intervals().tolist()
[[0.0, 2.5]]
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, IntArray
from workcell.arms._kinematics_jit import piecewise_cubic
from workcell.arms.profiles import Drive, Profile

__all__ = ["Interpolation", "JointTrajectory", "Segment"]

Interpolation = Literal["sync", "axis"]


@dataclass(frozen=True, slots=True)
class Segment:
    """One rest-to-rest piece of a trajectory.

    Attributes
    ----------
    q0, q1 : (dof,) float
        Joint vectors at its start and end (equal for a dwell).
    duration : float
    profiles : tuple of (Profile or None)
        One per joint (None: the joint does not move); empty for a dwell.
    """

    q0: FloatArray
    q1: FloatArray
    duration: float
    profiles: tuple[Profile | None, ...] = ()

    @property
    def moving(self) -> bool:
        """Whether some joint moves in this segment."""
        return any(p is not None for p in self.profiles)

    def sample(self, tau: FloatArray) -> FloatArray:
        """(N, dof) joint vectors at local times ``tau`` (clipped to the segment)."""
        out = np.repeat(self.q0[None, :], len(tau), axis=0)
        for j, p in enumerate(self.profiles):
            if p is not None:
                out[:, j] += p.position(tau)
        return out


@dataclass(frozen=True)
class JointTrajectory:
    """A timed joint path (module docstring).

    Attributes
    ----------
    segments : tuple of Segment
    knot_times : (K,) float
        Segment boundaries, from 0 to :attr:`duration` (K = segments + 1).
    """

    segments: tuple[Segment, ...]
    knot_times: FloatArray

    def __post_init__(self) -> None:
        if not self.segments:
            raise ValidationError("a trajectory needs at least one segment")
        self.knot_times.setflags(write=False)

    @classmethod
    def build(cls, segments: Sequence[Segment]) -> JointTrajectory:
        """A trajectory from segments in order."""
        segs = tuple(segments)
        knots = np.concatenate([[0.0], np.cumsum([s.duration for s in segs])])
        return cls(segs, knots)

    @property
    def duration(self) -> float:
        """Seconds from start to end."""
        return float(self.knot_times[-1])

    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.segments[0].q0)

    @property
    def q_start(self) -> FloatArray:
        """(dof,) joints at the start."""
        return self.segments[0].q0

    @property
    def q_end(self) -> FloatArray:
        """(dof,) joints at the end."""
        return self.segments[-1].q1

    def waypoints(self) -> FloatArray:
        """(K, dof) joints at the knot times."""
        return np.stack([self.segments[0].q0, *(s.q1 for s in self.segments)])

    def sample(self, t: FloatArray) -> FloatArray:
        """(N, dof) joint vectors at times ``t`` (clipped to ``[0, duration]``), vectorised."""
        breaks, coef, counts = self._packed
        tt = np.ascontiguousarray(np.asarray(t, dtype=float).reshape(-1))
        out: FloatArray = piecewise_cubic(breaks, coef, counts, tt, self.duration)
        return out

    def _sample_numpy(self, t: FloatArray) -> FloatArray:
        """The numpy version of :meth:`sample` (the tests' reference)."""
        t = np.clip(np.asarray(t, dtype=float).reshape(-1), 0.0, self.duration)
        out = np.empty((len(t), self.dof))
        for j, (breaks, coef) in enumerate(self._pieces):
            k = np.clip(np.searchsorted(breaks, t, side="right") - 1, 0, len(coef) - 1)
            tau = t - breaks[k]
            c = coef[k]
            out[:, j] = c[:, 0] + tau * (c[:, 1] + tau * (c[:, 2] + tau * c[:, 3]))
        return out

    @cached_property
    def _packed(self) -> tuple[FloatArray, FloatArray, IntArray]:
        """:attr:`_pieces` in padded arrays: breaks (dof, P), coefficients
        (dof, P, 4) and the pieces per joint (dof,), for the compiled sampler."""
        pieces = self._pieces
        width = max(len(b) for b, _ in pieces)
        breaks = np.full((len(pieces), width), np.inf)
        coef = np.zeros((len(pieces), width, 4))
        counts = np.zeros(len(pieces), dtype=np.int64)
        for j, (b, c) in enumerate(pieces):
            breaks[j, : len(b)] = b
            coef[j, : len(b)] = c
            counts[j] = len(b)
        return breaks, coef, counts

    @cached_property
    def _pieces(self) -> list[tuple[FloatArray, FloatArray]]:
        """Per joint: piece start times (P,) and cubic coefficients (P, 4) of
        the position in the time since the piece's start (built once)."""
        out = []
        knots = self.knot_times.tolist()
        starts_q = [seg.q0.tolist() for seg in self.segments]
        for j in range(self.dof):
            breaks: list[float] = []
            coef: list[tuple[float, float, float, float]] = []
            for i, seg in enumerate(self.segments):
                # plain floats: the same IEEE operations as on numpy scalars
                t0 = float(knots[i])
                q0 = float(starts_q[i][j])
                p = seg.profiles[j] if seg.profiles else None
                if p is None or len(p.durations) == 0:
                    breaks.append(t0)
                    coef.append((q0, 0.0, 0.0, 0.0))
                    continue
                sc = p._scale
                state = p._state.tolist()
                starts = p._starts.tolist()
                acc = np.asarray(p.accel, dtype=float).tolist()
                jrk = np.asarray(p.jerk, dtype=float).tolist()
                for k in range(len(p.durations)):
                    p0, v0 = state[k]
                    breaks.append(t0 + starts[k])
                    coef.append((q0 + sc * p0, sc * v0, sc * acc[k] / 2, sc * jrk[k] / 6))
                if p.duration < seg.duration:  # this joint stops before the segment ends
                    breaks.append(t0 + p.duration)
                    coef.append((q0 + p.distance, 0.0, 0.0, 0.0))
            out.append((np.array(breaks), np.array(coef)))
        return out

    def motion_intervals(self) -> FloatArray:
        """(K, 2) sorted disjoint intervals in which some joint moves."""
        spans: list[list[float]] = []
        for i, s in enumerate(self.segments):
            if not s.moving or s.duration <= 0:
                continue
            a, b = float(self.knot_times[i]), float(self.knot_times[i + 1])
            if spans and spans[-1][1] >= a:
                spans[-1][1] = b
            else:
                spans.append([a, b])
        return np.array(spans, dtype=float).reshape(-1, 2)

    def append_dwell(self, seconds: float) -> JointTrajectory:
        """The trajectory followed by a dwell at its end pose."""
        return JointTrajectory.concatenate([self, JointTrajectory.dwell(self.q_end, seconds)])

    @classmethod
    def dwell(cls, q: FloatArray, seconds: float) -> JointTrajectory:
        """Standing still at ``q`` for ``seconds``."""
        s = float(seconds)
        if not (np.isfinite(s) and s >= 0):
            raise ValidationError(f"dwell time must be finite and >= 0, got {seconds!r}")
        qa = np.array(q, dtype=float)
        return cls.build([Segment(qa, qa, s)])

    @classmethod
    def concatenate(cls, parts: Sequence[JointTrajectory]) -> JointTrajectory:
        """One trajectory running ``parts`` one after the other (each must start
        where the previous one ends)."""
        if not parts:
            raise ValidationError("nothing to concatenate")
        segs: list[Segment] = []
        for i, p in enumerate(parts):
            if i and not np.allclose(p.q_start, parts[i - 1].q_end, atol=1e-9):
                raise ValidationError(
                    f"trajectory part {i} starts at {p.q_start.tolist()}, not where part "
                    f"{i - 1} ends ({parts[i - 1].q_end.tolist()})"
                )
            segs.extend(p.segments)
        return cls.build(segs)

    @classmethod
    def from_waypoints(
        cls,
        drives: Sequence[Drive],
        waypoints: FloatArray,
        interpolation: Interpolation = "sync",
        speed: float = 1.0,
    ) -> JointTrajectory:
        """Rest-to-rest moves through joint ``waypoints`` (K, dof) timed with ``drives``.

        Consecutive equal waypoints are skipped; a path of one point (or of
        equal points) is a zero-length dwell.
        """
        w = np.asarray(waypoints, dtype=float)
        if w.ndim != 2 or w.shape[1] != len(drives) or len(w) == 0:
            raise ValidationError(
                f"waypoints must be (K, {len(drives)}) joint vectors, got shape {w.shape}"
            )
        if not np.all(np.isfinite(w)):
            raise ValidationError("waypoints must be finite")
        if interpolation not in ("sync", "axis"):
            raise ValidationError(f"interpolation must be 'sync' or 'axis', not {interpolation!r}")
        segs = []
        current = w[0]
        for b in w[1:]:
            seg = move_segment(drives, current, b, interpolation, speed)
            if seg is not None:
                segs.append(seg)
                current = seg.q1
        if not segs:
            return cls.dwell(w[0], 0.0)
        return cls.build(segs)


def move_segment(
    drives: Sequence[Drive],
    q0: FloatArray,
    q1: FloatArray,
    interpolation: Interpolation = "sync",
    speed: float = 1.0,
) -> Segment | None:
    """One rest-to-rest move from ``q0`` to ``q1`` (None when nothing moves)."""
    dq = (np.asarray(q1, dtype=float) - np.asarray(q0, dtype=float)).tolist()
    profiles: list[Profile | None] = []
    for drive, dj in zip(drives, dq, strict=False):
        p = drive.profile(dj, speed) if dj != 0 else None
        profiles.append(p if p is not None and p.duration > 0 else None)
    if all(p is None for p in profiles):
        return None
    duration = max(p.duration for p in profiles if p is not None)
    if interpolation == "sync":
        profiles = [None if p is None else p.stretched(duration) for p in profiles]
    # A stepper moves whole steps: the segment ends at the joint values it
    # reaches (within half a step of ``q1``; a joint asked to move less than
    # half a step stays put). Servo joints end exactly at ``q1``.
    start = np.array(q0, dtype=float)
    end = start + np.array([0.0 if p is None else p.distance for p in profiles])
    return Segment(start, end, float(duration), tuple(profiles))
