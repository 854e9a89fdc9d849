"""Every solver on problems with every window kind in every zone kind.

The generator (``tests.strategies.zone_problems``) puts occupy and move
windows in exclusive and restricted-simultaneous (shared) zones, move windows
in exclusive zones included, several windows of one mode in one zone, tools,
releases and precedence. Every schedule must pass :func:`validate` and an
independent check of the zones written here from the raw windows (not from
:mod:`scheduler.timing`, which the solvers share with the validator).
"""

from __future__ import annotations

import itertools

import pytest
from hypothesis import HealthCheck, find, given, settings
from hypothesis import strategies as st

from scheduler import SOLVERS, CpSatOptions, Problem, Schedule, TreeOptions, solve, validate
from tests.strategies import WINDOW_KINDS, ZONE_POLICIES, zone_problems

WORK = {
    "tree": dict(time_limit=None, options=TreeOptions(max_evaluations=150, max_width=3)),
    "greedy": dict(time_limit=None),
    "cpsat": dict(time_limit=None, options=CpSatOptions(workers=1, max_deterministic_time=1.0)),
}


def _has(p: Problem, kind: str, policy: str) -> bool:
    return any(
        bool(p.win_move[w]) == (kind == "move")
        and bool(p.zone_exclusive[int(p.win_zone[w])]) == (policy == "exclusive")
        for w in range(p.n_windows)
    )


@pytest.mark.parametrize(("kind", "policy"), list(itertools.product(WINDOW_KINDS, ZONE_POLICIES)))
def test_the_generator_reaches_every_window_kind_in_every_zone_kind(kind: str, policy: str) -> None:
    p = find(
        zone_problems(),
        lambda p: _has(p, kind, policy),
        settings=settings(database=None, max_examples=500),
    )
    assert _has(p, kind, policy)


def _zone_intervals(p: Problem, s: Schedule, t: int) -> list[tuple[int, bool, float, float]]:
    """(zone, moving, start, end) of task ``t`` from its raw windows and waits.

    In an exclusive zone every window is presence and holds the zone through
    the waits at borders inside it; in a shared zone only move windows count,
    each split at the borders where the arm waits (a waiting arm does not move).
    """
    m = int(s.mode[t])
    borders = p.mode_borders(m)
    waits = dict(zip(borders, s.waits[t].tolist(), strict=True))
    S = float(s.start[t])

    def at(x: float, inclusive: bool) -> float:
        return S + x + float(sum(w for b, w in waits.items() if b < x or (inclusive and b == x)))

    out = []
    for w in p.mode_windows[m]:
        z = int(p.win_zone[w])
        ws, we = float(p.win_start[w]), float(p.win_end[w])
        if p.zone_exclusive[z]:
            out.append((z, False, at(ws, True), at(we, False)))
        elif p.win_move[w]:
            cuts = [ws, *(b for b in borders if ws < b < we and waits[b] > 0), we]
            for a, b in itertools.pairwise(cuts):
                out.append((z, True, at(a, True), at(b, False)))
    return out


def _independent_zone_check(p: Problem, s: Schedule) -> None:
    arms = s.arms(p)
    iv = {t: _zone_intervals(p, s, t) for t in range(p.n_tasks)}
    for t, u in itertools.combinations(range(p.n_tasks), 2):
        if arms[t] == arms[u]:
            continue
        for (z1, _m1, s1, e1), (z2, _m2, s2, e2) in itertools.product(iv[t], iv[u]):
            if z1 == z2 and s1 < e2 - 1e-6 and s2 < e1 - 1e-6:
                raise AssertionError(
                    f"tasks {p.task_names[t]} and {p.task_names[u]} overlap in zone "
                    f"{p.zone_names[z1]} during [{max(s1, s2)}, {min(e1, e2)})"
                )


@pytest.mark.parametrize("solver", SOLVERS)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(p=zone_problems(), waits=st.booleans(), seed=st.integers(0, 1000))
def test_every_solver_schedule_validates_on_every_window_kind(
    solver: str, p: Problem, waits: bool, seed: int
) -> None:
    r = solve(p, solver, seed=seed, waits=waits, **WORK[solver])  # type: ignore[arg-type]
    # no start zones: a schedule always exists, and a solver must find one
    assert r.schedule is not None, r.summary()
    assert validate(p, r.schedule) == r.objective
    _independent_zone_check(p, r.schedule)
    assert r.bound <= r.objective + 1e-9
    if not waits:
        assert r.schedule.total_wait() == 0.0


@pytest.mark.parametrize(
    ("policy", "kind", "expect"),
    [
        ("exclusive", "move", 6.0),
        ("exclusive", "occupy", 6.0),
        ("shared", "move", 6.0),
        ("shared", "occupy", 4.0),
    ],
)
def test_each_window_kind_in_each_zone_kind_for_every_solver(
    policy: str, kind: str, expect: float
) -> None:
    # two arms, each with a window in zone z over [1, 3) of a 4 s task: any
    # window in an exclusive zone and move windows in a shared one serialise
    # the two (the second starts at 2: makespan 6); occupants of a shared zone
    # that do not move there run together (makespan 4)
    from scheduler import Model, Window

    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_zone("z", policy)  # type: ignore[arg-type]
    m.add_task("t1")
    m.add_task("t2")
    m.add_mode("t1", "a", 4.0, windows=[Window("z", 1.0, 3.0, kind)])  # type: ignore[arg-type]
    m.add_mode("t2", "b", 4.0, windows=[Window("z", 1.0, 3.0, kind)])  # type: ignore[arg-type]
    p = m.build()
    for solver in SOLVERS:
        r = solve(p, solver, waits=False, **WORK[solver])  # type: ignore[arg-type]
        assert r.schedule is not None
        _independent_zone_check(p, r.schedule)
        assert r.objective == expect, (solver, r.objective)


def test_the_independent_check_can_fail() -> None:
    from scheduler import Model, Window

    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_zone("z", "exclusive")
    m.add_task("t1")
    m.add_task("t2")
    m.add_mode("t1", "a", 4.0, windows=[Window("z", 1.0, 3.0, "move")])
    m.add_mode("t2", "b", 4.0, windows=[Window("z", 1.0, 3.0, "move")])
    p = m.build()
    _independent_zone_check(p, Schedule.from_starts(p, [0, 1], [0.0, 2.0]))
    with pytest.raises(AssertionError, match=r"overlap in zone z during \[2\.0, 3\.0\)"):
        _independent_zone_check(p, Schedule.from_starts(p, [0, 1], [0.0, 1.0]))
