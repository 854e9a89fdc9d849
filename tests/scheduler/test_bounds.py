"""Lower bounds: valid (never above an optimum) and each part doing its job."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scheduler import Model, Problem, Window, lower_bounds, solve, validate
from scheduler.generate import random_problem


def test_load_lp_handles_different_speeds() -> None:
    # 6 tasks; arm fast does each in 1, arm slow in 3: fractional best is 6 / (1 + 1/3) = 4.5
    m = Model()
    m.add_arm("fast")
    m.add_arm("slow")
    for i in range(6):
        m.add_task(f"t{i}")
        m.add_mode(f"t{i}", "fast", 1.0)
        m.add_mode(f"t{i}", "slow", 3.0)
    lb = lower_bounds(m.build())
    assert lb.load == pytest.approx(4.5, abs=1e-6)
    assert lb.capability == pytest.approx(3.0)  # the plain average of shortest modes: weaker
    assert lb.value == pytest.approx(4.5, abs=1e-6)


def test_capability_subset_bound() -> None:
    # three tasks only arm a can do (4 each), one any arm can do
    m = Model()
    for a in "abc":
        m.add_arm(a)
    for i in range(3):
        m.add_task(f"only{i}")
        m.add_mode(f"only{i}", "a", 4.0)
    m.add_task("any")
    for a in "abc":
        m.add_mode("any", a, 1.0)
    lb = lower_bounds(m.build())
    assert lb.capability == 12.0 and lb.value == 12.0


def test_exclusive_zone_bound() -> None:
    # four tasks on four arms, each in zone z for 3 s after a 1 s approach: the zone serialises them
    m = Model()
    m.add_zone("z")
    for i in range(4):
        m.add_arm(f"a{i}")
        m.add_task(f"t{i}")
        m.add_mode(f"t{i}", f"a{i}", 5.0, windows=[Window("z", 1.0, 4.0)])
    lb = lower_bounds(m.build())
    assert lb.resources == 1.0 + 4 * 3.0 + 1.0
    assert lb.resource_name == "zone z"
    r = solve(m.build(), "cpsat", time_limit=None, workers=1)
    assert r.objective == 14.0 and r.status.value == "optimal"


def test_release_and_critical_path() -> None:
    m = Model()
    m.add_arm("a", available=2.0)
    m.add_task("x", release=5.0)
    m.add_task("y", predecessors=["x"])
    m.add_mode("x", "a", 1.0)
    m.add_mode("y", "a", 2.0)
    assert lower_bounds(m.build()).critical_path == 8.0


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.integers(2, 3), st.integers(4, 7))
def test_bound_never_exceeds_the_optimum(seed: int, arms: int, tasks: int) -> None:
    p = random_problem(arms, tasks, 3, 1, seed=seed, start_zones=seed % 3 == 0)
    r = solve(p, "cpsat", time_limit=None, workers=1)
    assert r.status.value == "optimal"
    assert lower_bounds(p).value <= r.objective + 1e-6


def test_the_load_lp_counts_each_zone_as_a_machine() -> None:
    """Modes that hold one exclusive zone for a different share of their time:
    the arms alone allow 6 s, the zone's row of the LP about 7.2 s, and every
    schedule is at least that long."""
    m = Model("zone row")
    a, b, z = m.add_arm("a"), m.add_arm("b"), m.add_zone("z")
    for i in range(4):
        t = m.add_task(f"t{i}")
        m.add_mode(t, a, 3.0, windows=[Window(z, 0.0, 3.0)])
        m.add_mode(t, b, 3.0, windows=[Window(z, 0.0, 1.0)])
    p = m.build()
    parts = lower_bounds(p)
    # X tasks on a: max(3 X, 3 (4 - X), 3 X + (4 - X)) is least at X = 1.6
    assert parts.load == pytest.approx(36 / 5, abs=1e-6)
    assert parts.value >= parts.load
    assert validate(p, solve(p, "tree", time_limit=None).schedule) >= parts.value - 1e-9


# --- one-machine (Jackson) bounds on the resources, heads with travel ---------------------


def _jobs() -> st.SearchStrategy[list[tuple[float, float, float]]]:
    job = st.tuples(st.integers(1, 6), st.integers(0, 8), st.integers(0, 8))
    return st.lists(
        job.map(lambda j: (float(j[0]), float(j[1]), float(j[2]))), min_size=1, max_size=6
    )


@settings(max_examples=200, deadline=None)
@given(_jobs())
def test_jackson_is_the_best_subset_bound_and_below_every_sequence(
    jobs: list[tuple[float, float, float]],
) -> None:
    """Carlier: the preemptive schedule's value is the maximum over subsets of
    (least head + lengths + least tail), and no one-machine sequence does better."""
    import itertools

    from scheduler.bounds import jackson_preemptive

    best_subset = max(
        min(jobs[j][1] for j in s) + sum(jobs[j][0] for j in s) + min(jobs[j][2] for j in s)
        for k in range(1, len(jobs) + 1)
        for s in itertools.combinations(range(len(jobs)), k)
    )
    jps = jackson_preemptive(jobs)
    assert jps == best_subset
    best_sequence = math.inf
    for perm in itertools.permutations(range(len(jobs))):
        now, value = 0.0, 0.0
        for j in perm:
            now = max(now, jobs[j][1]) + jobs[j][0]
            value = max(value, now + jobs[j][2])
        best_sequence = min(best_sequence, value)
    assert jps <= best_sequence


def test_one_machine_bound_sees_two_long_tails_in_one_zone() -> None:
    """Two tasks hold zone z for 2 s and run 5 s more, a third holds it 1 s: the
    second of the first two to enter ends at 9 at the earliest. The arms (7 s),
    the zone's work (5 s) and the head-body-tail bound (5 s) all say less."""
    m = Model()
    z = m.add_zone("z")
    for arm, d, e in [("a", 7.0, 2.0), ("b", 7.0, 2.0), ("c", 1.0, 1.0)]:
        m.add_arm(arm)
        m.add_task(f"t{arm}")
        m.add_mode(f"t{arm}", arm, d, windows=[Window(z, 0.0, e)])
    p = m.build()
    lb = lower_bounds(p)
    assert lb.resources == 5.0 and lb.load == pytest.approx(7.0, abs=1e-6)
    assert lb.one_machine == 9.0 and lb.one_machine_name == "zone z" and lb.value == 9.0
    r = solve(p, "cpsat", time_limit=None, workers=1)
    assert r.status.value == "optimal" and r.objective == 9.0


