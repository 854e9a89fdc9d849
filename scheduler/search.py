"""Search building blocks shared by the solvers.

A *solution* is a list (a topological order of the tasks) plus a mode per
task; :class:`Evaluator` decodes it into a schedule with the placement
kernel (earliest placement of each task in list order, arm gaps used, waits
at zone borders where they help). With a blocking oracle, decoding is
chronological (each task starts no earlier than the one before it in the
list) and the oracle is asked, lazily and cached, about the arms parked at
each start; the detour cost it charges is never less than what the final
schedule needs, because an arm's future tasks all start later (see
``docs/scheduler.md``).

:func:`critical_path` explains a schedule's makespan: the chain of tasks
each of which could not start earlier because of the one before it (a
predecessor, the previous task on the arm, or a zone or tool it had to wait
for). :func:`local_search` improves a solution with moves on that chain.
"""

from __future__ import annotations

import heapq
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from multiarm.errors import InternalError
from multiarm.types import FloatArray, IntArray
from scheduler.kernel import Ctx, State, compile_problem, decode, to_schedule
from scheduler.kernel import place_blocking as kernel_place_blocking
from scheduler.kernel.moves_jit import BEFORE, LIST, MODE, chrono_extend, neighbour_moves
from scheduler.kernel.resume import (
    ResumeWork,
    Snaps,
    chunk_size,
    copy_rows,
    decode_resume,
    new_flags,
    new_snaps,
    new_work,
    resume_chrono,
)
from scheduler.problem import Problem
from scheduler.schedule import Schedule

__all__ = [
    "Evaluator",
    "Solution",
    "critical_path",
    "local_search",
    "priority_order",
    "rank_upward",
]


@dataclass
class Solution:
    """A list and a mode per task, with the makespan it decodes to."""

    order: IntArray
    modes: IntArray
    makespan: float
    secondary: float = 0.0
    state: State | None = None
    built: Schedule | None = field(default=None, repr=False, compare=False)
    """Its schedule, once :meth:`Evaluator.schedule` has built it."""

    def key(self) -> tuple[float, float]:
        """(makespan, secondary): smaller is better."""
        return (self.makespan, self.secondary)


def rank_upward(problem: Problem) -> FloatArray:
    """HEFT upward rank: mean mode duration plus the largest rank of a successor."""
    p = problem
    mean = np.zeros(p.n_tasks)
    np.add.at(mean, p.mode_task, p.mode_duration)
    mean /= np.maximum(np.bincount(p.mode_task, minlength=p.n_tasks), 1)
    rank = mean.copy()
    order = p.topological_order
    for t in reversed(order):
        best = 0.0
        for s in p.task_succs[t]:
            best = max(best, rank[s])
        rank[t] = mean[t] + best
    return rank


def priority_order(
    problem: Problem,
    key: FloatArray | None = None,
    rng: np.random.Generator | None = None,
    noise: float = 0.0,
) -> IntArray:
    """A topological list: among ready tasks, the largest ``key`` first (default:
    the upward rank, i.e. HEFT), earlier release breaking ties. ``noise``
    (relative, with ``rng``) perturbs the keys for randomized restarts."""
    p = problem
    k = rank_upward(p) if key is None else np.asarray(key, dtype=float)
    if noise > 0 and rng is not None:
        k = k * (1.0 + noise * rng.standard_normal(len(k)))
    missing = [len(ps) for ps in p.task_preds]
    heap = [(-k[t], p.task_release[t], t) for t in range(p.n_tasks) if missing[t] == 0]
    heapq.heapify(heap)
    out = []
    while heap:
        _, _, t = heapq.heappop(heap)
        out.append(t)
        for s in p.task_succs[t]:
            missing[s] -= 1
            if missing[s] == 0:
                heapq.heappush(heap, (-k[s], p.task_release[s], s))
    return np.array(out, dtype=np.int64)


def _copy_state(src: State, dst: State) -> None:
    """Every field of ``src`` copied into ``dst`` (arrays of the same shapes)."""
    for a, b in zip(src, dst, strict=True):
        np.copyto(b, a)


