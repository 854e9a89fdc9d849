"""Coordination policies: the protocol every policy implements, and the registry.

:func:`~workcell.simulate` takes ``coordination=<name>`` and builds the policy
registered under that name (:data:`POLICIES`): ``"centralized"``, the S2.7
coordinator (:class:`~workcell.sim.coordination.centralized.Coordinator`),
and ``"distributed"``, one peer per arm and no coordinator
(:class:`~workcell.sim.coordination.distributed.DistributedPolicy`: per-zone
mutual exclusion by request/reply in plan order, activations and emergency
stops broadcast, S2.4 and S2.7's last sentence). A policy is constructed
with the compiled cell, the plan, the event loop, the link, the trace and
the control channel (:class:`~workcell.sim.protocol.channel.ControlChannel`,
the S2.12 exchange); it knows the arms only from their messages. The
centralized one talks to the arms through the link (station 0 receives,
the arms are stations ``1..n``), the distributed one's peers share the
arms' stations (a policy with ``colocated = True`` gets the controllers'
messages to station 0 through the channel's ``local``); both answer the
harness through :class:`CoordinationPolicy`.

Examples
--------
>>> sorted(POLICIES)
['centralized', 'distributed']
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol

from multiarm.errors import UsageError
from scheduler import Problem, Schedule
from workcell.compile import CompiledCell
from workcell.sim.comms.link import Link
from workcell.sim.coordination.centralized import Coordinator
from workcell.sim.coordination.distributed import DistributedPolicy
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.exchange import ArmView
from workcell.sim.protocol.messages import LateNotice
from workcell.sim.protocol.states import TaskState

__all__ = ["POLICIES", "CoordinationPolicy", "PolicyFactory", "make_policy", "register_policy"]


class CoordinationPolicy(Protocol):
    """What the harness needs of a coordination policy."""

    p: Problem

    @property
    def book(self) -> list[ArmView]:
        """Per arm, its motion as the policy knows it (the arm's last report)."""

    @property
    def status(self) -> list[TaskState]:
        """Per task, its state (a published record: the harness reads it)."""

    @property
    def cause(self) -> list[str]:
        """Per task, why it failed ("" if it did not)."""

    @property
    def cause_kind(self) -> list[str]:
        """Per task, the category of :attr:`cause`."""

    plan: Schedule
    """The plan followed now (after any re-solve)."""
    dropped: frozenset[int]
    plans: list[Schedule]
    """Every plan followed: the one given, then one per re-solve."""
    plan_of: list[int]
    """Per task, the index in ``plans`` of the plan its planned times come from."""
    failed_arms: set[int]
    resolving: bool
    resolves: int
    resolve_latency: list[float]
    resolve_budget: float

    @property
    def detours(self) -> int:
        """Alternative trajectories and back-offs so far."""

    @property
    def geo_held(self) -> dict[int, list[int]]:
        """Per arm held by the geometric check, the arms in its way."""

    def start(self) -> None:
        """Dispatch the first work (before the event loop runs)."""

    def arm_failed(self, a: int) -> None:
        """Fault: arm ``a`` failed."""

    def emergency_stop(self, duration: float) -> None:
        """Fault: broadcast an emergency stop for ``duration`` seconds."""

    def activate(self, zones: tuple[str, ...]) -> None:
        """Fault: change the active zones (S2.5)."""

    def part_late(self, notice: LateNotice) -> None:
        """Fault: ``notice.part`` comes at ``notice.arrival`` for ``notice.tasks``."""

    def parts_late(self, notices: Sequence[LateNotice]) -> None:
        """Fault: parts found late at one instant (one :class:`LateNotice` each)."""


PolicyFactory = Callable[..., CoordinationPolicy]
"""``factory(compiled, plan, loop, link, trace, channel, **settings)``."""

POLICIES: dict[str, PolicyFactory] = {
    "centralized": Coordinator,
    "distributed": DistributedPolicy,
}
"""Registered coordination policies by name."""


def register_policy(name: str, factory: PolicyFactory) -> None:
    """Register a coordination policy under ``name``.

    Raises
    ------
    UsageError
        For a name already registered.
    """
    if name in POLICIES:
        raise UsageError(f"coordination policy {name!r} is already registered")
    POLICIES[name] = factory


def make_policy(
    name: str,
    compiled: CompiledCell,
    plan: Schedule,
    loop: EventLoop,
    link: Link,
    trace: Trace,
    channel: ControlChannel,
    **settings: Any,
) -> CoordinationPolicy:
    """Build the policy registered under ``name``.

    Raises
    ------
    UsageError
        For an unknown name (the message lists the known ones).
    """
    factory = POLICIES.get(name)
    if factory is None:
        raise UsageError(
            f"unknown coordination policy {name!r} (known: {', '.join(sorted(POLICIES))})"
        )
    return factory(compiled, plan, loop, link, trace, channel, **settings)
