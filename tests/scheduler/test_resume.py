"""Resumable chunked decoding (scheduler.kernel.resume) and the local search
that uses it: the same schedules as decoding from the start."""

from __future__ import annotations

import numpy as np
import pytest

from scheduler import validate
from scheduler.generate import random_problem
from scheduler.kernel import compile_problem, decode, to_schedule
from scheduler.kernel.resume import chunk_size, decode_resume, new_snaps
from scheduler.search import Evaluator, local_search


def _states_equal(a: object, b: object) -> bool:
    return all(
        np.array_equal(x, y, equal_nan=True)
        for x, y in zip(a, b, strict=True)  # type: ignore[call-overload]
    )


@pytest.mark.parametrize("seed", range(6))
def test_chunked_decoding_equals_list_decoding_without_deferrals(seed: int) -> None:
    p = random_problem(4, 40, 4, 2, seed=seed)
    inst = compile_problem(p)
    rng = np.random.default_rng(seed)
    order = np.asarray(p.topological_order, dtype=np.int64)
    modes = np.array([rng.choice(p.task_modes[t]) for t in range(p.n_tasks)], dtype=np.int64)
    for fixed in (modes, np.full(p.n_tasks, -1, dtype=np.int64)):
        e = chunk_size(len(order))
        sn = new_snaps(inst, len(order), e)
        code, st = decode_resume(inst, order, fixed, sn, sn, -1, every=e)
        code0, st0 = decode(inst, order, fixed)
        assert code == code0 == 0
        assert _states_equal(st, st0)
        assert sn.ok.all()


@pytest.mark.parametrize("seed", range(6))
def test_resuming_from_any_snapshot_gives_the_same_schedule(seed: int) -> None:
    p = random_problem(3, 30, 3, 1, seed=seed, start_zones=seed % 2 == 0)
    inst = compile_problem(p)
    order = np.asarray(p.topological_order, dtype=np.int64)
    free = np.full(p.n_tasks, -1, dtype=np.int64)
    e = 4
    sn = new_snaps(inst, len(order), e)
    code, ref = decode_resume(inst, order, free, sn, sn, -1, every=e)
    assert code == 0
    validate(p, to_schedule(inst, ref))
    # a changed suffix: swap two tasks late in the list where precedence allows
    for k in range(len(sn.ok)):
        if not sn.ok[k]:
            continue
        out = new_snaps(inst, len(order), e)
        code_k, st_k = decode_resume(inst, order, ref.t_mode, sn, out, k, every=e)
        assert code_k == 0
        assert _states_equal(st_k, ref), k


def test_the_local_search_is_the_same_with_resumed_decoding() -> None:
    """Same moves, same schedules: the resumed decoder changes only the cost."""
    p = random_problem(6, 80, 6, 2, seed=11)
    order = np.asarray(p.topological_order, dtype=np.int64)
    results = []
    for resume in (True, False):
        ev = Evaluator(p)
        if not resume:
            ev.evaluate_resume = ev.evaluate  # type: ignore[method-assign]
            ev.anchor = lambda sol: True  # type: ignore[method-assign]
        start = ev.evaluate(order)
        assert start is not None
        best = local_search(ev, start, float("inf"), np.random.default_rng(3), max_evaluations=150)
        results.append((best.makespan, best.order.tolist(), best.modes.tolist()))
        assert validate(p, ev.schedule(best)) == best.makespan
    assert results[0] == results[1]


def test_anchor_takes_only_the_last_decoded_solution() -> None:
    p = random_problem(3, 20, 2, 1, seed=2)
    ev = Evaluator(p)
    order = np.asarray(p.topological_order, dtype=np.int64)
    a = ev.evaluate_resume(order)
    b = ev.evaluate_resume(order)
    assert a is not None and b is not None
    assert not ev.anchor(a)  # its snapshots were overwritten by b's decode
    assert ev.anchor(b)
    assert ev.anchor(b)  # already the anchor
