"""The space grid as a measured knob: block size against compile time, zones and makespan.

The compile keeps moving arms apart outside the SDL zones with a space grid
(:mod:`workcell.geometry.reach`, S2.12's coarse-grid compromise): every block
of side ``grid`` that modes of two arms touch becomes an exclusive zone. This
script compiles each built-in cell with the grid off and at several block
sizes, side by side in one run (:func:`measure`, one ``benchmark`` run per
cell), and reports per block size:

* compile time (best of two; the cell compiled once before, so numba's
  one-time compiles are not in any column), zones (of which grid blocks) and windows;
* the tree search's makespan at a fixed work limit (``max_evaluations``, so
  the number reproduces on any machine), seed 0, checked by
  ``scheduler.validate``;
* **monitor**: the plan executed by ``workcell.simulate`` with the
  coordinator's live geometric check off, so that only the plan keeps arms
  apart: ``clean`` when the independent safety monitor saw no contact, else
  ``collision`` (``SafetyViolation``);
* **executed**: the makespan of the same plan simulated with the defaults
  (the coordinator's geometric check on stops an arm about to touch another,
  so an unsafe plan runs longer than planned);
* **exact**: the same plan re-timed under exact separation
  (:func:`workcell.exactcheck.retime_exact`: each arm's tasks, order,
  modes and waits kept, every task at its earliest start at which the arms'
  timed motions, checked pairwise with FCL on densely sampled, padded
  shapes, never touch; SDL zones, tools and precedences kept, the grid
  blocks not), its ratio to the grid plan, the seconds it took, and the
  monitor's verdict on it (simulated with the geometric check off);
* **at 10 s** (``time_limit`` in the sweep file): the tree search again at a
  wall-clock limit (seed 0, no work limit), the plan simulated under the
  monitor alone and re-timed as above, in a second table with its own
  price of the grid (these makespans depend on the machine's speed and load);
* **detours off**: the makespan at the same work limit when the blocking
  oracle plans no OMPL detours (``CompileOptions(detours=False)``), at the
  default block size.

A thin wrapper of ``benchmarks/sweeps/grid.toml``; it measures again on every
call. ``python -m benchmarks.bench_grid [--quick]`` writes
``results/grid.md``, ``grid.json``, ``grid.parquet`` and the plot
``docs/images/grid.png`` (not with ``--quick``).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

from benchmarks.common import output_dir, publish, run_table_sweep, sweep_arguments

NAME = "grid"
DOCS_PLOT = Path(__file__).resolve().parents[1] / "docs" / "images" / "grid.png"


def _run(cc: Any, evaluations: int | None, time_limit: float | None = None) -> tuple[float, Any]:
    """The tree's plan at a work limit (``evaluations``) or a wall-clock limit, and
    its validated makespan (nan and None without a plan)."""
    from scheduler import TreeOptions, solve, validate

    r = solve(
        cc, "tree", time_limit=time_limit, seed=0, options=TreeOptions(max_evaluations=evaluations)
    )
    if r.schedule is None:
        return math.nan, None
    return validate(cc, r.schedule), r.schedule


def _monitor(cc: Any, plan: Any) -> tuple[str, float, int]:
    """The plan under the safety monitor alone, then with the defaults
    (verdict, executed makespan, tasks done)."""
    from workcell import SimOptions, simulate
    from workcell.sim.harness.monitor import SafetyViolation

    try:
        simulate(cc, plan, seed=0, options=SimOptions(geometry_guard=False))
        verdict = "clean"
    except SafetyViolation:
        verdict = "collision"
    m = simulate(cc, plan, seed=0).metrics
    return verdict, float(m.executed_makespan), int(m.done_tasks)


def _exact(cc: Any, plan: Any) -> dict[str, Any]:
    """The plan re-timed under exact separation, and the monitor's verdict on it."""
    from multiarm.errors import MultiarmError
    from workcell import SimOptions, simulate
    from workcell.exactcheck import retime_exact
    from workcell.sim.harness.monitor import SafetyViolation

    t0 = time.perf_counter()
    try:
        ex = retime_exact(cc, plan)
    except MultiarmError as exc:  # e.g. an arm parked in another's way for good
        return {
            "exact": math.nan,
            "exact_s": round(time.perf_counter() - t0, 2),
            "exact_monitor": f"failed: {type(exc).__name__}",
            "exact_fcl": 0,
        }
    seconds = time.perf_counter() - t0
    try:
        m = simulate(ex.compiled, ex.schedule, seed=0, options=SimOptions(geometry_guard=False))
        verdict = (
            "clean"
            if abs(float(m.metrics.executed_makespan) - ex.makespan) < 1e-6
            else (f"clean, ran {float(m.metrics.executed_makespan):.1f}")
        )
    except SafetyViolation:
        verdict = "collision"
    if ex.unresolved:
        verdict += f" ({len(ex.unresolved)} tasks within 4 cm kept)"
    return {
        "exact": round(ex.makespan, 3),
        "exact_s": round(seconds, 2),
        "exact_monitor": verdict,
        "exact_fcl": ex.fcl_checks,
        "exact_unresolved": len(ex.unresolved),
    }


