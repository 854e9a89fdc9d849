"""Where a plan's time goes against the lower bounds: the anatomy of the gap.

For the tree's plan of each problem (the built-in cells ``supersigma``,
``scara4`` and ``cell8``, and the 16 x 1000 scale problems of
``benchmarks/sweeps/scale.toml``, seeds 0-2), without any further search.
The optimum of ``supersigma`` is proven (128.413 s, ``benchmarks/results/cells.md``)
and its 10 s plan reaches it, so its rows show what a gap to the bounds looks
like when all of it is the bounds':

* **Arms.** Every arm's time up to the makespan is split into its
  availability, travel (setups), task durations, waits at zone borders,
  idle time before a task (by what held the task: a predecessor, its
  release, a zone, movement or tool another arm held until that moment,
  or nothing but the plan's order) and idle time after its last task.
* **Critical chain.** From the task that ends last, back to time 0, each
  task is entered through what held it (its arm, a predecessor, a release,
  the arm that held its resource; "order" when nothing did: the arm could
  have started it earlier). The makespan is the sum of the chain's
  durations, travel, waits and idle gaps.
* **Bottlenecks.** Per exclusive zone, shared-zone movement and tool: the
  work that every plan must put on it (the tasks that need it in every mode,
  each at its least occupation) and the one-machine bound over it
  (:func:`scheduler.bounds.resource_bounds`), next to the plan's
  occupation of it (the union of its uses, waits inside them included).
* **Bounds.** Every part of :func:`scheduler.bounds.lower_bounds`.

Run: ``python -m benchmarks.gap_anatomy [--quick] [--time-limit S]`` (writes
``benchmarks/results/gap_anatomy.md`` and ``.json``; ``--quick``: seed 0 of
the scale problems only, tree at 1 s, into a temporary directory).
"""

from __future__ import annotations

import argparse
import itertools
import math
import time
from typing import Any

import numpy as np

from benchmarks.common import output_dir, write

TOL = 1e-6

CAUSES = ("predecessor", "release", "zone", "move", "tool", "start zone", "order")
"""What held a task past the moment its arm was ready (see :func:`arm_anatomy`)."""


def _held_by(
    p: Any, s: Any, t: int, rows_by_res: dict[tuple[str, str], list[Any]], task_rows: list[Any]
) -> tuple[str, int]:
    """Why task ``t`` starts when it does, other than its arm: (cause, the task that held it,
    -1 for none or a start zone)."""
    st = float(s.start[t])
    for q in p.task_preds[t]:
        if float(s.end[q]) >= st - TOL:
            return "predecessor", int(q)
    if float(p.task_release[t]) >= st - TOL:
        return "release", -1
    arm = p.arm_names[int(p.mode_arm[s.mode[t]])]
    # a resource the task enters at the moment another arm leaves it
    for kind, name, _task, _arm, s0, _e0 in task_rows:
        key = ("zone" if kind == "start" else kind, name)
        for k2, _n2, task2, arm2, _s2, e2 in rows_by_res.get(key, ()):
            if arm2 != arm and abs(e2 - s0) <= 1e-6 * max(1.0, abs(s0)) + TOL:
                if k2 == "start":
                    return "start zone", -1
                return kind, p.task_names.index(task2) if isinstance(task2, str) else -1
    return "order", -1