class Evaluator:
    """Decodes solutions of one problem and counts the evaluations.

    For re-solving, decoding can start from a ``base`` state (tasks already
    done or running, committed), with overridden ``release`` times, a mask of
    ``allowed`` modes (failed arms) and per-arm times ``arm_lb`` before which
    an arm cannot start; ``frozen`` tasks are never moved by the search.
    """

    def __init__(
        self,
        problem: Problem,
        *,
        waits: bool = True,
        chronological: bool | None = None,
        base: State | None = None,
        release: FloatArray | None = None,
        allowed: np.ndarray | None = None,
        arm_lb: FloatArray | None = None,
        frozen: frozenset[int] = frozenset(),
    ) -> None:
        self.problem = problem
        self.inst = compile_problem(problem)
        self.waits = waits
        self.blocking = problem.blocking is not None
        self.chrono = self.blocking if chronological is None else (chronological or self.blocking)
        self.evaluations = 0
        self.base = base
        self.release = release
        self.allowed = allowed
        self.arm_lb = arm_lb
        self.frozen = frozen
        self.frozen_mask = np.zeros(problem.n_tasks, dtype=np.bool_)
        """``frozen`` as a mask over the tasks (for the compiled moves)."""
        self.frozen_mask[list(frozen)] = True
        self.stop: threading.Event | None = None
        """Set by another thread (a racing exact solver that proved the optimum) to stop."""
        # resumable decoding (evaluate_resume): the anchor's snapshots, and
        # those of the last list decoded, kept until it becomes the anchor
        self._snap_n = -1
        self._every = 1
        self._snaps: Snaps | None = None
        self._scratch: Snaps | None = None
        self._anchor_order: IntArray | None = None
        self._anchor_modes: IntArray | None = None
        self._anchor_sol: Solution | None = None
        self._last_sol: Solution | None = None
        self._last_k = -1
        self._root_state: State | None = None
        self._ctx: Ctx | None = None
        self._work: ResumeWork | None = None
        self._spare: list[State] = []
        """States of recycled solutions (:meth:`recycle`), overwritten by the next decodes."""

    # ---------------------------------------------------------- decoding
    def decode(
        self, order: IntArray, modes: IntArray | None = None, state: State | None = None
    ) -> tuple[bool, State]:
        """Place ``order`` (modes fixed where >= 0, else earliest-finishing).

        Returns (complete, state): ``complete`` is False when some task could
        not be placed (only possible with start zones held for good or a
        parked arm in the way with no detour).
        """
        self.evaluations += 1
        fixed = np.full(self.problem.n_tasks, -1, dtype=np.int64) if modes is None else modes
        if state is None and self.base is not None:
            state = self.base.copy()
        # with a blocking oracle the kernel decodes chronologically and reads
        # the oracle's answers from its compiled table (asking only the new ones)
        code, st = decode(
            self.inst,
            order,
            fixed,
            chrono=self.chrono,
            waits=self.waits,
            state=state,
            release=self.release,
            allowed=self.allowed,
            arm_lb=self.arm_lb,
        )
        return code == 0, st

    def place_blocking(
        self, st: State, t: int, m: int, S0: float
    ) -> tuple[float, float, int, FloatArray, float]:
        """Chronological placement with the oracle's detour cost: (S, end, slot, waits, cost)."""
        return kernel_place_blocking(self.inst, st, t, m, S0, waits=self.waits, arm_lb=self.arm_lb)

    def evaluate(self, order: IntArray, modes: IntArray | None = None) -> Solution | None:
        """Decode and wrap as a :class:`Solution` (None if incomplete)."""
        ok, st = self.decode(order, modes)
        if not ok:
            return None
        return Solution(
            order.copy(),
            st.t_mode.copy(),
            float(st.t_end.max()) if len(st.t_end) else 0.0,
            float(st.t_end.sum()),
            st,
        )

    def evaluate_resume(self, order: IntArray, modes: IntArray | None = None) -> Solution | None:
        """:meth:`evaluate` by chunked decoding (:mod:`scheduler.kernel.resume`),
        starting from the anchor's (:meth:`anchor`) last snapshot before the
        first position where ``order`` or its modes differ from the anchor's:
        only the changed suffix is placed again."""
        n = len(order)
        T = self.problem.n_tasks
        if n != self._snap_n:
            self._every = chunk_size(n)
            # chronological decoding keeps only the flags: a boundary's state
            # is restored from the anchor's complete state (kernel.resume.restore)
            buffer = new_flags if self.chrono else new_snaps
            self._snaps = buffer(self.inst, n, self._every)
            self._scratch = buffer(self.inst, n, self._every)
            self._work = new_work(self.inst, n)
            self._snap_n = n
            self._anchor_order = self._anchor_modes = self._anchor_sol = None
        snaps, scratch, work = self._snaps, self._scratch, self._work
        if snaps is None or scratch is None or work is None:
            raise InternalError("snapshot buffers missing")
        fixed = np.full(T, -1, dtype=np.int64) if modes is None else modes
        if self._ctx is None:
            self._ctx = self.inst.ctx(
                chrono=self.chrono,
                waits=self.waits,
                blocking=self.blocking,
                release=self.release,
                allowed=self.allowed,
                arm_lb=self.arm_lb,
            )
        ao, am = self._anchor_order, self._anchor_modes
        self.evaluations += 1
        state = self._fresh()
        if self.chrono:
            # one compiled call: where to resume, the boundary restored, the decode
            anchor = self._anchor_sol
            held = anchor.state if anchor is not None else None
            code, k_from = resume_chrono(
                self.inst,
                self._ctx,
                self._root(),
                None if ao is None or am is None or held is None else (held, ao, am),
                np.ascontiguousarray(order, dtype=np.int64),
                np.ascontiguousarray(fixed, dtype=np.int64),
                snaps,
                scratch,
                self._every,
                state,
                work,
            )
            st = state
        else:
            k_from = -1
            if ao is not None and am is not None:
                diff = np.flatnonzero(order != ao)
                p0 = int(diff[0]) if len(diff) else n
                dm = np.flatnonzero(fixed[order] != am[order])
                if len(dm):
                    p0 = min(p0, int(dm[0]))
                k = p0 // self._every
                while k > 0 and not snaps.ok[k]:
                    k -= 1
                k_from = k
            if k_from < 0:
                # a snapshot (k_from >= 0) is loaded over the whole state
                _copy_state(self._root(), state)
            code, st = decode_resume(
                self.inst,
                order,
                fixed,
                snaps,
                scratch,
                k_from,
                every=self._every,
                state=state,
                ctx=self._ctx,
            )
        self._last_sol = None
        if code != 0:
            self._spare.append(st)
            return None
        sol = Solution(
            order.copy(),
            st.t_mode.copy(),
            float(st.t_end.max()) if len(st.t_end) else 0.0,
            float(st.t_end.sum()),
            st,
        )
        self._last_sol, self._last_k = sol, k_from
        return sol

    def _root(self) -> State:
        """The state every list is decoded from (the base, or the empty
        schedule); never changed."""
        if self._root_state is None:
            self._root_state = self.base if self.base is not None else self.inst.new_state()
        return self._root_state

    def _fresh(self) -> State:
        """A state to decode into: a recycled one (:meth:`recycle`) or a new one."""
        return self._spare.pop() if self._spare else self.inst.new_state()

    def recycle(self, sol: Solution) -> None:
        """Let :meth:`evaluate_resume` decode into the state of ``sol``, a
        solution the caller drops (it must hold no other reference to it):
        ``sol`` loses its state. The anchor (:meth:`anchor`) is never
        recycled; a solution without a state is left alone.

        Parameters
        ----------
        sol : Solution
        """
        st = sol.state
        if st is None or sol is self._anchor_sol or st is self._root_state or st is self.base:
            return
        if sol is self._last_sol:
            self._last_sol = None  # it can no longer become the anchor
        sol.state = None
        if len(self._spare) < 4:
            self._spare.append(st)

    def anchor(self, sol: Solution) -> bool:
        """Make ``sol`` the list that :meth:`evaluate_resume` resumes from.

        It takes only for the solution :meth:`evaluate_resume` returned last
        (its snapshots are kept until the next call); returns whether it took
        (otherwise the next call decodes from the start)."""
        if sol is self._anchor_sol:
            return True
        if sol is not self._last_sol or self._snaps is None or self._scratch is None:
            self._anchor_order = self._anchor_modes = self._anchor_sol = None
            return False
        lo = self._last_k + 1
        copy_rows(self._scratch, self._snaps, lo, len(self._snaps.ok))
        self._anchor_order, self._anchor_modes, self._anchor_sol = sol.order, sol.modes, sol
        return True

    def schedule(self, sol: Solution) -> Schedule:
        """The schedule of a decoded solution (built once, then kept on it)."""
        if sol.built is not None:
            return sol.built
        st = sol.state
        if st is None:
            ok, st = self.decode(sol.order, sol.modes)
            if not ok:
                raise InternalError("a decoded solution no longer decodes")
        sched: Schedule = to_schedule(self.inst, st)
        sol.built = sched
        return sched


