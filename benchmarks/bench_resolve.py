"""Re-solve latency at 8 arms x 200 remaining tasks.

A plan for a seeded generated problem (8 arms, 200 tasks, 8 zones) is made
with the tree search; then, at random times, reality departs from it — a part
arrives late (a task's release moves), an arm fails, or a running task takes
longer — and :func:`scheduler.reschedule` makes a new plan from that state,
warm-started from the old one. Reported: the latency of the first valid new
schedule and of the whole call (its time limit is the budget), as a
distribution over many events. Results: ``benchmarks/results/resolve.json``
and ``resolve.md``.

Every event is re-solved twice, side by side in one run: with the budget
under test (``budget``, 10 ms) and with the reference budget
(``reference_budget``, 15 ms, the earlier default), in alternating order;
reported for each: the latency distribution of the whole call and the mean
makespan over the same events.

A thin wrapper of the sweep ``benchmarks/sweeps/resolve.toml`` (one
``benchmark`` run of :func:`measure`: every event, both budgets); it
measures again on every call. Results: ``benchmarks/results/resolve.parquet``,
``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_resolve [--quick]``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from benchmarks.common import table_main
from scheduler import solve, validate
from scheduler.generate import random_problem
from scheduler.online import CellState, reschedule

NAME = "resolve"


def measure(
    seed: int,
    size: list[int] | tuple[int, ...],
    events: int,
    budget: float,
    reference_budget: float,
    plan_limit: float,
) -> dict[str, Any]:
    """Every event re-solved with both budgets (the whole table, one run)."""
    size = tuple(size)
    load = os.getloadavg()
    rng = np.random.default_rng(seed)
    p = random_problem(size[0], size[1], size[2], size[3], seed=seed)
    plan = solve(p, "tree", time_limit=plan_limit, seed=seed).schedule
    assert plan is not None
    reschedule(p, CellState(time=0.0), plan, time_limit=0.05)  # load the compiled kernel once
    first: list[float] = []
    total: list[float] = []
    makespan: list[float] = []
    ref_total: list[float] = []
    ref_makespan: list[float] = []
    kinds: list[str] = []
    remaining: list[int] = []
    for _ in range(events):
        # early in the plan, so that most of the tasks remain (about 200 for the full size)
        now = float(rng.uniform(0.0, 0.1 * plan.makespan))
        done = {
            t: (int(plan.mode[t]), float(plan.start[t]), float(plan.end[t]), plan.waits[t].tolist())
            for t in range(p.n_tasks)
            if plan.start[t] < now
        }
        rest = [t for t in range(p.n_tasks) if t not in done]
        kind = str(rng.choice(["late_part", "arm_failure", "slow_task"]))
        state = CellState(time=now, done=done)
        if kind == "late_part" and rest:
            t = int(rng.choice(rest))
            state.releases = {t: now + float(rng.uniform(5, 30))}
        elif kind == "arm_failure":
            # an arm whose remaining tasks others can all take over
            ok = [
                a
                for a in range(p.n_arms)
                if all(any(p.mode_arm[m] != a for m in p.task_modes[t]) for t in rest)
            ]
            if ok:
                state.failed_arms = {int(rng.choice(ok))}
        elif kind == "slow_task":
            running = [t for t in done if plan.end[t] > now]
            if running:
                t = int(rng.choice(running))
                m, s, e, w = done[t]
                state.done[t] = (m, s, e + float(rng.uniform(1, 10)), w)  # type: ignore[index]
        event_seed = int(rng.integers(1 << 31))
        runs = [("test", budget), ("ref", reference_budget)]
        if len(kinds) % 2:
            runs.reverse()  # alternate which runs first
        for which, limit in runs:
            r = reschedule(p, state, plan, time_limit=limit, seed=event_seed)
            assert r.schedule is not None and validate(p, r.schedule) == r.objective
            if which == "test":
                first.append(r.stats.first_time)
                total.append(r.runtime)
                makespan.append(r.objective)
            else:
                ref_total.append(r.runtime)
                ref_makespan.append(r.objective)
        kinds.append(kind)
        remaining.append(len(rest))
    return {
        "size": list(size),
        "events": events,
        "budget": budget,
        "reference_budget": reference_budget,
        "load_average_start": load[0],
        "load_average_end": os.getloadavg()[0],
        "first_ms": [x * 1e3 for x in first],
        "total_ms": [x * 1e3 for x in total],
        "makespan": makespan,
        "ref_total_ms": [x * 1e3 for x in ref_total],
        "ref_makespan": ref_makespan,
        "kinds": kinds,
        "remaining": remaining,
    }


def table(r: Any) -> str:
    """The Markdown table of the one measured row."""
    size, events, seed = r["size"], r["events"], r["seed"]
    budget, ref_budget = r["budget"], r["reference_budget"]
    first, total, ref_total = (np.asarray(r[k]) for k in ("first_ms", "total_ms", "ref_total_ms"))
    makespan, ref_makespan = np.asarray(r["makespan"]), np.asarray(r["ref_makespan"])
    remaining = r["remaining"]

    def q(xs: Any, k: float) -> float:
        return float(np.percentile(xs, k))

    lines = [
        f"# Re-solve latency: {size[0]} arms x {size[1]} tasks x {size[2]} zones",
        "",
        f"{events} events (late part / arm failure / slow task), seed {seed}, budget "
        f"{budget * 1e3:g} ms, {np.mean(remaining):.0f} tasks remaining on average "
        f"(min {min(remaining)}).",
        "",
        "| latency (ms) | p50 | p90 | p99 | max | mean makespan (s) |",
        "|---|---|---|---|---|---|",
        f"| first valid schedule | {q(first, 50):.2f} | {q(first, 90):.2f} | {q(first, 99):.2f} | "
        f"{first.max():.2f} | |",
        f"| whole call, budget {budget * 1e3:g} ms | {q(total, 50):.2f} | {q(total, 90):.2f} | "
        f"{q(total, 99):.2f} | {total.max():.2f} | {makespan.mean():.2f} |",
        f"| whole call, budget {ref_budget * 1e3:g} ms (reference) | {q(ref_total, 50):.2f} | "
        f"{q(ref_total, 90):.2f} | {q(ref_total, 99):.2f} | {ref_total.max():.2f} | "
        f"{ref_makespan.mean():.2f} |",
        "",
        f"Mean makespan ratio (budget / reference): {makespan.mean() / ref_makespan.mean():.4f}; "
        f"events where the budget run is longer: {int(np.sum(makespan > ref_makespan + 1e-9))}, "
        f"shorter: {int(np.sum(makespan < ref_makespan - 1e-9))}.",
        "",
        "Target: whole-call p99 <= 10 ms, mean makespan no worse than the reference's.",
        "",
        f"Load average {r['load_average_start']:.1f} at the start and "
        f"{r['load_average_end']:.1f} at the end (the latencies are wall-clock: other work on "
        "the machine lengthens them; the makespans compare the two budgets on the same events).",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the table.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    table_main(NAME, table, argv, __doc__, speed=True, one_row=True)


if __name__ == "__main__":
    main()
