"""Wrist force sensing and force-guided insertion in the simulated cell (S1.7, S1.2).

Each arm carries a wrist force sensor (:class:`ForceSensor`): three force
components (x, y, z in the wrist frame) sampled continuously by their own
controller, and one threshold per component. The arm controller has the two
S1.7 commands as operations: "tell me the force on axis k"
(:meth:`~workcell.sim.control.controller.ArmController.read_force`) and "set the
thresholds" (:meth:`~workcell.sim.control.controller.ArmController.set_thresholds`).

* **Free motion.** The thresholds are low (:data:`FREE_THRESHOLD`, 5 N by
  default; ``SimOptions(force_threshold=...)`` sets them for the whole
  cell or per arm): only inertial forces act, so a force above them is a
  crash, and the motor stops at once by itself (the reflex arc of S1.2); the
  coordinator is told afterwards.
* **Insertion.** For an ``insert`` step the controller raises the
  thresholds to the step's :attr:`tasklib.steps.ForceSearch.threshold` at
  the start of the search (the dwell the compile plans for the tries),
  pushes at each offset of :meth:`tasklib.steps.ForceSearch.offsets` in
  turn (``try_time`` each), reads a force at the threshold as "not in the
  hole", and restores the free thresholds after the last try.

Insertion tries drawn at run time
---------------------------------
With ``SimOptions(insertion="drawn")`` the hole's true lateral position
error is drawn for every insert step of every task from a normal
distribution (``insertion_sigma`` metres per axis, default
:data:`HOLE_SIGMA`), from a random stream of its own derived from the
simulate seed and the task's index (:func:`task_rng`), so a task's draws do
not depend on the order of events, nor on the arm that runs it. A try lands
in the hole when its offset is within ``insertion_tolerance`` of the error
on both axes (default: half the search step, so the tries' squares tile the
plane); the tries made are the index of the first offset that lands, plus
one (:func:`tries_needed`). When none does, all ``max_tries`` are made and
the task fails with the cause ``"insertion failed after N tries"``.

The compiled mode holds the planned tries (one with ``plan_with="nominal"``,
``max_tries`` with ``"worst"``, :mod:`workcell.program`); the executed task
takes ``(tries made - tries planned) * try_time`` longer (or shorter).
With the default ``insertion="planned"`` the search is not simulated: every
insertion takes its planned time, the thresholds stay at the free ones, and
the run is exactly as before.

Examples
--------
>>> from tasklib.steps import ForceSearch
>>> search = ForceSearch(max_tries=5, step=0.001)
>>> tries_needed(search, (0.0, 0.0))
(1, True)
>>> tries_needed(search, (0.0009, 0.0011))  # the third offset, (1, 1) mm
(3, True)
>>> tries_needed(search, (0.005, 0.0))
(5, False)
>>> sensor = ForceSensor(5.0)
>>> sensor.exceeds(50.0), sensor.set_thresholds(25.0), sensor.exceeds(20.0)
(True, None, False)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from multiarm.errors import InternalError, UsageError
from multiarm.types import FloatArray
from tasklib.steps import ForceSearch, Insert
from workcell.compile import CompiledCell
from workcell.program import expand_task

__all__ = [
    "CRASH_AXIS",
    "CRASH_FORCE",
    "FREE_THRESHOLD",
    "HOLE_SIGMA",
    "INSERTION_MODES",
    "ForceSensor",
    "InsertSearch",
    "check_insertion",
    "free_thresholds",
    "insert_searches",
    "task_rng",
    "tries_needed",
]

FREE_THRESHOLD = 5.0
"""Newtons: the default free-motion threshold of every force component (S1.7:
during free moves only inertial forces act, so a few newtons detect a crash)."""

CRASH_FORCE = 50.0
"""Newtons (50): the default force of a :class:`~workcell.sim.harness.faults.Crash`,
above the free threshold and above the raised thresholds of the built-in
insert steps (25 N), so a crash record without a force stops the arm as it
always did."""

CRASH_AXIS = 2
"""The wrist axis a crash's force acts on (z, along the tool)."""

HOLE_SIGMA = 2.5e-4
"""Metres: the default standard deviation of a hole's lateral position error
(per axis) when insertion tries are drawn."""

INSERTION_MODES: tuple[str, ...] = ("planned", "drawn")
"""Values of ``SimOptions(insertion=...)``."""

_STREAM = 0x5F17
"""Tag of the insertion draws in each task's seed sequence (keeps them apart
from any other stream derived from the same seed)."""


