"""The outside families (scheduler.families) and the tree's race with CP-SAT on them.

The two generators make S2.11 problems (arms of different abilities and
speeds, tasks with precedence) with S2.5 zones used for part of a task and
the S2.12 waits at zone borders, in shapes unlike
:func:`scheduler.generate.random_problem`'s. Checked here: determinism,
sizes, input errors and that every generated problem has a schedule
:func:`scheduler.validate` accepts; then the race (``TreeOptions``'
portfolio rule): where the racing CP-SAT proves an optimum, the tree
returns it with status ``optimal``; the window rule keeps the race off
problems with many windows; the rounded-up bound proves integral optima;
the new option is validated.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from multiarm.errors import UsageError, ValidationError
from scheduler import Model, solve, validate
from scheduler.cpsat import solve_cpsat
from scheduler.families import ROUTE_SHAPES, random_routes_problem, random_stations_problem
from scheduler.generate import GENERATORS, generate_problem
from scheduler.setup import TravelSetup
from scheduler.tree import TreeOptions, solve_tree

FAMILIES = {"routes": random_routes_problem, "stations": random_stations_problem}


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_families_are_registered_and_seeded(name: str) -> None:
    """generate_problem reaches both; the same seed gives the same problem, another seed another."""
    assert GENERATORS[name] is FAMILIES[name]
    p = generate_problem(name, 4, 30, 4, 2, seed=7)
    assert (p.n_arms, p.n_tasks, p.n_zones, p.n_tools) == (4, 30, 4, 2)
    assert generate_problem(name, 4, 30, 4, 2, seed=7).to_dict() == p.to_dict()
    assert generate_problem(name, 4, 30, 4, 2, seed=8).to_dict() != p.to_dict()
    # every time an integer: CP-SAT solves the exact problem
    for values in (p.mode_duration, p.win_start, p.win_end, p.task_release):
        assert np.all(np.asarray(values) == np.round(values))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(sorted(FAMILIES)),
    arms=st.integers(1, 6),
    tasks=st.integers(1, 60),
    zones=st.integers(0, 6),
    tools=st.integers(0, 2),
    seed=st.integers(0, 2**31 - 1),
)
def test_every_generated_problem_has_a_valid_schedule(
    name: str, arms: int, tasks: int, zones: int, tools: int, seed: int
) -> None:
    """A seeded campaign over sizes: greedy schedules each problem, validate accepts it, and
    the windows lie inside their modes."""
    p = FAMILIES[name](arms, tasks, zones, tools, seed=seed)
    assert p.n_tasks == tasks and all(len(ms) >= 1 for ms in p.task_modes)
    dur = np.asarray(p.mode_duration)[np.asarray(p.win_mode, dtype=np.int64)]
    assert np.all(np.asarray(p.win_start) >= 0) and np.all(np.asarray(p.win_end) <= dur)
    assert np.all(np.asarray(p.win_start) < np.asarray(p.win_end))
    for waits in (True, False):
        r = solve(p, "greedy", waits=waits)
        assert r.schedule is not None
        assert validate(p, r.schedule) == pytest.approx(r.objective)


def test_routes_draws_every_window_shape() -> None:
    """Across a few seeds the routes family uses zones over the whole task, its start only,
    its end only, a middle part, and two windows (the five ROUTE_SHAPES)."""
    seen = set()
    for seed in range(5):
        p = random_routes_problem(3, 40, 3, 0, seed=seed, shared_fraction=0.0)
        for m in range(p.n_modes):
            ws = np.flatnonzero(np.asarray(p.win_mode) == m)
            d = float(p.mode_duration[m])
            s, e = np.asarray(p.win_start)[ws], np.asarray(p.win_end)[ws]
            if len(ws) == 2:
                seen.add("several")
            elif len(ws) == 1:
                at0, atd = s[0] == 0, e[0] == d
                seen.add(
                    {(True, True): "whole", (True, False): "start", (False, True): "end"}.get(
                        (bool(at0), bool(atd)), "middle"
                    )
                )
    assert seen == set(ROUTE_SHAPES)


def test_stations_corridors_are_shared_and_stations_exclusive() -> None:
    """Shared corridors carry only move windows (the approach and retreat); stations are exclusive."""
    p = random_stations_problem(4, 40, 5, 1, seed=3, shared_fraction=0.4)
    excl = np.asarray(p.zone_exclusive)
    assert excl.sum() == 3 and (~excl).sum() == 2
    zone = np.asarray(p.win_zone)
    move = np.asarray(p.win_move)
    assert np.all(move[~excl[zone]])  # corridor windows are moves
    assert not np.any(move[excl[zone]])  # station windows are occupations
    assert isinstance(p.setup, TravelSetup)  # travel between stations


@pytest.mark.parametrize(
    ("call", "culprit"),
    [
        (lambda: random_routes_problem(0, 10, 2, 0), "n_arms"),
        (lambda: random_routes_problem(2, 10, 2, True), "n_tools"),
        (lambda: random_routes_problem(2, 10, 2, 0, flexibility=1.5), "flexibility"),
        (lambda: random_stations_problem(2, 0, 2, 0), "n_tasks"),
        (lambda: random_stations_problem(2, 10, 2, 0, reach=0), "reach"),
        (lambda: random_stations_problem(2, 10, 2, 0, shared_fraction=-0.1), "shared_fraction"),
        (lambda: generate_problem("routes", 2, 10, 2, 0, grid=3), "grid"),
    ],
)
def test_bad_parameters_name_the_culprit(call, culprit: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValidationError, match=culprit):
        call()


# the race, bounded: small problems of each family that CP-SAT (one worker) proves
# within a fraction of a second on an idle machine
# (and one of 22 tasks, solved without waits, beyond the earlier 16-task race rule)
RACED = [
    ("routes", (3, 10, 3, 1), 1, True),
    ("routes", (2, 12, 2, 1), 2, True),
    ("routes", (4, 22, 6, 1), 1, False),
    ("stations", (2, 8, 2, 0), 0, True),
    ("stations", (3, 10, 3, 1), 0, True),
]


@pytest.mark.parametrize(("name", "size", "seed", "waits"), RACED)
def test_tree_returns_the_optimum_the_racing_cpsat_proves(
    name: str, size: tuple[int, int, int, int], seed: int, waits: bool
) -> None:
    """Exact B&B off, so the proof can only come from the race (or the bound): the tree's
    result is CP-SAT's proven optimum, status optimal, and it stopped well before its limit."""
    p = generate_problem(name, *size, seed=seed)
    ref = solve_cpsat(p, 20.0, seed, workers=1, waits=waits)
    assert ref.status.value == "optimal"
    r = solve_tree(p, 20.0, seed, waits=waits, options=TreeOptions(exact_max_tasks=0))
    assert "portfolio" in r.stats.extra  # it raced
    assert r.status.value == "optimal"
    assert r.objective == pytest.approx(ref.objective)
    assert validate(p, r.schedule) == pytest.approx(ref.objective)
    assert r.runtime < 15.0  # stopped at the proof, not at the limit


