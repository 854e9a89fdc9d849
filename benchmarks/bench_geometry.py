"""Geometry throughput: detour validity checks, the vectorised zone sweep vs plain FCL,
and an OMPL planner comparison (OMPL benchmark log format).

The arm is the two-link planar test arm of ``tests/workcell/geometry/fake_arm.py``
(two capsule links, vectorised forward kinematics); the zones are the
``scara4`` example map; the obstacle is a second arm parked with its links
reaching across the first one's workspace.

* validity checks/s: one configuration per call (``DetourPlanner.is_valid``,
  what OMPL's state checker costs) and batched along joint-space edges
  (``DetourPlanner.segment_free``, the motion validator: one forward
  kinematics call per edge), and inside a whole ``plan_detour`` call;
* link-zone checks/s (samples x arm shapes x zone solids): the vectorised
  sweep (:func:`workcell.geometry.zone_contacts`) and plain FCL, one query
  per sample (:func:`workcell.geometry.reference_contacts`), on the same
  samples, side by side;
* an OMPL ``Benchmark`` run over several planners on the detour query,
  written as ``results/geometry_ompl.log``.

A thin wrapper of the sweep ``benchmarks/sweeps/geometry.toml`` (one
``benchmark`` run per part: :func:`validity`, :func:`sweep`,
:func:`ompl_log`, each measuring its whole comparison); it measures again
on every call. Results: ``benchmarks/results/geometry.parquet``, ``.json``
and ``.md``.

Run: ``python -m benchmarks.bench_geometry [--quick]``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.common import best_rate, output_dir, publish, run_table_sweep, sweep_arguments
from tests.workcell.geometry.fake_arm import PlanarArm
from workcell.geometry import (
    DetourPlanner,
    ObstacleSet,
    plan_detour,
    reference_contacts,
    write_ompl_benchmark_log,
    zone_contacts,
)
from zones import examples

NAME = "geometry"


def validity(seed: int, n: int) -> dict[str, float]:
    """Validity checks per second: one by one, along edges, inside ``plan_detour``."""
    arm = PlanarArm()
    parked = ObstacleSet.from_arm(PlanarArm("o", base_xy=(1.2, 0.0)), np.array([np.pi, 0.0]))
    ctx = DetourPlanner(arm, parked, resolution=0.01)
    rng = np.random.default_rng(seed)
    lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
    q = rng.uniform(lo, hi, size=(n, arm.dof))

    def one_by_one() -> int:
        for row in q:
            ctx.is_valid(row)
        return len(q)

    single, _ = best_rate(one_by_one, repeat=3)

    def edges() -> int:
        before = ctx.n_checks
        for a, b in zip(q[:-1:2], q[1::2], strict=True):
            ctx.segment_free(a, b)
        return ctx.n_checks - before

    batched, _ = best_rate(edges, repeat=3)
    qs, qg = np.array([-1.0, 0.3]), np.array([1.0, -0.3])
    res = [plan_detour(arm, qs, qg, parked, budget=2.0, seed=seed + k) for k in range(5)]
    in_plan = sum(r.n_checks for r in res) / sum(r.planning_time for r in res)
    return {
        "single_checks_per_s": single,
        "edge_checks_per_s": batched,
        "plan_checks_per_s": in_plan,
        "us_per_check_single": 1e6 / single,
        "us_per_check_edge": 1e6 / batched,
        "us_per_check_in_plan": 1e6 / in_plan,
        "plans_solved": float(sum(r.solved for r in res)),
        "plan_median_ms": float(np.median([r.planning_time for r in res]) * 1e3),
    }


def sweep(seed: int, n: int) -> dict[str, float]:
    """Link-zone checks per second: the vectorised sweep and plain FCL on the same samples."""
    arm = PlanarArm()
    zm = examples.load_example("scara4")
    n_solids = sum(len(zm.primitives(z)) for z in range(zm.n_zones))
    rng = np.random.default_rng(seed)
    q = rng.uniform(arm.joint_limits[:, 0], arm.joint_limits[:, 1], size=(n, arm.dof))
    pairs = n * len(arm.shapes) * n_solids
    k = max(1, n // 10)  # FCL is slower: time it on a tenth of the samples

    def vectorised() -> int:
        zone_contacts(arm, q, zm, padding=0.005)
        return pairs

    def plain_fcl() -> int:
        reference_contacts(arm, q[:k], zm)
        return k * len(arm.shapes) * n_solids

    fast, _ = best_rate(vectorised)
    plain, _ = best_rate(plain_fcl, repeat=3)
    agree = zone_contacts(arm, q[:k], zm, padding=0.0) | ~reference_contacts(arm, q[:k], zm)
    return {
        "samples": float(n),
        "zone_solids": float(n_solids),
        "vectorised_link_zone_checks_per_s": fast,
        "fcl_link_zone_checks_per_s": plain,
        "speedup": fast / plain,
        "vectorised_covers_fcl": float(agree.all()),
    }


def ompl_log(seed: int, runs: int) -> list[dict[str, Any]]:
    """OMPL's Benchmark over four planners on the detour query: one row per planner.

    The first row also holds the OMPL benchmark log's text (``log``), which
    the wrapper writes as ``geometry_ompl.log``.
    """
    arm = PlanarArm()
    parked = ObstacleSet.from_arm(PlanarArm("o", base_xy=(1.2, 0.0)), np.array([np.pi, 0.0]))
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "geometry_ompl.log"
        rows = _ompl(arm, parked, log, seed, runs)
        text = log.read_text() if log.is_file() else ""
    out: list[dict[str, Any]] = [{"planner": name, **row} for name, row in rows.items()]
    if out:
        out[0]["log"] = text
    return out


def _ompl(arm: Any, parked: Any, log: Path, seed: int, runs: int) -> dict[str, dict[str, float]]:
    return write_ompl_benchmark_log(
        log,
        arm,
        np.array([-1.0, 0.3]),
        np.array([1.0, -0.3]),
        parked,
        planners=("RRTConnect", "RRT", "PRM", "RRTstar"),
        runs=runs,
        budget=1.0,
        seed=seed,
    )


def table(m: Any) -> str:
    """The Markdown tables of the measured rows (the three parts)."""
    v = m[m["family"] == "validity"].iloc[0]
    s = m[m["family"] == "sweep"].iloc[0]
    o = m[m["family"] == "ompl"]
    lines = [
        "# Geometry throughput",
        "",
        f"seed {', '.join(map(str, sorted(set(map(int, m['seed'])))))}; best of 3-5 runs, one "
        "process, one core; test arm: 2 capsule links (numpy forward kinematics; the built-in "
        "arms' compiled check is measured in cells.md).",
        "",
        "| validity checks (arm vs parked arm, FCL) | checks/s | us/check |",
        "|---|---|---|",
        f"| one configuration per call | {v['single_checks_per_s']:,.0f} | "
        f"{v['us_per_check_single']:.1f} |",
        f"| batched along edges (motion validator) | {v['edge_checks_per_s']:,.0f} | "
        f"{v['us_per_check_edge']:.1f} |",
        f"| inside plan_detour (RRTConnect, 5 seeds, {v['plans_solved']:.0f} solved, "
        f"median {v['plan_median_ms']:.0f} ms) | {v['plan_checks_per_s']:,.0f} | "
        f"{v['us_per_check_in_plan']:.1f} |",
        "",
        f"| link-zone checks (scara4 zones, {s['zone_solids']:.0f} solids) | checks/s |",
        "|---|---|",
        f"| sweep (compiled loop, bounding capsules) | {s['vectorised_link_zone_checks_per_s']:,.0f} |",
        f"| plain FCL, one query per sample | {s['fcl_link_zone_checks_per_s']:,.0f} |",
        f"| ratio | {s['speedup']:.1f}x (vectorised covers every FCL contact: "
        f"{bool(s['vectorised_covers_fcl'])}) |",
        "",
        "| OMPL planner (detour query) | solved | median time s | median simplified length |",
        "|---|---|---|---|",
    ]
    for _, row in o.iterrows():
        lines.append(
            f"| {row['planner']} | {row['solved']:.2f} | {row['time']:.4f} | {row['length']:.3f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Run the sweep and write the tables and the OMPL log.

    Parameters
    ----------
    argv : list of str or None
        Command-line arguments (default: ``sys.argv``).
    """
    from workcell.experiments.analysis import measurements

    ap = argparse.ArgumentParser(description=__doc__)
    sweep_arguments(ap, fresh=True)
    args = ap.parse_args(argv)
    out = output_dir(args.quick)
    df = run_table_sweep(NAME, args, out)
    m = measurements(df)
    logs = [t for t in m.get("log", []) if isinstance(t, str) and t]
    if logs:
        (out / "geometry_ompl.log").write_text(logs[0])
    m = m.drop(columns=["log"], errors="ignore")
    path = publish(NAME, df, table(m), out, quick=args.quick, rows=m)
    print(path.read_text())


if __name__ == "__main__":
    main()
