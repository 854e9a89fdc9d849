from __future__ import annotations

import itertools

import pytest
from hypothesis import given
from hypothesis import strategies as st

from multiarm.graph import find_cycle, longest_path_lengths, topological_order


def test_cycle_found_and_closed() -> None:
    cyc = find_cycle({"a": ["b"], "b": ["c"], "c": ["b"], "d": []})
    assert cyc == ["b", "c", "b"]


def test_self_loop() -> None:
    assert find_cycle({"a": ["a"]}) == ["a", "a"]


def test_deep_chain_has_no_recursion_limit() -> None:
    n = 50_000
    graph = {i: [i + 1] for i in range(n)}
    graph[n] = []
    assert find_cycle(graph) is None
    graph[n] = [0]
    cyc = find_cycle(graph)
    assert cyc is not None and len(cyc) == n + 2


def test_longest_path_depth() -> None:
    g = {"a": ["b", "c"], "b": ["d"], "c": [], "d": []}
    assert longest_path_lengths(g) == {"a": 1, "b": 2, "c": 2, "d": 3}
    assert longest_path_lengths(g, {"a": 5, "b": 1, "c": 10, "d": 1})["c"] == 15


def test_topological_order_rejects_cycle() -> None:
    with pytest.raises(ValueError, match="cycle"):
        topological_order({"a": ["b"], "b": ["a"]})


@given(st.lists(st.tuples(st.integers(0, 12), st.integers(0, 12)), max_size=40))
def test_cycle_iff_no_topological_order(edges: list[tuple[int, int]]) -> None:
    graph: dict[int, list[int]] = {i: [] for i in range(13)}
    for a, b in edges:
        graph[a].append(b)
    cyc = find_cycle(graph)
    if cyc is None:
        order = topological_order(graph)
        pos = {n: i for i, n in enumerate(order)}
        assert all(pos[a] < pos[b] for a, b in edges)
    else:
        assert cyc[0] == cyc[-1]
        for x, y in itertools.pairwise(cyc):
            assert y in graph[x]
        with pytest.raises(ValueError):
            topological_order(graph)
