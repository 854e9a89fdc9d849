"""Immutable records of an assembly: tasks, parts, part groups, and the task set.

An *elementary task* (SEEDS.md S2.10) is done by one arm, start to end: an
ordered list of step primitives, the capabilities and tool it needs, the tasks
that must finish before it (prerequisites), and the parts it consumes and
produces. Which arm does it, and when, is the scheduler's business.

Parts can also carry the description (S2.11, part-driven): a :class:`Part`
lists the parts that must be assembled before it and the tasks that assemble
it; a :class:`PartGroup` holds tasks that belong to a set of *independent*
parts (none a prerequisite of another) and run once all of them are assembled.
:meth:`TaskSet.precedence` folds every source of ordering into one task graph.

A :class:`TaskSet` validates itself when built and names the culprit of every
problem; see :meth:`TaskSet.__post_init__` for the list of checks.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from multiarm.errors import CycleError, ValidationError
from multiarm.graph import find_cycle, longest_path_lengths
from multiarm.types import Seed, as_rng
from tasklib.arrivals import Feeder, PartArrival
from tasklib.steps import (
    STEP_KINDS,
    Detect,
    Grasp,
    Insert,
    Move,
    Release,
    SetFlag,
    Step,
    UseTool,
    WaitFlag,
)
from tasklib.tdl import TDLDocument

__all__ = ["Part", "PartGroup", "Task", "TaskSet"]


def _ident(value: object, what: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ValidationError(f"{what} must be a non-empty name, got {value!r}")
    return value


def _names(values: Iterable[object], what: str) -> tuple[str, ...]:
    if isinstance(values, str):
        raise ValidationError(f"{what} must be a list of names, got the string {values!r}")
    out = tuple(_ident(v, what) for v in values)
    if len(set(out)) != len(out):
        dup = next(v for v in out if out.count(v) > 1)
        raise ValidationError(f"{what} lists {dup!r} twice")
    return out


@dataclass(frozen=True, slots=True)
class Task:
    """An elementary task, performed start to end by one arm.

    Parameters
    ----------
    id : str
    steps : tuple of Step
        At least one, in order.
    capabilities : tuple of str
        Capabilities the arm needs beyond those the steps imply (see
        :attr:`required_capabilities`). Whether any arm offers them is
        checked by later layers, which know the arms.
    tool : str or None
        The tool the task holds from start to end (every ``use_tool`` step
        must use this tool).
    prerequisites : tuple of str
        Tasks that must finish before this one starts.
    consumes : tuple of str
        Parts the task needs (fed parts, or parts another task produces).
    produces : tuple of str
        Parts (sub-assemblies) the task makes.
    description : str
    """

    id: str
    steps: tuple[Step, ...]
    capabilities: tuple[str, ...] = ()
    tool: str | None = None
    prerequisites: tuple[str, ...] = ()
    consumes: tuple[str, ...] = ()
    produces: tuple[str, ...] = ()
    description: str = ""

    def __post_init__(self) -> None:
        _ident(self.id, "task id")
        object.__setattr__(self, "steps", tuple(self.steps))
        if not self.steps:
            raise ValidationError(f"task {self.id!r} has no step")
        kinds = tuple(STEP_KINDS.values())
        for i, s in enumerate(self.steps, start=1):
            if not isinstance(s, kinds):
                raise ValidationError(
                    f"task {self.id!r} step {i} is not a step primitive: {type(s).__name__}"
                )
        object.__setattr__(
            self, "capabilities", _names(self.capabilities, f"task {self.id!r} capabilities")
        )
        if self.tool is not None:
            _ident(self.tool, f"task {self.id!r} tool")
        object.__setattr__(
            self, "prerequisites", _names(self.prerequisites, f"task {self.id!r} prerequisites")
        )
        if self.id in self.prerequisites:
            raise CycleError(f"task {self.id!r} lists itself as a prerequisite", (self.id, self.id))
        object.__setattr__(self, "consumes", _names(self.consumes, f"task {self.id!r} consumes"))
        object.__setattr__(self, "produces", _names(self.produces, f"task {self.id!r} produces"))
        both = set(self.consumes) & set(self.produces)
        if both:
            raise ValidationError(f"task {self.id!r} both consumes and produces part {min(both)!r}")
        for i, s in enumerate(self.steps, start=1):
            if isinstance(s, UseTool) and s.tool != self.tool:
                declared = "no tool" if self.tool is None else f"tool {self.tool!r}"
                raise ValidationError(
                    f"task {self.id!r} step {i} uses tool {s.tool!r} but the task declares {declared}"
                )

    @property
    def required_capabilities(self) -> frozenset[str]:
        """Declared capabilities plus those the steps imply
        (``grasp``/``release`` need ``gripper``, ``insert`` a ``force_sensor``,
        ``detect`` an ``object_detector``, ``use_tool`` a ``tool_changer``)."""
        caps = set(self.capabilities)
        for s in self.steps:
            caps.update(s.capabilities)
        return frozenset(caps)

    def flags_set(self) -> tuple[str, ...]:
        """Flags raised by ``set_flag`` steps, in order."""
        return tuple(s.flag for s in self.steps if isinstance(s, SetFlag))

    def flags_waited(self) -> tuple[str, ...]:
        """Flags waited for by ``wait_flag`` steps, in order."""
        return tuple(s.flag for s in self.steps if isinstance(s, WaitFlag))

    def trajectories(self) -> tuple[str, ...]:
        """Names of the TDL trajectories the task's moves follow."""
        return tuple(s.trajectory for s in self.steps if isinstance(s, Move) and s.trajectory)

    def parts_handled(self) -> tuple[str, ...]:
        """Parts named by grasp, release, insert and detect steps."""
        return tuple(
            s.part
            for s in self.steps
            if isinstance(s, Grasp | Release | Insert | Detect) and s.part is not None
        )


