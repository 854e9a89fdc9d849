"""A plan re-timed under exact separation: the reference for the space grid.

The compile keeps moving arms apart outside the SDL zones with a space grid
(:mod:`workcell.geometry.reach`, S2.12's coarse-grid compromise): two arms
never share a block at the same time, even where their bodies would pass
each other with room to spare. :func:`retime_exact` measures what that
conservatism costs. It keeps a plan's assignment, each arm's task order and
modes, and gives every task the earliest start at which

* the arms' **timed motions never touch**: each arm's body (its collision
  shapes, :meth:`workcell.arms.Arm.shape_transforms`) standing at its start
  pose, travelling to a task (the move the coordinator sends,
  ``arm.move(q_end, q_start)``, over ``[start - travel, start)``), executing
  the compiled mode's joint trajectory (with the plan's waits at its zone
  borders), and parked at the task's end pose until it leaves again,
  checked pairwise against every other arm's timeline with FCL;
* the precedences, part releases and each arm's travel hold;
* the SDL zones, the tools and the start zones hold; the space-grid blocks
  do not (:func:`inert_grid`: the same compile with every grid zone made
  a shared zone without moves, so a plan may still make an arm wait at a
  block's border, but nothing forces it to).

The result is a schedule of :func:`inert_grid` of the compile, so
:func:`scheduler.validate` checks it and :func:`workcell.simulate` executes
it with the coordinator's geometric check off
(``SimOptions(geometry_guard=False)``): only the plan keeps the arms apart,
and the independent safety monitor confirms no contact. Each task keeps its
waits at the borders, or drops those at grid borders (keeping the SDL ones),
whichever ends it earlier.

The geometric check
-------------------
Dense sampling with a conservative margin, not FCL's continuous collision
(``notes/deps.md``: FCL's CCD handles one rigid body, misses thin contacts
with the conservative-advancement solver and interpolates rotations
linearly, where an arm's links follow its joints). Every motion is sampled
so that between consecutive samples no point of any shape moves more than
``padding`` (``arm.displacement_bound``, as the zone sweep does,
:func:`workcell.geometry.sample_trajectory`), and every shape is grown by
``padding``. At any time ``t`` between samples ``i`` and ``i + 1`` the body
is inside the grown shapes at both samples, so sample ``i`` stands for its
arm over ``[t_{i-1}, t_{i+1}]``. Two samples of two arms whose grown shapes
FCL finds touching forbid every shift that makes their time spans overlap;
a start outside all forbidden shifts keeps the arms apart at every instant,
not only at the samples (two arms that pass within ``2 padding`` of each
other may be kept apart needlessly; nothing closer is let through).
Sample pairs go to FCL only after two pre-tests that never drop a touching
pair (boxes around each sample's shapes, then capsules holding the shapes),
coarse pairs first, and a pair whose forbidden shifts the contacts found so
far already forbid is not decided at all: the forbidden set is the same.

How starts are found
--------------------
Left shifts to a fixed point (a semi-active schedule): tasks are visited in
the order of their current starts, and each moves to the earliest start at
or after its lower bound (release, predecessors, its arm's previous task
plus travel) that no motion, parked pose, zone use or tool use of another
arm forbids, the other arms at their current times. Passes repeat until no
start moves by more than ``settle``. Every state visited is free of
contacts; from a plan that is free of contacts under this check, no task
can end later than it did, so the re-timed makespan is at most the plan's.
(A plan that touches under this check, within ``2 padding``, has the
touching task moved to its first free start, later if need be.) The
forbidden shifts of each pair of motions are computed once, for the range
of shifts asked, and cached.

Examples
--------
>>> from workcell import CompileOptions, compile_cell, load_example
>>> from scheduler import TreeOptions, solve
>>> cc = compile_cell(load_example("supersigma"), options=CompileOptions(grid=0.6))
>>> plan = solve(cc, "tree", seed=0, options=TreeOptions(max_evaluations=50)).plan
>>> exact = retime_exact(cc, plan)
>>> exact.makespan <= plan.makespan
True
>>> exact.plan.validate() == exact.makespan
True
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from multiarm.errors import UsageError, ValidationError
from multiarm.types import BoolArray, FloatArray, IntArray
from scheduler import Plan, Schedule, validate
from workcell.arms.base import LinkShape
from workcell.compile import CompiledCell
from workcell.geometry import CollisionWorld, sample_trajectory
from workcell.geometry._zone_sweep_jit import _segment_distance
from workcell.geometry.reach import grid_block

__all__ = ["ExactRetiming", "inert_grid", "retime_exact"]

_TOL = 1e-9


@dataclass(frozen=True, slots=True)
class ExactRetiming:
    """A plan re-timed under exact separation (:func:`retime_exact`).

    Attributes
    ----------
    compiled : CompiledCell
        :func:`inert_grid` of the compile given: :attr:`schedule` is a
        schedule of its problem (validate and simulate it with this one; the
        grid compile would make the arms wait for the blocks again).
    schedule : scheduler.Schedule
        The same modes and task orders, re-timed.
    grid_makespan : float
        The makespan of the plan given (seconds).
    passes : int
        Left-shift passes made (the last moved no start by more than ``settle``).
    motion_pairs : int
        Pairs of timed motions whose forbidden shifts were computed.
    fcl_checks : int
        Configuration pairs FCL decided (after the box and capsule pre-tests).
    padding : float
        Metres: sampling bound and growth of every shape.
    unresolved : tuple of str
        Tasks for which every start at or after their lower bound touches
        another arm under the padded check (an arm parked within ``2
        padding`` of another's path that neither can leave): they keep the
        plan's start (or their lower bound), and the safety monitor judges
        the real clearance. Empty when the whole plan is separated.
    """

    compiled: CompiledCell
    schedule: Schedule
    grid_makespan: float
    passes: int
    motion_pairs: int
    fcl_checks: int
    padding: float
    unresolved: tuple[str, ...] = ()

    @property
    def makespan(self) -> float:
        """The re-timed makespan, seconds."""
        return self.schedule.makespan

    @property
    def plan(self) -> Plan:
        """The re-timed schedule bound to :attr:`compiled`'s problem."""
        return Plan(self.compiled.problem, self.schedule)

    @property
    def ratio(self) -> float:
        """Re-timed makespan over the plan's (1.0 when both are 0)."""
        if self.grid_makespan <= 0:
            return 1.0
        return self.makespan / self.grid_makespan


@dataclass(frozen=True, slots=True)
class _Motion:
    """Samples of one arm's motion, times relative to its origin (the task start)."""

    arm: int
    t: FloatArray  # (M,) increasing
    lo: FloatArray  # (M,) the span each sample stands for
    hi: FloatArray
    tf: FloatArray  # (M, S, 4, 4) shape poses
    p0: FloatArray  # (M, S, 3) ends of the segments of capsules holding the shapes
    p1: FloatArray
    box: FloatArray  # (2, 3) bounding box of every grown shape
    boxes: FloatArray  # (M, 2, 3) the same per sample


def _earliest(lb: float, blocked: list[tuple[float, float]]) -> float:
    """The smallest ``s >= lb`` inside no open interval of ``blocked``.

    Open intervals: a start where one forbidden interval ends and the next
    begins is free (touching is fine, as in :func:`scheduler.validate`).
    """
    s = lb
    for lo, hi in sorted(blocked):
        if lo >= s - _TOL:  # sorted by lo: no later interval holds s either
            break
        if hi > s:
            s = hi
    return s


def _capsules(shapes: Sequence[LinkShape]) -> tuple[FloatArray, FloatArray]:
    """Local segment ends (S, 2, 3) and radii (S,) of capsules holding the shapes
    (a box in the capsule along its longest side)."""
    ends = np.zeros((len(shapes), 2, 3))
    rad = np.zeros(len(shapes))
    for i, sh in enumerate(shapes):
        size = np.asarray(sh.size, dtype=float)
        if sh.kind in ("capsule", "cylinder"):
            ends[i, :, 2] = (-size[1] / 2, size[1] / 2)
            rad[i] = size[0] if sh.kind == "capsule" else math.hypot(size[0], 0.0)
        elif sh.kind == "sphere":
            rad[i] = size[0]
        elif sh.kind == "box":
            k = int(np.argmax(size))
            ends[i, :, k] = (-size[k] / 2, size[k] / 2)
            rad[i] = float(np.linalg.norm(np.delete(size, k))) / 2
        else:
            raise ValidationError(f"shape {sh.name!r}: unknown shape kind {sh.kind!r}")
    return ends, rad


@njit(cache=True)
def _capsules_meet(
    p0x: FloatArray,
    p1x: FloatArray,
    rx: FloatArray,
    bx: FloatArray,
    p0y: FloatArray,
    p1y: FloatArray,
    ry: FloatArray,
    by: FloatArray,
    ci: IntArray,
    cj: IntArray,
) -> BoolArray:  # pragma: no cover - compiled
    """(P,) bool: some capsule of sample ``ci[k]`` of x meets one of sample ``cj[k]``
    of y (boxes ``bx``, ``by`` (M, 2, 3) around each sample's capsules first)."""
    out = np.zeros(len(ci), dtype=np.bool_)
    for k in range(len(ci)):
        i, j = ci[k], cj[k]
        apart = False
        for d in range(3):
            if bx[i, 1, d] < by[j, 0, d] or by[j, 1, d] < bx[i, 0, d]:
                apart = True
                break
        if apart:
            continue
        for s in range(p0x.shape[1]):
            for u in range(p0y.shape[1]):
                if _segment_distance(p0x[i, s], p1x[i, s], p0y[j, u], p1y[j, u], 1e-18) <= (
                    rx[s] + ry[u] + 1e-6
                ):
                    out[k] = True
                    break
            if out[k]:
                break
    return out


def _runs(j0: IntArray, j1: IntArray, n: int) -> tuple[IntArray, IntArray]:
    """Pairs ``(i, j)`` with ``j0[k] <= j < j1[k]`` and ``i = k mod n``."""
    ln = np.maximum(np.asarray(j1) - np.asarray(j0), 0)
    total = int(ln.sum())
    ii = np.repeat(np.arange(len(ln), dtype=np.int64) % n, ln)
    if not total:
        return ii, ii
    starts = np.repeat(np.asarray(j0, dtype=np.int64), ln)
    offs = np.arange(total, dtype=np.int64) - np.repeat(np.cumsum(ln) - ln, ln)
    return ii, starts + offs


def _covered(lo: FloatArray, hi: FloatArray, hlo: FloatArray, hhi: FloatArray) -> BoolArray:
    """(P,) bool: open interval ``(lo, hi)`` lies inside the union of the ``(hlo, hhi)``."""
    order = np.argsort(hlo, kind="stable")
    ulo: list[float] = []
    uhi: list[float] = []
    for a, b in zip(hlo[order].tolist(), hhi[order].tolist(), strict=True):
        if ulo and a < uhi[-1]:  # overlapping, not merely touching
            uhi[-1] = max(uhi[-1], b)
        else:
            ulo.append(a)
            uhi.append(b)
    la, ha = np.array(ulo), np.array(uhi)
    k = np.searchsorted(la, lo, side="right") - 1
    ok = k >= 0
    kk = np.clip(k, 0, None)
    out: BoolArray = ok & (la[kk] <= lo) & (ha[kk] >= hi)
    return out


class _Checker:
    """Sampled motions, their pairwise contacts (cached) and the FCL world."""

    def __init__(self, cc: CompiledCell, padding: float) -> None:
        self.cc = cc
        self.arms = cc.cell.arms
        self.pad = padding
        self.world = CollisionWorld()
        for arm in self.arms:
            self.world.add_arm(arm, padding=padding)
        caps = [_capsules(arm.shapes) for arm in self.arms]
        self.cap_ends = [e for e, _ in caps]
        self.cap_r = [r + padding for _, r in caps]
        self.motions: dict[Any, _Motion] = {}
        self.pairs: dict[tuple[Any, Any], tuple[float, float, IntArray, IntArray]] = {}
        self.fcl_checks = 0

    def _make(self, a: int, t: FloatArray, q: FloatArray) -> _Motion:
        arm = self.arms[a]
        tf = np.ascontiguousarray(arm.shape_transforms(q), dtype=float)
        ends = self.cap_ends[a]  # (S, 2, 3)
        rot, c = tf[:, :, :3, :3], tf[:, :, :3, 3]
        p0 = np.ascontiguousarray(np.einsum("msij,sj->msi", rot, ends[:, 0]) + c)
        p1 = np.ascontiguousarray(np.einsum("msij,sj->msi", rot, ends[:, 1]) + c)
        r = self.cap_r[a][None, :, None]
        boxes = np.stack(
            [(np.minimum(p0, p1) - r).min(axis=1), (np.maximum(p0, p1) + r).max(axis=1)], axis=1
        )
        box = np.stack([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])
        lo = np.concatenate([t[:1], t[:-1]])
        hi = np.concatenate([t[1:], t[-1:]])
        return _Motion(a, t, lo, hi, tf, p0, p1, box, boxes)

    def pose(self, key: Any, a: int, q: FloatArray) -> _Motion:
        m = self.motions.get(key)
        if m is None:
            qq = np.asarray(q, dtype=float)[None, :]
            m = self.motions[key] = self._make(a, np.zeros(1), qq)
        return m

    def motion(
        self, key: Any, a: int, traj: Any, shift: float, waits: list[tuple[float, float]]
    ) -> _Motion:
        """A trajectory from relative time ``shift``, pausing ``w`` at each border ``(b, w)``."""
        m = self.motions.get(key)
        if m is not None:
            return m
        arm = self.arms[a]
        tau, q = sample_trajectory(arm, traj, padding=self.pad)
        tau = np.asarray(tau, dtype=float)
        q = np.asarray(q, dtype=float)
        if waits:
            extra = np.array([b for b, _ in waits], dtype=float)
            new = extra[~np.isin(extra, tau)]
            if len(new):
                tau = np.concatenate([tau, new])
                q = np.concatenate([q, np.asarray(traj.sample(new), dtype=float)])
                order = np.argsort(tau, kind="stable")
                tau, q = tau[order], q[order]
            rel = tau.copy()
            ts, qs = [], []
            done = 0.0
            wl = sorted(waits)
            k = 0
            for i in range(len(tau)):
                x = float(tau[i])
                while k < len(wl) and wl[k][0] < x:
                    done += wl[k][1]
                    k += 1
                if k < len(wl) and wl[k][0] == x and wl[k][1] > 0:
                    ts.append(x + done)
                    qs.append(q[i])
                    done += wl[k][1]
                    k += 1
                rel[i] = x + done
                ts.append(rel[i])
                qs.append(q[i])
            tau, q = np.array(ts, dtype=float), np.array(qs, dtype=float)
        if tau[-1] + shift < -1e-9:  # a travel shorter than its setup:
            tau = np.append(tau, -shift)  # the arm then stands at the task's start
            q = np.concatenate([q, q[-1:]])
        m = self.motions[key] = self._make(a, tau + shift, q)
        return m

    def contacts(
        self, kx: Any, ky: Any, dmin: float = -math.inf, dmax: float = math.inf
    ) -> tuple[IntArray, IntArray]:
        """Sample indices ``(i, j)`` at which motions ``kx`` and ``ky`` touch.

        Only pairs whose forbidden shifts ``(y.lo[j] - x.hi[i], y.hi[j] -
        x.lo[i])`` meet ``[dmin, dmax]`` are decided (and remembered, so a
        wider range later decides only the new pairs); the answer may hold
        touching pairs outside the range too.
        """
        got = self.pairs.get((kx, ky))
        if got is not None and got[0] <= dmin and got[1] >= dmax:
            return got[2], got[3]
        x, y = self.motions[kx], self.motions[ky]
        cmin, cmax = (got[0], got[1]) if got is not None else (math.inf, -math.inf)
        nmin, nmax = min(cmin, dmin), max(cmax, dmax)  # the hull: decided ranges stay one interval
        hi_i = np.zeros(0, dtype=np.int64)
        hi_j = np.zeros(0, dtype=np.int64)
        if got is not None:
            hi_i, hi_j = got[2], got[3]
        if np.any(x.box[1] < y.box[0]) or np.any(y.box[1] < x.box[0]):
            ci = cj = hi_i[:0]
        else:  # y.lo and y.hi increase: the wanted j of each i are a run (two runs
            # when a decided range is cut out of it)
            j0 = np.searchsorted(y.hi, nmin + x.lo, side="right")
            j1 = np.searchsorted(y.lo, nmax + x.hi, side="left")
            if got is not None:
                k0 = np.clip(np.searchsorted(y.hi, cmin + x.lo, side="right"), j0, None)
                k1 = np.clip(np.searchsorted(y.lo, cmax + x.hi, side="left"), None, j1)
                k1 = np.maximum(k1, k0)
                ci, cj = _runs(np.concatenate([j0, k1]), np.concatenate([k0, j1]), len(x.t))
            else:
                ci, cj = _runs(j0, j1, len(x.t))
        if len(ci):
            # coarse pairs first; a pair whose forbidden shifts the contacts found
            # so far already forbid cannot change the answer and is not decided
            for stride in (16, 4, 1):
                if not len(ci):
                    break
                pick = (ci % stride == 0) & (cj % stride == 0)
                if len(hi_i):
                    covered = _covered(
                        y.lo[cj] - x.hi[ci],
                        y.hi[cj] - x.lo[ci],
                        y.lo[hi_j] - x.hi[hi_i],
                        y.hi[hi_j] - x.lo[hi_i],
                    )
                    pick &= ~covered
                    rest = ~covered & ~pick
                else:
                    rest = ~pick
                pi, pj = ci[pick], cj[pick]
                near = _capsules_meet(
                    x.p0,
                    x.p1,
                    self.cap_r[x.arm],
                    x.boxes,
                    y.p0,
                    y.p1,
                    self.cap_r[y.arm],
                    y.boxes,
                    pi,
                    pj,
                )
                pi, pj = pi[near], pj[near]
                if len(pi):
                    hit = self._fcl(x, y, np.column_stack([pi, pj]))
                    hi_i = np.concatenate([hi_i, pi[hit]])
                    hi_j = np.concatenate([hi_j, pj[hit]])
                ci, cj = ci[rest], cj[rest]
        hi_i, hi_j = hi_i.astype(np.int64), hi_j.astype(np.int64)
        self.pairs[(kx, ky)] = (nmin, nmax, hi_i, hi_j)
        return hi_i, hi_j

    def _fcl(self, x: _Motion, y: _Motion, pairs: IntArray) -> BoolArray:
        self.fcl_checks += len(pairs)
        na, nb = self.arms[x.arm].name, self.arms[y.arm].name
        return self.world.collide_configurations(na, x.tf, nb, y.tf, pairs)


@dataclass(slots=True)
class _Seg:
    """One piece of an arm's timeline: a motion at an offset, or a pose held over [t0, t1)."""

    key: Any
    offset: float
    t0: float
    t1: float
    moving: bool


class _Retimer:
    def __init__(
        self, free: CompiledCell, schedule: Schedule, padding: float, margin: float
    ) -> None:
        p = self.p = free.problem
        self.free = free
        self.margin = margin
        self.chk = _Checker(free, padding)
        T = self.T = p.n_tasks
        self.arm: list[int] = schedule.arms(p).tolist()
        self.mode: list[int] = schedule.mode.tolist()
        self.start: list[float] = schedule.start.astype(float).tolist()
        self.waits: list[FloatArray] = [np.array(w, dtype=float) for w in schedule.waits]
        self.shapes = p.shapes
        self.unresolved: set[int] = set()
        # the waits kept when a task drops the ones at grid borders: those at SDL borders
        grid = [grid_block(n) is not None for n in p.zone_names]
        self.sdl_border: list[BoolArray] = []
        for t in range(T):
            m = self.mode[t]
            sdl = {float(p.win_start[w]) for w in p.mode_windows[m] if not grid[int(p.win_zone[w])]}
            self.sdl_border.append(np.array([b in sdl for b in p.mode_borders(m)], dtype=bool))
        self.seqs = [sorted(seq, key=lambda t: (self.start[t], t)) for seq in schedule.sequences(p)]
        self.pos = {t: (a, k) for a, seq in enumerate(self.seqs) for k, t in enumerate(seq)}
        self.setup = [0.0] * T
        self.travel: dict[int, Any] = {}
        arms = free.cell.arms
        for a, seq in enumerate(self.seqs):
            prev = -1
            q = np.asarray(free.cell.start[a], dtype=float)
            for t in seq:
                cm = free.modes[self.mode[t]]
                self.setup[t] = float(p.setup_time(a, prev, t))
                self.travel[t] = arms[a].move(q, cm.q_start, arms[a].interpolation)
                prev, q = t, np.asarray(cm.q_end, dtype=float)

    # ------------------------------------------------------------ timelines
    def length(self, t: int) -> float:
        return self.shapes[self.mode[t]].length(self.waits[t])

    def end(self, t: int) -> float:
        return self.start[t] + self.length(t)

    def task_key(self, t: int) -> Any:
        return ("task", t, tuple(self.waits[t].tolist()))

    def _ensure(self, t: int) -> None:
        a = self.arm[t]
        cm = self.free.modes[self.mode[t]]
        borders = self.p.mode_borders(self.mode[t])
        w = self.waits[t].tolist()
        waits = [(b, x) for b, x in zip(borders, w, strict=True) if x > 0]
        self.chk.motion(self.task_key(t), a, cm.trajectory, 0.0, waits)
        if self.setup[t] > 0:
            self.chk.motion(("travel", t), a, self.travel[t], -self.setup[t], [])
        self.chk.pose(("end", t), a, cm.q_end)

    def timeline(self, a: int) -> list[_Seg]:
        out: list[_Seg] = []
        prev_end, pose = 0.0, ("start", a)
        self.chk.pose(pose, a, self.free.cell.start[a])
        for t in self.seqs[a]:
            self._ensure(t)
            s = self.start[t]
            dep = s - self.setup[t]
            out.append(_Seg(pose, 0.0, prev_end, dep, False))
            if self.setup[t] > 0:
                out.append(_Seg(("travel", t), s, dep, s, True))
            out.append(_Seg(self.task_key(t), s, s, self.end(t), True))
            prev_end, pose = self.end(t), ("end", t)
        out.append(_Seg(pose, 0.0, prev_end, math.inf, False))
        return out

    # ------------------------------------------------------------ one task
    def lower_bound(self, t: int) -> float:
        a, k = self.pos[t]
        p = self.p
        lb = float(p.task_release[t])
        for q in p.task_preds[t]:
            lb = max(lb, self.end(int(q)))
        ready = float(p.arm_available[a]) if k == 0 else self.end(self.seqs[a][k - 1])
        return max(lb, ready + self.setup[t])

    def blocked(
        self, t: int, lb: float, upper: float, lines: list[list[_Seg]]
    ) -> list[tuple[float, float]]:
        """Open intervals of starts of ``t`` at which another arm is in the way."""
        a, k = self.pos[t]
        seq = self.seqs[a]
        tau = self.margin
        su, d = self.setup[t], self.length(t)
        prev_end = self.end(seq[k - 1]) if k > 0 else 0.0
        before = ("end", seq[k - 1]) if k > 0 else ("start", a)
        nxt = seq[k + 1] if k + 1 < len(seq) else -1
        next_dep = self.start[nxt] - self.setup[nxt] if nxt >= 0 else math.inf
        after = ("end", t)
        own = [self.task_key(t)] + ([("travel", t)] if su > 0 else [])
        chk = self.chk
        out: list[tuple[float, float]] = []
        span_lo, span_hi = lb - su - tau, upper + d + tau
        for b, line in enumerate(lines):
            if b == a:
                continue
            for seg in line:
                if seg.t1 < seg.t0:  # a departure moved before the end it follows: re-placed later
                    continue
                # this task's travel and trajectory against the segment
                if seg.t1 > span_lo and seg.t0 < span_hi:
                    for kx in own:
                        x = chk.motions[kx]
                        if seg.moving:
                            i, j = chk.contacts(
                                kx, seg.key, lb - seg.offset - tau, upper - seg.offset + tau
                            )
                            if not len(i):
                                continue
                            y = chk.motions[seg.key]
                            lo = seg.offset + y.lo[j] - x.hi[i] - tau
                            hi = seg.offset + y.hi[j] - x.lo[i] + tau
                        else:
                            i, j = chk.contacts(kx, seg.key)
                            if not len(i):
                                continue
                            lo = seg.t0 - x.hi[i] - tau
                            hi = seg.t1 - x.lo[i] + tau
                        out.extend(zip(lo.tolist(), hi.tolist(), strict=True))
                # the pose held before (from the previous end) and after (until the next departure)
                for pose, p0, p1 in ((before, prev_end, upper - su), (after, lb + d, next_dep)):
                    if not (seg.t1 > p0 - tau and seg.t0 < p1 + tau):
                        continue
                    i, j = chk.contacts(pose, seg.key)
                    if not len(i):
                        continue
                    if seg.moving:
                        y = chk.motions[seg.key]
                        c0 = seg.offset + y.lo[j]
                        c1 = seg.offset + y.hi[j]
                    else:
                        c0, c1 = np.array([seg.t0]), np.array([seg.t1])
                    if pose is before:
                        keep = c1 > prev_end - tau
                        out.extend((float(c) + su - tau, math.inf) for c in c0[keep].tolist())
                    else:
                        keep = c0 < next_dep + tau
                        out.extend((-math.inf, float(c) - d + tau) for c in c1[keep].tolist())
        out.extend(self._resources(t, a, su))
        return out

    def _resources(self, t: int, a: int, su: float) -> list[tuple[float, float]]:
        """Starts of ``t`` at which an SDL zone, a movement or a tool would be shared."""
        p, shapes = self.p, self.shapes
        sh = shapes[self.mode[t]]
        mine = list(sh.intervals(0.0, self.waits[t]))
        mine += [(r, 0.0, self.length(t)) for r in sh.tools]
        first = self.pos[t][1] == 0
        start_zones = [z for z in p.arm_start_zones[a] if p.zone_exclusive[z]] if first else []
        if not mine and not start_zones:
            return []
        want = {r for r, _, _ in mine} | set(start_zones)
        theirs: dict[int, list[tuple[float, float]]] = {}
        for u in range(self.T):
            if self.arm[u] == a:
                continue
            sh_u = shapes[self.mode[u]]
            for r, s, e in sh_u.intervals(self.start[u], self.waits[u]):
                if r in want:
                    theirs.setdefault(r, []).append((s, e))
            for r in sh_u.tools:
                if r in want:
                    theirs.setdefault(r, []).append((self.start[u], self.end(u)))
        for b in range(p.n_arms):
            if b == a or not self.seqs[b]:
                continue
            first_b = self.seqs[b][0]
            dep = self.start[first_b] - self.setup[first_b]
            for z in p.arm_start_zones[b]:
                if p.zone_exclusive[z] and z in want:
                    theirs.setdefault(z, []).append((0.0, dep))
        out: list[tuple[float, float]] = []
        for r, s, e in mine:
            if e <= s:
                continue
            for c, d in theirs.get(r, ()):
                if d > c:
                    out.append((c - e, d - s))
        for z in start_zones:  # this arm stands in its start zone until it leaves
            for c, d in theirs.get(z, ()):
                if d > c:
                    out.append((c + su, math.inf))
        return out

    def _earliest_with(self, t: int, lines: list[list[_Seg]]) -> float:
        self._ensure(t)
        lb = self.lower_bound(t)
        upper = max(self.start[t], lb)
        while True:
            s = _earliest(lb, self.blocked(t, lb, upper, lines))
            if s <= upper + _TOL or math.isinf(s):
                return s
            upper = s + max(self.length(t), 1.0)

    def place(self, t: int, lines: list[list[_Seg]]) -> bool:
        """Move ``t`` to its best start (its waits, or without those at grid borders)."""
        old_s, old_w = self.start[t], self.waits[t]
        options = [old_w]
        dropped = np.where(self.sdl_border[t], old_w, 0.0)
        if np.any(dropped != old_w):
            options.append(dropped)
        best: tuple[float, float, FloatArray] | None = None
        for w in options:
            self.waits[t] = w
            s = self._earliest_with(t, lines)
            if math.isinf(s):
                continue
            e = s + self.length(t)
            if best is None or e < best[0] - 1e-9:
                best = (e, s, w)
        if best is None:  # every start touches: stay (the monitor judges the clearance)
            self.waits[t] = old_w
            self.unresolved.add(t)
            s = max(old_s, self.lower_bound(t))
            self.start[t] = s
            return abs(s - old_s) > 1e-7
        self.unresolved.discard(t)
        _, s, w = best
        self.start[t], self.waits[t] = s, w
        return abs(s - old_s) > 1e-7 or w is not old_w

    def run(self, max_passes: int, settle: float) -> int:
        for t in range(self.T):
            self._ensure(t)
        for n in range(1, max_passes + 1):
            moved = 0.0
            lines = [self.timeline(a) for a in range(self.p.n_arms)]
            for t in sorted(range(self.T), key=lambda u: (self.start[u], u)):
                old_s, old_w = self.start[t], self.waits[t]
                if self.place(t, lines):
                    a = self.arm[t]
                    lines[a] = self.timeline(a)
                    shift = abs(self.start[t] - old_s)
                    moved = max(moved, math.inf if self.waits[t] is not old_w else shift)
            if moved <= settle:
                return n
        return max_passes

    def schedule(self) -> Schedule:
        return Schedule.from_starts(self.p, self.mode, self.start, self.waits)


def inert_grid(compiled: CompiledCell) -> CompiledCell:
    """The same compile with its space-grid blocks made inert.

    Every grid zone (named ``grid_...``) becomes a shared zone whose windows
    are occupancy only, so no arm ever waits for one; the modes, their
    borders (where a plan may make an arm wait), the SDL zones, tools,
    travel and the blocking oracle stay. A schedule of the grid compile is a
    schedule of this one; :func:`workcell.simulate` executes it with the
    same pauses, and only the SDL zones and tools are coordinated.

    Parameters
    ----------
    compiled : CompiledCell

    Returns
    -------
    CompiledCell
        ``compiled`` itself when it has no grid zones.
    """
    p = compiled.problem
    grid = np.array([grid_block(n) is not None for n in p.zone_names], dtype=bool)
    if not grid.any():
        return compiled
    in_grid = grid[p.win_zone]
    q = dataclasses.replace(
        p,
        zone_exclusive=np.asarray(p.zone_exclusive, dtype=bool) & ~grid,
        win_move=np.asarray(p.win_move, dtype=bool) & ~in_grid,
    )
    return dataclasses.replace(compiled, problem=q)


def _schedule_of(plan: object) -> Schedule:
    if isinstance(plan, Schedule):
        return plan
    sched = getattr(plan, "schedule", None)
    if isinstance(sched, Schedule):
        return sched
    raise UsageError(
        f"retime_exact: expected a scheduler.Plan, Result or Schedule, got {type(plan).__name__}"
    )


def retime_exact(
    compiled: CompiledCell,
    plan: object,
    *,
    padding: float = 0.02,
    margin: float = 0.0,
    max_passes: int = 50,
    settle: float = 0.05,
) -> ExactRetiming:
    """Re-time ``plan`` so that arms are kept apart only where their bodies really meet.

    See the module docstring for the motions compared, the sampled check
    and the left shifts.

    Parameters
    ----------
    compiled : CompiledCell
        The compile the plan was made for (any grid, or none).
    plan : scheduler.Plan, scheduler.Result or scheduler.Schedule
        A plan of ``compiled``'s problem, without detours.
    padding : float, metres
        Largest displacement of any shape point between consecutive samples,
        and growth of every shape (> 0): the clearance kept is at least
        nothing, at most ``4 padding``.
    margin : float, seconds
        Added to both ends of every forbidden interval of starts (>= 0).
    max_passes : int
        Left-shift passes at most (>= 1).
    settle : float, seconds
        Passes stop once no start moved by more than this in a pass (>= 0).
        Two tasks of two arms that are each other's next obstacle can creep
        earlier together by a sample's span per pass; this leaves such
        small shifts undone.

    Returns
    -------
    ExactRetiming
        Its schedule is validated on :func:`inert_grid` of ``compiled``.

    Raises
    ------
    multiarm.errors.UsageError
        A bad argument, or a plan with detour costs (the detour's path is not
        the mode's trajectory).
    multiarm.errors.ScheduleError
        ``plan`` is not a valid schedule of ``compiled``.
    """
    if isinstance(padding, bool) or not (
        isinstance(padding, int | float) and math.isfinite(padding) and padding > 0
    ):
        raise UsageError(f"retime_exact: padding must be a number > 0 (metres), got {padding!r}")
    if isinstance(margin, bool) or not (
        isinstance(margin, int | float) and math.isfinite(margin) and margin >= 0
    ):
        raise UsageError(f"retime_exact: margin must be a number >= 0 (seconds), got {margin!r}")
    if isinstance(settle, bool) or not (
        isinstance(settle, int | float) and math.isfinite(settle) and settle >= 0
    ):
        raise UsageError(f"retime_exact: settle must be a number >= 0 (seconds), got {settle!r}")
    if isinstance(max_passes, bool) or not isinstance(max_passes, int) or max_passes < 1:
        raise UsageError(f"retime_exact: max_passes must be an int >= 1, got {max_passes!r}")
    sched = _schedule_of(plan)
    grid_makespan = validate(compiled, sched)
    if sched.n_tasks and float(np.max(sched.blocking)) > 0:
        t = int(np.argmax(sched.blocking))
        raise UsageError(
            f"retime_exact: task {compiled.problem.task_names[t]!r} takes a detour "
            f"({float(sched.blocking[t]):.6g} s); plans with detours are not re-timed"
        )
    free = inert_grid(compiled)
    r = _Retimer(free, sched, float(padding), float(margin))
    passes = r.run(max_passes, float(settle))
    out = r.schedule()
    validate(free, out)
    return ExactRetiming(
        free,
        out,
        grid_makespan,
        passes,
        len(r.chk.pairs),
        r.chk.fcl_checks,
        float(padding),
        tuple(free.problem.task_names[t] for t in sorted(r.unresolved)),
    )
