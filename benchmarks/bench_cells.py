"""The built-in cells: compile time, detours, and schedule quality, side by side in one run.

A thin wrapper of two sweeps: ``benchmarks/sweeps/cells_compile.toml``
(``benchmark`` runs of the measurement functions below, one per table, each
measuring its whole comparison in one run) and ``benchmarks/sweeps/cells.toml``
(the schedules). ``python -m benchmarks.bench_cells [--quick]`` writes
``results/cells.md`` and ``results/cells.json`` (and the two Parquet files):

1. Compile time per cell (:func:`compile_times`), cold (first in the
   process: numba's one-time compiles included) and warm (again in the same
   process), and per mode.
2. Detours on ``scara4`` with arms parked at their last poses (``park =
   "last"``, :func:`detours`): every blocking query of every mode against
   every other arm parked after each of its tasks; how they were settled
   (pre-test, no contact, detour, none) and the OMPL detour times (median,
   p95) and the share solved within 100 ms.
3. The detour planner's single-state validity check on ``scara4``
   (:func:`validity_checks`: arm 0 against arm 1 parked at home, uniform
   random joints): the compiled path (compiled forward kinematics, one
   compiled bounding-capsule call, FCL only for candidates) next to the
   numpy reference path (numpy forward kinematics and matmul shape poses,
   then the same capsule test and FCL), in one run; both must give the same
   answers.
4. Schedule quality on the compiled cells: greedy, tree and CP-SAT at the
   same time limit (seed 0), makespans checked by ``scheduler.validate``
   (:func:`workcell.experiments.analysis.cells_table`).
5. The exact reference and the bounds (:func:`references`, sweep
   ``benchmarks/sweeps/cells_reference.toml``): tree at 10 s, CP-SAT's general
   model at 60 s, the no-wait reference of :mod:`scheduler.reference` at 60 s,
   the exact branch and bound of :func:`scheduler.exact.prove` (600 s or
   5,000,000 nodes, from the tree's plan), the best lower bound, which bound
   it is, whether anything is proven, and the gaps to it; the tree plan's busiest arm, its waits and its
   busiest resource (:func:`plan_loads`) say where a plan's time goes.
6. The space grid (:func:`grid_section`): the table of
   :mod:`benchmarks.bench_grid` (block size against compile time, zones,
   windows, makespan and the exact re-timing), read from its recorded runs
   with their own provenance line; ``bench_grid`` measures it (it takes
   long on ``cell8``'s exact re-timings, so this script does not run it).

The schedule sweep resumes where a previous run stopped (``--fresh`` runs it
again); the speed measurements are always taken again, unless ``--render``:
then every recorded run is kept (only a run missing from the results files
is run) and the tables are written again from them.
"""

from __future__ import annotations

import argparse
import math
import re
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.common import RESULTS, SWEEPS, output_dir, publish, run_table_sweep, sweep_arguments
from workcell import compile_cell, load_example
from workcell.oracle import CellOracle


def compile_times(seed: int, cells: tuple[str, ...] | list[str]) -> list[dict[str, Any]]:
    """Compile each built-in cell twice (cold, then warm) in this process; one row per cell.

    ``seed`` is unused (compiling is deterministic); the sweep passes one to every run.
    """
    rows = []
    for name in cells:
        cell = load_example(name)
        t0 = time.perf_counter()
        cc = compile_cell(cell)
        cold = time.perf_counter() - t0
        t0 = time.perf_counter()
        compile_cell(cell)
        warm = time.perf_counter() - t0
        m = cc.problem.n_modes
        rows.append(
            {
                "cell": name,
                "tasks": cc.problem.n_tasks,
                "modes": m,
                "cold (s)": round(cold, 2),
                "warm (s)": round(warm, 2),
                "per mode, warm (ms)": round(1000 * warm / m, 1),
                "oracle (s)": round(cc.problem.blocking.stats.seconds, 2),  # type: ignore[union-attr]
            }
        )
    return rows


