"""Delay distributions of the network media against the CSMA/DCR bound (S2.8, S2.9).

Three parts, side by side in one run:

1. **Contention rounds** (batch simulators): every round starts at a sampling
   tick; the coordinator (station 0) has a trajectory frame of 26 + 2 + 24 p
   bytes (p = 1..5), each robot a 51-byte position report, each present with
   probability ``load``. CSMA/DCR (:func:`~workcell.sim.comms.dcr_rounds`)
   and Ethernet CSMA/CD (:func:`~workcell.sim.comms.ethernet_rounds`,
   numba) over stations x load; p50, p99 and max delay against
   :func:`workcell.dcr_bound` for the same station count, and the share of
   frames over it. At 10 stations and full load both run ``--big`` rounds
   (10^6 by default).
2. **Event-level media** (:func:`workcell.sim.comms.make_medium`): the same
   traffic, one round per 1 ms sampling period with up to 20 us of jitter,
   for ``--ticks`` periods, on CSMA/DCR, Ethernet, Multibus II, serial star
   and serial bus (9600 b/s). A medium that cannot carry the traffic builds
   a queue: its delays grow with the run's length.
3. **Makespan of one cell and schedule over each medium**, with
   ``workcell.simulate`` (needs :mod:`workcell.sim.harness.simulate`), and under the
   SUPERSIGMA central unit and MICROBUS
   (:func:`workcell.sim.control.supersigma.run_schedule`: tasks as stepper moves,
   zone hand-overs as flags).

A plot of the delay tails (complementary CDF) goes to
``results/network_tails.png``. Results: ``results/network.json`` and
``network.md``.

A thin wrapper of the sweep ``benchmarks/sweeps/network.toml`` (one
``benchmark`` run per part: :func:`measure_rounds`, :func:`measure_variants`,
:func:`measure_event`, :func:`measure_makespan`; the delay tails of the plot
are stored with their rows, a few thousand points per curve); it measures
again on every call. Results: ``benchmarks/results/network.parquet``,
``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_network [--quick]``.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import time
from typing import Any

import numpy as np

from benchmarks.common import output_dir, publish, run_table_sweep, sweep_arguments
from multiarm.types import FloatArray
from workcell.sim.comms import (
    MEDIA,
    REDUCED,
    dcr_bound,
    dcr_rounds,
    ethernet_rounds,
    make_medium,
)
from workcell.sim.comms.medium import Frame, trajectory_bytes
from workcell.sim.events.loop import EventLoop

NAME = "network"
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
    stations: list[int], loads: list[float], rounds: int, big: int, seed: int = SEED
) -> tuple[list[dict[str, Any]], dict[str, FloatArray]]:
    rows: list[dict[str, Any]] = []
    tails: dict[str, FloatArray] = {}
    for n in stations:
        bound = dcr_bound(n_stations=n)
        for load in loads:
            r = big if (n == 10 and load == 1.0) else rounds
            for name, fn in (("csma-dcr", dcr_rounds), ("ethernet", ethernet_rounds)):
                t0 = time.perf_counter()
                d = chunked(fn, r, 100_000, n_stations=n, load=load, seed=seed)
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


def variants_part(rounds: int, seed: int = SEED) -> list[dict[str, Any]]:
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
        d = chunked(fn, rounds, 100_000, n_stations=10, load=load, seed=seed, **kw)
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
    k = EventLoop()
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
    stations: list[int], loads: list[float], ticks: int, seed: int = SEED
) -> tuple[list[dict[str, Any]], dict[str, FloatArray]]:
    rows: list[dict[str, Any]] = []
    tails: dict[str, FloatArray] = {}
    for n in stations:
        bound = dcr_bound(n_stations=n)
        for load in loads:
            for name in EVENT_MEDIA:
                t0 = time.perf_counter()
                d, drops = event_delays(name, n, load, ticks, seed)
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


def makespan_part(quick: bool, seed: int = SEED) -> tuple[list[dict[str, Any]], str]:
    """The same cell and schedule over every medium (needs workcell.sim.harness.simulate),
    and under the SUPERSIGMA central unit (``run_schedule``)."""
    import scheduler
    import workcell
    from workcell.sim.control.supersigma import run_schedule

    cell = workcell.load_example(CELL)
    compiled = workcell.compile_cell(cell)
    problem = compiled.problem
    sched = scheduler.solve(problem, solver="greedy", time_limit=5.0, seed=seed).schedule
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
    if importlib.util.find_spec("workcell.sim.harness.simulate") is None:
        return (
            rows,
            "workcell.sim.harness.simulate (workcell.simulate) is not available in this checkout",
        )
    # imported by name: the simulation is another module's concern
    simulate: Any = (
        getattr(workcell, "simulate", None)
        or importlib.import_module("workcell.sim.harness.simulate").simulate
    )
    for name in ("ideal", "csma-dcr") if quick else MEDIA:
        t0 = time.perf_counter()
        try:
            res = simulate(compiled, sched, seed=seed, medium=name)
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


def tail_curve(d: FloatArray, points: int = 1500) -> list[list[float]]:
    """The complementary CDF of delays ``d`` as ``[delay_us, P(delay > x)]`` pairs.

    A few thousand points, dense in the tail (what the plot draws; stored
    with the measured rows instead of every delay).
    """
    ok = np.sort(d[~np.isnan(d)]) / US
    n = ok.size
    if n == 0:
        return []
    ranks = np.unique(
        np.concatenate([np.linspace(0, n - 1, points), n - np.logspace(0, np.log10(n), points)])
        .astype(np.int64)
        .clip(0, n - 1)
    )
    return [[float(ok[i]), float(1.0 - i / n)] for i in ranks]


def measure_rounds(
    seed: int, stations: list[int], loads: list[float], rounds: int, big: int
) -> list[dict[str, Any]]:
    """Contention rounds of CSMA/DCR and Ethernet over stations x load (part 1)."""
    ethernet_rounds(10, seed=seed)  # compile the numba kernel outside the timings
    rows, tails = rounds_part(list(stations), list(loads), rounds, big, seed)
    for r in rows:
        key = f"{r['medium']} N=10 load {r['load']:g}"
        if key in tails:
            r["tail"] = tail_curve(tails[key])
    return rows


def measure_variants(seed: int, rounds: int) -> list[dict[str, Any]]:
    """The reduced parameters and the slotted resolution at 10 stations (part 1)."""
    ethernet_rounds(10, seed=seed)
    return variants_part(rounds, seed)


def measure_event(
    seed: int, stations: list[int], loads: list[float], ticks: int
) -> list[dict[str, Any]]:
    """Event-level media (part 2)."""
    rows, tails = event_part(list(stations), list(loads), ticks, seed)
    for r in rows:
        key = f"{r['medium']} (event level)"
        if r["stations"] == 10 and r["load"] == 1.0 and key in tails:
            r["tail"] = tail_curve(tails[key])
    return rows


def measure_makespan(seed: int, every_medium: bool) -> list[dict[str, Any]]:
    """One cell and schedule over each medium and under the central unit (part 3)."""
    rows, note = makespan_part(not every_medium, seed)
    return [{"note": note}] if not rows else [{**r, "note": note} for r in rows]


def plot(tails: dict[str, list[list[float]]], bound: float, path: Any) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, event in zip(axes, (False, True), strict=True):
        for label, curve in tails.items():
            if ("event level" in label) != event or not curve:
                continue
            xy = np.asarray(curve, dtype=np.float64)
            ax.loglog(xy[:, 0], xy[:, 1], label=label, lw=1.3)
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


def _records(df: Any, family: str) -> list[dict[str, Any]]:
    from workcell.experiments.analysis import measurements

    head = ["family", "instance", "seed", "repetition", "load_average"]
    rows: list[dict[str, Any]] = measurements(df, family).drop(columns=head).to_dict("records")
    return rows


def _nan(v: Any) -> bool:
    return isinstance(v, float) and bool(np.isnan(v))


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the tables and the plot.

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
    seed = int(m["seed"].iloc[0])
    round_rows = _records(df, "rounds")
    variant_rows = _records(df, "variants")
    event_rows = _records(df, "event")
    span = _records(df, "makespan")
    span_note = span[0].get("note", "") if span else ""
    span_rows = [
        {k: v for k, v in r.items() if k != "note" and not _nan(v)}
        for r in span
        if "medium" in r and not _nan(r["medium"])
    ]
    # rows without a curve carry NaN there (the rows of one table share columns)
    tails = {
        f"{r['medium']} N=10 load {r['load']:g}": r["tail"]
        for r in round_rows
        if isinstance(r.get("tail"), list)
    }
    tails.update(
        {
            f"{r['medium']} (event level)": r["tail"]
            for r in event_rows
            if isinstance(r.get("tail"), list)
        }
    )
    png = out / "network_tails.png"
    plot(tails, dcr_bound(), png)
    ticks = max((r["ticks"] for r in event_rows), default=0)
    big_n = max(
        (r["rounds"] for r in round_rows if r["stations"] == 10 and r["load"] == 1.0), default=0
    )
    rounds = min((r["rounds"] for r in round_rows), default=0)
    big = [r for r in round_rows if r["stations"] == 10 and r["load"] == 1.0]
    lines = [
        "# Network media: delays against the CSMA/DCR bound",
        "",
        f"Seed {seed}. D_max = `workcell.dcr_bound(n_stations=N)` (100 m bus, 10 Mb/s, "
        "148-byte trajectory + 51-byte positions; 604.1 us at N = 10). Delays in "
        "microseconds from the frame's send to its last bit at the receiver; drops are "
        "frames given up after 16 attempts.",
        "",
        f"## Contention rounds ({rounds:,} rounds per cell; {big_n:,} at N = 10, full load)",
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
        f"## Event level (`make_medium`, {ticks} sampling periods of 1 ms)",
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
            "central unit (`workcell.sim.control.supersigma.run_schedule`: messages = MICROBUS "
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
    data = [{k: v for k, v in r.items() if k != "tail"} for r in m.to_dict("records")]
    path = publish(
        NAME,
        df,
        "\n".join(lines),
        out,
        quick=args.quick,
        rows=pd_frame(data),
        extra={"plot": png.name, "dcr_bound_us": dcr_bound() / US},
    )
    print(path)


def pd_frame(rows: list[dict[str, Any]]) -> Any:
    import pandas as pd

    return pd.DataFrame(rows)


if __name__ == "__main__":
    main()