def test_heads_count_the_travel_into_each_mode() -> None:
    """An arm that must travel 4 s from its initial pose before its only task:
    the critical path and the zone's head both count the travel."""
    from scheduler.bounds import mode_heads
    from scheduler.setup import MatrixSetup

    m = Model()
    z = m.add_zone("z")
    m.add_arm("a")
    m.add_task("t")
    m.add_mode("t", "a", 3.0, windows=[Window(z, 1.0, 2.0)])
    m.set_setup(MatrixSetup([[[4.0], [0.0]]]))  # arm a: 4 s from its initial pose
    p = m.build()
    est_mode, est, _ = mode_heads(p)
    assert est_mode.tolist() == [4.0] and est.tolist() == [4.0]
    lb = lower_bounds(p)
    assert lb.critical_path == 7.0 and lb.one_machine == 7.0
    assert validate(p, solve(p, "greedy").schedule) == 7.0


def _contended(seed: int, arms: int, tasks: int) -> Problem:
    """Few zones and tools that most tasks need (where the one-machine bound matters)."""
    return random_problem(
        arms,
        tasks,
        2,
        1,
        seed=seed,
        zone_fraction=0.9,
        tool_fraction=0.3,
        start_zones=seed % 2 == 0,
    )


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.integers(2, 3), st.integers(4, 7))
def test_every_part_is_below_the_optimum_on_contended_problems(
    seed: int, arms: int, tasks: int
) -> None:
    p = _contended(seed, arms, tasks)
    r = solve(p, "cpsat", time_limit=None, workers=1)
    assert r.status.value == "optimal"
    lb = lower_bounds(p)
    for part in (lb.critical_path, lb.load, lb.capability, lb.resources, lb.one_machine):
        assert part <= r.objective + 1e-6
    assert lb.value <= r.objective + 1e-6


@pytest.mark.parametrize("seed", range(6))
def test_bounds_below_every_plan_and_above_the_old_parts(seed: int) -> None:
    """Seeded larger problems (travel, start zones, a blocking oracle on odd seeds):
    the bound is below the makespan of every plan found, the new parts at least
    the old ones (heads without travel: :func:`scheduler.bounds.heads_and_tails`)."""
    import numpy as np

    from scheduler.bounds import heads_and_tails

    p = random_problem(
        4, 40, 3, 2, seed=seed, start_zones=True, blocking=seed % 2 == 1, zone_fraction=0.8
    )
    lb = lower_bounds(p)
    for solver in ("greedy", "tree"):
        r = solve(p, solver, time_limit=None if solver == "greedy" else 1.0, seed=seed)
        assert validate(p, r.schedule) >= lb.value - 1e-9
    est, mind, tail = heads_and_tails(p)
    assert lb.critical_path >= float(np.max(est + mind + tail)) - 1e-9
    assert lb.one_machine >= lb.resources - 1e-9
    assert lb.value == max(lb.critical_path, lb.load, lb.capability, lb.resources, lb.one_machine)
