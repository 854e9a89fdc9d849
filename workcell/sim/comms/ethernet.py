"""Ethernet CSMA/CD and CSMA/DCR on one bus, event by event (S2.8, S2.9).

Stations sit at given positions (metres) along a bus; a signal travels at
``propagation_speed`` (default 2e8 m/s, about 2/3 of c in coaxial cable).
A station *senses carrier* at its own position: it hears a transmission from
``start + d / v`` to ``end + d / v`` (d = distance between the two stations).

* **Deferral (1-persistent).** A station with a frame waits until the channel
  has been idle at its position for one IFS, then transmits.
* **Collision.** A station that starts while another's signal has not yet
  reached it collides with it; each detects the other's signal on arrival
  (+ ``detect_delay``, the epsilon of S2.9), stops and sends a 32-bit jam.
* **CSMA/CD** (``mode="csma_cd"``): after the n-th collision of a frame the
  station waits r slots, r uniform in [0, 2^k - 1], k = min(n, 10) (binary
  exponential backoff, IEEE 802.3), then defers as above; after 16
  attempts the frame is dropped (drop callback, reason ``"excessive
  collisions"``). Seeded.
* **CSMA/DCR** (``mode="csma_dcr"``): a collision opens a resolution
  epoch. Every station that has heard the collision stops contending; when
  the channel is quiet (last jam + tau + IFS), every station with a frame
  waiting -- the colliders and those that deferred -- transmits one frame in
  a fixed order (station number, or ``order``), back to back with tau + IFS
  between frames (the worst-case end-to-end propagation as guard). Frames
  that arrive during the epoch wait for its end. With at most one frame per
  station in a round, delay is bounded by
  :func:`workcell.sim.comms.dcr.dcr_bound` (checked by the tests over
  random positions, orders and arrival times).
* **Transmit chain** (:class:`TransmitChain`): each station's LAN
  coprocessor holds a chain of frames, ordered by priority (default for
  DCR) or FIFO. The head frame is loaded into the 64-byte transmit FIFO as
  soon as it is at the head and can no longer be overtaken: a new urgent
  frame goes at best second (S2.9).

Frame sizes are taken as given (the S2.9 sizes include 26 bytes of overhead,
preamble included); ``min_frame_bytes`` pads short frames (64 + 8 on real
Ethernet; 0 by default, as in the paper's arithmetic).

Not modelled: bit errors, the capture effect, transceiver and repeater
delays, the exact shape of jam signals, 802.3's carrier-sense window within
the second part of the IFS.

Examples
--------
>>> from workcell.sim.events.loop import EventLoop
>>> from workcell.sim.comms.medium import Frame
>>> k = EventLoop()
>>> m = EthernetMedium(k, positions=[0.0, 50.0, 100.0], mode="csma_dcr")
>>> got = []
>>> for s in (1, 2):
...     m.attach(s, lambda f, t: got.append((f.src, round(t * 1e6, 1))))
>>> m.attach(0, lambda f, t: got.append((f.src, round(t * 1e6, 1))))
>>> for s in (1, 2):
...     _ = m.send(Frame(src=s, dst=0, size=51, kind="position"))
>>> k.run()
>>> got   # collision, jam, then station 1 and station 2 in order
[(1, 54.6), (2, 105.8)]
"""

from __future__ import annotations

import heapq
import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, Seed, as_rng
from workcell.sim.comms.medium import BaseMedium, Frame
from workcell.sim.events.loop import EventLoop, Handle

__all__ = ["EthernetMedium", "EthernetParams", "Mode", "TransmitChain"]

Mode = Literal["csma_cd", "csma_dcr"]
"""Channel access: binary exponential backoff or deterministic resolution."""


