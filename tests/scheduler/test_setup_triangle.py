"""Setups that break the triangle inequality: the initial pose's setup binds the first task only.

A task may move its arm closer to the next one, so the setup from the
initial pose into a task can exceed the way through another task
(``setup(-1, b) > setup(-1, a) + d_a + setup(a, b)``). Every CP-SAT model
(:func:`scheduler.cpsat.solve_cpsat`, the no-wait reference of
:mod:`scheduler.reference`) and relaxation (zone-free, overlap, busy
resources) once bounded *every* task's start by ``available + setup(-1,
t)``: on such data CP-SAT called a feasible problem infeasible and the
relaxations' bounds could exceed the optimum. Now that setup is enforced on
the circuit's start arc only, and every task's start keeps the arm's shortest
way into it (:func:`scheduler.cpsat.arrival_heads`: the initial setup itself
where setups are metric, so the models lose no strength there).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from scheduler import Model, SolveStatus, solve, validate
from scheduler.cpsat import arrival_heads
from scheduler.problem import Problem
from scheduler.reference import best_bound, solve_reference
from scheduler.setup import MatrixSetup


def _one_arm_pair() -> Problem:
    """1 arm, 2 tasks of 1 s; from the start pose t1 costs 10 s, through t0 nothing."""
    m = Model()
    m.add_arm("a")
    for i in range(2):
        m.add_task(f"t{i}")
        m.add_mode(f"t{i}", "a", 1.0)
    m.set_setup(MatrixSetup([[[0.0, 10.0], [0.0, 0.0], [0.0, 0.0]]]))
    return m.build()


def _brute_force(p: Problem) -> float:
    """The optimum of a zone-free problem by enumeration: modes, then each
    arm's order, tasks as early as the arm, releases and predecessors allow."""
    best = np.inf
    for modes in itertools.product(*[list(ms) for ms in p.task_modes]):
        per_arm: dict[int, list[int]] = {}
        for t, m in enumerate(modes):
            per_arm.setdefault(int(p.mode_arm[m]), []).append(t)
        arms = sorted(per_arm)
        for orders in itertools.product(*[itertools.permutations(per_arm[a]) for a in arms]):
            end = [np.nan] * p.n_tasks
            pos = {t: (a, i) for a, o in zip(arms, orders, strict=True) for i, t in enumerate(o)}
            seq = dict(zip(arms, orders, strict=True))
            done: set[int] = set()
            ok = True
            while len(done) < p.n_tasks and ok:
                ok = False
                for t in range(p.n_tasks):
                    a, i = pos[t]
                    prev = seq[a][i - 1] if i else -1
                    if t in done or (prev >= 0 and prev not in done):
                        continue
                    if any(q not in done for q in p.task_preds[t]):
                        continue
                    s = float(p.task_release[t])
                    s = max(s, *(end[q] for q in p.task_preds[t])) if p.task_preds[t] else s
                    ready = float(p.arm_available[a]) if prev < 0 else end[prev]
                    s = max(s, ready + p.setup_time(a, prev, t))
                    end[t] = s + float(p.mode_duration[modes[t]])
                    done.add(t)
                    ok = True
            if ok:
                best = min(best, max(end))
    return float(best)


def _random_problem(seed: int) -> Problem:
    """2 arms, 4 tasks, random matrix setups, the initial pose far from some tasks."""
    rng = np.random.default_rng(seed)
    m = Model()
    for a in ("a", "b"):
        m.add_arm(a)
    T = 4
    for t in range(T):
        m.add_task(f"t{t}", release=float(rng.integers(0, 3)))
        for a in ("a", "b"):
            if rng.random() < 0.8 or a == "a":
                m.add_mode(f"t{t}", a, float(rng.integers(1, 5)))
    times = rng.integers(0, 3, size=(2, T + 1, T)).astype(float)
    times[:, 0, :] += rng.integers(0, 2, size=(2, T)) * 12.0  # far from the start pose
    m.set_setup(MatrixSetup(times))
    return m.build()


def test_cpsat_solves_a_problem_whose_initial_setup_is_longer_than_the_way_round() -> None:
    p = _one_arm_pair()
    r = solve(p, "cpsat", time_limit=10, seed=0, workers=1)
    assert r.status is SolveStatus.OPTIMAL and r.schedule is not None
    assert r.schedule.makespan == pytest.approx(2.0)
    validate(p, r.schedule)


@pytest.mark.parametrize("seed", range(8))
def test_models_and_bounds_agree_with_brute_force_on_non_metric_setups(seed: int) -> None:
    p = _random_problem(seed)
    opt = _brute_force(p)
    r = solve(p, "cpsat", time_limit=20, seed=0, workers=1)
    assert r.status is SolveStatus.OPTIMAL and r.schedule is not None, r.status
    validate(p, r.schedule)
    assert r.schedule.makespan == pytest.approx(opt)
    ref = solve_reference(p, 20, workers=1)
    assert ref.schedule is not None
    validate(p, ref.schedule)
    assert ref.bound <= opt + 1e-6
    assert best_bound(p, 10, workers=1) <= opt + 1e-6


@pytest.mark.parametrize("seed", range(4))
def test_arrival_heads_are_the_initial_setup_where_setups_are_metric(seed: int) -> None:
    """Travel between points of a plane (a metric) keeps the models as strong as before."""
    rng = np.random.default_rng(seed)
    T = 6
    m = Model()
    for a in ("a", "b"):
        m.add_arm(a, available=float(rng.integers(0, 4)))
    for t in range(T):
        m.add_task(f"t{t}")
        for a in ("a", "b"):
            m.add_mode(f"t{t}", a, float(rng.integers(1, 5)))
    home = rng.uniform(0, 10, size=(2, 2))
    where = rng.uniform(0, 10, size=(T, 2))
    times = np.zeros((2, T + 1, T))
    for k in range(2):
        times[k, 0] = np.linalg.norm(where - home[k], axis=1)
        times[k, 1:] = np.linalg.norm(where[:, None] - where[None], axis=2)
    m.set_setup(MatrixSetup(times))
    p = m.build()
    want = np.array(
        [
            p.arm_available[p.mode_arm[k]]
            + p.setup_time(int(p.mode_arm[k]), -1, int(p.mode_task[k]))
            for k in range(p.n_modes)
        ]
    )
    np.testing.assert_allclose(arrival_heads(p), want)
    # and below it on the one-arm pair that breaks the inequality: 0 through t0, not 10
    np.testing.assert_allclose(arrival_heads(_one_arm_pair()), [0.0, 1.0])
