"""Every solver through one interface: valid schedules, optimality on tiny
problems (against an independent brute force), determinism, bad input."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from multiarm.errors import UsageError
from scheduler import (
    SOLVERS,
    CpSatOptions,
    MatrixSetup,
    Model,
    Problem,
    Window,
    lower_bound,
    solve,
    validate,
)
from scheduler.generate import generate_problem, random_problem
from scheduler.tree import TreeOptions

FAST = {
    "tree": dict(time_limit=None, options=TreeOptions(max_evaluations=300, max_width=4)),
    "greedy": dict(time_limit=None),
    # a work limit, not a wall-clock one: repeatable on a loaded machine
    "cpsat": dict(time_limit=None, options=CpSatOptions(workers=1, max_deterministic_time=0.5)),
}


def run(problem: Problem, solver: str, seed: int = 0, **kw: object):  # type: ignore[no-untyped-def]
    args = {**FAST[solver], **kw}
    return solve(problem, solver, seed=seed, **args)  # type: ignore[arg-type]


# ------------------------------------------------------- valid schedules


@pytest.mark.parametrize("solver", SOLVERS)
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 100_000),
    shape=st.sampled_from([(2, 6, 2, 1), (3, 12, 3, 1), (4, 20, 4, 2)]),
    start_zones=st.booleans(),
    blocking=st.booleans(),
    waits=st.booleans(),
)
def test_every_schedule_validates(
    solver: str,
    seed: int,
    shape: tuple[int, int, int, int],
    start_zones: bool,
    blocking: bool,
    waits: bool,
) -> None:
    p = random_problem(*shape, seed=seed, start_zones=start_zones, blocking=blocking)
    r = run(p, solver, seed=seed, waits=waits)
    assert r.schedule is not None, r.summary()
    assert validate(p, r.schedule) == r.objective
    assert r.bound <= r.objective + 1e-9
    assert r.bound >= lower_bound(p) - 1e-6  # never below the proven bound
    if not waits:
        assert r.schedule.total_wait() == 0.0


# ----------------------------------------------- tiny problems: exact optima


def tiny(seed: int, n_tasks: int = 4, setups: bool = True) -> Problem:
    """2 arms, an exclusive and a shared zone, a tool, integer data, metric setups."""
    rng = np.random.default_rng(seed)
    m = Model(f"tiny{seed}")
    m.add_zone("E")
    m.add_zone("S", "shared")
    m.add_tool("K")
    m.add_arm("a", available=float(rng.integers(0, 2)))
    m.add_arm("b")
    for t in range(n_tasks):
        preds = [q for q in range(t) if rng.random() < 0.25]
        m.add_task(f"t{t}", release=float(rng.integers(0, 3)), predecessors=preds)
    for t in range(n_tasks):
        arms = ["a", "b"] if rng.random() < 0.7 else [str(rng.choice(["a", "b"]))]
        tool = ["K"] if rng.random() < 0.2 else []
        for arm in arms:
            d = int(rng.integers(1, 5))
            wins = []
            if rng.random() < 0.6:
                s = int(rng.integers(0, d))
                wins.append(Window("E", s, int(rng.integers(s + 1, d + 1))))
            if rng.random() < 0.5:
                s = int(rng.integers(0, d))
                e = int(rng.integers(s + 1, d + 1))
                wins += [Window("S", s, e), Window("S", s, int(rng.integers(s + 1, e + 1)), "move")]
            m.add_mode(f"t{t}", arm, float(d), windows=wins, tools=tool)
    if setups:
        m.set_setup(MatrixSetup(np.ones((2, n_tasks + 1, n_tasks))))  # 1 s between tasks: metric
    return m.build()


def brute_force(p: Problem, horizon: float) -> float:
    """Best makespan over integer starts, no waits: an independent check of the constraints."""
    T = p.n_tasks
    order = []
    indeg = [len(x) for x in p.task_preds]
    ready = [t for t in range(T) if indeg[t] == 0]
    while ready:
        t = ready.pop(0)
        order.append(t)
        for s in p.task_succs[t]:
            indeg[s] -= 1
            if indeg[s] == 0:
                ready.append(s)
    Z = p.n_zones

    def uses(m: int, S: int) -> list[tuple[str, int, float, float]]:
        out = []
        for w in p.mode_windows[m]:
            z = int(p.win_zone[w])
            if p.zone_exclusive[z]:
                out.append(("zone", z, S + p.win_start[w], S + p.win_end[w]))
            elif p.win_move[w]:
                out.append(("move", z, S + p.win_start[w], S + p.win_end[w]))
        for k in p.mode_tools[m]:
            out.append(("tool", k, S, S + p.mode_duration[m]))
        return out

    best = [horizon + 1e-9]
    chosen: dict[int, tuple[int, int]] = {}

    def compatible(t: int, m: int, S: int) -> bool:
        a = int(p.mode_arm[m])
        E = S + p.mode_duration[m]
        if p.arm_available[a] + p.setup_time(a, -1, t) > S:
            return False
        mine = uses(m, S)
        for u, (mu, Su) in chosen.items():
            Eu = Su + p.mode_duration[mu]
            if int(p.mode_arm[mu]) == a:
                if not (Su >= E + p.setup_time(a, t, u) or Eu + p.setup_time(a, u, t) <= S):
                    return False
                continue
            for kind, r, s1, e1 in mine:
                for kind2, r2, s2, e2 in uses(mu, Su):
                    if kind == kind2 and r == r2 and s1 < e2 and s2 < e1:
                        return False
        return True

    def dfs(i: int, cmax: float) -> None:
        if cmax >= best[0]:
            return
        if i == T:
            best[0] = cmax
            return
        t = order[i]
        lo = max(
            [
                p.task_release[t],
                *(chosen[q][1] + p.mode_duration[chosen[q][0]] for q in p.task_preds[t]),
            ]
        )
        for m in p.task_modes[t]:
            d = p.mode_duration[m]
            for S in range(math.ceil(lo), int(best[0] - d) + 1):
                if compatible(t, m, S):
                    chosen[t] = (m, S)
                    dfs(i + 1, max(cmax, S + d))
                    del chosen[t]

    dfs(0, 0.0)
    _ = Z
    return best[0]


@pytest.mark.parametrize("seed", range(12))
def test_tiny_optimum_tree_cpsat_brute_force_agree(seed: int) -> None:
    p = tiny(seed)
    greedy = solve(p, "greedy", waits=False)
    brute = brute_force(p, greedy.objective)
    tree = solve(p, "tree", time_limit=None, waits=False)
    cp = solve(p, "cpsat", time_limit=None, waits=False, workers=1)
    assert tree.status.value == "optimal" and cp.status.value == "optimal", (
        tree.summary(),
        cp.summary(),
    )
    assert tree.objective == cp.objective == brute, (tree.objective, cp.objective, brute)


@pytest.mark.parametrize("seed", range(12, 20))
def test_tiny_optimum_with_border_waits(seed: int) -> None:
    p = tiny(seed, n_tasks=5)
    tree = solve(p, "tree", time_limit=None)
    cp = solve(p, "cpsat", time_limit=None, workers=1)
    assert tree.status.value == "optimal" and cp.status.value == "optimal"
    assert tree.objective == pytest.approx(cp.objective)
    # waiting is allowed, not required: never worse than without waits
    assert tree.objective <= solve(p, "tree", time_limit=None, waits=False).objective + 1e-9


def test_waiting_at_a_border_beats_delaying_the_task() -> None:
    # A's task holds zone E over [0, 4) and F over [3, 6); B's task needs F over [0, 3) then E
    # over [3, 5). B can start at 0 and wait 1 s at its border 3 until E frees: makespan 7.
    # Without waits, B's whole task must avoid both (start >= 6), or A's must move: 11.
    m = Model()
    m.add_zone("E")
    m.add_zone("F")
    m.add_arm("A")
    m.add_arm("B")
    m.add_task("hold")
    m.add_mode("hold", "A", 6.0, windows=[Window("E", 0.0, 4.0), Window("F", 3.0, 6.0)])
    m.add_task("pass")
    m.add_mode("pass", "B", 6.0, windows=[Window("F", 0.0, 3.0), Window("E", 3.0, 5.0)])
    p = m.build()
    with_waits = solve(p, "tree", time_limit=None)
    without = solve(p, "tree", time_limit=None, waits=False)
    assert with_waits.objective == 7.0 and with_waits.schedule.total_wait() == 1.0  # type: ignore[union-attr]
    assert without.objective == 11.0
    assert solve(p, "cpsat", time_limit=None, workers=1).objective == 7.0
    assert solve(p, "greedy").objective == 7.0


# ------------------------------------------------------------- determinism


@pytest.mark.parametrize("solver", SOLVERS)
def test_same_seed_same_schedule(solver: str) -> None:
    # work limits, not wall-clock ones: cpsat single-threaded to the proven optimum
    p = random_problem(3, 25 if solver != "cpsat" else 8, 3, 1, seed=5)
    kw = {"time_limit": None} if solver == "cpsat" else {}
    r1 = run(p, solver, seed=7, **kw)
    r2 = run(p, solver, seed=7, **kw)
    assert r1.schedule == r2.schedule


def test_seed_changes_the_search() -> None:
    p = random_problem(4, 40, 4, 2, seed=2)
    opts = TreeOptions(max_evaluations=400, max_width=2)
    runs = {
        tuple(solve(p, "tree", time_limit=None, seed=s, options=opts).schedule.start.tolist())  # type: ignore[union-attr]
        for s in range(4)
    }
    assert len(runs) > 1


# ---------------------------------------------------------------- results


def test_time_limit_is_a_status_not_an_error() -> None:
    from scheduler import read_fjsp
    from tests.scheduler.test_fjsp import path_of

    p = read_fjsp(path_of("mk10"))  # open for decades: no solver closes it in half a second
    r = solve(p, "tree", time_limit=0.5)
    # the limit ends in a status, not an exception (no timing claim: machines are shared)
    assert r.status.value == "feasible" and r.schedule is not None
    assert r.stats.first_time <= r.stats.best_time <= r.runtime


def test_bad_calls() -> None:
    p = tiny(0)
    with pytest.raises(UsageError, match="unknown solver 'magic'"):
        solve(p, "magic")  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="time_limit"):
        solve(p, time_limit=-1)
    with pytest.raises(UsageError, match="has no option 'beam'"):
        solve(p, "greedy", beam=3)
    with pytest.raises(UsageError, match="seed"):
        solve(p, seed=1.5)  # type: ignore[arg-type]


def test_empty_problem() -> None:
    m = Model()
    m.add_arm("a")
    p = m.build()
    for s in SOLVERS:
        r = solve(p, s)
        assert r.objective == 0.0 and r.status.value == "optimal"


def test_fjsp_small_instances_are_solved_to_optimality(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from scheduler import parse_fjsp

    p = parse_fjsp("3 3 2\n2 2 1 3 2 2  1 3 4\n2 1 2 3  2 1 2 3 1\n1 2 1 4 3 2\n")
    results = {s: solve(p, s, time_limit=None) for s in SOLVERS}
    for s in ("tree", "cpsat"):  # the known optimum is 7
        assert results[s].status.value == "optimal" and results[s].objective == 7.0, s
    assert results["greedy"].objective >= 7.0
    _ = itertools


def test_parallel_workers_return_a_valid_schedule() -> None:
    p = random_problem(4, 60, 4, 2, seed=11)
    r = solve(
        p, "tree", time_limit=1.5, seed=3, options=TreeOptions(workers=2, parallel_min_time=0.5)
    )
    assert r.schedule is not None and validate(p, r.schedule) == r.objective
    assert "worker_error" not in r.stats.extra
    # the second process searches the other neighbourhood (list local search)
    assert r.stats.extra["worker_searches"] == ("local_search",)
    fjsp = generate_problem("setup_fjsp", 4, 30, 0, 0, seed=2)
    opt = TreeOptions(workers=3, parallel_min_time=0.5, portfolio_fjsp_max_tasks=0)
    r = solve(fjsp, "tree", time_limit=1.5, seed=3, options=opt)
    # on a pure FJSP every worker runs the compiled graph tabu search
    assert r.stats.extra["worker_searches"] == ("tabu_search", "tabu_search")
    single = solve(
        p, "tree", time_limit=None, seed=3, options=TreeOptions(workers=2, max_evaluations=200)
    )
    assert single.schedule is not None  # a work limit keeps the search in one process