@dataclass(frozen=True, slots=True)
class EthernetParams:
    """Physical and MAC parameters (10 Mb/s Ethernet by default).

    Parameters
    ----------
    rate : float
        Bits per second.
    slot_time : float
        Seconds (51.2e-6 = 512 bit times).
    ifs : float
        Interframe spacing, seconds.
    jam_bits : int
        Jam length, bits.
    propagation_speed : float
        Metres per second.
    max_attempts : int
        Transmission attempts before a frame is dropped (CSMA/CD).
    backoff_limit : int
        k = min(n, backoff_limit) in the backoff range [0, 2^k - 1].
    detect_delay : float
        Collision detection time epsilon, seconds.
    min_frame_bytes : int
        Short frames are padded to this size (0: no padding).

    Raises
    ------
    ValidationError
        For non-positive values.
    """

    rate: float = 10e6
    slot_time: float = 51.2e-6
    ifs: float = 9.6e-6
    jam_bits: int = 32
    propagation_speed: float = 2e8
    max_attempts: int = 16
    backoff_limit: int = 10
    detect_delay: float = 0.0
    min_frame_bytes: int = 0

    def __post_init__(self) -> None:
        for name in ("rate", "slot_time", "propagation_speed", "max_attempts", "jam_bits"):
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ValidationError(f"EthernetParams: {name} must be > 0, got {v!r}")
        for name in ("ifs", "detect_delay", "min_frame_bytes", "backoff_limit"):
            v = getattr(self, name)
            if not (v >= 0 and math.isfinite(v)):
                raise ValidationError(f"EthernetParams: {name} must be >= 0, got {v!r}")


class TransmitChain:
    """A station's transmit queue (the LAN coprocessor's chain of TRANSMIT
    commands, S2.9).

    Parameters
    ----------
    by_priority : bool
        Order waiting frames by ``Frame.priority`` (lower first, FIFO among
        equals) instead of arrival.

    Notes
    -----
    The head frame is *committed*: it has started to fill the 64-byte
    transmit FIFO and is sent first whatever arrives later. A more urgent
    frame arriving meanwhile becomes the next head, i.e. goes at best second.

    Examples
    --------
    >>> from workcell.sim.comms.medium import Frame
    >>> c = TransmitChain(by_priority=True)
    >>> for prio, kind in ((5, "position"), (5, "position2"), (0, "alarm")):
    ...     c.push(Frame(src=0, dst=1, size=51, kind=kind, priority=prio))
    >>> [c.pop().kind for _ in range(3)]
    ['position', 'alarm', 'position2']
    """

    __slots__ = ("_fifo", "_heap", "_seq", "by_priority", "head")

    def __init__(self, by_priority: bool) -> None:
        self.by_priority = by_priority
        self.head: Frame | None = None
        self._heap: list[tuple[int, int, Frame]] = []
        self._fifo: deque[Frame] = deque()
        self._seq = 0

    def __len__(self) -> int:
        return (self.head is not None) + len(self._heap) + len(self._fifo)

    def push(self, frame: Frame) -> None:
        """Queue ``frame``; it becomes the committed head if the chain is empty.

        Parameters
        ----------
        frame : Frame
            The frame.
        """
        if self.head is None:
            self.head = frame
        elif self.by_priority:
            heapq.heappush(self._heap, (frame.priority, self._seq, frame))
            self._seq += 1
        else:
            self._fifo.append(frame)

    def pop(self) -> Frame:
        """Remove and return the head; the next frame becomes the head.

        Returns
        -------
        Frame
            The former head.

        Raises
        ------
        ValidationError
            If the chain is empty.
        """
        if self.head is None:
            raise ValidationError("TransmitChain.pop: the chain is empty")
        out = self.head
        if self._heap:
            self.head = heapq.heappop(self._heap)[2]
        elif self._fifo:
            self.head = self._fifo.popleft()
        else:
            self.head = None
        return out


class _Tx:
    __slots__ = ("collided", "end", "frame", "handle", "src", "start")

    def __init__(self, src: int, start: float, end: float, frame: Frame) -> None:
        self.src = src
        self.start = start
        self.end = end
        self.frame = frame
        self.collided = False
        self.handle: Handle | None = None


