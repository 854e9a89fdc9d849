"""Simulation speed and re-solving in the loop, on ``cell8`` (8 arms).

Side by side in one run, on one plan (the tree search's, seeded):

* **speed** -- simulated seconds per wall second of :func:`workcell.simulate`
  at event level (idle controller ticks skipped) and with every controller
  tick of every arm modelled (``tick=1e-3``, S2.3), best of a few runs; the
  safety monitor is off for these two rows; it has its own rows at event
  level: the live monitor (the default: a kernel process that samples while
  some arm moves and stops the run at the first violation) and, side by
  side, the post-run check of the same records (``monitor="post"``);
* **re-solving** -- seeded fault scenarios (a part arriving late, a crash
  stopping an arm, an arm failing for good) run twice with the same faults:
  with re-solving (the coordinator asks :func:`scheduler.reschedule` for a
  new plan within its real-time budget) and without (``simulate(...,
  options=SimOptions(resolve=False))``: the coordinator keeps the plan and waits; an arm failure
  then leaves its tasks failed). Reported:
  the re-solve latency (p50/p99 over every re-solve of every scenario) and
  the executed makespan and failed tasks with and without re-solving.

Targets (issue): >= 2000x at event level with the monitor off, >= 1000x at
event level with the live monitor, >= 200x at 1 ms ticks.

The plan is work-limited (``evaluations`` decodes of the tree search, so the
same on every machine). With a ``baseline`` revision, the same speed rows
run in a second process on that revision's code (``git archive``), fed the
same plan, alternating with this one, so the ratios hold on a loaded
machine. Then one run of each level is profiled (``cProfile``) and its time
split by where it goes (:data:`AREAS`): the misses are explained there.

A thin wrapper of the sweep ``benchmarks/sweeps/sim.toml`` (one
``benchmark`` run of :func:`measure`: the whole table); it measures again on
every call. Results: ``benchmarks/results/sim.parquet``, ``.json`` and
``.md``.

Run: ``python -m benchmarks.bench_sim [--quick]`` (``--quick``: supersigma,
one repeat, two scenarios; seconds).
"""

from __future__ import annotations

import json
import math
import signal
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.common import RevisionProcess, table_main
from multiarm.errors import MultiarmError
from scheduler import solve, validate
from scheduler.tree import TreeOptions
from workcell import compile_cell, load_example
from workcell.sim.harness.faults import FaultPlan
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import simulate

NAME = "sim"
EVENT_TARGET = 2000.0
LIVE_TARGET = 1000.0
TICK_TARGET = 200.0


def _speed(cc: Any, plan: Any, repeat: int, **kw: Any) -> dict[str, Any]:
    """Best simulated-seconds-per-wall-second over ``repeat`` runs (and the
    least process CPU time, which a loaded machine inflates less)."""
    rates, walls, cpus = [], [], []
    last = None
    for _ in range(repeat):
        c0 = time.process_time()
        t0 = time.perf_counter()
        last = simulate(cc, plan, seed=0, options=SimOptions(**kw))
        wall = time.perf_counter() - t0
        cpus.append(time.process_time() - c0)
        walls.append(wall)
        rates.append(float(last.metrics.executed_makespan) / wall)
    assert last is not None
    m = last.metrics
    return {
        "rate": max(rates),
        "rates": rates,
        "wall_s": min(walls),
        "cpu_s": min(cpus),
        "simulated_s": float(m.executed_makespan),
        "events": int(m.events),
        "ticks": int(m.ticks),
        "trace": len(last.trace),
        "failed_tasks": int(m.failed_tasks),
    }


