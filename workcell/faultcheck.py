"""Fault records checked against a cell before any long work.

A fault file is read into records (:class:`workcell.sim.FaultPlan`) that
check their own fields (types and physical ranges). Whether those records
make sense *for a cell* needs the cell: :func:`check_faults` refuses, each
error naming the file and the field path,

* an arm, part or zone the cell does not have (``faults.toml: faults[1].arm:
  unknown arm 'sx'; known: sa, sb``), a lost-sync axis the arm does not
  have or that is not a stepper axis;
* a message kind the coordination protocol does not send (a misspelt
  ``"zone_reqest"`` in a ``message_loss`` record's ``kinds`` would otherwise
  never match a frame, so nothing would ever be lost);
* two failures of one arm (an arm fails for good once), and more than one
  ``message_loss`` record;
* given the compiled cell (a :class:`~workcell.CompiledCell`, or its
  ``problem=``): a fault time after any possible end of the run, see
  :func:`plan_end_bound`.

The name checks (:func:`workcell.sim.harness.faults.check_fault_names`,
which :func:`workcell.sim.simulate` runs too, with the same messages) need
only the :class:`~workcell.Cell` and cost nothing, so
the pipeline calls :func:`check_faults` **before compiling**; the time check
needs the modes' durations, so it runs **after compiling and before
solving** (the compile takes seconds, the solve and the simulation the
long time). Both calls are the same function::

    check_faults(cell, faults, source="faults.toml")       # before compile_cell
    compiled = compile_cell(cell)
    check_faults(compiled, faults, source="faults.toml")   # before solve

Examples
--------
>>> from workcell import load_example
>>> cell = load_example("supersigma")
>>> check_faults(cell, [{"kind": "arm_failure", "arm": "left", "at": 3.0}])
>>> check_faults(cell, [{"kind": "message_loss", "probability": 0.1,
...                      "kinds": ["zone_reqest"]}], source="f.toml")
Traceback (most recent call last):
...
multiarm.errors.ValidationError: f.toml: faults[0].kinds[0]: unknown message kind 'zone_reqest' (did you mean 'zone_request'?); known: ...
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from multiarm.errors import ValidationError
from scheduler.problem import Problem
from workcell.cell import Cell
from workcell.compile import CompiledCell
from workcell.sim import Crash, EmergencyStop, FaultPlan, LatePart, MessageLoss
from workcell.sim.harness.faults import MESSAGE_KINDS, check_fault_names

__all__ = ["MESSAGE_KINDS", "PLAN_END_MARGIN", "check_faults", "plan_end_bound"]

PLAN_END_MARGIN = 2.0
"""Factor on the serial bound of :func:`plan_end_bound` (room for blocking
detours and for the tasks an arm failure interrupts and a re-solve starts
again)."""


def plan_end_bound(problem: Problem, faults: Iterable[Any] = ()) -> float:
    """An upper bound, seconds, on when a run of ``problem`` can still be going on.

    The serial bound ``S``: the latest release, plus the latest arm
    availability, plus, over the tasks, the longest mode of each task plus the
    longest travel of that mode's arm into the task (from its start pose or
    the end of any other task). No plan of the scheduler's solvers ends later
    than ``S``: they never leave every arm idle while a task is ready, so
    even one task at a time, each on its slowest arm, fits. A run can be
    stretched by its faults, so the bound is

    ``PLAN_END_MARGIN * S`` + the emergency stops' durations + the crashes'
    recoveries + the finite late-part delays,

    divided by ``1 - p`` for a message loss of probability ``p`` (each frame
    is sent ``1 / (1 - p)`` times on average). The cost is one pass over the
    travel table: ``arms x (tasks + 1)`` rows of ``tasks`` setup times.

    Parameters
    ----------
    problem : scheduler.Problem
        A compiled cell's problem.
    faults : iterable of fault records
        The records whose delays stretch the run.

    Returns
    -------
    float
        Seconds.
    """
    p = problem
    serial = float(np.max(p.task_release, initial=0.0)) + float(
        np.max(p.arm_available, initial=0.0)
    )
    if p.n_tasks:
        worst_in = np.zeros((p.n_arms, p.n_tasks))
        for a in range(p.n_arms):
            for prev in range(-1, p.n_tasks):
                row = np.asarray(p.setup_row(a, prev), dtype=float)
                np.maximum(worst_in[a], np.where(np.isfinite(row), row, 0.0), out=worst_in[a])
        for t, modes in enumerate(p.task_modes):
            serial += max(
                (float(p.mode_duration[m]) + float(worst_in[int(p.mode_arm[m]), t]) for m in modes),
                default=0.0,
            )
    stretch = 0.0
    slow = 1.0
    for f in faults:
        if isinstance(f, EmergencyStop):
            stretch += f.duration
        elif isinstance(f, Crash):
            stretch += f.recovery
        elif isinstance(f, LatePart) and math.isfinite(f.delay):
            stretch += f.delay
        elif isinstance(f, MessageLoss):
            slow = 1.0 / (1.0 - f.probability)
    return (PLAN_END_MARGIN * serial + stretch) * slow


def _plan(faults: object, top: str) -> FaultPlan:
    if faults is None:
        return FaultPlan()
    if isinstance(faults, FaultPlan):
        return faults
    if isinstance(faults, str | bytes) or not isinstance(faults, Sequence):
        raise ValidationError(
            f"{top}: expected a FaultPlan or a list of fault records, got {type(faults).__name__}"
        )
    items = list(faults)
    try:
        if items and all(isinstance(x, Mapping) for x in items):
            return FaultPlan.from_dicts(items)
        return FaultPlan(items)
    except ValidationError as exc:
        raise ValidationError(f"{top}: {exc}") from None


def check_faults(
    cell: Cell | CompiledCell,
    faults: FaultPlan | Sequence[Any] | None,
    *,
    source: str | None = None,
    problem: Problem | None = None,
) -> None:
    """Refuse fault records that do not fit ``cell`` (module docstring).

    Parameters
    ----------
    cell : Cell or CompiledCell
        The cell the faults will be injected into. A compiled cell (or
        ``problem``) adds the check of fault times against
        :func:`plan_end_bound`.
    faults : FaultPlan, list of records or dicts, or None
        What a fault file holds (``None``: nothing to check).
    source : str, optional
        The fault file's name, the first word of every message
        (``"faults"`` when not given).
    problem : scheduler.Problem, optional
        The compiled problem (taken from ``cell`` when it is compiled).

    Raises
    ------
    ValidationError
        ``"SOURCE: faults[i].field: what is wrong"``.
    """
    top = source if source is not None else "faults"
    plan = _plan(faults, top)
    if isinstance(cell, CompiledCell):
        problem = cell.problem if problem is None else problem
        cell = cell.cell
    if not isinstance(cell, Cell):
        raise ValidationError(f"check_faults: expected a Cell or CompiledCell, got {cell!r}")
    check_fault_names(plan, cell, source=source)
    if problem is None:
        return
    end = plan_end_bound(problem, plan)
    for i, f in enumerate(plan):
        t = getattr(f, "at", None)
        if t is not None and t > end:
            raise ValidationError(
                f"{top}: faults[{i}].at: {t:g} s is after any possible end of the run "
                f"(at most {end:.6g} s for cell {cell.name!r}; workcell.faultcheck.plan_end_bound)"
            )