class EthernetMedium(BaseMedium):
    """CSMA/CD or CSMA/DCR bus (see the module docstring).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    positions : sequence of float
        Position of each station along the bus, metres (station i at
        ``positions[i]``).
    mode : {"csma_cd", "csma_dcr"}, optional
        Channel access.
    params : EthernetParams, optional
        Parameters (10 Mb/s Ethernet by default).
    order : sequence of int, optional
        DCR transmission order after a collision (default by station number).
    priority_chain : bool, optional
        Priority-ordered transmit chains (default: True for DCR, False for
        CSMA/CD).
    seed : int or Generator, optional
        Random source of the backoff.

    Attributes
    ----------
    collisions : int
        Collisions seen (pairs of overlapping transmissions).
    epochs : int
        DCR resolution epochs run.

    Raises
    ------
    ValidationError
        For fewer than two stations, non-finite positions or a bad order.
    """

    broadcast_once = True
    """One transmission on the bus: every station hears it."""

    def __init__(
        self,
        kernel: EventLoop,
        positions: Sequence[float] | FloatArray,
        mode: Mode = "csma_cd",
        params: EthernetParams | None = None,
        order: Sequence[int] | None = None,
        priority_chain: bool | None = None,
        seed: Seed = None,
    ) -> None:
        super().__init__(kernel, len(positions))
        pos = np.asarray(positions, dtype=np.float64)
        if not np.all(np.isfinite(pos)):
            raise ValidationError(f"EthernetMedium: positions must be finite, got {positions}")
        if mode not in ("csma_cd", "csma_dcr"):
            raise ValidationError(f"EthernetMedium: unknown mode {mode!r}")
        self.mode: Mode = mode
        self.params = params if params is not None else EthernetParams()
        self.positions = pos
        n = len(pos)
        rank = list(range(n)) if order is None else list(order)
        if sorted(rank) != list(range(n)):
            raise ValidationError(
                f"EthernetMedium: order {rank} is not a permutation of 0..{n - 1}"
            )
        self._rank = {s: i for i, s in enumerate(rank)}
        v = self.params.propagation_speed
        dt = np.abs(pos[:, None] - pos[None, :]) / v
        self._dt: list[list[float]] = dt.tolist()
        self.tau = float(dt.max())
        by_prio = (mode == "csma_dcr") if priority_chain is None else priority_chain
        self.chains = [TransmitChain(by_prio) for _ in range(n)]
        self._rng = as_rng(seed)
        self._attempts = [0] * n
        self._busy = [False] * n  # has a pending attempt / backoff / transmission
        self._txs: list[_Tx] = []
        self._epoch: list[int] | None = None
        self._resolving = False
        self._heard_at = [math.inf] * n
        self._later: list[Handle | None] = [None] * n
        self._epoch_pending: set[int] = set()
        self._collided: set[int] = set()
        self._epoch_handle: Handle | None = None
        self._held: list[int] = []
        self.collisions = 0
        self.epochs = 0

    # ----------------------------------------------------------- sending ---
    def _transmit(self, frame: Frame) -> None:
        s = frame.src
        self.chains[s].push(frame)
        if not self._busy[s]:
            self._busy[s] = True
            self._attempt(s)

    def _frame_time(self, frame: Frame) -> float:
        return max(frame.size, self.params.min_frame_bytes) * 8 / self.params.rate

    def _quiet_since(self, s: int, t: float) -> tuple[bool, float]:
        """(carrier present at s at t, time the carrier at s ends or ended)."""
        dt = self._dt[s]
        last = -math.inf
        busy = False
        changed = True
        idle_at = t
        while changed:
            changed = False
            for tx in self._txs:
                arrive = tx.start + dt[tx.src]
                leave = tx.end + dt[tx.src]
                if arrive < idle_at < leave:
                    busy = True
                    idle_at = leave
                    changed = True
                if leave <= t and leave > last:
                    last = leave
        return busy, (idle_at if busy else last)

    def _attempt(self, s: int) -> None:
        now = self.kernel.now
        if self._resolving and now >= self._heard_at[s] and s not in self._epoch_pending:
            self._held.append(s)
            return
        busy, edge = self._quiet_since(s, now)
        ready = edge + self.params.ifs
        if busy or ready > now:
            self._later[s] = self.kernel.schedule(ready, self._attempt, s, absolute=True)
            return
        self._start(s)

    def _start(self, s: int) -> None:
        now = self.kernel.now
        frame = self.chains[s].head
        if frame is None:  # pragma: no cover - guarded by _busy
            self._busy[s] = False
            return
        me = _Tx(s, now, now + self._frame_time(frame), frame)
        jam = self.params.jam_bits / self.params.rate
        eps = self.params.detect_delay
        for tx in self._txs:
            if tx.src == s:
                continue
            d = self._dt[s][tx.src]
            if tx.start + d >= now:  # s could not hear it when it started: collision
                self.collisions += 1
                me.end = min(me.end, tx.start + d + eps + jam)
                me.collided = True
                new_end = max(tx.start, now + d + eps) + jam
                if new_end < tx.end or not tx.collided:
                    tx.end = min(tx.end, new_end)
                    tx.collided = True
                    if tx.handle is not None:
                        tx.handle.cancel()
                    if tx.end >= now:
                        tx.handle = self.kernel.schedule(tx.end, self._end, tx, absolute=True)
                    self._collided.add(tx.src)
        if me.collided:
            self._collided.add(s)
            if self.mode == "csma_dcr":
                # every station knows a resolution is coming once the colliding
                # signals reach it; one that starts earlier joins the collision
                self._resolving = True
                for t in [*self._txs, me]:
                    if t.collided:
                        dt = self._dt[t.src]
                        for x in range(self.n_stations):
                            self._heard_at[x] = min(self._heard_at[x], t.start + dt[x])
        self._txs.append(me)
        me.handle = self.kernel.schedule(me.end, self._end, me, absolute=True)

    def _end(self, tx: _Tx) -> None:
        now = self.kernel.now
        horizon = now - 2 * self.tau - self.params.ifs - 1e-9
        self._txs = [t for t in self._txs if t.end + self.tau >= horizon or t is tx]
        s = tx.src
        if not tx.collided:
            frame = self.chains[s].pop()
            self._attempts[s] = 0
            for d in self.destinations(frame):
                self.kernel.schedule(self._dt[s][d], self._deliver, frame, d)
            self._next(s, now + self.params.ifs)
            if self._epoch is not None:
                self._epoch_step(now + self.tau + self.params.ifs)
            return
        if self.mode == "csma_dcr":
            self._maybe_open_epoch()
            return
        self._attempts[s] += 1
        n = self._attempts[s]
        if n >= self.params.max_attempts:
            frame = self.chains[s].pop()
            self._attempts[s] = 0
            self._drop(frame, f"excessive collisions ({n} attempts)")
            self._next(s, now)
            return
        k = min(n, self.params.backoff_limit)
        r = int(self._rng.integers(0, 2**k))
        self._later[s] = self.kernel.schedule(r * self.params.slot_time, self._attempt, s)

    def _next(self, s: int, at: float) -> None:
        if self.chains[s].head is None:
            self._busy[s] = False
        else:
            self._later[s] = self.kernel.schedule(at, self._attempt, s, absolute=True)

    # --------------------------------------------------------------- DCR ---
    def _maybe_open_epoch(self) -> None:
        now = self.kernel.now
        if any(t.collided and t.end > now for t in self._txs):
            return
        if self._epoch_handle is not None:
            self._epoch_handle.cancel()
        start = now + self.tau + self.params.ifs
        self._epoch_handle = self.kernel.schedule(start, self._open_epoch, absolute=True)

    def _open_epoch(self) -> None:
        now = self.kernel.now
        self._epoch_handle = None
        if any(t.collided and t.end > now for t in self._txs):
            return  # a late collider; its end reopens the epoch
        # DCR resolves every station with a frame waiting when the epoch
        # begins: the colliders, and those deferring or held meanwhile
        sending = {t.src for t in self._txs if t.end > now}
        waiting = {
            x
            for x in range(self.n_stations)
            if self._busy[x] and x not in sending and self.chains[x].head is not None
        }
        for x in waiting - self._collided:
            h = self._later[x]
            if h is not None:
                h.cancel()
        self._held = [x for x in self._held if x not in waiting]
        members = sorted(self._collided | waiting, key=self._rank.__getitem__)
        self._collided = set()
        if self._epoch is not None:  # a collision inside an epoch cannot happen
            self._epoch_pending.update(members)
            return
        self.epochs += 1
        self._epoch = members
        self._epoch_pending = set(members)
        self._epoch_step(now)

    def _epoch_step(self, at: float) -> None:
        if self._epoch is None:  # pragma: no cover - only called inside an epoch
            return
        if not self._epoch:
            self._epoch = None
            self._resolving = False
            self._heard_at = [math.inf] * self.n_stations
            self._epoch_pending = set()
            held, self._held = self._held, []
            for s in held:
                self._later[s] = self.kernel.schedule(
                    at - self.params.ifs, self._attempt, s, absolute=True
                )
            return
        s = self._epoch.pop(0)
        self._epoch_pending.discard(s)
        self.kernel.schedule(at, self._start, s, absolute=True)
