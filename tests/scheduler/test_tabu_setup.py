"""The graph tabu search with sequence-dependent setup times (SDST-FJSP).

With setups obeying the triangle inequality, the disjunctive graph carries
each setup on the arc between consecutive tasks of an arm, and the
k-insertion makespans stay exact (S2.10-S2.11 search, travel as setups as in
S2.12). Checked against the exact sequence decoder (``seq_decode``) by brute
force on seeded random instances of :func:`scheduler.generate.random_setup_fjsp`.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import ValidationError
from scheduler import Model, solve, validate
from scheduler.generate import generate_problem, metric_closure, random_setup_fjsp
from scheduler.search import Evaluator, priority_order
from scheduler.setup import MatrixSetup
from scheduler.tabu import _Graph, _sequences, graph_setup, graph_tabu, pure_fjsp
from scheduler.tree import TreeOptions
from tests.scheduler.tabu_brute import assert_insertions_exact


def _state(ev: Evaluator, seed: int):  # type: ignore[no-untyped-def]
    sol = ev.evaluate(priority_order(ev.problem, rng=np.random.default_rng(seed), noise=0.5))
    assert sol is not None
    return sol


@given(st.integers(0, 10_000), st.integers(1, 4), st.integers(1, 14))
@settings(max_examples=40, deadline=None)
def test_generated_setups_are_metric_integers_and_repeatable(seed: int, m: int, n: int) -> None:
    p = random_setup_fjsp(m, n, seed=seed, setup_fraction=1.0)
    assert p.n_tasks == n and p.n_arms == m and p.n_zones == 0
    times = p.setup.times  # type: ignore[attr-defined]
    assert np.array_equal(times, np.round(times)) and (times >= 0).all()
    assert p._setup.is_metric()
    assert random_setup_fjsp(m, n, seed=seed, setup_fraction=1.0).to_dict() == p.to_dict()
    assert graph_setup(p) is not None


def test_metric_closure_keeps_shortest_chains() -> None:
    raw = np.array([[0, 9, 9], [0, 1, 9], [9, 0, 1], [1, 9, 0]], dtype=float)
    out = metric_closure(raw)
    # from task 0 to 2 via task 1: 1 + 1; from home to 2 via task 0 and 1: 0 + 1 + 1
    assert out[1, 2] == 2 and out[0, 2] == 2 and out[0, 1] == 1


def test_generator_names_and_bad_sizes() -> None:
    assert generate_problem("setup_fjsp", 2, 5, 0, 0, seed=3).n_tasks == 5
    with pytest.raises(ValidationError, match="zones = tools = 0"):
        generate_problem("setup_fjsp", 2, 5, 1, 0)
    with pytest.raises(ValidationError, match="unknown generator 'nope'"):
        generate_problem("nope", 2, 5, 0, 0)
    with pytest.raises(ValidationError, match="n_machines"):
        random_setup_fjsp(0, 5)


def test_a_setup_breaking_the_triangle_inequality_keeps_the_list_search() -> None:
    m = Model("not metric")
    a = m.add_arm("a")
    for k in range(3):
        m.add_mode(m.add_task(f"t{k}"), a, 1.0)
    times = np.zeros((1, 4, 3))
    times[0, 1, 2] = 10.0  # t0 -> t2 costs 10, but t0 -> t1 -> t2 only 1
    m.set_setup(MatrixSetup(times))
    p = m.build()
    assert graph_setup(p) is None
    assert not pure_fjsp(Evaluator(p))
    r = solve(p, "tree", time_limit=None, seed=0, options=TreeOptions(max_evaluations=200))
    assert validate(p, r.schedule) == r.objective == 3.0


@pytest.mark.parametrize("seed", range(6))
def test_graph_makespan_with_setups_is_the_decoders(seed: int) -> None:
    p = random_setup_fjsp(3, 14, seed=seed, setup_fraction=0.8)
    ev = Evaluator(p)
    assert pure_fjsp(ev)
    sol = _state(ev, seed)
    g = _Graph(ev)
    seq, seq_n = _sequences(p, sol.state, np.arange(p.n_tasks))
    assert g.makespan(g.choice_of(sol.state.t_mode), seq, seq_n) == pytest.approx(sol.makespan)


@pytest.mark.parametrize("fast", [False, True])
@pytest.mark.parametrize("seed", range(4))
def test_insertion_makespans_with_setups_are_exact(seed: int, fast: bool) -> None:
    """Every k-insertion the search scores, applied and decoded by seq_decode,
    has the makespan computed from the graph with setups; and every acyclic
    insertion of a critical task is scored."""
    p = random_setup_fjsp(3, 11, seed=seed + 20, setup_fraction=1.0, flexibility=0.6)
    ev = Evaluator(p)
    sol = _state(ev, seed)
    g = _Graph(ev)
    seq, seq_n = _sequences(p, sol.state, np.arange(p.n_tasks))
    choice = g.choice_of(sol.state.t_mode)
    assert_insertions_exact(ev, g, choice, seq, seq_n, fast)


def test_graph_search_with_setups_improves_and_validates() -> None:
    p = random_setup_fjsp(5, 40, seed=7)
    ev = Evaluator(p)
    sol = ev.evaluate(priority_order(p))
    assert sol is not None
    best = graph_tabu(ev, sol, np.inf, np.random.default_rng(0), max_evaluations=1500)
    assert best.makespan < sol.makespan
    assert validate(p, ev.schedule(best)) == best.makespan
    again = graph_tabu(Evaluator(p), sol, np.inf, np.random.default_rng(0), max_evaluations=1500)
    assert again.makespan == best.makespan


def test_generator_parameters_are_checked_by_name() -> None:
    with pytest.raises(ValidationError, match="'line' has no parameter 'precedence'"):
        generate_problem("line", 2, 6, 1, 0, precedence=0.2)
    p = generate_problem("line", 3, 9, 2, 1, seed=2, stay_fraction=1.0)
    assert (p.n_arms, p.n_tasks, p.n_zones, p.n_tools) == (3, 9, 2, 1)


@given(
    st.integers(0, 10_000),
    st.integers(1, 5),
    st.integers(1, 14),
    st.integers(0, 4),
    st.integers(0, 2),
    st.sampled_from([0.0, 0.5, 1.0]),
)
@settings(max_examples=30, deadline=None)
def test_line_problems_build_solve_and_repeat(
    seed: int, arms: int, tasks: int, zones: int, tools: int, stay: float
) -> None:
    p = generate_problem("line", arms, tasks, zones, tools, seed=seed, stay_fraction=stay)
    assert (p.n_arms, p.n_tasks, p.n_zones, p.n_tools) == (arms, tasks, zones, tools)
    assert np.array_equal(p.mode_duration, np.round(p.mode_duration))
    assert p._setup.is_metric()
    again = generate_problem("line", arms, tasks, zones, tools, seed=seed, stay_fraction=stay)
    assert again.to_dict() == p.to_dict()
    r = solve(p, "greedy", seed=0)
    assert validate(p, r.schedule) == r.objective
