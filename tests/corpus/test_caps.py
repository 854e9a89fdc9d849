"""Loops over user-given sizes: a documented cap with a clear error."""

from __future__ import annotations

import time

import pytest

from multiarm.errors import UsageError, ValidationError
from scheduler.generate import MAX_TASKS, random_problem
from tasklib.examples import MAX_TASKS as MAX_TASKSET
from tasklib.examples import generate_taskset
from workcell.sim import MessageLoss, SimOptions
from workcell.sim.harness.faults import MAX_LOSS
from workcell.sim.harness.options import RANGES


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: random_problem(2, 10**7), rf"n_tasks must be an integer in \[0, {MAX_TASKS}\]"),
        (lambda: random_problem(10**6, 4), r"n_arms must be an integer in \[1, 1000\]"),
        (lambda: random_problem(0, 4), r"n_arms must be an integer in \[1, 1000\]"),
        (lambda: random_problem(2, 4, 10**9), r"n_zones"),
        (lambda: generate_taskset(10**7), rf"n_tasks in \[1, {MAX_TASKSET}\]"),
        (lambda: generate_taskset(2.5), r"n_tasks in \[1, "),  # type: ignore[arg-type]
    ],
)
def test_generators_refuse_sizes_above_their_cap_at_once(call: object, words: str) -> None:
    t0 = time.perf_counter()
    with pytest.raises(ValidationError, match=words):
        call()  # type: ignore[operator]
    assert time.perf_counter() - t0 < 1.0


def test_the_caps_leave_the_largest_allowed_sizes_working() -> None:
    assert random_problem(2, 0).n_tasks == 0
    assert len(generate_taskset(1).tasks) == 1
    assert MessageLoss(MAX_LOSS).probability == MAX_LOSS


def test_message_loss_is_capped_where_a_run_would_take_hours() -> None:
    with pytest.raises(ValidationError, match=r"a dead link is an arm_failure"):
        MessageLoss(0.9999)


@pytest.mark.parametrize(("name", "bad"), [("tick", 1e6), ("tick", 1e-9), ("monitor_period", 1e-9)])
def test_sim_options_outside_their_range_are_refused_by_field(name: str, bad: float) -> None:
    lo, hi = RANGES[name]
    with pytest.raises(UsageError, match=rf"SimOptions\.{name} must be .*\[{lo:g}, {hi:g}\]"):
        SimOptions(**{name: bad})  # type: ignore[arg-type]
    SimOptions(**{name: hi})  # type: ignore[arg-type]
    SimOptions(**{name: lo})  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [1e300, 0.0, {"left": 1e300}, {"left": -1.0}])
def test_force_thresholds_have_a_physical_range(bad: object) -> None:
    with pytest.raises(UsageError, match=r"SimOptions\.force_threshold must be a number in"):
        SimOptions(force_threshold=bad)  # type: ignore[arg-type]
