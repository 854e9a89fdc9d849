"""Zone layer throughput: point-in-zone tests per second and ZoneManager
requests per second, on one core (targets in the zones issue: 1e6 point-zone
tests/s and 1e5 requests/s).

A thin wrapper of the sweep ``benchmarks/sweeps/zones.toml`` (one
``benchmark`` run of :func:`measure` per example cell: its point queries and
its requests, measured in one run); it measures again on every call.
Results: ``benchmarks/results/zones.parquet``, ``.json`` and ``.md``.

Run: ``python -m benchmarks.bench_zones [--quick]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from benchmarks.common import best_rate, table_main
from zones import examples
from zones.manager import ReportOnly, ZoneManager

NAME = "zones"


def point_queries(
    points: int, seed: int, cells: tuple[str, ...] | None = None
) -> list[dict[str, object]]:
    """Point-zone tests per second, batched and one point per call, per example cell."""
    rows = []
    rng = np.random.default_rng(seed)
    for name in cells or examples.EXAMPLES:
        zm = examples.load_example(name)
        lo, hi = np.asarray(zm.bounds[0]), np.asarray(zm.bounds[1])
        pts = rng.uniform(lo, hi, size=(points, 3))
        zm.contains(pts[:10])  # warm the caches (hull and wall geometry)
        rate, _ = best_rate(lambda zm=zm, pts=pts: zm.contains(pts).size)
        one = pts[:1]
        single, _ = best_rate(
            lambda zm=zm, one=one: sum(zm.contains(one).size for _ in range(2000))
        )
        rows.append(
            {
                "cell": name,
                "zones": zm.n_zones,
                "points": points,
                "point_zone_tests_per_s": rate,
                "single_point_calls_tests_per_s": single,
            }
        )
    return rows


def manager_requests(
    n_ops: int, seed: int, cells: tuple[str, ...] | None = None
) -> list[dict[str, object]]:
    """A random but legal workload: enter/leave/stop/move/tools, as a
    coordinator would issue them; every call counts as one request."""
    rows = []
    for name in cells or examples.EXAMPLES:
        zm = examples.load_example(name)
        arms = [f"arm{i}" for i in range(8)]
        rng = np.random.default_rng(seed)
        zone_names = list(zm.zone_names())
        tool_names = [t.name for t in zm.tools]
        script = rng.integers(0, 1 << 30, size=(n_ops, 3))

        def run(
            zm=zm, arms=arms, zone_names=zone_names, tool_names=tool_names, script=script
        ) -> int:
            m = ZoneManager(zm, arms, deadlock_policy=ReportOnly())
            calls = 0
            for a_i, z_i, kind in script:
                arm = arms[a_i % len(arms)]
                waiting = m.waiting(arm) is not None
                if waiting:
                    m.cancel(arm)
                    calls += 1
                    continue
                k = kind % 10
                inside = m.zones_of(arm)
                if k < 4:
                    z = zone_names[z_i % len(zone_names)]
                    if z in inside:
                        m.release(arm, z)
                    else:
                        m.request_enter(arm, z)
                elif k < 6:
                    m.stop(arm)
                elif k < 8:
                    m.request_move(arm)
                elif tool_names:
                    t = tool_names[z_i % len(tool_names)]
                    if t in m.tools_of(arm):
                        m.release_tool(arm, t)
                    else:
                        m.acquire_tool(arm, t)
                else:
                    m.stop(arm)
                calls += 1
            return calls

        rate, _ = best_rate(run, repeat=3)
        rows.append(
            {
                "cell": name,
                "zones": zm.n_zones,
                "arms": 8,
                "requests": n_ops,
                "requests_per_s": rate,
            }
        )
    return rows


def measure(seed: int, cell: str, points: int, requests: int) -> dict[str, Any]:
    """One row of the table: the point queries and the requests of one example cell."""
    q = point_queries(points, seed, (cell,))[0]
    r = manager_requests(requests, seed, (cell,))[0]
    return {**q, "requests": requests, "requests_per_s": r["requests_per_s"]}


def table(m: Any) -> str:
    """The Markdown table of the measured rows."""
    points = ", ".join(map(str, sorted(set(m["points"]))))
    lines = [
        "# Zone layer throughput",
        "",
        f"seed {', '.join(map(str, sorted(set(m['seed']))))}; best of 5 (points) / 3 (requests) "
        "runs, one process, one core",
        "",
        f"| cell | zones | point-zone tests/s (batch of {points}) | tests/s (one point per call) "
        "| ZoneManager requests/s |",
        "|---|---|---|---|---|",
    ]
    for _, a in m.iterrows():
        lines.append(
            f"| {a['cell']} | {a['zones']} | {a['point_zone_tests_per_s']:.3g} | "
            f"{a['single_point_calls_tests_per_s']:.3g} | {a['requests_per_s']:.3g} |"
        )
    lines += ["", "Targets: 1e6 point-zone tests/s, 1e5 requests/s."]
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