def _scenarios(cc: Any, plan: Any, n: int, seed: int) -> list[tuple[str, FaultPlan]]:
    """``n`` seeded fault scenarios, cycling through late part, crash, arm failure."""
    p = cc.problem
    rng = np.random.default_rng(seed)
    arriving = sorted(cc.cell.taskset.expected_arrivals())  # parts with an arrival model
    mk = plan.makespan
    arms = plan.arms(p)
    busy = [a for a in range(p.n_arms) if (arms == a).any()]
    spare = [
        a
        for a in busy
        if all(any(int(p.mode_arm[m]) != a for m in p.task_modes[t]) for t in range(p.n_tasks))
    ] or busy
    out = []
    for i in range(n):
        kind = ("late_part", "crash", "arm_failure")[i % 3]
        at = round(float(rng.uniform(0.2, 0.6)) * mk, 3)
        if kind == "late_part":
            rec = {"kind": kind, "part": str(rng.choice(arriving)), "delay": round(0.1 * mk, 3)}
            label = f"part {rec['part']!r} {rec['delay']:g} s late"
        elif kind == "crash":
            arm = p.arm_names[int(rng.choice(busy))]
            rec = {"kind": kind, "arm": arm, "at": at, "recovery": 5.0}
            label = f"crash of {arm} at {at:g} s (5 s to recover)"
        else:
            arm = p.arm_names[int(rng.choice(spare))]
            rec = {"kind": kind, "arm": arm, "at": at}
            label = f"{arm} fails at {at:g} s"
        out.append((label, FaultPlan.from_dicts([rec])))
    return out


class _Overrun(Exception):
    """A run went past its wall-clock cap."""


@contextmanager
def _wall_cap(seconds: float) -> Iterator[None]:
    """Stop the body with :class:`_Overrun` after ``seconds`` of wall time (SIGALRM)."""

    def stop(_signum: int, _frame: object) -> None:
        raise _Overrun

    old = signal.signal(signal.SIGALRM, stop)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


def _faulty_run(
    cc: Any, plan: Any, faults: FaultPlan, seed: int, cap: float, resolve: bool = True
) -> dict[str, Any]:
    """One run under ``faults``: makespan, failed tasks, re-solves and their latencies
    (``resolve=False``: the coordinator keeps the plan)."""
    try:
        with _wall_cap(cap):
            r = simulate(
                cc,
                plan,
                seed=seed,
                faults=faults,
                options=SimOptions(monitor=False, resolve=resolve),
            )
    except _Overrun:
        return {
            "makespan": math.nan,
            "failed": None,
            "resolves": None,
            "latency": [],
            "stopped": f"not finished after {cap:g} s",
        }
    except MultiarmError as exc:
        return {
            "makespan": math.nan,
            "failed": None,
            "resolves": None,
            "latency": [],
            "stopped": str(exc),
        }
    m = r.metrics
    return {
        "makespan": float(m.executed_makespan),
        "failed": int(m.failed_tasks),
        "resolves": int(m.resolves),
        "latency": np.asarray(m.resolve_latency, dtype=float).tolist(),
        "stopped": "",
    }


LEVELS: dict[str, dict[str, Any]] = {
    "event": {"monitor": False},
    "live": {"monitor": "live"},
    "post": {"monitor": "post"},
    "tick": {"monitor": False, "tick": 1e-3},
}
"""The speed rows: :class:`SimOptions` keywords of each (``tick``'s period
is replaced by the sweep's)."""

AREAS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("geometric check (S2.12 guard)", ("workcell/sim/coordination/guard", "_zone_sweep_jit")),
    ("safety monitor", ("workcell/sim/harness/monitor",)),
    (
        "link, channel and medium (per frame)",
        ("workcell/sim/comms/", "workcell/sim/protocol/channel", "workcell/sim/protocol/records"),
    ),
    ("event loop", ("workcell/sim/events/loop",)),
    ("trace records", ("workcell/sim/events/trace",)),
    ("arm controllers", ("workcell/sim/control/",)),
    (
        "coordinator (zones, dispatch, recovery)",
        ("workcell/sim/coordination/", "zones/"),
    ),
    ("kinematics and trajectories", ("workcell/arms/",)),
    ("results and set-up", ("workcell/sim/harness/",)),
    ("numpy, numba and Python built-ins", ("numpy", "numba", "~", "<")),
)
"""Where a profiled run's time goes: (area, path fragments of its functions),
first match wins; the rest is "other"."""


