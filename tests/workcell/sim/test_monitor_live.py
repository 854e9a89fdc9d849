"""The live safety monitor (workcell.sim.harness.monitor.LiveMonitor; S2.5-S2.7, S2.12).

It runs inside the simulation as a kernel process and stops the run at the
first violating sample; the post-run check (``monitor="post"``) reads the
same motion records after the run and must find the same first violation.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Any

import numpy as np
import pytest
from numba import njit

from multiarm.errors import UsageError
from scheduler import Schedule, solve
from workcell import SimOptions, compile_cell, load_example, simulate
from workcell.geometry import CollisionWorld
from workcell.sim import EmergencyStop
from workcell.sim.harness.monitor import SafetyMonitor, SafetyViolation, segment_dist2

PERIOD = 0.02


@pytest.fixture(scope="module")
def supersigma() -> Any:
    return compile_cell(load_example("supersigma"))


def _greedy(cc: Any) -> Schedule:
    plan = solve(cc.problem, "greedy", seed=0).schedule
    assert plan is not None
    return plan


def _violation(cc: Any, plan: Schedule, monitor: str, **kw: Any) -> SafetyViolation:
    with pytest.raises(SafetyViolation) as info:
        simulate(cc, plan, seed=0, options=SimOptions(monitor=monitor, **kw))
    return info.value


@pytest.mark.parametrize("name", ["supersigma", "scara4"])
def test_a_colliding_run_stops_at_the_first_sample_the_post_run_check_reports(name: str) -> None:
    """Without the space grid and the coordinator's geometric check the
    greedy plans collide (tests/workcell/test_space_grid.py)."""
    cc = compile_cell(dataclasses.replace(load_example(name), grid=0.0))
    plan = _greedy(cc)
    live = _violation(cc, plan, "live", geometry_guard=False)
    post = _violation(cc, plan, "post", geometry_guard=False)
    assert "collide" in str(live) and str(live) == str(post)
    assert live.time == post.time and live.arms == post.arms
    # a sample of the monitor's grid, found there and then
    assert live.found == live.time
    assert live.time / PERIOD == pytest.approx(round(live.time / PERIOD), abs=1e-9)
    # the run stopped there: the partial trace ends with the monitor's event
    assert live.trace is not None and post.trace is not None
    events = list(live.trace)
    monitor = [e for e in events if e.kind == "monitor"]
    assert len(monitor) == 1 and monitor[0].time == live.time and monitor[0].detail == str(live)
    assert max(e.time for e in events) == live.time
    # the post-run check let the run go on to its end
    assert post.found > live.time and len(post.trace) > len(live.trace)
    assert max(e.time for e in post.trace if e.kind != "monitor") > live.time
    # FCL at every sample, without the pre-tests: the same first contact
    run = simulate(cc, plan, seed=0, options=SimOptions(monitor=False, geometry_guard=False))
    assert _first_contact_by_fcl_alone(cc, run, live.time + PERIOD / 2) == live.time


def _first_contact_by_fcl_alone(cc: Any, run: Any, until: float) -> float:
    world = CollisionWorld()
    for arm, q in zip(cc.cell.arms, cc.cell.start, strict=True):
        world.add_arm(arm, q=q)
    times = np.arange(math.floor(until / PERIOD) + 1, dtype=np.float64) * PERIOD
    tfs = [
        arm.shape_transforms(SafetyMonitor.joints(c, times))
        for arm, c in zip(cc.cell.arms, run.arm_logs, strict=True)
    ]
    names = [arm.name for arm in cc.cell.arms]
    for i, t in enumerate(times):
        for a, b in itertools.combinations(range(len(names)), 2):
            world.set_group_transforms(names[a], tfs[a][i])
            world.set_group_transforms(names[b], tfs[b][i])
            if world.collide(names[a], names[b]):
                return float(t)
    return math.inf


def test_a_broken_zone_invariant_stops_the_run_live(supersigma: Any) -> None:
    """Two arms in one exclusive zone (the coordinator's zone checks off):
    the plan puts sort_queen on the right arm while sort_king runs on the
    left one; the first broken invariant is the shared zone 'fixture'."""
    p = supersigma.problem
    left, right = p.arm_names.index("left"), p.arm_names.index("right")
    modes, starts = [0] * p.n_tasks, [0.0] * p.n_tasks
    end = [0.0] * p.n_tasks
    ready, prev = 0.0, -1
    for t in p.topological_order:  # every task on the left arm, one after the other
        m = int(p.mode_of[left, t])
        s = max([ready + p.setup_time(left, prev, t)] + [end[q] for q in p.task_preds[t]])
        modes[t], starts[t] = m, s
        end[t] = s + float(p.mode_duration[m])
        ready, prev = end[t], t
    king, queen = p.task_names.index("sort_king"), p.task_names.index("sort_queen")
    modes[queen] = int(p.mode_of[right, queen])
    starts[queen] = starts[king] + 5.0
    bad = Schedule.from_starts(p, modes, starts)
    kw = {"zone_protocol": False, "geometry_guard": False}
    live = _violation(supersigma, bad, "live", **kw)
    post = _violation(supersigma, bad, "post", **kw)
    msg = "arms 'left' and 'right' both moving in shared zone 'fixture'"
    assert str(live).startswith(msg) and str(post).startswith(msg)
    assert live.time == post.time
    # found as soon as the overlap is longer than the tolerance (1 us)
    assert live.time < live.found <= live.time + 2e-6
    assert live.trace is not None
    assert [e.time for e in live.trace if e.kind == "monitor"] == [live.found]
    assert max(e.time for e in live.trace) == live.found


@pytest.mark.parametrize("name", ["supersigma", "scara4"])
def test_nominal_runs_pass_and_the_monitor_does_not_change_them(name: str) -> None:
    cc = compile_cell(load_example(name))
    plan = _greedy(cc)
    on = simulate(cc, plan, seed=0)  # live monitor, the default
    off = simulate(cc, plan, seed=0, options=SimOptions(monitor=False))
    assert on.safety is not None and off.safety is None
    assert on.safety.samples > 0
    with pytest.warns(DeprecationWarning, match="SimResult.safety"):  # the old name, one release
        assert on.monitor is on.safety
    assert not [e for e in on.trace if e.kind == "monitor"]
    assert set(on.tasks_frame()["status"]) == {"done"}
    # every sample while arms move is decided, most of them ahead in batches
    # without a wake of their own (no pair within reach, no event in between)
    assert _moving_samples(on, PERIOD) <= on.safety.samples
    assert on.safety.wakes < on.safety.samples / 2
    # the monitor only reads: the same run, event for event
    assert on.trace.to_dataframe().equals(off.trace.to_dataframe())
    assert on.metrics.executed_makespan == off.metrics.executed_makespan


def _moving_samples(result: Any, period: float) -> int:
    """Grid instants ``k * period`` at which some arm is moving (from the records)."""
    t_end = max(rec.end for c in result.arm_logs for rec in c.records)
    k = np.arange(math.ceil(t_end / period) + 1)
    t = k * period
    moving = np.zeros(len(t), dtype=bool)
    for c in result.arm_logs:
        for rec in c.records:
            if rec.leg is not None and rec.moving:
                moving |= (t >= rec.start) & (t < rec.end)
    return int(moving.sum())


def test_idle_stretches_cost_no_samples(supersigma: Any) -> None:
    """An emergency stop holds every arm for 200 s: the monitor samples
    while some arm moves (and once after an arm comes to rest), not every
    20 ms of the stop."""
    plan = _greedy(supersigma)
    r = simulate(supersigma, plan, seed=0, faults=[EmergencyStop(20.0, 200.0)])
    mon = r.safety
    assert mon is not None
    t_end = max(rec.end for c in r.arm_logs for rec in c.records)
    grid = math.ceil(t_end / PERIOD) + 1
    moving = _moving_samples(r, PERIOD)
    records = sum(len(c.records) for c in r.arm_logs)
    assert moving <= mon.samples <= moving + records + 1
    assert mon.samples < grid - 200.0 / PERIOD  # the stop cost no sample
    assert mon.wakes < mon.samples + 2 * r.metrics.events  # at most one wake per event


@njit(cache=False)
def _many(p0: Any, p1: Any, q0: Any, q1: Any, out: Any) -> None:
    for i in range(p0.shape[0]):
        out[i] = segment_dist2(p0[i], p1[i], q0[i], q1[i])


def test_the_capsule_pre_test_never_overestimates_a_distance() -> None:
    """The pre-test keeps every pair FCL could find touching: the segment
    distance is never above the true one (brute force on fine samples)."""

    rng = np.random.default_rng(7)
    n = 1000
    p0, q0 = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    p1 = p0 + rng.normal(size=(n, 3)) * rng.integers(0, 2, (n, 1))  # some are points
    q1 = q0 + rng.normal(size=(n, 3)) * rng.integers(0, 2, (n, 1))
    q1[:200] = q0[:200] + 0.7 * (p1[:200] - p0[:200])  # parallel
    q1[200:400] = q0[200:400] + 0.7 * (p1[200:400] - p0[200:400]) + 1e-7  # nearly
    got = np.zeros(n)
    _many(p0, p1, q0, q1, got)
    s = np.linspace(0.0, 1.0, 201)
    P = p0[:, None, :] + (p1 - p0)[:, None, :] * s[None, :, None]
    Q = q0[:, None, :] + (q1 - q0)[:, None, :] * s[None, :, None]
    best = np.full(n, np.inf)
    for k in range(len(s)):
        best = np.minimum(best, ((P[:, k : k + 1, :] - Q) ** 2).sum(-1).min(axis=1))
    # squared distances; the pre-test adds 0.1 mm of slack on top
    assert np.all(np.sqrt(got) <= np.sqrt(best) + 1e-6)


def test_monitor_values(supersigma: Any) -> None:
    plan = _greedy(supersigma)
    post = simulate(supersigma, plan, seed=0, options=SimOptions(monitor="post"))
    assert post.safety is None and set(post.tasks_frame()["status"]) == {"done"}
    with pytest.raises(UsageError, match="monitor must be True, False, 'live' or 'post'"):
        simulate(supersigma, plan, options=SimOptions(monitor="sometimes"))


@pytest.mark.parametrize(("name", "separate"), [("supersigma", True), ("scara4", False)])
def test_live_and_post_run_agree_on_randomly_broken_plans(name: str, separate: bool) -> None:
    """Seeded random edits of the greedy plan (arms swapped, starts moved),
    run with the coordinator's zone and geometric checks off: the live
    monitor and the post-run check name the same first violation, or none."""
    cc = compile_cell(dataclasses.replace(load_example(name), grid=0.3 if separate else 0.0))
    p = cc.problem
    base = _greedy(cc)
    rng = np.random.default_rng(1)
    seen = 0
    for _ in range(4):
        modes, starts = base.mode.copy(), base.start.copy()
        for t in rng.choice(p.n_tasks, size=3, replace=False):
            m = int(p.mode_of[int(rng.integers(p.n_arms)), t])
            if m >= 0:
                modes[t] = m
            starts[t] = max(0.0, float(starts[t]) + float(rng.uniform(-20.0, 5.0)))
        plan = Schedule.from_starts(p, [int(m) for m in modes], [float(s) for s in starts])
        found: dict[str, Any] = {}
        for how in ("live", "post"):
            try:
                simulate(
                    cc,
                    plan,
                    seed=0,
                    options=SimOptions(monitor=how, zone_protocol=False, geometry_guard=False),
                )
                found[how] = None
            except SafetyViolation as exc:
                found[how] = (
                    exc.time,
                    exc.arms,
                    str(exc).split(" during [")[0].split(" from t")[0],
                )
        assert found["live"] == found["post"]
        seen += found["live"] is not None
    assert seen >= 2  # the edits do break the plans
