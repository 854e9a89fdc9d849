"""The messages arm peers exchange under distributed coordination (S2.4, S2.7).

Under ``coordination="distributed"``
(:mod:`workcell.sim.coordination.distributed`) there is no coordinator: one
peer per arm, beside the arm's controller at the arm's station, and the peers
talk to each other over the same medium as the controllers would talk to a
coordinator. Each record below is the payload of one frame; the frame kinds
(and so the sizes, :data:`~workcell.sim.comms.medium.MESSAGE_BYTES`) are the
S2.7 ones whose role they take:

* :class:`Ask` (``zone_request``): may I take the resource at this place of
  its plan order? (the Ricart-Agrawala request);
* :class:`Reply` (``zone_grant``): every use of mine before that place is
  over (the reply; it also says how far I am);
* :class:`Notice` (``trajectory_end``): a task ended (done, or failed with
  its cause);
* :class:`Alarm` (``alarm`` / ``wake_up``): an emergency stop in force /
  released, matched by id;
* :class:`Activation` (``sleep`` / ``position`` / ``active_zone_grant``): a
  zone activation: stop / my arm stands / the change is made, go on;
* :class:`ArmOut` (``alarm``): an arm failed (the last frame of its station);
* :class:`PeerView` (``motion_report``): my arm's motion and standing, told
  to the peers whose arms may meet mine;
* :class:`Clearance` (``departure_request``): may my arm set off on this
  motion? (the Ricart-Agrawala request of the departure check, S2.12);
* :class:`ClearanceReply` (``motion_report``): the answer, with where my arm
  is; it reserves the asked motion at the replier until the asker's report
  that it stands;
* :class:`~workcell.sim.protocol.exchange.BackOffUntil` (``back_off``):
  please back off out of my arm's way (S2.6).

They are frozen records, never tuples, so the link's checks on the
coordinator's tuple payloads never apply to them.

Examples
--------
>>> a = Ask(("zone", 2), 5)
>>> a.resource, a.position
(('zone', 2), 5)
>>> Reply(("zone", 2), 7).upto
7
"""

from __future__ import annotations

from dataclasses import dataclass

from workcell.sim.protocol.exchange import ArmView, BackOffUntil

__all__ = [
    "ACTIVATION_KINDS",
    "PEER_RECORDS",
    "Activation",
    "Alarm",
    "ArmOut",
    "Ask",
    "Clearance",
    "ClearanceReply",
    "Notice",
    "PeerView",
    "Reply",
    "Resource",
]

Resource = tuple[str, int]
"""A resource: ``(kind, index)`` with kind ``"zone"`` (an exclusive zone's
occupancy), ``"move"`` (movement in a shared zone) or ``"tool"``."""


@dataclass(frozen=True, slots=True)
class Ask:
    """Request for ``resource`` at ``position`` of its plan order.

    Attributes
    ----------
    resource : Resource
    position : int
        Index in the resource's plan order of the use asked for.
    """

    resource: Resource
    position: int


@dataclass(frozen=True, slots=True)
class Reply:
    """Answer to :class:`Ask`: every use of ``resource`` by the sender placed
    before ``upto`` in the plan order is over.

    Attributes
    ----------
    resource : Resource
    upto : int
        The place of the sender's first use not over yet (or the order's
        length).
    """

    resource: Resource
    upto: int


@dataclass(frozen=True, slots=True)
class Notice:
    """Task ``task`` ended: ``outcome`` is ``"done"`` or ``"failed"``.

    Attributes
    ----------
    task : int
    outcome : str
    cause : str
        Why it failed ("" when done).
    cause_kind : str
        The category of the cause
        (:data:`~workcell.sim.coordination.constants.CAUSE_KINDS`).
    """

    task: int
    outcome: str
    cause: str = ""
    cause_kind: str = ""


@dataclass(frozen=True, slots=True)
class Alarm:
    """An emergency stop: ``on`` when it starts, off when it is released.

    Attributes
    ----------
    stop : int
        Its id (a release matches its stop by id).
    on : bool
    """

    stop: int
    on: bool


