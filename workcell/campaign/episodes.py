"""One episode of a fault campaign: drawn from a seed, simulated, checked.

An *episode* is a cell, a seed and an index: from them (and nothing else) it
draws a fault plan of 1-4 records over every fault kind the simulator knows
(:mod:`workcell.sim.harness.faults`), a medium (:data:`workcell.sim.comms.MEDIA`),
a coordination policy (:data:`COORDINATIONS`) and re-solving on or off
(:func:`draw_episode`). Fault
times are uniform over the plan, or exactly at, or a hair
(:data:`HAIRS`) before or after, a planned task start or end. Each cell is
compiled once and planned once per process (:func:`prepare`: the tree
search on a work limit, so the plan is the same on every machine).

:func:`run_episode` simulates the episode and checks it (:func:`check_result`):

* ``exception`` -- :func:`workcell.simulate` raised (type and message);
* ``safety`` -- the safety monitor raised
  :class:`~workcell.sim.harness.monitor.SafetyViolation`;
* ``unexplained_failure`` -- a failed task whose cause is empty, the fallback
  "not completed when the simulation ended", a stall, or a deadlock named
  without its wait-for cycle;
* ``not_done`` -- a failed task (with a cause) that a surviving arm can do
  (:func:`required_tasks`; the distributed policy never re-solves, so its
  episodes are judged as with re-solving off, :func:`replans`);
* ``release`` -- a done task started before a part gating it arrived (its
  expected arrival plus any delay) or before its release;
* ``precedence`` -- a done task started before a predecessor ended, or ran
  although a predecessor did not;
* ``replay`` -- the episode, run again, gave another trace or tasks frame
  (a share :data:`REPLAY_SHARE` of the episodes, chosen by the seed).

Every finding replays with one command, :meth:`Episode.command`.

Examples
--------
>>> Finding("not_done", "task 'screw' failed (arm 'left' failed) although 'right' can do it")
Finding(kind='not_done', detail="task 'screw' failed (arm 'left' failed) although 'right' can do it", task='')
"""

from __future__ import annotations

import json
import math
import time
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from multiarm.errors import UsageError
from workcell.sim.harness.faults import (
    ActivateZones,
    ArmFailure,
    Crash,
    EmergencyStop,
    Fault,
    FaultPlan,
    LatePart,
    LostSync,
    MessageLoss,
)

if TYPE_CHECKING:
    from scheduler import Schedule
    from workcell.compile import CompiledCell
    from workcell.sim.harness.simulate import SimResult

__all__ = [
    "COORDINATIONS",
    "FAULT_KINDS",
    "FINDING_KINDS",
    "HAIRS",
    "PLAN_EVALUATIONS",
    "REPLAY_SHARE",
    "TOLERANCE",
    "CampaignCell",
    "Episode",
    "EpisodeResult",
    "Finding",
    "check_result",
    "check_tasks",
    "draw_episode",
    "prepare",
    "replans",
    "required_tasks",
    "run_episode",
    "simulate_episode",
]

FAULT_KINDS: tuple[str, ...] = (
    "arm_failure",
    "crash",
    "lost_sync",
    "message_loss",
    "late_part",
    "emergency_stop",
    "activate_zones",
)
"""Every fault kind the simulator knows (:mod:`workcell.sim.harness.faults`)."""

COORDINATIONS: tuple[str, ...] = ("centralized", "distributed")
"""The coordination policies an episode can draw: S2.7's central coordinator
and its last sentence's distributed peers
(:data:`workcell.sim.harness.options.COORDINATION_POLICIES`)."""

FINDING_KINDS: tuple[str, ...] = (
    "exception",
    "safety",
    "unexplained_failure",
    "not_done",
    "release",
    "precedence",
    "replay",
)
"""Every kind of finding, in the order the checks run."""

HAIRS: tuple[float, ...] = (0.0, -1e-9, 1e-9, -1e-6, 1e-6)
"""Seconds added to a planned task start or end to place a fault exactly on
it or a hair before or after it."""

REPLAY_SHARE = 0.05
"""The share of episodes run twice and compared (chosen by the seed)."""

TOLERANCE = 1e-9
"""Seconds: how much earlier than its release or a predecessor's end a done
task may start (rounding of virtual time)."""

PLAN_EVALUATIONS = 300
"""The work limit of each cell's plan (schedules the tree search decodes)."""

FALLBACK_CAUSE = "not completed when the simulation ended"
"""The cause the simulator gives when it knows no reason."""


