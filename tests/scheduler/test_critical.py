"""The compiled critical chain (scheduler.kernel.critical) against a plain
reference built from the Schedule and the problem's Python objects; the
reservation intervals of a mode with waits against the border-by-border rule."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scheduler.generate import random_problem
from scheduler.kernel import compile_problem, decode, to_schedule
from scheduler.kernel.critical import critical_chain, task_reasons
from scheduler.problem import Problem
from scheduler.schedule import Schedule
from scheduler.timing import ModeShape

TOL = 1e-6


def reference_reasons(p: Problem, sched: Schedule, t: int) -> set[tuple[str, int]]:
    """Why ``t`` starts when it does, from the schedule (independent of the kernel)."""
    start, end = sched.start, sched.end
    arms = sched.arms(p)
    out: set[tuple[str, int]] = set()
    S = float(start[t])
    for q in p.task_preds[t]:
        if abs(float(end[q]) - S) <= TOL:
            out.add(("pred", q))
    for seq in sched.sequences(p):
        seq = list(seq)
        if t in seq and seq.index(t) > 0:
            q = seq[seq.index(t) - 1]
            if abs(float(end[q]) + p.setup_time(int(arms[t]), q, t) - S) <= TOL:
                out.add(("arm", q))
    mine = p.shapes[int(sched.mode[t])]
    starts = [(r, s) for r, s, _e in mine.intervals(S, sched.waits[t])]
    starts += [(r, S) for r in mine.tools]
    for x in range(p.n_tasks):
        if x == t or arms[x] == arms[t]:
            continue
        sh = p.shapes[int(sched.mode[x])]
        ends = [(r, e) for r, _s, e in sh.intervals(float(start[x]), sched.waits[x])]
        ends += [(r, float(end[x])) for r in sh.tools]
        for r, s in starts:
            if any(r == r2 and abs(e - s) <= TOL for r2, e in ends):
                out.add(("resource", x))
    return out


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize(
    ("size", "start_zones"),
    [((2, 8, 2, 1), False), ((3, 20, 4, 2), True), ((4, 30, 6, 2), False)],
)
def test_reasons_match_the_reference(
    size: tuple[int, int, int, int], start_zones: bool, seed: int
) -> None:
    p = random_problem(*size, seed=seed, start_zones=start_zones)
    inst = compile_problem(p)
    order = np.asarray(p.topological_order, dtype=np.int64)
    code, st = decode(inst, order, np.full(p.n_tasks, -1, dtype=np.int64))
    assert code == 0
    sched = to_schedule(inst, st)
    for t in range(p.n_tasks):
        assert set(task_reasons(inst, st, t)) == reference_reasons(p, sched, t), t


def test_chain_links_are_reasons_and_start_at_the_makespan() -> None:
    p = random_problem(4, 40, 6, 2, seed=3)
    inst = compile_problem(p)
    order = np.asarray(p.topological_order, dtype=np.int64)
    _code, st = decode(inst, order, np.full(p.n_tasks, -1, dtype=np.int64))
    sched = to_schedule(inst, st)
    for rng in (None, np.random.default_rng(0), np.random.default_rng(1)):
        chain = critical_chain(inst, st, rng)
        assert chain[0][0] == int(np.argmax(st.t_end))
        assert chain[-1][1] == "release" and chain[-1][2] == -1
        for (t, why, by), nxt in itertools.pairwise(chain):
            assert (why, by) in reference_reasons(p, sched, t)
            assert nxt[0] == by
        # a release link: the task has no reason at all
        assert reference_reasons(p, sched, chain[-1][0]) == set()


def test_seeded_picks_repeat() -> None:
    p = random_problem(4, 40, 6, 2, seed=5)
    inst = compile_problem(p)
    _code, st = decode(
        inst,
        np.asarray(p.topological_order, dtype=np.int64),
        np.full(p.n_tasks, -1, dtype=np.int64),
    )
    a = critical_chain(inst, st, np.random.default_rng(7))
    b = critical_chain(inst, st, np.random.default_rng(7))
    assert a == b


def test_empty_problem_has_no_chain() -> None:
    from scheduler.problem import Model

    m = Model()
    m.add_arm("a")
    p = m.build()
    assert p.n_tasks == 0
    inst = compile_problem(p)
    assert critical_chain(inst, inst.new_state()) == []


def _reference_intervals(
    sh: ModeShape, start: float, waits: np.ndarray
) -> list[tuple[int, float, float]]:
    """ModeShape.intervals as the timing rules state it, one border at a time."""
    out = []
    for r, s, e in sh.exclusive:
        out.append((r, start + s + sh.shift(waits, s, True), start + e + sh.shift(waits, e, False)))
    for r, s, e in sh.moves:
        cuts = [b for b, w in zip(sh.borders, waits, strict=True) if s < b < e and w > 0]
        points = [s, *cuts, e]
        for p0, p1 in itertools.pairwise(points):
            out.append(
                (r, start + p0 + sh.shift(waits, p0, True), start + p1 + sh.shift(waits, p1, False))
            )
    return out


@settings(max_examples=200, deadline=None)
@given(
    borders=st.lists(st.integers(1, 99), min_size=1, max_size=12, unique=True),
    windows=st.lists(
        st.tuples(st.integers(0, 3), st.integers(0, 99), st.integers(1, 40), st.booleans()),
        min_size=1,
        max_size=10,
    ),
    waits=st.lists(st.sampled_from([0.0, 0.5, 1.25, 3.0]), min_size=12, max_size=12),
    start=st.floats(0, 1000),
)
def test_intervals_equal_the_border_by_border_rule(
    borders: list[int],
    windows: list[tuple[int, int, int, bool]],
    waits: list[float],
    start: float,
) -> None:
    """Prefix sums of the waits give exactly (bit for bit) the per-border sums."""
    b = tuple(float(x) for x in sorted(borders))
    excl = tuple((r, float(s), float(min(s + n, 100))) for r, s, n, move in windows if not move)
    moves = tuple((4 + r, float(s), float(min(s + n, 100))) for r, s, n, move in windows if move)
    sh = ModeShape(100.0, b, excl, moves, ())
    w = np.array(waits[: len(b)])
    assert sh.intervals(start, w) == _reference_intervals(sh, start, w)