def detours(seed: int, every: int = 1) -> dict[str, Any]:
    """Every blocking query of every ``every``-th mode on ``scara4`` with arms parked last.

    ``seed`` is unused (the oracle's planner is seeded by the cell file).
    """
    cell = replace(load_example("scara4"), park="last")
    cc = compile_cell(cell)
    p, o = cc.problem, cc.problem.blocking
    assert isinstance(o, CellOracle)
    t0 = time.perf_counter()
    costs = []
    for m in range(0, p.n_modes, every):
        for b in range(p.n_arms):
            for pose in [t for t in range(p.n_tasks) if p.mode_of[b, t] >= 0]:
                costs.append(o.cost(m, b, pose))
    wall = time.perf_counter() - t0
    c = np.array(costs)
    plans = np.array(o.stats.plan_seconds)
    s = o.stats
    return {
        "queries": len(costs),
        "distinct": s.queries - s.cached,
        "pre-test free": s.pretest_free,
        "checked free": s.checked_free,
        "detoured": s.detoured,
        "no detour": s.infeasible,
        "budget stops": s.budget_stops,
        "finite > 0": int(np.sum((c > 0) & np.isfinite(c))),
        "wall (s)": round(wall, 2),
        "plans": len(plans),
        "plan median (ms)": round(1000 * float(np.median(plans)), 1) if len(plans) else math.nan,
        "plan p95 (ms)": round(1000 * float(np.percentile(plans, 95)), 1)
        if len(plans)
        else math.nan,
        "plans within 100 ms": f"{float(np.mean(plans <= 0.1)):.1%}" if len(plans) else "-",
    }


def validity_checks(seed: int, states: int) -> dict[str, Any]:
    """The compiled and the numpy single-state checks on the same ``states`` random states."""
    from workcell.geometry._zone_sweep_jit import capsules_touch
    from workcell.geometry.planner import DetourPlanner, ObstacleSet

    cell = load_example("scara4")
    mover, blocker = cell.arms[0], cell.arms[1]
    ctx = DetourPlanner(
        mover, ObstacleSet.from_arm(blocker, blocker.home, 0.005), resolution=0.005, clearance=0.005
    )
    lo, hi = mover.joint_limits[:, 0], mover.joint_limits[:, 1]
    n = states
    qs = np.random.default_rng(seed).uniform(lo, hi, (n, mover.dof))
    idx = np.array([s.frame for s in mover.shapes])
    off = np.stack([s.offset for s in mover.shapes])

    def reference(q: np.ndarray) -> bool:
        row = q.reshape(1, -1)
        if not ctx._in_limits(row[0]):
            return False
        tfs = np.matmul(mover._frames_numpy(row)[:, idx], off)  # type: ignore[attr-defined]
        rot, trans = tfs[..., :3, :3], tfs[..., :3, 3]
        p0 = np.matmul(rot, ctx._local[:, 0, :, None])[..., 0] + trans
        p1 = np.matmul(rot, ctx._local[:, 1, :, None])[..., 0] + trans
        near = capsules_touch(p0, p1, ctx._rad, ctx._ob0, ctx._ob1, ctx._orad, 0.0)
        if not near[0]:
            return True
        return bool(ctx._world.first_collision("arm", tfs, "obstacles") < 0)

    for q in qs[:50]:  # warm up (numba's cache loads)
        reference(q)
        ctx.is_valid(q)
    times = {}
    answers = {}
    for name, f in (("compiled", ctx.is_valid), ("numpy reference", reference)):
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            got = [f(q) for q in qs]
            best = min(best, time.perf_counter() - t0)
        times[name] = 1e6 * best / n
        answers[name] = got
    assert answers["compiled"] == answers["numpy reference"], "the two checks disagree"
    return {
        "states": n,
        "valid": f"{float(np.mean(answers['compiled'])):.1%}",
        "compiled (us/check)": round(times["compiled"], 1),
        "numpy reference (us/check)": round(times["numpy reference"], 1),
        "speed-up": round(times["numpy reference"] / times["compiled"], 1),
    }


