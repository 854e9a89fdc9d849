"""The independent safety monitor of a simulated run.

The monitor shares no code path with the coordinator: it never reads the
zone manager, the plan or the coordinator's grants. It reads only what the
arms physically did -- each arm's record of its own motion (which
trajectory, from which offset, moving or standing, over which interval of
time; the actual joints including any lost steps), including the segment in
progress -- and the compiled cell (arm geometry, the modes' zone windows and
tools). From these it checks:

* **collisions**: no two arms touch, with FCL (:class:`workcell.geometry.CollisionWorld`,
  the only module that imports it) on the arms' collision shapes; cheap
  pre-tests pick the arm pairs FCL decides: bounding spheres, then capsules
  that hold the shapes (a box in the capsule of its longest axis), with
  ``_SLACK`` of margin so that they never skip a pair FCL finds touching;
* **zone invariants** (S2.5-S2.7): at most one arm inside each exclusive
  zone, at most one arm moving in each shared zone, at most one holder of
  each tool. An arm is inside a zone while its trajectory is within the
  zone's occupancy window (an arm stopped exactly at the window's start
  border is outside, waiting), and moves in a shared zone while its
  trajectory advances within a move window. An arm holds a task's tools
  from the task's start to its end; an arm that fails is retracted to its
  home joints and gives its tools back at the failure (its record ends
  there). Two uses of one resource by two arms that overlap by more than
  ``tol`` seconds break the invariant.

Two forms share these rules:

* :class:`LiveMonitor` (the default of :func:`workcell.simulate`) is a
  kernel process that checks *during* the run and stops it at the first
  violating sample, so nothing after a violation is simulated;
* :class:`SafetyMonitor` checks a finished run from the arms' records
  (``SimOptions(monitor="post")``); on the same run both report the same
  first violation.

Any violation fails the run loudly with :class:`SafetyViolation` (and is
recorded in the trace as a ``"monitor"`` event).

Sampling (live)
---------------
Collisions are checked every ``period`` seconds of virtual time (the
samples ``k * period``, after every other event at that instant) *while some
arm moves*, and once more for an arm that came to rest between two samples.
When no arm moves nothing can start to touch, so the monitor skips the idle
stretch: it sleeps until the next kernel event instead of waking every
``period``. Only the arm pairs in which some arm moved since the pair was
last decided are tested, all of them in one compiled pass of the pre-tests
per sample (numba); the positions of a moving arm are computed for a few samples
ahead at once from its segment in progress (used while that segment lasts,
recomputed when it changes). While arms move and no kernel event comes, the
records cannot change, so the samples up to the one that sees the next event
are decided ahead in compiled batches over the segments in progress: the
monitor wakes only at a sample where a moving arm's capsules come within
reach of another arm's (where FCL decides, as before), at the sample that
sees the next event, and at a predicted zone overlap; every sample in
between is one at which every pair passes the pre-tests apart, so it is
decided as at a wake (the same samples, the same verdicts, far fewer
wakes). The zone and tool invariants do not need
samples: at its next wake after an arm's record changed (a sample, or the
next event when no arm moves), the monitor computes the intervals of that
arm's uses (the finished ones, and the ones in progress as if the arm went
on as it goes) and the earliest instant at which two arms' uses of one
resource overlap by more than ``tol``; it wakes at that instant and fails
the run if both uses still stand as predicted (a use that changed before
is compared again from its record: an overlap that began in between is
found at that wake, with the time it began). The monitor only reads, so a
run it lets pass is the same run as without it (the same trace); the events
it does not wake for (the controller ticks of ``SimOptions(tick=...)``,
messages) cost it nothing.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np

from multiarm.errors import MultiarmError
from multiarm.types import FloatArray
from scheduler import Problem
from workcell.compile import CompiledCell
from workcell.sim.events.trace import Trace
from workcell.sim.harness.monitor_geometry import (
    MonitorGeometry,
    pair_touches,
    segment_dist2,
    touching_pairs,
)
from workcell.sim.protocol.records import MotionLog, MotionRecord

__all__ = [
    "MONITOR_PRIORITY",
    "MonitorGeometry",
    "SafetyMonitor",
    "SafetyViolation",
    "ZoneWindows",
    "record_joints",
    "segment_dist2",
    "static_uses",
    "touching_pairs",
    "violation_message",
]

MONITOR_PRIORITY = 1 << 30
"""EventLoop priority of the live monitor's wakes: after every other callback
due at the same instant, so a sample sees the state the post-run records
give for that instant."""

Record = MotionRecord
"""One segment of an arm's published motion
(:class:`~workcell.sim.protocol.records.MotionRecord`)."""

Use = tuple[tuple[str, str], float, float]
"""One use of a resource: ``((what, name), start, end)``."""


class SafetyViolation(MultiarmError, RuntimeError):
    """The safety monitor saw two arms collide or a zone invariant broken.

    Parameters
    ----------
    message : str
    time : float
        When the broken state began, seconds of virtual time: the first
        sample at which two arms touch, or the start of the overlap of two
        arms' uses of one zone or tool.
    found : float
        When the monitor raised: the time of its ``"monitor"`` trace event
        (the live monitor: the sample that saw it; the post-run check: the
        end of the run).
    arms : tuple of str
        The two arms.
    trace : Trace, optional
        The run's trace up to ``found`` (sorted; for the live monitor the
        partial trace of the stopped run).

    Attributes
    ----------
    time, found, arms, trace
        As given.
    """

    def __init__(
        self,
        message: str,
        *,
        time: float = math.nan,
        found: float = math.nan,
        arms: tuple[str, ...] = (),
        trace: Trace | None = None,
    ) -> None:
        super().__init__(message)
        self.time = float(time)
        self.found = float(found)
        self.arms = tuple(arms)
        self.trace = trace


# ------------------------------------------------------------ shared rules


def record_joints(rec: Record, times: FloatArray) -> FloatArray:
    """(N, dof) actual joints at ``times`` (all within the record) from one record."""
    return rec.joints_at(times)


class ZoneWindows:
    """The zone windows of every mode of a problem (built on first use)."""

    def __init__(self, p: Problem) -> None:
        self.p = p
        self._modes: dict[int, tuple[list[tuple[tuple[str, str], float, float]], int]] = {}

    def _mode(self, m: int) -> tuple[list[tuple[tuple[str, str], float, float]], int]:
        """``([(key, start, end), ...], n_exclusive)``: the exclusive zones'
        occupancy windows first, then the shared zones' move windows."""
        got = self._modes.get(m)
        if got is None:
            p = self.p
            sh = p.shapes[m]
            keys = [("inside exclusive zone", p.zone_names[r]) for r, _s, _e in sh.exclusive]
            keys += [
                ("moving in shared zone", p.zone_names[r - p.n_zones]) for r, _s, _e in sh.moves
            ]
            se = [(float(s), float(e)) for _r, s, e in (*sh.exclusive, *sh.moves)]
            got = ([(k, s, e) for k, (s, e) in zip(keys, se, strict=True)], len(sh.exclusive))
            self._modes[m] = got
        return got

    def uses(self, rec: Record, t_end: float | None = None) -> list[Use]:
        """The zone uses of one motion record (a task leg's windows).

        ``t_end=None``: the record as it is. Otherwise the record is taken to
        go on as it goes (moving or standing) until ``t_end`` (``inf``: for
        ever): the uses of a segment in progress, as predicted.
        """
        t0, t1, leg, tau0, moving = rec.start, rec.end, rec.leg, rec.tau0, rec.moving
        if leg is None or leg.kind != "task":
            return []
        windows, n_ex = self._mode(leg.mode)
        if t_end is not None:
            t1 = t_end
        ta = tau0
        if moving:  # the part of each window the trajectory clock runs through
            tb = tau0 + (t1 - t0)
            out = []
            for key, s, e in windows:
                lo = s if s > ta else ta
                hi = e if e < tb else tb
                if hi > lo:
                    out.append((key, t0 + lo - ta, t0 + hi - ta))
            return out
        if not t1 > t0:
            return []
        return [(key, t0, t1) for key, s, e in windows[:n_ex] if s < ta < e]


