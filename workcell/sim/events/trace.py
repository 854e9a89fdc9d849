"""Traces and metrics of a simulated run (records, pandas and JSON views).

A :class:`Trace` is the ordered list of everything that happened in a run:
every message on the medium (and the arm controllers' internal S2.3
messages), zone grants, sleeps and wakes, motion segments, faults, detours,
re-solves, task starts and ends, zone entries and exits, safety-monitor
findings, and the wrist force sensors' thresholds and readings during an
insertion search (``"force"``). Each record is a :class:`TraceEvent` with the same fields, so the
whole trace is one table (:meth:`Trace.to_dataframe`).

:class:`Metrics` summarises a run: planned against executed makespan,
per-arm utilisation, zone waits, sleeps and wakes, detours, re-solves and
their wall-clock latency, message delays and failed tasks.

Examples
--------
>>> tr = Trace()
>>> tr.add(0.5, "task_start", arm="left", task="pick")
>>> tr.add(1.5, "task_end", arm="left", task="pick")
>>> len(tr), tr[1].kind
(2, 'task_end')
>>> list(tr.to_dataframe()["time"])
[0.5, 1.5]
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray

__all__ = ["KINDS", "Metrics", "Trace", "TraceEvent"]

KINDS: tuple[str, ...] = (
    "message",
    "grant",
    "sleep",
    "wake",
    "segment",
    "fault",
    "detour",
    "resolve",
    "task_start",
    "task_end",
    "task_failed",
    "zone_enter",
    "zone_leave",
    "monitor",
    "force",
    "drop",
)
"""Every kind of trace record (``"force"``: the wrist force sensor's
thresholds set and forces read during an insertion search, S1.7, with
``SimOptions(insertion="drawn")``; :mod:`workcell.sim.control.force`;
``"drop"``: a frame dropped at its receiver, a duplicate or older than the
withdrawal of its task, by the links' sequence numbers)."""

COLUMNS: tuple[str, ...] = (
    "time",
    "kind",
    "arm",
    "task",
    "zone",
    "message",
    "src",
    "dst",
    "size",
    "delay",
    "detail",
)
"""Columns of :meth:`Trace.to_dataframe`, in order."""


@dataclass(frozen=True, slots=True)
class TraceEvent:
    """One record of a trace.

    Attributes
    ----------
    time : float
        Virtual time, seconds.
    kind : str
        One of :data:`KINDS`.
    arm, task, zone : str
        Names, ``""`` when not applicable.
    message : str
        Message type (``"trajectory"``, ``"zone_request"``, ... or an S2.3
        internal message such as ``"TRAJECTORY_POINT"``), ``""`` otherwise.
    src, dst : int
        Stations of a message (0 = coordinator, 1..N = arms; -1: broadcast
        or not a message).
    size : int
        Bytes of a message (0 otherwise).
    delay : float
        Seconds: a message's delay on the medium, a wait's or a segment's
        length (0 otherwise).
    detail : str
        Free text (the cause of a fault, the answer to a request, ...).
    """

    time: float
    kind: str
    arm: str = ""
    task: str = ""
    zone: str = ""
    message: str = ""
    src: int = -1
    dst: int = -1
    size: int = 0
    delay: float = 0.0
    detail: str = ""


def _values(e: TraceEvent) -> tuple[Any, ...]:
    """The fields of a record, in the order of :data:`COLUMNS` (all scalars: a
    plain tuple, which ``dataclasses.asdict``'s deep copy only slowed: 7 s of
    writing a ``cell8`` run's 87,000 records)."""
    return (
        e.time,
        e.kind,
        e.arm,
        e.task,
        e.zone,
        e.message,
        e.src,
        e.dst,
        e.size,
        e.delay,
        e.detail,
    )


def _jsonable(x: float) -> float | str:
    if math.isfinite(x):
        return x
    return "inf" if x > 0 else ("-inf" if x < 0 else "nan")


class _Described:
    """A detail text written when the trace is read: ``describe(payload)``
    (the hot paths record a frame's payload, a frozen record, and the text is
    made once, on the first read)."""

    __slots__ = ("describe", "payload")

    def __init__(self, describe: Callable[[Any], str], payload: Any) -> None:
        self.describe = describe
        self.payload = payload


_Row = tuple[float, str, str, str, str, str, int, int, int, float, "str | _Described"]


def _record(r: _Row) -> TraceEvent:
    """The :class:`TraceEvent` of a row (its detail written now if it is deferred)."""
    detail = r[10]
    text = detail if isinstance(detail, str) else str(detail.describe(detail.payload))
    return TraceEvent(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], text)


