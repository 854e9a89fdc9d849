"""Delay distributions of the network media against the CSMA/DCR bound (S2.8, S2.9).

Three parts, side by side in one run:

1. **Contention rounds** (batch simulators): every round starts at a sampling
   tick; the coordinator (station 0) has a trajectory frame of 26 + 2 + 24 p
   bytes (p = 1..5), each robot a 51-byte position report, each present with
   probability ``load``. CSMA/DCR (:func:`~workcell.sim.network.dcr_rounds`)
   and Ethernet CSMA/CD (:func:`~workcell.sim.network.ethernet_rounds`,
   numba) over stations x load; p50, p99 and max delay against
   :func:`workcell.dcr_bound` for the same station count, and the share of
   frames over it. At 10 stations and full load both run ``--big`` rounds
   (10^6 by default).
2. **Event-level media** (:func:`workcell.sim.network.make_medium`): the same
   traffic, one round per 1 ms sampling period with up to 20 us of jitter,
   for ``--ticks`` periods, on CSMA/DCR, Ethernet, Multibus II, serial star
   and serial bus (9600 b/s). A medium that cannot carry the traffic builds
   a queue: its delays grow with the run's length.
3. **Makespan of one cell and schedule over each medium**, with
   ``workcell.simulate`` (needs :mod:`workcell.sim.run`), and under the
   SUPERSIGMA central unit and MICROBUS
   (:func:`workcell.sim.supersigma.run_schedule`: tasks as stepper moves,
   zone hand-overs as flags).

A plot of the delay tails (complementary CDF) goes to
``results/network_tails.png``. Results: ``results/network.json`` and
``network.md``.

Run: ``python -m benchmarks.bench_network [--rounds 100000] [--big 1000000]
[--ticks 200] [--quick]``.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import time
from typing import Any

import numpy as np

from benchmarks.common import RESULTS, write
from multiarm.types import FloatArray
from workcell.sim.kernel import Kernel
from workcell.sim.medium import Frame, trajectory_bytes
from workcell.sim.network import (
    MEDIA,
    REDUCED,
    dcr_bound,
    dcr_rounds,
    ethernet_rounds,
    make_medium,
)

SEED = 0
US = 1e-6
CELL = "scara4"
EVENT_MEDIA = ("csma-dcr", "ethernet", "multibus2", "serial-star", "serial-bus")


def stats(d: FloatArray, bound: float) -> dict[str, Any]:
    """p50, p99, max (us), frames, drops and the share over ``bound``."""
    ok = d[~np.isnan(d)]
    return {
        "frames": int(d.size),
        "drops": int(np.isnan(d).sum()),
        "p50_us": float(np.percentile(ok, 50)) / US if ok.size else float("nan"),
        "p99_us": float(np.percentile(ok, 99)) / US if ok.size else float("nan"),
        "max_us": float(ok.max()) / US if ok.size else float("nan"),
        "over_bound": float(np.mean(ok > bound)) if ok.size else float("nan"),
    }


def chunked(fn: Any, rounds: int, chunk: int, **kw: Any) -> FloatArray:
    """Run a batch simulator in chunks of rounds with one seeded Generator."""
    rng = np.random.default_rng(kw.pop("seed"))
    parts = []
    left = rounds
    while left > 0:
        n = min(chunk, left)
        parts.append(fn(n, seed=rng, **kw))
        left -= n
    return np.concatenate(parts)


def rounds_part(
    stations: list[int], loads: list[float], rounds: int, big: int
) -> tuple[list[dict[str, Any]], dict[str, FloatArray]]:
    rows: list[dict[str, Any]] = []
    tails: dict[str, FloatArray] = {}
    for n in stations:
        bound = dcr_bound(n_stations=n)
        for load in loads:
            r = big if (n == 10 and load == 1.0) else rounds
            for name, fn in (("csma-dcr", dcr_rounds), ("ethernet", ethernet_rounds)):
                t0 = time.perf_counter()
                d = chunked(fn, r, 100_000, n_stations=n, load=load, seed=SEED)
                wall = time.perf_counter() - t0
                row = {
                    "medium": name,
                    "stations": n,
                    "load": load,
                    "rounds": r,
                    "bound_us": bound / US,
                    **stats(d, bound),
                    "wall_s": wall,
                }
                rows.append(row)
                print(row, flush=True)
                if n == 10 and load in (0.25, 1.0):
                    tails[f"{name} N=10 load {load:g}"] = d
    return rows, tails


def variants_part(rounds: int) -> list[dict[str, Any]]:
    """10 stations at full load: the reduced parameters (S2.9) and a slotted
    resolution that charges each silent station one slot."""
    rows: list[dict[str, Any]] = []
    cases: list[tuple[str, Any, dict[str, Any], float]] = [
        ("csma-dcr, reduced (20 Mb/s, IFS 3.2, slot 3.2)", dcr_rounds, REDUCED, 1.0),
        ("ethernet, reduced (20 Mb/s, IFS 3.2, slot 3.2)", ethernet_rounds, REDUCED, 1.0),
        ("csma-dcr, silent slot 51.2 us, load 0.3", dcr_rounds, {"empty_slot": 51.2e-6}, 0.3),
    ]
    for label, fn, kw, load in cases:
        bound = dcr_bound(**{k: v for k, v in kw.items() if k != "empty_slot"})
        t0 = time.perf_counter()
        d = chunked(fn, rounds, 100_000, n_stations=10, load=load, seed=SEED, **kw)
        row = {
            "medium": label,
            "stations": 10,
            "load": load,
            "rounds": rounds,
            "bound_us": bound / US,
            **stats(d, bound),
            "wall_s": time.perf_counter() - t0,
        }
        rows.append(row)
        print(row, flush=True)
    return rows


def event_delays(name: str, n: int, load: float, ticks: int, seed: int) -> tuple[FloatArray, int]:
    """Delays of one event-level run: a round per 1 ms period, jitter 20 us."""
    k = Kernel()
    m = make_medium(name, k, n, seed=seed)
    rng = np.random.default_rng(seed)
    period, jitter = 1e-3, 20e-6
    for tick in range(ticks):
        for s in range(n):
            if rng.random() >= load:
                continue
            if s == 0:
                pts = int(rng.integers(1, 6))
                f = Frame(0, int(rng.integers(1, n)), trajectory_bytes(pts), "trajectory")
            else:
                f = Frame(s, 0, 51, "position")
            k.schedule(tick * period + float(rng.uniform(0.0, jitter)), m.send, f, absolute=True)
    k.run()
    return m.stats.delays(), m.stats.drops


def event_part(
    stations: list[int], loads: list[float], ticks: int
) -> tuple[list[dict[str, Any]], dict[str, FloatArray]]:
    rows: list[dict[str, Any]] = []
    tails: dict[str, FloatArray] = {}
    for n in stations:
        bound = dcr_bound(n_stations=n)
        for load in loads:
            for name in EVENT_MEDIA:
                t0 = time.perf_counter()
                d, drops = event_delays(name, n, load, ticks, SEED)
                wall = time.perf_counter() - t0
                row = {
                    "medium": name,
                    "stations": n,
                    "load": load,
                    "ticks": ticks,
                    "bound_us": bound / US,
                    **stats(d, bound),
                    "dropped": drops,
                    "wall_s": wall,
                }
                rows.append(row)
                print(row, flush=True)
                if n == 10 and load == 1.0:
                    tails[f"{name} (event level)"] = d
    return rows, tails


def makespan_part(quick: bool) -> tuple[list[dict[str, Any]], str]:
    """The same cell and schedule over every medium (needs workcell.sim.run),
    and under the SUPERSIGMA central unit (``run_schedule``)."""
    import scheduler
    import workcell
    from workcell.sim.supersigma import run_schedule

    cell = workcell.load_example(CELL)
    compiled = workcell.compile_cell_detailed(cell)
    problem = compiled.problem
    sched = scheduler.solve(problem, solver="greedy", time_limit=5.0, seed=SEED).schedule
    if sched is None:
        return [], f"no greedy schedule for {CELL}"
    rows: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    ccu = run_schedule(problem, sched)
    rows.append(
        {
            "medium": "CCU + MICROBUS (run_schedule)",
            "planned_makespan": float(sched.makespan),
            "executed_makespan": ccu.makespan,
            "messages": ccu.report.commands,
            "p99_delay_ms": 0.1,  # one command holds the bus 100 us
            "max_delay_ms": 0.1,
            "failed_tasks": 0,
            "wall_s": time.perf_counter() - t0,
        }
    )
    print(rows[-1], flush=True)
    if importlib.util.find_spec("workcell.sim.run") is None:
        return rows, "workcell.sim.run (workcell.simulate) is not available in this checkout"
    # imported by name: the simulation is another module's concern
    simulate: Any = (
        getattr(workcell, "simulate", None) or importlib.import_module("workcell.sim.run").simulate
    )
    for name in ("ideal", "csma-dcr") if quick else MEDIA:
        t0 = time.perf_counter()
        try:
            res = simulate(compiled, sched, seed=SEED, medium=name)
        except Exception as exc:  # reported in the table, not hidden
            rows.append({"medium": name, "error": f"{type(exc).__name__}: {exc}"})
            print(rows[-1], flush=True)
            continue
        wall = time.perf_counter() - t0
        m = res.metrics
        delays = np.asarray(m.message_delay, dtype=np.float64)
        rows.append(
            {
                "medium": name,
                "planned_makespan": float(m.planned_makespan),
                "executed_makespan": float(m.executed_makespan),
                "messages": int(delays.size),
                "p99_delay_ms": float(np.percentile(delays, 99)) * 1e3 if delays.size else 0.0,
                "max_delay_ms": float(delays.max()) * 1e3 if delays.size else 0.0,
                "failed_tasks": int(m.failed_tasks)
                if not isinstance(m.failed_tasks, list | tuple)
                else len(m.failed_tasks),
                "wall_s": wall,
            }
        )
        print(rows[-1], flush=True)
    return rows, ""


def plot(tails: dict[str, FloatArray], bound: float, path: Any) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, event in zip(axes, (False, True), strict=True):
        for label, d in tails.items():
            if ("event level" in label) != event:
                continue
            ok = np.sort(d[~np.isnan(d)]) / US
            if ok.size == 0:
                continue
            n = ok.size  # a few thousand points, dense in the tail
            ranks = np.unique(
                np.concatenate(
                    [np.linspace(0, n - 1, 2000), n - np.logspace(0, np.log10(n), 2000)]
                ).astype(np.int64)
            )
            ax.loglog(ok[ranks], 1.0 - ranks / n, label=label, lw=1.3)
        ax.axvline(bound / US, color="k", ls="--", lw=1, label=f"dcr_bound {bound / US:.1f} us")
        ax.set_xlabel("delay (us)")
        ax.set_ylabel("P(delay > x)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="lower left")
    axes[0].set_title("contention rounds, 10 stations")
    axes[1].set_title("event level, 10 stations, full load, 1 ms period")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _table(rows: list[dict[str, Any]], count: str) -> list[str]:
    lines = [
        f"| medium | stations | load | {count} | frames | p50 (us) | p99 (us) | max (us) "
        "| D_max (us) | > D_max | drops |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['medium']} | {r['stations']} | {r['load']:g} | {r[count]:,} | "
            f"{r['frames']:,} | {r['p50_us']:,.1f} | {r['p99_us']:,.1f} | "
            f"{r['max_us']:,.1f} | {r['bound_us']:.1f} | {100 * r['over_bound']:.2f} % | "
            f"{r['drops']} |"
        )
    return lines


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--rounds", type=int, default=100_000)
    ap.add_argument("--big", type=int, default=1_000_000)
    ap.add_argument("--ticks", type=int, default=200)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    stations = [2, 5, 10, 20, 40]
    loads = [0.1, 0.25, 0.5, 0.75, 1.0]
    ev_stations, ev_loads = [4, 10], [0.5, 1.0]
    if args.quick:
        args.rounds, args.big, args.ticks = 300, 2_000, 10
        stations, loads = [2, 10], [0.25, 1.0]
        ev_stations, ev_loads = [10], [1.0]
    ethernet_rounds(10, seed=SEED)  # compile the numba kernel outside the timings
    round_rows, tails = rounds_part(stations, loads, args.rounds, args.big)
    variant_rows = variants_part(args.big)
    event_rows, ev_tails = event_part(ev_stations, ev_loads, args.ticks)
    tails.update(ev_tails)
    span_rows, span_note = makespan_part(args.quick)
    RESULTS.mkdir(exist_ok=True)
    png = RESULTS / "network_tails.png"
    plot(tails, dcr_bound(), png)

    big = [r for r in round_rows if r["stations"] == 10 and r["load"] == 1.0]
    lines = [
        "# Network media: delays against the CSMA/DCR bound",
        "",
        f"Command: `python -m benchmarks.bench_network{' --quick' if args.quick else ''}`; "
        f"seed {SEED}. D_max = `workcell.dcr_bound(n_stations=N)` (100 m bus, 10 Mb/s, "
        "148-byte trajectory + 51-byte positions; 604.1 us at N = 10). Delays in "
        "microseconds from the frame's send to its last bit at the receiver; drops are "
        "frames given up after 16 attempts.",
        "",
        f"## Contention rounds ({args.rounds:,} rounds per cell; {args.big:,} at N = 10, "
        "full load)",
        "",
        *_table(round_rows, "rounds"),
        "",
        "At 10 stations and full load: "
        + "; ".join(
            f"{r['medium']} max {r['max_us']:.1f} us over {r['rounds']:,} rounds "
            f"({r['wall_s']:.2f} s)"
            for r in big
        )
        + ".",
        "",
        "## Variants at 10 stations",
        "",
        "The reduced parameters of S2.9 (D_max from `dcr_bound(**REDUCED)`), and "
        "CSMA/DCR with each silent station charged one standard slot "
        "(`dcr_rounds(..., empty_slot=51.2e-6)`).",
        "",
        *_table(variant_rows, "rounds"),
        "",
        f"## Event level (`make_medium`, {args.ticks} sampling periods of 1 ms)",
        "",
        *_table(event_rows, "ticks"),
        "",
        "Serial lines run at 9600 b/s: 55 bytes take 57 ms, so a 1 ms period "
        "overloads them and their queues (and delays) grow with the run (S2.8: "
        "unsuitable).",
        "",
        "## Makespan of one cell and schedule over each medium",
        "",
    ]
    if span_rows:
        lines += [
            f"Cell `{CELL}`, greedy schedule (seed 0), `workcell.simulate(..., medium=name)`; "
            "the first row runs the same schedule as a task program on the SUPERSIGMA "
            "central unit (`workcell.sim.supersigma.run_schedule`: messages = MICROBUS "
            "commands, each holding the bus 100 us).",
            "",
            "| medium | planned (s) | executed (s) | messages | p99 delay (ms) "
            "| max delay (ms) | failed tasks |",
            "|---|---|---|---|---|---|---|",
        ]
        for r in span_rows:
            if "error" in r:
                lines.append(f"| {r['medium']} | failed: {r['error']} | | | | | |")
                continue
            lines.append(
                f"| {r['medium']} | {r['planned_makespan']:.3f} | {r['executed_makespan']:.3f} "
                f"| {r['messages']} | {r['p99_delay_ms']:.3f} | {r['max_delay_ms']:.3f} "
                f"| {r['failed_tasks']} |"
            )
    if span_note:
        lines.append(f"Not run over the media: {span_note}.")
    lines += ["", f"Plot of the delay tails: `{png.name}`.", ""]
    path = write(
        "network",
        {
            "seed": SEED,
            "rounds": round_rows,
            "variants": variant_rows,
            "event": event_rows,
            "makespan": span_rows,
            "makespan_note": span_note,
            "plot": png.name,
            "dcr_bound_us": dcr_bound() / US,
        },
        "\n".join(lines),
    )
    print(path)


if __name__ == "__main__":
    main()
