"""The scheduling problem: a builder for people, validated arrays for solvers.

:class:`Model` is the human-facing builder (names, one call per element);
:meth:`Model.build` validates everything and returns an immutable,
index-based :class:`Problem`, which is what every solver, the validator and
the simulator read (SEEDS.md S2.10-S2.12, DESIGN.md "Contracts").

The problem
-----------
* **Arms** ``a``: a name, capabilities (informational), the time it becomes
  available, and the zones it stands in at the start (it holds an exclusive
  one until it departs for its first task).
* **Tasks** ``t``: a name, a release time (e.g. the arrival of its parts),
  predecessors (tasks that must end before it starts), a part-set group
  (informational).
* **Modes** ``m`` = (task, capable arm): a duration, zone **windows** and the
  tools held for the whole task. A window is ``(zone, start, end, kind)`` with
  offsets from the task's start: ``occupy`` (the arm is inside the zone) or
  ``move`` (the arm moves inside it). A mode's *borders* are the offsets in
  ``(0, duration)`` where some window starts: a schedule may make the arm
  wait there (S2.6, S2.12; see :mod:`scheduler.timing`).
* **Zones**: exclusive (any window excludes every other arm's windows) or
  shared (only ``move`` windows exclude each other). **Tools** are exclusive
  from a task's start to its end.
* **Setup**: a sequence-dependent travel time per arm between one task's end
  and the next task's start (:mod:`scheduler.setup`).
* **Blocking oracle** (optional): asked whether a mode collides with another
  arm parked at the end pose of a task, and what the detour costs
  (:class:`BlockingOracle`).

Examples
--------
>>> m = Model()
>>> left, right = m.add_arm("left"), m.add_arm("right")
>>> fixture = m.add_zone("fixture", "shared")
>>> pick = m.add_task("pick")
>>> place = m.add_task("place", predecessors=[pick])
>>> m.add_mode(pick, left, 4.0)
>>> m.add_mode(place, left, 5.0, windows=[Window(fixture, 1.0, 4.0, "move")])
>>> m.add_mode(place, right, 6.0, windows=[Window(fixture, 1.0, 5.0, "move")])
>>> p = m.build()
>>> p.n_tasks, p.n_modes, p.task_modes[1]
(2, 3, (1, 2))
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np

from multiarm.errors import CycleError, MultiarmError, UsageError, ValidationError
from multiarm.graph import find_cycle
from multiarm.types import BoolArray, FloatArray, IntArray
from scheduler.setup import BoundSetup, NoSetup, Setup, setup_from_dict
from scheduler.timing import Shapes

__all__ = [
    "BlockingOracle",
    "HasProblem",
    "Model",
    "Problem",
    "ProblemLike",
    "Window",
    "as_problem",
]

WindowKind = Literal["occupy", "move"]

MAX_TIME = 1e9
"""Largest time (seconds, about 32 years) a problem may state: beyond it the
solvers' arithmetic (float sums, CP-SAT's integer scaling) is no longer exact."""


@dataclass(frozen=True, slots=True)
class Window:
    """A zone window of a mode: ``zone`` (name or id), offsets ``start`` < ``end``
    from the task's start (seconds), ``kind`` ``"occupy"`` or ``"move"``."""

    zone: str | int
    start: float
    end: float
    kind: WindowKind = "occupy"


@runtime_checkable
class BlockingOracle(Protocol):
    """Geometry answers for parked arms (DESIGN.md data flow, step 3).

    ``cost(mode, arm, pose_task)``: arm ``arm`` stands parked at the end pose
    of task ``pose_task`` (``-1``: its initial pose) when ``mode`` starts.
    Return 0.0 if they do not collide, the extra time of the detour
    (seconds, > 0) if they do, or ``math.inf`` if no detour exists. Called
    lazily and cached by the solvers, so it may be expensive.
    """

    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        """The detour (seconds) mode ``mode`` costs when arm ``arm`` is parked at
        the end pose of task ``pose_task`` (-1: its initial pose): 0 when it is
        not in the way, ``inf`` when no detour exists."""
        ...


