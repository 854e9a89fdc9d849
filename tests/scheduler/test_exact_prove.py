"""The exact branch and bound ``scheduler.exact.prove`` against CP-SAT's proofs.

On small generated problems (integer data, so CP-SAT's general model is
exact and its OPTIMAL status is a proof of the true problem, waits at zone
borders included, S2.6, S2.12) the branch and bound proves the same optimum
and its schedule validates. The families vary arms, zones, tools, setups,
waits and start zones; none of them was used to tune the method (it was
developed on the compiled cells ``supersigma`` and ``scara4``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from scheduler import solve, validate
from scheduler.exact import prove, relevant_borders
from scheduler.generate import random_problem


def _family(seed: int) -> tuple[dict[str, object], bool]:
    """Problem keywords and the waits flag of a seeded case."""
    kw: dict[str, object] = {
        "n_arms": 2 + seed % 2,
        "n_tasks": 4 + seed % 4,
        "n_zones": 1 + seed % 3,
        "n_tools": seed % 3,
        "seed": 100 + seed,
        "setups": seed % 4 != 3,
        "zone_fraction": 0.9,
        "tool_fraction": 0.3,
    }
    return kw, seed % 5 != 4


@pytest.mark.parametrize("seed", range(24))
def test_prove_meets_cpsat_proven_optimum(seed: int) -> None:
    kw, waits = _family(seed)
    p = random_problem(**kw)  # type: ignore[arg-type]
    cp = solve(p, "cpsat", time_limit=20, seed=0, waits=waits, workers=1)
    if cp.status.value != "optimal":
        pytest.skip("CP-SAT did not prove this one")  # pragma: no cover - not seen
    res = prove(p, max_nodes=5_000_000, waits=waits)
    assert res.proven and res.reason == "proven"
    assert res.schedule is not None
    assert res.makespan == pytest.approx(cp.objective, abs=1e-6)
    assert validate(p, res.schedule) == pytest.approx(res.makespan, abs=1e-9)
    assert res.bound == res.makespan
    # started from a valid schedule (the tree's), it proves the same optimum
    tree = solve(p, "tree", time_limit=0.3, seed=seed, waits=waits)
    again = prove(p, max_nodes=5_000_000, waits=waits, incumbent=tree.schedule)
    assert again.proven and again.makespan == pytest.approx(cp.objective, abs=1e-6)
    assert again.makespan <= tree.objective + 1e-9
    if seed % 3 == 0:  # without the sequence level (modes, then pairwise orders only)
        plain = prove(p, max_nodes=5_000_000, waits=waits, sequences=False)
        assert plain.proven and plain.makespan == pytest.approx(cp.objective, abs=1e-6)


@pytest.mark.parametrize("seed", range(10))
def test_sequence_level_alone_meets_cpsat(seed: int) -> None:
    """The arm-sequence level and its coordination-diagram bound on their own
    (``plain_nodes=0``: no first search without them) prove CP-SAT's optimum."""
    p = random_problem(
        2, 4 + seed % 2, 1 + seed % 3, seed % 2, seed=300 + seed, zone_fraction=1.0,
        setups=seed % 3 != 0,
    )  # fmt: skip
    cp = solve(p, "cpsat", time_limit=20, seed=0, workers=1)
    assert cp.status.value == "optimal"
    res = prove(p, max_nodes=5_000_000, plain_nodes=0)
    assert res.proven and res.schedule is not None
    assert res.makespan == pytest.approx(cp.objective, abs=1e-6)
    assert validate(p, res.schedule) == pytest.approx(res.makespan, abs=1e-9)


def test_work_limit_is_deterministic_and_bound_stays_below() -> None:
    p = random_problem(3, 9, 3, 1, seed=7, zone_fraction=0.9)
    a = prove(p, max_nodes=40)
    b = prove(p, max_nodes=40)
    assert not a.proven and a.reason == "nodes"
    assert (a.nodes, a.pruned, a.makespan) == (b.nodes, b.pruned, b.makespan)
    full = prove(p, max_nodes=5_000_000)
    assert full.proven
    assert a.bound <= full.makespan + 1e-9 <= a.makespan + 1e-9


def test_lower_bound_met_stops_with_proof() -> None:
    p = random_problem(2, 6, 2, 1, seed=3)
    opt = prove(p, max_nodes=5_000_000)
    assert opt.proven
    early = prove(p, max_nodes=5_000_000, lower=opt.makespan)
    assert early.proven and early.makespan == pytest.approx(opt.makespan)
    assert early.nodes <= opt.nodes


def test_fixed_modes_give_the_best_schedule_with_those_modes() -> None:
    p = random_problem(2, 6, 2, 1, seed=5, zone_fraction=0.9)
    opt = prove(p, max_nodes=5_000_000)
    assert opt.schedule is not None
    same = prove(p, max_nodes=5_000_000, modes=opt.schedule.mode.tolist())
    assert same.proven and same.makespan == pytest.approx(opt.makespan)
    other = [max(p.task_modes[t]) for t in range(p.n_tasks)]
    res = prove(p, max_nodes=5_000_000, modes=other)
    assert res.proven and res.schedule is not None
    assert res.schedule.mode.tolist() == other
    assert res.makespan >= opt.makespan - 1e-9


def test_refuses_a_binding_oracle_and_empty_problem_is_proven() -> None:
    p = random_problem(2, 5, 2, 1, seed=1, blocking=True)
    res = prove(p, time_limit=5)
    assert not res.proven and res.schedule is None and res.reason == "a blocking oracle is set"
    idle = replace(p, blocking=replace(p.blocking, cost_s=0.0))  # type: ignore[type-var]
    assert prove(idle, max_nodes=5_000_000).proven
    empty = random_problem(2, 0, 1, 0, seed=1)
    out = prove(empty)
    assert out.proven and out.makespan == 0.0


def test_relevant_borders_keep_window_starts_and_move_cuts() -> None:
    p = random_problem(2, 8, 3, 1, seed=11, zone_fraction=1.0)
    everything = frozenset(range(2 * p.n_zones + p.n_tools))
    for m in range(p.n_modes):
        kept = relevant_borders(p, m, everything)
        assert set(kept) <= set(p.shapes[m].borders)
        sh = p.shapes[m]
        starts = {s for _, s, _ in (*sh.exclusive, *sh.moves) if 0 < s < sh.duration}
        assert starts <= set(kept)
        assert relevant_borders(p, m, frozenset()) == ()
    assert math.isfinite(prove(p, max_nodes=5_000_000).makespan)
