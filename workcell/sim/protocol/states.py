"""The protocol participants' states and their transition tables.

Each participant of the coordination protocol is a small state machine:

* :class:`TaskState` -- a task as the coordinator sees it (S2.7: dispatched
  with its trajectory, started by its arm, ended, or failed with a cause);
* :class:`ArmState` -- an arm controller (S2.3: idle, moving, standing at a
  station until its conditions hold, stopped on its way, failed);
* :class:`RoundState` -- a distributed peer's own departure request (S2.12:
  idle, or asking the arms that may meet its arm);
* :class:`AnswerState` -- another arm's departure request at a distributed
  peer (deferred, answered and so reserved, over).

A :class:`Machine` holds the legal transitions of one of them; a transition
not in its table raises :class:`~multiarm.errors.InternalError` (a bug of
the simulator, never of the input). :func:`mermaid` prints a table as a
Mermaid state diagram: ``docs/simulation.md`` holds the diagrams it prints,
and a test checks that they match.

Examples
--------
>>> TASK_MACHINE.check(TaskState.PENDING, TaskState.DISPATCHED)
>>> TASK_MACHINE.check(TaskState.DONE, TaskState.PENDING)
Traceback (most recent call last):
...
multiarm.errors.InternalError: task: illegal transition done -> pending
>>> print(mermaid(TASK_MACHINE).splitlines()[1])
    [*] --> pending
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from multiarm.errors import InternalError

__all__ = [
    "ANSWER_MACHINE",
    "ARM_MACHINE",
    "MACHINES",
    "ROUND_MACHINE",
    "TASK_MACHINE",
    "AnswerState",
    "ArmState",
    "Machine",
    "RoundState",
    "TaskState",
    "markdown",
    "mermaid",
]


class TaskState(enum.StrEnum):
    """A task's state at the coordinator (a ``str``: ``TaskState.DONE == "done"``)."""

    PENDING = "pending"
    """Not sent to its arm (again): waiting for its planned departure."""
    DISPATCHED = "dispatched"
    """Its trajectory was sent; the arm has not left the task's start."""
    RUNNING = "running"
    """Its arm left the task's start station."""
    DONE = "done"
    """Its arm reported the trajectory's end."""
    FAILED = "failed"
    """It can never run or it ran and failed; it carries its cause."""


class ArmState(enum.StrEnum):
    """An arm controller's state (S2.3), read from its motion at every change."""

    IDLE = "idle"
    """No trajectory: standing where the last one ended."""
    MOVING = "moving"
    """Following a trajectory; the trajectory clock runs."""
    AT_STATION = "at_station"
    """Standing at a station of its trajectory until its conditions hold
    (the plan's time, the zone grants, the start permission)."""
    STOPPED = "stopped"
    """Standing on its way: a stop in force (emergency, activation, crash,
    geometric conflict, a search try) or about to set off again."""
    FAILED = "failed"
    """Failed for good (retracted to its home joints)."""


class RoundState(enum.StrEnum):
    """A distributed peer's own departure request (S2.12, Ricart and Agrawala)."""

    IDLE = "idle"
    """No request of its arm out."""
    ASKING = "asking"
    """Its request is out to the arms that may meet its arm; it defers its
    answers to their requests of a higher ``(clock, arm)``."""


class AnswerState(enum.StrEnum):
    """Another arm's departure request at a distributed peer."""

    RECEIVED = "received"
    """Just taken from the medium."""
    DEFERRED = "deferred"
    """The peer asks itself with a lower ``(clock, arm)``: answered once it
    has decided its own departure."""
    RESERVED = "reserved"
    """Answered: the asked motion counts as under way in the peer's checks."""
    OVER = "over"
    """A frame of the asker sent after it decided says its arm stands, or
    the asker failed."""


@dataclass(frozen=True, slots=True)
class Machine:
    """One participant's states, start state and legal transitions.

    Attributes
    ----------
    name : str
    states : tuple of str
        The states, in the order the enum lists them.
    initial : str
    transitions : tuple of (str, str, str)
        ``(from, to, why)``: the legal transitions and what causes each.
    """

    name: str
    states: tuple[str, ...]
    initial: str
    transitions: tuple[tuple[str, str, str], ...]
    legal: frozenset[tuple[str, str]] = field(init=False, repr=False, compare=False)
    """The ``(from, to)`` pairs of the table, and every state staying put."""

    def __post_init__(self) -> None:
        pairs = {(a, b) for a, b, _ in self.transitions} | {(s, s) for s in self.states}
        object.__setattr__(self, "legal", frozenset(pairs))

    def allowed(self, old: str, new: str) -> bool:
        """Whether ``old -> new`` is in the table (staying put always is)."""
        return (old, new) in self.legal

    def check(self, old: str, new: str) -> None:
        """Raise :class:`InternalError` unless ``old -> new`` is legal.

        Raises
        ------
        InternalError
            Naming the machine and the transition.
        """
        if (old, new) not in self.legal:
            raise InternalError(f"{self.name}: illegal transition {old} -> {new}")

    def table(self) -> str:
        """The transition table as text, one ``from -> to: why`` per line."""
        return "\n".join(f"{a} -> {b}: {why}" for a, b, why in self.transitions)