@dataclass(frozen=True, slots=True)
class Part:
    """A part of the product (S2.11, part-driven description).

    Parameters
    ----------
    id : str
    prerequisites : tuple of str
        Parts that must be assembled before this part's tasks start.
    tasks : tuple of str
        Tasks that assemble this part; the part is *assembled* when they are
        all done (a part with no task is assembled when it arrives).
    description : str
    """

    id: str
    prerequisites: tuple[str, ...] = ()
    tasks: tuple[str, ...] = ()
    description: str = ""

    def __post_init__(self) -> None:
        _ident(self.id, "part id")
        object.__setattr__(
            self, "prerequisites", _names(self.prerequisites, f"part {self.id!r} prerequisites")
        )
        if self.id in self.prerequisites:
            raise CycleError(f"part {self.id!r} lists itself as a prerequisite", (self.id, self.id))
        object.__setattr__(self, "tasks", _names(self.tasks, f"part {self.id!r} tasks"))


@dataclass(frozen=True, slots=True)
class PartGroup:
    """Tasks that belong to a set of independent parts once all are assembled (S2.11).

    Parameters
    ----------
    id : str
    parts : tuple of str
        At least two parts, none a (transitive) prerequisite of another.
    tasks : tuple of str
        Tasks that start only when every part of the group is assembled.
    """

    id: str
    parts: tuple[str, ...]
    tasks: tuple[str, ...] = ()
    description: str = ""

    def __post_init__(self) -> None:
        _ident(self.id, "part group id")
        object.__setattr__(self, "parts", _names(self.parts, f"part group {self.id!r} parts"))
        if len(self.parts) < 2:
            raise ValidationError(f"part group {self.id!r} needs at least two parts")
        object.__setattr__(self, "tasks", _names(self.tasks, f"part group {self.id!r} tasks"))


def _dups(ids: list[str]) -> str | None:
    seen: set[str] = set()
    for i in ids:
        if i in seen:
            return i
        seen.add(i)
    return None