class Trace:
    """An ordered list of :class:`TraceEvent` (module docstring).

    Records are kept as plain rows while a run appends them (a hot path) and
    become :class:`TraceEvent` objects, each once, when the trace is first
    read."""

    __slots__ = ("_events", "_rows")

    def __init__(self, events: list[TraceEvent] | None = None) -> None:
        self._rows: list[_Row] = []
        self._events: list[TraceEvent] = list(events or [])

    def _settled(self) -> list[TraceEvent]:
        """Every record as a :class:`TraceEvent` (the rows appended since the
        last read made into records now)."""
        rows = self._rows
        if rows:
            out = self._events
            out.extend(map(_record, rows))
            rows.clear()
        return self._events

    def add(
        self,
        time: float,
        kind: str,
        *,
        arm: str = "",
        task: str = "",
        zone: str = "",
        message: str = "",
        src: int = -1,
        dst: int = -1,
        size: int = 0,
        delay: float = 0.0,
        detail: str = "",
    ) -> None:
        """Append one record (the arguments are :class:`TraceEvent`'s fields)."""
        self._rows.append(
            (float(time), kind, arm, task, zone, message, src, dst, size, delay, detail)
        )

    def row(
        self,
        time: float,
        kind: str,
        arm: str,
        task: str,
        zone: str,
        message: str,
        src: int,
        dst: int,
        size: int,
        delay: float,
        detail: str,
    ) -> None:
        """Append one record from all its fields, in :class:`TraceEvent`'s
        order (what :meth:`add` does, without keywords: for the hot paths)."""
        self._rows.append(
            (float(time), kind, arm, task, zone, message, src, dst, size, delay, detail)
        )

    def row_described(
        self,
        time: float,
        kind: str,
        arm: str,
        message: str,
        src: int,
        dst: int,
        size: int,
        delay: float,
        describe: Callable[[Any], str],
        payload: Any,
    ) -> None:
        """Append a message record whose detail is ``describe(payload)``,
        written when the trace is first read (``payload`` must not change:
        the frozen message records)."""
        self._rows.append(
            (
                float(time),
                kind,
                arm,
                "",
                "",
                message,
                src,
                dst,
                size,
                delay,
                _Described(describe, payload),
            )
        )

    def __len__(self) -> int:
        return len(self._events) + len(self._rows)

    def sort(self) -> None:
        """Order the records by time (stable: records of one instant keep
        the order they happened in)."""
        if self._events:
            self._settled().sort(key=lambda e: e.time)
        else:
            self._rows.sort(key=lambda r: r[0])

    def __iter__(self) -> Iterator[TraceEvent]:
        return iter(self._settled())

    def __getitem__(self, i: int) -> TraceEvent:
        return self._settled()[i]

    def of_kind(self, kind: str) -> list[TraceEvent]:
        """The records of one kind, in order."""
        return [e for e in self._settled() if e.kind == kind]

    def select(self, kinds: Collection[str]) -> list[TraceEvent]:
        """The records of the given kinds, in order (without making records
        of the rest)."""
        out = [e for e in self._events if e.kind in kinds]
        out.extend(_record(r) for r in self._rows if r[1] in kinds)
        return out

    def count(self, kind: str) -> int:
        """How many records are of ``kind`` (without making records of the rest)."""
        n = sum(1 for r in self._rows if r[1] == kind)
        return n + sum(1 for e in self._events if e.kind == kind)

    def to_records(self) -> list[dict[str, Any]]:
        """Plain dicts (JSON-ready; infinite times become strings)."""
        out = []
        for e in self._settled():
            d = dict(zip(COLUMNS, _values(e), strict=True))
            d["time"] = _jsonable(e.time)
            d["delay"] = _jsonable(e.delay)
            out.append(d)
        return out

    def to_dataframe(self) -> Any:
        """A pandas DataFrame with the columns of :data:`COLUMNS`."""
        import pandas as pd

        return pd.DataFrame([_values(e) for e in self._settled()], columns=list(COLUMNS))

    def to_json(self, path: str | PathLike[str] | None = None) -> str:
        """The trace as JSON text (``{"format": "multiarm.trace/1", "events": [...]}``),
        written to ``path`` when given."""
        text = json.dumps({"format": "multiarm.trace/1", "events": self.to_records()})
        if path is not None:
            Path(path).write_text(text)
        return text

    @classmethod
    def from_json(cls, text: str) -> Trace:
        """Inverse of :meth:`to_json`.

        Raises
        ------
        ValidationError
            For text that is not a trace.
        """
        try:
            data = json.loads(text)
            events = [
                TraceEvent(
                    **{**d, "time": float(d["time"]), "delay": float(d["delay"])}  # "inf" ok
                )
                for d in data["events"]
            ]
        except (ValueError, KeyError, TypeError) as exc:
            raise ValidationError(f"not a multiarm trace: {exc}") from None
        return cls(events)


