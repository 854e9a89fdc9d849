"""The coordinator's OMPL-planned detour (S2.12 "continue with alternative trajectory").

No built-in cell reaches it: with the space grid the zones keep arms apart
(the geometric check never stops one), and without it (``scara4`` with
``grid = 0``) every geometric stop has the other arm standing
on the mover's next station (``goal_in_collision``: no detour, the arms back
off instead). The cell here is ``scara4`` without the space grid plus a
fifth SCARA with no capability, ``pole``, that never works and stands at its
start joints by the east side: the compile drops the modes whose motions
would hit it, which changes the greedy plan so that ``se``, on its way to
the next station of a task, finds ``nw`` parked in its way while that
station is free. The straight joint move touches ``nw`` too; OMPL
(RRTConnect, seeded, work-limited) plans a way around it. The arm follows
that path, goes on with its task from the station, the independent safety
monitor (live, the default) stays quiet and every task completes.

The search needs about 4100 configuration checks, within the coordinator's
work limit (``detour_checks``, 10,000).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import workcell
from scheduler import solve
from workcell import compile_cell, simulate
from workcell.cell import load_cell
from workcell.geometry import check_path, plan_detour
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
    found: list[Any] = []
    mp = pytest.MonkeyPatch()
    real_plan = plan_detour  # the function the coordinator imported

    def spy(*args: Any, **kwargs: Any) -> Any:  # records what the planner answered
        res = real_plan(*args, **kwargs)
        found.append((args, kwargs, res))
        return res

    mp.setattr("workcell.sim.coordination.geometric.plan_detour", spy)
    try:
        result = simulate(cc, plan, seed=0)  # the live safety monitor is on
    finally:
        mp.undo()
    return {"cc": cc, "plan": plan, "result": result, "found": found}


def test_a_parked_arm_in_the_way_gets_a_planned_detour(run: dict[str, Any]) -> None:
    r = run["result"]
    solved = [(a, k, res) for a, k, res in run["found"] if res.status == "solved"]
    assert len(solved) == 1
    args, _kwargs, res = solved[0]
    arm, q_start, q_goal, obstacles = args
    assert arm.name == "se" and obstacles.name == "standing arms"
    # a real detour: the straight joint move touches the pole, the path does not
    assert not check_path(arm, np.stack([q_start, q_goal]), obstacles, step=0.002)
    assert len(res.path) >= 3
    assert check_path(arm, res.path, obstacles, step=0.002)
    # the trace shows it, as an alternative around the standing pole
    detours = [e for e in r.trace if e.kind == "detour" and "alternative trajectory" in e.detail]
    assert len(detours) == 1
    assert detours[0].arm == "se" and "around arm(s) 'nw'" in detours[0].detail
    assert r.metrics.detours == len([e for e in r.trace if e.kind == "detour"])


def test_the_arm_follows_the_planned_path_and_the_task_completes(run: dict[str, Any]) -> None:
    r = run["result"]
    (_args, _kwargs, res) = next(x for x in run["found"] if x[2].status == "solved")
    se = next(c for c in r.arm_logs if c.name == "se")
    legs = [rec for rec in se.records if rec.leg is not None and rec.leg.kind == "detour"]
    assert legs, "the detour leg was never executed"
    leg = legs[0].leg
    # the executed leg is the OMPL path timed with the arm's drives ...
    knots = leg.trajectory.sample(np.asarray(leg.trajectory.knot_times))
    assert np.allclose(knots, res.path, atol=1e-9)
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