def _timed(cc: Any, time_limit: float, exact: bool) -> dict[str, Any]:
    """The columns of the plan found at a wall-clock limit (see :func:`measure`)."""
    makespan, plan = _run(cc, None, time_limit)
    out: dict[str, Any] = {"time_limit": time_limit, "makespan_t": round(makespan, 3)}
    if plan is None:
        return out | {"monitor_t": "-", "exact_t": math.nan, "exact_t_monitor": "-"}
    out["monitor_t"] = _monitor(cc, plan)[0]
    if exact:
        e = _exact(cc, plan)
        out |= {"exact_t": e["exact"], "exact_t_monitor": e["exact_monitor"]}
    return out


def measure(
    seed: int,
    cell: str,
    grids: list[float],
    evaluations: int,
    detours_off: bool = True,
    exact: bool = True,
    compile_runs: int = 2,
    time_limit: float | None = None,
) -> list[dict[str, Any]]:
    """One row per block size (0: off) of ``cell``, all in this process.

    ``seed`` is unused (compile and search are seeded with 0 and work-limited).
    ``exact``: also re-time each plan under exact separation (:func:`_exact`).
    ``compile_runs``: compiles per block size, the best one timed.
    ``time_limit``: also plan with the tree at this wall-clock limit (seed 0, no
    work limit: the makespan the issue's "tree at 10 s" asks for, which depends on
    the machine's speed and load), with the columns ``makespan_t``, ``monitor_t``
    and, with ``exact``, ``exact_t`` and ``exact_t_monitor``.
    """
    from workcell import CompileOptions, compile_cell, load_example

    c = load_example(cell)
    compile_cell(c, options=CompileOptions(grid=0))  # warm: numba's one-time compiles
    rows = []
    for g in grids:
        seconds = math.inf
        for _ in range(compile_runs):  # the best: the machine's load only ever adds
            t0 = time.perf_counter()
            cc = compile_cell(c, options=CompileOptions(grid=float(g)))
            seconds = min(seconds, time.perf_counter() - t0)
        p = cc.problem
        makespan, plan = _run(cc, evaluations)
        verdict, executed, done = _monitor(cc, plan) if plan is not None else ("-", math.nan, 0)
        extra = _exact(cc, plan) if exact and plan is not None else {}
        if time_limit is not None:
            extra |= _timed(cc, float(time_limit), exact)
        rows.append(
            {
                "cell": cell,
                "grid": float(g),
                "compile_s": round(seconds, 2),
                "compile_runs": compile_runs,
                "zones": p.n_zones,
                "grid_zones": sum(z.startswith("grid_") for z in p.zone_names),
                "windows": p.n_windows,
                "evaluations": evaluations,
                "makespan": round(makespan, 3),
                "monitor": verdict,
                "executed": round(executed, 3),
                "tasks": p.n_tasks,
                "done": done,
                **extra,
            }
        )
    if detours_off:
        cc = compile_cell(c, options=CompileOptions(detours=False))
        makespan, _ = _run(cc, evaluations)
        for r in rows:
            r["default_grid"] = cc.options.grid
            r["makespan_detours_off"] = round(makespan, 3)
    return rows