@dataclass(frozen=True, slots=True)
class CampaignCell:
    """A cell compiled and planned once, with the facts the draws and checks need.

    Attributes
    ----------
    name : str
        The built-in cell's name or the cell file's path, as given.
    compiled : CompiledCell
    schedule : scheduler.Schedule
        The plan every episode executes (tree search, seed 0, work-limited).
    tasks, arms : tuple of str
        Task and arm names in the problem's order.
    preds : tuple of tuple of int
        Each task's predecessors.
    capable : tuple of frozenset of str
        Each task's arms that have a mode for it.
    planned_arm : tuple of str
        Each task's arm in the plan.
    gating : tuple of tuple of str
        Each task's fed parts whose arrival it waits for.
    arrivals : tuple of (str, float)
        Every fed part's expected arrival (seconds).
    release : tuple of float
        Each task's release in the problem (seconds).
    parts : tuple of str
        Parts a :class:`~workcell.sim.harness.faults.LatePart` may name.
    steppers : tuple of (str, int)
        (arm, axis) of every stepper axis (:class:`~workcell.sim.harness.faults.LostSync`).
    zones : tuple of str
        The SDL zones (:class:`~workcell.sim.harness.faults.ActivateZones`).
    times : tuple of float
        Every distinct planned task start and end, sorted.
    """

    name: str
    compiled: CompiledCell
    schedule: Schedule
    tasks: tuple[str, ...]
    arms: tuple[str, ...]
    preds: tuple[tuple[int, ...], ...]
    capable: tuple[frozenset[str], ...]
    planned_arm: tuple[str, ...]
    gating: tuple[tuple[str, ...], ...]
    arrivals: tuple[tuple[str, float], ...]
    release: tuple[float, ...]
    parts: tuple[str, ...]
    steppers: tuple[tuple[str, int], ...]
    zones: tuple[str, ...]
    times: tuple[float, ...]

    @property
    def makespan(self) -> float:
        """The plan's makespan, seconds."""
        return float(self.schedule.makespan)


def _load(cell: str) -> Any:
    from workcell.cell import EXAMPLES, load_cell, load_example

    if cell in EXAMPLES:
        return load_example(cell)
    path = Path(cell)
    if path.is_file() and path.suffix.lower() == ".toml":
        return load_cell(path)
    raise UsageError(
        f"campaign: unknown cell {cell!r}: not a built-in cell ({', '.join(EXAMPLES)}) "
        "nor a .toml cell file"
    )


@lru_cache(maxsize=8)
def prepare(cell: str, evaluations: int = PLAN_EVALUATIONS) -> CampaignCell:
    """Compile ``cell`` and plan it (once per process; cached).

    Parameters
    ----------
    cell : str
        A built-in cell's name or a ``.toml`` cell file.
    evaluations : int
        The plan's work limit (tree search, seed 0): the same plan anywhere.

    Returns
    -------
    CampaignCell

    Raises
    ------
    UsageError
        An unknown cell.
    NoFeasibleSchedule
        The solver found no plan.
    """
    from workcell.arms.profiles import StepperDrive
    from workcell.pipeline import solve_cell

    # the compile and solve steps of run_cell, on the work limit alone (no clock)
    solved = solve_cell(_load(cell), solver="tree", time_limit=None, evaluations=evaluations)
    cc, p, s = solved.compiled, solved.problem, solved.schedule
    ts = cc.cell.taskset
    arrivals = ts.expected_arrivals()
    arms = tuple(str(a) for a in p.arm_names)
    return CampaignCell(
        name=cell,
        compiled=cc,
        schedule=s,
        tasks=tuple(str(t) for t in p.task_names),
        arms=arms,
        preds=tuple(tuple(int(q) for q in ps) for ps in p.task_preds),
        capable=tuple(
            frozenset(arms[int(p.mode_arm[m])] for m in p.task_modes[t]) for t in range(p.n_tasks)
        ),
        planned_arm=tuple(arms[int(p.mode_arm[int(m)])] for m in s.mode),
        gating=tuple(tuple(ts.gating_parts(task.id)) for task in ts.tasks),
        arrivals=tuple(sorted((k, float(v)) for k, v in arrivals.items())),
        release=tuple(float(x) for x in p.task_release),
        parts=tuple(sorted(set(arrivals) | {x.id for x in ts.parts})),
        steppers=tuple(
            (arm.name, j)
            for arm in cc.cell.arms
            for j, d in enumerate(arm.drives)
            if isinstance(d, StepperDrive)
        ),
        zones=tuple(sorted(cc.cell.zone_map.zone_names())),
        times=tuple(sorted({float(x) for x in (*s.start, *s.end)})),
    )