def _areas(stats: Any) -> dict[str, float]:
    """Seconds of own time (``tottime``) per :data:`AREAS` entry of a
    :class:`pstats.Stats`, plus ``"other"`` and ``"total"``."""
    out = {name: 0.0 for name, _frags in AREAS}
    out["other"] = 0.0
    for (path, _line, _fn), (_cc, _nc, tt, _ct, _callers) in stats.stats.items():
        for name, frags in AREAS:
            if any(f in path for f in frags):
                out[name] += tt
                break
        else:
            out["other"] += tt
    out["total"] = sum(out.values())
    return out


def _profile(cc: Any, plan: Any, **kw: Any) -> dict[str, Any]:
    """One run under ``cProfile``: its time per area and the ten functions
    with the most own time."""
    import cProfile
    import pstats

    prof = cProfile.Profile()
    prof.enable()
    try:
        simulate(cc, plan, seed=0, options=SimOptions(**kw))
    finally:
        prof.disable()
    st = pstats.Stats(prof)
    top = sorted(st.stats.items(), key=lambda kv: -kv[1][2])[:10]  # type: ignore[attr-defined]
    return {
        "areas": _areas(st),
        "top": [
            {
                "function": f"{Path(path).name}:{line}({fn})" if path != "~" else fn,
                "calls": int(v[1]),
                "own_s": float(v[2]),
            }
            for (path, line, fn), v in top
        ],
    }


_CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
import workcell
assert workcell.__file__.startswith(sys.argv[1]), workcell.__file__
from scheduler.schedule import Schedule
from workcell import compile_cell, load_example
from workcell.sim.harness.options import SimOptions
from workcell.sim.harness.simulate import simulate
job = json.loads(open(sys.argv[2]).read())
cc = compile_cell(load_example(job["cell"]))
plan = Schedule(np.array(job["mode"], dtype=np.int64), np.array(job["start"]),
                np.array(job["end"]), tuple(np.array(w) for w in job["waits"]),
                np.array(job["blocking"]))
simulate(cc, plan, seed=0, options=SimOptions(monitor=False))
print("ready", flush=True)
for line in sys.stdin:
    kw = json.loads(line)
    c0 = time.process_time(); t0 = time.perf_counter()
    r = simulate(cc, plan, seed=0, options=SimOptions(**kw))
    wall = time.perf_counter() - t0; cpu = time.process_time() - c0
    m = r.metrics
    print(json.dumps({"wall_s": wall, "cpu_s": cpu, "simulated_s": float(m.executed_makespan),
                      "events": int(m.events), "ticks": int(m.ticks)}), flush=True)
"""
"""The baseline's process: the same plan, one run per line of keywords."""


