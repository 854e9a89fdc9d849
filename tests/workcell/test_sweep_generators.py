"""Sweep files name the generator of their generated problems and may solve them without waits."""

from __future__ import annotations

import pytest

from multiarm.errors import MultiarmError
from scheduler import solve, validate
from scheduler.generate import random_line_problem, random_setup_fjsp
from workcell.experiments.instances import build_problem
from workcell.experiments.runner import run_one
from workcell.experiments.spec import parse_sweep

SWEEP = """
[sweep]
name = "g"

[[instances]]
kind = "generated"
generator = "{gen}"
sizes = [[{size}]]
seeds = [3]
{extra}

[[solvers]]
solver = "greedy"
time_limit = 5.0
"""


def test_setup_fjsp_and_line_instances_are_their_generators_problems() -> None:
    s = parse_sweep(SWEEP.format(gen="setup_fjsp", size="3, 9, 0, 0", extra="setup_fraction = 1.0"))
    p = build_problem(s.instances[0])
    assert p.to_dict() == random_setup_fjsp(3, 9, seed=3, setup_fraction=1.0).to_dict()
    s = parse_sweep(SWEEP.format(gen="line", size="2, 7, 2, 1", extra="stay_fraction = 1.0"))
    p = build_problem(s.instances[0])
    assert p.to_dict() == random_line_problem(2, 7, 2, 1, seed=3, stay_fraction=1.0).to_dict()


def test_waits_false_reaches_every_solver_and_names_the_instance() -> None:
    s = parse_sweep(SWEEP.format(gen="line", size="3, 10, 3, 1", extra="waits = false"))
    inst = s.instances[0]
    assert inst.name == "3x10x3x1-nowait-s3"
    row = run_one(s.runs()[0])
    p = random_line_problem(3, 10, 3, 1, seed=3)
    r = solve(p, "greedy", time_limit=5.0, seed=0, waits=False)
    assert row["makespan"] == validate(p, r.schedule)
    assert sum(w.sum() for w in r.schedule.waits) == 0.0


@pytest.mark.parametrize(
    ("gen", "extra", "message"),
    [
        ("nope", "", "generator: expected one of 'zones', 'line', 'setup_fjsp'"),
        ("line", "waits = 1", "waits: expected a bool"),
    ],
)
def test_bad_generator_fields_are_named(gen: str, extra: str, message: str) -> None:
    with pytest.raises(MultiarmError, match=message):
        parse_sweep(SWEEP.format(gen=gen, size="2, 6, 1, 0", extra=extra))