class ForceSensor:
    """A wrist force sensor (S1.7): three components and one threshold each.

    Parameters
    ----------
    free : float
        Free-motion threshold, newtons (> 0), of every component.

    Attributes
    ----------
    free : float
    thresholds : (3,) float
        The thresholds in force now, newtons.
    force : (3,) float
        The last sample, newtons.

    Examples
    --------
    >>> s = ForceSensor(5.0)
    >>> s.set_thresholds([25.0, 25.0, 30.0])
    >>> s.raised, s.thresholds.tolist()
    (True, [25.0, 25.0, 30.0])
    >>> s.restore(); s.raised
    False
    """

    __slots__ = ("force", "free", "thresholds")

    def __init__(self, free: float = FREE_THRESHOLD) -> None:
        self.free = float(free)
        self.thresholds: FloatArray = np.full(3, self.free)
        self.force: FloatArray = np.zeros(3)

    def set_thresholds(self, values: float | Sequence[float]) -> None:
        """The S1.7 "set the thresholds" command: one value for every
        component, or three.

        Raises
        ------
        UsageError
            For anything but one or three finite values > 0.
        """
        v = np.broadcast_to(np.asarray(values, dtype=float), (3,)).copy()
        if not (np.all(np.isfinite(v)) and np.all(v > 0)):
            raise UsageError(f"force thresholds must be > 0 newtons, got {values!r}")
        self.thresholds = v

    def restore(self) -> None:
        """Back to the free-motion thresholds."""
        self.thresholds = np.full(3, self.free)

    @property
    def raised(self) -> bool:
        """Whether some threshold is above the free one (an operation that pushes)."""
        return bool(np.any(self.thresholds > self.free))

    def read(self, axis: int) -> float:
        """The S1.7 "tell me the force on axis k" command (newtons)."""
        if isinstance(axis, bool) or not isinstance(axis, int) or not 0 <= axis < 3:
            raise UsageError(f"force axis must be 0, 1 or 2, got {axis!r}")
        return float(self.force[axis])

    def exceeds(self, force: float, axis: int = CRASH_AXIS) -> bool:
        """Whether ``force`` newtons on ``axis`` is above the threshold in force."""
        return abs(float(force)) > float(self.thresholds[axis])


@dataclass(frozen=True, slots=True)
class InsertSearch:
    """The force-guided search of one insert step in one compiled mode.

    Attributes
    ----------
    task : int
        Task index.
    step : int
        The insert step's number in the task (1-based).
    segment : int
        Index of the search dwell in the mode's trajectory segments.
    start : float
        Offset of the dwell in the mode's trajectory, seconds.
    planned : int
        Tries the compiled dwell holds.
    tries : int
        Tries made at run time (``max_tries`` when the hole is not found).
    found : bool
        Whether a try landed in the hole.
    error : (float, float)
        The hole's drawn lateral position error, metres.
    search : tasklib.steps.ForceSearch
    """

    task: int
    step: int
    segment: int
    start: float
    planned: int
    tries: int
    found: bool
    error: tuple[float, float]
    search: ForceSearch

    @property
    def end(self) -> float:
        """Offset of the end of the compiled dwell, seconds."""
        return self.start + self.planned * self.search.try_time

    @property
    def extra(self) -> float:
        """Seconds the executed search takes beyond the planned one (< 0: less)."""
        return (self.tries - self.planned) * self.search.try_time

    @property
    def cause(self) -> str:
        """The failure's cause (``""`` when the hole was found)."""
        if self.found:
            return ""
        return f"insertion failed after {self.tries} tries (step {self.step})"


def task_rng(seed: int, task: int) -> np.random.Generator:
    """The random stream of task ``task``'s insertions: derived from the
    simulate seed and the task index only.

    Examples
    --------
    >>> float(task_rng(3, 1).normal()) == float(task_rng(3, 1).normal())
    True
    """
    return np.random.default_rng([int(seed), _STREAM, int(task)])


def tries_needed(
    search: ForceSearch, error: Sequence[float] | FloatArray, tolerance: float | None = None
) -> tuple[int, bool]:
    """Tries until an offset of ``search`` lands in the hole at ``error``.

    Parameters
    ----------
    search : tasklib.steps.ForceSearch
    error : (2,) float
        The hole's lateral position error, metres.
    tolerance : float, optional
        A try lands when its offset is within this many metres of ``error``
        on both axes; default half the search step.

    Returns
    -------
    (int, bool)
        The tries made and whether the last one landed (``max_tries`` and
        False when none does).
    """
    tol = search.step / 2 if tolerance is None else float(tolerance)
    off = search.offsets()
    e = np.asarray(error, dtype=float).reshape(1, 2)
    hit = np.flatnonzero(np.max(np.abs(off - e), axis=1) <= tol * (1 + 1e-12))
    if len(hit):
        return int(hit[0]) + 1, True
    return search.max_tries, False


