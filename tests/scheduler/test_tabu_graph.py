"""The compiled graph tabu search of pure FJSPs (scheduler.tabu.graph_tabu, kernel._tabu_jit).

Checked against references: the graph's longest path against the exact
sequence decoder (seq_decode), the exact k-insertion makespans against
brute force (apply each move, decode again), the compiled search against
the same functions run as plain Python, and determinism under work limits.
These are the S2.10-S2.11 search of the scheduler on the FJSP special case
(no zones: S2.12's waits never arise).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from scheduler import Model, parse_fjsp, read_fjsp, solve, validate
from scheduler.generate import random_problem
from scheduler.kernel._tabu_jit import SearchArrays, graph_makespan, tabu_run
from scheduler.search import Evaluator, Solution, priority_order
from scheduler.tabu import (
    GRAPH_CONFIGS,
    GraphConfig,
    _Graph,
    _sequences,
    graph_tabu,
    pure_fjsp,
    tabu_search,
)
from scheduler.tree import TreeOptions, solve_tree
from tests.scheduler.tabu_brute import assert_insertions_exact

SHARED = Path(os.environ.get("MULTIARM_SHARED", Path(__file__).resolve().parents[3] / "shared"))
DATA = SHARED / "data" / "fjsp"
MK01 = DATA / "brandimarte" / "mk01.fjs"


def random_fjsp(seed: int, jobs: int = 5, machines: int = 4, ops: int = 4) -> str:
    """FJSPLIB text of a random instance (1..machines capable machines per operation)."""
    rng = np.random.default_rng(seed)
    lines = [f"{jobs} {machines} 2"]
    for _ in range(jobs):
        n = int(rng.integers(1, ops + 1))
        parts = [str(n)]
        for _ in range(n):
            ms = rng.choice(machines, size=int(rng.integers(1, machines + 1)), replace=False)
            parts.append(str(len(ms)))
            for m in ms:
                parts += [str(int(m) + 1), str(int(rng.integers(1, 20)))]
        lines.append(" ".join(parts))
    return "\n".join(lines) + "\n"


def _state(ev: Evaluator, seed: int):  # type: ignore[no-untyped-def]
    """A decoded solution from a noisy priority list."""
    rng = np.random.default_rng(seed)
    sol = ev.evaluate(priority_order(ev.problem, rng=rng, noise=0.5))
    assert sol is not None
    return sol


def _arrays(ev: Evaluator, sol):  # type: ignore[no-untyped-def]
    p = ev.problem
    g = _Graph(ev)
    seq, seq_n = _sequences(p, sol.state, np.arange(p.n_tasks))
    return g, g.choice_of(sol.state.t_mode), seq, seq_n


@pytest.mark.parametrize("seed", range(6))
def test_graph_makespan_is_the_decoders(seed: int) -> None:
    p = parse_fjsp(random_fjsp(seed, jobs=6))
    ev = Evaluator(p)
    sol = _state(ev, seed)
    g, choice, seq, seq_n = _arrays(ev, sol)
    assert g.makespan(choice, seq, seq_n) == pytest.approx(sol.makespan)


def test_graph_makespan_reports_a_cycle() -> None:
    p = parse_fjsp("2 1 1\n2 1 1 3 1 1 4\n1 1 1 2\n")  # J1: O1 -> O2, one machine
    g = _Graph(Evaluator(p))
    seq = np.array([[1, 0, 2]], dtype=np.int64)  # O2 before O1 on the machine
    assert g.makespan(np.zeros(3, dtype=np.int64), seq, np.array([3])) == -1.0


@pytest.mark.parametrize("fast", [False, True])
@pytest.mark.parametrize("seed", range(5))
def test_insertion_makespans_are_exact(seed: int, fast: bool) -> None:
    """Every candidate of the k-insertion neighbourhood, applied and decoded by
    seq_decode, has the makespan the search computed; and every acyclic
    insertion of a critical task is a candidate."""
    p = parse_fjsp(random_fjsp(seed + 10, jobs=5, machines=3))
    ev = Evaluator(p)
    sol = _state(ev, seed)
    g, choice, seq, seq_n = _arrays(ev, sol)
    assert_insertions_exact(ev, g, choice, seq, seq_n, fast)


def _run(fn, ev: Evaluator, sol, cfg: GraphConfig, iters: int):  # type: ignore[no-untyped-def]
    g, choice, seq, seq_n = _arrays(ev, sol)
    T = ev.problem.n_tasks
    b = (choice.copy(), seq.copy(), seq_n.copy())
    tabu = np.zeros((T, T + ev.problem.n_arms + 1), dtype=np.int64)
    rs = np.array([12345], dtype=np.uint64)
    ctl = np.zeros(3, dtype=np.int64)
    fctl = np.array([sol.makespan, sol.makespan, 0.0])
    state = SearchArrays(choice, seq, seq_n, *b, tabu, rs, ctl, fctl)
    done = fn(
        g.arrays, state,
        iters, cfg.tenure, cfg.tenure_span, 50, 3, cfg.style, cfg.rank, cfg.top,
    )  # fmt: skip
    return done, choice, seq, seq_n, b, tabu, rs, ctl, fctl


@pytest.mark.parametrize("cfg", GRAPH_CONFIGS)
def test_compiled_search_equals_plain_python(cfg: GraphConfig) -> None:
    p = parse_fjsp(random_fjsp(3, jobs=6, machines=4))
    ev = Evaluator(p)
    sol = _state(ev, 0)
    a = _run(tabu_run, ev, sol, cfg, 120)
    b = _run(getattr(tabu_run, "py_func", tabu_run), ev, sol, cfg, 120)
    assert a[0] == b[0] == 120
    for x, y in zip(a[1:], b[1:], strict=True):
        if isinstance(x, tuple):
            for u, w in zip(x, y, strict=True):
                np.testing.assert_array_equal(u, w)
        else:
            np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("cfg", GRAPH_CONFIGS)
def test_every_configuration_improves_and_stays_exact(cfg: GraphConfig) -> None:
    p = read_fjsp(DATA / "brandimarte" / "mk01.fjs")
    ev = Evaluator(p)
    sol = ev.evaluate(priority_order(p))
    assert sol is not None
    best = graph_tabu(
        ev, sol, np.inf, np.random.default_rng(0), max_evaluations=1500, configs=(cfg,)
    )
    assert best.makespan < sol.makespan
    assert validate(p, ev.schedule(best)) == best.makespan


def _note(seen: list[float], s: Solution) -> None:
    seen.append(s.makespan)


def test_same_seed_same_schedule_different_seed_other_search() -> None:
    p = read_fjsp(DATA / "brandimarte" / "mk06.fjs")
    runs = []
    for seed in (0, 0, 1):
        ev = Evaluator(p)
        sol = ev.evaluate(priority_order(p))
        assert sol is not None
        seen: list[float] = []
        best = graph_tabu(
            ev,
            sol,
            np.inf,
            np.random.default_rng(seed),
            max_evaluations=800,
            on_improve=partial(_note, seen),
        )
        assert seen and seen[-1] == best.makespan and seen == sorted(seen, reverse=True)
        # the improvement log is reported once per chunk of iterations, and chunks
        # grow with the wall clock (cheap iterations): its granularity is not part
        # of the seed's promise, the search and its result are
        runs.append((best.makespan, ev.schedule(best).start.tolist()))
    assert runs[0] == runs[1]
    assert runs[0][1] != runs[2][1]


def test_tree_on_fjsp_is_repeatable_and_valid() -> None:
    p = read_fjsp(DATA / "fattahi" / "mfjs05.fjs")
    opts = TreeOptions(max_evaluations=3000)
    a = solve_tree(p, None, 3, options=opts)
    b = solve_tree(p, None, 3, options=opts)
    assert a.schedule is not None and b.schedule is not None
    assert validate(p, a.schedule) == a.objective
    np.testing.assert_array_equal(a.schedule.start, b.schedule.start)
    np.testing.assert_array_equal(a.schedule.mode, b.schedule.mode)
    assert a.objective == 514.0  # the best-known (optimal) makespan


def test_solve_with_work_limit_reaches_the_known_optimum() -> None:
    p = read_fjsp(DATA / "brandimarte" / "mk01.fjs")
    r = solve(p, "tree", seed=0, max_evaluations=20000)
    assert r.schedule is not None
    assert validate(p, r.schedule) == r.objective == 40.0


def test_pure_fjsp_is_recognised() -> None:
    assert pure_fjsp(Evaluator(parse_fjsp(random_fjsp(0))))
    zoned = random_problem(3, 10, 2, 1, seed=0)
    assert zoned.n_windows > 0
    assert not pure_fjsp(Evaluator(zoned))
    m = Model("released")
    m.add_arm("a")
    m.add_arm("b", available=5.0)
    m.add_task("x", release=3.0)
    m.add_task("y")
    m.add_predecessors("y", ["x"])
    m.add_mode("x", "a", 2.0)
    m.add_mode("x", "b", 1.0)
    m.add_mode("y", "a", 4.0)
    p = m.build()
    ev = Evaluator(p)
    assert pure_fjsp(ev)
    sol = ev.evaluate(np.array([0, 1]))
    assert sol is not None
    # releases and arm availability are heads of the graph: the decoder's makespan
    best = tabu_search(ev, sol, np.inf, np.random.default_rng(0), max_evaluations=50)
    assert validate(p, ev.schedule(best)) == best.makespan == 9.0
    assert not pure_fjsp(Evaluator(p, frozen=frozenset({0})))


def test_allowed_modes_are_respected() -> None:
    p = parse_fjsp(random_fjsp(5, jobs=6, machines=3))
    allowed = np.ones(p.n_modes, dtype=bool)
    dropped = [ms[0] for ms in p.task_modes if len(ms) > 1]
    allowed[dropped] = False
    ev = Evaluator(p, allowed=allowed)
    sol = ev.evaluate(priority_order(p))
    assert sol is not None and allowed[sol.modes].all()
    best = graph_tabu(ev, sol, np.inf, np.random.default_rng(1), max_evaluations=500)
    assert allowed[best.modes].all()
    assert validate(p, ev.schedule(best)) == best.makespan


def test_graph_makespan_reference_in_numpy() -> None:
    """The compiled longest path against a plain numpy/Python one."""
    p = parse_fjsp(random_fjsp(9, jobs=7, machines=4))
    ev = Evaluator(p)
    sol = _state(ev, 2)
    g, choice, seq, seq_n = _arrays(ev, sol)
    idx = g.tm_ptr[:-1] + choice
    dur = g.tm_dur[idx]
    head = np.zeros(p.n_tasks)
    for t in sorted(range(p.n_tasks), key=lambda t: sol.state.t_start[t]):
        a = int(g.tm_arm[idx[t]])
        prev = [int(x) for x in seq[a, : seq_n[a]]]
        i = prev.index(t)
        cands = [0.0] + [head[q] + dur[q] for q in p.task_preds[t]]
        if i > 0:
            cands.append(head[prev[i - 1]] + dur[prev[i - 1]])
        head[t] = max(cands)
    ref = float((head + dur).max())
    assert graph_makespan(g.arrays, g.tm_arm[idx], dur, seq, seq_n) == pytest.approx(ref)


def test_fjsp_up_to_portfolio_size_races_cpsat_for_the_proof() -> None:
    """mfjs05 (21 tasks): within TreeOptions.portfolio_fjsp_max_tasks, CP-SAT runs
    beside the graph search and proves the optimum (514), which ends the solve."""
    p = read_fjsp(DATA / "fattahi" / "mfjs05.fjs")
    r = solve_tree(p, 30.0, 0)
    assert r.stats.extra["portfolio"] == "optimal"
    assert r.status.value == "optimal" and r.objective == 514.0
    assert r.schedule is not None and validate(p, r.schedule) == 514.0
    r = solve_tree(p, 1.0, 0, options=TreeOptions(portfolio_fjsp_max_tasks=20))
    assert "portfolio" not in r.stats.extra


def test_the_search_does_not_depend_on_how_it_is_chunked() -> None:
    """Chunks grow with the machine's speed; the course of the search must not."""
    p = read_fjsp(DATA / "brandimarte" / "mk06.fjs")
    got = set()
    for chunk in (1, 5, 4096):
        ev = Evaluator(p)
        sol = ev.evaluate(priority_order(p))
        assert sol is not None
        best = graph_tabu(
            ev, sol, np.inf, np.random.default_rng(5), max_evaluations=3500, chunk=chunk
        )
        got.add((best.makespan, ev.schedule(best).start.tobytes(), ev.evaluations))
    assert len(got) == 1


_SCRIPT = """
import json, sys
import numpy as np
from scheduler import read_fjsp
from scheduler.kernel import jit_enabled
from scheduler.search import Evaluator, priority_order
from scheduler.tabu import graph_tabu
p = read_fjsp(sys.argv[1])
ev = Evaluator(p)
sol = ev.evaluate(priority_order(p))
best = graph_tabu(ev, sol, np.inf, np.random.default_rng(5), max_evaluations=150)
print(json.dumps([jit_enabled(), best.makespan, ev.schedule(best).start.tolist()]))
"""


def test_compiled_and_plain_python_runs_agree() -> None:
    """MULTIARM_NO_JIT=1 runs the same search as plain Python: the same schedule."""
    out = []
    for extra in ({}, {"MULTIARM_NO_JIT": "1"}):
        proc = subprocess.run(
            [sys.executable, "-W", "error::RuntimeWarning", "-c", _SCRIPT, str(MK01)],
            cwd=Path(__file__).resolve().parents[2],
            env={**os.environ, **extra},
            capture_output=True,
            text=True,
            check=True,
            timeout=600,
        )
        out.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    assert out[0][0] and not out[1][0]
    assert out[0][1:] == out[1][1:]
