"""Travel-aware starting schedules: arms that walk from place to place.

On problems whose tasks gather at a few *places* (tasks between which an arm
travels in no time: the points of a work cell, the bins of a kitting line),
the earliest-finish-time list (:mod:`scheduler.greedy`) sends each arm
wherever the next task of the list happens to be, and the arms spend a third
of their time travelling (``benchmarks/results/gap_anatomy.md``). The
construction here, :func:`place_start`, is a dispatcher instead: the arm
that is free first picks its next task, preferring one that can start soon
*and* lies where it stands, so it works through runs of tasks at one place
and moves on to a nearby one when the place has none ready for it.

One construction (:func:`place_dispatch`):

* the arm ``a`` whose last task ends first (``f_a``) picks its next task
  among the tasks it can do whose predecessors are all placed. Each
  candidate ``t`` is scored::

      score(t) = start(t) + travel_weight * travel(a, last, t) + quota(a, t)

  ``start`` is its earliest start after the travel from the arm's last
  task, its release and its predecessors' ends, first estimated without
  zones and tools for every candidate, then for the ``candidates`` best
  exactly by the placement kernel (zone and tool conflicts with everything
  placed so far, waits at zone borders). ``quota`` is large once the arm
  has done its share of the task's *class* (the set of arms that can do
  it), the shares coming from the load LP aggregated by class
  (:func:`class_quotas`): an arm that alone can do some tasks keeps time
  for them, and slow and fast arms get the shares that balance them;
* the best candidate is placed at once, where the kernel put it; the arm's
  end moves on and the next arm decides.

The result is a complete schedule with the decoder's state, which the tree
search takes as an incumbent and polishes with its tabu search
(:mod:`scheduler.tabu`). :func:`place_start` runs a few constructions
(travel weights and tie noise from :class:`PlaceOptions`) and returns the
best. It applies only where it was measured to help (:func:`usable_places`):
setup times, no blocking oracle, enough tasks, and tasks that share places.

Examples
--------
>>> from scheduler.generate import random_problem
>>> from scheduler.search import Evaluator
>>> p = random_problem(4, 120, 4, 1, seed=3, grid=2)
>>> usable_places(p, PlaceOptions(min_tasks=100)).n_places
9
>>> ev = Evaluator(p)
>>> sol = place_start(p, ev, seed=0)
>>> from scheduler.schedule import validate
>>> validate(p, ev.schedule(sol)) == sol.makespan
True
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from multiarm.errors import UsageError
from multiarm.types import FloatArray, IntArray
from scheduler.problem import Problem
from scheduler.search import Evaluator, Solution, rank_upward

__all__ = [
    "PlaceOptions",
    "Places",
    "class_quotas",
    "find_places",
    "place_dispatch",
    "place_start",
    "usable_places",
]


@dataclass(frozen=True, slots=True)
class PlaceOptions:
    """Knobs of the place-aware start (:func:`place_start`).

    Tuned on generated problems (:func:`scheduler.generate.random_problem`
    with ``start_zones=True``) of 16 arms x 1000 tasks (seeds 10-19), 12 x
    800 and 8 x 500 (seeds 10-14), never on the scale benchmark's seeds 0-2;
    see ``docs/scheduler.md``.

    Raises
    ------
    UsageError
        A field out of range (checked at construction).
    """

    travel_weights: tuple[float, ...] = (1.0, 0.5, 2.0)
    """Weight of the travel time in the score (seconds per second of travel),
    one construction each, in turn."""
    starts: int = 6
    """Constructions tried: the travel weights in turn, the first pass of
    each without tie noise, later ones with it."""
    noise: float = 1.0
    """Tie noise (uniform, seconds) added to each task's score in the later
    constructions."""
    candidates: int = 4
    """Candidates placed exactly (zones, tools) per decision."""
    quota_travel: float = 0.5
    """Travel charged per task in the class LP (times the arm's shortest move
    between two places)."""
    quota_penalty: float = 1000.0
    """Score added to a task of a class whose share the arm has done."""
    min_tasks: int = 100
    """Apply to problems with at least this many tasks."""
    min_tasks_per_place: float = 2.0
    """Apply when the tasks share places: at least this many per place on
    average. With ``random_problem``'s 49 grid points, the tree at 10 s
    gained from the start at 6 x 100 (2.0-2.4 tasks per place, seeds 10-14:
    mean gap to the bound 47.8 % -> 40.8 %, better on all five) and 8 x 200
    (about 4 per place: 50.2 % -> 33.9 %), and nothing at 4 x 40 (about 1.5
    per place: 35.5 % -> 34.8 %, worse on one of five)."""
    time_share: float = 0.15
    """With a time limit, start no construction after this share of it."""

    def __post_init__(self) -> None:
        if not self.travel_weights or any(
            not isinstance(w, int | float) or not (0.0 <= w < math.inf) for w in self.travel_weights
        ):
            raise UsageError(
                f"PlaceOptions.travel_weights must be finite weights >= 0, got {self.travel_weights!r}"
            )
        for name, least in (("starts", 1), ("candidates", 1), ("min_tasks", 0)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < least:
                raise UsageError(f"PlaceOptions.{name} must be an int >= {least}, got {v!r}")
        for name in ("noise", "quota_travel", "quota_penalty", "min_tasks_per_place"):
            v = getattr(self, name)
            if not isinstance(v, int | float) or not (0.0 <= v < math.inf):
                raise UsageError(f"PlaceOptions.{name} must be finite and >= 0, got {v!r}")
        if not isinstance(self.time_share, int | float) or not 0.0 < self.time_share <= 1.0:
            raise UsageError(f"PlaceOptions.time_share must be in (0, 1], got {self.time_share!r}")


@dataclass(frozen=True, slots=True)
class Places:
    """Where the tasks are, as the setup times tell.

    Attributes
    ----------
    place : (T,) int
        Each task's place: tasks are at one place when some arm that can do
        both travels between them in no time (closed under chaining).
    n_places : int
    unit : (A,) float, seconds
        Each arm's shortest travel between two different places (0 when it
        sees only one).
    clean : bool
        Every arm reaches every task it can do at a place from every other
        one there in no time (checked from one task per arm and place): the
        places are points, not chains of near ones.
    """

    place: IntArray
    n_places: int
    unit: FloatArray
    clean: bool


def find_places(problem: Problem, tol: float = 1e-9) -> Places:
    """The places of a problem's tasks (see :class:`Places`).

    For each arm, one setup row per place it sees: tasks it reaches from a
    task in at most ``tol`` seconds join that task's place.

    Parameters
    ----------
    problem : Problem
    tol : float
        Seconds of travel that still count as staying.

    Returns
    -------
    Places

    Examples
    --------
    >>> from scheduler.generate import random_problem
    >>> find_places(random_problem(3, 60, 2, 0, seed=1, grid=1)).n_places
    4
    """
    p = problem
    T, A = p.n_tasks, p.n_arms
    parent = np.arange(T)

    def root(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = int(parent[x])
        return x

    unit = np.full(A, math.inf)
    reps: list[tuple[int, int, int]] = []  # (arm, task, tasks of the arm at its place)
    for a in range(A):
        tasks = np.flatnonzero(p.mode_of[a] >= 0)
        if len(tasks) == 0:
            continue
        seen = np.zeros(T, dtype=bool)
        for t in tasks.tolist():
            if seen[t]:
                continue
            row = p.setup_row(a, t)[tasks]
            here = row <= tol
            here[tasks == t] = True
            reps.append((a, t, int(here.sum())))
            seen[tasks[here]] = True
            away = row[~here]
            if len(away):
                unit[a] = min(unit[a], float(away.min()))
            rt = root(t)
            for u in tasks[here].tolist():
                ru = root(u)
                if ru != rt:
                    parent[ru] = rt
    roots = np.array([root(t) for t in range(T)], dtype=np.int64)
    _, inverse = np.unique(roots, return_inverse=True)
    place = inverse.astype(np.int64)
    P = int(place.max()) + 1 if T else 0
    counts = np.zeros((A, max(P, 1)), dtype=np.int64)
    np.add.at(counts, (p.mode_arm, place[p.mode_task]), 1)
    clean = all(counts[a, place[t]] == n for a, t, n in reps)
    unit[~np.isfinite(unit)] = 0.0
    return Places(place, P, unit, clean)


def usable_places(problem: Problem, options: PlaceOptions | None = None) -> Places | None:
    """The problem's places when :func:`place_start` applies to it, else None.

    The rule: setup times (something to save), no blocking oracle (the
    construction places tasks without the oracle's detours), at least
    ``options.min_tasks`` tasks, places that are points (``Places.clean``:
    not chains of tasks a zero setup apart, as random setup matrices make),
    at least two of them, and on average at least
    ``options.min_tasks_per_place`` tasks per place (:func:`find_places`).

    Parameters
    ----------
    problem : Problem
    options : PlaceOptions or None

    Returns
    -------
    Places or None
    """
    opt = options or PlaceOptions()
    p = problem
    if p._setup.zero or p.blocking is not None or p.n_tasks < max(opt.min_tasks, 1):
        return None
    pl = find_places(p)
    if not pl.clean or pl.n_places < 2:
        return None
    return pl if p.n_tasks >= opt.min_tasks_per_place * pl.n_places else None


def class_quotas(problem: Problem, overhead: FloatArray) -> tuple[IntArray, FloatArray]:
    """Each arm's share of each class of tasks, from the load LP by class.

    A task's *class* is the set of arms that can do it. The LP minimises
    ``C`` with ``available[a] + sum_k z[k, a] * D[k, a] <= C`` and
    ``sum_a z[k, a] = 1``, where ``D[k, a]`` is the work of class ``k`` on
    arm ``a`` (durations plus ``overhead[a]`` per task); the quota of arm
    ``a`` in class ``k`` is ``z[k, a] * D[k, a]``.

    Parameters
    ----------
    problem : Problem
    overhead : (A,) float, seconds
        Time charged per task on each arm besides its duration (travel).

    Returns
    -------
    cls : (T,) int
        Each task's class.
    quota : (A, K) float, seconds
        Each arm's share of each class's work (zeros if the LP fails).
    """
    from scipy.optimize import linprog

    p = problem
    T, A = p.n_tasks, p.n_arms
    can = p.mode_of >= 0  # (A, T)
    keys: dict[bytes, int] = {}
    cls = np.zeros(T, dtype=np.int64)
    for t in range(T):
        cls[t] = keys.setdefault(can[:, t].tobytes(), len(keys))
    K = len(keys)
    cost = np.where(can, p.mode_duration[np.maximum(p.mode_of, 0)] + overhead[:, None], 0.0)
    work = np.zeros((K, A))
    np.add.at(work, cls, cost.T)
    can_k = np.zeros((K, A), dtype=bool)
    can_k[cls] = can.T
    pairs = np.argwhere(can_k)  # (n, 2): class, arm
    n = len(pairs)
    c = np.zeros(n + 1)
    c[n] = 1.0
    a_eq = np.zeros((K, n + 1))
    a_eq[pairs[:, 0], np.arange(n)] = 1.0
    a_ub = np.zeros((A, n + 1))
    a_ub[pairs[:, 1], np.arange(n)] = work[pairs[:, 0], pairs[:, 1]]
    a_ub[:, n] = -1.0
    res = linprog(
        c,
        A_ub=a_ub,
        b_ub=-np.asarray(p.arm_available, dtype=float),
        A_eq=a_eq,
        b_eq=np.ones(K),
        bounds=[(0.0, 1.0)] * n + [(0.0, None)],
        method="highs",
    )
    quota = np.zeros((A, K))
    if res.status == 0:
        quota[pairs[:, 1], pairs[:, 0]] = res.x[:n] * work[pairs[:, 0], pairs[:, 1]]
    return cls, quota


@dataclass(frozen=True, slots=True)
class _Prepared:
    """What every construction of one problem shares."""

    rank: FloatArray  # (T,) HEFT upward rank (a tiny tie-break: longer tails first)
    can: np.ndarray  # (A, T) bool, the arm can do the task
    cls: IntArray  # (T,) each task's class
    quota: FloatArray  # (A, K) each arm's share of each class, seconds
    charge: FloatArray  # (A, T) what a task counts against the arm's share, seconds


def _prepare(problem: Problem, places: Places, opt: PlaceOptions) -> _Prepared:
    p = problem
    can = p.mode_of >= 0
    dur = np.where(can, p.mode_duration[np.maximum(p.mode_of, 0)], np.inf)
    overhead = opt.quota_travel * places.unit
    cls, quota = class_quotas(p, overhead)
    return _Prepared(rank_upward(p), can, cls, quota, dur + overhead[:, None])


def place_dispatch(
    problem: Problem,
    ev: Evaluator,
    travel_weight: float = 1.0,
    *,
    places: Places | None = None,
    options: PlaceOptions | None = None,
    noise: FloatArray | None = None,
    _prep: _Prepared | None = None,
) -> Solution | None:
    """One place-aware construction (see the module docstring).

    Parameters
    ----------
    problem : Problem
    ev : Evaluator
        The problem's decoder (its ``waits``; counts one evaluation).
    travel_weight : float
        Seconds of score per second of travel.
    places : Places or None
        :func:`find_places` of the problem (computed when None).
    options : PlaceOptions or None
        ``candidates``, ``quota_travel`` and ``quota_penalty`` are read.
    noise : (T,) float or None
        Added to each task's score (seconds; tie noise).

    Returns
    -------
    Solution or None
        The schedule built, with its decoder state; None when some task
        cannot be placed (a start zone held for good).
    """
    p = problem
    T, A = p.n_tasks, p.n_arms
    if T == 0:
        return None
    opt = options or PlaceOptions()
    pl = places if places is not None else find_places(p)
    pre = _prep if _prep is not None else _prepare(p, pl, opt)
    inst = ev.inst
    ev.evaluations += 1
    st = inst.new_state()
    rel = np.asarray(p.task_release, dtype=float)
    tie = -1e-6 * pre.rank
    if noise is not None:
        tie = tie + noise
    missing = np.array([len(ps) for ps in p.task_preds], dtype=np.int64)
    pred_end = np.zeros(T)
    placed = np.zeros(T, dtype=bool)
    stuck = np.zeros(T, dtype=bool)  # cannot be placed now (a start zone still held)
    used = np.zeros_like(pre.quota)
    free = np.asarray(p.arm_available, dtype=float).copy()  # end of each arm's last task
    last = np.full(A, -1, dtype=np.int64)
    waiting = np.zeros(A, dtype=bool)  # nothing it can place now
    k_best = opt.candidates
    penalty = opt.quota_penalty
    waits = ev.waits
    done = 0
    while done < T:
        arms = np.flatnonzero(~waiting)
        if len(arms) == 0:
            return None
        a = int(arms[np.argmin(free[arms])])
        cand = np.flatnonzero(pre.can[a] & ~placed & ~stuck & (missing == 0))
        if len(cand) == 0:
            waiting[a] = True
            continue
        row = p.setup_row(a, int(last[a]))[cand]
        ready = np.maximum(rel[cand], pred_end[cand])
        cl = pre.cls[cand]
        over = used[a, cl] + pre.charge[a, cand] > pre.quota[a, cl] + 1e-9
        extra = travel_weight * row + tie[cand] + penalty * over
        score = np.maximum(free[a] + row, ready) + extra
        top = (
            np.argpartition(score, k_best)[:k_best] if len(cand) > k_best else np.arange(len(cand))
        )
        best = math.inf
        pick: tuple[int, int, float, float, int, FloatArray] | None = None
        for i in sorted(top.tolist(), key=lambda i: int(cand[i])):
            t = int(cand[i])
            m = int(p.mode_of[a, t])
            S, end, k, w = inst.query(st, t, m, float(ready[i]), chrono=True, waits=waits)
            if not end < math.inf:
                stuck[t] = True
                continue
            if S + extra[i] < best:
                best = S + extra[i]
                pick = (t, m, S, end, k, w)
        if pick is None:
            continue  # its best candidates wait for a start zone: try the others
        t, m, S, end, k, w = pick
        inst.commit(st, t, m, S, end, k, w)
        done += 1
        placed[t] = True
        used[a, pre.cls[t]] += pre.charge[a, t]
        free[a] = end
        last[a] = t
        for s in p.task_succs[t]:
            missing[s] -= 1
            pred_end[s] = max(pred_end[s], end)
        stuck[:] = False
        waiting[:] = False
    order = np.lexsort((np.arange(T), st.t_start)).astype(np.int64)
    return Solution(order, st.t_mode.copy(), float(st.t_end.max()), float(st.t_end.sum()), st)


def place_start(
    problem: Problem,
    ev: Evaluator,
    seed: int = 0,
    *,
    options: PlaceOptions | None = None,
    places: Places | None = None,
    deadline: float = math.inf,
) -> Solution | None:
    """The best of ``options.starts`` place-aware constructions.

    Parameters
    ----------
    problem : Problem
    ev : Evaluator
        The problem's decoder (each construction counts one evaluation).
    seed : int
        Seeds the tie noise of the later constructions.
    options : PlaceOptions or None
    places : Places or None
        :func:`find_places` of the problem (computed when None).
    deadline : float
        ``time.perf_counter()`` after which no construction starts (the
        first always runs).

    Returns
    -------
    Solution or None
        None when no construction places every task.
    """
    opt = options or PlaceOptions()
    p = problem
    if p.n_tasks == 0:
        return None
    pl = places if places is not None else find_places(p)
    pre = _prepare(p, pl, opt)
    rng = np.random.default_rng(seed)
    best: Solution | None = None
    weights = opt.travel_weights
    for i in range(opt.starts):
        if i and time.perf_counter() >= deadline:
            break
        noise = opt.noise * rng.random(p.n_tasks) if i >= len(weights) else None
        sol = place_dispatch(
            p, ev, weights[i % len(weights)], places=pl, options=opt, noise=noise, _prep=pre
        )
        if sol is not None and (best is None or sol.key() < best.key()):
            best = sol
    return best