def _runs_text(m: Any) -> str:
    if "compile_runs" not in m.columns:
        return "two"
    by: dict[int, list[str]] = {}
    for c, g in m.groupby("cell", sort=False):
        by.setdefault(int(g["compile_runs"].iloc[0]), []).append(str(c))
    if len(by) == 1:
        n = next(iter(by))
        return {1: "one", 2: "two"}.get(n, str(n))
    return "; ".join(f"{n} for {', '.join(cells)}" for n, cells in sorted(by.items(), reverse=True))


CELL_ORDER = ("supersigma", "scara4", "cell8")
"""The order of the cells in the table and the plot (the sweep file's), whatever
order the runs finished in."""


def _ordered(m: Any) -> Any:
    rank = {c: i for i, c in enumerate(CELL_ORDER)}
    key = m["cell"].map(lambda c: rank.get(str(c), len(rank)))
    return m.assign(_rank=key).sort_values(["_rank", "grid"], kind="stable").drop(columns="_rank")


def _has_exact(m: Any) -> bool:
    return "exact" in m.columns


def table(m: Any) -> str:
    """The Markdown table of the measured rows."""
    m = _ordered(m)
    ev = ", ".join(str(int(e)) for e in sorted(set(m["evaluations"])))
    ex = _has_exact(m)
    lines = [
        "# The space grid: block size against compile time, zones and makespan",
        "",
        "Per built-in cell and block size (off: no grid). Compile time (best of "
        f"{_runs_text(m)}) side "
        f"by side in one run; tree search makespan at a work limit of {ev} evaluations, "
        "seed 0 (reproducible), checked by `scheduler.validate`; *x 0.3*: makespan over the "
        "0.3 m grid's; *monitor*: the plan simulated with the coordinator's geometric check "
        "off, so only the plan keeps arms apart (`collision`: the safety monitor raised "
        "`SafetyViolation`); *executed*: the same plan simulated with the defaults (an arm "
        "about to touch another is stopped, so an unsafe plan runs longer or some of its "
        "tasks fail: *done* counts the tasks completed).",
    ]
    if ex:
        lines += [
            "",
            "*exact*: the same plan re-timed under exact separation "
            "(`workcell.exactcheck.retime_exact`: each arm's tasks, order, modes and waits "
            "kept; every task at its earliest start at which the arms' timed motions, their "
            "shapes grown by 2 cm and sampled so that no point moves more than 2 cm between "
            "samples, checked pairwise with FCL, never touch; SDL zones, tools, precedences "
            "and travel kept, grid blocks not); *x plan*: exact over the grid plan's makespan; "
            "*exact monitor*: the re-timed plan simulated with the geometric check off "
            "(`clean`: no contact, and it ran exactly as re-timed); *re-time*: seconds the "
            "re-timing took. On the grid-off row the plan collides, and the re-timing first "
            "moves the touching tasks apart (later if need be); a task that touches another "
            "arm under this padded check at every start it could take (parked arms closer "
            "than 4 cm) keeps its time and is counted, the monitor judging it.",
        ]
    head = (
        "| cell | grid (m) | compile (s) | zones (grid) | windows | makespan (s) | x 0.3 "
        "| monitor | executed (s) | done |"
    )
    rule = "|---|---|---|---|---|---|---|---|---|---|"
    if ex:
        head += " exact (s) | x plan | exact monitor | re-time (s) |"
        rule += "---|---|---|---|"
    lines += ["", head, rule]
    for cell, grp in m.groupby("cell", sort=False):
        ref = grp[grp["grid"] == 0.3]["makespan"]
        base = float(ref.iloc[0]) if len(ref) else math.nan
        for _, r in grp.iterrows():
            g = "off" if r["grid"] == 0 else f"{r['grid']:g}"
            ratio = r["makespan"] / base if base == base else math.nan
            row = (
                f"| {cell} | {g} | {r['compile_s']:.2f} | {r['zones']} ({r['grid_zones']}) | "
                f"{r['windows']} | {r['makespan']:.1f} | {ratio:.3f} | {r['monitor']} | "
                f"{r['executed']:.1f} | {r['done']}/{r['tasks']} |"
            )
            if ex:
                row += (
                    f" {r['exact']:.1f} | {r['exact'] / r['makespan']:.3f} | "
                    f"{r['exact_monitor']} | {r['exact_s']:.1f} |"
                )
            lines.append(row)
    if ex:
        lines += [
            "",
            "The price of the grid: per cell, the best makespan the tree search found at "
            "a safe grid, and the best exact re-timing of any of those plans (the grid-off "
            "row is left out: its plan is not safe as planned).",
            "",
            "| cell | best plan (s) | at grid (m) | best exact (s) | of the plan at (m) | "
            "plan over exact |",
            "|---|---|---|---|---|---|",
        ]
        for cell, grp in m.groupby("cell", sort=False):
            on = grp[grp["grid"] > 0]
            bp = on.loc[on["makespan"].idxmin()]
            be = on.loc[on["exact"].idxmin()]
            lines.append(
                f"| {cell} | {bp['makespan']:.1f} | {bp['grid']:g} | {be['exact']:.1f} | "
                f"{be['grid']:g} | {bp['makespan'] / be['exact']:.3f} |"
            )
    if "makespan_t" in m.columns:
        lines += _timed_table(m)
    if "makespan_detours_off" in m.columns:
        lines += [
            "",
            "Detours off (`CompileOptions(detours=False)`: a mode touching a parked arm is "
            "blocked, no OMPL path is planned), default grid, same work limit:",
            "",
            "| cell | grid (m) | makespan, detours on (s) | makespan, detours off (s) |",
            "|---|---|---|---|",
        ]
        for cell, grp in m.groupby("cell", sort=False):
            if grp["makespan_detours_off"].isna().all():
                continue
            d = float(grp["default_grid"].iloc[0])
            on = grp[grp["grid"] == d]["makespan"]
            lines.append(
                f"| {cell} | {d:g} | {float(on.iloc[0]) if len(on) else math.nan:.1f} | "
                f"{float(grp['makespan_detours_off'].iloc[0]):.1f} |"
            )
    return "\n".join(lines) + "\n"