def anatomy(p: Any, s: Any) -> dict[str, Any]:
    """The arms' time split, the critical chain and the busiest resources of a plan.

    Parameters
    ----------
    p : scheduler.Problem
    s : scheduler.Schedule
        A schedule :func:`scheduler.validate` accepts.

    Returns
    -------
    dict
        ``makespan``; ``arms``: per arm, seconds of ``available``, ``travel``,
        ``work``, ``waits``, idle before tasks per cause (:data:`CAUSES`) and
        ``idle after``; ``chain``: seconds of the critical chain per
        component (``in tasks``, ``of which waits``, ``travel``, ``idle``,
        ``release``; all but the waits add up to the makespan) and ``hops``,
        how each task on it was entered.
    """
    from scheduler import validate

    makespan = validate(p, s)
    rows = s.reservation_rows(p)
    by_res: dict[tuple[str, str], list[Any]] = {}
    by_task: dict[str, list[Any]] = {}
    for r in rows:
        by_res.setdefault(("zone" if r[0] == "start" else r[0], r[1]), []).append(r)
        if r[2] is not None:
            by_task.setdefault(r[2], []).append(r)
    seqs = s.sequences(p)
    names = p.task_names
    prev_of: dict[int, int] = {}
    arms = []
    held: dict[int, tuple[str, int]] = {}
    for a, seq in enumerate(seqs):
        row = {c: 0.0 for c in ("available", "travel", "work", "waits", *CAUSES, "idle after")}
        row["available"] = float(p.arm_available[a])
        prev, ready = -1, float(p.arm_available[a])
        for t in seq:
            prev_of[t] = prev
            setup = p.setup_time(a, prev, t)
            row["travel"] += setup
            gap = float(s.start[t]) - (ready + setup)
            if gap > TOL:
                why = _held_by(p, s, t, by_res, by_task.get(names[t], []))
                held[t] = why
                row[why[0]] += gap
            row["work"] += float(p.mode_duration[s.mode[t]]) + float(s.blocking[t])
            row["waits"] += float(np.sum(s.waits[t]))
            prev, ready = t, float(s.end[t])
        row["idle after"] = makespan - ready
        arms.append(row)
    # the critical chain, from the last end back to 0: a cursor walks back in
    # time; each task on the chain covers the time from its start to the
    # cursor, and the gap to what held it is travel or idle time
    chain = {c: 0.0 for c in ("in tasks", "of which waits", "travel", "idle", "release")}
    hops = {c: 0 for c in ("arm", *CAUSES)}
    t = int(np.argmax(s.end))
    now = makespan
    seen = set()
    while t >= 0 and t not in seen:
        seen.add(t)
        a = int(p.mode_arm[s.mode[t]])
        st = float(s.start[t])
        chain["in tasks"] += max(0.0, now - st)
        chain["of which waits"] += float(np.sum(s.waits[t]))
        now = min(now, st)
        prev = prev_of[t]
        setup = p.setup_time(a, prev, t)
        cause, by = held.get(t, ("arm", -1))
        hops[cause] += 1
        if cause == "release":
            chain["release"] += now
            now = 0.0
            break
        if cause in ("predecessor", "zone", "move", "tool") and by >= 0:
            # a predecessor's end, or the moment the holder left the resource
            until = float(s.end[by]) if cause == "predecessor" else now
            chain["idle"] += max(0.0, now - until)
            now = min(now, until)
            t = by
            continue
        # its arm (or a start zone, or only the plan's order): travel from the task before
        ready = float(s.end[prev]) if prev >= 0 else float(p.arm_available[a])
        chain["travel"] += min(setup, max(0.0, now - ready))
        chain["idle"] += max(0.0, now - ready - setup)
        now = min(now, ready)
        t = prev
    chain["idle"] += now  # the arm's availability before its first task
    return {"makespan": makespan, "arms": arms, "chain": chain, "hops": hops}


def bottlenecks(p: Any, s: Any, top: int = 5) -> list[dict[str, Any]]:
    """The ``top`` resources by the one-machine bound over the work every plan puts on
    them, with the plan's occupation of each (:func:`scheduler.bounds.resource_bounds`)."""
    from scheduler.bounds import resource_bounds
    from scheduler.timing import merge_intervals

    uses: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for kind, res, _task, _arm, s0, e0 in s.reservation_rows(p):
        uses.setdefault(("zone" if kind == "start" else kind, res), []).append((s0, e0))
    occupied = {k: sum(e - b for b, e in merge_intervals(v)) for k, v in uses.items()}
    out = []
    for rb in sorted(resource_bounds(p), key=lambda r: -r.bound)[:top]:
        out.append(
            {
                "resource": f"{rb.kind} {rb.name}",
                "tasks needing it": rb.tasks,
                "least work (s)": round(rb.work, 2),
                "head-body-tail (s)": round(rb.simple, 2),
                "one-machine bound (s)": round(rb.bound, 2),
                "plan occupies (s)": round(occupied.get((rb.kind, rb.name), 0.0), 2),
            }
        )
    return out


