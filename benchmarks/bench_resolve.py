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
under test (``--budget``, default 10 ms) and with the reference budget
(``--reference-budget``, default 15 ms, the earlier default), in alternating
order; reported for each: the latency distribution of the whole call and the
mean makespan over the same events.

Run: ``python -m benchmarks.bench_resolve [--events 300] [--budget 0.010]
[--reference-budget 0.015] [--seed 0] [--quick]``.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

from benchmarks.common import write
from scheduler import solve, validate
from scheduler.generate import random_problem
from scheduler.online import CellState, reschedule


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--events", type=int, default=300)
    ap.add_argument("--budget", type=float, default=0.010, help="reschedule time limit, seconds")
    ap.add_argument(
        "--reference-budget", type=float, default=0.015, help="the budget compared against"
    )
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    size = (8, 200, 8, 2)
    if args.quick:
        size, args.events = (4, 40, 4, 1), 10
    load = os.getloadavg()
    rng = np.random.default_rng(args.seed)
    p = random_problem(*size, seed=args.seed)
    plan = solve(p, "tree", time_limit=2.0 if args.quick else 5.0, seed=args.seed).schedule
    assert plan is not None
    reschedule(p, CellState(time=0.0), plan, time_limit=0.05)  # load the compiled kernel once
    first: list[float] = []
    total: list[float] = []
    makespan: list[float] = []
    ref_total: list[float] = []
    ref_makespan: list[float] = []
    kinds: list[str] = []
    remaining: list[int] = []
    for _ in range(args.events):
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
        seed = int(rng.integers(1 << 31))
        runs = [("test", args.budget), ("ref", args.reference_budget)]
        if len(kinds) % 2:
            runs.reverse()  # alternate which runs first
        for which, budget in runs:
            r = reschedule(p, state, plan, time_limit=budget, seed=seed)
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
    q = lambda xs, k: float(np.percentile(xs, k)) * 1e3  # noqa: E731
    lines = [
        f"# Re-solve latency: {size[0]} arms x {size[1]} tasks x {size[2]} zones",
        "",
        f"{args.events} events (late part / arm failure / slow task), seed {args.seed}, budget {args.budget * 1e3:g} ms, "
        f"{np.mean(remaining):.0f} tasks remaining on average (min {min(remaining)}).",
        "",
        "| latency (ms) | p50 | p90 | p99 | max | mean makespan (s) |",
        "|---|---|---|---|---|---|",
        f"| first valid schedule | {q(first, 50):.2f} | {q(first, 90):.2f} | {q(first, 99):.2f} | "
        f"{max(first) * 1e3:.2f} | |",
        f"| whole call, budget {args.budget * 1e3:g} ms | {q(total, 50):.2f} | {q(total, 90):.2f} | "
        f"{q(total, 99):.2f} | {max(total) * 1e3:.2f} | {np.mean(makespan):.2f} |",
        f"| whole call, budget {args.reference_budget * 1e3:g} ms (reference) | {q(ref_total, 50):.2f} | "
        f"{q(ref_total, 90):.2f} | {q(ref_total, 99):.2f} | {max(ref_total) * 1e3:.2f} | "
        f"{np.mean(ref_makespan):.2f} |",
        "",
        f"Mean makespan ratio (budget / reference): {np.mean(makespan) / np.mean(ref_makespan):.4f}; "
        f"events where the budget run is longer: {sum(a > b + 1e-9 for a, b in zip(makespan, ref_makespan, strict=True))}, "
        f"shorter: {sum(a < b - 1e-9 for a, b in zip(makespan, ref_makespan, strict=True))}.",
        "",
        "Target: whole-call p99 <= 10 ms, mean makespan no worse than the reference's.",
        "",
        f"Machine: {os.cpu_count()} CPUs, load average {load[0]:.1f} at the start and "
        f"{os.getloadavg()[0]:.1f} at the end (the latencies are wall-clock: other work on "
        "the machine lengthens them; the makespans compare the two budgets on the same events).",
    ]
    path = write(
        "resolve",
        {
            "size": size,
            "events": args.events,
            "budget": args.budget,
            "reference_budget": args.reference_budget,
            "load_average_start": load[0],
            "makespan": makespan,
            "ref_total_ms": [x * 1e3 for x in ref_total],
            "ref_makespan": ref_makespan,
            "seed": args.seed,
            "first_ms": [x * 1e3 for x in first],
            "total_ms": [x * 1e3 for x in total],
            "kinds": kinds,
            "remaining": remaining,
        },
        "\n".join(lines) + "\n",
    )
    print(path.read_text())


if __name__ == "__main__":
    main()
