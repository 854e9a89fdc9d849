"""The medium interface: frames, delivery, drops and delay statistics.

A *medium* carries :class:`Frame` records between numbered stations attached
to a :class:`~workcell.sim.events.loop.EventLoop`. ``send(frame)`` stamps the send
time; the medium later calls the receiver callback of the destination (every
other station for :data:`BROADCAST`) at the delivery time, or the drop
callback with a reason: a medium never loses a frame silently. Every delivery
adds the frame's delay (delivery time - send time) to the medium's
:class:`DelayStats`.

The coordinator and arm controllers of a simulated cell (S2.7) talk through
this interface: robot -> coordinator zone request, position report (51 bytes,
S2.9), zone release, trajectory end, alarm; coordinator -> robot trajectory
(26 + 2 + 24..120 bytes), sleep, wake up, grants, alarm. :data:`MESSAGE_BYTES`
gives the sizes used by default.

Implementations here: :class:`IdealMedium` (zero delay) and
:class:`FixedLatencyMedium`; the network models are in
:mod:`workcell.sim.comms`.

Examples
--------
>>> from workcell.sim.events.loop import EventLoop
>>> k = EventLoop()
>>> m = FixedLatencyMedium(k, stations=3, latency=1e-3)
>>> got = []
>>> m.attach(1, lambda f, t: got.append((f.kind, f.src, t)))
>>> _ = m.send(Frame(src=0, dst=1, size=51, kind="position"))
>>> k.run()
>>> got
[('position', 0, 0.001)]
>>> m.stats.count, m.stats.max()
(1, 0.001)
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol, runtime_checkable

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray
from workcell.sim.events.loop import EventLoop

__all__ = [
    "BROADCAST",
    "MESSAGE_BYTES",
    "BaseMedium",
    "DelayStats",
    "DropCallback",
    "FixedLatencyMedium",
    "Frame",
    "IdealMedium",
    "Medium",
    "ReceiveCallback",
    "trajectory_bytes",
]

BROADCAST = -1
"""Destination meaning "every station but the sender"."""

MESSAGE_BYTES: dict[str, int] = {
    "zone_request": 30,
    "position": 51,
    "zone_release": 30,
    "trajectory_end": 28,
    "alarm": 28,
    "trajectory": 148,
    "sleep": 28,
    "wake_up": 28,
    "zone_grant": 30,
    "active_zone_grant": 30,
    # the S2.12 exchange (workcell.sim.protocol.exchange)
    "motion_report": 67,
    "departure_request": 67,
    "task_started": 37,
    "task_ended": 37,
    "departure": 30,
    "release_hold": 27,
    "come_back": 27,
    "fail": 27,
    "detour": 154,
    "back_off": 148,
}
"""Default frame sizes in bytes of the coordination messages (S2.7, S2.9,
S2.12).