@dataclass(frozen=True, eq=False)
class Problem:
    """Immutable, validated, index-based scheduling problem.

    Build it with :class:`Model`. Arrays are read-only; ids are dense
    (arms ``0..A-1``, tasks ``0..T-1``, modes ``0..M-1``, windows
    ``0..W-1``, zones ``0..Z-1``, tools ``0..K-1``).

    Attributes
    ----------
    arm_names, task_names, zone_names, tool_names : tuple of str
    arm_capabilities : tuple of tuple of str
    arm_available : (A,) float, seconds
    arm_start_zones : tuple of tuple of int
    task_release : (T,) float, seconds
    task_preds : tuple of tuple of int
    task_group : (T,) int (-1: none)
    mode_task, mode_arm : (M,) int
    mode_duration : (M,) float, seconds
    mode_tools : tuple of tuple of int
    win_mode, win_zone : (W,) int
    win_start, win_end : (W,) float, offsets from the task start
    win_move : (W,) bool (True: move window, False: occupy)
    zone_exclusive : (Z,) bool
    setup : Setup
    blocking : BlockingOracle or None
    name : str
    """

    arm_names: tuple[str, ...]
    arm_capabilities: tuple[tuple[str, ...], ...]
    arm_available: FloatArray
    arm_start_zones: tuple[tuple[int, ...], ...]
    task_names: tuple[str, ...]
    task_release: FloatArray
    task_preds: tuple[tuple[int, ...], ...]
    task_group: IntArray
    mode_task: IntArray
    mode_arm: IntArray
    mode_duration: FloatArray
    mode_tools: tuple[tuple[int, ...], ...]
    win_mode: IntArray
    win_zone: IntArray
    win_start: FloatArray
    win_end: FloatArray
    win_move: BoolArray
    zone_names: tuple[str, ...]
    zone_exclusive: BoolArray
    tool_names: tuple[str, ...]
    setup: Setup = field(default_factory=NoSetup)
    blocking: BlockingOracle | None = None
    name: str = "problem"
    # derived
    task_modes: tuple[tuple[int, ...], ...] = field(init=False)
    task_succs: tuple[tuple[int, ...], ...] = field(init=False)
    mode_windows: tuple[tuple[int, ...], ...] = field(init=False)
    mode_of: IntArray = field(init=False)
    _setup: BoundSetup = field(init=False, repr=False)

    def __post_init__(self) -> None:
        T, M = len(self.task_names), len(self.mode_task)
        modes: list[list[int]] = [[] for _ in range(T)]
        for m in range(M):
            modes[int(self.mode_task[m])].append(m)
        object.__setattr__(self, "task_modes", tuple(tuple(x) for x in modes))
        succ: list[list[int]] = [[] for _ in range(T)]
        for t, ps in enumerate(self.task_preds):
            for p in ps:
                succ[p].append(t)
        object.__setattr__(self, "task_succs", tuple(tuple(x) for x in succ))
        wins: list[list[int]] = [[] for _ in range(M)]
        for w in range(len(self.win_mode)):
            wins[int(self.win_mode[w])].append(w)
        object.__setattr__(self, "mode_windows", tuple(tuple(x) for x in wins))
        mode_of = -np.ones((len(self.arm_names), T), dtype=np.int64)
        mode_of[self.mode_arm, self.mode_task] = np.arange(M)
        object.__setattr__(self, "mode_of", mode_of)
        object.__setattr__(self, "_setup", self.setup.bind(self))
        for arr in (
            self.arm_available,
            self.task_release,
            self.task_group,
            self.mode_task,
            self.mode_arm,
            self.mode_duration,
            self.win_mode,
            self.win_zone,
            self.win_start,
            self.win_end,
            self.win_move,
            self.zone_exclusive,
            self.mode_of,
        ):
            arr.setflags(write=False)

    # ----------------------------------------------------------- sizes
    @property
    def n_arms(self) -> int:
        """The number of arms."""
        return len(self.arm_names)

    @property
    def n_tasks(self) -> int:
        """The number of tasks."""
        return len(self.task_names)

    @property
    def n_modes(self) -> int:
        """The number of modes (task, arm) pairs."""
        return len(self.mode_task)

    @property
    def n_windows(self) -> int:
        """The number of zone windows of all modes."""
        return len(self.win_mode)

    @property
    def n_zones(self) -> int:
        """The number of zones."""
        return len(self.zone_names)

    @property
    def n_tools(self) -> int:
        """The number of tools."""
        return len(self.tool_names)

    @cached_property
    def topological_order(self) -> tuple[int, ...]:
        """Task ids in an order where every task comes after its predecessors."""
        indeg = [len(ps) for ps in self.task_preds]
        order = [t for t in range(self.n_tasks) if indeg[t] == 0]
        i = 0
        while i < len(order):
            for s in self.task_succs[order[i]]:
                indeg[s] -= 1
                if indeg[s] == 0:
                    order.append(s)
            i += 1
        return tuple(order)

    @cached_property
    def shapes(self) -> Shapes:
        """Per-mode timing structure (:mod:`scheduler.timing`), computed once."""
        return Shapes(self)

    def setup_time(self, arm: int, prev: int, nxt: int) -> float:
        """Travel time of ``arm`` from the end of task ``prev`` (-1: its initial
        pose) to the start of task ``nxt``, seconds."""
        return self._setup.time(arm, prev, nxt)

    def setup_row(self, arm: int, prev: int) -> FloatArray:
        """(T,) float: setup times of ``arm`` from ``prev`` to every task
        (cached; entries for tasks the arm cannot do are meaningless)."""
        return self._setup.row(arm, prev)

    def min_duration(self) -> FloatArray:
        """(T,) float: each task's shortest mode duration."""
        out = np.full(self.n_tasks, np.inf)
        np.minimum.at(out, self.mode_task, self.mode_duration)
        return out

    def mode_borders(self, m: int) -> tuple[float, ...]:
        """Offsets in ``(0, duration)`` where a window of mode ``m`` starts (wait points)."""
        d = float(self.mode_duration[m])
        return tuple(
            sorted(
                {
                    float(self.win_start[w])
                    for w in self.mode_windows[m]
                    if 0.0 < self.win_start[w] < d
                }
            )
        )

    def has_zones(self) -> bool:
        """Whether any mode has a zone window."""
        return self.n_windows > 0

    def __repr__(self) -> str:
        return (
            f"Problem({self.name!r}: {self.n_arms} arms, {self.n_tasks} tasks, "
            f"{self.n_modes} modes, {self.n_zones} zones, {self.n_tools} tools)"
        )

    # ---------------------------------------------------------- equality
    def __eq__(self, other: object) -> bool:
        """Equal data: names, every array, the setup (by its data) and the same
        blocking oracle object. For round-trip checks (``save_problem`` then
        ``load_problem`` gives an equal problem).

        Examples
        --------
        >>> from scheduler.fjsp import parse_fjsp
        >>> parse_fjsp("1 1\\n1 1 1 2\\n") == parse_fjsp("1 1\\n1 1 1 2\\n")
        True
        >>> parse_fjsp("1 1\\n1 1 1 2\\n") == parse_fjsp("1 1\\n1 1 1 3\\n")
        False
        """
        if not isinstance(other, Problem):
            return NotImplemented
        if self is other:
            return True
        for f in _DATA_FIELDS:
            a, b = getattr(self, f), getattr(other, f)
            if isinstance(a, np.ndarray):
                if a.dtype != b.dtype or not np.array_equal(a, b):
                    return False
            elif a != b:
                return False
        return self.blocking is other.blocking and _same_setup(self.setup, other.setup)

    def __hash__(self) -> int:
        # consistent with __eq__: equal problems have equal names and sizes
        return hash((self.name, self.task_names, self.arm_names, self.n_modes, self.n_windows))

    # -------------------------------------------------------- plain data
    def to_dict(self) -> dict[str, Any]:
        """Plain data with names (JSON-ready). The blocking oracle is not
        included (it is code); a callable setup cannot be written."""
        arms = [
            {
                "name": self.arm_names[a],
                "available": float(self.arm_available[a]),
                "capabilities": list(self.arm_capabilities[a]),
                "start_zones": [self.zone_names[z] for z in self.arm_start_zones[a]],
            }
            for a in range(self.n_arms)
        ]
        tasks = []
        for t in range(self.n_tasks):
            modes = []
            for m in self.task_modes[t]:
                modes.append(
                    {
                        "arm": self.arm_names[self.mode_arm[m]],
                        "duration": float(self.mode_duration[m]),
                        "windows": [
                            {
                                "zone": self.zone_names[self.win_zone[w]],
                                "start": float(self.win_start[w]),
                                "end": float(self.win_end[w]),
                                "kind": "move" if self.win_move[w] else "occupy",
                            }
                            for w in self.mode_windows[m]
                        ],
                        "tools": [self.tool_names[k] for k in self.mode_tools[m]],
                    }
                )
            tasks.append(
                {
                    "name": self.task_names[t],
                    "release": float(self.task_release[t]),
                    "predecessors": [self.task_names[p] for p in self.task_preds[t]],
                    "group": int(self.task_group[t]),
                    "modes": modes,
                }
            )
        return {
            "format": "multiarm.problem/1",
            "name": self.name,
            "arms": arms,
            "zones": [
                {"name": n, "policy": "exclusive" if e else "shared"}
                for n, e in zip(self.zone_names, self.zone_exclusive.tolist(), strict=True)
            ],
            "tools": list(self.tool_names),
            "tasks": tasks,
            "setup": self.setup.to_dict(),
        }


