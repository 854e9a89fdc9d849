"""The node bounds of ``scheduler.exact.prove`` that see every arm in a resource.

* ``stn_tails`` (the longest paths of the network to the end, so that a
  task's tail includes the arm's later tasks and the orders fixed so far)
  against a plain longest-path computation on random networks;
* ``jackson_bound`` (the preemptive one-machine bound over the intervals of
  ALL arms in a resource, heads and tails) against the maximum over all
  subsets, and never above a feasible one-machine schedule;
* the whole search with them against CP-SAT's proven optima on generated
  problems where three or four arms take turns in one shared zone (S2.12
  zones, S2.6 waits at their borders). These families were not used to tune
  anything (the bounds were written for the compiled cell ``scara4``).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scheduler import solve, validate
from scheduler.exact import prove
from scheduler.generate import random_problem
from scheduler.kernel.exact_bb import jackson_bound, stn_add, stn_tails


def _network(n_tasks: int, rng: np.random.Generator) -> tuple[list[tuple[int, int, float]], int]:
    """Random task chains (start, one inner point, end; the end pinned to its
    nominal offset) and random precedences from earlier to later tasks."""
    edges: list[tuple[int, int, float]] = []
    for t in range(n_tasks):
        b = 1 + 3 * t
        d1, d2 = float(rng.uniform(0.5, 3.0)), float(rng.uniform(0.5, 3.0))
        edges += [(0, b, float(rng.uniform(0, 4))), (b, b + 1, d1), (b + 1, b + 2, d2)]
        edges.append((b + 2, b + 1, -d2))  # no wait at the end
        for s in range(t):
            if rng.random() < 0.3:
                edges.append((1 + 3 * s + 2, b, float(rng.uniform(0, 1))))
    return edges, 1 + 3 * n_tasks


@given(st.integers(1, 7), st.integers(0, 10_000))
@settings(max_examples=60, deadline=None)
def test_stn_tails_are_the_longest_paths_to_an_end(n_tasks: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    edges, n = _network(n_tasks, rng)
    head = np.full(n, -1, dtype=np.int64)
    m = len(edges) + 1
    nxt, src, dst = (np.zeros(m, dtype=np.int64) for _ in range(3))
    wt, ne, dist = np.zeros(m), np.zeros(1, dtype=np.int64), np.zeros(n)
    queue, queued = np.zeros(n + 1, dtype=np.int64), np.zeros(n, dtype=np.bool_)
    for u, v, w in edges:
        assert stn_add(head, nxt, src, dst, wt, ne, dist, queue, queued, u, v, w)
    ends = np.array([3 + 3 * t for t in range(n_tasks)], dtype=np.int64)
    tail = np.zeros(n)
    stn_tails(head, nxt, dst, wt, ends, tail)
    # reference: n rounds of relaxation over the edge list
    ref = np.full(n, -np.inf)
    ref[ends] = 0.0
    for _ in range(n + 1):
        for u, v, w in edges:
            if ref[v] > -np.inf:
                ref[u] = max(ref[u], w + ref[v])
    assert np.allclose(tail, ref)
    # the makespan of the earliest times is the origin's tail
    assert tail[0] == pytest.approx(max(dist[ends]))


@given(
    st.lists(
        st.tuples(st.integers(0, 20), st.integers(1, 6), st.integers(0, 20)),
        min_size=1,
        max_size=7,
    )
)
@settings(max_examples=150, deadline=None)
def test_jackson_bound_is_the_best_subset_bound_and_a_bound(
    jobs: list[tuple[int, int, int]],
) -> None:
    n = len(jobs)
    head = np.array([float(r) for r, _, _ in jobs])
    length = np.array([float(p) for _, p, _ in jobs])
    tail = np.array([float(q) for _, _, q in jobs])
    got = jackson_bound(head, length, tail, n, np.zeros(n, dtype=np.int64))
    subsets = max(
        min(head[list(s)]) + sum(length[list(s)]) + min(tail[list(s)])
        for k in range(1, n + 1)
        for s in itertools.combinations(range(n), k)
    )
    assert got == pytest.approx(subsets)
    # never above any one-machine schedule (every order, jobs as early as possible)
    best = np.inf
    for order in itertools.permutations(range(n)):
        t, worst = 0.0, 0.0
        for j in order:
            t = max(t, head[j]) + length[j]
            worst = max(worst, t + tail[j])
        best = min(best, worst)
    assert got <= best + 1e-9


@pytest.mark.parametrize("seed", range(8))
def test_prove_meets_cpsat_with_arms_taking_turns_in_one_zone(seed: int) -> None:
    p = random_problem(
        3 + seed % 2, 5 + seed % 3, 1, seed % 2, seed=500 + seed, zone_fraction=1.0,
        setups=seed % 4 != 1,
    )  # fmt: skip
    cp = solve(p, "cpsat", time_limit=20, seed=0, workers=1)
    assert cp.status.value == "optimal"
    res = prove(p, max_nodes=5_000_000)
    assert res.proven and res.schedule is not None
    assert res.makespan == pytest.approx(cp.objective, abs=1e-6)
    assert validate(p, res.schedule) == pytest.approx(res.makespan, abs=1e-9)
    # the sequence level on its own too (no first search without it)
    seq = prove(p, max_nodes=5_000_000, plain_nodes=0)
    assert seq.proven and seq.makespan == pytest.approx(cp.objective, abs=1e-6)


@pytest.mark.parametrize("step", [1 / 16, 0.06249999999999999, 0.0625000000000001, 0.1])
def test_diagram_bound_lets_a_path_along_a_window_that_ends_with_the_axis(step: float) -> None:
    """Regression: both arms' last windows in one zone end with their axes,
    so the end of the diagram is a corner of the forbidden rectangle. A cell
    side a hair below 1/16 once put ``e / step`` a hair above 16 and marked
    the last cell, so the bound said "no path" (-1) and ``prove`` cut the
    optimal leaf (``random_problem(3, 6, 1, 0, seed=902, zone_fraction=1.0)``
    "proven" at 30 instead of CP-SAT's 27)."""
    from scheduler.kernel.exact_bb import diagram_bound

    one = np.zeros(1, dtype=np.int64)
    half, end = np.array([0.5]), np.array([1.0])
    none_i, none_f = np.zeros(0, dtype=np.int64), np.zeros(0)
    got = diagram_bound(
        1.0, 1.0, one, half, end, one, half, end, np.array([True]), none_i, none_f, none_f,
        none_f, none_f, none_f, none_f, step, np.inf,
    )  # fmt: skip
    # A's window first, then B's: 0.5 together, 0.5 A alone, 0.5 B alone
    assert 0.0 <= got <= 1.5 + 1e-9


def test_sequence_level_meets_cpsat_where_the_diagram_rounding_cut_the_optimum() -> None:
    p = random_problem(3, 6, 1, 0, seed=902, zone_fraction=1.0)
    cp = solve(p, "cpsat", time_limit=20, seed=0, workers=1)
    assert cp.status.value == "optimal" and cp.objective == pytest.approx(27.0)
    res = prove(p, max_nodes=5_000_000, plain_nodes=0, select=False)
    assert res.proven and res.makespan == pytest.approx(27.0, abs=1e-6)