def test_race_rule_follows_the_options() -> None:
    """The window rule keeps the race off (a second tree process instead, searching the
    other neighbourhood); beside the race the main process alternates the two; the size
    rule reaches 40 tasks by default without setups, 16 with them; a work-limited run
    never races."""
    p = generate_problem("routes", 3, 30, 3, 1, seed=1)
    assert p.n_windows > 5
    off = solve_tree(p, 1.0, 0, options=TreeOptions(portfolio_max_windows=5, parallel_min_time=0.3))
    assert "portfolio" not in off.stats.extra
    # no race: the second process runs the list local search, the main one never does
    assert off.stats.extra["worker_searches"] == ("local_search",)
    assert "improve_list" not in off.stats.phases
    on = solve_tree(p, 1.0, 0)
    assert "portfolio" in on.stats.extra
    # racing, no second process: the main one takes turns with the list local search
    assert "worker_searches" not in on.stats.extra
    assert on.stats.phases["improve_list"] > 0
    small = solve_tree(p, 1.0, 0, options=TreeOptions(portfolio_max_tasks=29))
    assert "portfolio" not in small.stats.extra
    worked = solve_tree(p, None, 0, options=TreeOptions(max_evaluations=300))
    assert "portfolio" not in worked.stats.extra
    # with setup times the size rule is portfolio_setup_max_tasks
    q = generate_problem("stations", 3, 20, 3, 1, seed=1)
    assert "portfolio" not in solve_tree(q, 1.0, 0).stats.extra
    opt = TreeOptions(portfolio_setup_max_tasks=20)
    assert "portfolio" in solve_tree(q, 1.0, 0, options=opt).stats.extra


