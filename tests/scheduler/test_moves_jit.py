"""The compiled moves of the local search (scheduler.kernel.moves_jit, used
by scheduler.search.neighbours and local_search) against the plain-Python
reference (moves_reference.py) on seeded random problems: the same chain,
the same moves in the same shuffled order, and the same random stream left
behind, with and without a blocking oracle (chronological decoding, the
chain continued through the list), with frozen tasks and modes not allowed
(re-solving, S2.11-S2.12)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from scheduler.generate import random_problem
from scheduler.kernel.moves_jit import AFTER, BEFORE, MODE
from scheduler.search import Evaluator, neighbours, priority_order
from tests.scheduler import moves_reference as ref


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 100_000),
    arms=st.integers(2, 4),
    tasks=st.integers(4, 40),
    blocking=st.booleans(),
    start_zones=st.booleans(),
    frozen_share=st.sampled_from([0.0, 0.2, 0.5]),
    arm_out=st.booleans(),
    rng_seed=st.integers(0, 50),
)
def test_compiled_moves_are_the_reference_moves(
    seed: int,
    arms: int,
    tasks: int,
    blocking: bool,
    start_zones: bool,
    frozen_share: float,
    arm_out: bool,
    rng_seed: int,
) -> None:
    p = random_problem(arms, tasks, 3, 1, seed=seed, blocking=blocking, start_zones=start_zones)
    pick = np.random.default_rng(seed)
    frozen = frozenset(int(t) for t in range(p.n_tasks) if pick.random() < frozen_share)
    allowed = None
    if arm_out:
        allowed = np.asarray(p.mode_arm) != int(pick.integers(p.n_arms))
    ev = Evaluator(p, frozen=frozen, allowed=allowed)
    order = priority_order(p, rng=pick, noise=0.3)
    sol = ev.evaluate(order)
    if sol is None or sol.state is None:
        return
    r1 = np.random.default_rng(rng_seed)
    r2 = np.random.default_rng(rng_seed)
    want = ref.moves(ev, sol.state, sol.order, sol.modes, r1)
    built = [make() for make in neighbours(ev, sol, r2)]
    assert r1.random() == r2.random()  # the same draws were taken
    assert len(built) == len(want)
    pos = {int(t): i for i, t in enumerate(sol.order)}
    for (kind, a, b), (o, m) in zip(want, built, strict=True):
        assert a not in frozen
        if kind == MODE:
            assert np.array_equal(o, sol.order)
            assert int(m[a]) == b and (allowed is None or allowed[b])
            assert int((m != sol.modes).sum()) == 1
        else:
            assert np.array_equal(m, sol.modes)
            moved = [int(x) for x in o]
            if kind == BEFORE:
                assert moved.index(a) == moved.index(b) - 1 and pos[a] > pos[b]
            else:
                assert kind == AFTER
                assert moved.index(a) == moved.index(b) + 1 and pos[a] < pos[b]
            # still a topological list
            where = {t: i for i, t in enumerate(moved)}
            assert all(where[q] < where[t] for t in moved for q in p.task_preds[t] if q in where)
