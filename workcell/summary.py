"""Figures of a plan and of a run, as rows a table can print.

:func:`run_summary` is the planned-against-executed table of ``multiarm
simulate`` and ``multiarm demo``: makespan, utilisation per arm, zone waits
(by SDL zone first, then tools, then the space grid as one row with its
worst block's coordinates, :func:`workcell.viz.waits.wait_summary`), sleeps
and wakes, detours, insertion tries (S1.7), re-solves and their latency,
messages, retransmissions, failed tasks. :func:`arm_usage` and
:func:`zone_usage` summarise a schedule per arm and per zone.

The rows are data (strings already formatted); the command line prints them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from scheduler import Problem, Schedule
from workcell.compile import CompiledCell
from workcell.sim.harness.simulate import SimResult

__all__ = [
    "ArmUsage",
    "SummaryRow",
    "ZoneUsage",
    "arm_usage",
    "insertion_tries",
    "run_summary",
    "side_by_side",
    "zone_usage",
]


@dataclass(frozen=True, slots=True)
class SummaryRow:
    """One row of a run's summary: a metric, its planned and its executed value (text).

    ``metric`` of a row that details the row above starts with two spaces.
    """

    metric: str
    planned: str
    executed: str


@dataclass(frozen=True, slots=True)
class ArmUsage:
    """One arm in a schedule: its kind, tasks and busy time (seconds)."""

    arm: str
    kind: str
    tasks: int
    busy: float
    utilisation: float

    COLUMNS: ClassVar[tuple[str, ...]] = ("arm", "type", "tasks", "busy (s)", "utilisation")
    """The columns of :meth:`row`."""

    def row(self) -> dict[str, str]:
        """The record as one row of text (keys :attr:`COLUMNS`)."""
        return dict(
            zip(
                self.COLUMNS,
                (
                    self.arm,
                    self.kind,
                    str(self.tasks),
                    f"{self.busy:.1f}",
                    f"{self.utilisation:.0%}",
                ),
                strict=True,
            )
        )


@dataclass(frozen=True, slots=True)
class ZoneUsage:
    """One SDL zone (or the whole space grid) in a schedule.

    Attributes
    ----------
    zone : str
        The zone's name, or ``"space grid (N blocks)"``.
    exclusive : bool
    uses : int
        Reservations (occupancies of an exclusive zone, moves in a shared one).
    held : float
        Seconds occupied (exclusive) or moved in (shared), summed.
    """

    zone: str
    exclusive: bool
    uses: int
    held: float

    COLUMNS: ClassVar[tuple[str, ...]] = ("zone", "policy", "uses", "occupied or moved in (s)")
    """The columns of :meth:`row`."""

    def row(self) -> dict[str, str]:
        """The record as one row of text (keys :attr:`COLUMNS`)."""
        policy = "exclusive" if self.exclusive else "shared"
        values = (self.zone, policy, str(self.uses), f"{self.held:.1f}")
        return dict(zip(self.COLUMNS, values, strict=True))


def _ms(values: object, q: float) -> str:
    arr = np.asarray(values, dtype=float)
    return f"{float(np.percentile(arr, q)) * 1e3:.2f}" if arr.size else "-"


def insertion_tries(compiled: CompiledCell, schedule: Schedule, sim: SimResult) -> tuple[int, int]:
    """Force-guided insertion tries (S1.7): planned by the schedule, and made in the run.

    Planned: the tries the compiled dwells of the schedule's modes hold.
    Made: with tries drawn at run time (``SimOptions(insertion="drawn")``),
    one per force reading in the trace; with planned tries, those of the
    tasks done.

    Returns
    -------
    (int, int)
        Planned, made.
    """
    from workcell.sim.control.force import insert_searches

    searches = insert_searches(compiled, 0)
    per_mode = {m: sum(s.planned for s in ss) for m, ss in searches.items()}
    planned = sum(per_mode.get(int(m), 0) for m in schedule.mode)
    readings = sum(
        1 for e in sim.trace if e.kind == "force" and str(e.detail).startswith("read force")
    )
    if readings:
        return planned, readings
    tasks = sim.tasks_frame()
    done = tasks[tasks["status"] == "done"]
    return planned, sum(per_mode.get(int(m), 0) for m in done["mode"])


def run_summary(
    compiled: CompiledCell, schedule: Schedule, sim: SimResult
) -> tuple[SummaryRow, ...]:
    """The planned-against-executed table of one run (module docstring).

    Parameters
    ----------
    compiled : CompiledCell
    schedule : scheduler.Schedule
        The plan simulated.
    sim : SimResult

    Returns
    -------
    tuple of SummaryRow
    """
    from workcell.viz.waits import wait_summary

    problem = compiled.problem
    m = sim.metrics
    arms = schedule.arms(problem)
    planned_mk = float(m.planned_makespan)
    executed_mk = float(m.executed_makespan)
    rows = [
        SummaryRow(
            "makespan (s)",
            f"{planned_mk:.2f}",
            f"{executed_mk:.2f}" if np.isfinite(executed_mk) else "none (no task done)",
        )
    ]
    for a, name in enumerate(problem.arm_names):
        busy = float(np.sum((schedule.end - schedule.start)[arms == a]))
        rows.append(
            SummaryRow(
                f"utilisation {name}",
                f"{busy / planned_mk:.0%}" if planned_mk > 0 else "-",
                f"{float(m.utilisation.get(name, 0.0)):.0%}",
            )
        )
    rows.append(
        SummaryRow("zone waits (s)", f"{schedule.total_wait():.2f}", f"{m.border_wait:.2f}")
    )
    for w in wait_summary(sim, compiled):
        if w.kind == "grid":
            lo, hi = w.worst_bounds or ((0.0,) * 3, (0.0,) * 3)
            where = ", ".join(
                f"{c} {a:.2f}..{b:.2f}" for c, a, b in zip("xyz", lo, hi, strict=True)
            )
            text = f"{w.seconds:.2f} at {w.worst} ({where} m)"
            rows.append(SummaryRow(f"  {w.label}", "", text))
        else:
            label = f"tool {w.label}" if w.kind == "tool" else w.label
            rows.append(SummaryRow(f"  {label}", "", f"{w.seconds:.2f}"))
    planned_tries, made = insertion_tries(compiled, schedule, sim)
    delays = np.asarray(m.message_delay, dtype=float)
    latency = np.asarray(m.resolve_latency, dtype=float)
    rows += [
        SummaryRow("sleeps / wakes", "", f"{m.sleeps} / {m.wakes}"),
        SummaryRow("detours", "", str(m.detours)),
        SummaryRow("insertion tries", str(planned_tries), str(made)),
        SummaryRow("re-solves", "", str(m.resolves)),
        SummaryRow(
            "re-solve latency p50 / p99 (ms)", "", f"{_ms(latency, 50)} / {_ms(latency, 99)}"
        ),
        SummaryRow(
            "re-solves over budget",
            "",
            f"{int(np.sum(latency > m.resolve_budget))} (budget {m.resolve_budget * 1e3:g} ms)",
        ),
        SummaryRow(
            "messages; delay mean / p99 (ms)",
            "",
            f"{m.messages}; {float(delays.mean()) * 1e3:.3f} / {_ms(delays, 99)}"
            if delays.size
            else f"{m.messages}; -",
        ),
        SummaryRow("retransmissions", "", str(m.retransmissions)),
        SummaryRow("failed tasks", "", str(int(m.failed_tasks))),
    ]
    return tuple(rows)


def arm_usage(compiled: CompiledCell, schedule: Schedule) -> tuple[ArmUsage, ...]:
    """Per arm of the cell: kind, tasks in ``schedule``, busy seconds, share of the makespan."""
    p = compiled.problem
    arm_of = schedule.arms(p)
    mk = float(schedule.makespan)
    out = []
    for a, name in enumerate(p.arm_names):
        tasks = [t for t in range(p.n_tasks) if int(arm_of[t]) == a]
        busy = sum(float(schedule.end[t] - schedule.start[t]) for t in tasks)
        kind = compiled.cell.arms[a].kind
        out.append(ArmUsage(str(name), kind, len(tasks), busy, busy / mk if mk > 0 else 0.0))
    return tuple(out)


def zone_usage(problem: Problem, schedule: Schedule) -> tuple[ZoneUsage, ...]:
    """Per SDL zone, then one row for all space-grid blocks: reservations and time held."""
    from workcell.viz.waits import grid_block, grid_lane_label

    reservations = schedule.reservations(problem)
    out = []
    grid = [z for z in problem.zone_names if grid_block(z) is not None]
    for z, name in enumerate(problem.zone_names):
        if grid_block(name) is not None:
            continue
        exclusive = bool(problem.zone_exclusive[z])
        kind = "zone" if exclusive else "move"
        res = [r for r in reservations if r.kind == kind and r.resource == name]
        out.append(ZoneUsage(str(name), exclusive, len(res), sum(r.end - r.start for r in res)))
    if grid:
        res = [r for r in reservations if r.kind == "zone" and grid_block(r.resource) is not None]
        out.append(
            ZoneUsage(grid_lane_label(len(grid)), True, len(res), sum(r.end - r.start for r in res))
        )
    return tuple(out)


def side_by_side(columns: Mapping[str, Sequence[SummaryRow]]) -> list[dict[str, str]]:
    """Summaries of several runs of one plan as one table.

    Parameters
    ----------
    columns : mapping of str to rows
        Column title -> :func:`run_summary` of one run of the same plan.

    Returns
    -------
    list of dict
        One row a metric, keys ``metric``, ``planned`` and the column titles
        (``""`` where a run has no such row). A detail row (its metric
        indented) stays under its metric, whichever run it came from.
    """
    merged: dict[str, dict[str, str]] = {}
    details: dict[str, list[str]] = {}
    for col, rows in columns.items():
        last = ""
        for r in rows:
            if not r.metric.startswith("  "):
                last = r.metric
            elif r.metric not in merged:
                details.setdefault(last, []).append(r.metric)
            entry = merged.setdefault(
                r.metric, {"metric": r.metric, "planned": r.planned, **dict.fromkeys(columns, "")}
            )
            entry[col] = r.executed
    table = []
    for name, entry in merged.items():
        if not name.startswith("  "):
            table.append(entry)
            table += [merged[d] for d in details.get(name, [])]
    return table
