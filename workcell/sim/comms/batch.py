"""Fast batch contention simulator for Ethernet CSMA/CD rounds (numba).

Same round model as :func:`workcell.sim.comms.dcr.dcr_rounds`: each round
starts at a common instant, station 0 has a trajectory frame, the others a
51-byte position report, each present with probability ``load``; every
pair of stations is taken tau (end-to-end) apart. Stations transmit when
their timer expires: two or more within tau of each other collide; the
channel is then busy for gamma = 2 tau + jam + epsilon, and each station
involved waits r slots (r uniform in [0, 2^k - 1], k = min(n, 10)) after the
collision and one IFS; one station alone holds the channel for X/R + tau and
the others defer to its end + IFS (1-persistent). After 16 attempts a frame
is dropped (delay NaN).

The random draws come from a seeded numpy Generator (uniforms handed to
the compiled loop in chunks), so a seed replays exactly.

Examples
--------
>>> d = ethernet_rounds(200, n_stations=10, seed=1)
>>> d.shape, bool(np.nanmax(d) > 0)
((2000,), True)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, cast

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, Seed, as_rng

__all__ = ["ethernet_rounds"]


def _rounds_py(
    xs: Any,
    active: Any,
    u: Any,
    tau: float,
    ifs: float,
    gamma: float,
    slot: float,
    max_attempts: int,
    backoff_limit: int,
    out: Any,
    first_round: int,
) -> tuple[int, int]:
    """Simulate rounds from ``first_round``; return (next round, uniforms used).

    Stops early (returning the round to redo) when the uniforms run out."""
    n_rounds, n = xs.shape
    ready = np.zeros(n)
    attempts = np.zeros(n, dtype=np.int64)
    pending = np.zeros(n, dtype=np.bool_)
    k_u = 0
    n_u = u.shape[0]
    for r in range(first_round, n_rounds):
        if k_u + n * max_attempts > n_u:
            return r, k_u
        left = 0
        for i in range(n):
            pending[i] = active[r, i]
            ready[i] = 0.0
            attempts[i] = 0
            if pending[i]:
                left += 1
        while left > 0:
            tmin = math.inf
            for i in range(n):
                if pending[i] and ready[i] < tmin:
                    tmin = ready[i]
            count = 0
            who = -1
            for i in range(n):
                if pending[i] and ready[i] < tmin + tau:
                    count += 1
                    who = i
            if count == 1:
                end = tmin + xs[r, who] + tau
                out[r, who] = end
                pending[who] = False
                left -= 1
                for i in range(n):
                    if pending[i] and ready[i] < end + ifs:
                        ready[i] = end + ifs
            else:
                cend = tmin + gamma
                for i in range(n):
                    if pending[i] and ready[i] < tmin + tau:
                        attempts[i] += 1
                        if attempts[i] >= max_attempts:
                            out[r, i] = math.nan
                            pending[i] = False
                            left -= 1
                            continue
                        k = min(attempts[i], backoff_limit)
                        slots = math.floor(u[k_u] * (1 << k))
                        k_u += 1
                        ready[i] = cend + ifs + slots * slot
                    elif pending[i] and ready[i] < cend + ifs:
                        ready[i] = cend + ifs
    return n_rounds, k_u


_compiled: Callable[..., tuple[int, int]] | None = None


def _kernel() -> Callable[..., tuple[int, int]]:
    global _compiled
    if _compiled is None:
        try:
            import numba
        except ImportError:  # pragma: no cover - numba is a dependency
            _compiled = _rounds_py
        else:
            _compiled = cast(Callable[..., tuple[int, int]], numba.njit(cache=False)(_rounds_py))
    return _compiled


def ethernet_rounds(
    n_rounds: int,
    n_stations: int = 10,
    load: float = 1.0,
    bus_length: float = 100.0,
    rate: float = 10e6,
    ifs: float = 9.6e-6,
    slot_time: float = 51.2e-6,
    jam_bits: int = 32,
    epsilon: float | None = None,
    propagation_speed: float = 2e8,
    position_bytes: int = 51,
    trajectory_points: tuple[int, int] = (1, 5),
    max_attempts: int = 16,
    backoff_limit: int = 10,
    seed: Seed = None,
    jit: bool = True,
) -> FloatArray:
    """Batch simulation of Ethernet CSMA/CD contention rounds.

    Parameters
    ----------
    n_rounds : int
        Rounds (>= 1).
    n_stations : int, optional
        Stations including the coordinator.
    load : float, optional
        Probability that a station has a frame in a round, (0, 1].
    bus_length, rate, ifs, jam_bits, epsilon, propagation_speed : optional
        As in :func:`workcell.sim.comms.dcr.dcr_bound`.
    slot_time : float, optional
        Backoff slot, seconds.
    position_bytes : int, optional
        Bytes of a position report.
    trajectory_points : (int, int), optional
        Range of trajectory points (1..5).
    max_attempts, backoff_limit : int, optional
        802.3: 16 and 10.
    seed : int or Generator, optional
        Random source.
    jit : bool, optional
        Run compiled by numba (default) or as plain Python.

    Returns
    -------
    (n_frames,) float ndarray
        Delay of every frame present (round order, then station order),
        seconds; NaN for a dropped frame.

    Raises
    ------
    ValidationError
        For bad counts or load.
    """
    if n_rounds < 1 or n_stations < 1 or max_attempts < 1:
        raise ValidationError(
            f"ethernet_rounds: n_rounds={n_rounds}, n_stations={n_stations}, "
            f"max_attempts={max_attempts} must be >= 1"
        )
    if not 0 < load <= 1:
        raise ValidationError(f"ethernet_rounds: load must be in (0, 1], got {load!r}")
    lo, hi = trajectory_points
    if not 1 <= lo <= hi <= 5:
        raise ValidationError(f"ethernet_rounds: trajectory_points {trajectory_points} not in 1..5")
    rng = as_rng(seed)
    eps = jam_bits / rate if epsilon is None else epsilon
    tau = bus_length / propagation_speed
    gamma = 2 * tau + jam_bits / rate + eps
    size = np.full((n_rounds, n_stations), float(position_bytes))
    size[:, 0] = 28 + 24 * rng.integers(lo, hi + 1, size=n_rounds)
    xs = size * 8 / rate
    active = rng.random((n_rounds, n_stations)) < load
    out = np.full((n_rounds, n_stations), np.nan)
    fn = _kernel() if jit else _rounds_py
    r = 0
    chunk = n_stations * max_attempts * 1024
    while r < n_rounds:
        u = rng.random(chunk)
        nxt, _ = fn(
            xs,
            active,
            u,
            tau,
            ifs,
            gamma,
            slot_time,
            max_attempts,
            backoff_limit,
            out,
            r,
        )
        if nxt == r:  # pragma: no cover - a chunk too small for one round
            chunk *= 2
        r = nxt
    return cast(FloatArray, out[active])
