"""Serial lines: a star of point-to-point lines, or one shared bus (S2.8).

Timing on a line: every byte costs 10 bits (UART framing: start bit, 8 data
bits, stop bit) and every message carries a ``header_bytes`` header (default
4: start byte, type, length, checksum; the papers give none), so one message
of n bytes takes ``(n + header_bytes) * 10 / rate`` seconds. Propagation on a
few metres of cable (< 1 us) is neglected next to milliseconds of
transmission.

* :class:`SerialStar`: one full-duplex line between the hub (the
  coordinator, station 0 by default) and each other station; each direction
  of each line is a FIFO queue. A frame between two robots is relayed by the
  hub (two hops, store and forward); a broadcast from the hub goes out on
  every line at once, a broadcast from a robot goes to the hub, which relays
  it on every other line.
* :class:`SerialBus`: one shared half-duplex line (about 10 kb/s, S2.8: the
  paper calls it unsuitable); one global FIFO queue for the bus, every
  station hears every frame. Arbitration is ideal (no collisions, no
  polling overhead): a lower bound for a real polled bus.

Examples
--------
>>> from workcell.sim.events.loop import EventLoop
>>> from workcell.sim.comms.medium import Frame
>>> k = EventLoop()
>>> m = SerialStar(k, stations=3, rate=9600.0, header_bytes=0)
>>> f = m.send(Frame(src=1, dst=0, size=51, kind="position"))
>>> k.run()
>>> round(m.stats.max(), 6) == round(51 * 10 / 9600, 6)
True
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from multiarm.errors import ValidationError
from workcell.sim.comms.medium import BROADCAST, BaseMedium, Frame
from workcell.sim.events.loop import EventLoop

__all__ = ["SerialBus", "SerialStar", "line_time"]

BITS_PER_BYTE = 10
"""UART framing: start + 8 data + stop."""


def line_time(size: int, rate: float, header_bytes: int = 4) -> float:
    """Seconds to send one message of ``size`` bytes on a serial line.

    Parameters
    ----------
    size : int
        Message bytes.
    rate : float
        Bits per second.
    header_bytes : int, optional
        Header bytes added to every message.

    Returns
    -------
    float
        ``(size + header_bytes) * 10 / rate``.

    Examples
    --------
    >>> line_time(51, 9600.0, header_bytes=0)
    0.053125
    """
    return (size + header_bytes) * BITS_PER_BYTE / rate


class _Line:
    """One direction of one line: a FIFO served at ``rate``."""

    __slots__ = ("free_at",)

    def __init__(self) -> None:
        self.free_at = 0.0


def _check(rate: float, header_bytes: int, where: str) -> None:
    if not (rate > 0 and math.isfinite(rate)):
        raise ValidationError(f"{where}: rate must be > 0 bits/s, got {rate!r}")
    if header_bytes < 0:
        raise ValidationError(f"{where}: header_bytes must be >= 0, got {header_bytes}")


class SerialStar(BaseMedium):
    """One full-duplex serial line per station to the hub (S2.8).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    stations : int or sequence of int
        Stations (the hub included).
    rate : float, optional
        Bits per second per line (default 9600; 9.6-115.2 kb/s are usual).
    header_bytes : int, optional
        Header per message, bytes (default 4).
    hub : int, optional
        The coordinator's station (default 0).

    Raises
    ------
    ValidationError
        For a bad rate, header or hub.
    """

    def __init__(
        self,
        kernel: EventLoop,
        stations: int | Sequence[int],
        rate: float = 9600.0,
        header_bytes: int = 4,
        hub: int = 0,
    ) -> None:
        super().__init__(kernel, stations)
        _check(rate, header_bytes, "SerialStar")
        self._check_station(hub, "hub")
        self.rate = float(rate)
        self.header_bytes = header_bytes
        self.hub = hub
        self._up = [_Line() for _ in range(self.n_stations)]  # station -> hub
        self._down = [_Line() for _ in range(self.n_stations)]  # hub -> station

    def _send_on(self, line: _Line, frame: Frame, at: float) -> float:
        start = max(at, line.free_at)
        line.free_at = start + line_time(frame.size, self.rate, self.header_bytes)
        return line.free_at

    def _transmit(self, frame: Frame) -> None:
        now = self.kernel.now
        if frame.src == self.hub:
            targets = self.destinations(frame)
            for d in targets:
                t = self._send_on(self._down[d], frame, now)
                self.kernel.schedule(t, self._deliver, frame, d, absolute=True)
            return
        t_hub = self._send_on(self._up[frame.src], frame, now)
        if frame.dst == self.hub:
            self.kernel.schedule(t_hub, self._deliver, frame, self.hub, absolute=True)
            return
        self.kernel.schedule(t_hub, self._relay, frame, absolute=True)

    def _relay(self, frame: Frame) -> None:
        now = self.kernel.now
        for d in self.destinations(frame):
            if d == self.hub:
                self._deliver(frame, d)
                continue
            t = self._send_on(self._down[d], frame, now)
            self.kernel.schedule(t, self._deliver, frame, d, absolute=True)


class SerialBus(BaseMedium):
    """One shared serial line for every station (S2.8, about 10 kb/s).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    stations : int or sequence of int
        Stations.
    rate : float, optional
        Bits per second (default 9600).
    header_bytes : int, optional
        Header per message, bytes (default 4).

    Raises
    ------
    ValidationError
        For a bad rate or header.

    Examples
    --------
    >>> from workcell.sim.events.loop import EventLoop
    >>> from workcell.sim.comms.medium import Frame, BROADCAST
    >>> k = EventLoop()
    >>> m = SerialBus(k, 3, rate=10_000.0, header_bytes=0)
    >>> for s in (1, 2):
    ...     _ = m.send(Frame(src=s, dst=0, size=50))
    >>> k.run()
    >>> [round(float(d), 3) for d in m.stats.delays()]   # the second queues behind the first
    [0.05, 0.1]
    """

    def __init__(
        self,
        kernel: EventLoop,
        stations: int | Sequence[int],
        rate: float = 9600.0,
        header_bytes: int = 4,
    ) -> None:
        super().__init__(kernel, stations)
        _check(rate, header_bytes, "SerialBus")
        self.rate = float(rate)
        self.header_bytes = header_bytes
        self._line = _Line()

    broadcast_once = True
    """One transfer on the one line: every station hears it."""

    def _transmit(self, frame: Frame) -> None:
        t = self._send_on(frame)
        self.kernel.schedule(t, self._deliver_all, frame, absolute=True)

    def _send_on(self, frame: Frame) -> float:
        start = max(self.kernel.now, self._line.free_at)
        self._line.free_at = start + line_time(frame.size, self.rate, self.header_bytes)
        return self._line.free_at


_ = BROADCAST  # re-exported meaning: a broadcast reaches every other station