def measure(
    seed: int,
    cell: str,
    scenarios: int,
    repeat: int,
    evaluations: int,
    tick: float,
    cap: float,
    baseline: str = "",
) -> dict[str, Any]:
    """The whole table, side by side on one plan: the speed rows (and the
    baseline revision's, alternating), their profiles, and the fault
    scenarios with and without re-solving (one sweep run)."""
    t0 = time.perf_counter()
    cc = compile_cell(load_example(cell))
    compile_s = time.perf_counter() - t0
    p = cc.problem
    r = solve(
        p, "tree", time_limit=None, seed=seed, options=TreeOptions(max_evaluations=evaluations)
    )
    if r.schedule is None:
        raise MultiarmError(
            f"cell {cell!r}: the tree search found no plan in {evaluations} decodes"
        )
    plan = r.schedule
    planned = validate(p, plan)
    # warm caches and compiled code once
    simulate(cc, plan, seed=0, options=SimOptions(monitor=False))
    levels = {k: {**v, "tick": tick} if "tick" in v else dict(v) for k, v in LEVELS.items()}
    child = None
    if baseline:
        job = {
            "cell": cell,
            "mode": np.asarray(plan.mode).tolist(),
            "start": np.asarray(plan.start).tolist(),
            "end": np.asarray(plan.end).tolist(),
            "waits": [np.asarray(w).tolist() for w in plan.waits],
            "blocking": np.asarray(plan.blocking).tolist(),
        }
        child = RevisionProcess(baseline, _CHILD, json.dumps(job).encode())
    rows: dict[str, dict[str, Any]] = {}
    base: dict[str, dict[str, Any]] = {}
    try:
        for level, kw in levels.items():
            print(f"bench_sim: {level}", file=sys.stderr, flush=True)
            n = repeat if level != "tick" else max(1, repeat - 1)
            runs, theirs = [], []
            for _ in range(n):  # alternating: the baseline's run, then this one's
                if child is not None:
                    theirs.append(child.ask(json.dumps(kw)))
                try:
                    runs.append(_speed(cc, plan, 1, **kw))
                except MultiarmError as exc:  # the monitor stopped the run: say so
                    runs.append({"error": str(exc)})
                    break
            ok = [x for x in runs if "error" not in x]
            rows[level] = (
                min(ok, key=lambda x: x["cpu_s"]) | {"rates": [x["rate"] for x in ok]}
                if ok
                else runs[-1]
            )
            if theirs:
                base[level] = min(theirs, key=lambda x: x["cpu_s"])
    finally:
        if child is not None:
            child.close()
    print("bench_sim: profiles", file=sys.stderr, flush=True)
    profiles = {level: _profile(cc, plan, **levels[level]) for level in ("event", "live", "tick")}
    event, ticked = rows["event"], rows["tick"]
    monitors = {"live": rows["live"], "post": rows["post"]}

    scen: list[dict[str, Any]] = []
    latencies: list[float] = []
    for label, faults in _scenarios(cc, plan, scenarios, seed):
        print(f"bench_sim: fault: {label}", file=sys.stderr, flush=True)
        with_r = _faulty_run(cc, plan, faults, seed, cap)
        without = _faulty_run(cc, plan, faults, seed, cap, resolve=False)
        latencies += with_r["latency"]
        scen.append(
            {"fault": label, "faults": faults.to_dicts(), "with": with_r, "without": without}
        )
    return {
        "cell": cell,
        "seed": seed,
        "repeat": repeat,
        "evaluations": evaluations,
        "tick": tick,
        "baseline": {"revision": child.rev, "rows": base} if child is not None else {},
        "profiles": profiles,
        "n_arms": p.n_arms,
        "n_tasks": p.n_tasks,
        "planned_makespan": planned,
        "compile_s": compile_s,
        "event_level": event,
        "tick_level": ticked,
        "monitored": monitors["live"],
        "monitored_post_run": monitors["post"],
        "targets": {
            "event_level": EVENT_TARGET,
            "monitored": LIVE_TARGET,
            "tick_level": TICK_TARGET,
        },
        "resolve_latency_ms": (np.asarray(latencies) * 1e3).tolist(),
        "scenarios": scen,
    }


