"""The simulation's event kernel against SimPy, side by side in one run.

Two workloads, the same on both kernels, with the same seeded delays:

* **callbacks** -- ``chains`` independent timer chains; each callback
  schedules the next one of its chain after a seeded random delay (what the
  network media do: frame ends, collision ends, backoff timers). Our kernel:
  ``Kernel.schedule(delay, cb)``; SimPy: ``env.timeout(delay)`` with the
  callback appended to the event's callback list (the cheapest way to run a
  plain callback in SimPy).
* **processes** -- ``procs`` generator processes, each looping over
  ``yield <delay>`` (ours: a float; SimPy: ``env.timeout(delay)``).

Each is run ``--repeat`` times, the two kernels interleaved, and the best
rate (events per second) of each is kept; the ratio ours / SimPy is what to read (the machines are shared).
Results: ``benchmarks/results/simkernel.json`` and ``simkernel.md``.

Run: ``python -m benchmarks.bench_simkernel [--events 400000] [--quick]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Generator
from functools import partial
from typing import Any

import numpy as np
import simpy

from benchmarks.common import write
from workcell.sim.kernel import Kernel

SEED = 0


def _delays(n: int) -> list[float]:
    return [float(x) for x in np.random.default_rng(SEED).exponential(1e-3, size=n)]


def ours_callbacks(events: int, chains: int) -> int:
    k = Kernel()
    delays = _delays(events)
    left = [events]

    def fire(i: int) -> None:
        n = left[0]
        if n > 0:
            left[0] = n - 1
            k.schedule(delays[n - 1], fire, i)

    for i in range(chains):
        k.schedule(0.0, fire, i)
    k.run()
    return k.events_run


def simpy_callbacks(events: int, chains: int) -> int:
    env = simpy.Environment()
    delays = _delays(events)
    left = [events]
    count = [0]

    def fire(_ev: object) -> None:
        count[0] += 1
        n = left[0]
        if n > 0:
            left[0] = n - 1
            env.timeout(delays[n - 1]).callbacks.append(fire)

    for _ in range(chains):
        env.timeout(0.0).callbacks.append(fire)
    env.run()
    return count[0]


def ours_processes(events: int, procs: int) -> int:
    k = Kernel()
    delays = _delays(events)
    per = events // procs
    count = [0]

    def proc(j: int) -> Generator[float, Any, None]:
        for i in range(per):
            yield delays[j * per + i]
            count[0] += 1

    for j in range(procs):
        k.process(proc(j))
    k.run()
    return count[0]


def simpy_processes(events: int, procs: int) -> int:
    env = simpy.Environment()
    delays = _delays(events)
    per = events // procs
    count = [0]

    def proc(j: int) -> Generator[simpy.events.Event, Any, None]:
        for i in range(per):
            yield env.timeout(delays[j * per + i])
            count[0] += 1

    for j in range(procs):
        env.process(proc(j))
    env.run()
    return count[0]


def best(fn: Callable[[], int], repeat: int) -> tuple[float, int]:
    rates = []
    n = 0
    for _ in range(repeat):
        t0 = time.perf_counter()
        n = fn()
        rates.append(n / (time.perf_counter() - t0))
    return max(rates), n


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--events", type=int, default=400_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    if args.quick:
        args.events, args.repeat = 5_000, 1
    rows: list[dict[str, Any]] = []
    for workload, width, ours, theirs in (
        ("callbacks", 1, ours_callbacks, simpy_callbacks),
        ("callbacks", 100, ours_callbacks, simpy_callbacks),
        ("processes", 10, ours_processes, simpy_processes),
        ("processes", 1000, ours_processes, simpy_processes),
    ):
        r_ours = r_simpy = 0.0
        n_ours = n_simpy = 0
        for _ in range(args.repeat):  # interleaved, so both see the same load
            rate, n_ours = best(partial(ours, args.events, width), 1)
            r_ours = max(r_ours, rate)
            rate, n_simpy = best(partial(theirs, args.events, width), 1)
            r_simpy = max(r_simpy, rate)
        rows.append(
            {
                "workload": workload,
                "concurrent": width,
                "events_ours": n_ours,
                "events_simpy": n_simpy,
                "ours_per_s": r_ours,
                "simpy_per_s": r_simpy,
                "ratio": r_ours / r_simpy,
            }
        )
        print(rows[-1], flush=True)
    lines = [
        "# Event kernel vs SimPy",
        "",
        f"SimPy {simpy.__version__}; {args.events} events per workload, best of "
        f"{args.repeat}; seed {SEED} for the delays. Command: "
        "`python -m benchmarks.bench_simkernel`. Events/s (best of the repeats); "
        "only the ratio is meaningful on a shared machine.",
        "",
        "| workload | concurrent | ours (events/s) | SimPy (events/s) | ratio |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['workload']} | {r['concurrent']} | {r['ours_per_s']:,.0f} | "
            f"{r['simpy_per_s']:,.0f} | {r['ratio']:.2f} |"
        )
    path = write(
        "simkernel",
        {"seed": SEED, "events": args.events, "repeat": args.repeat, "rows": rows},
        "\n".join(lines) + "\n",
    )
    print(path)


if __name__ == "__main__":
    main()
