"""Sweep throughput: the same small sweep in this process, a local process pool, and a Dask LocalCluster.

The sweep is ``benchmarks/sweeps/quick.toml`` (18 work-limited runs on small
generated problems: greedy, tree with ``max_evaluations``, CP-SAT with one
worker and a deterministic-time limit), so every way of running it must give
identical results, which the script checks. Reported: runs per minute of each
way, side by side in one run; the cluster's start-up is timed apart.

A thin wrapper of the sweep ``benchmarks/sweeps/sweep.toml`` (one
``benchmark`` run of :func:`measure`: every way, every round); it measures
again on every call. Results: ``benchmarks/results/sweep.parquet``,
``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_sweep [--quick]``.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.common import table_main
from workcell.experiments import load_sweep, parse_sweep, run_sweep

NAME = "sweep"
SWEEP = Path(__file__).resolve().parent / "sweeps" / "quick.toml"
SAME = ["status", "makespan", "objective", "bound", "nodes", "evaluations"]


def _run_way(way: str, sweep: Any, out: Path, workers: int) -> dict[str, Any]:
    from distributed import Client, LocalCluster

    start = 0.0
    if way == "dask LocalCluster":
        t0 = time.perf_counter()
        cluster = LocalCluster(  # type: ignore[no-untyped-call]
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)  # type: ignore[no-untyped-call]
        start = time.perf_counter() - t0
        try:
            o = run_sweep(sweep, dask_address=client, out=out, progress=False)
        finally:
            client.close()  # type: ignore[no-untyped-call]
            cluster.close()
    else:
        o = run_sweep(sweep, workers=1 if way == "in process" else workers, out=out, progress=False)
    return {
        "way": way,
        "workers": 1 if way == "in process" else workers,
        "runs": o.ran,
        "failed": o.failed,
        "wall_s": o.wall_time,
        "runs_per_minute": o.runs_per_minute,
        "startup_s": start,
        "frame": o.results().set_index("key").sort_index()[SAME],
    }


def measure(seed: int, workers: int, repeat: int, small: bool) -> dict[str, Any]:
    """The sweep ``quick.toml`` run three ways, ``repeat`` rounds (the whole table, one run).

    ``small``: one problem instead of six (three runs; a smoke run). ``seed``
    is unused: the sweep's runs are work-limited and seeded by the sweep file.
    """
    sweep = load_sweep(SWEEP)
    if small:
        text = SWEEP.read_text().replace(
            "sizes = [[2, 8, 2, 1], [3, 12, 3, 1]]\nseeds = [0, 1, 2]",
            "sizes = [[2, 8, 2, 1]]\nseeds = [0]",
        )
        sweep = parse_sweep(text, filename=str(SWEEP), base_dir=SWEEP.parent)
    rows: list[dict[str, Any]] = []
    frames: list[tuple[str, Any]] = []
    ways = ("in process", "process pool", "dask LocalCluster")
    with tempfile.TemporaryDirectory() as tmp:
        # warm the kernel cache once, so that no way pays the first compile
        run_sweep(sweep, workers=1, out=Path(tmp) / "warm.parquet", progress=False)
        for rep in range(repeat):
            # rounds alternate the order, so that a burst of load on the machine
            # does not always fall on the same way
            for way in ways if rep % 2 == 0 else ways[::-1]:
                out = Path(tmp) / f"{way.replace(' ', '_')}-{rep}.parquet"
                rows.append(_run_way(way, sweep, out, workers))
                frames.append((way, rows[-1].pop("frame")))
    best = {
        way: max((r for r in rows if r["way"] == way), key=lambda r: r["runs_per_minute"])
        for way in ways
    }
    base = next(f for w, f in frames if w == "in process")
    same = {w: all(f.equals(base) for v, f in frames if v == w) for w in ways}
    assert all(same.values()), f"results differ between ways of running: {same}"
    return {
        "sweep": SWEEP.name,
        "small": small,
        "repeat": repeat,
        "best": [best[w] for w in ways],
        "all_rounds": rows,
        "same": same,
    }


def table(r: Any) -> str:
    """The Markdown table of the one measured row."""
    rows, same = r["best"], r["same"]
    ref = rows[0]["runs_per_minute"]
    lines = [
        "# Sweep throughput: in process, local process pool, Dask LocalCluster",
        "",
        f"`{r['sweep']}`{' (small: 3 runs)' if r['small'] else ''}: {rows[0]['runs']} "
        "work-limited runs (greedy, tree with max_evaluations, CP-SAT with one worker and "
        "a deterministic-time limit), the same sweep three ways, side by side in one run, "
        f"after one warm-up run of the sweep; best of {r['repeat']} rounds (order alternating). "
        "Results identical in all three ways: "
        f"{'yes' if all(same.values()) else 'no'}. Wall time includes starting the pool's "
        "processes (not the cluster's, given apart).",
        "",
        "| way | workers | runs | wall (s) | runs/min | vs in process | cluster start (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for w in rows:
        start = f"{w['startup_s']:.1f}" if w["way"] == "dask LocalCluster" else "-"
        lines.append(
            f"| {w['way']} | {w['workers']} | {w['runs']} | {w['wall_s']:.1f} | "
            f"{w['runs_per_minute']:.1f} | {w['runs_per_minute'] / ref:.2f}x | {start} |"
        )
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
