"""The blocking oracle in the kernel: answers cached in an array, asked once,
pre-fillable, and decoding exactly as the reference loop (S2.9 detours)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from multiarm.errors import UsageError, ValidationError
from multiarm.types import IntArray
from scheduler import Model, Problem, validate
from scheduler.generate import random_problem
from scheduler.kernel import (
    EPS,
    Instance,
    State,
    compile_problem,
    decode,
    expand_blocking,
    place_blocking,
    to_schedule,
)
from scheduler.search import priority_order


class Counting:
    """Deterministic oracle: 0-3 s detours, some (mode, arm, pose) with none at all."""

    def __init__(self, none_every: int = 0) -> None:
        self.calls: list[tuple[int, int, int]] = []
        self.none_every = none_every

    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        self.calls.append((mode, arm, pose_task))
        h = (mode * 31 + arm * 17 + (pose_task + 1) * 7) % 23
        if self.none_every and h % self.none_every == 0:
            return math.inf
        return float(h % 4) if h < 9 else 0.0


def with_oracle(p: Problem, oracle: object) -> Problem:
    return dataclasses.replace(p, blocking=oracle)  # type: ignore[arg-type]


# ------------------------------------------------------------ reference


def ref_cost(p: Problem, inst: Instance, st: State, m: int, S: float) -> float:
    a = int(p.mode_arm[m])
    total = 0.0
    assert p.blocking is not None
    for b in range(p.n_arms):
        if b == a:
            continue
        n = int(st.arm_n[b])
        pose = -1
        if n > 0:
            last = int(st.arm_t[inst.arm_lo[b] + n - 1])
            if st.t_end[last] > S + EPS:
                continue
            pose = last
        total += float(p.blocking.cost(m, b, pose))
    return total


def ref_decode(p: Problem, order: IntArray, waits: bool) -> tuple[bool, State]:
    """The plain loop the compiled decoder replaces: chronological, the detour
    cost growing with the start to a fixpoint, modes by (end, waits + detour)."""
    inst = compile_problem(p)
    st = inst.new_state()
    pending = order.tolist()
    while pending:
        kept = []
        for t in pending:
            if any(st.t_mode[q] < 0 for q in p.task_preds[t]):
                kept.append(t)
                continue
            S0 = inst.earliest(st, t, True)
            best: tuple[float, float, int] = (math.inf, math.inf, 0)
            choice = None
            for m in p.task_modes[t]:
                c = 0.0
                while True:
                    S, end, k, w = inst.query(st, t, m, S0, chrono=True, waits=waits, extra=c)
                    if not math.isfinite(S):
                        break
                    c2 = ref_cost(p, inst, st, m, S)
                    if math.isinf(c2):
                        S = math.inf
                        break
                    if c2 <= c + 1e-12:
                        break
                    c = c2
                if not math.isfinite(S):
                    continue
                key = (end, float(w.sum()) + c, m)
                if key < best:
                    best, choice = key, (m, S, end, k, w)
            if choice is None:
                kept.append(t)
                continue
            m, S, end, k, w = choice
            inst.commit(st, t, m, S, end, k, w)
        if len(kept) == len(pending):
            return False, st
        pending = kept
    return True, st


def same_state(a: State, b: State) -> bool:
    return all(np.array_equal(x, y, equal_nan=True) for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize("seed", range(6))
def test_compiled_blocking_decode_matches_the_reference_loop(seed: int) -> None:
    base = random_problem(4, 30, 4, 1, seed=seed, start_zones=seed % 2 == 0)
    oracle = Counting(none_every=7 if seed >= 4 else 0)
    p = with_oracle(base, oracle)
    order = priority_order(p)
    for waits in (True, False):
        ok_ref, st_ref = ref_decode(with_oracle(base, Counting(oracle.none_every)), order, waits)
        code, st = decode(compile_problem(p), order, np.full(p.n_tasks, -1), waits=waits)
        assert (code == 0) == ok_ref
        assert same_state(st, st_ref)
        if code == 0:
            s = to_schedule(compile_problem(p), st)
            assert validate(p, s) == pytest.approx(float(st.t_end.max()))
            assert s.blocking.sum() > 0 or seed >= 4  # the detours are charged


def test_each_answer_is_asked_once_and_kept_in_the_table() -> None:
    oracle = Counting()
    p = with_oracle(random_problem(4, 30, 4, 1, seed=3), oracle)
    inst = compile_problem(p)
    order = priority_order(p)
    free = np.full(p.n_tasks, -1)
    code, st1 = decode(inst, order, free)
    assert code == 0 and oracle.calls
    assert len(set(oracle.calls)) == len(oracle.calls)  # never the same question twice
    assert inst.known_blocking() == len(oracle.calls)
    assert len(inst.oracle.keys) <= 4 * max(len(oracle.calls), 32)  # grows with the answers
    n = len(oracle.calls)
    code, st2 = decode(inst, order, free)
    assert code == 0 and len(oracle.calls) == n  # warm: no question at all
    assert same_state(st1, st2)


def test_prefilled_table_means_no_questions_and_the_same_schedule() -> None:
    base = random_problem(3, 20, 3, 1, seed=5)
    asked = Counting()
    p1 = with_oracle(base, asked)
    order = priority_order(p1)
    free = np.full(base.n_tasks, -1)
    _c, st1 = decode(compile_problem(p1), order, free)
    M, A, T = base.n_modes, base.n_arms, base.n_tasks
    full = np.full((M, A, T + 1), np.nan)
    ref = Counting()
    for m in range(M):
        for b in range(A):
            for pose in range(-1, T):
                if pose < 0 or base.mode_of[b, pose] >= 0:
                    full[m, b, pose + 1] = ref.cost(m, b, pose)
    silent = Counting()
    p2 = with_oracle(base, silent)
    stored = compile_problem(p2).prefill_blocking(full)
    assert stored == int(np.count_nonzero(~np.isnan(full)))
    _c, st2 = decode(compile_problem(p2), order, free)
    assert silent.calls == []
    assert same_state(st1, st2)


def test_an_oracle_table_method_prefills_at_compile_time() -> None:
    base = random_problem(2, 8, 2, 0, seed=1)

    class WithTable(Counting):
        def table(self) -> np.ndarray:
            M, A, T = base.n_modes, base.n_arms, base.n_tasks
            return np.zeros((M, A, T + 1))

    oracle = WithTable()
    p = with_oracle(base, oracle)
    code, st = decode(compile_problem(p), priority_order(p), np.full(p.n_tasks, -1))
    assert code == 0 and oracle.calls == []
    assert np.all(to_schedule(compile_problem(p), st).blocking == 0.0)


def test_bad_answers_and_bad_prefills_are_clear_errors() -> None:
    class Negative:
        def cost(self, mode: int, arm: int, pose_task: int) -> float:
            return -1.0

    base = random_problem(2, 6, 1, 0, seed=0)
    p = with_oracle(base, Negative())
    with pytest.raises(ValidationError, match=r"returned -1.0 for mode \d+, arm"):
        decode(compile_problem(p), priority_order(p), np.full(p.n_tasks, -1))
    q = with_oracle(base, Counting())
    with pytest.raises(ValidationError, match="expected shape"):
        compile_problem(q).prefill_blocking(np.zeros((1, 1, 1)))
    bad = np.zeros((q.n_modes, q.n_arms, q.n_tasks + 1))
    bad[0, 0, 0] = -2.0
    with pytest.raises(ValidationError, match=r"negative cost -2\.0 for mode 0, arm 0, pose -1"):
        compile_problem(q).prefill_blocking(bad)
    with pytest.raises(UsageError, match="no blocking oracle"):
        compile_problem(base).prefill_blocking(bad)


def test_batched_and_single_blocking_placements_agree() -> None:
    p = with_oracle(random_problem(4, 30, 4, 1, seed=2), Counting())
    inst = compile_problem(p)
    order = priority_order(p)
    _c, st = decode(inst, order[:12], np.full(p.n_tasks, -1))
    ct, cm = [], []
    for t in range(p.n_tasks):
        if st.t_mode[t] < 0 and all(st.t_mode[q] >= 0 for q in p.task_preds[t]):
            for m in p.task_modes[t]:
                ct.append(t)
                cm.append(m)
    assert ct
    S, end, k, wsum, waits, cost = expand_blocking(inst, st, np.array(ct), np.array(cm))
    for i, (t, m) in enumerate(zip(ct, cm, strict=True)):
        S1, e1, k1, w1, c1 = place_blocking(inst, st, t, m, inst.earliest(st, t, True))
        assert (S1, e1, k1, c1) == (S[i], end[i], k[i], cost[i])
        assert np.array_equal(w1, waits[i][: len(w1)]) and wsum[i] == pytest.approx(w1.sum())
        if math.isfinite(e1):
            assert e1 >= S1 + float(p.mode_duration[m]) + c1 - 1e-9


def test_a_parked_arm_in_the_way_for_good_leaves_the_task_unplaced() -> None:
    class Wall:
        def cost(self, mode: int, arm: int, pose_task: int) -> float:
            return math.inf if arm == 1 and pose_task == -1 else 0.0

    m = Model()
    m.add_arm("A")
    m.add_arm("B")
    m.add_task("a")
    m.add_mode("a", "A", 2.0)
    m.set_blocking(Wall())
    p = m.build()
    code, st = decode(compile_problem(p), np.array([0]), np.full(1, -1))
    assert code == -1 and st.t_mode[0] == -1


def test_blocking_calls_without_an_oracle_are_refused() -> None:
    p = random_problem(2, 6, 1, 0, seed=0)
    st = compile_problem(p).new_state()
    with pytest.raises(UsageError, match="has no blocking oracle"):
        expand_blocking(compile_problem(p), st, np.array([0]), np.array([p.task_modes[0][0]]))
    with pytest.raises(UsageError, match="has no blocking oracle"):
        place_blocking(compile_problem(p), st, 0, p.task_modes[0][0], 0.0)
    with pytest.raises(UsageError, match="has no blocking oracle"):
        decode(compile_problem(p), np.arange(6), np.full(6, -1), blocking=True)
    code, _st = decode(compile_problem(p), np.arange(6), np.full(6, -1), blocking=False)
    assert code == 0
