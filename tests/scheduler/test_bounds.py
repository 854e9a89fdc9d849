"""Lower bounds: valid (never above an optimum) and each part doing its job."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scheduler import Model, Window, lower_bounds, solve, validate
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