@dataclass(frozen=True, slots=True)
class Activation:
    """A zone activation (S2.5) agreed among the peers.

    Attributes
    ----------
    stop : int
        Its id (the stop and the release of every arm match by it).
    zones : tuple of str
        The zones to make active.
    phase : str
        ``"stop"`` (from the arm that raises it: stop and tell me),
        ``"stopped"`` (the answer: my arm stands) or ``"go"`` (the change
        is made: go on).
    origin : int
        The arm that raised it (and collects the answers).
    """

    stop: int
    zones: tuple[str, ...]
    phase: str
    origin: int


@dataclass(frozen=True, slots=True)
class ArmOut:
    """Arm ``arm`` failed: its last frame, broadcast by its station.

    Attributes
    ----------
    arm : int
    """

    arm: int


@dataclass(frozen=True, slots=True)
class PeerView:
    """The sender's arm's motion and standing (S2.7's report, peer to peer).

    Attributes
    ----------
    view : ArmView
        As its controller reported it at the sender's station.
    n : int
        The sender's count of the frames that carry its view
        (:class:`PeerView`, :class:`Clearance`, :class:`ClearanceReply`): a
        receiver keeps the view of the highest count it took, so a frame
        that a retransmission let overtake is not read as newer.
    decided : int
        The number of the sender's last departure request decided
        (:attr:`Clearance.ask`): with ``view`` standing, every motion asked
        for up to it is over (the receiver's reservations of them end).
    """

    view: ArmView
    n: int
    decided: int

    def describe(self) -> str:
        """What the trace says of it."""
        v = self.view
        state = "failed" if v.failed else "moving" if v.running else "standing"
        return f"arm {v.index} {state} (view {self.n}, decided {self.decided})"


@dataclass(frozen=True, slots=True)
class Clearance:
    """May the sender's arm set off from ``view`` towards its next station?

    Attributes
    ----------
    view, n, decided
        As :class:`PeerView` (the request carries the asker's view).
    ask : int
        The asker's request number (its controller's
        :attr:`~workcell.sim.protocol.exchange.DepartureRequest.ask`).
    clock : int
        The asker's Lamport time of the request: of two arms asking at once
        the lower ``(clock, arm)`` goes first (the other defers its reply).
    """

    view: ArmView
    n: int
    decided: int
    ask: int
    clock: int

    def describe(self) -> str:
        """What the trace says of it."""
        return f"arm {self.view.index} asks to set off (request {self.ask}, clock {self.clock})"


@dataclass(frozen=True, slots=True)
class ClearanceReply:
    """The answer to the :class:`Clearance` numbered ``ask``: where the
    replier's arm is (``view``: standing, or moving up to its next station),
    and a promise: the replier's arm starts no motion that the asked one
    would touch until the asker's report that it stands.

    Attributes
    ----------
    view, n, decided
        The replier's, as :class:`PeerView`.
    ask : int
        The asker's request it answers.
    """

    view: ArmView
    n: int
    decided: int
    ask: int

    def describe(self) -> str:
        """What the trace says of it."""
        return f"arm {self.view.index} answers request {self.ask}"


PEER_RECORDS: dict[type, str] = {
    Ask: "zone_request",
    Reply: "zone_grant",
    Notice: "trajectory_end",
    ArmOut: "alarm",
    PeerView: "motion_report",
    Clearance: "departure_request",
    ClearanceReply: "motion_report",
    BackOffUntil: "back_off",
}
"""The frame kind that carries each record, so its size
(:data:`~workcell.sim.comms.medium.MESSAGE_BYTES`: a view, a request or an
answer 67 bytes as the S2.12 report, whose acknowledgement and
request-number fields carry the count and the request numbers; the few
bytes of a request's Lamport clock are not counted; a back-off request 148
bytes as the back-off order). An :class:`Alarm` travels as
``alarm`` when on and ``wake_up`` when off; an :class:`Activation` as
``sleep``, ``position`` and ``active_zone_grant`` by phase)."""

ACTIVATION_KINDS: dict[str, str] = {
    "stop": "sleep",
    "stopped": "position",
    "go": "active_zone_grant",
}
"""The frame kind of each phase of an :class:`Activation`."""
