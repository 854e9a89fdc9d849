"""Drives and their rest-to-rest motion profiles: stepper axes (S1.5, S1.6) and servo joints.

Every drive turns a move of one joint over a distance (metres or radians)
into a :class:`Profile`: a piecewise motion with constant jerk on each piece,
evaluated in closed form and vectorised over query times. Two drives:

:class:`StepperDrive` (SEEDS.md S1.5, S1.6)
    The SUPERSIGMA stepper controller. A command carries only the number of
    steps and the direction; the controller chooses the profile itself:

    * a very short move (at most ``short_steps`` steps) runs at the constant
      low (start/stop) rate ``low_rate``;
    * a longer one accelerates at ``accel`` from the low rate to a peak and
      decelerates back (**triangle**): ``n`` steps reach the peak
      ``f_p = sqrt(f_0^2 + a n)``;
    * once that peak would exceed ``max_rate``, a cruise at ``max_rate`` is
      inserted (**trapezoid**). The switch-over length is
      ``n* = (f_max^2 - f_0^2) / a`` steps (:meth:`StepperDrive.switch_steps`);
    * the join between acceleration and cruise is smooth: the step rate is
      continuous there (it reaches ``max_rate`` exactly as the cruise starts);
    * ``curves`` name selectable accelerations (e.g. for the load in the
      hand); an interrupt stops the motor along ``stop_accel``, the steepest
      *allowed* deceleration (cutting the pulses would lose synchronism).

    With the defaults (half step, 400 steps per shaft turn, 0.0375 mm of
    travel per step, 15,000 steps/s) the top speed is 562.5 mm/s.

    Step timestamps (:meth:`StepperDrive.step_times`) follow D. Austin,
    "Generate stepper-motor speed profiles in real time", *Embedded Systems
    Programming*, January 2005: the exact square-root ramp (from rest,
    ``t_n = sqrt(2 n / a)``; from the low rate ``f_0``,
    ``t_n = (sqrt(f_0^2 + 2 a n) - f_0) / a``), or, as an option, the
    recurrence of the same article that the AccelStepper library uses,
    ``c_n = c_{n-1} - 2 c_{n-1} / (4 n + 1)`` with ``c_0 = 0.676 sqrt(2 / a)``.

:class:`ServoDrive`
    A servo joint with velocity, acceleration and optional jerk limits:
    trapezoidal (triangle when short) or, with a jerk limit, the
    jerk-limited 7-piece S-curve, in closed form.

Both expose ``profile(distance, speed=1.0) -> Profile``; a profile can be
stretched in time (:meth:`Profile.stretched`) so that every joint of a
synchronised move finishes together (S1.9 interpolated moves).

Examples
--------
>>> d = StepperDrive()
>>> round(d.top_speed * 1000, 1)  # mm/s
562.5
>>> d.kind_of(d.switch_steps() - 1), d.kind_of(d.switch_steps() + 1), d.kind_of(4)
('triangle', 'trapezoid', 'constant')
>>> s = ServoDrive(1.0, 2.0)
>>> s.profile(0.25).duration  # triangle: 2 sqrt(d / a)
0.7071067811865476
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray

__all__ = ["Drive", "Profile", "ServoDrive", "StepperDrive"]


@dataclass(frozen=True, slots=True)
class Profile:
    """A rest-to-rest (or from the stepper's start rate) move along one joint.

    The move is a sequence of pieces; on piece ``k`` the jerk is constant
    ``jerk[k]`` for ``durations[k]`` seconds and the acceleration starts at
    ``accel[k]`` (so trapezoids jump in acceleration, S-curves do not). The
    velocity starts at ``v0`` (0 for servos, the low rate for steppers).
    Positions are scaled so the move ends exactly at ``distance``.

    Attributes
    ----------
    distance : float
        Signed distance (metres or radians).
    kind : str
        ``"none"``, ``"constant"``, ``"triangle"``, ``"trapezoid"`` or ``"scurve"``.
    durations, accel, jerk : (P,) float
    v0 : float
    peak : float
        Peak speed reached (absolute).
    """

    distance: float
    kind: str
    durations: FloatArray
    accel: FloatArray
    jerk: FloatArray
    v0: float = 0.0
    peak: float = 0.0
    _duration: float = field(init=False, repr=False)
    _starts_cache: FloatArray | None = field(init=False, repr=False)
    _integrated: tuple[FloatArray, float] | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        # the total is summed in order, as the last entry of ``numpy.cumsum``
        # (a sequential accumulation); piece starts, positions and velocities
        # are built on first use: many profiles are only asked for their
        # duration (then stretched or dropped)
        total = 0.0
        for tk in np.asarray(self.durations, dtype=float).tolist():
            total += tk
        object.__setattr__(self, "_duration", total)
        object.__setattr__(self, "_starts_cache", None)
        object.__setattr__(self, "_integrated", None)

    @property
    def _starts(self) -> FloatArray:
        """(P + 1,) piece start times, the last one the duration."""
        got = self._starts_cache
        if got is None:
            d = np.asarray(self.durations, dtype=float)
            got = np.concatenate([[0.0], np.cumsum(d)])
            object.__setattr__(self, "_starts_cache", got)
        return got

    def _integrate(self) -> tuple[FloatArray, float]:
        got = self._integrated
        if got is None:
            # position, velocity at piece starts; plain floats (the same IEEE
            # operations as on numpy scalars, without their per-element overhead)
            rows: list[tuple[float, float]] = []
            p, v = 0.0, float(self.v0)
            d = np.asarray(self.durations, dtype=float).tolist()
            acc = np.asarray(self.accel, dtype=float).tolist()
            jrk = np.asarray(self.jerk, dtype=float).tolist()
            for tk, a0, j in zip(d, acc, jrk, strict=False):
                rows.append((p, v))
                p = p + v * tk + a0 * tk**2 / 2 + j * tk**3 / 6
                v = v + a0 * tk + j * tk**2 / 2
            rows.append((p, v))
            got = (np.array(rows, dtype=float), self.distance / p if p > 0 else 0.0)
            object.__setattr__(self, "_integrated", got)
        return got

    @property
    def _state(self) -> FloatArray:
        """(P + 1, 2) position and velocity at the piece starts (unscaled)."""
        return self._integrate()[0]

    @property
    def _scale(self) -> float:
        """Factor making the integrated end position equal :attr:`distance`."""
        return self._integrate()[1]

    @property
    def duration(self) -> float:
        """Seconds the move takes."""
        return self._duration

    def position(self, t: FloatArray) -> FloatArray:
        """Signed position at times ``t`` (clipped to ``[0, duration]``), vectorised."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        if len(self.durations) == 0:
            return np.zeros_like(t)
        k = np.clip(np.searchsorted(self._starts, t, side="right") - 1, 0, len(self.durations) - 1)
        tau = t - self._starts[k]
        p0, v0 = self._state[k, 0], self._state[k, 1]
        a0, j = self.accel[k], self.jerk[k]
        out: FloatArray = (p0 + v0 * tau + a0 * tau**2 / 2 + j * tau**3 / 6) * self._scale
        return out

    def velocity(self, t: FloatArray) -> FloatArray:
        """Signed velocity at times ``t`` (0 outside the move), vectorised."""
        t = np.asarray(t, dtype=float)
        if len(self.durations) == 0:
            return np.zeros_like(t)
        tc = np.clip(t, 0.0, self.duration)
        k = np.clip(np.searchsorted(self._starts, tc, side="right") - 1, 0, len(self.durations) - 1)
        tau = tc - self._starts[k]
        v = (self._state[k, 1] + self.accel[k] * tau + self.jerk[k] * tau**2 / 2) * self._scale
        out: FloatArray = np.where((t < 0) | (t > self.duration), 0.0, v)
        return out

    def stretched(self, duration: float) -> Profile:
        """The same move slowed down to last ``duration`` seconds (time scaling:
        speeds divide by the ratio, accelerations by its square, jerks by its cube)."""
        if duration < self.duration - 1e-12:
            raise ValidationError(
                f"cannot stretch a {self.duration:.6g} s move to a shorter {duration:.6g} s"
            )
        if self.duration == 0 or duration == self.duration:
            return self
        k = duration / self.duration
        return Profile(
            self.distance,
            self.kind,
            self.durations * k,
            self.accel / k**2,
            self.jerk / k**3,
            self.v0 / k,
            self.peak / k,
        )


def _empty(distance: float = 0.0) -> Profile:
    z = np.zeros(0)
    return Profile(distance, "none", z, z, z)


class Drive:
    """What every joint drive offers (see :class:`StepperDrive`, :class:`ServoDrive`)."""

    top_speed: float

    def profile(self, distance: float, speed: float = 1.0) -> Profile:
        """The drive's own rest-to-rest profile for a signed ``distance``.

        ``speed`` is the fraction (0, 1] of the top speed allowed.
        """
        raise NotImplementedError

    def duration(self, distance: float, speed: float = 1.0) -> float:
        """Seconds the move over ``distance`` takes."""
        return self.profile(distance, speed).duration

    def durations(self, distances: FloatArray, speed: float = 1.0) -> FloatArray:
        """Vectorised :meth:`duration` over an array of distances."""
        raise NotImplementedError


def _positive(value: float, what: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValidationError(f"{what} must be a finite number > 0, got {value!r}")
    return v


def _speed(speed: float) -> float:
    s = float(speed)
    if not (math.isfinite(s) and 0 < s <= 1):
        raise ValidationError(f"speed fraction must be in (0, 1], got {speed!r}")
    return s


DEFAULT_CURVES: Mapping[str, float] = {"light": 2.0, "loaded": 1.0}
"""Acceleration curves (m/s^2 of arm travel) of the default stepper axis."""


@dataclass(frozen=True)
class StepperDrive(Drive):
    """A stepper axis with the SUPERSIGMA controller (S1.5, S1.6; module docstring).

    Parameters
    ----------
    steps_per_turn : int
        400 in half-step mode (0.9 degree per step).
    step_length : float
        Metres of arm travel per step (0.0375 mm).
    max_rate : float
        Top step rate, steps/s (15,000: about 500 mm/s).
    low_rate : float
        The start/stop rate, steps/s: the motor starts and stops at it
        without a ramp, and very short moves run at it.
    curves : mapping of str to float
        Named accelerations in m/s^2 of travel.
    curve : str
        The curve in use.
    stop_accel : float
        The steepest allowed deceleration, m/s^2 (emergency stops).
    short_steps : int
        Moves of at most this many steps run at the constant low rate.
    homing_rate : float
        Steps/s while seeking the end-of-rail switch (S1.6).
    switch_hysteresis : int
        Steps forward until the switch releases.
    """

    steps_per_turn: int = 400
    step_length: float = 0.0375e-3
    max_rate: float = 15_000.0
    low_rate: float = 1_000.0
    curves: Mapping[str, float] = field(default_factory=lambda: dict(DEFAULT_CURVES))
    curve: str = "light"
    stop_accel: float = 4.0
    short_steps: int = 32
    homing_rate: float = 4_000.0
    switch_hysteresis: int = 40

    def __post_init__(self) -> None:
        if isinstance(self.steps_per_turn, bool) or int(self.steps_per_turn) < 1:
            raise ValidationError(f"steps_per_turn must be >= 1, got {self.steps_per_turn!r}")
        _positive(self.step_length, "step_length")
        _positive(self.max_rate, "max_rate")
        _positive(self.low_rate, "low_rate")
        if self.low_rate > self.max_rate:
            raise ValidationError(
                f"low_rate {self.low_rate} must not exceed max_rate {self.max_rate}"
            )
        if not self.curves:
            raise ValidationError("a stepper needs at least one acceleration curve")
        for name, a in self.curves.items():
            _positive(a, f"acceleration of curve {name!r}")
        if self.curve not in self.curves:
            raise ValidationError(
                f"unknown acceleration curve {self.curve!r} (known: {', '.join(self.curves)})"
            )
        _positive(self.stop_accel, "stop_accel")
        if self.stop_accel < max(self.curves.values()):
            raise ValidationError("stop_accel must be at least every curve's acceleration")
        if int(self.short_steps) < 0:
            raise ValidationError(f"short_steps must be >= 0, got {self.short_steps!r}")
        _positive(self.homing_rate, "homing_rate")

    # ------------------------------------------------------- in steps
    @property
    def top_speed(self) -> float:  # type: ignore[override]
        """Metres per second at the top rate."""
        return self.max_rate * self.step_length

    @property
    def accel_steps(self) -> float:
        """Acceleration of the current curve, steps/s^2."""
        return self.curves[self.curve] / self.step_length

    def with_curve(self, curve: str) -> StepperDrive:
        """The same drive with another acceleration curve."""
        from dataclasses import replace

        return replace(self, curve=curve)

    def steps(self, distance: float) -> int:
        """Whole steps for a distance (metres), rounded to the nearest step."""
        return round(abs(float(distance)) / self.step_length)

    def switch_steps(self, speed: float = 1.0) -> float:
        """Move length (steps) above which the profile is a trapezoid:
        ``(f_max^2 - f_0^2) / a``."""
        fmax = max(self.low_rate, self.max_rate * _speed(speed))
        return (fmax**2 - self.low_rate**2) / self.accel_steps

    def kind_of(self, n: int, speed: float = 1.0) -> str:
        """The profile the controller picks for ``n`` steps."""
        if n <= 0:
            return "none"
        if n <= self.short_steps:
            return "constant"
        return "triangle" if n <= self.switch_steps(speed) else "trapezoid"

    def steps_duration(self, n: FloatArray, speed: float = 1.0) -> FloatArray:
        """Closed-form move time of ``n`` steps (vectorised)."""
        n = np.asarray(n, dtype=float)
        a, f0 = self.accel_steps, self.low_rate
        fmax = max(f0, self.max_rate * _speed(speed))
        nsw = (fmax**2 - f0**2) / a
        peak = np.sqrt(f0**2 + a * np.minimum(n, nsw))
        ramp = 2 * (peak - f0) / a
        cruise = np.maximum(n - nsw, 0.0) / fmax
        out = np.where(n <= self.short_steps, n / f0, ramp + cruise)
        res: FloatArray = np.where(n <= 0, 0.0, out)
        return res

    def step_times(
        self, n: int, speed: float = 1.0, ramp: Literal["exact", "accelstepper"] = "exact"
    ) -> FloatArray:
        """Timestamps (seconds) of the ``n`` steps of a move, vectorised.

        ``ramp="exact"``: the exact square-root ramp (Austin 2005) from the
        low rate; ``"accelstepper"``: the recurrence of the same article
        (AccelStepper), from rest with Austin's corrected first delay
        ``c_0 = 0.676 sqrt(2 / a)``. The last step lands at the move's end.
        """
        kind = self.kind_of(n, speed)
        if kind == "none":
            return np.zeros(0)
        f0, a = self.low_rate, self.accel_steps
        fmax = max(f0, self.max_rate * _speed(speed))
        k = np.arange(1, n + 1, dtype=float)
        if kind == "constant":
            return k / f0
        if ramp == "accelstepper":
            return self._accelstepper(n, fmax)
        if ramp != "exact":
            raise ValidationError(f"ramp must be 'exact' or 'accelstepper', not {ramp!r}")
        n_up = min(n / 2, (fmax**2 - f0**2) / (2 * a))
        t_up = (np.sqrt(f0**2 + 2 * a * n_up) - f0) / a
        t_total = float(self.steps_duration(np.array([n]), speed)[0])
        up = (np.sqrt(f0**2 + 2 * a * k) - f0) / a
        cruise = t_up + (k - n_up) / fmax
        down_k = n - k  # steps remaining
        down = t_total - (np.sqrt(f0**2 + 2 * a * down_k) - f0) / a
        out: FloatArray = np.where(k <= n_up, up, np.where(k >= n - n_up, down, cruise))
        return out

    def _accelstepper(self, n: int, fmax: float) -> FloatArray:
        a = self.accel_steps
        cmin = 1.0 / fmax
        delays = np.empty(n)
        c = 0.676 * math.sqrt(2.0 / a)
        half = n // 2
        up = 0
        for i in range(half):
            if i > 0:
                c = c - 2 * c / (4 * i + 1)
            if c <= cmin:
                c = cmin
                delays[i] = c
                break
            delays[i] = c
            up = i + 1
        else:
            i = half
        if up < half:  # cruise reached
            delays[up : n - up] = cmin
        elif n % 2:
            delays[half] = delays[half - 1] if half > 0 else c
        delays[n - up :] = delays[:up][::-1]
        out: FloatArray = np.cumsum(delays)
        return out

    def stop_steps(self, rate: float) -> float:
        """Steps to stop from ``rate`` (steps/s) along the steepest allowed deceleration."""
        a = self.stop_accel / self.step_length
        return max(0.0, rate**2 - self.low_rate**2) / (2 * a)

    def stop_time(self, rate: float) -> float:
        """Seconds to stop from ``rate`` (steps/s) along the steepest allowed deceleration."""
        a = self.stop_accel / self.step_length
        return max(0.0, rate - self.low_rate) / a

    def homing_time(self, position: float) -> float:
        """Seconds to home from ``position`` metres past the switch (S1.6):
        back at the homing rate until the end-of-rail switch trips, then
        forward at the low rate until it releases."""
        back = self.steps(position) / self.homing_rate
        return back + self.switch_hysteresis / self.low_rate

    # ------------------------------------------------- in metres
    def profile(self, distance: float, speed: float = 1.0) -> Profile:
        n = self.steps(distance)
        kind = self.kind_of(n, speed)
        sign = 1.0 if distance >= 0 else -1.0
        dist = sign * n * self.step_length
        if kind == "none":
            return _empty(dist)
        f0, a = self.low_rate, self.accel_steps
        fmax = max(f0, self.max_rate * _speed(speed))
        L = self.step_length
        if kind == "constant":
            return Profile(dist, kind, np.array([n / f0]), np.zeros(1), np.zeros(1), f0 * L, f0 * L)
        peak = min(math.sqrt(f0**2 + a * n), fmax)
        t_ramp = (peak - f0) / a
        if kind == "triangle":
            return Profile(
                dist,
                kind,
                np.array([t_ramp, t_ramp]),
                np.array([a * L, -a * L]),
                np.zeros(2),
                f0 * L,
                peak * L,
            )
        n_ramp = (fmax**2 - f0**2) / (2 * a)
        t_cruise = (n - 2 * n_ramp) / fmax
        return Profile(
            dist,
            kind,
            np.array([t_ramp, t_cruise, t_ramp]),
            np.array([a * L, 0.0, -a * L]),
            np.zeros(3),
            f0 * L,
            fmax * L,
        )

    def durations(self, distances: FloatArray, speed: float = 1.0) -> FloatArray:
        n = np.rint(np.abs(np.asarray(distances, dtype=float)) / self.step_length)
        return self.steps_duration(n, speed)


@dataclass(frozen=True)
class ServoDrive(Drive):
    """A servo joint with velocity, acceleration and optional jerk limits.

    Parameters
    ----------
    max_velocity : float
        m/s or rad/s.
    max_acceleration : float
        m/s^2 or rad/s^2.
    max_jerk : float or None
        With a jerk limit the profile is the jerk-limited S-curve; without,
        the trapezoid (triangle when the move is too short to reach the top
        speed).

    Examples
    --------
    >>> ServoDrive(1.0, 2.0).profile(2.0).duration  # trapezoid: d / v + v / a
    2.5
    >>> round(ServoDrive(1.0, 2.0, 10.0).profile(2.0).duration, 6)  # + a / j
    2.7
    """

    max_velocity: float
    max_acceleration: float
    max_jerk: float | None = None

    def __post_init__(self) -> None:
        _positive(self.max_velocity, "max_velocity")
        _positive(self.max_acceleration, "max_acceleration")
        if self.max_jerk is not None:
            _positive(self.max_jerk, "max_jerk")

    @property
    def top_speed(self) -> float:  # type: ignore[override]
        """The velocity limit."""
        return self.max_velocity

    def profile(self, distance: float, speed: float = 1.0) -> Profile:
        d = abs(float(distance))
        if not math.isfinite(d):
            raise ValidationError(f"move distance must be finite, got {distance!r}")
        if d == 0:
            return _empty(0.0)
        v, a = self.max_velocity * _speed(speed), self.max_acceleration
        if self.max_jerk is None:
            if d <= v * v / a:
                t = math.sqrt(d / a)
                return Profile(
                    float(distance),
                    "triangle",
                    np.array([t, t]),
                    np.array([a, -a]),
                    np.zeros(2),
                    0.0,
                    a * t,
                )
            ta = v / a
            return Profile(
                float(distance),
                "trapezoid",
                np.array([ta, d / v - ta, ta]),
                np.array([a, 0.0, -a]),
                np.zeros(3),
                0.0,
                v,
            )
        return self._scurve(float(distance), d, v, a, float(self.max_jerk))

    @staticmethod
    def _scurve(distance: float, d: float, v: float, a: float, j: float) -> Profile:
        a = min(a, math.sqrt(v * j))

        def acc_distance(vp: float) -> float:
            if vp * j >= a * a:
                return vp * (vp / a + a / j) / 2
            return vp * math.sqrt(vp / j)

        if 2 * acc_distance(v) <= d:
            vp = v
        else:
            # the peak speed the distance allows (no cruise)
            vp = (-(a * a) / j + math.sqrt((a * a / j) ** 2 + 4 * a * d)) / 2
            if vp * j < a * a:
                vp = (d * math.sqrt(j) / 2) ** (2 / 3)
        if vp * j >= a * a:
            tj, ta = a / j, vp / a - a / j  # jerk time, constant-accel time
            ap = a
        else:
            tj, ta = math.sqrt(vp / j), 0.0
            ap = j * tj
        cruise = max(0.0, (d - 2 * acc_distance(vp)) / vp)
        durs = np.array([tj, ta, tj, cruise, tj, ta, tj])
        acc0 = np.array([0.0, ap, ap, 0.0, 0.0, -ap, -ap])
        jerk = np.array([j, 0.0, -j, 0.0, -j, 0.0, j])
        return Profile(distance, "scurve", durs, acc0, jerk, 0.0, vp)

    def durations(self, distances: FloatArray, speed: float = 1.0) -> FloatArray:
        d = np.abs(np.asarray(distances, dtype=float))
        v, a = self.max_velocity * _speed(speed), self.max_acceleration
        if self.max_jerk is None:
            tri = 2 * np.sqrt(d / a)
            trap = d / v + v / a
            out: FloatArray = np.where(d <= v * v / a, tri, trap)
            return np.where(d == 0, 0.0, out)
        return np.array([self.profile(float(x), speed).duration for x in d.ravel()]).reshape(
            d.shape
        )