def plan_loads(problem: Any, schedule: Any) -> dict[str, Any]:
    """Where a plan's time goes: its busiest arm, its waits, its busiest resource.

    * busiest arm: the arm's availability plus, in start order, the travel
      into each of its tasks and the task's duration (no waits, no idle
      time);
    * waits: the sum of all waits at zone borders;
    * busiest resource: the exclusive zone, shared-zone movement or tool
      occupied longest (the union of its uses, waits inside them included).

    A plan whose makespan is far above its busiest arm's work and its
    busiest resource's occupancy spends the rest idle or waiting.
    """
    from scheduler.timing import merge_intervals

    p = problem
    arms = np.asarray(p.mode_arm)[schedule.mode]
    busiest = 0.0
    for a in range(p.n_arms):
        prev = -1
        work = float(p.arm_available[a])
        for t in sorted(np.flatnonzero(arms == a), key=lambda t: schedule.start[t]):
            work += p.setup_time(a, prev, int(t)) + float(p.mode_duration[schedule.mode[t]])
            prev = int(t)
        busiest = max(busiest, work)
    uses: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for kind, res, _task, _arm, s, e in schedule.reservation_rows(p):
        uses.setdefault((kind, res), []).append((s, e))
    occupied = {k: sum(e - s for s, e in merge_intervals(v)) for k, v in uses.items()}
    top = max(occupied, key=lambda k: occupied[k], default=None)
    return {
        "busiest arm": busiest,
        "waits": float(sum(float(np.sum(w)) for w in schedule.waits)),
        "busiest resource": "-" if top is None else f"{top[0]} {top[1]}",
        "occupied": 0.0 if top is None else occupied[top],
    }


