"""Brute-force check of the graph tabu search's k-insertion neighbourhood
(shared by ``test_tabu_graph`` and ``test_tabu_setup``)."""

from __future__ import annotations

from typing import Any

import pytest

from multiarm.types import IntArray
from scheduler.kernel import seq_decode
from scheduler.kernel._tabu_jit import all_moves
from scheduler.search import Evaluator


def assert_insertions_exact(
    ev: Evaluator, g: Any, choice: IntArray, seq: IntArray, seq_n: IntArray, fast: bool
) -> None:
    """Every candidate the search scores (``all_moves``), applied and decoded
    by ``seq_decode``, has the makespan the search computed; and every
    acyclic insertion of a task the search considered is a candidate.

    ``g`` is the search's graph (``scheduler.tabu._Graph``), ``choice`` each
    task's mode choice, ``seq``/``seq_n`` each arm's sequence."""
    rows = all_moves(g.arrays, choice, seq, seq_n, fast)
    got = {(int(r[0]), int(r[1]), int(r[3])): float(r[4]) for r in rows}
    assert got
    arm = g.tm_arm[g.tm_ptr[:-1] + choice]
    brute = {}
    for v in sorted({k[0] for k in got}):
        a0 = int(arm[v])
        rest0 = [int(t) for t in seq[a0, : seq_n[a0]] if t != v]
        for c in range(int(g.tm_ptr[v + 1] - g.tm_ptr[v])):
            k = int(g.tm_arm[g.tm_ptr[v] + c])
            base = rest0 if k == a0 else [int(t) for t in seq[k, : seq_n[k]]]
            for i in range(len(base) + 1):
                s2, n2 = seq.copy(), seq_n.copy()
                s2[a0, :] = -1
                s2[a0, : len(rest0)] = rest0
                n2[a0] = len(rest0)
                new = [*base[:i], v, *base[i:]]
                s2[k, :] = -1
                s2[k, : len(new)] = new
                n2[k] = len(new)
                if k == a0 and new == [int(t) for t in seq[a0, : seq_n[a0]]]:
                    continue  # where it is
                ch2 = choice.copy()
                ch2[v] = c
                ok, st, _ = seq_decode(ev.inst, s2, n2, g.modes_of(ch2))
                mk = g.makespan(ch2, s2, n2)
                assert ok == (mk >= 0)
                if ok:
                    assert float(st.t_end.max()) == pytest.approx(mk)
                    brute[(v, c, i)] = mk
    assert set(got) == set(brute)
    for key, mk in got.items():
        assert mk == pytest.approx(brute[key]), key
