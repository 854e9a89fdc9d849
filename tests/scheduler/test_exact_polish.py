"""The tree's exact polish (TreeOptions.exact_polish_share): its rule, the phase, and solve_tree.

On problems the CP-SAT race and polish leave alone (a blocking oracle or many
windows: the compiled cells) the last share of a wall-clock budget goes to
:func:`scheduler.exact.prove` from the tree's best schedule. Checked here:
when it runs and when not (work limits stay repeatable), that it keeps the
better schedule and a valid bound, and that a result with it validates.
The measured effect (``scara4`` and its tuning family) is in
docs/scheduler.md ("Solvers: options").
"""

from __future__ import annotations

import math
import time

import pytest

from multiarm.errors import UsageError
from scheduler import validate
from scheduler.fjsp import parse_fjsp
from scheduler.generate import generate_problem
from scheduler.result import SearchStats
from scheduler.search import Evaluator
from scheduler.start import begin
from scheduler.tree import TreeOptions, _exact_polish, _exact_polish_problem, solve_tree

# the race and the CP-SAT polish need at most this many windows: 5 keeps them off,
# as a compiled cell's thousands of windows do
NO_CPSAT = {"portfolio_max_windows": 5}


def test_the_rule_follows_the_problem_and_the_options() -> None:
    """The exact polish runs on a problem the race leaves alone, of more than
    exact_max_tasks and at most exact_polish_max_tasks tasks, with a wall-clock
    limit whose share reaches polish_min_time; never on a work limit, a pure FJSP,
    a problem the race takes, or with a share of 0."""
    p = generate_problem("routes", 3, 20, 3, 1, seed=1)
    ev = Evaluator(p)
    opt = TreeOptions(**NO_CPSAT)
    assert _exact_polish_problem(p, ev, 10.0, opt) is p
    assert _exact_polish_problem(p, ev, None, opt) is None
    assert _exact_polish_problem(p, ev, 10.0, TreeOptions(**NO_CPSAT, max_evaluations=100)) is None
    assert (
        _exact_polish_problem(p, ev, 10.0, TreeOptions(**NO_CPSAT, exact_polish_share=0.0)) is None
    )
    assert _exact_polish_problem(p, ev, 6.0, opt) is None  # 0.3 * 6 s < polish_min_time
    assert _exact_polish_problem(p, ev, 10.0, TreeOptions()) is None  # the race takes it
    assert _exact_polish_problem(p, ev, 10.0, TreeOptions(**NO_CPSAT, exact_max_tasks=20)) is None
    assert _exact_polish_problem(p, ev, 10.0, TreeOptions(**NO_CPSAT, exact_max_tasks=19)) is p
    assert (
        _exact_polish_problem(p, ev, 10.0, TreeOptions(**NO_CPSAT, exact_polish_max_tasks=19))
        is None
    )
    assert (
        _exact_polish_problem(p, ev, 10.0, TreeOptions(**NO_CPSAT, exact_polish_max_tasks=20)) is p
    )
    f = generate_problem("setup_fjsp", 4, 20, 0, 0, seed=0, setup_fraction=0.0)
    assert f.n_tasks == 20 and _exact_polish_problem(f, Evaluator(f), 10.0, opt) is None
    small = parse_fjsp("2 2\n2 1 1 3 1 2 2\n1 2 1 1 2 2\n")
    assert _exact_polish_problem(small, Evaluator(small), 10.0, opt) is None  # 3 tasks


@pytest.mark.parametrize("name", ["exact_polish_share"])
@pytest.mark.parametrize(
    "bad", [-0.1, 1.0, "0.3", None, True], ids=["neg", "one", "str", "none", "bool"]
)
def test_the_share_is_validated(name: str, bad: object) -> None:
    with pytest.raises(UsageError, match=name):
        TreeOptions(**{name: bad})  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [-1, 2.5, True, "10"], ids=["negative", "float", "bool", "str"])
def test_the_size_rule_is_validated(bad: object) -> None:
    with pytest.raises(UsageError, match="exact_polish_max_tasks"):
        TreeOptions(exact_polish_max_tasks=bad)  # type: ignore[arg-type]


def test_the_phase_keeps_the_better_schedule_and_a_valid_bound() -> None:
    """From the HEFT schedule of a 14-task routes problem the exact search finds a
    shorter schedule and proves it optimal (as CP-SAT does); the result is a
    Solution whose schedule validates, and the bound never exceeds it. From the
    optimum given as a worker's schedule, it keeps that schedule."""
    from scheduler.cpsat import solve_cpsat

    p = generate_problem("routes", 2, 14, 2, 1, seed=1)
    ref = solve_cpsat(p, 20.0, 0, workers=1)
    assert ref.status.value == "optimal"
    st = begin(p, "tree", 0)
    heft = st.first
    assert heft is not None and heft.makespan > ref.objective + 1e-6
    stats = SearchStats()
    t0 = time.perf_counter()
    best, lb, proven = _exact_polish(p, st.ev, heft, st.lb, t0 + 60.0, True, stats, t0, None)
    assert proven and best.makespan == pytest.approx(ref.objective, abs=1e-6)
    assert lb <= best.makespan + 1e-9
    assert stats.extra["exact_polish"] == "proven" and stats.phases["exact_polish"] < 60.0
    assert validate(p, stats.extra["exact_schedule"]) == pytest.approx(best.makespan)
    again = SearchStats()
    again.extra["worker_schedule"] = kept = stats.extra["exact_schedule"]
    same, _lb, proven = _exact_polish(p, st.ev, best, st.lb, t0 + 60.0, True, again, t0, None)
    assert same is best and proven and again.extra["worker_schedule"] is kept
    assert "exact_schedule" not in again.extra


def test_solve_tree_runs_it_within_its_rule() -> None:
    """solve_tree hands the end of its budget to the exact polish where the rule
    holds (the phase and its outcome in the stats; the schedule validates), and
    not with the default options on a problem the race takes, nor on a work limit."""
    p = generate_problem("stations", 3, 16, 3, 1, seed=1)
    opt = TreeOptions(**NO_CPSAT, exact_polish_share=0.5, polish_min_time=0.5)
    on = solve_tree(p, 1.5, 0, options=opt)
    assert on.schedule is not None and validate(p, on.schedule) == pytest.approx(on.objective)
    # far from its bound (98 against 119 or so): neither proven nor done before the phase
    assert "exact_polish" in on.stats.phases
    assert on.stats.extra.get("exact_polish") in ("proven", "time", "nodes")
    assert on.bound <= on.objective + 1e-9
    assert "exact_polish" not in solve_tree(p, 1.5, 0).stats.phases
    worked = solve_tree(p, None, 0, options=TreeOptions(**NO_CPSAT, max_evaluations=300))
    assert "exact_polish" not in worked.stats.phases and math.isfinite(worked.objective)
