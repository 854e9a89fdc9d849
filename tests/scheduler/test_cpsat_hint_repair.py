"""The CP-SAT model's hint, repaired where the model rounds (scheduler.cpsat.repair_hint).

Rounded outwards to a unit that does not divide the data, a valid schedule is
usually no solution of the general model (windows that touch overlap by a unit
or two), so CP-SAT started from nothing and found no schedule of a compiled
cell in 10 s. ``repair_hint`` re-times the hint in the model's units with its
modes and orders; these tests check that its values are a solution of the
model, on a compiled cell and on seeded generated problems at units that round.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from ortools.sat.python import cp_model

from scheduler import Schedule, validate
from scheduler.cpsat import _longest_paths, _schedule_of, build_model, repair_hint, solve_cpsat
from scheduler.generate import random_problem
from scheduler.problem import Problem
from scheduler.schedule import ScheduleError
from scheduler.start import begin


def _greedy(p: Problem) -> Schedule:
    st = begin(p, "cpsat", 0, waits=True)
    assert st.first is not None
    return st.ev.schedule(st.first)


def _fixed(mdl: Any, values: dict[int, int] | list[int]) -> str:
    """CP-SAT's status for the model with every listed variable fixed to its value."""
    m = mdl.clone()
    m.clear_hints()
    items = values.items() if isinstance(values, dict) else enumerate(values)
    for i, val in items:
        m.add(m.get_int_var_from_proto_index(i) == val)
    s = cp_model.CpSolver()
    s.parameters.num_workers = 1
    s.parameters.max_time_in_seconds = 20
    return str(s.status_name(s.solve(m)))


def _hint_values(mdl: Any, v: dict[str, Any], p: Problem, hint: Schedule) -> dict[int, int]:
    """The plain hint (starts, modes, delay points rounded to the nearest unit)."""
    scale = v["scale"]
    out: dict[int, int] = {}
    for t in range(p.n_tasks):
        mh = int(hint.mode[t])
        st = float(hint.start[t])
        out[v["S"][t].index] = round(st * scale)
        for m in p.task_modes[t]:
            out[v["X"][m].index] = int(m == mh)
        cw = np.concatenate([[0.0], np.cumsum(hint.waits[t])])
        for i, var in v["P"][mh].items():
            if i:
                out[var.index] = round((st + float(cw[i])) * scale)
    return out


@pytest.fixture(scope="module")
def supersigma() -> Problem:
    from workcell import compile_cell, load_example

    return compile_cell(load_example("supersigma")).problem


def test_the_plain_hint_is_no_solution_and_the_repaired_one_is(supersigma: Problem) -> None:
    """The finding, on a compiled cell: the greedy schedule rounded to 1 ms
    violates the model; the repaired values are a complete solution of it whose
    schedule is valid, with the hint's modes."""
    p = supersigma
    hint = _greedy(p)
    mdl, v = build_model(p, hint.makespan, waits=True)
    assert not v["exact"] and v["scale"] == 1000.0
    assert _fixed(mdl, _hint_values(mdl, v, p, hint)) == "INFEASIBLE"
    sol = repair_hint(mdl, p, v, hint, 10.0)
    assert sol is not None and len(sol) == len(mdl.proto.variables)
    assert _fixed(mdl, sol) in ("OPTIMAL", "FEASIBLE")
    s = _schedule_of(p, lambda x: int(sol[x.index]), v, None)
    assert (s.mode == hint.mode).all()
    mk = validate(p, s)
    # outward rounding costs a unit or two per window touched, never a second
    assert hint.makespan - 1.0 < mk < hint.makespan + 1.0


@pytest.mark.parametrize("seed", range(8))
def test_repaired_hint_is_a_solution_at_units_that_round(seed: int) -> None:
    """Seeded campaign: generated problems (arms, zones, tools, setups and start
    zones varying with the seed) at a unit that does not divide their data; the
    repair's values are a solution of the model, and ``solve_cpsat`` hints
    them and returns a valid schedule no longer than the model's rounding
    allows over the greedy one."""
    rng = np.random.default_rng(seed)
    p = random_problem(
        int(rng.integers(2, 4)),
        int(rng.integers(5, 11)),
        int(rng.integers(1, 4)),
        int(rng.integers(0, 2)),
        seed=seed,
        setups=bool(seed % 2),
        start_zones=bool(seed % 3 == 0),
        zone_fraction=1.0,
    )
    unit = (0.3, 0.7, 0.45)[seed % 3]
    hint = _greedy(p)
    mdl, v = build_model(p, hint.makespan, waits=True, unit=unit)
    assert not v["exact"]
    sol = repair_hint(mdl, p, v, hint, 10.0)
    assert sol is not None
    assert _fixed(mdl, sol) in ("OPTIMAL", "FEASIBLE")
    r = solve_cpsat(p, None, seed, workers=1, unit=unit, max_deterministic_time=2.0)
    assert r.stats.extra["hint_repaired"] is True
    assert r.schedule is not None
    validate(p, r.schedule)


def test_an_exact_unit_keeps_the_plain_hint() -> None:
    """Integral data (an exact unit): the hint is already a solution; no repair."""
    p = random_problem(2, 6, 1, 0, seed=3)
    r = solve_cpsat(p, None, 0, workers=1, max_deterministic_time=2.0)
    assert "hint_repaired" not in r.stats.extra and r.schedule is not None


def test_longest_paths() -> None:
    # a chain with a shortcut, the lower bounds kept
    assert _longest_paths(4, [(0, 1, 2), (1, 2, 3), (0, 2, 1), (3, 2, 0)], [1, 0, 0, 9]) == [
        1,
        3,
        9,
        9,
    ]
    # a cycle of length 0 is fine (label-correcting), a positive one is not
    assert _longest_paths(3, [(0, 1, 2), (1, 0, -2), (1, 2, 1)], [0, 0, 0]) == [0, 2, 3]
    assert _longest_paths(2, [(0, 1, 1), (1, 0, 0)], [0, 0]) is None
    assert _longest_paths(0, [], []) == []


def test_the_result_is_never_longer_than_a_valid_hint(supersigma: Problem) -> None:
    """A plan hinted at a coarse unit: re-timed outwards it is 13 s longer
    (132.4 s -> 145.2 s at 0.1 s), and that was what CP-SAT returned; now the
    plan itself is the result when nothing shorter is found. An invalid hint
    is only a hint (CP-SAT's own schedule is returned)."""
    from scheduler import solve

    p = supersigma
    plan = solve(p, "tree", time_limit=None, seed=0, max_evaluations=2000).schedule
    assert plan is not None
    for unit in (0.1, 0.5):
        r = solve_cpsat(p, None, 0, workers=1, hint=plan, unit=unit, max_deterministic_time=0.5)
        assert r.stats.extra["from_hint"] is True and r.schedule is plan
        assert r.objective == validate(p, plan) and r.stats.improvements == [(0.0, r.objective)]
        assert r.bound <= r.objective
    late = Schedule(plan.mode, plan.start - 1.0, plan.end - 1.0, plan.waits, plan.blocking)
    with pytest.raises(ScheduleError):  # before the releases and the arms' arrival
        validate(p, late)
    r = solve_cpsat(p, None, 0, workers=1, hint=late, unit=0.5, max_deterministic_time=0.5)
    assert r.schedule is not None and r.schedule is not late
    assert r.objective == validate(p, r.schedule) > validate(p, plan)
