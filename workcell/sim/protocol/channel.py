"""The streams between the coordinator and each arm: every frame between
an arm's station and the coordinator's, the S2.7 messages and the records
of the S2.12 exchange (:mod:`workcell.sim.protocol.exchange`), numbered per
arm and direction and taken in order.

Examples
--------
>>> import numpy as np
>>> from workcell.sim.comms.link import Link
>>> from workcell.sim.comms.medium import FixedLatencyMedium
>>> from workcell.sim.events.loop import EventLoop
>>> from workcell.sim.events.trace import Trace
>>> k = EventLoop()
>>> names = ["coordinator", "a", "b"]
>>> link = Link(k, FixedLatencyMedium(k, 3, 1e-3), Trace(), names, None, np.random.default_rng(0))
>>> from workcell.sim.protocol.exchange import ReleaseHold, TaskStarted
>>> ch = ControlChannel(2, link)
>>> link.receivers[0] = ch.at_coordinator
>>> link.receivers[2] = lambda frame: ch.at_station(1, frame)
>>> got = []
>>> ch.attach_coordination(lambda arm, rec, taken: got.append((k.now, arm, type(rec).__name__)))
>>> ch.attach_arm(1, lambda rec: got.append((k.now, "arm 1", type(rec).__name__)))
>>> ch.report(1, TaskStarted(3, 0.0))
>>> _ = ch.order(1, ReleaseHold())
>>> k.run()
>>> got, ch.sent, link.sent
([(0.001, 1, 'TaskStarted'), (0.001, 'arm 1', 'ReleaseHold')], 2, 2)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from multiarm.errors import InternalError
from workcell.sim.comms.link import Link, describe_payload
from workcell.sim.comms.medium import Frame
from workcell.sim.protocol.exchange import KINDS, ORDERS, REPORTS, Order, Report

__all__ = ["ControlChannel", "Sequenced"]


@dataclass(frozen=True, slots=True)
class Sequenced:
    """A payload in its frame between an arm and the coordinator (frozen).

    Attributes
    ----------
    seq : int
        Its number in its direction of its arm's stream (0, 1, 2, ...).
    record : Any
        The record of the exchange or the S2.7 message's payload.
    taken : int
        Arm to coordinator: the number of the last frame from the
        coordinator the arm took when it sent this one (-1: none), so the
        coordinator knows which of its answers an arm's report follows.
    """

    seq: int
    record: Any
    taken: int = -1

    def describe(self) -> str:
        """What the trace says of the payload."""
        return describe_payload(self.record)


class ControlChannel:
    """The streams between the coordinator and each arm (module docstring):
    construction-time routing over the :class:`~workcell.sim.comms.link.Link`,
    with no delivery of its own.

    Every frame between an arm's station and the coordinator's (the S2.7
    messages and the records of the exchange, each direction of each arm a
    stream) carries a :class:`Sequenced` number and is taken in order: a
    frame that arrives before one sent earlier (which was lost and is being
    sent again) waits for it. Broadcasts and frames between arms go on the
    link as they are. A coordination that shares the arms' stations (the
    distributed peers, ``colocated``) takes its own arm's records at the
    station, without the medium.

    Parameters
    ----------
    arms : int
        Number of arms.
    link : Link, optional
        The medium's link (``None``: only the colocated paths work).

    Attributes
    ----------
    sent : int
        Frames sent through the streams (both directions).
    waited : int
        Frames that arrived out of order and waited for an earlier one.
    """

    def __init__(self, arms: int, link: Link | None = None) -> None:
        self.n_arms = int(arms)
        self.link = link
        self._arm_rx: list[Callable[[Any], None] | None] = [None] * self.n_arms
        self._arm_msg: list[Callable[[str, Any], None] | None] = [None] * self.n_arms
        self._coord_rx: Callable[[int, Any, int], None] | None = None
        self._frames_rx: Callable[[Frame], None] | None = None
        self._local_rx: Callable[[int, str, Any], None] | None = None
        self._station_rx: Callable[[int, Any], bool] | None = None
        self._next = [[0, 0] for _ in range(self.n_arms)]
        """Per arm: next number of its stream up (to the coordinator), down."""
        self._expect = [[0, 0] for _ in range(self.n_arms)]
        """Per arm: the number each stream's receiver takes next."""
        self._early: list[list[dict[int, Frame]]] = [[{}, {}] for _ in range(self.n_arms)]
        """Per arm and stream: frames that came before an earlier one."""
        self.taken = [-1] * self.n_arms
        """Per arm: the number of the last frame its station took from the coordinator."""
        self.sent = 0
        self.waited = 0

    def attach_arm(
        self,
        arm: int,
        receive: Callable[[Any], None],
        message: Callable[[str, Any], None] | None = None,
    ) -> None:
        """The arm's controller takes its orders with ``receive(order)``
        and the coordination's messages at its station with
        ``message(kind, payload)``."""
        self._arm_rx[arm] = receive
        self._arm_msg[arm] = message

    def attach_coordination(
        self,
        receive: Callable[[int, Any, int], None],
        local: Callable[[int, str, Any], None] | None = None,
        station: Callable[[int, Any], bool] | None = None,
        frames: Callable[[Frame], None] | None = None,
    ) -> None:
        """The coordination takes reports with ``receive(arm, report,
        taken)`` (``taken``: :attr:`Sequenced.taken`) and the arms' S2.7
        messages with ``frames(frame)``. A policy whose peers share the
        arms' stations also takes the controllers' messages with
        ``local(station, kind, payload)`` and the frames that reach arm
        ``a``'s station first with ``station(a, frame) -> taken``."""
        self._coord_rx = receive
        self._local_rx = local
        self._station_rx = station
        self._frames_rx = frames

    @property
    def colocated(self) -> bool:
        """The coordination takes the controllers' messages at their own station."""
        return self._local_rx is not None

    # ------------------------------------------------------------ sending
    def send(self, src: int, dst: int, kind: str, payload: Any) -> None:
        """Send an S2.7 message: on its arm's stream between an arm and the
        coordinator, else on the link as it is (broadcasts)."""
        if src == 0 and dst > 0:
            self._put(dst - 1, 1, kind, payload)
        elif dst == 0 and src > 0:
            if self._local_rx is not None:
                self._local_rx(src, kind, payload)
            else:
                self._put(src - 1, 0, kind, payload)
        else:
            self._link().send(src, dst, kind, payload)

    def report(self, arm: int, record: Report) -> None:
        """Send ``record`` from ``arm`` to the coordination."""
        if self._local_rx is not None:  # the coordination at the arm's station
            self.sent += 1
            rx = self._coord_rx
            if rx is not None:
                rx(arm, record, self.taken[arm])
            return
        self._put(arm, 0, KINDS[type(record)], record)

    def next_order(self, arm: int) -> int:
        """The number the next frame from the coordinator to ``arm`` will carry."""
        return self._next[arm][1]

    def order(self, arm: int, record: Order) -> int:
        """Send ``record`` from the coordination to ``arm``; returns its number."""
        if self._local_rx is not None:  # the coordination at the arm's station
            seq = self._next[arm][1]
            self._next[arm][1] = seq + 1
            self._expect[arm][1] = seq + 1
            self.sent += 1
            self.taken[arm] = seq
            self._arm(arm)(record)
            return seq
        return self._put(arm, 1, KINDS[type(record)], record)

    def _link(self) -> Link:
        if self.link is None:
            raise InternalError("control channel: no link to send on")
        return self.link

    def _put(self, arm: int, way: int, kind: str, payload: Any) -> int:
        seq = self._next[arm][way]
        self._next[arm][way] = seq + 1
        self.sent += 1
        if way == 0:
            self._link().send(arm + 1, 0, kind, Sequenced(seq, payload, self.taken[arm]))
        else:
            self._link().send(0, arm + 1, kind, Sequenced(seq, payload))
        return seq

    # ---------------------------------------------------------- receiving
    def at_coordinator(self, frame: Frame) -> None:
        """A frame reached the coordinator's station (the link's receiver)."""
        env = frame.payload[0]  # type: ignore[index]
        if isinstance(env, Sequenced) and frame.src > 0:
            self._take(frame.src - 1, 0, frame, env)
        elif self._frames_rx is not None:
            self._frames_rx(frame)

    def at_station(self, arm: int, frame: Frame) -> None:
        """A frame reached ``arm``'s station (the link's receiver): its
        stream's frames in order; a coordination sharing the station takes
        the others first, else the controller does."""
        env = frame.payload[0]  # type: ignore[index]
        if isinstance(env, Sequenced) and frame.src == 0:
            self._take(arm, 1, frame, env)
            return
        take = self._station_rx
        if take is not None and take(arm, frame):
            return
        self.to_controller(arm, frame.kind, env)

    def _take(self, arm: int, way: int, frame: Frame, env: Sequenced) -> None:
        expect = self._expect[arm][way]
        if env.seq < expect:  # pragma: no cover - the link drops duplicates
            return
        early = self._early[arm][way]
        if env.seq > expect:
            self.waited += 1
            early[env.seq] = frame
            return
        while True:
            self._expect[arm][way] = env.seq + 1
            self._deliver(arm, way, frame, env)
            nxt = early.pop(env.seq + 1, None)
            if nxt is None:
                return
            frame = nxt
            env = frame.payload[0]  # type: ignore[index]

    def _deliver(self, arm: int, way: int, frame: Frame, env: Sequenced) -> None:
        record = env.record
        if way == 1:
            self.taken[arm] = env.seq
            if isinstance(record, ORDERS):
                self._arm(arm)(record)
            else:
                self.to_controller(arm, frame.kind, record)
            return
        if isinstance(record, REPORTS):
            rx = self._coord_rx
            if rx is not None:
                rx(arm, record, env.taken)
        elif self._frames_rx is not None:
            self._frames_rx(frame.with_payload((record, frame.payload[1])))  # type: ignore[index]

    def _arm(self, arm: int) -> Callable[[Any], None]:
        rx = self._arm_rx[arm]
        if rx is None:
            raise InternalError(f"control channel: no controller for arm {arm}")
        return rx

    def to_controller(self, arm: int, kind: str, payload: Any) -> None:
        """A coordination message handed to ``arm``'s controller at its station."""
        rx = self._arm_msg[arm]
        if rx is None:
            raise InternalError(f"control channel: no controller at arm {arm}'s station")
        rx(kind, payload)

    def local(self, station: int, kind: str, payload: Any) -> None:
        """A controller's message to a coordination at its own station."""
        if self._local_rx is None:
            raise InternalError("control channel: no coordination at the arms' stations")
        self._local_rx(station, kind, payload)
