"""Resumable chunked decoding (scheduler.kernel.resume) and the local search
that uses it: the same schedules as decoding from the start."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st_

from scheduler import validate
from scheduler.generate import random_problem
from scheduler.kernel import compile_problem, decode, to_schedule
from scheduler.kernel.resume import (
    chunk_size,
    decode_resume,
    new_flags,
    new_snaps,
    new_work,
    restore,
    resume_chrono,
)
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


def _used_equal(inst: object, a: object, b: object) -> bool:
    """Two states equal on everything a decoder reads: the held part of every
    timeline and arm sequence, the placed tasks (with their waits), the
    latest start."""
    d = inst.data  # type: ignore[attr-defined]
    if not (np.array_equal(a.res_n, b.res_n) and np.array_equal(a.arm_n, b.arm_n)):  # type: ignore[attr-defined]
        return False
    for r, lo in enumerate(d.res_lo.tolist()):
        hi = lo + int(a.res_n[r])  # type: ignore[attr-defined]
        for f in ("tl_s", "tl_e", "tl_own", "tl_task"):
            if not np.array_equal(getattr(a, f)[lo:hi], getattr(b, f)[lo:hi]):
                return False
    for x, lo in enumerate(d.arm_lo.tolist()):
        hi = lo + int(a.arm_n[x])  # type: ignore[attr-defined]
        if not np.array_equal(a.arm_t[lo:hi], b.arm_t[lo:hi]):  # type: ignore[attr-defined]
            return False
    placed = a.t_mode >= 0  # type: ignore[attr-defined]
    return (
        all(
            np.array_equal(getattr(a, f), getattr(b, f), equal_nan=True)
            for f in ("t_start", "t_end", "t_mode", "t_last")
        )
        and np.array_equal(a.t_waits[placed], b.t_waits[placed])  # type: ignore[attr-defined]
    )


@settings(max_examples=25, deadline=None)
@given(
    seed=st_.integers(0, 100_000),
    arms=st_.integers(2, 4),
    tasks=st_.integers(5, 45),
    start_zones=st_.booleans(),
    frozen=st_.sampled_from([0.0, 0.3]),
    every=st_.integers(2, 7),
)
def test_a_restored_boundary_is_the_saved_snapshot(
    seed: int, arms: int, tasks: int, start_zones: bool, frozen: float, every: int
) -> None:
    """Chronological decoding (a blocking oracle): the state after a prefix,
    restored from the complete state (kernel.resume.restore), is what a
    snapshot saved there holds, on top of a frozen base or of the empty
    schedule; and resuming from it decodes the same schedule."""
    p = random_problem(arms, tasks, 3, 1, seed=seed, blocking=True, start_zones=start_zones)
    inst = compile_problem(p)
    rng = np.random.default_rng(seed)
    topo = [int(t) for t in p.topological_order]
    cut = int(frozen * len(topo))
    base = inst.new_state()
    if cut:
        code, base = decode(
            inst, np.asarray(topo[:cut], dtype=np.int64), np.full(p.n_tasks, -1), chrono=True
        )
        if code != 0:
            return
    rest = np.asarray(topo[cut:], dtype=np.int64)
    free = np.full(p.n_tasks, -1, dtype=np.int64)
    if rng.random() < 0.5:
        free = np.array([rng.choice(p.task_modes[t]) for t in range(p.n_tasks)], dtype=np.int64)
    sn = new_snaps(inst, len(rest), every)
    code, fin = decode_resume(
        inst, rest, free, sn, sn, -1, every=every, state=base.copy(), chrono=True
    )
    if code != 0:
        return
    flags = new_flags(inst, len(rest), every)
    code2, fin2 = decode_resume(
        inst,
        rest,
        free,
        flags,
        flags,
        -1,
        every=every,
        state=base.copy(),
        chrono=True,
        states=False,
    )
    assert code2 == 0 and _states_equal(fin, fin2)
    assert np.array_equal(sn.ok, flags.ok)
    for k in np.flatnonzero(sn.ok).tolist():
        snap = type(base)._make(f[k] for f in sn[:-1])
        got = restore(inst, base, fin, rest, k * every, inst.new_state())
        assert _used_equal(inst, got, snap), k
        code_k, st_k = decode_resume(
            inst,
            rest,
            fin.t_mode,
            flags,
            new_flags(inst, len(rest), every),
            k,
            every=every,
            state=got,
            chrono=True,
            states=False,
        )
        assert code_k == 0 and _used_equal(inst, st_k, fin), k
    # the same in one compiled call (resume_chrono), decoded into a state that
    # holds another schedule: from the root, from the anchor with the same
    # list, and from the anchor with one task in another mode
    cx = inst.ctx(chrono=True, blocking=True)
    work = new_work(inst, len(rest))
    fixed = fin.t_mode.copy()
    changed = fixed.copy()
    q = int(rest[int(rng.integers(len(rest)))])
    changed[q] = next((m for m in p.task_modes[q] if m != fixed[q]), fixed[q])
    for anchor, modes in (
        (None, fixed),
        ((fin, rest, fixed), fixed),
        ((fin, rest, fixed), changed),
    ):
        want_code, want = decode_resume(
            inst,
            rest,
            modes,
            new_flags(inst, len(rest), every),
            new_flags(inst, len(rest), every),
            -1,
            every=every,
            state=base.copy(),
            chrono=True,
            states=False,
        )
        into = fin.copy()
        into.tl_s[:] = 7.0  # what it held before must not matter
        got_code, _k = resume_chrono(
            inst,
            cx,
            base,
            anchor,
            rest,
            modes,
            flags,
            new_flags(inst, len(rest), every),
            every,
            into,
            work,
        )
        assert got_code == want_code
        if want_code == 0:
            assert _used_equal(inst, into, want)


@pytest.mark.parametrize("seed", range(4))
def test_the_chronological_local_search_is_the_same_with_restored_boundaries(seed: int) -> None:
    """With a blocking oracle the resumed decoder restores boundaries instead
    of saving snapshots: the same search as decoding every list from the start."""
    p = random_problem(4, 50, 4, 1, seed=seed, blocking=True, start_zones=seed % 2 == 0)
    order = np.asarray(p.topological_order, dtype=np.int64)
    results = []
    for resume in (True, False):
        ev = Evaluator(p)
        assert ev.chrono
        if not resume:
            ev.evaluate_resume = ev.evaluate  # type: ignore[method-assign]
            ev.anchor = lambda sol: True  # type: ignore[method-assign]
        start = ev.evaluate(order)
        assert start is not None
        best = local_search(
            ev, start, float("inf"), np.random.default_rng(seed), max_evaluations=120
        )
        results.append((best.makespan, best.order.tolist(), best.modes.tolist()))
        assert validate(p, ev.schedule(best)) == pytest.approx(best.makespan)
    assert results[0] == results[1]