def references(
    seed: int,
    cells: tuple[str, ...] | list[str],
    tree_time: float = 10.0,
    cpsat_time: float = 60.0,
    reference_time: float = 60.0,
    bound_time: float = 10.0,
    bound_dtime: float | None = None,
    exact_time: float = 600.0,
    exact_nodes: int | None = 5_000_000,
) -> list[dict[str, Any]]:
    """Per built-in cell, side by side in one run: the tree search, CP-SAT's
    general model, the no-wait reference and the bounds (seed ``seed``,
    2 CP-SAT workers; :mod:`scheduler.reference`).

    * tree: ``solve(p, "tree", tree_time)`` (waits allowed);
    * CP-SAT: ``solve(p, "cpsat", cpsat_time)``: the general model (waits at
      every border), its status, makespan and bound;
    * reference: :func:`scheduler.reference.solve_reference` for
      ``reference_time`` seconds, hinted with the tree's plan: the best
      schedule without waits at zone borders, proven or not, and the bound of
      the no-wait optimum;
    * best bound: the largest bound of the true problem (``lower_bound``, the
      zone-free relaxation, the overlap relaxation of :mod:`scheduler.overlap`
      and the busy-resources relaxation of :mod:`scheduler.resource_bound`
      (horizon: the shorter of the tree's plan and the reference), each stopped after ``bound_dtime`` of CP-SAT's
      deterministic time or ``bound_time`` seconds, CP-SAT's bound); the overlap relaxation is skipped ("-") with more than 20,000
      pairs of modes sharing a resource (``cell8``);
    * oracle binding: whether the blocking oracle charges any detour at all
      (:func:`scheduler.exact.oracle_binding`, every question a schedule can
      raise, "unchecked" beyond 50,000 questions; "no": the problem without
      the oracle is the true problem);
    * exact: :func:`scheduler.exact.prove` started from the tree's plan and
      the best bound, on the machine's 2 cores (``workers=2``: the mode
      assignments split into parts, each proven in a process of its own),
      stopped after ``exact_time`` seconds or ``exact_nodes`` nodes
      (deterministic; shared out evenly over the parts); run only where the oracle is not binding (else
      "not applicable"). Where it finishes, its makespan is the optimum of
      the true problem.
    """
    from scheduler import lower_bound, solve
    from scheduler.exact import oracle_binding, prove
    from scheduler.reference import solve_reference
    from scheduler.resource_bound import busy_resources_bound
    from workcell import compile_cell

    rows = []
    for name in cells:
        p = compile_cell(load_example(name)).problem
        t_audit = time.perf_counter()
        binding = oracle_binding(p, max_queries=50_000)
        t_audit = time.perf_counter() - t_audit
        lb = lower_bound(p)
        tree = solve(p, "tree", time_limit=tree_time, seed=seed)
        cp = solve(p, "cpsat", time_limit=cpsat_time, seed=seed)
        t_ref = time.perf_counter()
        ref = solve_reference(
            p,
            reference_time,
            seed,
            hint=tree.schedule,
            bound_time=bound_time,
            bound_deterministic_time=bound_dtime,
            workers=2,
        )
        t_ref = time.perf_counter() - t_ref
        # every one of these bounds the true problem (waits and detours allowed):
        # CP-SAT's general model keeps its bound only at an exact unit, even
        # when it stopped without a schedule (scheduler.cpsat.cpsat_bound)
        busy, _ = busy_resources_bound(
            p,
            bound_time,
            seed,
            max_deterministic_time=bound_dtime,
            horizon=min(tree.objective, ref.makespan),
        )
        sources = {
            "lower_bound": lb,
            "zone-free": ref.zone_free_bound,
            "overlap": ref.overlap_bound,
            "busy resources": busy,
            "cpsat": cp.bound,
        }
        ex = None
        if binding is False:
            ex = prove(
                p,
                time_limit=exact_time,
                max_nodes=exact_nodes,
                incumbent=tree.schedule,
                lower=max(sources.values()),
                workers=2,
            )
            sources["exact"] = ex.bound
        source = max(sources, key=lambda k: sources[k])
        best = sources[source]
        # proven: the true optimum when the tree's plan or the reference's
        # schedule (both validated) meets the best bound (10 ms, the
        # reference's tolerance), else the no-wait optimum when the no-wait
        # reference is solved to a proof, else nothing
        if ex is not None and ex.proven:
            proven, proof = "yes", f"{ex.seconds:.1f}"
        elif min(tree.objective, ref.makespan) - best <= 0.01:
            proven, proof = "yes", f"{t_ref:.1f}"
        elif ref.status == "optimal":
            proven, proof = "no-wait only", f"{ref.seconds:.1f}"
        else:
            proven, proof = "no", "-"

        def gap(x: float, best: float = best) -> str:
            return f"{x / best - 1:.1%}" if math.isfinite(x) and best > 0 else "-"

        loads = plan_loads(p, tree.schedule)
        rows.append(
            {
                "cell": name,
                "tasks": p.n_tasks,
                "zones": p.n_zones,
                "windows": p.n_windows,
                "oracle binding": {False: "no", True: "yes", None: "unchecked"}[binding],
                "oracle check (s)": round(t_audit, 1),
                "tree (s)": round(tree.objective, 2),
                "tree busiest arm (s)": round(loads["busiest arm"], 2),
                "tree waits (s)": round(loads["waits"], 2),
                "tree busiest resource": loads["busiest resource"],
                "occupied (s)": round(loads["occupied"], 2),
                "cpsat status": cp.status.value,
                "cpsat (s)": round(cp.objective, 2) if math.isfinite(cp.objective) else "none",
                "cpsat bound (s)": round(cp.bound, 2),
                "no-wait ref status": ref.status,
                "no-wait ref (s)": round(ref.makespan, 2)
                if math.isfinite(ref.makespan)
                else "none",
                "no-wait bound (s)": round(ref.nowait_bound, 2),
                "ref dtime": round(ref.deterministic_time, 1),
                "ref wall (s)": round(ref.seconds, 1),
                "lower_bound (s)": round(lb, 2),
                "zone-free bound (s)": round(ref.zone_free_bound, 2),
                "overlap bound (s)": round(ref.overlap_bound, 2) if ref.overlap_bound > 0 else "-",
                "busy-resources bound (s)": round(busy, 2) if busy > 0 else "-",
                "exact status": "not applicable"
                if ex is None
                else ("proven" if ex.proven else f"stopped ({ex.reason})"),
                "exact (s)": "-" if ex is None or ex.schedule is None else round(ex.makespan, 3),
                "exact nodes": "-" if ex is None else ex.nodes,
                "exact time (s)": "-" if ex is None else round(ex.seconds, 1),
                "best bound (s)": round(best, 2),
                "bound source": source,
                "proven?": proven,
                "proof time (s)": proof,
                "tree gap": gap(tree.objective),
                "tree above exact": "-"
                if ex is None or not ex.proven
                else f"{tree.objective / ex.makespan - 1:.2%}",
                "ref gap": gap(ref.makespan),
            }
        )
    return rows