def _timed_table(m: Any) -> list[str]:
    """The rows of the plans found at a wall-clock limit, beside the work-limited ones."""
    limits = ", ".join(f"{t:g}" for t in sorted(set(m["time_limit"].dropna())))
    ex = "exact_t" in m.columns
    lines = [
        "",
        f"## The tree at {limits} s",
        "",
        f"The same compiles, the tree search at a wall-clock limit of {limits} s (seed 0, no "
        "work limit; these makespans depend on the machine's speed and load, the work-limited "
        "ones above do not); *work-limited*: the makespan above; *monitor*: as above, for this "
        "plan" + ("; *exact*: this plan re-timed under exact separation, as above." if ex else "."),
        "",
        "| cell | grid (m) | windows | makespan (s) | x 0.3 | work-limited (s) | monitor |"
        + (" exact (s) | x plan | exact monitor |" if ex else ""),
        "|---|---|---|---|---|---|---|" + ("---|---|---|" if ex else ""),
    ]
    for cell, grp in m.groupby("cell", sort=False):
        ref = grp[grp["grid"] == 0.3]["makespan_t"]
        base = float(ref.iloc[0]) if len(ref) else math.nan
        for _, r in grp.iterrows():
            g = "off" if r["grid"] == 0 else f"{r['grid']:g}"
            row = (
                f"| {cell} | {g} | {r['windows']} | {r['makespan_t']:.1f} | "
                f"{r['makespan_t'] / base:.3f} | {r['makespan']:.1f} | {r['monitor_t']} |"
            )
            if ex:
                row += (
                    f" {r['exact_t']:.1f} | {r['exact_t'] / r['makespan_t']:.3f} | "
                    f"{r['exact_t_monitor']} |"
                )
            lines.append(row)
    if ex:
        lines += [
            "",
            f"The price of the grid at {limits} s: as above, for these plans.",
            "",
            "| cell | best plan (s) | at grid (m) | best exact (s) | of the plan at (m) | "
            "plan over exact |",
            "|---|---|---|---|---|---|",
        ]
        for cell, grp in m.groupby("cell", sort=False):
            on = grp[(grp["grid"] > 0) & grp["makespan_t"].notna()]
            if not len(on):
                continue
            bp = on.loc[on["makespan_t"].idxmin()]
            be = on.loc[on["exact_t"].idxmin()]
            lines.append(
                f"| {cell} | {bp['makespan_t']:.1f} | {bp['grid']:g} | {be['exact_t']:.1f} | "
                f"{be['grid']:g} | {bp['makespan_t'] / be['exact_t']:.3f} |"
            )
    return lines


