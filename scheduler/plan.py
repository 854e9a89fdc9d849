"""A self-describing plan: a schedule together with its problem.

A :class:`Plan` is what the simulator and users read: per task its arm, mode,
start, end, duration, total wait at zone borders and detour (one tidy row per
task), and every reservation of a zone, a shared zone's movement, a tool or a
start zone. It prints as a table and writes itself as JSON or CSV.

Examples
--------
>>> from scheduler.fjsp import parse_fjsp
>>> from scheduler.solve import solve
>>> p = parse_fjsp("2 2\\n2 1 1 3 1 2 2\\n1 1 1 4\\n")
>>> plan = solve(p, "greedy").plan
>>> plan.makespan
7.0
>>> print(plan.table())
task   arm  mode  start  end  duration  wait  detour
-----  ---  ----  -----  ---  --------  ----  ------
J1.O1  M1   0     0      3    3         0     0
J2.O1  M1   2     3      7    4         0     0
J1.O2  M2   1     3      5    2         0     0
>>> plan.to_dataframe().columns.tolist()
['task', 'arm', 'mode', 'start', 'end', 'duration', 'wait', 'detour']
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass
from os import PathLike, fspath
from pathlib import Path
from typing import Any

from multiarm.errors import UsageError, ValidationError
from scheduler.problem import Problem
from scheduler.schedule import ROW_COLUMNS, Reservation, Schedule, validate

__all__ = ["Plan"]


def _num(x: float) -> str:
    return f"{x:.6g}"


@dataclass(frozen=True)
class Plan:
    """A schedule bound to its problem.

    Attributes
    ----------
    problem : Problem
    schedule : Schedule

    Raises
    ------
    ValidationError
        The schedule covers another number of tasks than the problem has.
    """

    problem: Problem
    schedule: Schedule

    def __post_init__(self) -> None:
        if self.schedule.n_tasks != self.problem.n_tasks:
            raise ValidationError(
                f"a schedule of {self.schedule.n_tasks} tasks is no plan for a problem of "
                f"{self.problem.n_tasks} tasks"
            )

    @property
    def makespan(self) -> float:
        """The largest end, seconds (0 without tasks)."""
        return self.schedule.makespan

    def validate(self) -> float:
        """:func:`scheduler.validate` on this plan; returns the makespan."""
        return validate(self.problem, self.schedule)

    def rows(self) -> list[dict[str, Any]]:
        """One tidy record per task (see :meth:`Schedule.rows`), in task order."""
        return self.schedule.rows(self.problem)

    def to_dataframe(self) -> Any:
        """One row per task: ``task, arm, mode, start, end, duration, wait, detour``."""
        return self.schedule.to_dataframe(self.problem)

    def reservations(self) -> list[Reservation]:
        """Every reservation of a zone, movement, tool or start zone."""
        return self.schedule.reservations(self.problem)

    def reservations_frame(self) -> Any:
        """The reservations as a DataFrame (see :meth:`Schedule.reservations_frame`)."""
        return self.schedule.reservations_frame(self.problem)

    def to_dict(self) -> dict[str, Any]:
        """The schedule's JSON data (``multiarm.schedule/1``, see :meth:`Schedule.to_dict`)."""
        return self.schedule.to_dict(self.problem)

    def table(self, max_rows: int | None = None) -> str:
        """The rows as a text table, by arm then start.

        Parameters
        ----------
        max_rows : int or None
            Show at most this many rows (a last line says how many were left out).
        """
        arm_ids = {n: i for i, n in enumerate(self.problem.arm_names)}
        rows = sorted(self.rows(), key=lambda r: (arm_ids[r["arm"]], r["start"], r["task"]))
        shown = rows if max_rows is None else rows[:max_rows]
        cells = [
            [str(r[c]) if c in ("task", "arm", "mode") else _num(float(r[c])) for c in ROW_COLUMNS]
            for r in shown
        ]
        if not rows:  # a problem without tasks: nothing to schedule
            return "(no tasks: the plan is empty, makespan 0)"
        widths = [max([len(c), *(len(row[i]) for row in cells)]) for i, c in enumerate(ROW_COLUMNS)]
        lines = [
            "  ".join(c.ljust(w) for c, w in zip(ROW_COLUMNS, widths, strict=True)).rstrip(),
            "  ".join("-" * w for w in widths),
        ]
        lines += [
            "  ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)).rstrip()
            for row in cells
        ]
        if len(shown) < len(rows):
            lines.append(f"... {len(rows) - len(shown)} more tasks")
        return "\n".join(lines)

    def to_csv(self) -> str:
        """The rows as CSV text with a header line."""
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=list(ROW_COLUMNS), lineterminator="\n")
        w.writeheader()
        w.writerows(self.rows())
        return buf.getvalue()

    def write(self, path: str | PathLike[str]) -> Path:
        """Write the plan by the file's extension: ``.json`` (the schedule's
        data) or ``.csv`` (the rows).

        Returns
        -------
        Path

        Raises
        ------
        UsageError
            Another extension, or a file that cannot be written.
        """
        p = Path(path)
        suffix = p.suffix.lower()
        if suffix == ".json":
            text = json.dumps(self.to_dict(), indent=1, allow_nan=False) + "\n"
        elif suffix == ".csv":
            text = self.to_csv()
        else:
            raise UsageError(
                f"{fspath(p)}: a plan is written as .json or .csv, not {suffix or 'no extension'!r}"
            )
        try:
            p.write_text(text, encoding="utf-8")
        except OSError as exc:
            raise UsageError(f"cannot write {fspath(p)!r}: {exc.strerror}") from None
        return p