TASK_MACHINE = Machine(
    "task",
    tuple(s.value for s in TaskState),
    TaskState.PENDING.value,
    (
        ("pending", "dispatched", "trajectory sent at the planned departure"),
        ("pending", "failed", "a part never comes or a predecessor failed"),
        ("dispatched", "running", "the arm left the task's start station"),
        ("dispatched", "pending", "withdrawn: late part, re-solve, or its arm failed"),
        ("dispatched", "failed", "a part never comes or a predecessor failed"),
        ("pending", "running", "its arm started it before the withdrawal reached it"),
        ("running", "done", "trajectory end reported"),
        ("running", "failed", "its insertion failed"),
        ("running", "pending", "interrupted by its arm's failure"),
    ),
)
"""The coordinator's task machine (:class:`TaskState`)."""

ARM_MACHINE = Machine(
    "arm",
    tuple(s.value for s in ArmState),
    ArmState.IDLE.value,
    (
        ("idle", "moving", "a trajectory arrived (or an excursion started)"),
        ("idle", "stopped", "a trajectory arrived, departure held (geometric conflict)"),
        ("idle", "failed", "arm failure"),
        ("moving", "at_station", "reached a station"),
        ("moving", "stopped", "a stop (alarm, activation, crash, conflict, search try)"),
        ("moving", "idle", "trajectory end, or a withdrawal"),
        ("moving", "failed", "arm failure"),
        ("at_station", "moving", "conditions hold: passes the station"),
        ("at_station", "stopped", "an excursion or skip ends at the station"),
        ("at_station", "idle", "withdrawn before its start"),
        ("at_station", "failed", "arm failure"),
        ("stopped", "moving", "every stop released"),
        ("stopped", "at_station", "back at the station after an excursion"),
        ("stopped", "idle", "withdrawn, or a back-off reached the home joints"),
        ("stopped", "failed", "arm failure"),
    ),
)
"""The arm controller's machine (:class:`ArmState`)."""

ROUND_MACHINE = Machine(
    "departure round",
    tuple(s.value for s in RoundState),
    RoundState.IDLE.value,
    (
        ("idle", "asking", "its controller asks to set off: a request to each arm that may meet"),
        ("asking", "idle", "every answer in (or its sender failed): continue or stop"),
    ),
)
"""A distributed peer's own departure request (:class:`RoundState`; a
request made while one is out waits, and is asked next)."""

ANSWER_MACHINE = Machine(
    "departure answer",
    tuple(s.value for s in AnswerState),
    AnswerState.RECEIVED.value,
    (
        ("received", "reserved", "answered at once with where its arm is"),
        ("received", "deferred", "it asks itself with a lower (clock, arm)"),
        ("deferred", "reserved", "its own departure decided: answered"),
        ("deferred", "over", "the asker failed"),
        ("reserved", "over", "the asker's later frame says it stands, or it failed"),
    ),
)
"""Another arm's departure request at a distributed peer (:class:`AnswerState`)."""

MACHINES: tuple[Machine, ...] = (TASK_MACHINE, ARM_MACHINE, ROUND_MACHINE, ANSWER_MACHINE)
"""Every protocol participant's machine (documented in ``docs/simulation.md``)."""


def mermaid(machine: Machine) -> str:
    """The machine as a Mermaid ``stateDiagram-v2`` (text).

    Parameters
    ----------
    machine : Machine

    Returns
    -------
    str
    """
    lines = ["stateDiagram-v2", f"    [*] --> {machine.initial}"]
    lines += [f"    {a} --> {b}: {why}" for a, b, why in machine.transitions]
    return "\n".join(lines)


_TITLES = {
    "task": "A task at the coordinator (`TaskState`)",
    "arm": "An arm controller (`ArmState`)",
    "departure round": "A distributed peer's own departure request (`RoundState`)",
    "departure answer": "Another arm's departure request at a distributed peer (`AnswerState`)",
}


def markdown() -> str:
    """Every machine as Markdown: a title and a ``mermaid`` block each.

    ``docs/simulation.md`` holds this text between the markers
    ``<!-- state machines: begin -->`` and ``<!-- state machines: end -->``;
    ``python -m workcell.sim.protocol.states`` prints it.

    Returns
    -------
    str
    """
    parts = []
    for m in MACHINES:
        parts.append(f"#### {_TITLES.get(m.name, m.name)}\n\n```mermaid\n{mermaid(m)}\n```\n")
    return "\n".join(parts)


if __name__ == "__main__":  # pragma: no cover - prints the docs' diagrams
    print(markdown(), end="")
