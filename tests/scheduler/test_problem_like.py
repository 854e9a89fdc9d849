"""solve and validate take a Problem or anything carrying one as ``.problem``
(a compiled cell), duck typed: the scheduler never imports workcell."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from multiarm.errors import UsageError
from scheduler import HasProblem, Problem, solve, validate
from scheduler.generate import random_problem
from scheduler.problem import as_problem


@dataclass(frozen=True)
class Holder:
    problem: Problem


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_holder_solves_and_validates_like_its_problem(seed: int) -> None:
    p = random_problem(3, 12, 2, 1, seed=seed)
    h: HasProblem = Holder(p)
    assert as_problem(h) is p and as_problem(p) is p
    a = solve(h, "greedy", time_limit=None, seed=seed)
    b = solve(p, "greedy", time_limit=None, seed=seed)
    assert a.schedule is not None and b.schedule is not None
    assert a.objective == b.objective
    assert validate(h, a.schedule) == validate(p, b.schedule) == a.objective


@pytest.mark.parametrize("bad", [None, 3, "problem", Holder(None)])  # type: ignore[arg-type]
def test_anything_else_is_refused_naming_the_call(bad: object) -> None:
    with pytest.raises(UsageError, match=r"^solve: expected a scheduler\.Problem"):
        solve(bad, "greedy", time_limit=None)  # type: ignore[arg-type]
    p = random_problem(2, 4, 1, 1, seed=0)
    s = solve(p, "greedy", time_limit=None).schedule
    assert s is not None
    with pytest.raises(UsageError, match=r"^validate: expected a scheduler\.Problem"):
        validate(bad, s)  # type: ignore[arg-type]
