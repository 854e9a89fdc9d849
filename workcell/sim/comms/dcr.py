"""The CSMA/DCR worst-case delay bound (S2.9) and a fast batch simulator of
CSMA/DCR contention rounds.

The bound. With N stations, packet length X (bits), rate R, end-to-end
propagation tau, interframe spacing IFS and collision period
gamma = 2 tau + jam + epsilon::

    D_max = N (X/R + tau + IFS) + IFS + gamma + tau

and, with the coordinator sending one trajectory (X_t) and the N - 1 robots
one position report (X_p) each::

    D = (X_t/R + tau + IFS) + (N - 1)(X_p/R + tau + IFS) + IFS + gamma + tau

The paper states D_max = 604 us for 10 stations on a 100 m bus at 10 Mb/s and
leaves four choices open. The defaults of :func:`dcr_bound` are the ones that
reproduce it (see ``docs/networks.md``):

* N = 10 counts the coordinator (1 coordinator + 9 robots);
* the 8-byte preamble is *not* added to X: the 26 bytes of overhead in the
  S2.9 sizes already are preamble 8 + addresses 12 + length 2 + FCS 4;
* propagation speed 2e8 m/s (about 2/3 c in coaxial cable), so tau = 0.5 us;
* epsilon (collision detection time) = 32 bit times = 3.2 us, the length of
  the jam.

Arithmetic (microseconds)::

    X_t/R = 148*8/10 = 118.4      X_p/R = 51*8/10 = 40.8
    tau = 100 / 2e8 = 0.5         IFS = 9.6      jam = 3.2     epsilon = 3.2
    gamma = 2*0.5 + 3.2 + 3.2 = 7.4
    D = (118.4 + 0.5 + 9.6) + 9 (40.8 + 0.5 + 9.6) + 9.6 + 7.4 + 0.5
      = 128.5 + 458.1 + 17.5 = 604.1

Every microsecond of epsilon moves D by one microsecond; epsilon = 3.1 us
gives exactly 604.0. Counting the preamble again gives 668.1 us, taking N = 9
(robots only) 553.2 us: neither reproduces the paper.

Reduced parameters (S2.9): IFS 3.2 us, 20 Mb/s, and a slot just above
jam + 2 tau (1.6 + 1.0 = 2.6 us for 100 m at 20 Mb/s; 3.2 us = 64 bit times
is the next whole 8-byte multiple). Epsilon stays 32 bit times (1.6 us)::

    X_t/R = 59.2, X_p/R = 20.4, gamma = 1.0 + 1.6 + 1.6 = 4.2
    D = (59.2 + 0.5 + 3.2) + 9 (20.4 + 0.5 + 3.2) + 3.2 + 4.2 + 0.5 = 287.7

The slot does not enter D: in the worst case every position of the
resolution carries a frame; it only has to exceed jam + 2 tau so that a
collision is always detected within one slot.

Examples
--------
>>> round(dcr_bound() * 1e6, 1)
604.1
>>> round(dcr_bound(**REDUCED) * 1e6, 1)
287.7
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, Seed, as_rng

__all__ = [
    "PREAMBLE_BYTES",
    "REDUCED",
    "dcr_bound",
    "dcr_rounds",
    "min_slot_time",
]

PREAMBLE_BYTES = 8
"""Ethernet preamble + start-of-frame delimiter, bytes."""

REDUCED: dict[str, Any] = {"rate": 20e6, "ifs": 3.2e-6, "slot_time": 3.2e-6}
"""The paper's non-standard parameters (S2.9): 20 Mb/s, IFS 3.2 us and a
slot of 3.2 us (64 bit times at 20 Mb/s), just above jam + 2 tau = 2.6 us on
the 100 m bus. Accepted by :func:`dcr_bound`, :func:`dcr_rounds` and
:class:`~workcell.sim.comms.ethernet.EthernetParams`."""


def _check_positive(**values: float) -> None:
    for name, v in values.items():
        if not (v > 0 and math.isfinite(v)):
            raise ValidationError(f"dcr_bound: {name} must be > 0 and finite, got {v!r}")


def dcr_bound(
    n_stations: int = 10,
    bus_length: float = 100.0,
    rate: float = 10e6,
    trajectory_bytes: int = 148,
    position_bytes: int = 51,
    ifs: float = 9.6e-6,
    jam_bits: int = 32,
    epsilon: float | None = None,
    propagation_speed: float = 2e8,
    count_preamble: bool = False,
    mixed: bool = True,
    slot_time: float | None = None,
) -> float:
    """Worst-case CSMA/DCR access + transfer delay of one round (S2.9).

    Parameters
    ----------
    n_stations : int, optional
        N, all stations on the bus *including* the coordinator (default 10).
    bus_length : float, optional
        Metres (default 100).
    rate : float, optional
        Bits per second (default 10e6).
    trajectory_bytes : int, optional
        X_t, bytes (default 148, the S2.9 worst case; includes 26 bytes of
        overhead).
    position_bytes : int, optional
        X_p, bytes (default 51).
    ifs : float, optional
        Interframe spacing, seconds (default 9.6e-6).
    jam_bits : int, optional
        Jam length, bits (default 32).
    epsilon : float, optional
        Collision detection time, seconds; default ``jam_bits / rate``.
    propagation_speed : float, optional
        Metres per second (default 2e8).
    count_preamble : bool, optional
        Add the 8-byte preamble to both sizes (default False: the 26 bytes of
        overhead already contain it).
    mixed : bool, optional
        True: one trajectory + (N - 1) position reports (the paper's mixed
        form). False: N frames of ``trajectory_bytes`` (plain D_max with
        X = X_t).
    slot_time : float, optional
        Slot time, seconds. It does not enter D (in the worst case every
        turn of the resolution carries a frame); when given it is checked to
        exceed jam + 2 tau (:func:`min_slot_time`), the condition for every
        collision to be detected within one slot.

    Returns
    -------
    float
        Seconds.

    Raises
    ------
    ValidationError
        For N < 1, non-positive parameters or a slot not above jam + 2 tau.

    Examples
    --------
    >>> round(dcr_bound(mixed=False) * 1e6, 1)
    1302.5
    >>> dcr_bound(rate=20e6, slot_time=2e-6)
    Traceback (most recent call last):
    ...
    multiarm.errors.ValidationError: dcr_bound: slot_time 2.0 us must exceed jam + 2 tau = 2.6 us
    """
    if n_stations < 1:
        raise ValidationError(f"dcr_bound: n_stations must be >= 1, got {n_stations}")
    _check_positive(
        bus_length=bus_length,
        rate=rate,
        trajectory_bytes=trajectory_bytes,
        position_bytes=position_bytes,
        ifs=ifs,
        jam_bits=jam_bits,
        propagation_speed=propagation_speed,
    )
    eps = jam_bits / rate if epsilon is None else epsilon
    if not (eps >= 0 and math.isfinite(eps)):
        raise ValidationError(f"dcr_bound: epsilon must be >= 0, got {epsilon!r}")
    extra = PREAMBLE_BYTES if count_preamble else 0
    tau = bus_length / propagation_speed
    if slot_time is not None:
        need = jam_bits / rate + 2 * tau
        if not (slot_time > need * (1 + 1e-9) and math.isfinite(slot_time)):
            raise ValidationError(
                f"dcr_bound: slot_time {slot_time * 1e6:.1f} us must exceed jam + 2 tau = "
                f"{need * 1e6:.1f} us"
            )
    gamma = 2 * tau + jam_bits / rate + eps
    xt = (trajectory_bytes + extra) * 8 / rate
    xp = (position_bytes + extra) * 8 / rate if mixed else xt
    return (xt + tau + ifs) + (n_stations - 1) * (xp + tau + ifs) + ifs + gamma + tau


def min_slot_time(
    bus_length: float = 100.0,
    rate: float = 10e6,
    jam_bits: int = 32,
    propagation_speed: float = 2e8,
) -> float:
    """Shortest admissible slot time, jam + 2 tau (S2.9), seconds.

    Parameters
    ----------
    bus_length : float, optional
        Metres.
    rate : float, optional
        Bits per second.
    jam_bits : int, optional
        Bits.
    propagation_speed : float, optional
        Metres per second.

    Returns
    -------
    float
        Seconds.

    Examples
    --------
    >>> round(min_slot_time(2500.0) * 1e6, 1)   # the standard's 2500 m bus
    28.2
    >>> round(min_slot_time(100.0, rate=20e6) * 1e6, 2)
    2.6
    """
    _check_positive(bus_length=bus_length, rate=rate, propagation_speed=propagation_speed)
    return jam_bits / rate + 2 * bus_length / propagation_speed


def dcr_rounds(
    n_rounds: int,
    n_stations: int = 10,
    load: float = 1.0,
    bus_length: float = 100.0,
    rate: float = 10e6,
    ifs: float = 9.6e-6,
    jam_bits: int = 32,
    epsilon: float | None = None,
    propagation_speed: float = 2e8,
    position_bytes: int = 51,
    trajectory_points: tuple[int, int] = (1, 5),
    seed: Seed = None,
    slot_time: float | None = None,
    empty_slot: float = 0.0,
) -> FloatArray:
    """Batch simulation of CSMA/DCR contention rounds, vectorised.

    Each round starts at a common instant (the sampling tick). Station 0 (the
    coordinator) has a trajectory frame of 26 + 2 + 24 p bytes, p uniform in
    ``trajectory_points``; stations 1..N-1 a 51-byte position report; each
    station has its frame with probability ``load`` (1.0 = full load, the
    worst case). One frame alone goes through at once (X/R + tau); two or more
    collide (collision period gamma = 2 tau + jam + epsilon), then after IFS
    the stations involved transmit in station order, one frame per turn
    (X/R + tau + IFS each). Propagation is taken end to end (tau), the worst
    case for every pair.

    Parameters
    ----------
    n_rounds : int
        Rounds (>= 1).
    n_stations : int, optional
        N including the coordinator.
    load : float, optional
        Probability that a station has a frame in a round, in (0, 1].
    bus_length, rate, ifs, jam_bits, epsilon, propagation_speed : optional
        As in :func:`dcr_bound`.
    position_bytes : int, optional
        X_p, bytes.
    trajectory_points : (int, int), optional
        Range of trajectory points, inclusive (1..5).
    seed : int or Generator, optional
        Random source.
    slot_time : float, optional
        Accepted for symmetry with :data:`REDUCED`; checked as in
        :func:`dcr_bound`, it does not change the delays.
    empty_slot : float, optional
        Seconds the turn of a station with nothing to send costs in a
        resolution (default 0: the resolution skips silent stations, the
        idealisation behind the paper's bound). A slotted resolution spends
        at least a slot time of silence on each: with the standard 51.2 us
        slot a silent turn outlasts a 51-byte one (50.9 us) by 0.3 us, which
        the bound's IFS + tau of slack absorbs up to 33 silent stations (at
        10 stations the worst round ends at 596.4 us, under 604.1); at 40
        stations the coordinator and the last station alone would end
        2132.4 us after the collision, 1.3 us past :func:`dcr_bound`.

    Returns
    -------
    (n_frames,) float ndarray
        Delay of every frame (send instant to last bit at the farthest
        station), seconds.

    Raises
    ------
    ValidationError
        For bad counts or a load outside (0, 1].

    Examples
    --------
    >>> d = dcr_rounds(1000, seed=0)
    >>> bool(d.max() <= dcr_bound())
    True
    """
    if n_rounds < 1 or n_stations < 1:
        raise ValidationError(f"dcr_rounds: n_rounds={n_rounds}, n_stations={n_stations} < 1")
    if not 0 < load <= 1:
        raise ValidationError(f"dcr_rounds: load must be in (0, 1], got {load!r}")
    lo, hi = trajectory_points
    if not 1 <= lo <= hi <= 5:
        raise ValidationError(f"dcr_rounds: trajectory_points {trajectory_points} not in 1..5")
    if slot_time is not None:
        dcr_bound(
            bus_length=bus_length,
            rate=rate,
            jam_bits=jam_bits,
            propagation_speed=propagation_speed,
            slot_time=slot_time,
        )
    rng = as_rng(seed)
    eps = jam_bits / rate if epsilon is None else epsilon
    tau = bus_length / propagation_speed
    gamma = 2 * tau + jam_bits / rate + eps
    size = np.full((n_rounds, n_stations), float(position_bytes))
    size[:, 0] = 28 + 24 * rng.integers(lo, hi + 1, size=n_rounds)
    active = rng.random((n_rounds, n_stations)) < load if load < 1 else None
    x = size * 8 / rate
    turn = x + tau + ifs
    if active is None:
        ends = np.cumsum(turn, axis=1) - ifs + gamma + ifs
        if n_stations == 1:
            return (x[:, 0] + tau).astype(np.float64)
        return ends.ravel()
    if not (empty_slot >= 0 and math.isfinite(empty_slot)):
        raise ValidationError(f"dcr_rounds: empty_slot must be >= 0, got {empty_slot!r}")
    turn = np.where(active, turn, empty_slot)
    m = active.sum(axis=1, keepdims=True)
    ends = np.cumsum(turn, axis=1) + gamma  # = gamma + IFS + sum(turns) - IFS
    alone = np.broadcast_to(x + tau, ends.shape)
    delays = np.where(m == 1, alone, ends)
    return delays[active].astype(np.float64)
