"""The coordinator's OMPL-planned detour (S2.12 "continue with alternative trajectory").

The cell here is ``scara4`` without the space grid plus a fifth SCARA with
no capability, ``pole``, that never works and stands at its start joints by
the east side: the compile drops the modes whose motions would hit it, which
changes the greedy plan so that ``se``, on its way through a task, finds
another arm standing in its way. Its next station touches that arm too, so
the detour runs over the whole contact stretch, past the stations in it, to
the first clear pose of the task's leg after the contact (holding the zones
of the stations it passes). The straight joint move touches the standing
arm; OMPL (RRTConnect, seeded, work-limited by ``SimOptions.detour_checks``)
plans a way around it. The arm follows that path, goes on with its task from
there, the independent safety monitor (live, the default) stays quiet and
every task completes. Everything is read from the public records (the
trace, the motion records), not from the planner's calls.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import workcell
from scheduler import solve
from workcell import compile_cell, simulate
from workcell.cell import load_cell
from workcell.geometry import ObstacleSet, check_path
from workcell.sim.events.trace import Trace
from workcell.sim.harness.monitor import SafetyMonitor

POLE = """
[arms.pole]
type = "scara"
base = [0.9, 0.3, 0.0, 0.0]
link_lengths = [0.05, 0.05]
z_range = [0.0, 0.3]
arm_height = 0.6
capabilities = []
start = [0.0, 0.0, 0.3, 0.0]
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    text = (Path(workcell.__file__).parent / "examples" / "scara4.toml").read_text()
    text = text.replace("[compile]\n", "[compile]\ngrid = 0\n") + POLE
    path = tmp_path_factory.mktemp("cell") / "cell.toml"
    path.write_text(text, encoding="utf-8")
    cc = compile_cell(load_cell(path))
    plan = solve(cc.problem, "greedy", seed=0).schedule
    assert plan is not None
    result = simulate(cc, plan, seed=0)  # the live safety monitor is on
    return {"cc": cc, "plan": plan, "result": result}


def _detour_legs(r: Any, arm: str) -> list[Any]:
    log = next(c for c in r.arm_logs if c.name == arm)
    return [rec for rec in log.records if rec.leg is not None and rec.leg.kind == "detour"]


def test_a_parked_arm_in_the_way_gets_a_planned_detour(run: dict[str, Any]) -> None:
    r, cc = run["result"], run["cc"]
    # the trace shows it, as an alternative around the standing arm
    detours = [e for e in r.trace if e.kind == "detour" and "alternative trajectory" in e.detail]
    assert len(detours) == 1
    ev = detours[0]
    found = re.search(r"around arm\(s\) '(\w+)'", ev.detail)
    assert ev.arm == "se" and found is not None
    blocker = found.group(1)
    assert r.metrics.detours == len([e for e in r.trace if e.kind == "detour"])
    # the executed leg is a planned path (OMPL: more than the straight move's two knots)
    (rec, *_) = _detour_legs(r, "se")
    tr = rec.leg.trajectory
    path = tr.sample(np.asarray(tr.knot_times))
    assert len(path) >= 3
    # around the arm where it stood: the straight joint move touches it, the path does not
    other = next(c for c in r.arm_logs if c.name == blocker)
    at = np.array([rec.start])
    q_other = next(x for x in other.records if x.start <= rec.start <= x.end).joints_at(at)[0]
    obstacles = ObstacleSet.from_arm(cc.cell.arm(blocker), q_other)
    arm = cc.cell.arm("se")
    assert not check_path(arm, np.stack([path[0], path[-1]]), obstacles, step=0.002)
    assert check_path(arm, path, obstacles, step=0.002)


def test_the_arm_follows_the_planned_path_and_the_task_completes(run: dict[str, Any]) -> None:
    r = run["result"]
    se = next(c for c in r.arm_logs if c.name == "se")
    legs = [rec for rec in se.records if rec.leg is not None and rec.leg.kind == "detour"]
    assert legs, "the detour leg was never executed"
    leg = legs[0].leg
    # the executed leg is the OMPL path timed with the arm's drives, from
    # where the arm stood to a pose of its task's trajectory ...
    knots = leg.trajectory.sample(np.asarray(leg.trajectory.knot_times))
    before = next(x for x in se.records if x.end == legs[0].start and x.leg is not None)
    assert np.allclose(knots[0], before.joints_at(np.array([before.end]))[0], atol=1e-9)
    after = next(x for x in se.records if x.start == legs[-1].end and x.leg is not None)
    assert after.leg.kind == "task"
    assert np.allclose(knots[-1], after.joints_at(np.array([after.start]))[0], atol=1e-9)
    # ... driven from its start to its end
    assert sum(r.end - r.start for r in legs if r.moving) == pytest.approx(leg.duration, abs=1e-9)
    ev = next(e for e in r.trace if e.kind == "detour" and "alternative" in e.detail)
    assert legs[0].start == pytest.approx(ev.time, abs=1e-12)
    # the detoured task goes on from the station and completes, as do all the others
    task = ev.task
    tf = r.tasks_frame().set_index("task")
    assert tf.loc[task, "status"] == "done" and tf.loc[task, "arm"] == "se"
    assert tf.loc[task, "end"] > ev.time
    assert set(tf["status"]) == {"done"}
    assert r.metrics.detours >= 1


def test_the_safety_monitor_watched_the_detour_and_stayed_quiet(run: dict[str, Any]) -> None:
    r = run["result"]
    assert not [e for e in r.trace if e.kind == "monitor"]
    assert r.safety is not None and r.safety.samples > 0
    se = next(c for c in r.arm_logs if c.name == "se")
    detour = next(rec for rec in se.records if rec.leg is not None and rec.leg.kind == "detour")
    assert detour.end - detour.start > 2 * 0.02  # several samples while the detour ran
    # the post-run form of the monitor agrees: no contact, no broken invariant
    t_end = max(rec.end for c in r.arm_logs for rec in c.records)
    SafetyMonitor(run["cc"], 0.02).check(r.arm_logs, t_end, Trace())
