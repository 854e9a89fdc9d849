"""The tree search's exact phase on problems with an idle blocking oracle.

A compiled cell carries a blocking oracle (S2.6 detours); where it never
charges anything (``scheduler.exact.oracle_binding`` is False, as on
``supersigma`` and ``scara4``) the tree drops it and runs
``scheduler.exact.prove`` from its best schedule, so that the optimum is
returned and marked proven. Generated problems with an oracle whose cost is
zero stand in for such cells here (families not used for tuning).
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from scheduler import solve, validate
from scheduler.exact import oracle_binding, prove
from scheduler.generate import random_problem
from scheduler.tree import TreeOptions


def _idle(seed: int):  # type: ignore[no-untyped-def]
    p = random_problem(
        2 + seed % 2, 5 + seed % 3, 1 + seed % 2, seed % 2, seed=700 + seed, zone_fraction=0.9,
        blocking=True,
    )  # fmt: skip
    q = replace(p, blocking=replace(p.blocking, cost_s=0.0))  # type: ignore[type-var]
    assert oracle_binding(q) is False
    return q


@pytest.mark.parametrize("seed", range(6))
def test_work_limited_tree_proves_the_optimum_of_an_idle_oracle_problem(seed: int) -> None:
    p = _idle(seed)
    opt = prove(p, max_nodes=5_000_000)
    assert opt.proven
    options = TreeOptions(max_evaluations=300)
    a = solve(p, "tree", time_limit=None, seed=seed, options=options)
    b = solve(p, "tree", time_limit=None, seed=seed, options=options)
    assert a.stats.extra["exact"] == "prove, idle oracle dropped"
    assert a.status.value == "optimal" and a.schedule is not None
    assert a.objective == pytest.approx(opt.makespan, abs=1e-6)
    assert validate(p, a.schedule) == pytest.approx(a.objective, abs=1e-9)
    assert a.bound == a.objective
    assert (b.objective, b.status, b.stats.nodes) == (a.objective, a.status, a.stats.nodes)


def test_a_binding_oracle_is_kept_and_nothing_is_proven_by_prove() -> None:
    p = random_problem(2, 6, 2, 1, seed=701, zone_fraction=0.9, blocking=True)
    assert oracle_binding(p) is True
    res = solve(p, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=200))
    assert res.stats.extra["exact"] == "a blocking oracle is set"
    assert res.schedule is not None and validate(p, res.schedule) == res.objective


def test_a_small_node_budget_keeps_the_tree_plan_and_no_proof() -> None:
    """Stopped by its node budget, the exact phase leaves a valid plan, no
    better than the optimum and not marked proven unless it meets a bound."""
    p = _idle(5)
    opt = prove(p, max_nodes=5_000_000)
    options = TreeOptions(max_evaluations=300, exact_max_nodes=3)
    res = solve(p, "tree", time_limit=None, seed=0, options=options)
    assert res.schedule is not None
    assert res.objective >= opt.makespan - 1e-9
    assert res.bound <= opt.makespan + 1e-9
    if res.status.value == "optimal":
        assert res.objective == pytest.approx(opt.makespan, abs=1e-6)


def test_the_exact_phase_proves_on_the_portfolios_cores_with_a_wall_clock(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With a wall-clock limit the exact phase runs ``prove`` on the tree's
    ``workers`` (no worker process of the tree runs beside it); with a work
    limit in one process, so that the run stays repeatable."""
    from scheduler import exact

    real = exact.prove
    seen: list[int] = []

    def spy(*args, **kwargs):  # type: ignore[no-untyped-def]
        seen.append(int(kwargs.get("workers", 1)))
        return real(*args, **kwargs)

    monkeypatch.setattr(exact, "prove", spy)
    p = _idle(1)
    opt = real(p, max_nodes=5_000_000)
    res = solve(p, "tree", time_limit=5, seed=0, options=TreeOptions(workers=2))
    assert res.stats.extra["exact"] == "prove, idle oracle dropped"
    assert 2 in seen  # the exact phase's call (a zone-free proof may call it too)
    assert res.status.value == "optimal"
    assert res.objective == pytest.approx(opt.makespan, abs=1e-6)
    seen.clear()
    solve(p, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=300, workers=2))
    assert seen and set(seen) == {1}