class Budget:
    """When an improvement loop must stop: a wall-clock ``deadline``, a number
    of decodes (``max_evaluations``, counted on ``ev``), and the fixed cost of
    one iteration (``prep``, measured as it goes) that must still fit."""

    def __init__(self, ev: Evaluator, deadline: float, max_evaluations: int | None) -> None:
        self.ev = ev
        self.deadline = deadline
        self.limit = math.inf if max_evaluations is None else ev.evaluations + max_evaluations
        self.prep = 0.0

    def spent(self) -> bool:
        """Whether the deadline, the work limit or a stop request is reached."""
        stop = self.ev.stop
        return (
            time.perf_counter() >= self.deadline
            or self.ev.evaluations >= self.limit
            or (stop is not None and stop.is_set())
        )

    def room_for_iteration(self) -> bool:
        return not self.spent() and time.perf_counter() + self.prep <= self.deadline


# ------------------------------------------------------------ critical path


def critical_path(
    problem: Problem, sched: Schedule, rng: np.random.Generator | None = None, tol: float = 1e-6
) -> list[tuple[int, str, int]]:
    """The chain that explains the makespan, last task first.

    Each entry is ``(task, reason, by)``: ``task`` could not start (or pass a
    zone border) earlier because of ``by``, for ``reason`` ``"pred"``,
    ``"arm"`` (previous task on the arm, with the travel), ``"resource"`` (a
    zone or tool ``by`` held) — or ``"release"`` (``by = -1``) where the
    chain starts.
    """
    p = problem
    T = p.n_tasks
    if T == 0:
        return []
    shapes = p.shapes
    arms = sched.arms(p).tolist()
    seqs = sched.sequences(p)
    start, end, mode = sched.start.tolist(), sched.end.tolist(), sched.mode.tolist()
    prev_on_arm = [-1] * T
    for seq in seqs:
        for i in range(1, len(seq)):
            prev_on_arm[seq[i]] = seq[i - 1]
    # interval ends per resource: end time -> tasks ending there
    ends: dict[int, dict[float, list[int]]] = {}
    starts_of: list[list[tuple[int, float]]] = [[] for _ in range(T)]
    for t in range(T):
        sh = shapes[mode[t]]
        if not (sh.exclusive or sh.moves or sh.tools):
            continue
        ivs = sh.intervals(start[t], sched.waits[t])
        ivs += [(r, start[t], end[t]) for r in sh.tools]
        for r, s, e in ivs:
            ends.setdefault(r, {}).setdefault(round(e, 6), []).append(t)
            starts_of[t].append((r, s))

    def reasons(t: int) -> list[tuple[str, int]]:
        S = start[t]
        out: list[tuple[str, int]] = []
        for q in p.task_preds[t]:
            if abs(end[q] - S) <= tol:
                out.append(("pred", q))
        q = prev_on_arm[t]
        if q >= 0 and abs(end[q] + p.setup_time(arms[t], q, t) - S) <= tol:
            out.append(("arm", q))
        for r, s in starts_of[t]:
            for x in ends.get(r, {}).get(round(s, 6), []):
                if x != t and arms[x] != arms[t]:
                    out.append(("resource", x))
        return out

    last = int(np.argmax(sched.end))
    chain: list[tuple[int, str, int]] = []
    seen = set()
    t = last
    while t not in seen:
        seen.add(t)
        rs = reasons(t)
        if not rs:
            chain.append((t, "release", -1))
            break
        pick = rs[int(rng.integers(len(rs)))] if rng is not None and len(rs) > 1 else rs[0]
        chain.append((t, pick[0], pick[1]))
        t = pick[1]
    return chain