def violation_message(what: str, name: str, a1: str, a2: str, start: float, end: float) -> str:
    if math.isfinite(end):
        return f"arms {a1!r} and {a2!r} both {what} {name!r} during [{start:.6g}, {end:.6g}) s"
    return f"arms {a1!r} and {a2!r} both {what} {name!r} from t = {start:.6g} s"


# ------------------------------------------------------------ post-run


class SafetyMonitor:
    """Checks a finished run from the arms' motion records (module docstring).

    Parameters
    ----------
    compiled : CompiledCell
    period : float
        Sampling period of the collision check, seconds.
    tol : float
        Time tolerance of the zone checks, seconds.

    Attributes
    ----------
    samples : int
        Instants sampled.
    fcl_checks : int
        Arm pairs decided by FCL.
    """

    def __init__(self, compiled: CompiledCell, period: float = 0.02, tol: float = 1e-6) -> None:
        self.cc = compiled
        self.period = float(period)
        self.tol = float(tol)
        self.geo = MonitorGeometry(compiled)
        self.world = self.geo.world
        self.radii = self.geo.radii
        self.samples = 0

    @property
    def fcl_checks(self) -> int:
        """Arm pairs decided by FCL."""
        return self.geo.fcl_checks

    # ------------------------------------------------------------ positions
    @staticmethod
    def joints(ctl: MotionLog, times: FloatArray) -> FloatArray:
        """(N, dof) actual joints of an arm at ``times`` from its motion record."""
        out = np.repeat(ctl.home_q[None, :], len(times), axis=0)
        for rec in ctl.records:
            t0, t1 = rec.start, rec.end
            sel = np.flatnonzero((times >= t0) & (times < t1))
            if len(sel):
                out[sel] = record_joints(rec, times[sel])
        if ctl.records:  # after the last record: where it stands
            last = ctl.records[-1]
            t0, t1, leg, tau0 = last.start, last.end, last.leg, last.tau0
            moving, extra = last.moving, last.joints
            sel = np.flatnonzero(times >= t1)
            if len(sel):
                if leg is None:
                    out[sel] = extra
                else:
                    end = tau0 + (t1 - t0) if moving else tau0
                    out[sel] = leg.trajectory.sample(np.array([end]))[0] + extra
        return out

    # ------------------------------------------------------------ checks
    def check(self, arms: Sequence[MotionLog], t_end: float, trace: Trace) -> None:
        """Check the whole run up to ``t_end``; report the earliest violation.

        Raises
        ------
        SafetyViolation
            Naming the arms, the zone or shapes, and the time.
        """
        zone = self._zones(arms)
        hit = self._collisions(arms, t_end, before=zone[0] if zone else math.inf)
        found = zone if hit is None or (zone is not None and zone[0] <= hit[0]) else hit
        if found is None:
            return
        t, names, msg = found
        trace.add(t_end, "monitor", detail=msg)
        trace.sort()
        raise SafetyViolation(msg, time=t, found=t_end, arms=names, trace=trace)

    def _collisions(
        self, arms: Sequence[MotionLog], t_end: float, before: float = math.inf
    ) -> tuple[float, tuple[str, str], str] | None:
        """The first sample (before ``before``) at which two arms touch, in
        time order (ties: in the order of the arm pairs)."""
        geo = self.geo
        cell = self.cc.cell
        n = max(1, math.ceil(t_end / self.period) + 1)
        times = np.minimum(np.arange(n) * self.period, t_end)
        self.samples += n
        centres = []
        tfs_all = []
        moved = []  # per arm: count of pose changes up to each sample
        ends: list[tuple[FloatArray, FloatArray]] = []
        for ctl, arm in zip(arms, cell.arms, strict=True):
            q = self.joints(ctl, times)
            tfs = arm.shape_transforms(q)
            tfs_all.append(tfs)
            centres.append(np.ascontiguousarray(tfs[:, :, :3, 3]))
            ends.append(geo.ends(len(ends), tfs))
            step = np.zeros(n, dtype=np.int64)
            step[1:] = np.any(q[1:] != q[:-1], axis=1)
            moved.append(np.cumsum(step))
        cand_i, cand_a, cand_b = [], [], []
        for a, b in itertools.combinations(range(len(arms)), 2):
            sa = slice(geo.offsets[a], geo.offsets[a + 1])
            sb = slice(geo.offsets[b], geo.offsets[b + 1])
            r2 = geo.r2[sa, sb]
            near = np.zeros(n, dtype=np.bool_)
            pair_touches(
                centres[a],
                ends[a][0],
                ends[a][1],
                centres[b],
                ends[b][0],
                ends[b][1],
                np.ascontiguousarray(r2),
                geo.rc[sa],
                geo.rc[sb],
                near,
            )
            idx = np.flatnonzero(near)
            cand_i.append(idx)
            cand_a.append(np.full(len(idx), a))
            cand_b.append(np.full(len(idx), b))
        if not cand_i:
            return None
        ci, ca, cb = np.concatenate(cand_i), np.concatenate(cand_a), np.concatenate(cand_b)
        order = np.lexsort((cb, ca, ci))
        decided: dict[tuple[int, int], tuple[int, int]] = {}
        posed: dict[int, int] = {}
        for i, a, b in zip(ci[order].tolist(), ca[order].tolist(), cb[order].tolist(), strict=True):
            if times[i] >= before:
                break
            state = (int(moved[a][i]), int(moved[b][i]))
            if decided.get((a, b)) == state:
                continue  # neither arm moved since this pair was found apart
            decided[(a, b)] = state
            for x in (a, b):
                if posed.get(x) != int(moved[x][i]):  # the same count: the same pose
                    geo.world.set_group_transforms(geo.names[x], tfs_all[x][i])
                    posed[x] = int(moved[x][i])
            if geo.collide(a, b):
                t = float(times[i])
                return t, (geo.names[a], geo.names[b]), geo.violation(a, b, t)
        return None

    def _zones(self, arms: Sequence[MotionLog]) -> tuple[float, tuple[str, str], str] | None:
        """The earliest overlap of two arms' uses of one resource."""
        p: Problem = self.cc.problem
        windows = ZoneWindows(p)
        use: dict[tuple[str, str], list[tuple[float, float, str]]] = {}
        for ctl in arms:
            first_move = math.inf
            for rec in ctl.records:
                if rec.leg is None:
                    continue
                first_move = min(first_move, rec.start)
                for key, s, e in windows.uses(rec):
                    use.setdefault(key, []).append((s, e, ctl.name))
            first_move = min(first_move, ctl.failed_at)  # a failed arm is retracted
            for key, s, e in static_uses(p, ctl, first_move):
                use.setdefault(key, []).append((s, e, ctl.name))
            for t, task in ctl.tasks.items():
                start, end, m = task.start, task.end, task.mode
                if math.isfinite(end):
                    stop = end
                elif ctl.failed:
                    # interrupted by the arm's failure: the arm is retracted
                    # to its home joints and gives its tools back at once
                    stop = max(start, ctl.failed_at)
                else:
                    stop = ctl.records[-1].end if ctl.records else start
                for k in p.mode_tools[m]:
                    use.setdefault(("holding tool", p.tool_names[k]), []).append(
                        (start, stop, ctl.name)
                    )
                del t
        tol = self.tol
        best: tuple[float, tuple[str, str], str] | None = None
        best_key = ("", "")
        for (what, name), items in use.items():
            items.sort()
            for i, (_s1, e1, a1) in enumerate(items):
                for s2, e2, a2 in items[i + 1 :]:
                    if s2 >= e1 - tol:
                        break
                    if (
                        a1 != a2
                        and min(e1, e2) - s2 > tol
                        and (best is None or (s2, (what, name)) < (best[0], best_key))
                    ):
                        best = (
                            s2,
                            (a1, a2),
                            violation_message(what, name, a1, a2, s2, min(e1, e2)),
                        )
                        best_key = (what, name)
        return best


def static_uses(p: Problem, ctl: MotionLog, first_move: float) -> list[Use]:
    """The exclusive zones an arm starts in, held until it first moves."""
    out: list[Use] = []
    for z in p.arm_start_zones[ctl.index]:
        if p.zone_exclusive[z] and first_move > 0:
            out.append((("inside exclusive zone", p.zone_names[z]), 0.0, first_move))
    return out
