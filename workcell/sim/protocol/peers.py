"""The messages arm peers exchange under distributed coordination (S2.4, S2.7).

Under ``coordination="distributed"``
(:mod:`workcell.sim.coordination.distributed`) there is no coordinator: one
peer per arm, beside the arm's controller at the arm's station, and the peers
talk to each other over the same medium as the controllers would talk to a
coordinator. Each record below is the payload of one frame; the frame kinds
(and so the sizes, :data:`~workcell.sim.comms.medium.MESSAGE_BYTES`) are the
S2.7 ones whose role they take:

=============== ================ ===========================================
record          frame kind       meaning
=============== ================ ===========================================
:class:`Ask`    ``zone_request`` may I take the resource at this place of its
                                 plan order? (Ricart-Agrawala request)
:class:`Reply`  ``zone_grant``   every use of mine before that place is over
                                 (the reply; it also says how far I am)
:class:`Notice` ``trajectory_end`` a task ended (done, or failed with a cause)
:class:`Alarm`  ``alarm`` /      an emergency stop in force / released, by id
                ``wake_up``
=============== ================ ===========================================

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

__all__ = ["PEER_RECORDS", "Alarm", "Ask", "Notice", "Reply", "Resource"]

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


PEER_RECORDS: dict[type, str] = {Ask: "zone_request", Reply: "zone_grant", Notice: "trajectory_end"}
"""The frame kind that carries each record (an :class:`Alarm` travels as
``alarm`` when on and ``wake_up`` when off)."""
