"""The coordination link: frames through a medium, numbered, lost and sent again.

:class:`Link` is how the coordinator and the arm controllers talk (S2.7,
S2.9): every message is a :class:`~workcell.sim.comms.medium.Frame` of the
S2.9 size (:data:`~workcell.sim.comms.medium.MESSAGE_BYTES`) put on the
medium. Each link ``(src, dst)`` numbers its frames 0, 1, 2, ...; a
retransmission keeps the number of the original. The receiver drops a
duplicate and a frame older than the withdrawal of its task, so a
retransmitted trajectory can never overtake the cancellation that withdrew
it. A lost frame (:class:`LossModel`, e.g. the
:class:`~workcell.sim.harness.faults.MessageLoss` fault) or one the medium
drops is sent again after a timeout.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from workcell.sim.comms.medium import MESSAGE_BYTES, Frame, Medium, trajectory_bytes
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace

__all__ = ["Link", "LossModel", "Network", "describe_payload"]

_TRAJECTORY_BYTES = trajectory_bytes(5)


class LossModel(Protocol):
    """What the link needs of a loss fault (:class:`~workcell.sim.harness.faults.MessageLoss`)."""

    @property
    def probability(self) -> float:
        """Chance that a frame is lost."""

    @property
    def kinds(self) -> tuple[str, ...] | None:
        """Message kinds that may be lost (None: every kind)."""

    @property
    def timeout(self) -> float:
        """Seconds before a lost frame is sent again."""


class Link:
    """Sends coordination messages through a medium, with loss and retransmission.

    Parameters
    ----------
    kernel : EventLoop
    medium : Medium
    trace : Trace
    names : sequence of str
        Station names (0: the coordinator, then the arms).
    loss : LossModel, optional
    rng : numpy Generator
    """

    def __init__(
        self,
        kernel: EventLoop,
        medium: Medium,
        trace: Trace,
        names: list[str],
        loss: LossModel | None,
        rng: np.random.Generator,
    ) -> None:
        self.kernel = kernel
        self.medium = medium
        self.trace = trace
        self.names = names
        self.loss = loss
        self.rng = rng
        self.receivers: dict[int, Callable[[Frame], None]] = {}
        self._next_seq: dict[tuple[int, int], int] = {}
        self._seen: dict[tuple[int, int, int], set[int]] = {}
        """(src, dst as sent, receiving station) -> sequence numbers delivered."""
        self._cancelled: dict[tuple[int, int], int] = {}
        """(receiving station, task) -> sequence number of its withdrawal."""
        self.stale = 0
        """Frames dropped at the receiver: duplicates and frames older than a
        withdrawal of their task."""
        self.sent = 0
        self.retransmissions = 0
        self.delays: list[float] = []
        self.broadcast_once = bool(getattr(medium, "broadcast_once", False))
        """A broadcast costs the medium one frame (:attr:`~workcell.sim.comms.
        medium.BaseMedium.broadcast_once`): a sender with one frame for
        several stations may broadcast it."""
        for st in range(len(names)):
            medium.attach(st, self._receiver(st))
        medium.on_drop(self._dropped)

    def send(
        self, src: int, dst: int, kind: str, payload: Any, retry: int = 0, seq: int = -1
    ) -> None:
        """Send a frame now (``dst`` may be BROADCAST).

        Each link ``(src, dst)`` numbers its frames 0, 1, 2, ...; a
        retransmission (``retry > 0``) keeps the number of the original
        (``seq``)."""
        size = _TRAJECTORY_BYTES if kind == "trajectory" else MESSAGE_BYTES[kind]
        if seq < 0:
            seq = self._next_seq.get((src, dst), 0)
            self._next_seq[(src, dst)] = seq + 1
        frame = Frame(src, dst, size, kind, 0, (payload, retry), self.kernel.now, seq=seq)
        self.sent += 1
        if retry:
            self.retransmissions += 1
        lp = self.loss
        if (
            lp is not None
            and lp.probability > 0
            and (lp.kinds is None or kind in lp.kinds)
            and self.rng.random() < lp.probability
        ):
            self.trace.add(
                self.kernel.now,
                "fault",
                arm=self._arm_of(src, dst),
                message=kind,
                src=src,
                dst=dst,
                size=size,
                detail=f"message lost or corrupted; sent again after {lp.timeout:g} s",
            )
            self.kernel.schedule(lp.timeout, self.send, src, dst, kind, payload, retry + 1, seq)
            return
        self.medium.send(frame)

    def _arm_of(self, src: int, dst: int) -> str:
        st = src if src > 0 else dst
        return self.names[st] if 0 < st < len(self.names) else ""

    def _receiver(self, station: int) -> Callable[[Frame, float], None]:
        def rx(frame: Frame, t: float) -> None:
            self._deliver(frame, t, station)

        return rx

    def _stale(self, frame: Frame, payload: Any, station: int) -> str:
        """Why the receiver drops ``frame`` ("" if it does not)."""
        link = (frame.src, frame.dst, station)
        seen = self._seen.get(link)
        if seen is None:
            seen = self._seen[link] = set()
        if frame.seq in seen:
            return f"duplicate (sequence number {frame.seq})"
        seen.add(frame.seq)
        task = _frame_task(frame.kind, payload)
        if task < 0 or frame.src != 0:
            return ""
        if frame.kind == "sleep" and getattr(payload, "withdraws", False):
            self._cancelled[(station, task)] = frame.seq
            return ""
        cut = self._cancelled.get((station, task), -1)
        if frame.seq < cut:
            return f"older than the withdrawal of task {task} (sequence number {frame.seq} < {cut})"
        return ""

    def _deliver(self, frame: Frame, t: float, station: int) -> None:
        payload: Any = frame.payload[0]  # type: ignore[index]
        why = self._stale(frame, payload, station)
        if why:
            self.stale += 1
            self.trace.add(
                t,
                "drop",
                arm=self._arm_of(frame.src, station),
                message=frame.kind,
                src=frame.src,
                dst=station,
                size=frame.size,
                detail=f"dropped at the receiver: {why}",
            )
            return
        delay = t - frame.send_time
        self.delays.append(delay)
        src = frame.src
        self.trace.row_described(
            t,
            "message",
            self._arm_of(src, station),
            frame.kind,
            src,
            station,
            frame.size,
            delay,
            describe_payload,
            payload,
        )
        rx = self.receivers.get(station)
        if rx is not None:
            rx(frame)

    def _dropped(self, frame: Frame, reason: str) -> None:
        payload: Any = frame.payload[0]  # type: ignore[index]
        retry: int = frame.payload[1]  # type: ignore[index]
        timeout = self.loss.timeout if self.loss is not None else 0.005
        self.trace.add(
            self.kernel.now,
            "fault",
            arm=self._arm_of(frame.src, frame.dst),
            message=frame.kind,
            src=frame.src,
            dst=frame.dst,
            size=frame.size,
            detail=f"dropped by the medium ({reason}); sent again after {timeout:g} s",
        )
        self.kernel.schedule(
            timeout, self.send, frame.src, frame.dst, frame.kind, payload, retry + 1, frame.seq
        )


def _frame_task(kind: str, payload: Any) -> int:
    """The task a coordinator frame is about (-1: none): a trajectory's, a
    grant's or wake-up's piece ``(kind, index, task, tau)``, a start
    permission or a withdrawal (a payload record's ``frame_task``)."""
    task = getattr(payload, "frame_task", None)
    if task is not None:
        return int(task)
    if (
        kind in ("zone_grant", "wake_up", "sleep")
        and isinstance(payload, tuple)
        and len(payload) == 4
        and payload[0] in ("zone", "move", "tool", "start", "withdraw")
    ):
        return int(payload[2])
    return -1


def describe_payload(payload: Any) -> str:
    """What the trace says of a frame's payload (its ``describe()`` if it has one)."""
    describe = getattr(payload, "describe", None)
    if describe is not None:
        return str(describe())
    if isinstance(payload, tuple) and len(payload) == 4 and isinstance(payload[0], str):
        return f"{payload[0]} {payload[1]} task {payload[2]} at {payload[3]:.6g}"
    if isinstance(payload, tuple) and payload and isinstance(payload[0], str):
        return str(payload[0])
    if isinstance(payload, int):
        return f"task {payload}"
    return ""


Network = Link
"""The former name of :class:`Link`."""
