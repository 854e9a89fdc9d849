"""The cell's blocking oracle: parked arms in the way, and OMPL detours (S2.6, S2.12).

The scheduler asks :meth:`CellOracle.cost` "does mode ``m`` collide with arm
``b`` parked at the end pose of task ``p``, and what does the detour cost?"
(:class:`scheduler.BlockingOracle`, DESIGN.md data flow step 3). The answer:

1. **Pre-test.** The bounding box swept by the mode's arm over its whole
   trajectory (grown by the padding) against the parked arm's bounding box:
   disjoint boxes cannot touch, the answer is 0 without any collision check.
   This settles the far-apart majority.
2. **Contact runs.** The trajectory is sampled as in the zone sweep (every
   knot, bisected until the displacement bound between samples is at most
   the padding); a vectorised test of capsules holding the shapes picks the
   samples that may touch the parked arm, and FCL (shapes grown by the
   padding) decides each of them; a sample that touches flags the motion
   segment (between two knots) it lies in. No contact: 0.
3. **Detours.** For each run of flagged segments, a detour is planned in the
   arm's joint space with OMPL from the knot before the run to the knot
   after it, the parked arm an obstacle (:func:`workcell.geometry.plan_detour`,
   RRTConnect, simplified), and timed with the arm's drives (synchronised).
   A knot in contact (the task must pass through a pose that touches the
   parked arm: a start or goal in collision) or a search that finds nothing
   means no detour: ``inf``. Otherwise the cost is the detours' extra time over the
   segments they replace (at least :data:`MIN_COST`, so a contact is never
   free). With detours off (``detours=False``, the compile option
   :attr:`workcell.CompileOptions.detours`) every contact costs ``inf``
   without planning: the scheduler then waits the parked arm out.

Answers are cached per (mode, parked arm, pose task) and the detour paths
are kept for the simulation (:meth:`CellOracle.detours`). The planner runs
under a work limit (``max_checks``) as well as a wall-clock budget, so the
same cell gives the same answers on any machine as long as the budget is not
the binding limit (the statistics count searches stopped by it).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from multiarm.errors import UsageError
from multiarm.types import FloatArray, JointVector
from scheduler import Problem
from workcell.arms import DriveArm, time_path
from workcell.cell import Cell
from workcell.compiled import CompiledMode
from workcell.geometry import (
    DetourPlanner,
    ObstacleSet,
    aabbs_overlap,
    arm_contacts,
    plan_detour,
    sample_trajectory,
)

__all__ = ["MIN_COST", "CellOracle", "Detour", "OracleStats"]

MIN_COST = 1e-3
"""Smallest cost (seconds) charged for a contact that a detour resolves."""


@dataclass(frozen=True, slots=True)
class Detour:
    """One detour of a mode around a parked arm.

    Attributes
    ----------
    start, end : float
        Offsets (seconds from the task's start) of the knots it replaces the
        motion between.
    path : (K, dof) float
        The joint path from the knot before to the knot after.
    duration : float
        Seconds the detour takes (timed with the arm's drives).
    """

    start: float
    end: float
    path: FloatArray
    duration: float

    @property
    def extra(self) -> float:
        """Seconds the detour adds over the motion it replaces."""
        return self.duration - (self.end - self.start)


@dataclass
class OracleStats:
    """Counters of a :class:`CellOracle` (for benchmarks and reports)."""

    queries: int = 0
    cached: int = 0
    pretest_free: int = 0
    checked_free: int = 0
    detoured: int = 0
    infeasible: int = 0
    budget_stops: int = 0
    plan_seconds: list[float] = field(default_factory=list)
    seconds: float = 0.0


class CellOracle:
    """Blocking oracle of a compiled cell (implements :class:`scheduler.BlockingOracle`).

    Parameters
    ----------
    cell : Cell
    budget : float
        Wall-clock limit of one detour search, seconds.
    max_checks : int
        Work limit of one detour search (configurations checked).
    seed : int
        Seed of the planner (the same seed gives the same detours).
    grid : float
        Contact padding and sampling step of the checks, metres (at least the
        cell's padding). S2.12's compromise: a coarser grid answers faster
        but rejects some paths that are possible in reality (near misses
        within ``grid`` count as contacts).
    detours : bool
        Plan detours around a parked arm; ``False``: a contact costs ``inf``.
    """

    def __init__(
        self,
        cell: Cell,
        *,
        budget: float = 2.0,
        max_checks: int = 2_000,
        seed: int = 0,
        grid: float = 0.02,
        detours: bool = True,
    ) -> None:
        self.cell = cell
        self.plan_detours = bool(detours)
        self.budget = float(budget)
        self.max_checks = int(max_checks)
        self.seed = int(seed)
        self.padding = max(float(cell.padding), float(grid))
        self.stats = OracleStats()
        self._problem: Problem | None = None
        self._modes: tuple[CompiledMode, ...] = ()
        self._cache: dict[tuple[int, int, int], float] = {}
        self._detours: dict[tuple[int, int, int], tuple[Detour, ...]] = {}
        self._boxes: dict[int, FloatArray] = {}
        self._parked: dict[tuple[int, int], tuple[ObstacleSet, FloatArray]] = {}
        self._samples: dict[int, tuple[FloatArray, FloatArray]] = {}
        self._contexts: dict[tuple[int, int], DetourPlanner] = {}
        self._by_joints: dict[tuple[int, int, int, bytes], float] = {}
        self._detours_q: dict[tuple[int, int, int, bytes], tuple[Detour, ...]] = {}

    def bind(self, problem: Problem, modes: tuple[CompiledMode, ...]) -> None:
        """Attach the compiled problem (done by :func:`workcell.compile_cell`).

        Answers already found stay valid for a new problem of the same cell
        (they are keyed by task and arms, not by mode ids)."""
        self._problem = problem
        self._modes = modes
        self._cache.clear()
        self._detours.clear()
        self._boxes.clear()
        self._parked.clear()
        self._samples.clear()

    # --------------------------------------------------------- helpers
    def _need(self) -> Problem:
        if self._problem is None:
            raise UsageError("the oracle is not bound to a compiled problem yet")
        return self._problem

    def parked_joints(self, arm: int, pose_task: int) -> JointVector:
        """Joint vector of ``arm`` parked after task ``pose_task`` (-1: its start)."""
        p = self._need()
        if pose_task < 0:
            return np.asarray(self.cell.start[arm], dtype=float)
        m = int(p.mode_of[arm, pose_task])
        if m < 0:
            raise UsageError(
                f"arm {p.arm_names[arm]!r} never does task {p.task_names[pose_task]!r}"
            )
        return self._modes[m].q_end

    def _parked_set(self, arm: int, pose_task: int) -> tuple[ObstacleSet, FloatArray]:
        key = (arm, pose_task)
        got = self._parked.get(key)
        if got is None:
            blocker = self.cell.arms[arm]
            q = self.parked_joints(arm, pose_task)
            obs = ObstacleSet.from_arm(blocker, q)
            tfs = blocker.shape_transforms(q[None])[0]
            rad = np.array([s.radius() for s in blocker.shapes])
            centres = tfs[:, :3, 3]
            box = np.stack([(centres - rad[:, None]).min(0), (centres + rad[:, None]).max(0)])
            got = (obs, box)
            self._parked[key] = got
        return got

    def _swept(self, mode: int) -> FloatArray:
        """(2, 3) box holding every shape of the mode's arm over its samples,
        grown by the shapes' radii and the padding (conservative: between
        samples no point moves farther than the padding)."""
        box = self._boxes.get(mode)
        if box is None:
            cm = self._modes[mode]
            arm = self.cell.arm(cm.arm)
            _, q = self._sampled(mode)
            centres = arm.shape_transforms(q)[:, :, :3, 3]
            rad = np.array([sh.radius() for sh in arm.shapes]) + 2 * self.padding
            box = np.stack(
                [
                    (centres - rad[None, :, None]).min(axis=(0, 1)),
                    (centres + rad[None, :, None]).max(axis=(0, 1)),
                ]
            )
            self._boxes[mode] = box
        return box

    def _context(self, mover: DriveArm, obs: ObstacleSet) -> DetourPlanner:
        key = (id(mover), id(obs))
        ctx = self._contexts.get(key)
        if ctx is None:
            ctx = DetourPlanner(mover, obs, resolution=self.padding, clearance=self.padding)
            self._contexts[key] = ctx
        return ctx

    def _sampled(self, mode: int) -> tuple[FloatArray, FloatArray]:
        got = self._samples.get(mode)
        if got is None:
            cm = self._modes[mode]
            got = sample_trajectory(self.cell.arm(cm.arm), cm.trajectory, self.padding)
            self._samples[mode] = got
        return got

    # ------------------------------------------------------------ query
    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        """Extra seconds for ``mode`` with ``arm`` parked after ``pose_task``.

        0.0 when they do not touch, the detours' extra time when they do,
        ``inf`` when no detour exists.
        """
        key = (int(mode), int(arm), int(pose_task))
        got = self._cache.get(key)
        self.stats.queries += 1
        if got is not None:
            self.stats.cached += 1
            return got
        t0 = time.perf_counter()
        # arms parked at the same joints answer alike (always so with park="home");
        # keyed by task and arms, not mode ids, so answers survive a rebuilt problem
        p = self._need()
        qkey = (
            int(p.mode_task[key[0]]),
            int(p.mode_arm[key[0]]),
            key[1],
            self.parked_joints(key[1], key[2]).tobytes(),
        )
        value = self._by_joints.get(qkey)
        if value is None:
            value = self._cost(*key)
            self._by_joints[qkey] = value
            self._detours_q[qkey] = self._detours.get(key, ())
        else:
            self.stats.cached += 1
            self._detours[key] = self._detours_q[qkey]
        self.stats.seconds += time.perf_counter() - t0
        self._cache[key] = value
        return value

    def table(self) -> FloatArray:
        """(M, A, T + 1) answers known ahead, NaN where unknown (read by the
        scheduler's kernel when it compiles the problem).

        With ``park="home"`` every arm parks at its start joints whatever task
        it did last, so one answer per (mode, arm) fills a whole row: they are
        all computed here, the far-apart pairs by one vectorised bounding-box
        test. With ``park="last"`` nothing is known ahead (all NaN).
        """
        p = self._need()
        M, A, T = p.n_modes, p.n_arms, p.n_tasks
        out = np.full((M, A, T + 1), np.nan)
        if self.cell.park != "home":
            return out
        boxes = np.stack([self._swept(m) for m in range(M)])  # (M, 2, 3)
        parked = np.stack([self._parked_set(a, -1)[1] for a in range(A)])  # (A, 2, 3)
        overlap = np.all(
            (boxes[:, None, 0] <= parked[None, :, 1]) & (parked[None, :, 0] <= boxes[:, None, 1]),
            axis=2,
        )
        for m in range(M):
            for a in range(A):
                if int(p.mode_arm[m]) == a or not overlap[m, a]:
                    out[m, a, :] = 0.0
                else:
                    out[m, a, :] = self.cost(m, a, -1)
        return out

    def detours(self, mode: int, arm: int, pose_task: int) -> tuple[Detour, ...]:
        """The detours behind :meth:`cost` (empty when there is no contact)."""
        self.cost(mode, arm, pose_task)
        return self._detours.get((int(mode), int(arm), int(pose_task)), ())

    def _cost(self, mode: int, arm: int, pose_task: int) -> float:
        p = self._need()
        cm = self._modes[mode]
        mover_id = int(p.mode_arm[mode])
        if mover_id == arm:
            return 0.0
        obs, parked_box = self._parked_set(arm, pose_task)
        if not aabbs_overlap(self._swept(mode), parked_box):
            self.stats.pretest_free += 1
            return 0.0
        mover = self.cell.arms[mover_id]
        blocker = self.cell.arms[arm]
        q_park = self.parked_joints(arm, pose_task)
        ctx = self._context(mover, obs)
        knots = np.asarray(cm.trajectory.knot_times, dtype=float)
        # a vectorised capsule test picks candidates; FCL (grown by the
        # padding) decides each candidate exactly
        wp = cm.trajectory.waypoints()
        near = arm_contacts(mover, wp, blocker, q_park, self.padding)
        if any(not ctx.is_valid(wp[i]) for i in np.flatnonzero(near)):
            # the task must pass through a pose (a knot) where it touches the
            # parked arm: no detour can avoid it
            self.stats.infeasible += 1
            return math.inf
        t, q = self._sampled(mode)
        near = arm_contacts(mover, q, blocker, q_park, self.padding)
        bad = np.zeros(len(q), dtype=bool)
        for i in np.flatnonzero(near):
            bad[i] = not ctx.is_valid(q[i])
        if not bad.any():
            self.stats.checked_free += 1
            return 0.0
        if not self.plan_detours:
            self.stats.infeasible += 1
            return math.inf
        runs = _runs(t[bad], knots)
        total = 0.0
        found: list[Detour] = []
        for k0, k1 in runs:
            qa = cm.trajectory.sample(np.array([knots[k0]]))[0]
            qb = cm.trajectory.sample(np.array([knots[k1]]))[0]
            res = plan_detour(
                mover,
                qa,
                qb,
                obs,
                budget=self.budget,
                seed=self.seed,
                resolution=self.padding,
                clearance=self.padding,
                max_checks=self.max_checks,
            )
            self.stats.plan_seconds.append(res.planning_time)
            if not res.solved:
                if res.status == "timeout" and res.planning_time >= self.budget:
                    self.stats.budget_stops += 1
                self.stats.infeasible += 1
                return math.inf
            duration = float(time_path(mover, res.path, "sync").duration)
            d = Detour(float(knots[k0]), float(knots[k1]), res.path, duration)
            found.append(d)
            total += max(MIN_COST, d.extra)
        self.stats.detoured += 1
        self._detours[(mode, arm, pose_task)] = tuple(found)
        return total


def _runs(times: FloatArray, knots: FloatArray) -> list[tuple[int, int]]:
    """Merge contact times into runs of knot intervals ``(k0, k1)``."""
    spans: list[tuple[int, int]] = []
    for tc in times:
        k1 = int(np.searchsorted(knots, tc, side="right"))
        k1 = min(max(k1, 1), len(knots) - 1)
        spans.append((k1 - 1, k1))
    spans.sort()
    merged: list[tuple[int, int]] = []
    for a, b in spans:
        if merged and a <= merged[-1][1]:
            merged[-1] = (merged[-1][0], max(b, merged[-1][1]))
        else:
            merged.append((a, b))
    return merged
