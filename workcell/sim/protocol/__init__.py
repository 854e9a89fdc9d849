"""What the simulation's layers share: messages, published records, state machines.

* :mod:`.messages` -- the records carried by the coordination messages
  (:class:`Piece`, :class:`Leg`, :class:`Station`, :class:`Mark`);
* :mod:`.records` -- the motion and task records an arm controller
  publishes (:class:`MotionLog`), the safety monitor's only input;
* :mod:`.states` -- the protocol participants' states and transition tables;
* :mod:`.exchange` -- the S2.12 exchange, frames of the medium: motion
  reports (:class:`ArmView`), departure requests and answers, excursion and
  failure orders, task start and end notices;
* :mod:`.channel` -- the :class:`ControlChannel`: each arm's streams to and
  from the coordinator, numbered and taken in order.
"""

from workcell.sim.protocol.channel import ControlChannel
from workcell.sim.protocol.exchange import ArmView
from workcell.sim.protocol.messages import LEG_KINDS, PIECE_KINDS, Leg, Mark, Piece, Station
from workcell.sim.protocol.records import MotionLog, MotionRecord, TaskRecord
from workcell.sim.protocol.states import (
    ARM_MACHINE,
    MACHINES,
    TASK_MACHINE,
    ArmState,
    Machine,
    TaskState,
    markdown,
    mermaid,
)

__all__ = [
    "ARM_MACHINE",
    "LEG_KINDS",
    "MACHINES",
    "PIECE_KINDS",
    "TASK_MACHINE",
    "ArmState",
    "ArmView",
    "ControlChannel",
    "Leg",
    "Machine",
    "Mark",
    "MotionLog",
    "MotionRecord",
    "Piece",
    "Station",
    "TaskRecord",
    "TaskState",
    "markdown",
    "mermaid",
]