def bottleneck_timeline(p: Any, s: Any, resource: int) -> dict[str, float]:
    """How a plan spends its makespan on one resource (seconds; they add up to it).

    ``before first use`` and ``after last use``; ``least work``: the least
    occupation of each use in the plan's modes (merged window lengths; a
    tool: the mode); ``waits inside``: the plan's uses beyond that (waits at
    borders inside windows, detours); ``idle, a user ready``: gaps between
    uses while some task that uses it later had its release and predecessors
    behind it (only its arm, or the plan's order, kept it out);
    ``idle, none ready``: the other gaps. ``mode excess`` (not a share of
    the makespan): the plan's least work less the least work over each
    task's modes.
    """
    from scheduler.timing import merge_intervals

    Z = p.n_zones
    ms = float(np.max(s.end))
    uses: dict[int, list[tuple[float, float]]] = {}
    for t in range(p.n_tasks):
        m = int(s.mode[t])
        sh = p.shapes[m]
        if resource >= 2 * Z:
            if resource in sh.tools:
                uses[t] = [(float(s.start[t]), float(s.end[t]))]
            continue
        ivs = [(a, b) for r, a, b in sh.intervals(float(s.start[t]), s.waits[t]) if r == resource]
        if ivs:
            uses[t] = ivs
    if not uses:
        return {}
    least = 0.0
    excess = 0.0
    for t in uses:
        lengths = [_least(p, int(m), resource) for m in p.task_modes[t]]
        mine = _least(p, int(s.mode[t]), resource)
        least += mine
        excess += mine - min(x for x in lengths if x is not None) if None not in lengths else 0.0
    merged = merge_intervals([iv for ivs in uses.values() for iv in ivs])
    busy = sum(b - a for a, b in merged)
    first_use = {t: min(a for a, _ in ivs) for t, ivs in uses.items()}
    ready = {
        t: max([float(p.task_release[t])] + [float(s.end[q]) for q in p.task_preds[t]])
        for t in uses
    }
    idle_ready = idle_none = 0.0
    for (_, g0), (g1, _) in itertools.pairwise(merged):
        if g1 <= g0:
            continue
        if any(first_use[t] >= g1 - TOL and ready[t] <= g0 + TOL for t in uses):
            idle_ready += g1 - g0
        else:
            idle_none += g1 - g0
    return {
        "before first use": merged[0][0],
        "least work": least,
        "waits inside": max(0.0, busy - least),
        "idle, a user ready": idle_ready,
        "idle, none ready": idle_none,
        "after last use": ms - merged[-1][1],
        "mode excess": excess,
    }


def bottleneck_mode_move(
    p: Any, s: Any, resource: int, rounds: int = 2
) -> tuple[float, float, int]:
    """Does the plan's choice of modes on the bottleneck cost it? A probe, not a solver.

    The plan's start order and modes are decoded again as a list
    (:class:`scheduler.search.Evaluator`); then, task by task (the largest
    excess first), a task that uses ``resource`` longer than one of its other
    modes would is switched to the first such mode that shortens the
    decoded plan, for ``rounds`` passes.

    Returns
    -------
    (float, float, int)
        The decoded plan's makespan, after the switches, and the decodes.
    """
    from scheduler.search import Evaluator

    def use(m: int) -> float:
        got = _least(p, m, resource)
        return 0.0 if got is None else got

    ev = Evaluator(p)
    order = np.lexsort((np.arange(p.n_tasks), s.start)).astype(np.int64)
    modes = s.mode.astype(np.int64).copy()
    sol = ev.evaluate(order, modes)
    if sol is None:
        return math.inf, math.inf, ev.evaluations
    first = best = sol.makespan
    for _ in range(rounds):
        excess = {
            t: use(int(modes[t])) - min(use(int(m)) for m in p.task_modes[t])
            for t in range(p.n_tasks)
        }
        for t in sorted(excess, key=lambda t: -excess[t]):
            if excess[t] <= 0:
                break
            cur = use(int(modes[t]))
            for m in sorted(p.task_modes[t], key=use):
                if use(int(m)) >= cur - 1e-9:
                    break
                trial = modes.copy()
                trial[t] = m
                got = ev.evaluate(order, trial)
                if got is not None and got.makespan < best - 1e-6:
                    best, modes = got.makespan, trial
                    break
    return first, best, ev.evaluations


