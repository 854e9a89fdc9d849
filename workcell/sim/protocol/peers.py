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
* :class:`ArmOut` (``alarm``): an arm failed (the last frame of its station).

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

__all__ = [
    "ACTIVATION_KINDS",
    "PEER_RECORDS",
    "Activation",
    "Alarm",
    "ArmOut",
    "Ask",
    "Notice",
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


PEER_RECORDS: dict[type, str] = {
    Ask: "zone_request",
    Reply: "zone_grant",
    Notice: "trajectory_end",
    ArmOut: "alarm",
}
"""The frame kind that carries each record (an :class:`Alarm` travels as
``alarm`` when on and ``wake_up`` when off; an :class:`Activation` as
``sleep``, ``position`` and ``active_zone_grant`` by phase)."""

ACTIVATION_KINDS: dict[str, str] = {
    "stop": "sleep",
    "stopped": "position",
    "go": "active_zone_grant",
}
"""The frame kind of each phase of an :class:`Activation`."""
