"""Small directed-graph helpers used by several layers (task prerequisites,
scheduler precedence, wait-for graphs).

Graphs are given as a mapping ``node -> successors``; nodes are hashable and
kept in the mapping's order, so results are deterministic.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping, Sequence
from typing import TypeVar

__all__ = ["find_cycle", "longest_path_lengths", "topological_order"]

N = TypeVar("N", bound=Hashable)


def find_cycle(graph: Mapping[N, Iterable[N]]) -> list[N] | None:
    """One directed cycle of ``graph``, or ``None`` when it is acyclic.

    The cycle is returned closed: its first node is repeated at the end.
    Iterative depth-first search, so deep chains do not hit the recursion
    limit.

    Examples
    --------
    >>> find_cycle({"a": ["b"], "b": ["c"], "c": ["a"]})
    ['a', 'b', 'c', 'a']
    >>> find_cycle({"a": ["b"], "b": []}) is None
    True
    """
    white, grey, black = 0, 1, 2
    colour: dict[N, int] = {}
    for root in graph:
        if colour.get(root, white) != white:
            continue
        stack: list[tuple[N, Iterable[N]]] = [(root, iter(graph.get(root, ())))]
        path: list[N] = [root]
        colour[root] = grey
        while stack:
            node, it = stack[-1]
            advanced = False
            for nxt in it:
                state = colour.get(nxt, white)
                if state == grey:
                    start = path.index(nxt)
                    return [*path[start:], nxt]
                if state == white:
                    colour[nxt] = grey
                    path.append(nxt)
                    stack.append((nxt, iter(graph.get(nxt, ()))))
                    advanced = True
                    break
            if not advanced:
                colour[node] = black
                path.pop()
                stack.pop()
    return None


def topological_order(graph: Mapping[N, Iterable[N]]) -> list[N]:
    """Nodes in an order where every edge goes forward (Kahn, stable).

    Raises
    ------
    ValueError
        When the graph has a cycle.
    """
    indeg: dict[N, int] = dict.fromkeys(graph, 0)
    for succs in graph.values():
        for s in succs:
            indeg[s] = indeg.get(s, 0) + 1
    ready = [n for n, d in indeg.items() if d == 0]
    order: list[N] = []
    i = 0
    while i < len(ready):
        n = ready[i]
        i += 1
        order.append(n)
        for s in graph.get(n, ()):
            indeg[s] -= 1
            if indeg[s] == 0:
                ready.append(s)
    if len(order) != len(indeg):
        raise ValueError("graph has a cycle")
    return order


def longest_path_lengths(
    graph: Mapping[N, Sequence[N]], weight: Mapping[N, float] | None = None
) -> dict[N, float]:
    """For every node, the weight of the heaviest path that ends at it.

    With ``weight=None`` every node weighs 1, which gives the depth of a node
    in a prerequisite DAG (a node with no predecessor has depth 1).
    """
    order = topological_order(graph)
    best: dict[N, float] = {}
    for n in order:
        w = 1.0 if weight is None else float(weight[n])
        best[n] = best.get(n, 0.0) + w
        for s in graph.get(n, ()):
            if best.get(s, 0.0) < best[n]:
                best[s] = best[n]
    return best