@dataclass(frozen=True, slots=True)
class Episode:
    """One drawn episode (everything :func:`simulate_episode` needs besides the cell).

    Attributes
    ----------
    cell : str
    seed : int
        The campaign's seed.
    index : int
        The episode's number within the campaign.
    medium : str
        One of :data:`workcell.sim.comms.MEDIA`.
    coordination : str
        One of :data:`COORDINATIONS`.
    resolve : bool
        Re-solving on or off.
    faults : FaultPlan
    sim_seed : int
        The simulation's seed (message loss draws).
    replay : bool
        Run twice and compare (:data:`REPLAY_SHARE` of the episodes).
    """

    cell: str
    seed: int
    index: int
    medium: str
    coordination: str
    resolve: bool
    faults: FaultPlan
    sim_seed: int
    replay: bool

    def command(self) -> str:
        """The one command that replays this episode and prints its findings."""
        return f"multiarm campaign {self.cell} --replay {self.seed}:{self.index}"

    def faults_json(self) -> str:
        """The fault plan as JSON (``multiarm simulate --faults`` reads it)."""
        return json.dumps(self.faults.to_dicts())


def _generator(cell: str, seed: int, index: int, stream: int = 0) -> np.random.Generator:
    key = zlib.crc32(Path(cell).name.encode())
    entropy = [int(seed), int(index), key] + ([stream] if stream else [])
    return np.random.default_rng(np.random.SeedSequence(entropy))


def _time(cc: CampaignCell, rng: np.random.Generator) -> float:
    """Uniform over the plan, or on a planned task start or end, or a hair off it."""
    if rng.random() < 0.5 or not cc.times:
        return float(rng.uniform(0.0, max(cc.makespan, 1e-3)))
    t = cc.times[int(rng.integers(len(cc.times)))]
    return max(0.0, t + HAIRS[int(rng.integers(len(HAIRS)))])


def _fault(
    cc: CampaignCell, kind: str, rng: np.random.Generator, failed: set[str], late: set[str]
) -> Fault | None:
    """One record of ``kind`` (None when the cell or the plan so far allow none)."""
    if kind == "arm_failure":
        left = [a for a in cc.arms if a not in failed]
        if not left:
            return None
        arm = left[int(rng.integers(len(left)))]
        failed.add(arm)
        return ArmFailure(arm, _time(cc, rng))
    if kind == "crash":
        arm = cc.arms[int(rng.integers(len(cc.arms)))]
        # mostly the default 50 N (above every threshold), sometimes a weak push
        force = 50.0 if rng.random() < 0.8 else float(rng.uniform(0.0, 10.0))
        return Crash(arm, _time(cc, rng), float(rng.uniform(0.1, 2.0)), force)
    if kind == "lost_sync":
        if not cc.steppers:
            return None
        arm, axis = cc.steppers[int(rng.integers(len(cc.steppers)))]
        return LostSync(arm, axis, _time(cc, rng), int(rng.integers(1, 201)))
    if kind == "message_loss":
        return MessageLoss(float(rng.uniform(0.01, 0.3)))
    if kind == "late_part":
        fed = [x for x, _ in cc.arrivals if x not in late] or [x for x in cc.parts if x not in late]
        if not fed:
            return None
        part = fed[int(rng.integers(len(fed)))]
        late.add(part)
        if rng.random() < 0.2:
            return LatePart(part, math.inf)
        expected = dict(cc.arrivals).get(part, 0.0)
        # arrive on (or a hair off) a planned start or end when that is after the expected time
        delay = _time(cc, rng) - expected
        if delay <= 0.0:
            delay = float(rng.uniform(1e-3, max(cc.makespan, 1e-3)))
        return LatePart(part, delay)
    if kind == "emergency_stop":
        return EmergencyStop(_time(cc, rng), float(rng.uniform(0.05, 2.0)))
    if kind == "activate_zones":
        zones = tuple(z for z in cc.zones if rng.random() < 0.5)
        return ActivateZones(_time(cc, rng), zones)
    raise UsageError(f"campaign: unknown fault kind {kind!r}")  # pragma: no cover


