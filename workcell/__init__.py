"""workcell: the physical cell, its compilation into a scheduling problem, and the command line.

* :class:`Cell`, :func:`load_cell`, :func:`load_example`: tasks (tasklib), SDL
  zones (zones) and heterogeneous arms in one record, from a TOML cell file
  or a built-in cell (``"supersigma"``, ``"scara4"``, ``"cell8"``).
* :func:`compile_cell`: the cell compiled under :class:`CompileOptions` into
  a :class:`CompiledCell`, whose ``.problem`` is the :class:`scheduler.Problem`
  (modes timed with the arms' drives, zone windows from a conservative FCL
  sweep, the space grid, travel setups, the blocking oracle with OMPL
  detours) and whose ``.modes`` are the trajectories behind it.
  ``scheduler.solve`` and ``scheduler.validate`` accept it as it is.
* :func:`run_cell`: the main job in one call, compile → solve → validate →
  simulate → write (:mod:`workcell.pipeline`), returning a :class:`CellRun`;
  :func:`solve_cell` stops after the solve (a :class:`SolvedCell`).
* :mod:`workcell.arms`, :mod:`workcell.geometry`: arm models and motion
  timing; the collision world, sweeps and the detour planner.
* :mod:`workcell.cli`: the ``multiarm`` command.
* :func:`dcr_bound`: the CSMA/DCR worst-case delay, seconds (S2.9); with no
  arguments the paper's worst case, 604 us.

Examples
--------
>>> cc = compile_cell(load_example("scara4"))
>>> cc.problem.n_arms, cc.problem.n_tasks
(4, 20)
>>> round(dcr_bound() * 1e6)
604
"""

from workcell.cell import EXAMPLES, Cell, cell_from_dict, load_cell, load_example
from workcell.compile import (
    CompiledCell,
    compile_cell,
    compile_cell_detailed,
    compile_details,
)
from workcell.compiled import CompiledMode, CompileOptions
from workcell.oracle import CellOracle
from workcell.pipeline import CellRun, RunStatus, SolvedCell, run_cell, solve_cell
from workcell.sim.comms.dcr import dcr_bound
from workcell.sim.harness.faults import (
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
)
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import SimResult, simulate

__all__ = [
    "EXAMPLES",
    "ActivateZones",
    "ArmFailure",
    "Cell",
    "CellOracle",
    "CellRun",
    "CompileOptions",
    "CompiledCell",
    "CompiledMode",
    "Crash",
    "EmergencyStop",
    "FaultPlan",
    "LatePart",
    "LostSync",
    "MessageLoss",
    "RunStatus",
    "SimOptions",
    "SimResult",
    "SolvedCell",
    "cell_from_dict",
    "compile_cell",
    "compile_cell_detailed",
    "compile_details",
    "dcr_bound",
    "load_cell",
    "load_example",
    "run_cell",
    "simulate",
    "solve_cell",
]