def test_integral_data_rounds_the_bound_up_to_a_proof() -> None:
    """Three unit tasks on two arms: the load bound is 1.5, but with integer data the
    optimum is an integer, so 2 is a bound and the tree's schedule of 2 is proven
    (exact B&B off, work-limited: no race either). With a time of 0.1 the grid is
    tenths: the bound 0.15 rounds to 0.2, the optimum."""
    for unit in (1.0, 0.1):
        m = Model()
        for a in range(2):
            m.add_arm(f"a{a}")
        for t in range(3):
            m.add_task(f"t{t}")
            for a in range(2):
                m.add_mode(t, a, unit)
        p = m.build()
        r = solve_tree(p, None, 0, options=TreeOptions(exact_max_tasks=0, max_evaluations=50))
        assert r.objective == pytest.approx(2 * unit)
        assert r.status.value == "optimal" and r.bound == pytest.approx(2 * unit)
    # not on the grid: the bound is kept as it is
    m = Model()
    for a in range(2):
        m.add_arm(f"a{a}")
    for t in range(3):
        m.add_task(f"t{t}")
        for a in range(2):
            m.add_mode(t, a, 1.0 + 1e-7 * math.pi)
    p = m.build()
    r = solve_tree(p, None, 0, options=TreeOptions(exact_max_tasks=0, max_evaluations=50))
    assert r.status.value == "feasible" and r.bound < r.objective


@pytest.mark.parametrize(
    "bad", [-1, True, 2.5, "10", None], ids=["negative", "bool", "float", "str", "none"]
)
@pytest.mark.parametrize("name", ["portfolio_max_windows", "portfolio_setup_max_tasks"])
def test_portfolio_fields_are_validated(bad: object, name: str) -> None:
    with pytest.raises(UsageError, match=name):
        TreeOptions(**{name: bad})
    assert getattr(TreeOptions(**{name: 0}), name) == 0


def test_cpsat_reports_the_bounds_it_proves_only_on_an_exact_model() -> None:
    """solve_cpsat(on_bound=f): the bounds come in increasing and never pass the optimum;
    with a time unit that rounds the data the model's bound is no bound of the problem,
    and f is never called."""
    p = generate_problem("routes", 3, 10, 3, 1, seed=1)
    seen: list[float] = []
    r = solve_cpsat(p, 20.0, 0, workers=1, on_bound=seen.append)
    assert r.status.value == "optimal"
    assert seen and seen == sorted(seen) and seen[-1] <= r.objective
    rounded: list[float] = []
    solve_cpsat(p, 2.0, 0, workers=1, on_bound=rounded.append, unit=0.3)
    assert rounded == []


def test_polish_rule_follows_the_problem_and_the_options() -> None:
    """The polish (TreeOptions.polish_share) may run on a zone problem without setups,
    and with setups up to polish_setup_max_tasks tasks; never beyond
    portfolio_max_windows, with a blocking oracle or with a share of 0; the size rule
    of a pure FJSP is checked in solve_tree (below)."""
    from scheduler.tree import _may_polish

    routes = generate_problem("routes", 3, 30, 3, 1, seed=1)
    stations = generate_problem("stations", 3, 20, 3, 1, seed=1)
    opt = TreeOptions()
    assert _may_polish(routes, opt)
    assert not _may_polish(routes, TreeOptions(polish_share=0.0))
    assert not _may_polish(routes, TreeOptions(portfolio_max_windows=5))
    assert _may_polish(stations, opt)  # travel setups, 20 tasks <= polish_setup_max_tasks
    big = generate_problem("stations", 3, 50, 3, 1, seed=1)
    assert opt.polish_setup_max_tasks < 50 and not _may_polish(big, opt)
    assert _may_polish(generate_problem("zones", 3, 8, 2, 1, seed=1), opt)  # small, setups
    assert _may_polish(generate_problem("zones", 3, 8, 2, 1, seed=1, setups=False), opt)
    blocked = generate_problem("zones", 3, 8, 2, 1, seed=1, setups=False, blocking=True)
    assert blocked.blocking is not None and not _may_polish(blocked, opt)
    # setups: up to polish_setup_max_tasks tasks only
    assert _may_polish(stations, TreeOptions(polish_setup_max_tasks=20))
    assert not _may_polish(stations, TreeOptions(polish_setup_max_tasks=19))
    assert not _may_polish(stations, TreeOptions(polish_setup_max_tasks=20, polish_share=0.0))


@pytest.mark.parametrize("bad", [-0.1, 1.0, "0.3", None], ids=["negative", "one", "str", "none"])
def test_polish_share_is_validated(bad: object) -> None:
    with pytest.raises(UsageError, match="polish_share"):
        TreeOptions(polish_share=bad)  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="polish_min_time"):
        TreeOptions(polish_min_time=-1.0)


@pytest.mark.parametrize("name", ["polish_fjsp_max_tasks", "polish_setup_max_tasks"])
@pytest.mark.parametrize("bad", [-1, 2.5, True, "10"], ids=["negative", "float", "bool", "str"])
def test_polish_size_rules_are_validated(name: str, bad: object) -> None:
    with pytest.raises(UsageError, match=name):
        TreeOptions(**{name: bad})  # type: ignore[arg-type]


