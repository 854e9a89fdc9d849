"""The simulation's event kernel against SimPy, side by side in one run.

Two workloads, the same on both kernels, with the same seeded delays:

* **callbacks** -- ``chains`` independent timer chains; each callback
  schedules the next one of its chain after a seeded random delay (what the
  network media do: frame ends, collision ends, backoff timers). Our kernel:
  ``EventLoop.schedule(delay, cb)``; SimPy: ``env.timeout(delay)`` with the
  callback appended to the event's callback list (the cheapest way to run a
  plain callback in SimPy).
* **processes** -- ``procs`` generator processes, each looping over
  ``yield <delay>`` (ours: a float; SimPy: ``env.timeout(delay)``).

Each is run ``repeat`` times, the two kernels interleaved, and the best
rate (events per second) of each is kept; the ratio ours / SimPy is what to
read (the machines are shared). A thin wrapper of the sweep
``benchmarks/sweeps/simkernel.toml`` (one ``benchmark`` run of
:func:`measure` per workload: both kernels in one run); it measures again on
every call. Results: ``benchmarks/results/simkernel.parquet``, ``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_simkernel [--quick]``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Generator
from functools import partial
from typing import Any

import numpy as np
import simpy

from benchmarks.common import table_main
from workcell.sim.events.loop import EventLoop

NAME = "simkernel"
SEED = 0
"""The seed of the delays (the sweep passes it to :func:`measure`)."""


def _delays(n: int, seed: int = SEED) -> list[float]:
    return [float(x) for x in np.random.default_rng(seed).exponential(1e-3, size=n)]


def ours_callbacks(events: int, chains: int, seed: int = SEED) -> int:
    k = EventLoop()
    delays = _delays(events, seed)
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


def simpy_callbacks(events: int, chains: int, seed: int = SEED) -> int:
    env = simpy.Environment()
    delays = _delays(events, seed)
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


def ours_processes(events: int, procs: int, seed: int = SEED) -> int:
    k = EventLoop()
    delays = _delays(events, seed)
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


def simpy_processes(events: int, procs: int, seed: int = SEED) -> int:
    env = simpy.Environment()
    delays = _delays(events, seed)
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


WORKLOADS = {
    "callbacks": (ours_callbacks, simpy_callbacks),
    "processes": (ours_processes, simpy_processes),
}


def measure(seed: int, workload: str, concurrent: int, events: int, repeat: int) -> dict[str, Any]:
    """One row of the table: both kernels on one workload, ``repeat`` times interleaved."""
    ours, theirs = WORKLOADS[workload]
    r_ours = r_simpy = 0.0
    n_ours = n_simpy = 0
    for _ in range(repeat):  # interleaved, so both see the same load
        rate, n_ours = best(partial(ours, events, concurrent, seed=seed), 1)
        r_ours = max(r_ours, rate)
        rate, n_simpy = best(partial(theirs, events, concurrent, seed=seed), 1)
        r_simpy = max(r_simpy, rate)
    return {
        "workload": workload,
        "concurrent": concurrent,
        "events": events,
        "repeat": repeat,
        "events_ours": n_ours,
        "events_simpy": n_simpy,
        "ours_per_s": r_ours,
        "simpy_per_s": r_simpy,
        "ratio": r_ours / r_simpy,
    }


def table(m: Any) -> str:
    """The Markdown table of the measured rows."""
    lines = [
        "# Event kernel vs SimPy",
        "",
        f"SimPy {simpy.__version__}; {', '.join(map(str, sorted(set(m['events']))))} events per "
        f"workload, best of {', '.join(map(str, sorted(set(m['repeat']))))}; seed "
        f"{', '.join(map(str, sorted(set(m['seed']))))} for the delays. Events/s (best of the "
        "repeats); only the ratio is meaningful on a shared machine.",
        "",
        "| workload | concurrent | ours (events/s) | SimPy (events/s) | ratio |",
        "|---|---|---|---|---|",
    ]
    for _, r in m.iterrows():
        lines.append(
            f"| {r['workload']} | {r['concurrent']} | {r['ours_per_s']:,.0f} | "
            f"{r['simpy_per_s']:,.0f} | {r['ratio']:.2f} |"
        )
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
