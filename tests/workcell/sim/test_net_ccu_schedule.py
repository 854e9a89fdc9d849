"""A cell's schedule run as a SUPERSIGMA task program on the CCU (S1.1, S1.9)."""

from __future__ import annotations

import numpy as np
import pytest

from multiarm.errors import ValidationError
from scheduler import Problem, Schedule, solve
from scheduler.generate import random_problem
from workcell.sim.comms.microbus import move_time
from workcell.sim.control.supersigma import CCU, Box, Microbus, MotorController
from workcell.sim.control.supersigma.schedule import MAX_STEPS, run_schedule, steps_for
from workcell.sim.events.loop import EventLoop, ProcessGenerator


@pytest.fixture(scope="module")
def planned() -> tuple[Problem, Schedule]:
    problem = random_problem(3, 18, 3, 1, seed=4)
    plan = solve(problem, solver="greedy", time_limit=2.0, seed=0).schedule
    assert plan is not None
    return problem, plan


def test_every_task_runs_after_its_start_preds_and_resources(
    planned: tuple[Problem, Schedule],
) -> None:
    problem, plan = planned
    run = run_schedule(problem, plan)
    assert not np.isnan(run.start).any() and not np.isnan(run.end).any()
    assert run.report.lost == 0 and run.report.aborts == 0
    assert np.all(run.start >= plan.start - 1e-9)  # WAIT TIME
    for t, preds in enumerate(problem.task_preds):
        for p in preds:
            assert run.start[t] >= run.end[p], (problem.task_names[p], problem.task_names[t])
    # every resource passed from one task to another: the next user went in
    # only after the previous one had left
    assert len(run.handovers) > 0
    for h in run.handovers:
        assert h.left <= h.entered, h
    # each task lasts its planned duration, plus bus and polling latency and
    # any stop at a zone border; the whole run stays close to the plan
    extra = (run.end - run.start) - (plan.end - plan.start)
    assert np.all(extra > -move_time(1))
    assert run.makespan - run.planned_makespan < 0.01 * run.planned_makespan + 1.0
    assert run.makespan >= run.planned_makespan - 1e-9


def test_the_bus_load_of_a_schedule_is_low_and_the_ccu_mostly_idle(
    planned: tuple[Problem, Schedule],
) -> None:
    problem, plan = planned
    rep = run_schedule(problem, plan).report
    assert rep.commands >= problem.n_tasks  # at least one move per task
    assert rep.saturation < 0.01 and rep.idle_share >= 0.5


def test_same_schedule_same_run(planned: tuple[Problem, Schedule]) -> None:
    problem, plan = planned
    a, b = run_schedule(problem, plan), run_schedule(problem, plan)
    assert np.array_equal(a.end, b.end) and a.report == b.report


def test_refusals(planned: tuple[Problem, Schedule]) -> None:
    _problem, plan = planned
    other = random_problem(3, 5, 1, 0, seed=1)
    with pytest.raises(ValidationError, match="schedule has 18 tasks"):
        run_schedule(other, plan)
    big = random_problem(26, 30, 0, 0, seed=0)
    big_plan = solve(big, solver="greedy", time_limit=2.0, seed=0).schedule
    assert big_plan is not None
    with pytest.raises(ValidationError, match="at most 25"):
        run_schedule(big, big_plan)


def test_steps_for_inverts_the_profile() -> None:
    for d in (0.0, 0.01, 0.05, 0.3, 1.0):
        n = steps_for(d)
        assert move_time(n) <= d < move_time(n + 1)
    assert steps_for(1e6) == MAX_STEPS


def test_flags_that_stay_set_and_wait_until() -> None:
    k = EventLoop()
    bus = Microbus(k)
    bus.add(MotorController(1, "x"))
    ccu = CCU(k, bus, statement_time=0.0)
    seen: list[tuple[str, float]] = []

    def setter(c: CCU) -> ProcessGenerator:
        yield from c.wait_until(0.5)
        yield from c.set_flag("done")

    def waiter(name: str) -> Box:
        def box(c: CCU) -> ProcessGenerator:
            yield from c.wait_flag("done", consume=False)
            seen.append((name, round(c.kernel.now, 3)))

        return box

    ccu.run({"set": setter, "a": waiter("a"), "b": waiter("b")})
    assert sorted(seen) == [("a", 0.5), ("b", 0.5)]
    assert ccu.flags["done"] is True


@pytest.mark.parametrize("seed", range(4))
def test_every_schedule_completes(seed: int) -> None:
    # resource hand-overs follow planned start order: no box waits in a cycle
    problem = random_problem(4, 16, 4, 1, seed=seed, precedence=0.3)
    plan = solve(problem, solver="greedy", time_limit=2.0, seed=seed).schedule
    assert plan is not None
    run = run_schedule(problem, plan)
    assert not np.isnan(run.end).any() and run.report.lost == 0


def test_a_late_previous_user_holds_the_next_at_the_border(
    planned: tuple[Problem, Schedule],
) -> None:
    # a slow CCU (50 ms per statement) makes every task late: the next user
    # of a zone must stop at its border until the previous one has left
    problem, plan = planned
    run = run_schedule(problem, plan, statement_time=0.05)
    assert all(h.left <= h.entered for h in run.handovers)
    # some went in one statement after the other left: they were held
    held = [h for h in run.handovers if h.entered - h.left <= 0.05 + 1e-9]
    assert held
    assert run.makespan > run.planned_makespan