def test_polish_hands_the_tree_s_schedule_to_cpsat_and_keeps_the_better() -> None:
    """_polish from the HEFT schedule (the tree's first incumbent) on a small routes
    problem: CP-SAT, hinted with it, returns a shorter schedule and proves it optimal
    (the optimum CP-SAT alone proves); the result is a Solution whose schedule _finish
    validates. From the optimum itself, it keeps the tree's schedule (nothing shorter)."""
    from scheduler.result import SearchStats
    from scheduler.start import begin
    from scheduler.tree import _polish

    p = generate_problem("routes", 3, 10, 3, 1, seed=1)
    ref = solve_cpsat(p, 20.0, 0, workers=1)
    assert ref.status.value == "optimal"
    st = begin(p, "tree", 0)
    heft = st.first
    assert heft is not None and heft.makespan > ref.objective
    stats = SearchStats()
    t0 = time.perf_counter()
    best, lb, proven = _polish(p, st.ev, heft, st.lb, t0 + 20.0, True, 0, TreeOptions(), stats, t0)
    assert (
        proven
        and best.makespan == pytest.approx(ref.objective)
        and lb == pytest.approx(ref.objective)
    )
    assert stats.extra["polish"] == "optimal" and stats.phases["polish"] < 20.0
    assert validate(p, stats.extra["exact_schedule"]) == pytest.approx(ref.objective)
    # from the optimum (a schedule kept outside the decoder, as a worker's is): kept as it is
    again = SearchStats()
    again.extra["worker_schedule"] = kept_schedule = stats.extra["exact_schedule"]
    kept, _lb, proven = _polish(p, st.ev, best, st.lb, t0 + 40.0, True, 0, TreeOptions(), again, t0)
    assert kept is best and proven
    assert again.extra["worker_schedule"] is kept_schedule and "exact_schedule" not in again.extra


def test_polish_runs_only_within_its_rule() -> None:
    """solve_tree polishes a routes problem when the share of its limit reaches
    polish_min_time (stats: the phase, CP-SAT's status); not with a shorter limit, not
    on a work limit (those stay repeatable), not on a pure FJSP above
    polish_fjsp_max_tasks nor on setups above polish_setup_max_tasks."""
    p = generate_problem("routes", 3, 30, 3, 1, seed=1)
    opt = TreeOptions(polish_share=0.5, polish_min_time=0.5)
    on = solve_tree(p, 1.2, 0, options=opt)
    # the phase ran (what CP-SAT found in its 0.6 s depends on the machine's load)
    assert "polish" in on.stats.phases or on.status.value == "optimal"
    assert "polish" not in on.stats.phases or "polish" in on.stats.extra
    assert "polish" not in solve_tree(p, 1.2, 0).stats.phases  # 0.4 * 1.2 s < 2 s
    worked = solve_tree(p, None, 0, options=TreeOptions(max_evaluations=300, polish_min_time=0.0))
    assert "polish" not in worked.stats.phases
    from scheduler.fjsp import parse_fjsp

    f = parse_fjsp("2 2\n2 1 1 3 1 2 2\n1 2 1 1 2 2\n")
    no_fjsp = TreeOptions(polish_share=0.5, polish_min_time=0.5, polish_fjsp_max_tasks=0)
    assert "polish" not in solve_tree(f, 1.2, 0, options=no_fjsp).stats.phases
    # a pure FJSP the graph search does not prove in 0.6 s: polished within its size rule
    g = generate_problem("setup_fjsp", 8, 80, 0, 0, seed=0, setup_fraction=0.0)
    assert g._setup.zero
    within = TreeOptions(polish_share=0.5, polish_min_time=0.5, polish_fjsp_max_tasks=80)
    on_g = solve_tree(g, 1.2, 0, options=within)
    assert "polish" in on_g.stats.phases or on_g.status.value == "optimal"
    assert "polish" not in solve_tree(g, 1.2, 0, options=opt).stats.phases  # default: 60
    small = TreeOptions(polish_share=0.5, polish_min_time=0.5, polish_fjsp_max_tasks=79)
    assert "polish" not in solve_tree(g, 1.2, 0, options=small).stats.phases
    # setups: polished up to polish_setup_max_tasks tasks only
    s = generate_problem("stations", 3, 30, 3, 1, seed=1)
    with_setups = TreeOptions(polish_share=0.5, polish_min_time=0.5, polish_setup_max_tasks=30)
    on_s = solve_tree(s, 1.2, 0, options=with_setups)
    assert "polish" in on_s.stats.phases or on_s.status.value == "optimal"
    below = TreeOptions(polish_share=0.5, polish_min_time=0.5, polish_setup_max_tasks=29)
    assert "polish" not in solve_tree(s, 1.2, 0, options=below).stats.phases
