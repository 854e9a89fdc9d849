"""The two coordination policies side by side on every built-in cell and medium.

For each built-in cell (:func:`workcell.load_example`), one plan (the greedy
solver, seed 0) is executed with ``coordination="centralized"`` (S2.7's
coordinator at station 0) and ``coordination="distributed"`` (one peer per
arm, :mod:`workcell.sim.coordination.distributed`) on every medium
(:data:`workcell.sim.comms.media.MEDIA`), with the live safety monitor on.
Reported per run: the frames the link sent (``SimResult.metrics.messages``,
retransmissions included), the frames and bytes put on the medium (counted
at the medium's ``send``), the executed makespan, the total zone wait
(``metrics.zone_wait``), the failed tasks, and the frames per message kind.
Every number is a count of simulated events: deterministic, not timed.

A thin wrapper of the sweep ``benchmarks/sweeps/policies.toml`` (one
``benchmark`` run of :func:`measure` per sweep instance). Results:
``benchmarks/results/policies.parquet``, ``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_policies [--quick]``.
"""

from __future__ import annotations

from collections import Counter
from typing import Any

from benchmarks.common import table_main
from scheduler import solve
from workcell import compile_cell, load_example, simulate
from workcell.sim.comms.media import make_medium
from workcell.sim.comms.medium import Frame, Medium
from workcell.sim.events.loop import EventLoop

NAME = "policies"
POLICIES = ("centralized", "distributed")


class _Count:
    """A medium factory that counts the frames and bytes put on the medium."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.frames = 0
        self.bytes = 0

    def __call__(self, kernel: EventLoop, stations: int) -> Medium:
        medium: Any = make_medium(self.name, kernel, stations)
        send = medium.send

        def counted(frame: Frame) -> Frame:
            self.frames += 1
            self.bytes += frame.size
            out: Frame = send(frame)
            return out

        medium.send = counted
        return medium  # type: ignore[no-any-return]


def measure(seed: int, cells: list[str], media: list[str]) -> list[dict[str, Any]]:
    """Every cell x medium x policy (one row each)."""
    rows: list[dict[str, Any]] = []
    for cell in cells:
        cc = compile_cell(load_example(cell))
        plan = solve(cc.problem, "greedy", seed=0).schedule
        for medium in media:
            for policy in POLICIES:
                count = _Count(medium)
                r = simulate(cc, plan, seed=seed, medium=count, coordination=policy)
                m = r.metrics
                kinds = Counter(e.message for e in r.trace.of_kind("message") if e.src != e.dst)
                rows.append(
                    {
                        "cell": cell,
                        "arms": cc.problem.n_arms,
                        "tasks": cc.problem.n_tasks,
                        "medium": medium,
                        "policy": policy,
                        "messages": int(m.messages),
                        "retransmissions": int(m.retransmissions),
                        "frames": count.frames,
                        "bytes": count.bytes,
                        "planned_makespan": float(m.planned_makespan),
                        "executed_makespan": float(m.executed_makespan),
                        "zone_wait": float(sum(m.zone_wait.values())),
                        "sleeps": int(m.sleeps),
                        "failed_tasks": int(m.failed_tasks),
                        "delivered_by_kind": dict(sorted(kinds.items())),
                    }
                )
    return rows


def table(m: Any) -> str:
    """The Markdown table (one line per cell and medium, the two policies side by side)."""
    lines = [
        "| cell | medium | messages C | messages D | bytes C | bytes D | makespan C (s) "
        "| makespan D (s) | zone wait C (s) | zone wait D (s) | failed C/D |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    rows = m.to_dict("records")
    by = {(r["cell"], r["medium"], r["policy"]): r for r in rows}
    seen: list[tuple[str, str]] = []
    for r in rows:
        key = (r["cell"], r["medium"])
        if key not in seen:
            seen.append(key)
    for cell, medium in seen:
        c, d = by.get((cell, medium, "centralized")), by.get((cell, medium, "distributed"))
        if c is None or d is None:
            continue
        lines.append(
            f"| {cell} | {medium} | {c['messages']:,} | {d['messages']:,} | {c['bytes']:,} | "
            f"{d['bytes']:,} | {c['executed_makespan']:.2f} | {d['executed_makespan']:.2f} | "
            f"{c['zone_wait']:.2f} | {d['zone_wait']:.2f} | "
            f"{c['failed_tasks']}/{d['failed_tasks']} |"
        )
    lines += [
        "",
        "C: centralized (S2.7's coordinator at station 0), D: distributed (one peer per "
        "arm, no coordinator). Messages: frames the link sent, retransmissions included; "
        "bytes: put on the medium. Under D an arm's controller and its peer share the arm's "
        "station, so dispatch, zone requests, grants and releases of one arm never cross the "
        "medium; only the peers' requests and replies for resources shared with other arms, "
        "task-end notices to the successors' arms, broadcast emergency stops, and the S2.12 "
        "check among the arms that may meet (each arm's view whenever it changes, and a "
        "departure request and its answers before every motion; the view and the request "
        "are one broadcast frame on a medium whose broadcast is one transfer, every medium "
        "here but serial-star) do. Zone wait: "
        "seconds the arms stood at zone borders, summed over the arms. Every number is a count "
        "of simulated events (deterministic for the seed), not a timing.",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    table_main(NAME, table, argv, __doc__, speed=True)


if __name__ == "__main__":
    main()
