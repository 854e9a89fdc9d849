"""workcell: the physical cell, its compilation into a scheduling problem, and the command line.

* :class:`Cell`, :func:`load_cell`, :func:`load_example`: tasks (tasklib), SDL
  zones (zones) and heterogeneous arms in one record, from a TOML cell file
  or a built-in cell (``"supersigma"``, ``"scara4"``, ``"cell8"``).
* :func:`compile_cell`: the cell as a :class:`scheduler.Problem` (modes timed
  with the arms' drives, zone windows from a conservative FCL sweep, travel
  setups, the blocking oracle with OMPL detours); :func:`compile_details`
  gives the per-mode trajectories behind it.
* :mod:`workcell.arms`, :mod:`workcell.geometry`: arm models and motion
  timing; the collision world, sweeps and the detour planner.
* :mod:`workcell.cli`: the ``multiarm`` command.
* :func:`dcr_bound`: the CSMA/DCR worst-case delay, seconds (S2.9); with no
  arguments the paper's worst case, 604 us.

Examples
--------
>>> problem = compile_cell(load_example("scara4"))
>>> problem.n_arms, problem.n_tasks
(4, 20)
>>> round(dcr_bound() * 1e6)
604
"""

from workcell.cell import EXAMPLES, Cell, cell_from_dict, load_cell, load_example
from workcell.compile import (
    CompiledCell,
    CompiledMode,
    compile_cell,
    compile_cell_detailed,
    compile_details,
)
from workcell.oracle import CellOracle
from workcell.sim.faults import (
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
)
from workcell.sim.network.dcr import dcr_bound
from workcell.sim.options import SimOptions
from workcell.sim.run import SimResult, simulate

__all__ = [
    "EXAMPLES",
    "ActivateZones",
    "ArmFailure",
    "Cell",
    "CellOracle",
    "CompiledCell",
    "CompiledMode",
    "Crash",
    "EmergencyStop",
    "FaultPlan",
    "LatePart",
    "LostSync",
    "MessageLoss",
    "SimOptions",
    "SimResult",
    "cell_from_dict",
    "compile_cell",
    "compile_cell_detailed",
    "compile_details",
    "dcr_bound",
    "load_cell",
    "load_example",
    "simulate",
]