@dataclass
class Metrics:
    """Summary figures of a run (module docstring).

    Attributes
    ----------
    planned_makespan, executed_makespan : float
        Seconds (executed: the last end of a task done; missing, NaN, when no
        task was done: ``null`` in :meth:`to_dict`, see :attr:`done_tasks`).
    utilisation : dict of str to float
        Per arm, busy time / executed makespan, in [0, 1]: the time within
        ``[0, executed_makespan]`` the arm spent on a leg (travelling to a
        task, working on it, or stopped on the way: at a border, by an
        alarm); 0 when no task completed.
    zone_wait : dict of str to float
        Per zone (and tool), seconds arms spent stopped at a border where
        they entered it (a stop at a border where several zones are entered
        counts for each of them).
    border_wait : float
        Seconds arms spent stopped at zone borders in all, each stop once:
        comparable with the schedule's planned waits
        (:meth:`scheduler.Schedule.total_wait`).
    sleeps, wakes, detours, resolves : int
    resolve_latency : (n,) float
        Wall-clock seconds of each re-solve.
    resolve_budget : float
        The real-time budget of one re-solve, seconds.
    message_delay : (n,) float
        Seconds, one per delivered frame.
    messages : int
        Frames sent on the medium (retransmissions included).
    retransmissions : int
    stale_frames : int
        Frames dropped at their receiver by the links' sequence numbers: a
        duplicate, or a frame older than the withdrawal of its task.
    failed_tasks : int
    done_tasks : int
    ticks : int
        Controller ticks modelled (0 at event level).
    events : int
        EventLoop events run.
    wall_seconds : float
        Wall-clock time of the run.
    """

    planned_makespan: float = 0.0
    executed_makespan: float = math.nan
    utilisation: dict[str, float] = field(default_factory=dict)
    zone_wait: dict[str, float] = field(default_factory=dict)
    border_wait: float = 0.0
    sleeps: int = 0
    wakes: int = 0
    detours: int = 0
    resolves: int = 0
    resolve_latency: FloatArray = field(default_factory=lambda: np.zeros(0))
    resolve_budget: float = 0.015
    message_delay: FloatArray = field(default_factory=lambda: np.zeros(0))
    messages: int = 0
    retransmissions: int = 0
    stale_frames: int = 0
    failed_tasks: int = 0
    done_tasks: int = 0
    ticks: int = 0
    events: int = 0
    wall_seconds: float = 0.0

    def summary(self) -> dict[str, float | int]:
        """Scalar figures (dict name -> value): makespans, counts, latency and
        delay percentiles (p50/p99/max). A figure that does not exist (the
        executed makespan when no task was done, a percentile of no sample)
        is missing: NaN here, ``null`` in :meth:`to_dict` and the JSON."""

        def pct(a: FloatArray, q: float) -> float:
            return float(np.percentile(a, q)) if len(a) else math.nan

        return {
            "planned_makespan": self.planned_makespan,
            "executed_makespan": self.executed_makespan,
            "done_tasks": self.done_tasks,
            "failed_tasks": self.failed_tasks,
            "mean_utilisation": (
                float(np.mean(list(self.utilisation.values()))) if self.utilisation else math.nan
            ),
            "zone_wait": float(self.border_wait),
            "sleeps": self.sleeps,
            "wakes": self.wakes,
            "detours": self.detours,
            "resolves": self.resolves,
            "resolve_latency_p50": pct(self.resolve_latency, 50),
            "resolve_latency_p99": pct(self.resolve_latency, 99),
            "resolve_latency_max": float(self.resolve_latency.max())
            if len(self.resolve_latency)
            else math.nan,
            "resolves_over_budget": int(np.sum(self.resolve_latency > self.resolve_budget)),
            "messages": self.messages,
            "retransmissions": self.retransmissions,
            "stale_frames": self.stale_frames,
            "message_delay_mean": float(np.mean(self.message_delay))
            if len(self.message_delay)
            else math.nan,
            "message_delay_max": float(self.message_delay.max())
            if len(self.message_delay)
            else math.nan,
            "ticks": self.ticks,
            "events": self.events,
            "wall_seconds": self.wall_seconds,
        }

    def to_dataframe(self) -> Any:
        """Tidy pandas DataFrame: columns metric, key, value (per-arm and
        per-zone figures keyed by name; arrays one row per element, keyed by index)."""
        import pandas as pd

        rows: list[tuple[str, str, float]] = []
        for k, v in self.summary().items():
            rows.append((k, "", float(v)))
        for a, v in self.utilisation.items():
            rows.append(("utilisation", a, v))
        for z, v in self.zone_wait.items():
            rows.append(("zone_wait", z, v))
        for i, v in enumerate(self.resolve_latency.tolist()):
            rows.append(("resolve_latency", str(i), v))
        for i, v in enumerate(self.message_delay.tolist()):
            rows.append(("message_delay", str(i), v))
        return pd.DataFrame(rows, columns=["metric", "key", "value"])

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready; a missing figure, NaN in :meth:`summary`, is ``None``)."""
        return {
            "format": "multiarm.metrics/1",
            "summary": {
                k: None if math.isnan(float(v)) else _jsonable(float(v))
                for k, v in self.summary().items()
            },
            "utilisation": dict(self.utilisation),
            "zone_wait": dict(self.zone_wait),
            "resolve_latency": self.resolve_latency.tolist(),
            "message_delay": self.message_delay.tolist(),
        }

    def to_json(self, path: str | PathLike[str] | None = None) -> str:
        """:meth:`to_dict` as JSON text, written to ``path`` when given."""
        text = json.dumps(self.to_dict())
        if path is not None:
            Path(path).write_text(text)
        return text