def draw_episode(
    cc: CampaignCell,
    seed: int,
    index: int,
    *,
    media: Sequence[str] | None = None,
    coordinations: Sequence[str] = COORDINATIONS,
) -> Episode:
    """Draw episode ``index`` of the campaign ``seed`` on ``cc`` (module docstring).

    Parameters
    ----------
    cc : CampaignCell
    seed, index : int
        Together with the cell's name they decide every draw.
    media : sequence of str, optional
        The media to draw from (default: every one of
        :data:`workcell.sim.comms.MEDIA`).
    coordinations : sequence of str
        The coordination policies to draw from.

    Returns
    -------
    Episode

    Raises
    ------
    UsageError
        A negative seed or index, an unknown medium or policy.
    """
    from workcell.sim.comms import MEDIA

    for name, v in (("seed", seed), ("index", index)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise UsageError(f"campaign: {name} must be an integer >= 0, got {v!r}")
    media = tuple(MEDIA if media is None else media)
    for m in media:
        if m not in MEDIA:
            raise UsageError(f"campaign: unknown medium {m!r} (known: {', '.join(MEDIA)})")
    for c in coordinations:
        if c not in COORDINATIONS:
            raise UsageError(
                f"campaign: unknown coordination {c!r} (known: {', '.join(COORDINATIONS)})"
            )
    if not media or not coordinations:
        raise UsageError("campaign: needs at least one medium and one coordination policy")
    rng = _generator(cc.name, seed, index)
    replay = bool(rng.random() < REPLAY_SHARE)
    medium = str(media[int(rng.integers(len(media)))])
    # the policy from a stream of its own: every other draw of an episode is the
    # same whichever policies it may draw from
    pick = _generator(cc.name, seed, index, stream=1)
    coordination = str(coordinations[int(pick.integers(len(coordinations)))])
    resolve = bool(rng.random() < 0.5)
    sim_seed = int(rng.integers(2**31))
    failed: set[str] = set()
    late: set[str] = set()
    out: list[Fault] = []
    lossy = False
    n = int(rng.integers(1, 5))
    while len(out) < n:
        kind = FAULT_KINDS[int(rng.integers(len(FAULT_KINDS)))]
        if kind == "message_loss" and lossy:
            continue  # at most one message_loss record
        f = _fault(cc, kind, rng, failed, late)
        if f is None:
            continue
        lossy = lossy or kind == "message_loss"
        out.append(f)
    return Episode(
        cc.name, seed, index, medium, coordination, resolve, FaultPlan(out), sim_seed, replay
    )


def simulate_episode(cc: CampaignCell, episode: Episode) -> SimResult:
    """Run ``episode`` through :func:`workcell.simulate` (the campaign's only call of it).

    Parameters
    ----------
    cc : CampaignCell
    episode : Episode

    Returns
    -------
    SimResult
    """
    from workcell.sim.harness.options import SimOptions
    from workcell.sim.harness.simulate import simulate

    return simulate(
        cc.compiled,
        cc.schedule,
        seed=episode.sim_seed,
        faults=episode.faults,
        medium=episode.medium,
        coordination=episode.coordination,
        options=SimOptions(resolve=episode.resolve),
    )


@dataclass(frozen=True, slots=True)
class Finding:
    """Something an episode got wrong.

    Attributes
    ----------
    kind : str
        One of :data:`FINDING_KINDS`.
    detail : str
        What was seen (the task, the cause, the times).
    task : str
        The task concerned ("" for none).
    """

    kind: str
    detail: str
    task: str = ""

    def __post_init__(self) -> None:
        if self.kind not in FINDING_KINDS:
            raise UsageError(
                f"Finding.kind: unknown kind {self.kind!r} (known: {', '.join(FINDING_KINDS)})"
            )


def replans(episode: Episode) -> bool:
    """Whether the run of ``episode`` may re-solve after a fault.

    Re-solving on under the centralized coordinator; never under the
    distributed policy, which keeps the plan whatever ``SimOptions.resolve``
    says (docs/simulation.md, "Distributed coordination"): there a failed
    arm's unfinished tasks and the tasks after them fail, as the centralized
    coordinator fails them with re-solving off.
    """
    return episode.resolve and episode.coordination == "centralized"


def required_tasks(cc: CampaignCell, faults: FaultPlan, resolve: bool) -> tuple[bool, ...]:
    """Which tasks a surviving arm can do, so that the run must do them.

    A task is required when (re-solving on) some arm that never fails in
    ``faults`` has a mode for it, or (re-solving off) its planned arm never
    fails; and every part gating it arrives (a late part with a finite delay
    arrives); and every predecessor is required by the same rule. An arm
    counts as failing whatever the time of its :class:`ArmFailure`.
    Insertions are the planned ones, which never fail.

    Parameters
    ----------
    cc : CampaignCell
    faults : FaultPlan
    resolve : bool

    Returns
    -------
    tuple of bool
        One per task, in the problem's order.
    """
    failed = {f.arm for f in faults if isinstance(f, ArmFailure)}
    never = {f.part for f in faults if isinstance(f, LatePart) and math.isinf(f.delay)}
    memo: dict[int, bool] = {}

    def req(t: int) -> bool:
        if t in memo:
            return memo[t]
        memo[t] = False  # a cycle (none in a valid problem) requires nothing
        ok = bool(cc.capable[t] - failed) if resolve else cc.planned_arm[t] not in failed
        ok = ok and not (set(cc.gating[t]) & never) and all(req(q) for q in cc.preds[t])
        memo[t] = ok
        return ok

    return tuple(req(t) for t in range(len(cc.tasks)))


def _unexplained(cause: str) -> bool:
    c = cause.strip().lower()
    if not c or FALLBACK_CAUSE in c:
        return True
    # a stall is a liveness bug by definition; a deadlock is explained by its wait-for cycle
    return "stall" in c or ("deadlock" in c and "cycle" not in c)


def check_tasks(
    cc: CampaignCell, faults: FaultPlan, resolve: bool, frame: Any
) -> tuple[Finding, ...]:
    """The task checks of an episode on its tasks frame (:meth:`SimResult.tasks_frame`).

    Unexplained failures, required tasks not done (:func:`required_tasks`),
    releases and precedences (module docstring); a failed task gives at most
    one finding (unexplained first).

    Parameters
    ----------
    cc : CampaignCell
    faults : FaultPlan
    resolve : bool
    frame : pandas.DataFrame
        Columns ``task``, ``arm``, ``start``, ``end``, ``status``, ``cause``,
        one row per task of ``cc``.

    Returns
    -------
    tuple of Finding

    Raises
    ------
    UsageError
        A frame that does not name every task of the cell once.
    """
    rows = frame.to_dict("records")
    by_task = {str(r["task"]): r for r in rows}
    if len(rows) != len(cc.tasks) or set(by_task) != set(cc.tasks):
        raise UsageError(
            f"campaign: the tasks frame has {len(rows)} rows for the {len(cc.tasks)} tasks "
            f"of cell {cc.name!r}"
        )
    required = required_tasks(cc, faults, resolve)
    arrival = dict(cc.arrivals)
    for f in faults:
        if isinstance(f, LatePart):
            arrival[f.part] = arrival.get(f.part, 0.0) + f.delay
    out: list[Finding] = []
    for t, name in enumerate(cc.tasks):
        r = by_task[name]
        if r["status"] != "done":
            cause = "" if r["cause"] is None else str(r["cause"])
            if _unexplained(cause):
                out.append(
                    Finding(
                        "unexplained_failure",
                        f"task {name!r} (arm {r['arm']!r}) failed: {cause or '(no cause)'}",
                        name,
                    )
                )
            elif required[t]:
                out.append(
                    Finding(
                        "not_done",
                        f"task {name!r} failed ({cause}) although a surviving arm can do it",
                        name,
                    )
                )
            continue
        start = float(r["start"])
        gates = [(x, arrival.get(x, 0.0)) for x in cc.gating[t]]
        gates.append(("release", cc.release[t]))
        for what, at in gates:
            if start < at - TOLERANCE:
                out.append(
                    Finding(
                        "release",
                        f"task {name!r} started at {start!r} s, before "
                        + (
                            f"its release {at!r} s"
                            if what == "release"
                            else f"part {what!r} arrived at {at!r} s"
                        ),
                        name,
                    )
                )
        for q in cc.preds[t]:
            pr = by_task[cc.tasks[q]]
            if pr["status"] != "done":
                out.append(
                    Finding(
                        "precedence",
                        f"task {name!r} ran although its predecessor {cc.tasks[q]!r} did not",
                        name,
                    )
                )
            elif start < float(pr["end"]) - TOLERANCE:
                out.append(
                    Finding(
                        "precedence",
                        f"task {name!r} started at {start!r} s, before its predecessor "
                        f"{cc.tasks[q]!r} ended at {float(pr['end'])!r} s",
                        name,
                    )
                )
    return tuple(out)


def check_result(cc: CampaignCell, episode: Episode, result: SimResult) -> tuple[Finding, ...]:
    """Every check of a finished run but the replay (:func:`check_tasks`, with
    re-solving as the episode's policy does it, :func:`replans`)."""
    return check_tasks(cc, episode.faults, replans(episode), result.tasks_frame())


@dataclass(frozen=True, slots=True)
class EpisodeResult:
    """An episode, its findings and what the run measured.

    Attributes
    ----------
    episode : Episode
    findings : tuple of Finding
    executed_makespan : float
        Seconds (NaN when no task was done or the run raised; ``None`` in
        :meth:`row`, so no table holds NaN).
    done, failed : int
        Tasks done and failed (-1 when the run raised).
    wall_time : float
        Seconds of wall clock for the episode (and its replay).
    """

    episode: Episode
    findings: tuple[Finding, ...]
    executed_makespan: float
    done: int
    failed: int
    wall_time: float

    @property
    def outcome(self) -> str:
        """``"ok"`` or ``"finding"``."""
        return "finding" if self.findings else "ok"

    def row(self) -> dict[str, Any]:
        """One row of the episodes table (plain data; faults and findings as JSON)."""
        e = self.episode
        return {
            "cell": e.cell,
            "seed": e.seed,
            "episode": e.index,
            "medium": e.medium,
            "coordination": e.coordination,
            "resolve": e.resolve,
            "sim_seed": e.sim_seed,
            "n_faults": len(e.faults),
            "fault_kinds": ",".join(f.kind for f in e.faults),
            "faults": e.faults_json(),
            "replayed": e.replay,
            "outcome": self.outcome,
            "finding_kinds": ",".join(sorted({f.kind for f in self.findings})),
            "findings": json.dumps([[f.kind, f.task, f.detail] for f in self.findings]),
            "executed_makespan": (
                self.executed_makespan if math.isfinite(self.executed_makespan) else None
            ),
            "done": self.done,
            "failed": self.failed,
            "wall_time": self.wall_time,
            "command": e.command(),
        }

    @staticmethod
    def findings_of(row: Mapping[str, Any]) -> tuple[Finding, ...]:
        """The findings of a table row (inverse of the ``findings`` column)."""
        return tuple(Finding(k, d, t) for k, t, d in json.loads(str(row["findings"])))


def _same(a: SimResult, b: SimResult) -> str:
    """ "" when two runs agree exactly, else what differs."""
    ta, tb = a.trace.to_json(), b.trace.to_json()
    if ta != tb:
        ea, eb = a.trace.to_records(), b.trace.to_records()
        i = next((i for i, (x, y) in enumerate(zip(ea, eb, strict=False)) if x != y), None)
        where = f"first at event {i}" if i is not None else f"{len(ea)} vs {len(eb)} events"
        return f"the trace differs on replay ({where})"
    if not a.tasks_frame().equals(b.tasks_frame()):
        return "the tasks frame differs on replay"
    return ""


def run_episode(cc: CampaignCell, episode: Episode) -> EpisodeResult:
    """Simulate ``episode`` (twice when drawn for replay) and check it.

    Never raises for the run's own failures: an exception is a finding.

    Parameters
    ----------
    cc : CampaignCell
    episode : Episode

    Returns
    -------
    EpisodeResult
    """
    from workcell.sim.harness.monitor import SafetyViolation

    t0 = time.perf_counter()
    findings: list[Finding] = []
    mk, done, failed = math.nan, -1, -1
    try:
        result = simulate_episode(cc, episode)
    except SafetyViolation as exc:
        findings.append(Finding("safety", f"SafetyViolation: {exc}"))
    except Exception as exc:  # every exception is a finding, never lost
        findings.append(Finding("exception", f"{type(exc).__name__}: {exc}"))
    else:
        mk = float(result.metrics.executed_makespan)
        done, failed = int(result.metrics.done_tasks), int(result.metrics.failed_tasks)
        findings += check_result(cc, episode, result)
        if episode.replay:
            try:
                again = simulate_episode(cc, episode)
            except Exception as exc:
                findings.append(Finding("replay", f"the replay raised {type(exc).__name__}: {exc}"))
            else:
                diff = _same(result, again)
                if diff:
                    findings.append(Finding("replay", diff))
    return EpisodeResult(episode, tuple(findings), mk, done, failed, time.perf_counter() - t0)