def plot(m: Any, path: Path) -> Path:
    """Makespan against block size per cell (relative to the best exact re-timing),
    with the exact re-timings and the grid-off plan as references; compile time."""
    from matplotlib.figure import Figure

    m = _ordered(m)
    ex = _has_exact(m)
    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    ax_m, ax_c = fig.subplots(1, 2)
    for cell, grp in m.groupby("cell", sort=False):
        on = grp[grp["grid"] > 0].sort_values("grid")
        if ex:
            base = float(on["exact"].min())
        else:
            ref = grp[grp["grid"] == 0.3]["makespan"]
            base = float(ref.iloc[0]) if len(ref) else float(on["makespan"].iloc[0])
        (line,) = ax_m.plot(on["grid"], on["makespan"] / base, "o-", label=f"{cell}: plan")
        col = line.get_color()
        if ex:
            ax_m.plot(
                on["grid"],
                on["exact"] / base,
                "x--",
                color=col,
                linewidth=1,
                label=f"{cell}: same plan, exact",
            )
            ax_m.axhline(1.0, color=col, linestyle="-", linewidth=0.6, alpha=0.5)
        off = grp[grp["grid"] == 0]
        if len(off):
            ax_m.axhline(
                float(off["makespan"].iloc[0]) / base, color=col, linestyle=":", linewidth=1
            )
        ax_c.plot(on["grid"], on["compile_s"], "o-", color=col, label=str(cell))
    ax_m.set_xlabel("block side (m)")
    if ex:
        ax_m.set_ylabel("makespan / best exact re-timing")
        ax_m.set_title(
            "plan (solid), its exact re-timing (dashed), grid off (dotted, unsafe)", fontsize=8
        )
    else:
        ax_m.set_ylabel("makespan / makespan at 0.3 m")
        ax_m.set_title("plan length (dotted: grid off, unsafe)", fontsize=9)
    ax_m.legend(fontsize=7)
    ax_c.set_xlabel("block side (m)")
    ax_c.set_ylabel("compile time (s)")
    ax_c.set_yscale("log")
    ax_c.set_title("compile time (log scale)", fontsize=9)
    ax_c.legend(fontsize=7)
    for ax in (ax_m, ax_c):
        ax.grid(linewidth=0.3)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    return path


def main(argv: list[str] | None = None) -> Path:
    """Run the sweep, write the table and the plot.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import measurements

    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sweep_arguments(ap, fresh=True)
    args = ap.parse_args(argv)
    out = output_dir(args.quick)
    df = run_table_sweep(NAME, args, out)
    m = measurements(df)
    png = plot(m, out / "grid.png" if args.quick else DOCS_PLOT)
    where = png.relative_to(DOCS_PLOT.parents[2]) if png == DOCS_PLOT else png.name
    path = publish(NAME, df, table(m), out, quick=args.quick, rows=m, extra={"plot": str(where)})
    print(path.read_text())
    return path


if __name__ == "__main__":
    main()