def _table(rows: list[dict[str, Any]]) -> str:
    cols = list(rows[0])
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(_cell(r[c]) for c in cols) + " |" for r in rows]
    return "\n".join(out) + "\n"


def _cell(x: Any) -> str:
    return "nan" if isinstance(x, float) and math.isnan(x) else str(x)


def grid_section(out: Path) -> str:
    """The space-grid table of :mod:`benchmarks.bench_grid`, from its recorded runs.

    The runs of the current ``benchmarks/sweeps/grid.toml`` are read from
    ``out`` (a quick run's directory) or else from the published results,
    and rendered with :func:`benchmarks.bench_grid.table` under a second-level
    heading, followed by their own provenance line (when and where they ran:
    not this script's run).

    Parameters
    ----------
    out : Path
        The results directory of this run.

    Returns
    -------
    str
        Markdown; a line saying how to measure it when nothing is recorded.
    """
    import pandas as pd

    from benchmarks import bench_grid
    from workcell.experiments import load_sweep
    from workcell.experiments.analysis import measurements, sweep_note

    sweep = load_sweep(SWEEPS / "grid.toml")
    found = None
    for where in dict.fromkeys([out, RESULTS]):
        path = where / "grid.parquet"
        if not path.is_file():
            continue
        rows = pd.read_parquet(path)
        rows = rows[rows["status"] != "error"]
        # the published sweep's runs first, else a quick run's (a smoke run's directory)
        for quick, spec in ((False, sweep), (True, sweep.quick_version())):
            keys = {r.key for r in spec.runs()}
            df = rows[rows["key"].isin(keys)].reset_index(drop=True)
            if len(df):
                found = (df, quick)
                break
        if found is not None:
            break
    if found is None:
        return (
            "\n## The space grid\n\nNo grid measurements are recorded: "
            "`python -m benchmarks.bench_grid` measures them.\n"
        )
    df, quick = found
    body = bench_grid.table(measurements(df))
    body = re.sub(r"^(#+) ", r"#\1 ", body, flags=re.MULTILINE)  # every heading one level down
    command = "python -m benchmarks.bench_grid" + (" --quick" if quick else "")
    note = sweep_note(df, sweep_file="benchmarks/sweeps/grid.toml", command=command)
    return (
        "\n"
        + body
        + "\nMeasured by `bench_grid`, not by this script's run; its provenance:\n\n"
        + note
    )