# --------------------------------------------------------------- local search


def _move_before(
    order: IntArray, pos: IntArray, t: int, x: int, preds: tuple[tuple[int, ...], ...]
) -> IntArray | None:
    """``order`` with ``t`` moved just before ``x`` (None if that breaks precedence)."""
    i, j = int(pos[t]), int(pos[x])
    if i <= j:
        return None
    for q in preds[t]:
        if pos[q] >= j:
            return None
    out = np.empty_like(order)
    out[:j] = order[:j]
    out[j] = t
    out[j + 1 : i + 1] = order[j:i]
    out[i + 1 :] = order[i + 1 :]
    return out


def _move_after(
    order: IntArray, pos: IntArray, x: int, t: int, succs: tuple[tuple[int, ...], ...]
) -> IntArray | None:
    """``order`` with ``x`` moved just after ``t`` (None if that breaks precedence)."""
    j, i = int(pos[x]), int(pos[t])
    if j >= i:
        return None
    for s in succs[x]:
        if pos[s] <= i:
            return None
    out = np.empty_like(order)
    out[:j] = order[:j]
    out[j:i] = order[j + 1 : i + 1]
    out[i] = x
    out[i + 1 :] = order[i + 1 :]
    return out


_REASON_CODE = {"pred": 0, "arm": 1, "resource": 2, "release": 3, "list": LIST}
_REASON_NAME = ("pred", "arm", "resource", "release", "list")


