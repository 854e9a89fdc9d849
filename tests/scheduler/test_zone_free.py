"""The zone-free relaxation (scheduler.exact.zone_free) and the tree's proofs with it.

Where the exact search cannot prove a problem itself (a binding blocking
oracle, an arm starting inside an exclusive zone), the tree search asks
whether any schedule of the problem without zones is shorter than its plan
(TreeOptions.zone_free_share): where none is, the plan is optimal and the
search stops. Checked here: what the relaxation keeps, that its optimum
bounds the true one on a seeded campaign of problems with zones, tools,
travel and blocking oracles, that the S2.6 ``parking`` cell is proven at
once, that a plan zones delay is never called optimal, and the rule.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from multiarm.errors import UsageError
from scheduler import exact, solve, validate
from scheduler.generate import generate_problem, random_problem
from scheduler.search import Evaluator, priority_order
from scheduler.tree import TreeOptions, _zone_free_problem, _zone_free_proof


@pytest.fixture(scope="module")
def parking():  # type: ignore[no-untyped-def]
    from workcell import compile_cell, load_example

    return compile_cell(load_example("parking")).problem


def test_the_relaxation_keeps_everything_but_the_zones() -> None:
    p = random_problem(3, 8, 3, 1, seed=4, blocking=True)
    q = exact.zone_free(p)
    assert q.n_windows == 0 and q.blocking is None
    assert all(zs == () for zs in q.arm_start_zones)
    assert q.name == f"{p.name} (zone-free)"
    assert q.task_names == p.task_names and q.task_preds == p.task_preds
    assert q.mode_tools == p.mode_tools and q.zone_names == p.zone_names
    for a, b in [
        (q.mode_task, p.mode_task),
        (q.mode_arm, p.mode_arm),
        (q.mode_duration, p.mode_duration),
        (q.task_release, p.task_release),
        (q.arm_available, p.arm_available),
    ]:
        assert np.array_equal(a, b)
    assert all(
        q.setup_time(a, i, j) == p.setup_time(a, i, j)
        for a in range(p.n_arms)
        for i in range(-1, p.n_tasks)
        for j in range(p.n_tasks)
    )
    assert p.n_windows > 0 and p.blocking is not None  # the original is untouched


@pytest.mark.parametrize("seed", range(6))
def test_the_relaxed_optimum_bounds_every_plan(seed: int) -> None:
    """Seeded campaign over arms, zones, tools, travel and oracles: the proven
    optimum without zones is at most the true optimum (where the exact search
    proves it) and at most every validated plan (tree and greedy)."""
    arms, tasks, zones = [(2, 6, 1), (3, 7, 2), (2, 8, 3)][seed % 3]
    for blocking in (False, True):
        p = random_problem(arms, tasks, zones, seed % 2, seed=seed, blocking=blocking)
        relaxed = exact.prove(exact.zone_free(p), None, 200_000)
        assert relaxed.proven
        plans = [solve(p, s, time_limit=None, seed=seed) for s in ("greedy", "tree")]
        for r in plans:
            assert r.schedule is not None
            assert relaxed.makespan <= validate(p, r.schedule) + 1e-9
        if not blocking:
            true = exact.prove(p, None, 200_000)
            if true.proven:
                assert relaxed.makespan <= true.makespan + 1e-9


def test_stop_at_first_answers_whether_a_shorter_schedule_exists() -> None:
    p = generate_problem("stations", 3, 10, 3, 1, seed=0)
    opt = exact.prove(p, None, 500_000)
    assert opt.proven
    found = exact.prove(p, None, 500_000, upper=opt.makespan + 5.0, stop_at_first=True)
    assert found.reason == "found" and not found.proven
    assert found.schedule is not None and found.makespan < opt.makespan + 5.0
    assert validate(p, found.schedule) == pytest.approx(found.makespan)
    none = exact.prove(p, None, 500_000, upper=opt.makespan - 1e-9, stop_at_first=True)
    assert none.proven and none.schedule is None


def test_the_tree_proves_the_parking_cell_at_once(parking) -> None:  # type: ignore[no-untyped-def]
    """S2.6: the best plan sends an arm around a parked one; no plan without
    zones is shorter, so the tree stops at its first round, proven, within a
    wall-clock limit and within a work limit alike (10 s of search and a racing
    CP-SAT proved nothing before)."""
    assert not exact.applicable(exact.without_idle_oracle(parking))[0]  # a binding oracle
    for kw in (
        {"time_limit": 30.0},
        {"time_limit": None, "options": TreeOptions(max_evaluations=5000)},
    ):
        r = solve(parking, "tree", seed=0, **kw)  # type: ignore[arg-type]
        assert r.status.value == "optimal", r.stats.extra
        assert r.stats.extra["zone_free"] == "proven"
        assert "improve" not in r.stats.phases  # stopped before any search
        assert r.bound == r.objective == pytest.approx(validate(parking, r.schedule))
        assert r.schedule is not None and r.schedule.blocking.sum() > 0  # it takes the detour


def test_a_longer_plan_is_never_called_optimal(parking) -> None:  # type: ignore[no-untyped-def]
    """_zone_free_proof on every plan of seeded random lists of parking: 'proven'
    only for plans at the relaxed optimum, never above it."""
    zf = exact.zone_free(parking)
    best = exact.prove(zf, None, 100_000)
    assert best.proven
    ev = Evaluator(parking)
    seen = set()
    rng = np.random.default_rng(3)
    for _ in range(40):
        sol = ev.evaluate(priority_order(parking, rng=rng, noise=2.0))
        if sol is None or round(sol.makespan, 6) in seen:
            continue
        seen.add(round(sol.makespan, 6))
        verdict, _nodes = _zone_free_proof(zf, sol, 0.0, 5.0, 20_000, None)
        if sol.makespan > best.makespan + 1e-6:
            assert verdict == "shorter without zones", (sol.makespan, best.makespan)
        else:
            assert verdict == "proven"
    assert len(seen) >= 2


@pytest.mark.parametrize("seed", range(4))
def test_plans_zones_delay_stay_feasible_with_valid_bounds(seed: int) -> None:
    """On random problems with binding oracles (the relaxation far below): the
    phase runs, the result validates, its bound is at most its makespan, and
    it is called optimal only where the relaxation's optimum meets it."""
    p = random_problem(3, 10, 2, 1, seed=seed, blocking=True)
    r = solve(p, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=3000))
    assert r.schedule is not None and validate(p, r.schedule) == pytest.approx(r.objective)
    assert r.bound <= r.objective + 1e-9
    assert "zone_free" in r.stats.extra
    if r.status.value == "optimal":
        relaxed = exact.prove(exact.zone_free(p), None, 500_000)
        assert relaxed.proven and relaxed.makespan >= r.objective - 1e-6