@dataclass(frozen=True, slots=True)
class TaskSet:
    """The tasks, parts, feeders, part groups and trajectories of one assembly.

    Construction validates everything and raises :class:`ValidationError`
    (or :class:`CycleError`) naming the culprit:

    * duplicate ids among tasks, parts, feeders, groups;
    * unknown prerequisites, parts, feeders, trajectories, group members;
    * a task owned by two parts/groups, a part fed by two feeders or
      produced by two tasks, a part both fed and produced;
    * parts consumed but never supplied (no feeder, no producing task);
    * parts of a group that are not independent;
    * flags waited for but never set;
    * cycles in the part prerequisites, and in the task graph formed by
      prerequisites, parts, groups, produce/consume and flags (named).

    Capabilities that no arm offers are left to later layers.

    Examples
    --------
    >>> from tasklib.steps import Dwell
    >>> ts = TaskSet("tiny", (Task("a", (Dwell(1.0),)), Task("b", (Dwell(1.0),), prerequisites=("a",))))
    >>> ts.depth()
    2
    >>> TaskSet("bad", (Task("a", (Dwell(1.0),), prerequisites=("c",)),))
    Traceback (most recent call last):
    ...
    multiarm.errors.ValidationError: task 'a' requires unknown task 'c'
    """

    name: str
    tasks: tuple[Task, ...]
    parts: tuple[Part, ...] = ()
    feeders: tuple[Feeder, ...] = ()
    groups: tuple[PartGroup, ...] = ()
    trajectories: TDLDocument = field(default_factory=TDLDocument)
    description: str = ""
    _task: dict[str, Task] = field(default_factory=dict, init=False, compare=False, repr=False)
    _pred: dict[str, tuple[str, ...]] = field(
        default_factory=dict, init=False, compare=False, repr=False
    )

    # -------------------------------------------------------------- checks
    def __post_init__(self) -> None:
        _ident(self.name, "task set name")
        for attr, cls in (
            ("tasks", Task),
            ("parts", Part),
            ("feeders", Feeder),
            ("groups", PartGroup),
        ):
            items = tuple(getattr(self, attr))
            for it in items:
                if not isinstance(it, cls):
                    raise ValidationError(
                        f"task set {attr} must be {cls.__name__} records, got {type(it).__name__}"
                    )
            object.__setattr__(self, attr, items)
            dup = _dups([it.id for it in items])
            if dup is not None:
                raise ValidationError(f"duplicate {cls.__name__.lower()} id {dup!r}")
        if not isinstance(self.trajectories, TDLDocument):
            raise ValidationError("task set trajectories must be a TDLDocument")
        if not self.tasks:
            raise ValidationError(f"task set {self.name!r} has no task")
        tasks = {t.id: t for t in self.tasks}
        parts = {p.id: p for p in self.parts}
        self._task.update(tasks)

        for t in self.tasks:
            for r in t.prerequisites:
                if r not in tasks:
                    raise ValidationError(f"task {t.id!r} requires unknown task {r!r}")
            for p in (*t.consumes, *t.produces, *t.parts_handled()):
                if p not in parts:
                    raise ValidationError(f"task {t.id!r} names unknown part {p!r}")
            for i, s in enumerate(t.steps, start=1):
                if (
                    isinstance(s, Move)
                    and s.trajectory is not None
                    and s.trajectory not in self.trajectories
                ):
                    raise ValidationError(
                        f"task {t.id!r} step {i} (move) uses unknown trajectory {s.trajectory!r}"
                    )

        owner: dict[str, str] = {}
        for part in self.parts:
            for q in part.prerequisites:
                if q not in parts:
                    raise ValidationError(f"part {part.id!r} requires unknown part {q!r}")
            for tid in part.tasks:
                self._own(owner, tid, f"part {part.id!r}", tasks)
        for g in self.groups:
            for q in g.parts:
                if q not in parts:
                    raise ValidationError(f"part group {g.id!r} names unknown part {q!r}")
            for tid in g.tasks:
                self._own(owner, tid, f"part group {g.id!r}", tasks)

        cycle = find_cycle({p.id: list(p.prerequisites) for p in self.parts})
        if cycle is not None:
            raise CycleError("part prerequisite cycle: " + " -> ".join(cycle), cycle)
        closure = self._part_closure()
        for g in self.groups:
            for a in g.parts:
                for b in g.parts:
                    if a != b and b in closure[a]:
                        raise ValidationError(
                            f"part group {g.id!r} parts are not independent: "
                            f"{b!r} is a prerequisite of {a!r}"
                        )

        fed: dict[str, str] = {}
        for f in self.feeders:
            for p in f.parts:
                if p not in parts:
                    raise ValidationError(f"feeder {f.id!r} supplies unknown part {p!r}")
                if p in fed:
                    raise ValidationError(
                        f"part {p!r} is supplied by feeders {fed[p]!r} and {f.id!r}"
                    )
                fed[p] = f.id
        producer: dict[str, str] = {}
        for t in self.tasks:
            for p in t.produces:
                if p in producer:
                    raise ValidationError(
                        f"part {p!r} is produced by tasks {producer[p]!r} and {t.id!r}"
                    )
                if p in fed:
                    raise ValidationError(
                        f"part {p!r} is both supplied by feeder {fed[p]!r} and produced by task {t.id!r}"
                    )
                producer[p] = t.id
        for t in self.tasks:
            for p in t.consumes:
                if p not in fed and p not in producer:
                    raise ValidationError(
                        f"task {t.id!r} consumes part {p!r}, which no feeder supplies and no task produces"
                    )

        setters: dict[str, list[str]] = {}
        for t in self.tasks:
            for fl in t.flags_set():
                setters.setdefault(fl, []).append(t.id)
        for t in self.tasks:
            for fl in t.flags_waited():
                if fl not in setters:
                    raise ValidationError(
                        f"task {t.id!r} waits for flag {fl!r}, which no task sets"
                    )

        pred = self._build_precedence(producer)
        object.__setattr__(self, "_pred", pred)
        graph: dict[str, list[str]] = {tid: [] for tid in tasks}
        for tid, ps in pred.items():
            for q in ps:
                graph[q].append(tid)
        for t in self.tasks:
            for fl in t.flags_waited():
                for setter in setters[fl]:
                    if setter != t.id:
                        graph[setter].append(t.id)
        cycle = find_cycle(graph)
        if cycle is not None:
            raise CycleError("task prerequisite cycle: " + " -> ".join(cycle), cycle)

    @staticmethod
    def _own(owner: dict[str, str], tid: str, who: str, tasks: Mapping[str, Task]) -> None:
        if tid not in tasks:
            raise ValidationError(f"{who} lists unknown task {tid!r}")
        if tid in owner:
            raise ValidationError(f"task {tid!r} belongs to both {owner[tid]} and {who}")
        owner[tid] = who

    def _part_closure(self) -> dict[str, set[str]]:
        parts = {p.id: p for p in self.parts}
        closure: dict[str, set[str]] = {}

        def visit(pid: str) -> set[str]:
            if pid in closure:
                return closure[pid]
            out: set[str] = set()
            stack = list(parts[pid].prerequisites)
            while stack:
                q = stack.pop()
                if q not in out:
                    out.add(q)
                    stack.extend(parts[q].prerequisites)
            closure[pid] = out
            return out

        for pid in parts:
            visit(pid)
        return closure

    def _build_precedence(self, producer: Mapping[str, str]) -> dict[str, tuple[str, ...]]:
        parts = {p.id: p for p in self.parts}
        pred: dict[str, list[str]] = {t.id: list(t.prerequisites) for t in self.tasks}
        for t in self.tasks:
            for p in t.consumes:
                if p in producer:
                    pred[t.id].append(producer[p])
        for part in self.parts:
            needed = [q for prereq in part.prerequisites for q in parts[prereq].tasks]
            for tid in part.tasks:
                pred[tid].extend(needed)
        for g in self.groups:
            needed = [q for pid in g.parts for q in parts[pid].tasks]
            for tid in g.tasks:
                pred[tid].extend(needed)
        return {tid: tuple(dict.fromkeys(q for q in ps if q != tid)) for tid, ps in pred.items()}

    # ------------------------------------------------------------- queries
    def task(self, task_id: str) -> Task:
        """The task with this id (raises :class:`ValidationError` if none)."""
        try:
            return self._task[task_id]
        except KeyError:
            raise ValidationError(f"unknown task {task_id!r}") from None

    def precedence(self) -> dict[str, tuple[str, ...]]:
        """Every task's direct predecessors in the effective task graph.

        Union of explicit prerequisites, producers of consumed parts, the
        tasks of prerequisite parts (for a part's tasks) and of a group's
        parts (for the group's tasks). Flags are not in it: a flag may be
        set in the middle of a task (see :meth:`flag_edges`).
        """
        return dict(self._pred)

    def flag_edges(self) -> tuple[tuple[str, str, str], ...]:
        """``(setter task, waiting task, flag)`` for every flag synchronisation."""
        setters: dict[str, list[str]] = {}
        for t in self.tasks:
            for fl in t.flags_set():
                setters.setdefault(fl, []).append(t.id)
        return tuple(
            (s, t.id, fl) for t in self.tasks for fl in t.flags_waited() for s in setters[fl]
        )

    def gating_parts(self, task_id: str) -> tuple[str, ...]:
        """Fed parts whose arrival a task must wait for.

        The parts it consumes that a feeder supplies, plus task-less fed
        parts among its part's (or group's) prerequisites: such a part is
        "assembled" when it arrives.
        """
        t = self.task(task_id)
        fed = {p for f in self.feeders for p in f.parts}
        parts = {p.id: p for p in self.parts}
        out = [p for p in t.consumes if p in fed]
        for p in self.parts:
            if task_id in p.tasks:
                out.extend(q for q in p.prerequisites if q in fed and not parts[q].tasks)
        for g in self.groups:
            if task_id in g.tasks:
                out.extend(q for q in g.parts if q in fed and not parts[q].tasks)
        return tuple(dict.fromkeys(out))

    def depth(self) -> int:
        """Length (in tasks) of the longest chain of the effective task graph."""
        graph: dict[str, list[str]] = {t.id: [] for t in self.tasks}
        for tid, ps in self._pred.items():
            for q in ps:
                graph[q].append(tid)
        return int(max(longest_path_lengths(graph).values()))

    def capabilities(self) -> frozenset[str]:
        """Every capability some task requires."""
        out: set[str] = set()
        for t in self.tasks:
            out |= t.required_capabilities
        return frozenset(out)

    def tools(self) -> tuple[str, ...]:
        """Tools used by the tasks, sorted."""
        return tuple(sorted({t.tool for t in self.tasks if t.tool is not None}))

    def sample_arrivals(self, seed: Seed = 0) -> tuple[PartArrival, ...]:
        """One draw of every feeder's arrivals, sorted by time (one seed for all feeders)."""
        rng = as_rng(seed)
        out: list[PartArrival] = []
        for f in self.feeders:
            out.extend(f.sample(rng))
        out.sort(key=lambda a: (a.time, a.part))
        return tuple(out)

    def expected_arrivals(self) -> dict[str, float]:
        """Every fed part's expected arrival time (seconds), by part id
        (see :meth:`tasklib.arrivals.Feeder.expected`)."""
        out: dict[str, float] = {}
        for f in self.feeders:
            out.update(f.expected())
        return out

    def summary(self) -> dict[str, Any]:
        """Counts for a quick look: tasks, parts, feeders, groups, steps,
        prerequisite depth, trajectories, waypoints, capabilities, tools."""
        return {
            "name": self.name,
            "tasks": len(self.tasks),
            "steps": sum(len(t.steps) for t in self.tasks),
            "parts": len(self.parts),
            "feeders": len(self.feeders),
            "part_groups": len(self.groups),
            "depth": self.depth(),
            "trajectories": len(self.trajectories),
            "waypoints": sum(t.n_points for t in self.trajectories.trajectories),
            "capabilities": sorted(self.capabilities()),
            "tools": list(self.tools()),
        }
