"""What a re-solve builds before and after its search: the frozen prefix
committed in one compiled call (Instance.commit_all), the empty state, and the
schedule record of a decoded state (S2.11-S2.12: the prefix kept exactly)."""

from __future__ import annotations

import numpy as np
import pytest

from scheduler.generate import random_problem
from scheduler.kernel import compile_problem, decode, to_schedule


def _states_equal(a: object, b: object) -> bool:
    return all(
        np.array_equal(x, y, equal_nan=True)
        for x, y in zip(a, b, strict=True)  # type: ignore[call-overload]
    )


def _decoded(seed: int, **kw: object) -> tuple[object, object, object]:
    p = random_problem(4, 40, 4, 2, seed=seed, **kw)  # type: ignore[arg-type]
    inst = compile_problem(p)
    rng = np.random.default_rng(seed)
    order = np.asarray(p.topological_order, dtype=np.int64)
    modes = np.array([rng.choice(p.task_modes[t]) for t in range(p.n_tasks)], dtype=np.int64)
    code, st = decode(inst, order, modes)
    assert code == 0
    return p, inst, st


@pytest.mark.parametrize("seed", range(8))
def test_commit_all_equals_one_commit_per_task(seed: int) -> None:
    p, inst, st = _decoded(seed, start_zones=seed % 2 == 1)
    rng = np.random.default_rng(100 + seed)
    # a prefix by start: every task starting before a random time
    cut = rng.uniform(0.0, float(np.max(st.t_start)))
    ts = sorted(
        (t for t in range(p.n_tasks) if st.t_start[t] <= cut), key=lambda t: (st.t_start[t], t)
    )
    one = inst.new_state()
    for t in ts:
        m = int(st.t_mode[t])
        nb = len(p.shapes[m].borders)
        k = int(one.arm_n[int(p.mode_arm[m])])
        inst.commit(one, t, m, float(st.t_start[t]), float(st.t_end[t]), k, st.t_waits[t, :nb])
    many = inst.new_state()
    inst.commit_all(
        many,
        np.array(ts, dtype=np.int64),
        st.t_mode[ts],
        st.t_start[ts],
        st.t_end[ts],
        st.t_waits[ts],
    )
    assert _states_equal(one, many)
    # the template the empty states are copied from is left as it was
    assert _states_equal(inst.new_state(), compile_problem(p).new_state())
    assert not np.any(inst.new_state().t_mode >= 0)


@pytest.mark.parametrize("seed", range(6))
def test_schedule_record_of_a_state(seed: int) -> None:
    p, inst, st = _decoded(seed, blocking=seed % 2 == 0)
    s = to_schedule(inst, st)
    for t in range(p.n_tasks):
        sh = p.shapes[int(s.mode[t])]
        assert len(s.waits[t]) == len(sh.borders)
        assert np.array_equal(s.waits[t], st.t_waits[t, : len(sh.borders)])
        b = max(0.0, float(s.end[t]) - float(s.start[t]) - sh.length(s.waits[t]))
        assert s.blocking[t] == (b if b > 1e-12 * max(1.0, abs(float(s.end[t]))) else 0.0)
    # the record is read-only and independent of the state it came from
    assert not any(w.flags.writeable for w in s.waits)
    before = [w.copy() for w in s.waits]
    st.t_waits[:] += 1.0
    st.t_start[:] += 1.0
    assert all(np.array_equal(a, b) for a, b in zip(before, s.waits, strict=True))
    assert not np.array_equal(s.start, st.t_start)
    # bound: the same arrays, now with the problem
    bound = s.bind(p)
    assert bound.bound_problem is p and s.bound_problem is None
    assert bound.start is s.start and bound.waits is s.waits