def _chrono_chain(
    ev: Evaluator,
    st: State,
    order: IntArray,
    pos: IntArray,
    chain: list[tuple[int, str, int]],
    rng: np.random.Generator,
    max_links: int | None = None,
) -> list[tuple[int, str, int]]:
    """The critical chain of a chronological decode, continued through the list.

    Chronological decoding (a blocking oracle) starts every task no earlier
    than the task before it in the list. Where the compiled chain ends
    (``"release"``) at a task that starts later than its release, it was
    held there by that order: the chain goes on with reason ``"list"``, by
    the task before it in the list that starts at the same time, and from
    there on with that task's own reasons (several: one drawn from ``rng``).
    Without this link the chain of a chronological plan stops after a few
    tasks, and the moves that would start the held task earlier (before
    the one that held it, in the list) are never tried. Compiled:
    :func:`scheduler.kernel.moves_jit.chrono_extend`.
    """
    arrays = (
        np.array([t for t, _r, _b in chain], dtype=np.int64),
        np.array([_REASON_CODE[r] for _t, r, _b in chain], dtype=np.int64),
        np.array([b for _t, _r, b in chain], dtype=np.int64),
    )
    ts, kinds, bys = chrono_extend(
        ev.inst, st, order, pos, arrays, rng, release=ev.release, max_links=max_links
    )
    return [
        (int(t), _REASON_NAME[int(k)], int(b))
        for t, k, b in zip(ts.tolist(), kinds.tolist(), bys.tolist(), strict=True)
    ]


def _moves(
    ev: Evaluator, sol: Solution, rng: np.random.Generator
) -> tuple[IntArray, IntArray, IntArray]:
    """The compiled moves of :func:`neighbours` as arrays (kind, a, b)."""
    st = sol.state
    if st is None:
        ok, st = ev.decode(sol.order, sol.modes)
        if not ok:
            raise InternalError("a decoded solution no longer decodes")
        sol.state = st
    if len(st.t_start) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    return neighbour_moves(
        ev.inst,
        st,
        sol.order,
        sol.modes,
        rng,
        chrono=ev.chrono,
        frozen=ev.frozen_mask,
        allowed=ev.allowed,
        release=ev.release,
    )


def _apply(
    ev: Evaluator, sol: Solution, pos: IntArray, kind: int, a: int, b: int
) -> tuple[IntArray, IntArray]:
    """The (order, modes) of one move of :func:`_moves` on ``sol``."""
    p = ev.problem
    if kind == MODE:
        modes = sol.modes.copy()
        modes[a] = b
        return sol.order, modes
    if kind == BEFORE:
        o = _move_before(sol.order, pos, a, b, p.task_preds)
    else:
        o = _move_after(sol.order, pos, a, b, p.task_succs)
    if o is None:  # pragma: no cover - checked by the compiled moves
        raise InternalError("a checked move broke precedence")
    return o, sol.modes


def _positions(ev: Evaluator, order: IntArray) -> IntArray:
    """Each task's position in ``order`` (-1: not in it)."""
    pos = np.full(ev.problem.n_tasks, -1, dtype=np.int64)
    pos[order] = np.arange(len(order))
    return pos