def main(argv: list[str] | None = None) -> None:
    """Run both sweeps and write the tables.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    import pandas as pd

    from workcell.experiments.analysis import cells_table, measurements

    ap = argparse.ArgumentParser(description=__doc__)
    sweep_arguments(ap)
    ap.add_argument(
        "--render",
        action="store_true",
        help="keep every recorded run (speed and reference too) and write the tables"
        " again from them; only runs missing from the results files are run",
    )
    args = ap.parse_args(argv)
    if args.render and args.fresh:
        raise SystemExit("bench_cells: --render keeps the recorded runs; --fresh discards them")
    out = output_dir(args.quick)
    # the speed measurements are taken again, side by side in this run (not with --render)
    again = argparse.Namespace(**{**vars(args), "fresh": not args.render})
    speed = run_table_sweep("cells", again, out, sweep_file="cells_compile")
    sched = run_table_sweep("cells", args, out)
    refs = run_table_sweep("cells", again, out, sweep_file="cells_reference")
    head = ["family", "instance", "seed", "repetition", "load_average"]
    parts = {f: measurements(speed, f).drop(columns=head) for f in ("compile", "detours", "checks")}
    parts["reference"] = measurements(refs, "reference").drop(columns=head)
    limits = sorted({float(t) for t in sched["time_limit"].dropna()})
    md = (
        "# Built-in cells\n\nMachine: 2 cores shared with other work while this ran; times are"
        " noisy (compare the ratios in one run, not absolute times across runs).\n"
        "\n## Compile\n\n"
        + _table(parts["compile"].to_dict("records"))
        + "\n## Detours on scara4, arms parked at their last poses\n\n"
        + _table(parts["detours"].to_dict("records"))
        + "\n## Single-state validity check on scara4 (best of 3 passes)\n\n"
        + _table(parts["checks"].to_dict("records"))
        + f"\n## Schedules at {', '.join(f'{t:g}' for t in limits)} s per solver (seed 0, validated)\n\n"
        + cells_table(sched)
        + "\nThe solver's bound is its own (a proof's, where its status is optimal: the"
        " tree proves `parking` with the problem without zones); the lower bound is"
        " `scheduler.lower_bound` of the problem, the same for every solver.\n"
        + "\n## Exact reference and bounds (tree 10 s, CP-SAT 60 s, no-wait reference 60 s,"
        " zone-free and overlap relaxations 10 deterministic units or 60 s each, exact"
        " branch and bound 600 s or 5,000,000 nodes on 2 processes; seed 0, 2 CP-SAT"
        " workers)\n\n"
        + _table(parts["reference"].to_dict("records"))
        + "\nThe no-wait reference is proven only when its status says optimal; its bound"
        " bounds the no-wait optimum, the best bound bounds the true problem (waits and"
        " detours allowed); gaps are to the best bound (docs/scheduler.md, 'The exact"
        " reference on compiled cells'). An optimum of the true problem is proven only"
        " where the proven? column says yes: see"
        " docs/scheduler.md for what each bound keeps of the problem. An overlap bound '-'"
        " means none: skipped (more than 20,000 pairs of modes sharing a resource) or no"
        " solution of the relaxation within its limit; a busy-resources bound '-' means"
        " that relaxation proved nothing above 0 within its limit. ref dtime is CP-SAT's"
        " deterministic time of the no-wait solve (repeatable, unlike the wall time)."
        " bound source: which bound is the best (lower_bound: no solver; zone-free,"
        " overlap, busy resources: the CP-SAT relaxations; cpsat: the general model, at an exact unit"
        " only). proven?: 'yes' when the tree's plan or the no-wait reference's schedule"
        " meets the best bound within 10 ms (the true optimum; proof time: the"
        " reference's and the bounds' wall time), 'no-wait only' when the no-wait"
        " reference is proven (proof time: its solve), else 'no'. tree busiest arm:"
        " the most loaded arm's availability, travel and durations in the tree's plan"
        " (waits and idle time left out); tree waits: the plan's waits at zone"
        " borders; tree busiest resource: the zone, movement or tool the plan occupies"
        " longest, and for how long (occupied, waits inside its uses included). oracle"
        " binding: 'no' when the blocking oracle answers 0 to every question a schedule"
        " can raise (every mode against every other arm parked at its initial pose or at"
        " the end pose of any task it can do; scheduler.exact.oracle_binding), so that"
        " dropping it changes no schedule; oracle check: the wall time of those questions."
        " exact: scheduler.exact.prove, the branch and bound over modes, arm sequences"
        " and pairwise orders (started from the tree's plan and the best bound; run only"
        " where the oracle is not binding); exact status 'proven' means its makespan is"
        " the optimum of the true problem (proven? then says yes and proof time is its"
        " wall time); exact nodes is its deterministic work; bound source 'exact': the"
        " proven optimum. tree above exact: the tree's 10 s plan against that optimum.\n"
        + grid_section(out)
    )
    both = pd.concat([speed, sched, refs], ignore_index=True)
    path = publish(
        "cells",
        both,
        md,
        out,
        sweeps=("cells_compile", "cells", "cells_reference"),
        quick=args.quick,
        flags="--fresh",
        extra={
            "compile": parts["compile"].to_dict("records"),
            "detours": parts["detours"].to_dict("records"),
            "checks": parts["checks"].to_dict("records"),
            "reference": parts["reference"].to_dict("records"),
            # --render: the tables were written again from recorded runs; the
            # machine block above is the render's, the runs' own is in their note
            "rendered_from_recorded_runs": bool(args.render),
        },
        rows=sched.drop(columns=["dependencies"]),
    )
    print(path.read_text())


if __name__ == "__main__":
    main()