def _least(p: Any, m: int, resource: int) -> float | None:
    """The least occupation of ``resource`` by mode ``m`` (None: it does not use it)."""
    sh = p.shapes[m]
    if resource >= 2 * p.n_zones:
        return float(sh.duration) if resource in sh.tools else None
    got = [b - a for r, a, b in (*sh.exclusive, *sh.moves) if r == resource]
    return float(sum(got)) if got else None


def _problems(quick: bool) -> list[tuple[str, Any]]:
    from scheduler.generate import random_problem

    seeds = [0] if quick else [0, 1, 2]
    out: list[tuple[str, Any]] = []
    if not quick:
        from workcell import compile_cell, load_example

        for cell in ("supersigma", "scara4", "cell8"):
            out.append((cell, compile_cell(load_example(cell)).problem))
    for seed in seeds:
        out.append((f"scale-s{seed}", random_problem(16, 1000, 30, 4, seed=seed, start_zones=True)))
    return out


def main(argv: list[str] | None = None) -> None:
    """Solve each problem with the tree, then write the anatomy of its plan.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from scheduler import lower_bounds, solve

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="scale seed 0 only, tree at 1 s")
    ap.add_argument("--time-limit", type=float, default=None, help="tree seconds (default 10)")
    args = ap.parse_args(argv)
    tl = args.time_limit if args.time_limit is not None else (1.0 if args.quick else 10.0)
    out = output_dir(args.quick)
    records = []
    arm_lines, chain_lines, res_lines, bound_lines, time_lines = [], [], [], [], []
    for name, p in _problems(args.quick):
        seed = int(name.rsplit("-s", 1)[1]) if "-s" in name else 0
        res = solve(p, "tree", time_limit=tl, seed=seed)
        assert res.schedule is not None
        an = anatomy(p, res.schedule)
        t0 = time.perf_counter()
        lb = lower_bounds(p)
        lb_time = time.perf_counter() - t0
        ms = an["makespan"]
        tot = {k: sum(r[k] for r in an["arms"]) for k in an["arms"][0]}
        A = p.n_arms
        arm_lines.append(
            f"| {name} | {ms:.1f} | "
            + " | ".join(
                f"{100 * tot[k] / (A * ms):.1f}%"
                for k in ("available", "travel", "work", "waits", *CAUSES, "idle after")
            )
            + " |"
        )
        ch, hp = an["chain"], an["hops"]
        chain_lines.append(
            f"| {name} | {ms:.1f} | "
            + " | ".join(
                f"{ch[k]:.1f}" for k in ("in tasks", "of which waits", "travel", "idle", "release")
            )
            + " | "
            + ", ".join(f"{k} {v}" for k, v in hp.items() if v)
            + " |"
        )
        bn = bottlenecks(p, res.schedule)
        for b in bn:
            res_lines.append(f"| {name} | " + " | ".join(str(v) for v in b.values()) + " |")
        from scheduler.bounds import resource_bounds

        top = max(resource_bounds(p), key=lambda r: r.bound, default=None)
        tl_row = {} if top is None else bottleneck_timeline(p, res.schedule, top.resource)
        if top is not None and tl_row:
            decoded, moved, decodes = bottleneck_mode_move(p, res.schedule, top.resource)
            tl_row["decoded again"] = decoded
            tl_row["after mode switches"] = moved
            time_lines.append(
                f"| {name} | {top.kind} {top.name} | {top.bound:.1f} | {ms:.1f} | "
                + " | ".join(f"{v:.1f}" for v in tl_row.values())
                + f" | {decodes} |"
            )
        best = lb.value
        bound_lines.append(
            f"| {name} | {ms:.1f} | {lb.critical_path:.1f} | {lb.load:.1f} | "
            f"{lb.capability:.1f} | {lb.resources:.1f} ({lb.resource_name}) | "
            f"{lb.one_machine:.1f} ({lb.one_machine_name}) | {best:.1f} | "
            f"{100 * (ms - best) / best:.1f}% | {lb_time:.2f} |"
        )
        records.append(
            {
                "problem": name,
                "makespan": ms,
                "arms": tot,
                "chain": ch,
                "hops": hp,
                "bottlenecks": bn,
                "bottleneck_timeline": tl_row,
                "bounds": {
                    k: getattr(lb, k)
                    for k in (
                        "value",
                        "critical_path",
                        "load",
                        "capability",
                        "resources",
                        "one_machine",
                    )
                },
                "bound_time": lb_time,
            }
        )
        print(f"{name}: makespan {ms:.1f}, bound {best:.1f}", flush=True)
    head = " | ".join(("available", "travel", "work", "waits", *CAUSES, "idle after"))
    table = "\n".join(
        [
            "# Gap anatomy: where the tree's plans spend their time",
            "",
            f"Tree at {tl:g} s (seed = the problem's seed; scale seeds as in "
            "`benchmarks/sweeps/scale.toml`). Reproduce: `python -m benchmarks.gap_anatomy`.",
            "",
            "The exact branch and bound proves 128.413 s the optimum of `supersigma` "
            "(`benchmarks/results/cells.md`): where its row's makespan is that, the row "
            "shows the anatomy of a plan whose whole gap to the bounds is the bounds'. "
            "The other optima are not known.",
            "",
            "## The arms' time (share of arms x makespan)",
            "",
            "Idle time before a task is split by what held the task once its arm was ready "
            "(a zone, movement or tool: another arm left it at the task's entry; order: "
            "nothing did, the plan's order alone).",
            "",
            f"| problem | makespan | {head} |",
            "|---" * (3 + len(CAUSES) + 4) + "|",
            *arm_lines,
            "",
            "## The critical chain (seconds)",
            "",
            "From the task that ends last back to time 0, each task entered through what "
            "held it (its arm; a predecessor; a zone, movement or tool: into the task that "
            "held it, at the moment it let go). In tasks + travel + idle + release = makespan; "
            "hops: how each task on the chain was entered.",
            "",
            "| problem | makespan | in tasks | of which waits | travel | idle | release | hops |",
            "|---|---|---|---|---|---|---|---|---|",
            *chain_lines,
            "",
            "## Bottlenecks: the work every plan puts on a resource",
            "",
            "Tasks needing the resource in every mode, each at its least occupation "
            "(window lengths); head-body-tail: the best head threshold; one-machine: the "
            "preemptive one-machine bound with heads and tails (Jackson).",
            "",
            "| problem | resource | tasks needing it | least work (s) | head-body-tail (s) "
            "| one-machine bound (s) | plan occupies (s) |",
            "|---|---|---|---|---|---|---|",
            *res_lines,
            "",
            "## The busiest resource's timeline in the plan (seconds)",
            "",
            "The resource with the largest one-machine bound. Before first use + least "
            "work + waits inside + idle + after last use = makespan. Least work: each use "
            "at its mode's least occupation; waits inside: the plan's uses beyond that; "
            "idle, a user ready: gaps while a task that enters it later had its release "
            "and predecessors behind it (only its arm or the plan's order kept it out); "
            "mode excess: the least work of the plan's modes less the least over each "
            "task's modes. Decoded again: the plan's start order and modes decoded as a "
            "list; after mode switches: then each task switched, largest excess first, to "
            "a mode that uses the resource less where that shortens the decoded plan (two "
            "passes; decodes: how many plans that took).",
            "",
            "| problem | resource | one-machine bound | makespan | before first use | least work "
            "| waits inside | idle, a user ready | idle, none ready | after last use "
            "| mode excess | decoded again | after mode switches | decodes |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
            *time_lines,
            "",
            "## Lower bounds (scheduler.lower_bounds)",
            "",
            "| problem | plan | critical path | load LP | capability | resources (head-body-tail) "
            "| one-machine | lower_bound | plan gap | bound time (s) |",
            "|---|---|---|---|---|---|---|---|---|---|",
            *bound_lines,
            "",
        ]
    )
    seeds = [int(str(r["problem"]).rsplit("-s", 1)[1]) for r in records if "-s" in r["problem"]]
    path = write("gap_anatomy", {"time_limit": tl, "seeds": seeds, "problems": records}, table, out)
    print(f"wrote {path}")
    _ = math


if __name__ == "__main__":
    main()