def free_thresholds(spec: float | Mapping[str, float], arms: Sequence[str]) -> dict[str, float]:
    """Each arm's free-motion threshold from a number or an ``arm -> newtons``
    mapping (arms not named keep :data:`FREE_THRESHOLD`).

    Raises
    ------
    UsageError
        A value not > 0 or an unknown arm (named).

    Examples
    --------
    >>> free_thresholds({"left": 8.0}, ["left", "right"])
    {'left': 8.0, 'right': 5.0}
    """

    def value(x: object, what: str) -> float:
        if isinstance(x, bool) or not isinstance(x, int | float) or not (0 < x < math.inf):
            raise UsageError(f"simulate: {what} must be a number > 0 (newtons), got {x!r}")
        return float(x)

    if isinstance(spec, Mapping):
        unknown = sorted(set(spec) - set(arms))
        if unknown:
            raise UsageError(
                f"simulate: force_threshold names unknown arm {unknown[0]!r} "
                f"(arms: {', '.join(arms)})"
            )
        return {
            a: value(spec[a], f"force_threshold[{a!r}]") if a in spec else FREE_THRESHOLD
            for a in arms
        }
    v = value(spec, "force_threshold")
    return dict.fromkeys(arms, v)


def check_insertion(insertion: object, sigma: object, tolerance: object) -> None:
    """Check ``simulate``'s ``insertion``, ``insertion_sigma`` and
    ``insertion_tolerance`` arguments.

    Raises
    ------
    UsageError
        Naming the argument and the value.

    Examples
    --------
    >>> check_insertion("sampled", 0.0, None)
    Traceback (most recent call last):
    ...
    multiarm.errors.UsageError: simulate: insertion must be one of 'planned', 'drawn', got 'sampled'
    """
    if insertion not in INSERTION_MODES:
        raise UsageError(
            f"simulate: insertion must be one of {', '.join(map(repr, INSERTION_MODES))}, "
            f"got {insertion!r}"
        )
    if isinstance(sigma, bool) or not isinstance(sigma, int | float) or not 0 <= sigma < math.inf:
        raise UsageError(f"simulate: insertion_sigma must be a number >= 0 (metres), got {sigma!r}")
    if tolerance is not None and (
        isinstance(tolerance, bool)
        or not isinstance(tolerance, int | float)
        or not 0 < tolerance < math.inf
    ):
        raise UsageError(
            f"simulate: insertion_tolerance must be None or a number > 0 (metres), "
            f"got {tolerance!r}"
        )


def insert_searches(
    cc: CompiledCell,
    seed: int,
    *,
    sigma: float = HOLE_SIGMA,
    tolerance: float | None = None,
) -> dict[int, tuple[InsertSearch, ...]]:
    """The drawn insertion searches of every compiled mode with insert steps.

    Parameters
    ----------
    cc : CompiledCell
    seed : int
        The simulate seed (each task draws from :func:`task_rng`).
    sigma : float
        Standard deviation of a hole's lateral position error, metres per
        axis (>= 0; 0: every hole where planned, found at the first try).
    tolerance : float, optional
        Metres (> 0); default half of each search's step.

    Returns
    -------
    dict of mode index -> tuple of InsertSearch
        In the order of the steps.

    Raises
    ------
    UsageError
        Bad ``sigma`` or ``tolerance``.
    InternalError
        A compiled trajectory whose dwells do not match its task's program.
    """
    check_insertion("drawn", sigma, tolerance)
    p = cc.problem
    ts = cc.cell.taskset
    out: dict[int, tuple[InsertSearch, ...]] = {}
    for t, task in enumerate(ts.tasks):
        steps = [(i, s) for i, s in enumerate(task.steps, start=1) if isinstance(s, Insert)]
        if not steps:
            continue
        rng = task_rng(seed, t)
        draws: dict[int, tuple[tuple[float, float], int, bool]] = {}
        for i, ins in steps:
            e = rng.normal(0.0, 1.0, 2) * float(sigma)
            n, found = tries_needed(ins.search, e, tolerance)
            draws[i] = ((float(e[0]), float(e[1])), n, found)
        program = expand_task(task, ts.trajectories, "nominal")
        dwells = [s for s in program.segments if s.kind == "dwell"]
        for m in p.task_modes[t]:
            traj = cc.modes[int(m)].trajectory
            still = [j for j, s in enumerate(traj.segments) if not s.moving]
            if len(still) != len(dwells):
                raise InternalError(
                    f"task {task.id!r}: {len(still)} dwells in the trajectory of mode {int(m)}, "
                    f"{len(dwells)} in the program (please report)"
                )
            found_: list[InsertSearch] = []
            for j, seg in zip(still, dwells, strict=True):
                if seg.label != "insert":
                    continue
                insert = task.steps[seg.step - 1]
                assert isinstance(insert, Insert)
                fs = insert.search
                dur = float(traj.segments[j].duration)
                planned = max(1, round(dur / fs.try_time))
                err, n, ok = draws[seg.step]
                found_.append(
                    InsertSearch(t, seg.step, j, float(traj.knot_times[j]), planned, n, ok, err, fs)
                )
            out[int(m)] = tuple(found_)
    return out
