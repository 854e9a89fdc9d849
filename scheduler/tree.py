"""The tree search (default solver): beam, bounds, dominance, anytime, local search.

The search tree's nodes are partial schedules; a child places one more ready
task (all its predecessors placed) in one of its modes, at the earliest time
the placement kernel finds — zone conflicts are resolved there and then by
waiting at zone borders or delaying the task (S2.12: the waiting a window
conflict forces is computed while the schedule is generated). Each child is
scored by a valid lower bound on any completion of it::

    max(makespan so far, end of the new task + its tail,
        max over ready tasks r of earliest(r) + bottom level(r))

with ties broken by the waiting and detour time it causes (an assignment that
meets no resource or collision conflict is preferred), then by its end.

One *pass* is a beam search of width ``w`` down to complete schedules:

* **branch and bound**: children whose bound reaches the incumbent are cut;
* **dominance**: among children with the same set of placed tasks, one
  whose per-arm finish times and makespan are all no better than another's
  is dropped (and exact duplicates are merged);
* the ``w`` best survive to the next level.

Anytime: passes with widths 1, 2, 4, ... alternate with improvement of the
best schedule until the time limit — a tabu search on the arms' task
sequences (:mod:`scheduler.tabu`; on a pure FJSP its compiled search on the
disjunctive graph, which then keeps all the time after the first beam pass),
or, with a blocking oracle, an iterated
local search on the list (:func:`scheduler.search.local_search`). On small problems (:mod:`scheduler.exact`)
the search finishes with an exact branch and bound that proves optimality;
where it cannot (a binding blocking oracle, an arm starting inside an
exclusive zone), a plan that no schedule of the problem without zones beats
is proven optimal (``TreeOptions.zone_free_share``, S2.6's parking scene).
A schedule whose makespan meets the global lower bound is optimal at once.

On problems with few enough windows (and, with setup times or as a pure
FJSP, few enough tasks), the last share of a wall-clock budget
(``TreeOptions.polish_share``) goes to the *polish*: CP-SAT on both workers,
hinted with the tree's best schedule, whose schedule is kept only when it is
shorter.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from multiarm.errors import UsageError
from multiarm.types import FloatArray, IntArray
from scheduler import _ctrl_c, exact
from scheduler.bounds import heads_and_tails
from scheduler.kernel import State, expand
from scheduler.places import PlaceOptions, place_start, usable_places
from scheduler.problem import Problem
from scheduler.result import Result, SearchStats, SolveStatus
from scheduler.search import Evaluator, Solution, local_search, priority_order
from scheduler.start import begin
from scheduler.tabu import pure_fjsp, tabu_search, warm_up_graph

if TYPE_CHECKING:
    from collections.abc import Callable

    from scheduler.schedule import Schedule

__all__ = ["TreeOptions", "beam_pass", "solve_tree"]


@dataclass(frozen=True)
class TreeOptions:
    """Knobs of the tree search (defaults suit problems up to a few thousand tasks).

    Raises
    ------
    UsageError
        A field out of range (checked at construction).
    """

    max_width: int = 64
    """Widest beam tried."""
    beam_share: float = 0.1
    """Share of the remaining time a beam pass may take."""
    improve_share: float = 0.5
    """Share of the remaining time an improvement slice takes while beams remain."""
    exact_max_tasks: int = 12
    """Run the exact branch and bound on problems this small."""
    restart_noise: float = 0.3
    """Relative noise on priorities for randomized restarts."""
    max_evaluations: int | None = None
    """A work limit (decoded schedules): with it, and no time limit, the
    result depends on the seed only. A wall-clock limit stops wherever the
    machine got to."""
    local_evaluations: int = 2000
    """Decodes per local-search slice when running on a work limit."""
    exact_max_nodes: int | None = None
    """Node budget of the exact phase (default: none without a time limit,
    ``100 * max_evaluations`` with a work limit)."""
    workers: int = field(default_factory=lambda: min(2, os.cpu_count() or 1))
    """Processes searching at once (like CP-SAT's workers): the others run
    independent improvement from other seeds in forked processes (the first
    of them, on a zone problem, with the list local search, the neighbourhood
    the main process does not use there), and the best schedule wins. Used only with a wall-clock limit of at least
    ``parallel_min_time``, where ``fork`` exists (Linux) and the caller is
    not a daemon process (a daemon, e.g. a Dask worker, searches alone and
    says so in ``stats.extra["workers"]``); work-limited runs
    stay in one process, so they remain exactly repeatable. Where the exact
    phase proves a compiled cell (an idle oracle dropped), no worker process
    runs beside it: the proof takes the ``workers`` processes
    (:func:`scheduler.exact.prove`'s ``workers``)."""
    parallel_min_time: float = 1.0
    relaxed_workers: bool = True
    """On a problem with a blocking oracle, the worker processes search the
    problem without it, and each plan they return is checked against the
    oracle: kept where no parked arm is in its way, else its modes and start
    order are decoded again with the detours. The main process keeps the
    oracle, so the plan returned stays valid. Measured at 10 s
    (docs/scheduler.md, "Solvers"; nothing tuned): ``cell8`` seeds 0-2
    651.28, 641.00, 658.14 s without it, 600.70, 622.30, 615.56 s with it
    (every worker plan valid with the oracle); the other built-in cells
    unchanged; better or equal on 6 of 6 generated problems whose oracle
    binds. From its sweep (``benchmarks/results/relaxed.md``, seeds 0-2):
    lower on 10 of 15 runs on ``cell8`` and four generated problems with a
    binding oracle, higher on none. False: the workers search with the
    oracle, as the main process."""
    portfolio_max_tasks: int = 40
    """Race CP-SAT (one worker, in a thread) against the tree search on
    problems with at most this many tasks, when the run has a wall-clock
    limit and no work limit: the better schedule wins, CP-SAT's proof of
    optimality ends the tree search at once, and so does a bound CP-SAT
    proves that the tree's schedule meets (0: never). Tuned on the
    ``routes`` family (:mod:`scheduler.families`,
    ``benchmarks/sweeps/outside_tune.toml``): up to 40 tasks the race ended
    ahead of a second tree process on 5 of 12 problems and behind on 3 (by
    1-2 time units), and proved the 2 optima CP-SAT proves within a second
    (the second tree process proved none); from 50 tasks on it was behind
    on 6 of 12 and ahead on 2. The two rules below narrow it."""
    portfolio_fjsp_max_tasks: int = 40
    """The same size rule on a pure FJSP (no zones or tools; setups only where
    the graph search reads them, :func:`scheduler.tabu.graph_setup`), where the
    graph tabu search runs beside CP-SAT: there CP-SAT proves the optimum of
    the Fattahi instances up to 36 tasks within about a second."""
    portfolio_setup_max_tasks: int = 16
    """The size rule instead of ``portfolio_max_tasks`` on a problem with
    setup times (not a pure FJSP): CP-SAT's circuits over each arm's tasks
    take seconds to build from 40 tasks on, and on the zone problems of
    :func:`scheduler.generate.random_problem` (travel setups,
    ``benchmarks/results/generated.md``) CP-SAT at 10 s is behind the tree
    from 20 tasks on."""
    portfolio_max_windows: int = 1000
    """The race also needs at most this many zone windows (not on a pure
    FJSP): the compiled cells carry 1,578-2,329 windows, and there CP-SAT
    finds no schedule in 10 s, so the second core is better spent on a
    second tree process."""
    polish_share: float = 0.6
    """Share of a wall-clock budget kept for the polish, at its end: CP-SAT
    (on ``workers`` threads) hinted with the tree's best schedule, whose
    schedule replaces the tree's only when it is shorter (0: never). A pure
    FJSP gets it only up to ``polish_fjsp_max_tasks`` tasks (on larger ones
    the graph tabu search does as well or better alone), a problem with
    setup times only up to ``polish_setup_max_tasks`` tasks (CP-SAT's setup
    circuits take seconds to build on larger ones); never a problem with a
    blocking oracle or more than ``portfolio_max_windows`` windows; and only
    with no work limit and a polish of at least ``polish_min_time`` seconds.
    Tuned on the ``routes``
    family with seeds 2-3 (``benchmarks/sweeps/polish_tune.toml``, 24
    problems at 10 s): behind CP-SAT alone on 13 without the polish, on 10,
    7 and 6 with shares 0.4, 0.6 and 0.8, mean makespan -0.46, -0.82 and
    -0.80 %; 0.6 and 0.8 tie on the mean, and 0.6 keeps more time for the
    tree's own search where CP-SAT is weak. The tables use seeds 0-1; the
    check on a family it was not tuned on is ``benchmarks/results/polish.md``
    (docs/scheduler.md, "Solvers: options"). Re-tuned after the CP-SAT fix
    (``benchmarks/sweeps/polish_retune.toml``): 0.7 was behind CP-SAT on 4
    of the 24 against 6 at 0.6 (mean -0.10 %), but on the outside table
    (seeds 0-1) behind on 4 of 48 against 3, and higher from 60 tasks on;
    so it stays 0.6."""
    polish_min_time: float = 2.0
    """The shortest polish worth building CP-SAT's model for (seconds)."""
    polish_fjsp_max_tasks: int = 60
    """The polish also runs on a pure FJSP of at most this many tasks (0: never),
    after the graph tabu search's share. Tuned on random FJSPs without setups
    (:func:`scheduler.generate.random_setup_fjsp` with ``setup_fraction=0``,
    20-150 operations, seeds 0-1; ``benchmarks/sweeps/polish_fjsp_tune.toml``,
    22 problems at 10 s): with the polish at every size the tree was lower
    than without on 6 (60-100 operations), higher on none, and proved 8 more
    optima (50-100 operations); at 150 operations it changed nothing. That
    family pointed to 100, but the check on the published instances
    (``benchmarks/results/fjsp_seeds.md``) lost on Brandimarte's mk07 (100
    operations on 5 machines, where CP-SAT alone is 2-4 % off): 139.8 on
    average over seeds 0-4 without the polish, 141.0 with it. So the rule
    was lowered to 60 after the check (it keeps Fattahi's 15-48 operations
    and mk01-mk02); above 60 operations Brandimarte is no longer an
    untuned check of this knob."""
    polish_setup_max_tasks: int = 40
    """The polish also runs on a problem with setup times of at most this many
    tasks (0: never). Tuned on the ``stations`` problems (travel setups) of
    the outside sizes up to 50 tasks with seeds 2-3 (the outside table uses
    0-1; ``benchmarks/sweeps/polish_setup_tune.toml``, 16 problems at 10 s):
    up to 40 tasks the polish ended lower than the tree without it on 3 (at
    36 and 40 tasks) and higher on none; at 50 tasks higher on 2, lower on
    none (CP-SAT's setup circuits are slow to build there, and CP-SAT alone
    was 8-27 % behind the tree)."""
    exact_polish_share: float = 0.3
    """Share of a wall-clock budget kept, at its end, for the exact branch and
    bound (:func:`scheduler.exact.prove`) started from the tree's best
    schedule, on problems the CP-SAT polish and race leave alone (a blocking
    oracle, more than ``portfolio_max_windows`` windows: the compiled cells),
    larger than ``exact_max_tasks`` and of at most ``exact_polish_max_tasks``
    tasks, where the exact search applies (:func:`scheduler.exact.applicable`,
    an idle oracle dropped first) and never on a pure FJSP (0: never). Its
    first search fixes the incumbent's modes and branches on the pairwise
    orders in the zones, times found by longest paths: it reaches schedules
    the list and sequence decoders cannot give (an arm kept back at a border
    so that another passes first) and keeps the better schedule. Only with
    no work limit and at least ``polish_min_time`` seconds for it. Tuned on
    variants of ``scara4`` (block sides 0.2 and 0.45 m, sampled part
    arrivals with seeds 1-2, 3 and 4 products; seeds 0-1 at 10 s): on the
    20-task ones 0.3 ended lower than without on 4 of 8 (by 0.4-1.3 s),
    higher on 1 (by 0.05 s); 0.5 did the same there and worse on the
    30-40-task ones (docs/scheduler.md, "Solvers: options")."""
    exact_polish_max_tasks: int = 24
    """The largest problem the exact polish runs on (see ``exact_polish_share``;
    0: never). From the same tuning: at 30 tasks 0.3 was higher on average
    than without (one run by 1.6 s) and at 40 within the search's noise of
    1-2 s, so the rule stops between 20 and 30."""
    zone_free_share: float = 0.3
    """At most this share of a wall-clock budget (and ``zone_free_nodes``
    nodes) goes to proving the tree's plans with the problem without zones
    (:func:`scheduler.exact.zone_free`), whose optimum bounds the true one; 0:
    never. Only on problems of at most ``exact_max_tasks`` tasks that the
    exact search cannot prove itself (a binding blocking oracle, an arm
    starting inside an exclusive zone). Each new best plan, between rounds
    of the search (and the last one when a work limit, not the clock, ends
    it), is first decoded without zones (its own list and modes):
    when that, or a short list local search from it, is shorter, the
    relaxation cannot prove it and nothing more is spent; else the exact
    branch and bound looks for a schedule without zones shorter than the
    plan, and where none exists the plan is optimal and the tree stops (the
    ``parking`` cell: at once, where 10 s of search and a racing CP-SAT
    proved nothing). Tuned against 0.1 and 20,000 nodes on
    :func:`scheduler.generate.random_problem` with arms starting in their
    zones (2x10x3x1, 2x12x4x1, 3x12x4x1, seeds 10-13, 10 s): 0.3 proved
    one more plan optimal and ended no higher on any of the 12; the check is
    ``bench_small``'s seeds 0-3 (docs/scheduler.md, "Solvers: options")."""
    zone_free_nodes: int = 1_000_000
    """The node budget of those proofs, all together (deterministic work; see
    ``zone_free_share``); with a work limit at most ``10 * max_evaluations``."""
    fallback: bool = True
    """When no list order decodes, ask CP-SAT (one worker) within the budget
    left (:mod:`scheduler.fallback`)."""
    places: PlaceOptions | None = field(default_factory=PlaceOptions)
    """The place-aware start (:func:`scheduler.places.place_start`), offered
    after the HEFT list where its rule holds (:func:`scheduler.places.usable_places`:
    travel setups, many tasks per place); None: never."""

    def __post_init__(self) -> None:
        if self.places is not None and not isinstance(self.places, PlaceOptions):
            raise UsageError(
                f"TreeOptions.places must be PlaceOptions or None, got {self.places!r}"
            )
        for flag in ("fallback", "relaxed_workers"):
            if not isinstance(getattr(self, flag), bool):
                raise UsageError(
                    f"TreeOptions.{flag} must be True or False, got {getattr(self, flag)!r}"
                )
        ints = {
            "max_width": 1,
            "exact_max_tasks": 0,
            "local_evaluations": 1,
            "workers": 1,
            "portfolio_max_tasks": 0,
            "portfolio_fjsp_max_tasks": 0,
            "portfolio_setup_max_tasks": 0,
            "portfolio_max_windows": 0,
            "polish_fjsp_max_tasks": 0,
            "polish_setup_max_tasks": 0,
            "exact_polish_max_tasks": 0,
            "zone_free_nodes": 0,
        }
        for name, least in ints.items():
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < least:
                raise UsageError(f"TreeOptions.{name} must be an int >= {least}, got {v!r}")
        for name in ("max_evaluations", "exact_max_nodes"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 1):
                raise UsageError(f"TreeOptions.{name} must be an int >= 1 or None, got {v!r}")
        for name in ("polish_share", "exact_polish_share", "zone_free_share"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not (0.0 <= v < 1.0):
                raise UsageError(f"TreeOptions.{name} must be in [0, 1), got {v!r}")
        for name in ("beam_share", "improve_share"):
            v = getattr(self, name)
            if not isinstance(v, int | float) or not (0.0 < v <= 1.0):
                raise UsageError(f"TreeOptions.{name} must be in (0, 1], got {v!r}")
        for name in ("restart_noise", "parallel_min_time", "polish_min_time"):
            v = getattr(self, name)
            if not isinstance(v, int | float) or not (0.0 <= v < math.inf):
                raise UsageError(f"TreeOptions.{name} must be finite and >= 0, got {v!r}")


@dataclass
class _Node:
    state: State
    missing: IntArray
    order: list[int]
    cmax: float
    conflict: float
    arm_end: FloatArray


def _arm_end(st: State, inst, n_arms: int) -> FloatArray:  # type: ignore[no-untyped-def]
    out = np.zeros(n_arms)
    for a in range(n_arms):
        n = int(st.arm_n[a])
        if n:
            out[a] = st.t_end[st.arm_t[inst.arm_lo[a] + n - 1]]
    return out


def beam_pass(
    ev: Evaluator,
    width: int,
    deadline: float,
    incumbent: float,
    rng: np.random.Generator,
    stats: SearchStats,
) -> Solution | None:
    """One beam search of ``width``; returns the best complete solution found
    below ``incumbent`` (None if cut off by time or bounds)."""
    p = ev.problem
    inst = ev.inst
    T = p.n_tasks
    _, mind, tail = heads_and_tails(p)
    bottom = mind + tail
    root = _Node(
        inst.new_state(),
        np.array([len(ps) for ps in p.task_preds], dtype=np.int64),
        [],
        0.0,
        0.0,
        np.zeros(p.n_arms),
    )
    nodes = [root]
    for _depth in range(T):
        if time.perf_counter() > deadline:
            return None
        cands = []  # (bound, conflict, end, tiebreak, node index, t, m, S, k, waits, cost)
        for ni, node in enumerate(nodes):
            stats.nodes += 1
            ready = np.flatnonzero(node.missing == 0)
            if len(ready) == 0:
                continue
            # static part of the bound: every ready task must still run its bottom level
            st = node.state
            est = np.array([inst.earliest(st, int(r), ev.chrono) for r in ready])
            vals = est + bottom[ready]
            order_vals = np.argsort(-vals)
            top1 = vals[order_vals[0]]
            top2 = vals[order_vals[1]] if len(vals) > 1 else 0.0
            ct, cm = [], []
            for r in ready.tolist():
                for m in p.task_modes[r]:
                    ct.append(r)
                    cm.append(m)
            if ev.blocking:
                res = []
                for r, m in zip(ct, cm, strict=True):
                    S, end, k, w, c = ev.place_blocking(st, r, m, inst.earliest(st, r, True))
                    res.append((S, end, k, w, c))
            else:
                S_a, end_a, k_a, _w_a, waits_a = expand(
                    inst, st, np.array(ct), np.array(cm), chrono=ev.chrono, waits=ev.waits
                )
                res = [(S_a[i], end_a[i], k_a[i], waits_a[i], 0.0) for i in range(len(ct))]
            for i, (r, m) in enumerate(zip(ct, cm, strict=True)):
                S, end, k, w, c = res[i]
                if not math.isfinite(end):
                    continue
                rest = top2 if vals[order_vals[0]] == top1 and ready[order_vals[0]] == r else top1
                bound = max(node.cmax, end + tail[r], rest)
                if bound >= incumbent - 1e-9:
                    stats.pruned += 1
                    continue
                conflict = node.conflict + float(np.sum(w)) + c
                cands.append((bound, conflict, end, rng.random(), ni, r, m, S, k, w, c))
        if not cands:
            return None
        cands.sort(key=lambda c: c[:4])
        new_nodes: list[_Node] = []
        groups: dict[bytes, list[_Node]] = {}
        for _bound, conflict, end, _tb, ni, r, m, S, k, w, _c in cands:
            if len(new_nodes) >= width:
                break
            parent = nodes[ni]
            st2 = parent.state.copy()
            inst.commit(st2, r, m, S, end, k, w[: len(p.shapes[m].borders)])
            missing = parent.missing.copy()
            missing[r] = -1
            for s in p.task_succs[r]:
                missing[s] -= 1
            arm_end = parent.arm_end.copy()
            a = int(p.mode_arm[m])
            arm_end[a] = max(arm_end[a], end)
            child = _Node(
                st2, missing, [*parent.order, r], max(parent.cmax, end), conflict, arm_end
            )
            key = (missing < 0).tobytes()
            group = groups.setdefault(key, [])
            dominated = False
            for other in group:
                if (
                    other.cmax <= child.cmax + 1e-9
                    and np.all(other.arm_end <= child.arm_end + 1e-9)
                    and other.conflict <= child.conflict + 1e-9
                ):
                    dominated = True
                    break
            if dominated:
                stats.pruned += 1
                continue
            group.append(child)
            new_nodes.append(child)
        nodes = new_nodes
        if not nodes:
            return None
    best = min(nodes, key=lambda n: (n.cmax, n.conflict))
    st = best.state
    return Solution(
        np.array(best.order, dtype=np.int64),
        st.t_mode.copy(),
        float(st.t_end.max()),
        float(st.t_end.sum()),
        st,
    )


def _portfolio_member(  # type: ignore[no-untyped-def]
    conn,
    problem: Problem,
    waits: bool,
    seed: int,
    seconds: float,
    lower: float = 0.0,
    places: PlaceOptions | None = None,
    index: int = 1,
) -> None:
    """A forked worker: improve the HEFT schedule (or the place-aware start,
    when it applies and is better) from its own seed, send back the best schedule.
    ``problem`` may be the main one without its blocking oracle
    (:attr:`TreeOptions.relaxed_workers`; the main process checks the plan).

    Worker ``index`` 1, 3, ... improves with the list local search, the
    neighbourhood the main process does not use on a zone problem (it runs the
    tabu search on arm sequences there, :func:`_member_search`); 2, 4, ... with
    the same one as the main process."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    try:
        t0 = time.perf_counter()
        ev = Evaluator(problem, waits=waits)
        rng = np.random.default_rng(seed)
        sol = ev.evaluate(priority_order(problem, rng=rng, noise=0.1))
        pl = usable_places(problem, places) if places is not None else None
        if pl is not None and places is not None:
            start = place_start(
                problem,
                ev,
                seed,
                options=places,
                places=pl,
                deadline=t0 + places.time_share * seconds,
            )
            if start is not None and (sol is None or start.key() < sol.key()):
                sol = start
        if sol is None:
            conn.send(None)
            return
        found = [time.perf_counter() - t0]

        def mark(_s: Solution) -> None:
            found[0] = time.perf_counter() - t0

        improve = _member_search(ev, index)
        best = improve(ev, sol, t0 + seconds, rng, on_improve=mark, lower=lower)
        s = ev.schedule(best)
        conn.send(
            (
                best.makespan,
                s.mode,
                s.start,
                s.end,
                [w.copy() for w in s.waits],
                s.blocking,
                found[0],
                ev.evaluations,
            )
        )
    except Exception as exc:  # pragma: no cover - reported, never fatal for the main search
        conn.send(("error", repr(exc)))
    finally:
        conn.close()


class _Race:
    """CP-SAT on one worker in a thread (it releases the GIL while searching).

    Both sides learn what the other proves or finds: CP-SAT reports every
    lower bound it proves (:func:`scheduler.cpsat.solve_cpsat`'s
    ``on_bound``), the tree every better makespan (:meth:`offer`); once the
    bound meets the tree's makespan, that makespan is optimal and both stop.
    """

    def __init__(
        self, problem: Problem, waits: bool, seed: int, seconds: float, done: _ctrl_c.StopEvent
    ) -> None:
        import threading

        self.done = done
        """Set when CP-SAT proved the optimum (or infeasibility), or a bound
        that the tree's makespan meets: the tree stops."""
        self.bound = 0.0
        """The best lower bound CP-SAT proved so far (seconds; 0: none)."""
        self._incumbent = math.inf
        self.meets_bound = False
        """True once the tree's makespan met CP-SAT's bound (it is optimal)."""
        self._solver: Any = None
        self._stopped = False
        self._ready = threading.Event()
        self._finished = threading.Event()
        self._result: Result | None = None
        self._thread = threading.Thread(
            target=self._run, args=(problem, waits, seed, max(0.05, seconds)), daemon=True
        )
        # a KeyboardInterrupt inside Thread.start may come after the thread
        # exists but before it has its ident: whether it started is then
        # unknown, and a thread taken for unstarted searched on to its time
        # limit. The start is one piece (a Ctrl-C there is raised after it),
        # and a thread started by an interrupted start ends at once (_keep).
        # The wait below is one piece too: raised inside Condition.wait while
        # it takes its lock back, a KeyboardInterrupt became "RuntimeError:
        # release unlocked lock"; a Ctrl-C there ends the wait instead.
        ctrl_c = _ctrl_c.current()
        try:
            with _ctrl_c.deferred():
                self._thread.start()
                # let it build its model before the tree search takes the GIL (the
                # compiled kernel holds it through each call): the solve itself runs without it
                end = time.perf_counter() + max(0.05, seconds)
                while not (self._ready.wait(0.02) or ctrl_c.hit or time.perf_counter() >= end):
                    pass
        except KeyboardInterrupt:  # Ctrl-C before the tree search began: end CP-SAT too
            self._stopped = True  # (a thread started by an interrupted start ends at once)
            if self._thread.ident is not None:
                self._wait_stopped()
            raise

    def _run(self, problem: Problem, waits: bool, seed: int, seconds: float) -> None:
        from scheduler import result as _result
        from scheduler.cpsat import solve_cpsat

        _ = _result
        try:
            r = solve_cpsat(
                problem,
                seconds,
                seed,
                waits=waits,
                workers=1,
                on_solver=self._keep,
                callback=False,
                on_bound=self._bound,
            )
            self._result = r
            if r.status in (SolveStatus.OPTIMAL, SolveStatus.INFEASIBLE):
                self.done.set()
        except Exception as exc:  # pragma: no cover - the tree's own result stands
            self._result = None
            self.error = repr(exc)
        finally:
            self._ready.set()
            self._finished.set()

    def _bound(self, bound: float) -> None:
        """CP-SAT proved ``bound`` (in its thread)."""
        if bound > self.bound:
            self.bound = bound
        self._check()

    def offer(self, makespan: float) -> None:
        """The tree found a schedule of ``makespan`` (in the tree's thread)."""
        if makespan < self._incumbent:
            self._incumbent = makespan
        self._check()

    def _check(self) -> None:
        if not self.meets_bound and self._incumbent <= self.bound + 1e-9:
            self.meets_bound = True  # the tree's schedule is optimal: nothing more to find
            self.done.set()
            self.stop()

    def _keep(self, solver: Any) -> None:
        self._solver = solver
        self._ready.set()
        if self._stopped:  # stopped before it started: let it end at once
            solver.parameters.max_time_in_seconds = 0.0

    def stop(self) -> None:
        """Ask CP-SAT to stop now (a request made before its search began is
        lost by ``stop_search``: the time limit is cut too; see :meth:`result`)."""
        self._stopped = True
        s = self._solver
        if s is not None:
            s.parameters.max_time_in_seconds = 0.0
            s.stop_search()

    def _wait_stopped(self) -> None:
        """Stop CP-SAT and wait for its thread to end, asking again until it
        does (the request may come between the solver's start and its search)."""
        while not self._finished.is_set():
            self.stop()
            self._finished.wait(0.02)

    def result(self) -> Result | None:
        """Stop CP-SAT if it still runs, and return its result."""
        # waits in one piece: a KeyboardInterrupt inside Event.wait can break
        # its lock, and one inside join can mark the thread ended early
        with _ctrl_c.deferred():
            self._wait_stopped()
            self._thread.join()
        return self._result


def solve_tree(
    problem: Problem,
    time_limit: float | None,
    seed: int,
    *,
    waits: bool = True,
    options: TreeOptions | None = None,
    start: Solution | None = None,
) -> Result:
    """The anytime tree search (see the module docstring)."""
    with _ctrl_c.guard():
        return _solve_tree(problem, time_limit, seed, waits, options, start)


def _solve_tree(
    problem: Problem,
    time_limit: float | None,
    seed: int,
    waits: bool,
    options: TreeOptions | None,
    start: Solution | None,
) -> Result:
    opt = options or TreeOptions()
    if problem.n_windows == 0 and problem.n_tools == 0 and problem.blocking is None:
        warm_up_graph()  # before the clock starts, as the kernel's own warm-up
    polish = (
        time_limit is not None
        and opt.max_evaluations is None
        and time_limit * opt.polish_share >= opt.polish_min_time
        and _may_polish(problem, opt)
    )
    if (
        time_limit is not None
        and opt.max_evaluations is None
        and (polish or _may_race(problem, opt))
    ):
        _load_cpsat()
    st = begin(problem, "tree", seed, waits=waits, record_first=True)
    t0 = st.t0
    final = math.inf if time_limit is None else t0 + time_limit
    rng = np.random.default_rng(seed)
    stats = st.stats
    p = problem
    ev = st.ev
    polish = polish and (not pure_fjsp(ev) or p.n_tasks <= opt.polish_fjsp_max_tasks)
    xq = None if polish else _exact_polish_problem(p, ev, time_limit, opt)
    # the tree's own search (and a racing CP-SAT, and the worker processes)
    # ends here; the polish, if any, has the time from here to ``final``
    share = opt.polish_share if polish else opt.exact_polish_share if xq is not None else 0.0
    deadline = final - share * time_limit if share and time_limit else final
    best: Solution | None = st.first  # the HEFT list, recorded as the first incumbent
    race: _Race | None = None

    def offer(sol: Solution | None) -> None:
        nonlocal best
        if sol is not None and (best is None or sol.key() < best.key()):
            improved = best is None or sol.makespan < best.makespan - 1e-9
            best = sol
            if improved:
                stats.record(time.perf_counter() - t0, sol.makespan)
                if race is not None:
                    race.offer(sol.makespan)  # optimal at once if CP-SAT's bound meets it

    if p.n_tasks == 0:
        return _finish(p, ev, None, 0.0, t0, seed, stats, proven=True)
    # the HEFT list came first (begin); then the warm start, if given
    if start is not None:
        offer(ev.evaluate(start.order, start.modes))
    # then the place-aware start, where its rule holds (travel, many tasks per place)
    places = usable_places(p, opt.places) if opt.places is not None else None
    if places is not None and opt.places is not None:
        ph = time.perf_counter()
        until = math.inf if time_limit is None else t0 + opt.places.time_share * time_limit
        offer(place_start(p, ev, seed, options=opt.places, places=places, deadline=until))
        stats.phases["places"] = time.perf_counter() - ph
    lb = _integral_bound(p, st.lb)
    proven = False
    # the exact phase proves the problem without an idle blocking oracle (a
    # compiled cell's, when no parked arm is ever in the way): dropping it
    # changes no schedule (scheduler.exact.without_idle_oracle). There the
    # proof is scheduler.exact.prove's, whether CP-SAT races or not
    q = p
    if p.blocking is not None and p.n_tasks <= opt.exact_max_tasks:
        q = exact.without_idle_oracle(p)
    can_prove, why = exact.applicable(q, opt.exact_max_tasks)
    cell_proof = can_prove and q is not p
    stats.extra["exact"] = (
        ("prove, idle oracle dropped" if cell_proof else "applicable") if can_prove else why
    )
    race = None
    # a Ctrl-C anywhere from here on (also between the race's start and the
    # search's own handler, or while the race is asked to end) ends CP-SAT too;
    # one whose KeyboardInterrupt was lost is still noted (scheduler._ctrl_c)
    # and ends the search loops, which poll ``ev.stop``
    ctrl_c = _ctrl_c.current()
    stop = ev.stop = _ctrl_c.StopEvent(ctrl_c)
    members: list[tuple[Any, Any]] = []  # (process, receiving end of its pipe)
    try:
        # where no exact search can prove the problem itself (a binding oracle,
        # an arm starting in an exclusive zone), the problem without zones may:
        # a plan no schedule without zones beats is optimal (tried in the loop)
        zf = _zone_free_problem(p, can_prove, opt)
        zf_tried: Solution | None = None
        zf_left = math.inf if time_limit is None else opt.zone_free_share * time_limit
        zf_nodes = opt.zone_free_nodes
        if opt.max_evaluations is not None:  # a work limit: in proportion to it
            zf_nodes = min(zf_nodes, 10 * opt.max_evaluations)

        def zone_free_attempt(until: float) -> bool:
            """Try to prove a new best plan without zones, within the phase's
            budget and ``until``; True when it is proven optimal."""
            nonlocal zf, zf_tried, zf_left, zf_nodes, lb
            if zf is None or best is None or best is zf_tried:
                return False
            zf_tried = best
            ph = time.perf_counter()
            verdict, nodes_used = _zone_free_proof(
                zf, best, lb, min(zf_left, until - ph), zf_nodes, stop
            )
            zf_nodes -= nodes_used
            zf_left -= time.perf_counter() - ph
            stats.nodes += nodes_used
            stats.phases["zone_free"] = (
                stats.phases.get("zone_free", 0.0) + time.perf_counter() - ph
            )
            stats.extra["zone_free"] = verdict
            if zf_left <= 0 or zf_nodes <= 0:
                zf = None  # its budget is spent
            if verdict == "proven":
                lb = max(lb, best.makespan - 1e-9)
                return True
            return False

        if (
            time_limit is not None
            and opt.max_evaluations is None
            and _races(p, opt, pure_fjsp(ev))
            and (best is None or best.makespan > lb + 1e-9)
        ):
            race = _Race(p, waits, seed, deadline - time.perf_counter(), stop)
            if best is not None:
                race.offer(best.makespan)
            can_prove = False  # CP-SAT is the proof here (measured faster than the exact B&B)
            stats.extra["exact"] = "left to the racing CP-SAT"
        remaining = deadline - time.perf_counter()
        daemon = multiprocessing.current_process().daemon  # e.g. a Dask worker: no children
        if daemon and opt.workers > 1:
            stats.extra["workers"] = "1 (a daemon process may not start worker processes)"
        if (
            opt.workers > 1
            and not daemon
            and time_limit is not None
            and opt.max_evaluations is None
            and not can_prove
            and race is None
            and remaining >= opt.parallel_min_time
            and "fork" in multiprocessing.get_all_start_methods()
            and (best is None or best.makespan > lb + 1e-9)
        ):
            ctx = multiprocessing.get_context("fork")
            # with a blocking oracle the workers search the problem without it (its
            # plans are checked against the oracle when they come back)
            relaxed = _member_problem(p, opt)
            stats.extra["worker_searches"] = tuple(
                _member_search(ev, k, blocking=relaxed.blocking is not None).__name__
                for k in range(1, opt.workers)
            )
            for k in range(1, opt.workers):
                here, there = ctx.Pipe(duplex=False)
                proc = ctx.Process(
                    target=_portfolio_member,
                    args=(
                        there,
                        relaxed,
                        waits,
                        seed + 7919 * k,
                        remaining - 0.15,
                        lb,
                        opt.places,
                        k,
                    ),
                    daemon=True,
                )
                proc.start()
                there.close()
                members.append((proc, here))
        width = 1
        rounds = 0
        work_limit = opt.max_evaluations
        # a pure FJSP: the compiled graph tabu search keeps all the time left after
        # the first beam pass, in one run (its restarts and settings go on undisturbed)
        graph = pure_fjsp(ev)
        # racing CP-SAT, no second process carries the list local search
        # (_member_search): the main process alternates it with the tabu search
        alternate = race is not None and not graph and not ev.blocking

        def out_of_time() -> bool:
            return (
                time.perf_counter() >= deadline
                or (work_limit is not None and ev.evaluations >= work_limit)
                or stop.is_set()  # CP-SAT's proof, or Ctrl-C
            )

        try:
            while not out_of_time():
                if best is not None and best.makespan <= lb + 1e-9:
                    proven = True
                    break
                if zone_free_attempt(deadline):
                    proven = True
                    break
                if (can_prove or cell_proof) and (time_limit is None or rounds >= 2):
                    ph = time.perf_counter()
                    nodes = opt.exact_max_nodes
                    if nodes is None and work_limit is not None:
                        nodes = 100 * work_limit
                    if cell_proof:
                        stats.extra["exact"] = "prove, idle oracle dropped"  # also beside a race
                        # on every core of the portfolio (the proof takes them all),
                        # with a wall clock only: work-limited runs stay in one process
                        procs = opt.workers if nodes is None and not daemon else 1
                        res, bound = _prove(
                            q, ev, best, lb, deadline - ph, nodes, waits, stop, procs
                        )
                        lb = max(lb, bound)
                    else:
                        res = exact.branch_and_bound(
                            p, best.makespan if best else math.inf, deadline, waits, nodes, stop
                        )
                    stats.nodes += res.nodes
                    stats.pruned += res.pruned
                    stats.phases["exact"] = (
                        stats.phases.get("exact", 0.0) + time.perf_counter() - ph
                    )
                    if res.schedule is not None:
                        sched = res.schedule
                        kept = _solution_of(sched, res.makespan)
                        sol = ev.evaluate(kept.order, sched.mode.copy())
                        if sol is not None and sol.makespan <= res.makespan + 1e-9:
                            offer(sol)
                        else:  # the decoder cannot reproduce it: keep the exact schedule itself
                            stats.extra["exact_schedule"] = sched
                            offer(kept)
                    if res.complete:
                        proven = True
                        break
                    # out of budget for the proof: go on with the heuristics
                    can_prove = cell_proof = False
                    continue
                rounds += 1
                # a beam pass (widths 1, 2, 4, ...): new starting points
                if width <= opt.max_width:
                    ph = time.perf_counter()
                    budget = (
                        (deadline - ph) * opt.beam_share if math.isfinite(deadline) else math.inf
                    )
                    offer(
                        beam_pass(
                            ev, width, ph + budget, best.makespan if best else math.inf, rng, stats
                        )
                    )
                    stats.phases["beam"] = stats.phases.get("beam", 0.0) + time.perf_counter() - ph
                    width *= 2
                    if places is not None and time.perf_counter() >= ph + budget:
                        # on a problem as large as those the place-aware start serves, the
                        # pass ran out of its time: a wider one, with less time, would too
                        width = opt.max_width + 1
                if best is None:
                    offer(ev.evaluate(priority_order(p, rng=rng, noise=opt.restart_noise)))
                    if best is None:
                        if rounds >= 3:
                            break  # list decoding dead-locks here: the exact fallback takes over
                        continue
                # improvement: tabu search on arm sequences (list local search with a
                # blocking oracle); beside a race, the two take turns by slice
                ph = time.perf_counter()
                slice_end = deadline
                if math.isfinite(deadline) and (width <= opt.max_width or alternate) and not graph:
                    slice_end = ph + (deadline - ph) * opt.improve_share
                evals = None
                if work_limit is not None:
                    evals = min(opt.local_evaluations, max(1, work_limit - ev.evaluations))
                elif not math.isfinite(deadline):
                    evals = opt.local_evaluations
                listed = alternate and rounds % 2 == 0
                if ev.blocking or best.state is None or listed:
                    improved = local_search(
                        ev, best, slice_end, rng, on_improve=offer, lower=lb, max_evaluations=evals
                    )
                    if listed:
                        stats.phases["improve_list"] = (
                            stats.phases.get("improve_list", 0.0) + time.perf_counter() - ph
                        )
                else:
                    improved = tabu_search(
                        ev, best, slice_end, rng, on_improve=offer, lower=lb, max_evaluations=evals
                    )
                offer(improved)
                stats.phases["improve"] = (
                    stats.phases.get("improve", 0.0) + time.perf_counter() - ph
                )
                if (
                    time_limit is None
                    and work_limit is None
                    and not can_prove
                    and width > opt.max_width
                    and rounds > 12
                ):
                    break  # unlimited budget on a big problem: stop after a fair effort
            # a work limit (or none) ends the loop with work, not time, left:
            # the last best plan gets its attempt too
            if not proven and time_limit is None and not stop.is_set():
                proven = zone_free_attempt(math.inf)
        except KeyboardInterrupt:
            stats.interrupted = True  # Ctrl-C: keep the best schedule found so far
        if ctrl_c.hit:  # also when its KeyboardInterrupt was lost on the way
            stats.interrupted = True
        if stats.interrupted:
            if race is not None:
                race.stop()
            for member, _pipe in members:
                member.terminate()
        stats.evaluations = ev.evaluations
        for member, pipe in members:
            if stats.interrupted or (best is not None and best.makespan <= lb + 1e-9):
                if not stats.interrupted:  # optimal already: nothing the worker finds is better
                    member.terminate()
                member.join(timeout=1.0)
                continue
            got = (
                pipe.recv() if pipe.poll(max(0.05, deadline - time.perf_counter() + 2.0)) else None
            )
            member.join(timeout=1.0)
            if member.is_alive():  # pragma: no cover - a worker that did not stop in time
                member.terminate()
            if (
                isinstance(got, tuple)
                and len(got) == 8
                and (best is None or got[0] < best.makespan - 1e-9)
            ):
                from scheduler.schedule import Schedule

                mk, w_mode, w_start, w_end, w_waits, w_blocking, found, _evals = got
                sched = Schedule(w_mode, w_start, w_end, tuple(w_waits), w_blocking)
                if p.blocking is not None and opt.relaxed_workers:
                    checked, as_is = _checked_against_oracle(p, ev, sched, stats)
                    if checked is not None and (best is None or checked.key() < best.key()):
                        best = checked
                        if as_is is None:  # decoded: the decoder gives its schedule
                            stats.extra.pop("worker_schedule", None)
                        else:
                            stats.extra["worker_schedule"] = as_is
                        stats.record(found, checked.makespan)
                else:
                    stats.extra["worker_schedule"] = sched
                    best = _solution_of(sched, mk)
                    stats.record(found, mk)
            if isinstance(got, tuple) and len(got) == 8:
                stats.evaluations += int(got[7])
            elif isinstance(got, tuple) and got and got[0] == "error":
                stats.extra["worker_error"] = got[1]
        if race is not None:
            cp = race.result()
            stats.extra["portfolio"] = cp.status.value if cp is not None else "none"
            if cp is not None:
                if cp.schedule is not None and (
                    best is None or cp.objective < best.makespan - 1e-9
                ):
                    stats.extra["exact_schedule"] = cp.schedule
                    best = _solution_of(cp.schedule, cp.objective)
                    stats.record(time.perf_counter() - t0, cp.objective)
                lb = max(lb, cp.bound)
                if cp.status is SolveStatus.OPTIMAL and best is not None:
                    proven = best.makespan <= cp.objective + 1e-9
                elif cp.status is SolveStatus.INFEASIBLE:
                    proven = True
            # a bound CP-SAT proved while it searched (valid also when it was
            # stopped before it could say so in its result)
            lb = max(lb, race.bound)
            stats.extra["portfolio_bound"] = race.bound
            if best is not None and best.makespan <= lb + 1e-9:
                proven = True
        if (
            polish
            and best is not None
            and not proven
            and not (stats.interrupted or ctrl_c.hit)
            and final - time.perf_counter() > 0.1
        ):
            best, lb, proven = _polish(p, ev, best, lb, final, waits, seed, opt, stats, t0)
        if (
            xq is not None
            and best is not None
            and not proven
            and not (stats.interrupted or ctrl_c.hit)
            and final - time.perf_counter() > 0.1
        ):
            best, lb, proven = _exact_polish(xq, ev, best, lb, final, waits, stats, t0, stop)
        if best is None and not proven and opt.fallback and not (stats.interrupted or ctrl_c.hit):
            # no list order decodes (start zones dead-locking): ask CP-SAT within the budget left
            from scheduler.fallback import exact_fallback

            left = None if time_limit is None else final - time.perf_counter()
            left_evals = None if work_limit is None else max(1, work_limit - stats.evaluations)
            ph = time.perf_counter()
            fb = exact_fallback(
                p, waits=waits, seed=seed, time_limit=left, max_evaluations=left_evals
            )
            stats.phases["fallback"] = time.perf_counter() - ph
            stats.extra["fallback"] = fb.status.value
            stats.nodes += fb.stats.nodes
            if fb.schedule is not None:
                stats.extra["exact_schedule"] = fb.schedule
                best = _solution_of(fb.schedule, fb.objective)
                stats.record(time.perf_counter() - t0, fb.objective)
                if fb.status is SolveStatus.OPTIMAL:
                    proven = True
            elif fb.status is SolveStatus.INFEASIBLE:
                proven = True
        return _finish(p, ev, best, lb, t0, seed, stats, proven)
    except KeyboardInterrupt:
        # Ctrl-C outside the search loop (the race's start, the collection of
        # the workers' and CP-SAT's schedules, the fallback): end them, and
        # keep the best schedule so far as the search loop does
        if race is not None:
            race.result()
        for member, _pipe in members:
            member.terminate()
            member.join(timeout=1.0)
        stats.interrupted = True
        stats.evaluations = stats.evaluations or ev.evaluations
        return _finish(p, ev, best, lb, t0, seed, stats, proven)


def _polish(
    p: Problem,
    ev: Evaluator,
    best: Solution,
    lb: float,
    final: float,
    waits: bool,
    seed: int,
    opt: TreeOptions,
    stats: SearchStats,
    t0: float,
) -> tuple[Solution, float, bool]:
    """The polish (:attr:`TreeOptions.polish_share`): CP-SAT until ``final``,
    hinted with ``best``'s schedule. Returns the better of the two schedules,
    the lower bound (CP-SAT's where it is higher) and whether the schedule
    is proven optimal."""
    from scheduler.cpsat import solve_cpsat

    ph = time.perf_counter()
    hint = _schedule_of(ev, best, stats)
    cp = solve_cpsat(
        p, max(0.05, final - ph), seed, waits=waits, workers=opt.workers, hint=hint, callback=False
    )
    stats.phases["polish"] = time.perf_counter() - ph
    stats.extra["polish"] = cp.status.value
    if cp.stats.interrupted:
        stats.interrupted = True
    best = _keep_shorter(best, cp.schedule, cp.objective, stats, t0)
    lb = max(lb, cp.bound) if math.isfinite(cp.bound) else lb
    proven = cp.status is SolveStatus.OPTIMAL and best.makespan <= cp.objective + 1e-9
    return best, lb, proven or best.makespan <= lb + 1e-9


def _schedule_of(ev: Evaluator, best: Solution, stats: SearchStats) -> Schedule:
    """``best``'s schedule: the one kept beside it when it was found outside the
    decoder (a worker's, CP-SAT's, the exact search's), else decoded."""
    kept = None
    if best.state is None:
        kept = stats.extra.get("worker_schedule") or stats.extra.get("exact_schedule")
    return kept if kept is not None else ev.schedule(best)


def _keep_shorter(
    best: Solution, sched: Schedule | None, makespan: float, stats: SearchStats, t0: float
) -> Solution:
    """``best``, or ``sched`` (found by a last phase, outside the decoder) as a
    Solution when it is shorter: then kept where ``_finish`` reads it and recorded
    as an improvement."""
    if sched is None or makespan >= best.makespan - 1e-9:
        return best
    stats.extra.pop("worker_schedule", None)  # _finish reads the kept schedule here
    stats.extra["exact_schedule"] = sched
    stats.record(time.perf_counter() - t0, makespan)
    return _solution_of(sched, makespan)


def _zone_free_problem(p: Problem, can_prove: bool, opt: TreeOptions) -> Problem | None:
    """The zone-free relaxation (:func:`scheduler.exact.zone_free`) the tree
    tries to prove its plans with (:attr:`TreeOptions.zone_free_share`), or
    None where the rule does not hold: the exact search cannot prove ``p``
    itself (a binding blocking oracle, an arm starting inside an exclusive
    zone), it has zones to drop and at most ``exact_max_tasks`` tasks, and the
    exact search applies to the relaxation (setups obeying the triangle
    inequality)."""
    if opt.zone_free_share <= 0.0 or opt.zone_free_nodes <= 0 or can_prove:
        return None
    if p.n_tasks == 0 or p.n_tasks > opt.exact_max_tasks:
        return None
    if p.n_windows == 0 and p.blocking is None:
        return None  # nothing to drop: the relaxation is the problem
    zf = exact.zone_free(p)
    return zf if exact.applicable(zf, opt.exact_max_tasks)[0] else None


def _zone_free_proof(
    zf: Problem, best: Solution, lb: float, seconds: float, nodes: int, stop: Any
) -> tuple[str, int]:
    """Whether some schedule of the zone-free relaxation ``zf`` is shorter than
    ``best``: ("proven", nodes) when none is (``best`` is optimal), ("shorter
    without zones", nodes) when one is, ("stopped", nodes) when the budget
    ran out first.

    First ``best``'s own list and modes are decoded without zones, and
    improved by the list local search (500 decodes, half the time at most):
    when that finds a shorter one, nothing more is searched. Else the exact
    branch and bound looks for one within the time left and ``nodes``,
    stopping at the first, its modes and order tried first."""
    below = best.makespan - 1e-9
    t0 = time.perf_counter()
    zev = Evaluator(zf)
    relaxed = zev.evaluate(best.order, best.modes)
    if relaxed is not None and relaxed.makespan >= below:
        # the list local search without zones, a few hundred decodes from it
        relaxed = local_search(
            zev, relaxed, t0 + seconds / 2, np.random.default_rng(0), lower=lb, max_evaluations=500
        )
    if relaxed is not None and relaxed.makespan < below:
        return "shorter without zones", 0
    seconds -= time.perf_counter() - t0
    if seconds <= 0:
        return "stopped", 0
    # the relaxed schedule (no shorter than the plan) guides the search: its
    # modes and order first (on random problems with binding oracles it found
    # a shorter schedule in 214 nodes where the search alone took 10,578)
    guide = zev.schedule(relaxed) if relaxed is not None else None
    res = exact.prove(
        zf, seconds, nodes, incumbent=guide, upper=below, lower=lb, stop=stop, stop_at_first=True
    )
    if res.proven and res.schedule is None:
        return "proven", res.nodes
    return ("shorter without zones" if res.schedule is not None else "stopped"), res.nodes


def _exact_polish_problem(
    p: Problem, ev: Evaluator, time_limit: float | None, opt: TreeOptions
) -> Problem | None:
    """The problem the exact polish (:attr:`TreeOptions.exact_polish_share`)
    searches (``p`` without an idle blocking oracle), or None where it does
    not run: a work limit or too short a budget, a size outside
    ``exact_max_tasks < n <= exact_polish_max_tasks``, a pure FJSP, a
    problem the CP-SAT race takes, or one the exact search does not apply
    to (a binding oracle among them)."""
    if (
        time_limit is None
        or opt.max_evaluations is not None
        or opt.exact_polish_share <= 0.0
        or time_limit * opt.exact_polish_share < opt.polish_min_time
        or not (opt.exact_max_tasks < p.n_tasks <= opt.exact_polish_max_tasks)
        or pure_fjsp(ev)
        or _races(p, opt, False)
    ):
        return None
    q = exact.without_idle_oracle(p) if p.blocking is not None else p
    ok, _why = exact.applicable(q, p.n_tasks)
    return q if ok else None


def _exact_polish(
    q: Problem,
    ev: Evaluator,
    best: Solution,
    lb: float,
    final: float,
    waits: bool,
    stats: SearchStats,
    t0: float,
    stop: Any,
) -> tuple[Solution, float, bool]:
    """The exact polish (:attr:`TreeOptions.exact_polish_share`):
    :func:`scheduler.exact.prove` on ``q`` until ``final``, from ``best``'s
    schedule. Returns the better of the two schedules, the lower bound (the
    search's where it is higher) and whether the schedule is proven
    optimal."""
    ph = time.perf_counter()
    inc = _schedule_of(ev, best, stats)
    try:
        res = exact.prove(
            q, max(0.05, final - ph), None, incumbent=inc, lower=lb, waits=waits, stop=stop
        )
    finally:  # also on Ctrl-C, which solve_tree turns into the best schedule so far
        stats.phases["exact_polish"] = time.perf_counter() - ph
    stats.extra["exact_polish"] = "proven" if res.proven else res.reason
    stats.nodes += res.nodes
    stats.pruned += res.pruned
    best = _keep_shorter(best, res.schedule, res.makespan, stats, t0)
    if math.isfinite(res.bound):
        lb = max(lb, min(res.bound, best.makespan))
    return best, lb, res.proven or best.makespan <= lb + 1e-9


def _prove(
    q: Problem,
    ev: Evaluator,
    best: Solution | None,
    lb: float,
    seconds: float,
    nodes: int | None,
    waits: bool,
    stop: Any,
    workers: int = 1,
) -> tuple[exact.ExactResult, float]:
    """The exact phase on a compiled cell: :func:`scheduler.exact.prove` on
    ``q`` (the problem without its idle oracle), from the best schedule so far
    and the lower bound ``lb``, within ``seconds`` (None when infinite) or
    ``nodes``, stopped by ``stop``, on ``workers`` processes (no worker
    process of the tree runs beside it: the machine's cores are the proof's);
    as the result of :func:`scheduler.exact.branch_and_bound` (``complete``:
    proven), and the proof's lower bound of the optimum."""
    inc = ev.schedule(best) if best is not None and best.state is not None else None
    upper = best.makespan + 1e-9 if best is not None and inc is None else math.inf
    res = exact.prove(
        q,
        seconds if math.isfinite(seconds) else None,
        nodes,
        incumbent=inc,
        upper=upper,
        lower=lb,
        waits=waits,
        stop=stop,
        workers=workers,
    )
    out = exact.ExactResult(res.schedule, res.makespan, res.proven, res.nodes, res.pruned)
    return out, res.bound


def _integral_bound(p: Problem, lb: float) -> float:
    """``lb`` rounded up to the problem's time grid, when it has one.

    When every time of the problem is a multiple of ``1 / s``
    (:func:`scheduler.cpsat.integer_scale`) and no blocking oracle charges
    detours, some optimal schedule has all its times on that grid: once the
    modes and the order on every arm, zone and tool are fixed, the
    constraints are differences of times with constants on the grid, and
    the earliest times that meet them (longest paths) are no later than any
    others and lie on the grid. So the optimum is a multiple of ``1 / s``
    and the ceiling of a bound is a bound.
    """
    if p.blocking is not None or not math.isfinite(lb) or lb <= 0.0 or p.n_tasks > 5000:
        return lb
    from scheduler.cpsat import integer_scale

    scale, on_grid = integer_scale(p)
    if not on_grid:
        return lb
    return max(lb, math.ceil(lb * scale - 1e-6) / scale)


def _member_search(
    ev: Evaluator, index: int, blocking: bool | None = None
) -> Callable[..., Solution]:
    """The improvement a forked worker runs: the list local search with a
    blocking oracle (the only one that handles it) and, on odd ``index``, on
    any problem that is not a pure FJSP; else the tabu search (which is the
    compiled graph search on a pure FJSP).

    Measured at equal decodes (6,000 from the HEFT list, best of 2 seeds) on
    48 ``routes`` and ``stations`` problems with seeds 2-3 (the outside table
    uses 0-1): the list local search ended lower on 16, the tabu search on 25
    (equal: 7); on the 24 solved without waits the list search was lower on
    12, the tabu search on 8. The list search spent 2.9 times less CPU time
    on its decodes (mean ratio; the tabu search ranks its moves in Python).
    A second process with the same search as the main one only adds a seed;
    one with the other neighbourhood searches where the main one cannot go
    (docs/scheduler.md, "Solvers"). ``blocking`` overrides ``ev.blocking``
    (the main process names the searches of workers that search the problem
    without its oracle; an oracle-only problem whose relaxation is a pure
    FJSP is then named by the zone rule, though its worker runs the graph
    search)."""
    if (ev.blocking if blocking is None else blocking) or (index % 2 == 1 and not pure_fjsp(ev)):
        return local_search
    return tabu_search


def _member_problem(p: Problem, opt: TreeOptions) -> Problem:
    """What the worker processes search: ``p``, or ``p`` without its blocking
    oracle (:attr:`TreeOptions.relaxed_workers`)."""
    if p.blocking is None or not opt.relaxed_workers:
        return p
    return replace(p, blocking=None, name=f"{p.name} (no oracle)")


def _checked_against_oracle(
    p: Problem, ev: Evaluator, sched: Schedule, stats: SearchStats
) -> tuple[Solution | None, Schedule | None]:
    """A worker's plan of ``p`` without its oracle, as a solution of ``p``: the
    plan itself when no parked arm is in its way (``validate`` accepts it;
    returned as the second item, for ``_finish`` to keep), else its modes and
    start order decoded again with the oracle's detours (None when that order
    cannot be placed). ``stats.extra["worker_plan"]`` says which."""
    from scheduler.schedule import ScheduleError, validate

    try:
        mk = validate(p, sched)
    except ScheduleError:
        order = np.lexsort((np.arange(len(sched.start)), sched.start)).astype(np.int64)
        sol = ev.evaluate(order, np.asarray(sched.mode, dtype=np.int64).copy())
        stats.extra["worker_plan"] = "decoded again with the oracle"
        return sol, None
    stats.extra["worker_plan"] = "valid with the oracle"
    return _solution_of(sched, mk), sched


def _may_race(p: Problem, opt: TreeOptions) -> bool:
    """Whether :func:`_races` can hold for ``p`` whatever kind of problem it is."""
    most = max(opt.portfolio_max_tasks, opt.portfolio_fjsp_max_tasks, opt.portfolio_setup_max_tasks)
    return 0 < p.n_tasks <= most


def _may_polish(p: Problem, opt: TreeOptions) -> bool:
    """Whether the polish (:attr:`TreeOptions.polish_share`) may run on ``p``
    (setup times: up to ``polish_setup_max_tasks`` tasks); the size rule of a
    pure FJSP (``polish_fjsp_max_tasks``) is applied later, once the evaluator
    knows it is one."""
    if opt.polish_share <= 0.0 or p.n_tasks == 0 or p.blocking is not None:
        return False
    if not p._setup.zero and p.n_tasks > opt.polish_setup_max_tasks:
        return False
    return p.n_windows <= opt.portfolio_max_windows


def _load_cpsat() -> None:
    """Import OR-Tools' CP-SAT module before the solver's clock starts (once per
    process; about 0.4 s, longer from a cold disk), as the kernel's warm-up is.
    Imported first by the racing thread, it counted against the budget, and
    loading its extension modules holds the interpreter while the tree search
    waits. The likely cause of one measured miss: the first raced solve of a
    benchmark process (8 tasks, 2 s; the kernel's warm-up took 3.4 s there
    against 0.9 s usually) ran 4.4 s and kept its first schedule, 63, where
    the same solve proves 49 otherwise."""
    from ortools.sat.python import cp_model

    _ = cp_model


def _races(p: Problem, opt: TreeOptions, fjsp: bool) -> bool:
    """Whether the tree search races CP-SAT on ``p`` (the size rule of
    :class:`TreeOptions`; wall-clock runs without a work limit only)."""
    if fjsp:
        return p.n_tasks <= opt.portfolio_fjsp_max_tasks
    most = opt.portfolio_max_tasks if p._setup.zero else opt.portfolio_setup_max_tasks
    return p.n_tasks <= most and p.n_windows <= opt.portfolio_max_windows


def _solution_of(sched: Schedule, makespan: float) -> Solution:
    """A schedule found outside the list decoder (a worker process, CP-SAT, the
    exact search) as a :class:`Solution`: its tasks in start order (ties by
    index), its modes, ``makespan``, and no decoder state (``_finish`` then
    keeps the schedule itself)."""
    order = np.lexsort((np.arange(len(sched.start)), sched.start)).astype(np.int64)
    return Solution(order, sched.mode.copy(), makespan, float(sched.end.sum()), None)


def _finish(
    p: Problem,
    ev: Evaluator,
    best: Solution | None,
    lb: float,
    t0: float,
    seed: int,
    stats: SearchStats,
    proven: bool,
) -> Result:
    from scheduler.schedule import validate

    runtime = time.perf_counter() - t0
    if p.n_tasks == 0:
        return Result.empty("tree", seed, runtime, stats)
    if best is None:
        status = SolveStatus.INFEASIBLE if proven else SolveStatus.UNKNOWN
        return Result(status, None, math.inf, lb, runtime, "tree", seed, stats)
    sched = None
    if best.state is None:
        sched = stats.extra.pop("worker_schedule", None) or stats.extra.pop("exact_schedule", None)
    if sched is None:
        sched = ev.schedule(best)
    mk = validate(p, sched)
    bound = mk if proven else min(lb, mk)
    status = SolveStatus.OPTIMAL if proven or mk <= lb + 1e-9 else SolveStatus.FEASIBLE
    return Result(status, sched, mk, bound, runtime, "tree", seed, stats)