Position 51 = 1 type byte + 24 bytes (6 DOF x 4) + 26 bytes of Ethernet
overhead; trajectory 148 = worst case of :func:`trajectory_bytes`. The short
messages are assumed to be 1 type byte + 1 argument byte (+ 2 for a zone id)
+ 26 bytes of overhead; the paper gives no size for them. The S2.12
exchange: a motion report or departure request 67 = 1 type + 2 leg id + 1
station + 4 progress + 4 time + 1 flags + 24 joints + 2 acknowledgement (the
last coordinator frame taken) + 2 request number + 26; a task start or end
37 = 1 type + 2 task + 4 time + 2 acknowledgement + 2 spare + 26; the
answer 30 = 1 type + 1 go/stop + 2 request number + 26; release, come back,
fail 27 = 1 type + 26; a back-off 148 = a trajectory's; a detour 154 = a
trajectory's + 2 task + 4 rejoin offset. Sequence numbers ride in the
overhead, as on every frame."""

_ids = itertools.count()


def trajectory_bytes(points: int = 5) -> int:
    """Size of a trajectory message (S2.9): 26 overhead + 2 (type, velocity,
    continuity) + 24 bytes per point (1 = end point only .. 5 = interpolated).

    Parameters
    ----------
    points : int, optional
        Points carried, 1..5.

    Returns
    -------
    int
        Bytes.

    Raises
    ------
    ValidationError
        If ``points`` is not in 1..5.

    Examples
    --------
    >>> trajectory_bytes(1), trajectory_bytes(5)
    (52, 148)
    """
    if not 1 <= points <= 5:
        raise ValidationError(f"trajectory_bytes: points must be 1..5, got {points}")
    return 26 + 2 + 24 * points


@dataclass(frozen=True, slots=True)
class Frame:
    """One message on a medium.

    Parameters
    ----------
    src : int
        Sending station.
    dst : int
        Receiving station, or :data:`BROADCAST`.
    size : int
        Bytes on the medium (> 0), including the medium's own frame overhead
        where the caller counts it (the S2.9 sizes include 26 bytes of
        Ethernet overhead).
    kind : str
        Message type, e.g. ``"position"``, ``"trajectory"``, ``"alarm"``.
    priority : int, optional
        Lower is more urgent (used by priority-ordered transmit chains).
    payload : object, optional
        Anything the receiver needs; not interpreted by the medium.
    send_time : float, optional
        Set by :meth:`Medium.send` (NaN until sent).
    frame_id : int, optional
        Unique id, assigned at construction.
    seq : int, optional
        Sequence number on its link (sender, addressee), -1 when unused: a
        retransmission keeps the original's number, so the receiver can drop
        a duplicate or a frame older than a cancellation it already has
        (:class:`workcell.sim.coordination.centralized.Network`).

    Raises
    ------
    ValidationError
        For a non-positive size, a negative station, or ``src == dst``.
    """

    src: int
    dst: int
    size: int
    kind: str = "data"
    priority: int = 0
    payload: object = None
    send_time: float = math.nan
    frame_id: int = field(default_factory=lambda: next(_ids))
    seq: int = -1

    def __post_init__(self) -> None:
        if self.size <= 0:
            raise ValidationError(f"Frame {self.kind!r}: size must be > 0 bytes, got {self.size}")
        if self.src < 0:
            raise ValidationError(f"Frame {self.kind!r}: src must be >= 0, got {self.src}")
        if self.dst < 0 and self.dst != BROADCAST:
            raise ValidationError(f"Frame {self.kind!r}: dst must be >= 0 or BROADCAST")
        if self.dst == self.src:
            raise ValidationError(f"Frame {self.kind!r}: src and dst are both {self.src}")

    def with_payload(self, payload: object) -> Frame:
        """This frame carrying ``payload`` instead (same id, number and send
        time): ``dataclasses.replace(frame, payload=...)`` without its cost."""
        return Frame(
            self.src,
            self.dst,
            self.size,
            self.kind,
            self.priority,
            payload,
            self.send_time,
            self.frame_id,
            self.seq,
        )


ReceiveCallback = Callable[[Frame, float], object]
"""``receiver(frame, time)``: called at the delivery time."""

DropCallback = Callable[[Frame, str], object]
"""``on_drop(frame, reason)``: called when the medium gives a frame up."""


class DelayStats:
    """Per-frame delays (delivery - send), seconds, with summary statistics.

    Examples
    --------
    >>> s = DelayStats()
    >>> for d in (1.0, 2.0, 3.0):
    ...     s.add(d, "x")
    >>> s.count, s.mean(), s.percentile(50), s.max()
    (3, 2.0, 2.0, 3.0)
    """

    __slots__ = ("_delays", "_kinds", "drops")

    def __init__(self) -> None:
        self._delays: list[float] = []
        self._kinds: list[str] = []
        self.drops = 0

    def add(self, delay: float, kind: str) -> None:
        """Record one delivered frame.

        Parameters
        ----------
        delay : float
            Seconds.
        kind : str
            The frame's kind.
        """
        self._delays.append(delay)
        self._kinds.append(kind)

    @property
    def count(self) -> int:
        """Number of delivered frames recorded."""
        return len(self._delays)

    def delays(self, kind: str | None = None) -> FloatArray:
        """All recorded delays, optionally of one kind.

        Parameters
        ----------
        kind : str, optional
            Only this kind.

        Returns
        -------
        (n,) float ndarray
            Seconds, in delivery order.
        """
        if kind is None:
            return np.asarray(self._delays, dtype=np.float64)
        return np.asarray(
            [d for d, k in zip(self._delays, self._kinds, strict=True) if k == kind],
            dtype=np.float64,
        )

    def mean(self) -> float:
        """Mean delay, seconds (NaN when empty)."""
        return float(np.mean(self._delays)) if self._delays else math.nan

    def max(self) -> float:
        """Largest delay, seconds (NaN when empty)."""
        return float(np.max(self._delays)) if self._delays else math.nan

    def percentile(self, q: float) -> float:
        """The ``q``-th percentile of the delays, seconds (NaN when empty).

        Parameters
        ----------
        q : float
            0..100.

        Returns
        -------
        float
            Seconds.
        """
        return float(np.percentile(self._delays, q)) if self._delays else math.nan


@runtime_checkable
class Medium(Protocol):
    """What every medium offers (see the module docstring)."""

    kernel: EventLoop
    n_stations: int
    stats: DelayStats

    def attach(self, station: int, receiver: ReceiveCallback) -> None:
        """Set the receiver callback of ``station``."""

    def on_drop(self, callback: DropCallback) -> None:
        """Set the drop callback."""

    def send(self, frame: Frame) -> Frame:
        """Send ``frame`` now; returns it with ``send_time`` stamped."""


class BaseMedium:
    """Bookkeeping shared by the media: stations, receivers, drops, statistics.

    Subclasses implement :meth:`_transmit` and call :meth:`_deliver` (at the
    delivery time, for one destination) and :meth:`_drop`.

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    stations : int or sequence of int
        Number of stations (numbered 0..n-1) or their list (must be 0..n-1).

    Raises
    ------
    ValidationError
        For fewer than two stations or a list that is not 0..n-1.
    """

    broadcast_once: bool = False
    """A :data:`BROADCAST` frame costs this medium what one frame to one
    station costs (one transfer that every station hears: a bus). Senders
    with the same frame for several stations may then send it once as a
    broadcast (the distributed peers do, :mod:`workcell.sim.coordination.
    distributed.sight`); on a medium where it is ``False`` (a star that
    relays a broadcast on every line) they send one frame per addressee. A
    medium that is not a :class:`BaseMedium` is taken as ``False``."""

    def __init__(self, kernel: EventLoop, stations: int | Sequence[int]) -> None:
        n = stations if isinstance(stations, int) else len(stations)
        if not isinstance(stations, int) and list(stations) != list(range(n)):
            raise ValidationError(
                f"{type(self).__name__}: stations must be numbered 0..n-1, got {list(stations)}"
            )
        if n < 2:
            raise ValidationError(f"{type(self).__name__}: needs >= 2 stations, got {n}")
        self.kernel = kernel
        self.n_stations = n
        self.stats = DelayStats()
        self._receivers: list[ReceiveCallback | None] = [None] * n
        self._on_drop: DropCallback | None = None

    def attach(self, station: int, receiver: ReceiveCallback) -> None:
        """Set the receiver callback of ``station``.

        Parameters
        ----------
        station : int
            0..n-1.
        receiver : callable
            ``receiver(frame, time)``.

        Raises
        ------
        ValidationError
            For an unknown station.
        """
        self._check_station(station, "attach")
        self._receivers[station] = receiver

    def on_drop(self, callback: DropCallback) -> None:
        """Set the drop callback ``callback(frame, reason)``.

        Parameters
        ----------
        callback : callable
            Called for every frame the medium gives up.
        """
        self._on_drop = callback

    def send(self, frame: Frame) -> Frame:
        """Send ``frame`` now.

        Parameters
        ----------
        frame : Frame
            The frame; its ``send_time`` is set to the kernel's now.

        Returns
        -------
        Frame
            The stamped frame (the one receivers will get).

        Raises
        ------
        ValidationError
            For an unknown source or destination station.
        """
        n = self.n_stations
        if not 0 <= frame.src < n:
            self._check_station(frame.src, f"send ({frame.kind}) src")
        if frame.dst != BROADCAST and not 0 <= frame.dst < n:
            self._check_station(frame.dst, f"send ({frame.kind}) dst")
        now = self.kernel.now
        # a frame already stamped with now (the link does so) is sent as is
        stamped = frame if frame.send_time == now else replace(frame, send_time=now)
        self._transmit(stamped)
        return stamped

    def destinations(self, frame: Frame) -> list[int]:
        """Stations that receive ``frame``.

        Parameters
        ----------
        frame : Frame
            The frame.

        Returns
        -------
        list of int
            ``[dst]``, or every station but ``src`` for a broadcast.
        """
        if frame.dst == BROADCAST:
            return [s for s in range(self.n_stations) if s != frame.src]
        return [frame.dst]

    def _check_station(self, station: int, where: str) -> None:
        if not 0 <= station < self.n_stations:
            raise ValidationError(
                f"{type(self).__name__}.{where}: station {station} not in 0..{self.n_stations - 1}"
            )

    def _transmit(self, frame: Frame) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _deliver(self, frame: Frame, station: int) -> None:
        """Hand ``frame`` to ``station`` now and record its delay."""
        now = self.kernel.now
        self.stats.add(now - frame.send_time, frame.kind)
        rx = self._receivers[station]
        if rx is not None:
            rx(frame, now)

    def _deliver_all(self, frame: Frame) -> None:
        dst = frame.dst
        if dst != BROADCAST:  # one addressee: the common case
            self._deliver(frame, dst)
            return
        for s in self.destinations(frame):
            self._deliver(frame, s)

    def _drop(self, frame: Frame, reason: str) -> None:
        """Give ``frame`` up and tell the drop callback."""
        self.stats.drops += 1
        if self._on_drop is not None:
            self._on_drop(frame, reason)


class IdealMedium(BaseMedium):
    """Zero delay: every frame is delivered at its send time (as a new kernel
    callback, so the sender's own callback finishes first).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    stations : int or sequence of int
        Stations.
    """

    broadcast_once = True
    """One delivery event reaches every station."""

    def _transmit(self, frame: Frame) -> None:
        self.kernel.schedule(0.0, self._deliver_all, frame)


class FixedLatencyMedium(BaseMedium):
    """Every frame is delivered ``latency`` seconds after it is sent (no
    queueing, no contention).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    stations : int or sequence of int
        Stations.
    latency : float
        Seconds, >= 0.

    Raises
    ------
    ValidationError
        For a negative or non-finite latency.
    """

    def __init__(self, kernel: EventLoop, stations: int | Sequence[int], latency: float) -> None:
        super().__init__(kernel, stations)
        if not (latency >= 0 and math.isfinite(latency)):
            raise ValidationError(f"FixedLatencyMedium: latency must be >= 0, got {latency!r}")
        self.latency = float(latency)

    broadcast_once = True
    """One delivery, ``latency`` later, reaches every station."""

    def _transmit(self, frame: Frame) -> None:
        self.kernel.schedule(self.latency, self._deliver_all, frame)
