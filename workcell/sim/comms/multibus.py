"""Multibus II message passing (S2.8).

The parallel system bus moves data at 40 Mbyte/s. Message passing has two
kinds of messages:

* **unsolicited**: a fixed 32-byte packet carrying ``unsolicited_payload``
  (20) user bytes, sent at once; a coordination message of n bytes is split
  into ceil(n / 20) unsolicited messages and is delivered when the last has
  arrived. Alarms go as *broadcast* unsolicited messages (one bus transfer
  reaches every agent).
* **solicited**: for long data (trajectories): a buffer request (one
  unsolicited message), a buffer grant back (another), then the data moved
  in 32-byte bus transfers.

Assumed per-message overheads (the paper gives none; all configurable):
bus arbitration + handshake ``arbitration`` = 0.2 us per bus transfer, and
``mpc_latency`` = 2 us per message in each message-passing coprocessor
(queueing the message, interrupting the receiving CPU). The bus is one
shared resource: every transfer waits for the bus in FIFO order (real
Multibus II arbitration is fair round-robin; with single transfers the two
agree).

Examples
--------
>>> unsolicited_count(51)
3
>>> from workcell.sim.events.loop import EventLoop
>>> from workcell.sim.comms.medium import Frame
>>> k = EventLoop()
>>> m = MultibusII(k, 3)
>>> _ = m.send(Frame(src=1, dst=0, size=51, kind="position"))
>>> k.run()
>>> m.transfers, round(m.stats.max() * 1e6, 2)
(3, 5.0)
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence

from multiarm.errors import ValidationError
from workcell.sim.comms.medium import BROADCAST, BaseMedium, Frame
from workcell.sim.events.loop import EventLoop

__all__ = ["MultibusII", "unsolicited_count"]

PACKET_BYTES = 32
"""Bytes moved by one bus transfer (one unsolicited message)."""


def unsolicited_count(size: int, payload: int = 20) -> int:
    """Unsolicited messages needed for ``size`` user bytes.

    Parameters
    ----------
    size : int
        Bytes (> 0).
    payload : int, optional
        User bytes per unsolicited message (default 20).

    Returns
    -------
    int
        ``ceil(size / payload)``.

    Raises
    ------
    ValidationError
        For a non-positive size or payload.

    Examples
    --------
    >>> [unsolicited_count(n) for n in (1, 20, 21, 40, 41)]
    [1, 1, 2, 2, 3]
    """
    if size <= 0 or payload <= 0:
        raise ValidationError(f"unsolicited_count: size={size} and payload={payload} must be > 0")
    return -(-size // payload)


class MultibusII(BaseMedium):
    """Multibus II message passing (see the module docstring).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    stations : int or sequence of int
        Agents on the bus.
    bandwidth : float, optional
        Bytes per second (default 40e6).
    unsolicited_payload : int, optional
        User bytes per unsolicited message (default 20).
    arbitration : float, optional
        Seconds per bus transfer for arbitration and handshake (default 0.2e-6).
    mpc_latency : float, optional
        Seconds per message in the coprocessors, sender and receiver
        together (default 2e-6).
    solicited_kinds : collection of str, optional
        Frame kinds sent as solicited messages (default ``{"trajectory"}``).

    Attributes
    ----------
    transfers : int
        Bus transfers made (unsolicited packets + solicited data packets).

    Raises
    ------
    ValidationError
        For non-positive parameters.
    """

    def __init__(
        self,
        kernel: EventLoop,
        stations: int | Sequence[int],
        bandwidth: float = 40e6,
        unsolicited_payload: int = 20,
        arbitration: float = 0.2e-6,
        mpc_latency: float = 2e-6,
        solicited_kinds: Collection[str] = ("trajectory",),
    ) -> None:
        super().__init__(kernel, stations)
        if not (bandwidth > 0 and math.isfinite(bandwidth)) or unsolicited_payload <= 0:
            raise ValidationError(
                f"MultibusII: bandwidth={bandwidth!r} and unsolicited_payload="
                f"{unsolicited_payload!r} must be > 0"
            )
        if arbitration < 0 or mpc_latency < 0:
            raise ValidationError("MultibusII: arbitration and mpc_latency must be >= 0")
        self.bandwidth = float(bandwidth)
        self.payload = unsolicited_payload
        self.arbitration = float(arbitration)
        self.mpc_latency = float(mpc_latency)
        self.solicited_kinds = frozenset(solicited_kinds)
        self._free_at = 0.0
        self.transfers = 0

    broadcast_once = True
    """A broadcast goes as unsolicited messages, the same bus transfers as
    one to one agent (the solicited kinds are never broadcast)."""

    def _transfer(self, at: float, nbytes: int) -> float:
        """Reserve the bus for one transfer of ``nbytes``; return its end."""
        start = max(at, self._free_at)
        self._free_at = start + self.arbitration + nbytes / self.bandwidth
        self.transfers += 1
        return self._free_at

    def _transmit(self, frame: Frame) -> None:
        now = self.kernel.now
        if frame.kind in self.solicited_kinds and frame.dst != BROADCAST:
            t = self._transfer(now, PACKET_BYTES)  # buffer request
            t = self._transfer(t, PACKET_BYTES)  # buffer grant
            for _ in range(-(-frame.size // PACKET_BYTES)):
                t = self._transfer(t, PACKET_BYTES)
        else:
            t = now
            for _ in range(unsolicited_count(frame.size, self.payload)):
                t = self._transfer(t, PACKET_BYTES)
        self.kernel.schedule(t + self.mpc_latency, self._deliver_all, frame, absolute=True)