def table(r: Any) -> str:
    """The Markdown tables of the one measured row."""
    event, tick, scen = r["event_level"], r["tick_level"], r["scenarios"]
    monitors = {"live": r["monitored"], "post": r["monitored_post_run"]}
    lat_ms = np.asarray(r["resolve_latency_ms"], dtype=float)
    planned, n_arms, n_tasks = r["planned_makespan"], r["n_arms"], r["n_tasks"]
    repeat = int(r["repeat"])
    budget_ms = 15.0  # simulate's default resolve_budget
    stops: list[str] = []

    def q(k: float) -> str:
        return f"{float(np.percentile(lat_ms, k)):.2f}" if lat_ms.size else "-"

    def verdict(rate: float, target: float) -> str:
        return "met" if rate >= target else f"**missed** ({rate / target:.2f} of the target)"

    def cpu_rate(m: dict[str, Any]) -> str:
        cpu = m.get("cpu_s")  # absent from results measured before it was recorded
        return f"{m['simulated_s'] / cpu:.0f}x" if cpu else "-"

    def fmt(x: float | None) -> str:
        return f"{x:.1f}" if x is not None and math.isfinite(x) else "-"

    how = f"{r['evaluations']} decodes" if "evaluations" in r else f"{r.get('time_limit', 0):g} s"
    lines = [
        f"# Simulation: {r['cell']} ({n_arms} arms, {n_tasks} tasks)",
        "",
        f"Plan: tree search, {how}, seed {r['seed']}: makespan {planned:.1f} s "
        f"(compile {r['compile_s']:.1f} s). Simulation seed 0, ideal medium. Least CPU time of "
        f"{repeat} runs (ticks: of {max(1, repeat - 1)}). One process on a shared 2-core machine.",
        "",
        "| run | simulated s | wall s | simulated s per wall s | target | simulated s per CPU s "
        "| kernel events | ticks |",
        "|---|---|---|---|---|---|---|---|",
        f"| event level (monitor off) | {event['simulated_s']:.1f} | {event['wall_s']:.3f} | "
        f"{event['rate']:.0f}x | >= {EVENT_TARGET:.0f}x: {verdict(event['rate'], EVENT_TARGET)} | "
        f"{cpu_rate(event)} | {event['events']} | {event['ticks']} |",
        f"| every {r['tick'] * 1e3:g} ms tick, all {n_arms} arms (monitor off) | "
        f"{tick['simulated_s']:.1f} | {tick['wall_s']:.3f} | {tick['rate']:.0f}x | "
        f">= {TICK_TARGET:.0f}x: {verdict(tick['rate'], TICK_TARGET)} | {cpu_rate(tick)} | "
        f"{tick['events']} | {tick['ticks']} |",
        *(
            (
                f"| event level, safety monitor on ({label}) | {m['simulated_s']:.1f} | "
                f"{m['wall_s']:.3f} | {m['rate']:.0f}x | "
                + (f">= {target:.0f}x: {verdict(m['rate'], target)}" if target is not None else "-")
                + f" | {cpu_rate(m)} | {m['events']} | {m['ticks']} |"
                if "error" not in m
                else f"| event level, safety monitor on ({label}) | - | - | - | - | the monitor "
                f"stopped the run: {m['error']} | - | - |"
            )
            for label, m, target in (
                ("live, the default", monitors["live"], LIVE_TARGET),
                ("post-run check", monitors["post"], None),
            )
        ),
        *(
            [
                "",
                f"**Incomplete runs**: without any fault, {event['failed_tasks']} of {n_tasks} "
                "tasks were reported failed, so the rates above are over a run that stopped "
                f"early ({event['simulated_s']:.1f} s simulated of the {planned:.1f} s planned).",
            ]
            if event["failed_tasks"]
            else []
        ),
        *_side_by_side(r),
        *_profile_lines(r),
        "",
        f"## Re-solving in the loop ({len(scen)} seeded fault scenarios, the same faults twice)",
        "",
        f"Re-solve latency over {lat_ms.size} re-solves: p50 {q(50)} ms, p99 {q(99)} ms "
        f"(max {float(lat_ms.max()) if lat_ms.size else math.nan:.2f} ms); "
        f"{int(np.sum(lat_ms > budget_ms))} over the {budget_ms:g} ms budget.",
        "",
        "| fault | executed makespan, re-solving (s) | failed | re-solves | "
        "executed makespan, keeping the plan (s) | failed |",
        "|---|---|---|---|---|---|",
    ]
    for sc in scen:
        w, wo = sc["with"], sc["without"]
        if w["stopped"] or wo["stopped"]:
            stops.append(
                f"{sc['fault']}: "
                + "; ".join(
                    f"{which}: {x['stopped']}"
                    for which, x in (("re-solving", w), ("keeping the plan", wo))
                    if x["stopped"]
                )
            )
        lines.append(
            f"| {sc['fault']} | {fmt(w['makespan'])} | {w['failed'] if w['failed'] is not None else '-'} | "
            f"{w['resolves'] if w['resolves'] is not None else '-'} | "
            f"{fmt(wo['makespan'])} | {wo['failed'] if wo['failed'] is not None else '-'} |"
        )
    if stops:
        lines += ["", "Runs that did not finish (-):", "", *(f"- {x}" for x in stops)]
    lines += [
        "",
        "Without re-solving the coordinator keeps the plan: late parts and stops push the "
        "following tasks back, and a failed arm's tasks and the tasks after them are reported "
        "failed while the other arms go on (the makespan is then over the tasks that ran). "
        "Without re-solving is `simulate(..., options=SimOptions(resolve=False))`.",
    ]
    return "\n".join(lines) + "\n"


