"""The kernel's timelines hold exactly what :mod:`scheduler.timing` says a task holds.

After a decode, each placed task's intervals on the resource timelines must
be :meth:`ModeShape.intervals` of its start and waits plus its tools from
start to end, bit for bit (the kernel records them from prefix sums of the
waits, as the timing module computes them), and every timeline is sorted by
start and by end: the placement's early exit (everything held ends before a
piece starts, read from the last interval) relies on the ends being in order.
"""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings

from multiarm.types import IntArray
from scheduler import Model, Problem, Window, validate
from scheduler.generate import random_problem
from scheduler.kernel import State, compile_problem, decode, to_schedule
from scheduler.search import priority_order
from tests.strategies import zone_problems


def _held(p: Problem, st: State) -> dict[int, list[tuple[int, float, float]]]:
    """Per task, the (resource, start, end) intervals the state's timelines hold for it."""
    inst = compile_problem(p)
    out: dict[int, list[tuple[int, float, float]]] = {t: [] for t in range(p.n_tasks)}
    for r in range(inst.R):
        lo, n = int(inst.res_lo[r]), int(st.res_n[r])
        s, e = st.tl_s[lo : lo + n], st.tl_e[lo : lo + n]
        assert np.all(np.diff(s) >= 0.0), f"resource {r}: starts out of order"
        assert np.all(np.diff(e) >= 0.0), f"resource {r}: ends out of order"
        for k in range(lo, lo + n):
            t = int(st.tl_task[k])
            if t >= 0:
                out[t].append((r, float(st.tl_s[k]), float(st.tl_e[k])))
    return out


def _check(p: Problem, chrono: bool, order: IntArray | None = None) -> int:
    """Decode ``order`` (default: the priority order; earliest-finishing
    modes, waits at borders) and compare each task's intervals with the
    timing module's; returns the waits used."""
    inst = compile_problem(p)
    order = priority_order(p) if order is None else order
    code, st = decode(inst, order, np.full(p.n_tasks, -1), chrono=chrono)
    assert code == 0
    s = to_schedule(inst, st)
    validate(p, s)
    held = _held(p, st)
    for t in range(p.n_tasks):
        sh = p.shapes[int(s.mode[t])]
        want = sh.intervals(float(s.start[t]), s.waits[t])
        want += [(r, float(s.start[t]), float(s.end[t])) for r in sh.tools]
        assert sorted(held[t]) == sorted(want), f"task {t}"
    return sum(int(np.count_nonzero(w)) for w in s.waits)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(zone_problems(max_arms=3, max_tasks=8))
def test_timelines_hold_the_timing_modules_intervals(p: Problem) -> None:
    for chrono in (False, True):
        _check(p, chrono)


def test_timelines_with_many_waits_start_zones_and_detours() -> None:
    # seeds 6..11 carry the generator's blocking oracle (chronological, detours
    # at the end: tools held through them)
    waited = []
    for seed in range(12):
        p = random_problem(
            6, 60, 3, 1, seed=seed, zone_fraction=1.0, start_zones=True, blocking=seed >= 6, grid=3
        )
        waited.append(sum(_check(p, chrono) for chrono in (False, True)))
    # the waits' prefix sums are exercised, with and without the oracle
    assert min(waited) > 0, waited


def test_a_move_split_at_two_waits_holds_three_pieces() -> None:
    # arm A moves through shared zone S for its whole task and enters E1 at
    # 3 s and E2 at 6 s, which arms B and C hold until 5 s and 9 s: A waits
    # 2 s and 1 s at those borders, and its move in S is cut there
    m = Model()
    for z, policy in (("S", "shared"), ("E1", "exclusive"), ("E2", "exclusive")):
        m.add_zone(z, policy)  # type: ignore[arg-type]
    for a in ("A", "B", "C"):
        m.add_arm(a)
    m.add_task("b")
    m.add_mode("b", "B", 5.0, windows=[Window("E1", 0.0, 5.0)])
    m.add_task("c")
    m.add_mode("c", "C", 9.0, windows=[Window("E2", 0.0, 9.0)])
    m.add_task("a")
    m.add_mode(
        "a",
        "A",
        10.0,
        windows=[Window("S", 0.0, 10.0, "move"), Window("E1", 3.0, 4.0), Window("E2", 6.0, 7.0)],
    )
    p = m.build()
    inst = compile_problem(p)
    for chrono in (False, True):
        code, st = decode(inst, np.arange(3), np.full(3, -1), chrono=chrono)
        assert code == 0
        assert st.t_start[2] == 0.0 and st.t_waits[2, :2].tolist() == [2.0, 1.0]
        S, Z = 0, p.n_zones
        pieces = sorted((s, e) for r, s, e in _held(p, st)[2] if r == Z + S)
        assert pieces == [(0.0, 3.0), (5.0, 8.0), (9.0, 13.0)]
        assert _check(p, chrono, np.arange(3)) == 2
