"""What a Setup hands the kernel (``Setup.kernel_data``): every kind decodes the
same as the same times given as a dense matrix, and a callable setup becomes a
compact table of the pairs an arm can take, never an (A, T + 1, T) one."""

from __future__ import annotations

import dataclasses

import numpy as np

from scheduler import FunctionSetup, MatrixSetup, NoSetup, Problem, TravelSetup
from scheduler.generate import random_problem
from scheduler.kernel import compile_problem, decode, to_schedule
from scheduler.search import priority_order


def with_setup(p: Problem, setup: object) -> Problem:
    return dataclasses.replace(p, setup=setup)  # type: ignore[arg-type]


def dense_of(p: Problem) -> np.ndarray:
    A, T = p.n_arms, p.n_tasks
    out = np.zeros((A, T + 1, T))
    for a in range(A):
        for prev in range(-1, T):
            row = p.setup_row(a, prev)
            out[a, prev + 1] = np.where(p.mode_of[a] >= 0, row, 0.0)
    return out


def decoded(p: Problem) -> tuple[list[float], list[int]]:
    code, st = decode(compile_problem(p), priority_order(p), np.full(p.n_tasks, -1))
    assert code == 0
    s = to_schedule(compile_problem(p), st)
    return s.start.tolist(), s.mode.tolist()


def test_each_kind_decodes_like_its_dense_matrix() -> None:
    base = random_problem(3, 25, 3, 1, seed=4)  # travel setup (Manhattan)
    assert isinstance(base.setup, TravelSetup)
    assert compile_problem(base).data.su.kind == 3
    as_matrix = with_setup(base, MatrixSetup(dense_of(base)))
    as_function = with_setup(base, FunctionSetup(base.setup_time))
    tables = [compile_problem(q).data.su for q in (as_matrix, as_function)]
    assert [su.kind for su in tables] == [1, 1]
    assert np.array_equal(tables[0].table, tables[1].table)
    ref = decoded(as_matrix)
    assert decoded(base) == ref
    assert decoded(as_function) == ref
    none = with_setup(base, NoSetup())
    assert compile_problem(none).data.su.kind == 0
    assert decoded(none) == decoded(with_setup(base, MatrixSetup(np.zeros_like(dense_of(base)))))


def test_euclidean_travel_is_computed_bit_identically_to_the_bound_setup() -> None:
    base = random_problem(3, 15, 2, 0, seed=3)
    s = base.setup
    assert isinstance(s, TravelSetup)
    p = with_setup(base, TravelSetup(s.start, s.end, s.home, s.speed, s.base, "euclidean"))
    assert compile_problem(p).data.su.kind == 2
    as_matrix = with_setup(base, MatrixSetup(dense_of(p)))  # the bound setup's own values
    su = compile_problem(as_matrix).data.su
    assert np.all(su.table[: su.table.size] >= 0)
    # fractional travel times make ties rare: any difference in a setup shows in the starts
    assert decoded(p) == decoded(as_matrix)


def test_a_callable_setup_is_compact_and_asked_only_for_pairs_an_arm_can_take() -> None:
    base = random_problem(4, 30, 2, 0, seed=6)
    asked: list[tuple[int, int, int]] = []

    def fn(a: int, prev: int, nxt: int) -> float:
        asked.append((a, prev, nxt))
        return float((a + 2 * prev + 3 * nxt) % 5)

    p = with_setup(base, FunctionSetup(fn))
    su = compile_problem(p).data.su
    count = np.bincount(p.mode_arm, minlength=p.n_arms)
    assert su.table.size == int((count * (count + 1)).sum())
    assert su.table.size < p.n_arms * (p.n_tasks + 1) * p.n_tasks
    assert asked
    for a, prev, nxt in asked:
        assert p.mode_of[a, nxt] >= 0 and (prev < 0 or p.mode_of[a, prev] >= 0)
    # the table holds exactly fn's values
    a = int(p.mode_arm[0])
    modes = np.flatnonzero(p.mode_arm == a)
    n = len(modes)
    for i, m in enumerate(modes[:3]):
        for j, m2 in enumerate(modes[:3]):
            want = fn(a, int(p.mode_task[m]), int(p.mode_task[m2]))
            assert su.table[su.arm_off[a] + (1 + i) * n + j] == want
    assert decoded(p) == decoded(with_setup(base, MatrixSetup(dense_of(p))))