_DATA_FIELDS = (
    "name",
    "arm_names",
    "arm_capabilities",
    "arm_available",
    "arm_start_zones",
    "task_names",
    "task_release",
    "task_preds",
    "task_group",
    "mode_task",
    "mode_arm",
    "mode_duration",
    "mode_tools",
    "win_mode",
    "win_zone",
    "win_start",
    "win_end",
    "win_move",
    "zone_names",
    "zone_exclusive",
    "tool_names",
)


def _same_setup(a: Setup, b: Setup) -> bool:
    """Two setups with the same data (a setup that is code: the same object)."""
    if a is b:
        return True
    if type(a) is not type(b):
        return False
    try:
        return bool(a.to_dict() == b.to_dict())
    except MultiarmError:  # code (FunctionSetup): only itself is equal
        return False


# ---------------------------------------------------------------- builder


@dataclass
class _Arm:
    name: str
    available: float
    capabilities: tuple[str, ...]
    start_zones: tuple[str | int, ...]


@dataclass
class _Task:
    name: str
    release: float
    group: int
    preds: list[str | int] = field(default_factory=list)


@dataclass
class _Mode:
    task: str | int
    arm: str | int
    duration: float
    windows: tuple[Window, ...]
    tools: tuple[str | int, ...]


class Model:
    """Builder of a :class:`Problem`, for people: names or ids, one call per element.

    Every ``add_*`` returns the new element's id. References may use names
    or ids. Nothing is checked until :meth:`build`, which raises
    :class:`~multiarm.errors.ValidationError` naming the culprit.
    """

    def __init__(self, name: str = "problem") -> None:
        self.name = name
        self._arms: list[_Arm] = []
        self._tasks: list[_Task] = []
        self._modes: list[_Mode] = []
        self._zones: list[tuple[str, bool]] = []
        self._tools: list[str] = []
        self._setup: Setup | None = None
        self._setup_dict: Mapping[str, Any] | None = None
        self._blocking: BlockingOracle | None = None

    def add_arm(
        self,
        name: str,
        *,
        available: float = 0.0,
        capabilities: Iterable[str] = (),
        start_zones: Iterable[str | int] = (),
    ) -> int:
        """Add an arm; returns its id."""
        self._arms.append(
            _Arm(str(name), float(available), tuple(capabilities), tuple(start_zones))
        )
        return len(self._arms) - 1

    def add_zone(self, name: str, policy: Literal["exclusive", "shared"] = "exclusive") -> int:
        """Add a zone (``"exclusive"`` or ``"shared"``); returns its id."""
        if policy not in ("exclusive", "shared"):
            raise ValidationError(
                f"zone {name!r}: policy must be 'exclusive' or 'shared', not {policy!r}"
            )
        self._zones.append((str(name), policy == "exclusive"))
        return len(self._zones) - 1

    def add_tool(self, name: str) -> int:
        """Add a tool (an exclusive resource); returns its id."""
        self._tools.append(str(name))
        return len(self._tools) - 1

    def add_task(
        self,
        name: str,
        *,
        release: float = 0.0,
        predecessors: Iterable[str | int] = (),
        group: int = -1,
    ) -> int:
        """Add a task; returns its id."""
        self._tasks.append(_Task(str(name), float(release), int(group), list(predecessors)))
        return len(self._tasks) - 1

    def add_predecessors(self, task: str | int, predecessors: Iterable[str | int]) -> None:
        """Add precedence constraints: every ``predecessors`` task ends before ``task`` starts."""
        self._tasks[self._index(task, self._tasks, "task")].preds.extend(predecessors)

    def add_mode(
        self,
        task: str | int,
        arm: str | int,
        duration: float,
        *,
        windows: Iterable[Window] = (),
        tools: Iterable[str | int] = (),
    ) -> None:
        """Let ``arm`` do ``task`` in ``duration`` seconds, with zone windows and tools."""
        self._modes.append(_Mode(task, arm, float(duration), tuple(windows), tuple(tools)))

    def set_setup(self, setup: Setup | None) -> None:
        """Sequence-dependent setup (travel) times (:mod:`scheduler.setup`)."""
        self._setup = setup

    def set_blocking(self, oracle: BlockingOracle | None) -> None:
        """The blocking oracle (or None)."""
        if oracle is not None and not isinstance(oracle, BlockingOracle):
            raise ValidationError(
                "the blocking oracle must have a cost(mode, arm, pose_task) method"
            )
        self._blocking = oracle

    @staticmethod
    def _index(ref: str | int, items: Sequence[Any], what: str) -> int:
        if isinstance(ref, bool):
            raise ValidationError(f"unknown {what} {ref!r}")
        if isinstance(ref, int | np.integer):
            if 0 <= ref < len(items):
                return int(ref)
            raise ValidationError(f"unknown {what} id {ref} (there are {len(items)})")
        for i, it in enumerate(items):
            name = it if isinstance(it, str) else (it[0] if isinstance(it, tuple) else it.name)
            if name == ref:
                return i
        raise ValidationError(f"unknown {what} {ref!r}")

    def build(self) -> Problem:
        """Validate and freeze into a :class:`Problem`.

        Raises
        ------
        ValidationError
            Duplicate names; unknown arm, zone, tool or task; a task no arm
            can do; two modes of one task on the same arm; a negative or
            non-finite duration, release or availability; a window outside
            its mode or with ``end <= start``; an arm starting in an
            exclusive zone together with another arm.
        CycleError
            When the precedence constraints have a cycle (named).
        """
        for what, names in (
            ("arm", [a.name for a in self._arms]),
            ("task", [tk.name for tk in self._tasks]),
            ("zone", [z for z, _ in self._zones]),
            ("tool", self._tools),
        ):
            seen: set[str] = set()
            for n in names:
                if n in seen:
                    raise ValidationError(f"duplicate {what} name {n!r}")
                seen.add(n)
        if not self._arms:
            raise ValidationError("a problem needs at least one arm")
        for arm in self._arms:
            if not (math.isfinite(arm.available) and arm.available >= 0):
                raise ValidationError(
                    f"arm {arm.name!r}: available time must be finite and >= 0, got {arm.available}"
                )
            if arm.available > MAX_TIME:
                raise ValidationError(
                    f"arm {arm.name!r}: available time {arm.available:g} s is beyond the largest "
                    f"time the solvers handle ({MAX_TIME:g} s)"
                )
        start_zones = []
        for arm in self._arms:
            zs = tuple(sorted({self._index(z, self._zones, "zone") for z in arm.start_zones}))
            start_zones.append(zs)
        for z, (zname, excl) in enumerate(self._zones):
            if excl:
                inside = [self._arms[i].name for i, zs in enumerate(start_zones) if z in zs]
                if len(inside) > 1:
                    raise ValidationError(
                        f"arms {inside} cannot all start in exclusive zone {zname!r}"
                    )
        preds: list[tuple[int, ...]] = []
        for task in self._tasks:
            if not (math.isfinite(task.release) and task.release >= 0):
                raise ValidationError(
                    f"task {task.name!r}: release must be finite and >= 0, got {task.release}"
                )
            if task.release > MAX_TIME:
                raise ValidationError(
                    f"task {task.name!r}: release {task.release:g} s is beyond the largest time "
                    f"the solvers handle ({MAX_TIME:g} s)"
                )
            ps = []
            for p in task.preds:
                try:
                    pi = self._index(p, self._tasks, "task")
                except ValidationError:
                    raise ValidationError(
                        f"task {task.name!r} has unknown predecessor {p!r}"
                    ) from None
                ps.append(pi)
            preds.append(tuple(dict.fromkeys(ps)))
        names = [tk.name for tk in self._tasks]
        succ: dict[str, list[str]] = {n: [] for n in names}
        for s, pl in enumerate(preds):
            for q in pl:
                succ[names[q]].append(names[s])
        cycle = find_cycle(succ)
        if cycle is not None:
            raise CycleError("precedence cycle: " + " -> ".join(cycle), cycle)
        mode_task: list[int] = []
        mode_arm: list[int] = []
        mode_dur: list[float] = []
        mode_tools: list[tuple[int, ...]] = []
        win_mode: list[int] = []
        win_zone: list[int] = []
        win_s: list[float] = []
        win_e: list[float] = []
        win_mv: list[bool] = []
        seen_pairs: set[tuple[int, int]] = set()
        for md in self._modes:
            try:
                t = self._index(md.task, self._tasks, "task")
            except ValidationError:
                raise ValidationError(f"a mode names unknown task {md.task!r}") from None
            tname = self._tasks[t].name
            try:
                a = self._index(md.arm, self._arms, "arm")
            except ValidationError:
                raise ValidationError(
                    f"task {tname!r}: a mode names unknown arm {md.arm!r}"
                ) from None
            if (t, a) in seen_pairs:
                raise ValidationError(f"task {tname!r} has two modes on arm {self._arms[a].name!r}")
            seen_pairs.add((t, a))
            where = f"task {tname!r} on arm {self._arms[a].name!r}"
            if not (math.isfinite(md.duration) and md.duration >= 0):
                raise ValidationError(
                    f"{where}: duration must be finite and >= 0, got {md.duration}"
                )
            if md.duration > MAX_TIME:
                raise ValidationError(
                    f"{where}: duration {md.duration:g} s is beyond the largest time the "
                    f"solvers handle ({MAX_TIME:g} s)"
                )
            m = len(mode_task)
            for w in md.windows:
                if not isinstance(w, Window):
                    raise ValidationError(f"{where}: windows must be Window records, got {w!r}")
                try:
                    z = self._index(w.zone, self._zones, "zone")
                except ValidationError:
                    raise ValidationError(f"{where}: window in unknown zone {w.zone!r}") from None
                ws, we = float(w.start), float(w.end)
                if not (math.isfinite(ws) and math.isfinite(we)):
                    raise ValidationError(
                        f"{where}: window in zone {self._zones[z][0]!r} has a non-finite offset"
                    )
                if not (0.0 <= ws < we <= md.duration):
                    raise ValidationError(
                        f"{where}: window [{ws}, {we}) in zone {self._zones[z][0]!r} is outside the mode "
                        f"(must satisfy 0 <= start < end <= duration {md.duration})"
                    )
                if w.kind not in ("occupy", "move"):
                    raise ValidationError(
                        f"{where}: window kind must be 'occupy' or 'move', not {w.kind!r}"
                    )
                win_mode.append(m)
                win_zone.append(z)
                win_s.append(ws)
                win_e.append(we)
                win_mv.append(w.kind == "move")
            tools = []
            for k in md.tools:
                try:
                    tools.append(self._index(k, self._tools, "tool"))
                except ValidationError:
                    raise ValidationError(f"{where}: unknown tool {k!r}") from None
            mode_task.append(t)
            mode_arm.append(a)
            mode_dur.append(md.duration)
            mode_tools.append(tuple(sorted(set(tools))))
        has_mode = set(mode_task)
        for t, task in enumerate(self._tasks):
            if t not in has_mode:
                raise ValidationError(f"task {task.name!r} has no mode: no arm can do it")
        # order modes by (task, arm) so that ids are canonical
        order = sorted(range(len(mode_task)), key=lambda i: (mode_task[i], mode_arm[i]))
        remap = {old: new for new, old in enumerate(order)}
        worder = sorted(
            range(len(win_mode)),
            key=lambda w: (remap[win_mode[w]], win_s[w], win_e[w], win_zone[w], win_mv[w]),
        )
        problem_arrays = dict(
            mode_task=np.array([mode_task[i] for i in order], dtype=np.int64),
            mode_arm=np.array([mode_arm[i] for i in order], dtype=np.int64),
            mode_duration=np.array([mode_dur[i] for i in order], dtype=float),
            mode_tools=tuple(mode_tools[i] for i in order),
            win_mode=np.array([remap[win_mode[w]] for w in worder], dtype=np.int64),
            win_zone=np.array([win_zone[w] for w in worder], dtype=np.int64),
            win_start=np.array([win_s[w] for w in worder], dtype=float),
            win_end=np.array([win_e[w] for w in worder], dtype=float),
            win_move=np.array([win_mv[w] for w in worder], dtype=bool),
        )
        setup: Setup = self._setup if self._setup is not None else NoSetup()
        if self._setup_dict is not None and self._setup is None:
            setup = setup_from_dict(self._setup_dict)
        problem = Problem(
            arm_names=tuple(a.name for a in self._arms),
            arm_capabilities=tuple(a.capabilities for a in self._arms),
            arm_available=np.array([a.available for a in self._arms], dtype=float),
            arm_start_zones=tuple(start_zones),
            task_names=tuple(names),
            task_release=np.array([t.release for t in self._tasks], dtype=float),
            task_preds=tuple(preds),
            task_group=np.array([t.group for t in self._tasks], dtype=np.int64),
            zone_names=tuple(z for z, _ in self._zones),
            zone_exclusive=np.array([e for _, e in self._zones], dtype=bool),
            tool_names=tuple(self._tools),
            setup=setup,
            blocking=self._blocking,
            name=self.name,
            **problem_arrays,  # type: ignore[arg-type]
        )
        problem._setup.check()
        return problem


class HasProblem(Protocol):
    """Anything that carries a :class:`Problem` as ``.problem`` (a compiled
    cell, for example): :func:`scheduler.solve` and
    :func:`scheduler.validate` accept it in place of the problem."""

    @property
    def problem(self) -> Problem:
        """The scheduling problem."""
        ...


ProblemLike = Problem | HasProblem
"""A :class:`Problem` or an object with a ``.problem`` Problem."""


def as_problem(obj: ProblemLike, where: str = "problem") -> Problem:
    """The :class:`Problem` of ``obj``: itself, or its ``.problem``.

    Raises
    ------
    UsageError
        Neither (the message names ``where`` and the type given).
    """
    if isinstance(obj, Problem):
        return obj
    inner = getattr(obj, "problem", None)
    if isinstance(inner, Problem):
        return inner
    raise UsageError(
        f"{where}: expected a scheduler.Problem or an object with a .problem Problem "
        f"(such as a workcell.CompiledCell), got {type(obj).__name__}"
    )
