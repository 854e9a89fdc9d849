"""The re-solve contract of :func:`scheduler.reschedule` (SEEDS.md S2.11-S2.12)
on a seeded campaign of generated problems: what the coordinator knows (tasks
done, tasks running, tasks failed, arms out, parts late) is kept, every
re-solved plan validates although the call does not check it by default, and
the check changes nothing but the time; the list decoder places every task
as the plain loop over every mode does."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from scheduler import FrozenTask, reschedule, solve, validate
from scheduler.generate import random_problem
from scheduler.kernel import EPS, compile_problem, decode


def _situation(seed: int, blocking: bool) -> dict[str, Any]:
    """A generated problem, its greedy plan and a seeded departure from it:
    the tasks done and running at a random time, a failed task, an arm out,
    a late part and a part that never comes (each drawn or not)."""
    rng = np.random.default_rng(seed)
    p = random_problem(4, 30, 4, 1, seed=seed, blocking=blocking, start_zones=blocking)
    plan = solve(p, "greedy", seed=0).schedule
    assert plan is not None
    now = float(rng.uniform(0.0, 0.7)) * plan.makespan
    done: dict[int, FrozenTask] = {}
    running: dict[int, FrozenTask] = {}
    for t in p.topological_order:  # a prefix closed under predecessors
        if not all(q in done or q in running for q in p.task_preds[t]):
            continue
        f = FrozenTask(
            int(plan.mode[t]),
            float(plan.start[t]),
            float(plan.end[t]),
            tuple(plan.waits[t].tolist()),
        )
        if float(plan.end[t]) <= now and all(q in done for q in p.task_preds[t]):
            done[t] = f
        elif float(plan.start[t]) < now:
            # running: it may take longer than planned
            late = float(rng.choice([0.0, rng.uniform(0.5, 10.0)]))
            running[t] = FrozenTask(f.mode, f.start, max(f.end + late, now), f.waits)
    rest = [t for t in range(p.n_tasks) if t not in done and t not in running]
    kw: dict[str, Any] = {"now": now, "previous": plan, "done": done, "running": running}
    if rest and rng.random() < 0.3:
        kw["failed"] = {int(rng.choice(rest))}
    if rng.random() < 0.5:
        kw["arms_out"] = {int(rng.integers(p.n_arms))}
    if rest and rng.random() < 0.6:
        late = {int(rng.choice(rest)): now + float(rng.uniform(1.0, 40.0))}
        if rng.random() < 0.3:
            late[int(rng.choice(rest))] = math.inf
        kw["parts_late"] = late
    return {"p": p, "kw": kw, "rest": rest}


def _never(p: Any, kw: dict[str, Any]) -> set[int]:
    """The tasks that can never run, from the inputs alone."""
    frozen = set(kw["done"]) | set(kw["running"])
    out = set(kw.get("arms_out", ()))
    late = kw.get("parts_late", {})
    never: set[int] = set()
    for t in p.topological_order:
        if t in frozen:
            continue
        if (
            t in kw.get("failed", ())
            or math.isinf(late.get(t, 0.0))
            or all(int(p.mode_arm[m]) in out for m in p.task_modes[t])
            or any(q in never for q in p.task_preds[t])
        ):
            never.add(t)
    return never


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), blocking=st.booleans())
def test_every_re_solved_plan_validates_and_keeps_what_is_known(seed: int, blocking: bool) -> None:
    s = _situation(seed, blocking)
    p, kw = s["p"], s["kw"]
    r = reschedule(p, seed=seed, evaluations=8, **kw)
    assert r.schedule is not None, r.reason
    plan = r.schedule
    # the call did not validate (check=False): the plan validates all the same
    mk = validate(p, plan)
    assert r.dropped == frozenset(_never(p, kw))
    live = [t for t in range(p.n_tasks) if t not in r.dropped]
    assert r.makespan == max((float(plan.end[t]) for t in live), default=0.0)
    assert mk >= r.makespan - 1e-9
    for t, f in (*kw["done"].items(), *kw["running"].items()):
        assert (int(plan.mode[t]), float(plan.start[t]), float(plan.end[t])) == (
            f.mode,
            f.start,
            f.end,
        )
    out = kw.get("arms_out", set())
    for t in s["rest"]:
        if t in r.dropped:
            continue
        assert float(plan.start[t]) >= kw["now"] - 1e-9
        assert int(plan.arms(p)[t]) not in out
        assert float(plan.start[t]) >= kw.get("parts_late", {}).get(t, 0.0) - 1e-9
    if r.dropped and live:
        assert max(float(plan.start[t]) for t in live) < min(
            float(plan.start[t]) for t in r.dropped
        )
    # the check is a check only: the same plan, the same seed
    checked = reschedule(p, seed=seed, evaluations=8, check=True, **kw)
    assert checked.schedule is not None
    assert np.array_equal(checked.schedule.start, plan.start)
    assert np.array_equal(checked.schedule.mode, plan.mode)
    assert checked.dropped == r.dropped


def test_the_phases_add_up_to_at_most_the_latency() -> None:
    s = _situation(7, False)
    p, kw = s["p"], s["kw"]
    for check in (False, True):
        r = reschedule(p, seed=1, evaluations=5, check=check, **kw)
        phases = dict(r.phases)
        assert {"prepare", "state", "first", "search", "decodes", "build", "validate"} <= set(
            phases
        )
        assert all(v >= 0.0 for v in phases.values())
        spent = sum(v for k, v in phases.items() if k != "decodes")
        assert spent <= r.latency + 1e-9
        assert phases["decodes"] <= phases["first"] + phases["search"] + 1e-9
        assert (phases["validate"] > 0.0) == check


def _reference_decode(p: Any, order: Any, chrono: bool, waits: bool) -> Any:
    """The list decoder as a plain loop over every mode of every task: each
    task in the mode that ends first (ties: less waiting, then the lower mode
    id), a task that cannot be placed yet retried after the others."""
    inst = compile_problem(p)
    st = inst.new_state()
    pending = [int(t) for t in order]
    while pending:
        kept = []
        for t in pending:
            if any(st.t_mode[q] < 0 for q in p.task_preds[t]):
                kept.append(t)
                continue
            S0 = inst.earliest(st, t, chrono)
            best = math.inf
            bw = math.inf
            choice = None
            for m in p.task_modes[t]:
                S, end, k, w = inst.query(st, t, m, S0, chrono=chrono, waits=waits)
                if not end < math.inf:
                    continue
                ws = float(w.sum()) if waits else 0.0
                if end < best - EPS or (end <= best + EPS and ws < bw - EPS):
                    best, bw, choice = end, ws, (m, S, end, k, w)
            if choice is None:
                kept.append(t)
                continue
            m, S, end, k, w = choice
            inst.commit(st, t, m, S, end, k, w if waits else np.zeros_like(w))
        if len(kept) == len(pending):
            return st
        pending = kept
    return st


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    chrono=st.booleans(),
    waits=st.booleans(),
    start_zones=st.booleans(),
)
def test_the_list_decoder_places_every_task_as_the_plain_loop_does(
    seed: int, chrono: bool, waits: bool, start_zones: bool
) -> None:
    """The compiled list decoder and the plain loop give the same states
    (chronological or not, waits at borders or not, start zones or not)."""
    p = random_problem(4, 25, 4, 1, seed=seed, start_zones=start_zones)
    rng = np.random.default_rng(seed)
    order = np.asarray(p.topological_order, dtype=np.int64)
    if rng.random() < 0.5:
        order = rng.permutation(p.n_tasks).astype(np.int64)  # deferrals too
    fixed = np.full(p.n_tasks, -1, dtype=np.int64)
    _code, got = decode(compile_problem(p), order, fixed, chrono=chrono, waits=waits)
    want = _reference_decode(p, order, chrono, waits)
    for x, y in zip(got, want, strict=True):
        assert np.array_equal(x, y, equal_nan=True)


def test_the_collector_is_held_off_during_the_call_and_restored_after() -> None:
    """The call is latency-critical: no cyclic collection runs inside it
    (counted by a collector callback), and the collector's state is what it
    was before the call, on or off."""
    import gc

    s = _situation(3, False)
    p, kw = s["p"], s["kw"]
    runs: list[int] = []

    def count(phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            runs.append(info["generation"])

    gc.callbacks.append(count)
    try:
        for was in (True, False):
            (gc.enable if was else gc.disable)()
            thresholds = gc.get_threshold()
            gc.set_threshold(1, 1, 1)  # a collection on nearly every allocation
            runs.clear()
            r = reschedule(p, seed=0, evaluations=5, **kw)
            gc.set_threshold(*thresholds)
            assert r.schedule is not None
            assert runs == []
            assert gc.isenabled() == was
    finally:
        gc.callbacks.remove(count)
        gc.enable()


def test_a_call_gives_the_same_plan_whatever_ran_before_on_the_problem() -> None:
    # calls on one problem share its compiled instance (scratch buffers, the
    # oracle's answers): a plan returned is left alone by the next calls, and
    # a call gives the same plan after another one as before it
    for seed, blocking in ((3, True), (4, False)):
        s = _situation(seed, blocking)
        p, kw = s["p"], s["kw"]
        first = reschedule(p, seed=1, evaluations=12, **kw)
        assert first.schedule is not None
        kept = (first.schedule.start.copy(), first.schedule.mode.copy(), first.schedule.end.copy())
        other = reschedule(p, now=0.0, previous=kw["previous"], seed=2, evaluations=12)
        assert other.schedule is not None
        again = reschedule(p, seed=1, evaluations=12, **kw)
        assert again.schedule is not None
        now = (first.schedule.start, first.schedule.mode, first.schedule.end)
        for a, b in zip(kept, now, strict=True):
            assert np.array_equal(a, b)
        assert np.array_equal(again.schedule.start, first.schedule.start)
        assert np.array_equal(again.schedule.mode, first.schedule.mode)
        validate(p, again.schedule)