def test_the_rule(parking) -> None:  # type: ignore[no-untyped-def]
    opt = TreeOptions()
    assert _zone_free_problem(parking, False, opt) is not None
    assert _zone_free_problem(parking, True, opt) is None  # the exact search proves it itself
    assert _zone_free_problem(parking, False, TreeOptions(zone_free_share=0.0)) is None
    assert _zone_free_problem(parking, False, TreeOptions(zone_free_nodes=0)) is None
    assert _zone_free_problem(parking, False, TreeOptions(exact_max_tasks=4)) is None  # 5 tasks
    plain = random_problem(2, 6, 0, 1, seed=0)
    assert plain.n_windows == 0 and _zone_free_problem(plain, False, opt) is None  # nothing to drop
    # a problem the exact search proves itself never runs the phase
    routes = generate_problem("routes", 2, 8, 2, 0, seed=1)
    r = solve(routes, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=500))
    assert "zone_free" not in r.stats.extra


@pytest.mark.parametrize(
    ("name", "value"),
    list(itertools.product(["zone_free_share"], [-0.1, 1.0, "0.1", True]))
    + list(itertools.product(["zone_free_nodes"], [-1, 1.5, True])),
)
def test_bad_options_name_the_field(name: str, value: object) -> None:
    with pytest.raises(UsageError, match=f"TreeOptions.{name}"):
        TreeOptions(**{name: value})  # type: ignore[arg-type]


def test_a_plan_with_arms_starting_in_their_zones_is_proven() -> None:
    """bench_small's kind of problem: arms start inside exclusive zones, so the
    exact search does not apply and CP-SAT does not prove it in 2 s; the tree's
    plan meets the optimum without zones and is proven (a work limit: repeatable)."""
    p = random_problem(2, 10, 3, 1, seed=1, start_zones=True)
    assert exact.applicable(p)[1] == "an arm starts inside an exclusive zone"
    r = solve(p, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=2000))
    assert r.status.value == "optimal" and r.stats.extra["zone_free"] == "proven"
    relaxed = exact.prove(exact.zone_free(p), None, 1_000_000)
    assert relaxed.proven and relaxed.makespan == pytest.approx(r.objective)


def test_a_work_limit_caps_the_nodes() -> None:
    """With a work limit the phase takes at most 10 nodes per decode of it: here
    the branch and bound finds no shorter schedule without zones within 5,000
    nodes and stops (with 2,000 decodes the plan is proven, above)."""
    p = random_problem(2, 10, 3, 1, seed=1, start_zones=True)
    r = solve(p, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=500))
    assert r.stats.extra["zone_free"] == "stopped" and r.status.value == "feasible"
    assert 5000 <= r.stats.nodes <= 10 * 500 + 100  # the phase's, and the beam's few nodes