_LABELS = {
    "event": "event level (monitor off)",
    "live": "event level, live monitor",
    "post": "event level, post-run check",
    "tick": "every tick (monitor off)",
}


def _side_by_side(r: Any) -> list[str]:
    """The baseline revision's speed rows beside this revision's (CPU seconds)."""
    b = r.get("baseline") or {}
    if not b:
        return []
    mine = {
        "event": r["event_level"],
        "live": r["monitored"],
        "post": r["monitored_post_run"],
        "tick": r["tick_level"],
    }
    out = [
        "",
        f"## Side by side with {b['revision']} (the same plan, runs alternating)",
        "",
        "| run | CPU s, this revision | CPU s, " + b["revision"] + " | speed-up | "
        "simulated s per CPU s, this revision | kernel events (this, " + b["revision"] + ") |",
        "|---|---|---|---|---|---|",
    ]
    for level, theirs in b["rows"].items():
        m = mine[level]
        if "error" in m or "cpu_s" not in m:
            continue
        out.append(
            f"| {_LABELS[level]} | {m['cpu_s']:.3f} | {theirs['cpu_s']:.3f} | "
            f"{theirs['cpu_s'] / m['cpu_s']:.2f}x | {m['simulated_s'] / m['cpu_s']:.0f}x | "
            f"{m['events']}, {theirs['events']} |"
        )
    return out


def _profile_lines(r: Any) -> list[str]:
    """Where a profiled run's time goes (the misses' explanation)."""
    prof = r.get("profiles") or {}
    if not prof:
        return []
    levels = [lv for lv in ("event", "live", "tick") if lv in prof]
    names = [name for name, _f in AREAS] + ["other"]
    out = [
        "",
        "## Where the time goes (one profiled run each; cProfile's own time per area, "
        "so its overhead inflates the many small calls)",
        "",
        "| area | " + " | ".join(_LABELS[lv] for lv in levels) + " |",
        "|---|" + "---|" * len(levels),
    ]
    for name in names:
        cells = []
        for lv in levels:
            a = prof[lv]["areas"]
            cells.append(f"{100 * a[name] / a['total']:.1f} %")
        out.append(f"| {name} | " + " | ".join(cells) + " |")
    out.append(
        "| profiled seconds | "
        + " | ".join(f"{prof[lv]['areas']['total']:.2f}" for lv in levels)
        + " |"
    )
    out += ["", "The functions with the most own time, event level (monitor off):", ""]
    out += ["| function | calls | own s |", "|---|---|---|"]
    out += [
        f"| `{x['function']}` | {x['calls']} | {x['own_s']:.3f} |" for x in prof["event"]["top"]
    ]
    return out


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
