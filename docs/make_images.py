"""Write the figures of docs/plots.md into docs/images/ (run from the repository root).

    .venv/bin/python docs/make_images.py

One run of the built-in ``supersigma`` cell (two Cartesian gantries, SEEDS.md
S1), planned by the greedy solver (seed 0) and simulated (seed 0) with one
fault of every kind, drawn by every plot of :mod:`workcell.viz.plots`; and
the wait summary of that run, printed. Deterministic: the same images every
time (up to the fonts and the matplotlib version).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

OUT = Path(__file__).resolve().parent / "images"

ZONES = ["base_feeder", "bins", "board", "cap_feeder", "conveyor", "fixture", "pin_feeder"]
"""Every zone of the cell: the activation changes nothing, and is marked."""

FAULTS: list[dict[str, Any]] = [
    {"kind": "late_part", "part": "pin", "delay": 6.0},
    {"kind": "crash", "arm": "left", "at": 4.0},
    {"kind": "lost_sync", "arm": "right", "axis": 0, "at": 3.0, "steps": 80},
    {"kind": "message_loss", "probability": 0.02},
    {"kind": "emergency_stop", "at": 14.0, "duration": 3.0},
    {"kind": "activate_zones", "at": 22.0, "zones": ZONES},
    {"kind": "arm_failure", "arm": "right", "at": 90.0},
]
"""One fault of every kind (README.md, docs/simulation.md)."""


def main() -> list[Path]:
    """Compile, plan, simulate, draw; return the images written."""
    from scheduler import solve
    from workcell import compile_cell, load_example, simulate
    from workcell.viz import (
        gantt,
        joint_timeline,
        render_instants,
        wait_summary,
        zone_timeline,
    )

    OUT.mkdir(exist_ok=True)
    cc = compile_cell(load_example("supersigma"))
    plan = solve(cc.problem, "greedy", seed=0).schedule
    run = simulate(cc, plan, seed=0, faults=FAULTS)
    end = float(run.metrics.executed_makespan)
    figures = {
        "gantt_plan.png": gantt(cc, plan),
        "gantt_run.png": gantt(cc, plan, run),
        "zones.png": zone_timeline(run, arms=cc, title="supersigma: zone occupancy, executed"),
        "instants.png": render_instants(cc, run, [0.0, 0.25 * end, 0.5 * end, 0.75 * end]),
        "joints.png": joint_timeline(cc, run),
    }
    paths = []
    for name, fig in figures.items():
        path = OUT / name
        fig.savefig(path, dpi=90)
        paths.append(path)
    for row in wait_summary(run, cc):
        print(row)
    return paths


if __name__ == "__main__":
    for p in main():
        print(p)
