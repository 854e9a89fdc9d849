"""SUPERSIGMA: the central control unit, MICROBUS and device controllers (S1).

* :mod:`.microbus` -- the bus rules (S1.3), status lines (S1.4), the stepper,
  force, gripper and detector controllers (S1.5, S1.7, S1.8);
* :mod:`.ccu` -- the CCU and its task-box language (S1.1, S1.9);
* :mod:`.programs` -- a one/two-arm cell, the chess-piece demo (S1.8) and the
  S1.10 bus-load programs;
* :mod:`.schedule` -- a cell's schedule run as a task program on the CCU.

Examples
--------
>>> status_lines_needed(80)
(16, 16)
"""

from workcell.sim.comms.devices import (
    DetectorController,
    ForceController,
    GripperController,
    MotorController,
)
from workcell.sim.comms.microbus import (
    ABORT_FORCE,
    ABORT_RAIL,
    BUSY,
    FREE,
    Command,
    Controller,
    Microbus,
    StepProfile,
    move_time,
    status_lines_needed,
    steps_args,
)
from workcell.sim.control.supersigma.ccu import CCU, Box, RunReport
from workcell.sim.control.supersigma.programs import (
    PAPER_TABLE,
    Piece,
    SigmaCell,
    bus_load_table,
    chess_sort,
    run_program,
)
from workcell.sim.control.supersigma.schedule import Handover, ScheduleRun, run_schedule

__all__ = [
    "ABORT_FORCE",
    "ABORT_RAIL",
    "BUSY",
    "CCU",
    "FREE",
    "PAPER_TABLE",
    "Box",
    "Command",
    "Controller",
    "DetectorController",
    "ForceController",
    "GripperController",
    "Handover",
    "Microbus",
    "MotorController",
    "Piece",
    "RunReport",
    "ScheduleRun",
    "SigmaCell",
    "StepProfile",
    "bus_load_table",
    "chess_sort",
    "move_time",
    "run_program",
    "run_schedule",
    "status_lines_needed",
    "steps_args",
]