def neighbours(
    ev: Evaluator, sol: Solution, rng: np.random.Generator
) -> list[Callable[[], tuple[IntArray, IntArray]]]:
    """Candidate moves around the critical chain of ``sol``, shuffled
    (frozen tasks and disallowed modes left alone): re-assign a chain task,
    or the task that held it on a zone or tool; move a chain task just
    before the task that held it (arm, resource or list), or that one just
    after it. Each move is a function that builds its (order, modes) when
    called: a first-improvement search builds only the few it decodes. The
    chain and the moves are computed by the compiled
    :func:`scheduler.kernel.moves_jit.neighbour_moves`."""
    kinds, a_s, b_s = _moves(ev, sol, rng)
    pos = _positions(ev, sol.order)

    def move(k: int, a: int, b: int) -> Callable[[], tuple[IntArray, IntArray]]:
        return lambda: _apply(ev, sol, pos, k, a, b)

    return [
        move(k, a, b) for k, a, b in zip(kinds.tolist(), a_s.tolist(), b_s.tolist(), strict=True)
    ]


def perturb(
    ev: Evaluator, sol: Solution, rng: np.random.Generator, strength: int
) -> tuple[IntArray, IntArray]:
    """A random kick: ``strength`` random mode changes and list swaps that keep precedence."""
    p = ev.problem
    order = sol.order.copy()
    modes = sol.modes.copy()
    for _ in range(strength):
        if rng.random() < 0.5:
            t = int(order[int(rng.integers(len(order)))]) if len(order) else 0
            ms = [m for m in p.task_modes[t] if ev.allowed is None or ev.allowed[m]]
            if len(ms) > 1 and t not in ev.frozen:
                modes[t] = ms[int(rng.integers(len(ms)))]
        else:
            i = int(rng.integers(max(len(order) - 1, 1)))
            if i + 1 < len(order):
                a, b = int(order[i]), int(order[i + 1])
                if a not in p.task_preds[b]:
                    order[i], order[i + 1] = b, a
    return order, modes


def local_search(
    ev: Evaluator,
    start: Solution,
    deadline: float,
    rng: np.random.Generator,
    *,
    on_improve: Callable[[Solution], None] | None = None,
    lower: float = 0.0,
    max_no_improve: int = 200,
    max_evaluations: int | None = None,
) -> Solution:
    """Iterated local search on the critical path until ``deadline``.

    First improvement over shuffled critical-path moves (re-assign a critical
    task or the task that held it up; move a task before the one that held
    it up, or that one after it). With chronological decoding the chain goes
    on through the list where the list held a task back (:func:`_chrono_chain`). Equal makespan with a smaller sum of ends
    is accepted too. At a local optimum, the best solution is kicked with a
    few random moves (strength grows while nothing improves). Stops at
    ``deadline`` or after ``max_evaluations`` decodes (a work limit makes the
    result depend on the seed only).
    """
    best = cur = start
    stall = 0
    strength = 2
    budget = Budget(ev, deadline, max_evaluations)
    out_of_budget = budget.spent
    if not ev.anchor(start) and not out_of_budget():
        # decode the start once in chunks, so that moves resume from its prefix
        again = ev.evaluate_resume(start.order, start.modes)
        if again is not None and again.key() <= start.key():
            best = cur = again
            ev.anchor(cur)
    while budget.room_for_iteration() and best.makespan > lower + 1e-9:
        tp = time.perf_counter()
        improved = False
        kinds, a_s, b_s = _moves(ev, cur, rng)
        pos = _positions(ev, cur.order)
        budget.prep = time.perf_counter() - tp
        for k, a, b in zip(kinds.tolist(), a_s.tolist(), b_s.tolist(), strict=True):
            if out_of_budget():
                break
            order, modes = _apply(ev, cur, pos, k, a, b)
            cand = ev.evaluate_resume(order, modes)
            if cand is None:
                continue
            if cand.key() < cur.key():
                cur = cand
                ev.anchor(cur)
                improved = True
                break
            ev.recycle(cand)  # its state is decoded over by the next move
        if cur.key() < best.key():
            best = cur
            stall = 0
            strength = 2
            if on_improve is not None:
                on_improve(best)
        elif not improved:
            stall += 1
            if stall > max_no_improve:
                break
            strength = min(strength + 1, 2 + ev.problem.n_tasks // 10)
            order, modes = perturb(ev, best, rng, strength)
            kicked = ev.evaluate_resume(order, modes)
            if kicked is not None:
                cur = kicked
                ev.anchor(cur)
    return best
