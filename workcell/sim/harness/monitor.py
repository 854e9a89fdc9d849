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
recomputed when it changes). The zone and tool invariants do not need
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

import bisect
import heapq
import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit

from multiarm.errors import MultiarmError
from multiarm.types import FloatArray
from scheduler import Problem
from workcell.compile import CompiledCell
from workcell.geometry import CollisionWorld
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
from workcell.sim.protocol.records import MotionLog, MotionRecord, TaskRecord

__all__ = ["MONITOR_PRIORITY", "LiveMonitor", "SafetyMonitor", "SafetyViolation"]

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


def _record_joints(rec: Record, times: FloatArray) -> FloatArray:
    """(N, dof) actual joints at ``times`` (all within the record) from one record."""
    return rec.joints_at(times)


class _Windows:
    """The zone windows of every mode of a problem, as arrays (built on first use)."""

    def __init__(self, p: Problem) -> None:
        self.p = p
        self._modes: dict[int, tuple[list[tuple[str, str]], FloatArray, FloatArray, int]] = {}

    def _mode(self, m: int) -> tuple[list[tuple[str, str]], FloatArray, FloatArray, int]:
        got = self._modes.get(m)
        if got is None:
            p = self.p
            sh = p.shapes[m]
            keys = [("inside exclusive zone", p.zone_names[r]) for r, _s, _e in sh.exclusive]
            keys += [
                ("moving in shared zone", p.zone_names[r - p.n_zones]) for r, _s, _e in sh.moves
            ]
            se = np.array([(s, e) for _r, s, e in (*sh.exclusive, *sh.moves)], dtype=float)
            se = se.reshape(-1, 2)
            got = (
                keys,
                np.ascontiguousarray(se[:, 0]),
                np.ascontiguousarray(se[:, 1]),
                len(sh.exclusive),
            )
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
        keys, s, e, n_ex = self._mode(leg.mode)
        if t_end is not None:
            t1 = t_end
        ta = tau0
        if moving:
            tb = tau0 + (t1 - t0)
            lo, hi = np.maximum(s, ta), np.minimum(e, tb)
            idx = np.flatnonzero(hi > lo)
            start = (t0 + lo[idx] - ta).tolist()
            stop = (t0 + hi[idx] - ta).tolist()
            return [(keys[i], a, b) for i, a, b in zip(idx.tolist(), start, stop, strict=True)]
        if not t1 > t0:
            return []
        inside = np.flatnonzero((s[:n_ex] < ta) & (ta < e[:n_ex]))
        return [(keys[i], t0, t1) for i in inside.tolist()]


def _message(what: str, name: str, a1: str, a2: str, start: float, end: float) -> str:
    if math.isfinite(end):
        return f"arms {a1!r} and {a2!r} both {what} {name!r} during [{start:.6g}, {end:.6g}) s"
    return f"arms {a1!r} and {a2!r} both {what} {name!r} from t = {start:.6g} s"


class _Geometry:
    """The monitor's own collision world and bounding spheres of every shape."""

    def __init__(self, compiled: CompiledCell) -> None:
        cell = compiled.cell
        self.arms = list(cell.arms)
        self.names = [arm.name for arm in cell.arms]
        # No allowed pairs: the monitor asks only about pairs of arms, never
        # about one arm's own links (which FCL would then have to filter).
        self.world = CollisionWorld()
        for arm, q in zip(cell.arms, cell.start, strict=True):
            tfs = arm.shape_transforms(np.asarray(q, dtype=float)[None, :])[0]
            for shape, tf in zip(arm.shapes, tfs, strict=True):
                self.world.add_link_shape(f"{arm.name}/{shape.name}", shape, arm.name, tf)
        self.radii = [np.array([s.radius() for s in arm.shapes]) for arm in cell.arms]
        sizes = [len(r) for r in self.radii]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.arm_of = np.repeat(np.arange(len(sizes), dtype=np.int64), sizes)
        r = np.concatenate(self.radii) if sizes else np.zeros(0)
        self.r2 = (r[:, None] + r[None, :]) ** 2
        self.r2[self.arm_of[:, None] == self.arm_of[None, :]] = -1.0  # one arm's own shapes
        # every shape inside a capsule: a segment along a local axis, a radius
        axes, half, rc = [], [], []
        for arm in cell.arms:
            for sh in arm.shapes:
                u, h, r_ = _enclosing_capsule(sh.kind, sh.size)
                axes.append(u)
                half.append(h)
                rc.append(r_)
        self.axis = np.array(axes, dtype=float).reshape(-1, 3)
        self.half = np.array(half, dtype=float)
        self.rc = np.array(rc, dtype=float)
        self.fcl_checks = 0

    def ends(self, a: int, tfs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(..., n, 3) ends of arm ``a``'s shapes' capsules for shape poses ``tfs``."""
        sl = slice(int(self.offsets[a]), int(self.offsets[a + 1]))
        w = np.einsum("...ij,...j->...i", tfs[..., :3, :3], self.axis[sl]) * self.half[sl, None]
        c = tfs[..., :3, 3]
        return np.ascontiguousarray(c - w), np.ascontiguousarray(c + w)

    def collide(self, a: int, b: int) -> bool:
        self.fcl_checks += 1
        return bool(self.world.collide(self.names[a], self.names[b]))

    def violation(self, a: int, b: int, t: float) -> str:
        na, nb = self.names[a], self.names[b]
        pairs = self.world.colliding_pairs(na, nb)
        return (
            f"arms {na!r} and {nb!r} collide at t = {t:.6g} s "
            f"({', '.join(f'{x} - {y}' for x, y in pairs)})"
        )


def _enclosing_capsule(kind: str, size: Sequence[float]) -> tuple[FloatArray, float, float]:
    """A capsule holding a shape: (local unit axis, half-length, radius)."""
    z = np.array([0.0, 0.0, 1.0])
    if kind in ("capsule", "cylinder"):
        r, h = float(size[0]), float(size[1])
        return z, h / 2, r  # a cylinder lies inside the capsule of its axis and radius
    if kind == "box":
        dims = np.abs(np.asarray(size, dtype=float)) / 2
        i = int(np.argmax(dims))
        u = np.zeros(3)
        u[i] = 1.0
        others = np.delete(dims, i)
        return u, float(dims[i]), float(np.hypot(others[0], others[1]))
    return z, 0.0, float(size[0])  # sphere


_SLACK = 1e-4
"""Metres added to the capsules' reach in the pre-test, far above the rounding
of the segment distance (about 1e-6 m for nearly parallel segments a metre
long), so the pre-test never skips a pair FCL would find touching."""


@njit(cache=True, inline="always")
def _segment_dist2(p0: FloatArray, p1: FloatArray, q0: FloatArray, q1: FloatArray) -> float:
    """Squared distance between the segments ``p0 p1`` and ``q0 q1`` (3-vectors;
    the closest points of two segments after Ericson, Real-Time Collision
    Detection, 5.1.9)."""
    d1x, d1y, d1z = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    d2x, d2y, d2z = q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]
    rx, ry, rz = p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-18
    s = 0.0
    t = 0.0
    if a <= eps and e <= eps:
        pass
    elif a <= eps:
        t = min(1.0, max(0.0, f / e))
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= eps:
            s = min(1.0, max(0.0, -c / a))
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            den = a * e - b * b
            if den > 1e-12 * a * e:
                s = min(1.0, max(0.0, (b * f - c * e) / den))
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(1.0, max(0.0, -c / a))
            elif t > 1.0:
                t = 1.0
                s = min(1.0, max(0.0, (b - c) / a))
    dx = rx + d1x * s - d2x * t
    dy = ry + d1y * s - d2y * t
    dz = rz + d1z * s - d2z * t
    out: float = dx * dx + dy * dy + dz * dz
    return out


@njit(cache=True)
def _touching_pairs(
    c: FloatArray,
    p0: FloatArray,
    p1: FloatArray,
    rows: npt.NDArray[np.int64],
    r2: FloatArray,
    rc: FloatArray,
    arm_of: npt.NDArray[np.int64],
    out: npt.NDArray[np.bool_],
) -> int:
    """Mark in ``out[a, b]`` (``a < b``) the arm pairs with a shape of ``rows``
    whose bounding spheres meet and whose capsules touch (within ``_SLACK``);
    returns how many pairs were marked."""
    found = 0
    for ii in range(rows.shape[0]):
        i = rows[ii]
        ai = arm_of[i]
        for j in range(c.shape[0]):
            aj = arm_of[j]
            if aj == ai:
                continue
            lo, hi = (ai, aj) if ai < aj else (aj, ai)
            if out[lo, hi]:
                continue
            dx, dy, dz = c[i, 0] - c[j, 0], c[i, 1] - c[j, 1], c[i, 2] - c[j, 2]
            if dx * dx + dy * dy + dz * dz > r2[i, j]:
                continue
            reach = rc[i] + rc[j] + _SLACK
            if _segment_dist2(p0[i], p1[i], p0[j], p1[j]) <= reach * reach:
                out[lo, hi] = True
                found += 1
    return found


@njit(cache=True)
def _pair_touches(
    ca: FloatArray,
    a0: FloatArray,
    a1: FloatArray,
    cb: FloatArray,
    b0: FloatArray,
    b1: FloatArray,
    r2: FloatArray,
    rca: FloatArray,
    rcb: FloatArray,
    out: npt.NDArray[np.bool_],
) -> None:
    """``out[k]``: at sample ``k`` a shape of arm a (centres ``ca``, capsule
    ends ``a0 a1``; (n, shapes, 3)) and a shape of arm b have meeting
    bounding spheres (squared radius sums ``r2``) and touching capsules
    (radii ``rca``, ``rcb``; within ``_SLACK``)."""
    for k in range(ca.shape[0]):
        hit = False
        for x in range(ca.shape[1]):
            for y in range(cb.shape[1]):
                dx = ca[k, x, 0] - cb[k, y, 0]
                dy = ca[k, x, 1] - cb[k, y, 1]
                dz = ca[k, x, 2] - cb[k, y, 2]
                if dx * dx + dy * dy + dz * dz > r2[x, y]:
                    continue
                reach = rca[x] + rcb[y] + _SLACK
                if _segment_dist2(a0[k, x], a1[k, x], b0[k, y], b1[k, y]) <= reach * reach:
                    hit = True
                    break
            if hit:
                break
        out[k] = hit


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
        self.geo = _Geometry(compiled)
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
                out[sel] = _record_joints(rec, times[sel])
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
            _pair_touches(
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
        windows = _Windows(p)
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
            for key, s, e in _static_uses(p, ctl, first_move):
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
                        best = (s2, (a1, a2), _message(what, name, a1, a2, s2, min(e1, e2)))
                        best_key = (what, name)
        return best


def _static_uses(p: Problem, ctl: MotionLog, first_move: float) -> list[Use]:
    """The exclusive zones an arm starts in, held until it first moves."""
    out: list[Use] = []
    for z in p.arm_start_zones[ctl.index]:
        if p.zone_exclusive[z] and first_move > 0:
            out.append((("inside exclusive zone", p.zone_names[z]), 0.0, first_move))
    return out


# ------------------------------------------------------------ live


class LiveMonitor:
    """The safety monitor as a kernel process: checks while the run goes on.

    Call :meth:`start` before running the kernel. A violation raises
    :class:`SafetyViolation` out of :meth:`EventLoop.run <workcell.sim.events.loop.EventLoop.run>`
    at the first violating sample, with a ``"monitor"`` event at that time
    in the trace and the partial trace on the exception. What it samples and
    what it skips: module docstring.

    Parameters
    ----------
    compiled : CompiledCell
    kernel : EventLoop
    arms : sequence of MotionLog
        Read only for their motion records, the segment in progress and
        their task records (never the coordinator, plan or zone manager).
    trace : Trace
    period : float
        Seconds between collision samples.
    tol : float
        Time tolerance of the zone checks, seconds.
    lookahead : int
        Samples of a moving arm's positions computed at once.
    horizon : float
        Seconds: an arm's predicted zone uses that start further ahead are
        compared with the other arms' uses later, when they come within it.

    Attributes
    ----------
    samples : int
        Collision samples taken.
    wakes : int
        EventLoop callbacks of the monitor (samples, events while no arm moves,
        predicted overlaps).
    pair_tests : int
        Arm pairs put to the bounding-sphere test.
    """

    def __init__(
        self,
        compiled: CompiledCell,
        kernel: EventLoop,
        arms: Sequence[MotionLog],
        trace: Trace,
        period: float = 0.02,
        tol: float = 1e-6,
        lookahead: int = 32,
        horizon: float = 2.0,
    ) -> None:
        self.cc = compiled
        self.p: Problem = compiled.problem
        self.kernel = kernel
        self.arms = list(arms)
        self.trace = trace
        self.period = float(period)
        self.tol = float(tol)
        self.lookahead = int(lookahead)
        self.horizon = float(horizon)
        self.geo = _Geometry(compiled)
        self._windows = _Windows(self.p)
        A = len(self.arms)
        self.samples = 0
        self.wakes = 0
        self.pair_tests = 0
        # collision state
        S = int(self.geo.offsets[-1])
        self._centres = np.zeros((S, 3))
        self._p0 = np.zeros((S, 3))
        self._p1 = np.zeros((S, 3))
        self._pos: list[tuple[Any, ...] | None] = [None] * A
        self._sampled: list[Any] = [None] * A  # pose state at the arm's last sample
        self._posed: list[Any] = [None] * A  # pose state in the FCL world
        self._decided: dict[tuple[int, int], tuple[Any, Any]] = {}
        self._rows: dict[tuple[int, ...], np.ndarray[Any, np.dtype[np.int64]]] = {}
        # zone state
        self._keys: list[Any] = [None] * A
        self._ver = [0] * A
        self._nrec = [0] * A
        self._first_move = [math.inf] * A
        self._start_closed = [False] * A
        self._tasks_seen = [0] * A
        self._open_tasks: list[list[tuple[int, TaskRecord]]] = [[] for _ in range(A)]
        self._refresh: list[tuple[float, int, int]] = []
        # per resource, per arm: finished uses as (end, start) sorted, and the
        # uses in progress (as predicted) as (start, end)
        self._closed: dict[tuple[str, str], dict[int, list[tuple[float, float]]]] = {}
        self._current: dict[tuple[str, str], dict[int, list[tuple[float, float]]]] = {}
        self._current_keys: list[set[tuple[str, str]]] = [set() for _ in range(A)]
        self._due: list[tuple[float, tuple[str, str], int, int, int, float, float, Any, Any]] = []
        self._seq = itertools.count()
        self._started = False

    # ------------------------------------------------------------ process
    def start(self) -> None:
        """Schedule the first sample (at the current time)."""
        if self._started:
            return
        self._started = True
        k = self._grid_after(self.kernel.now, inclusive=True)
        self.kernel.schedule(
            k * self.period, self._wake, k, absolute=True, priority=MONITOR_PRIORITY
        )

    def _grid_after(self, t: float, inclusive: bool = False) -> int:
        """Index of the first sample at (``inclusive``) or after ``t``."""
        P = self.period
        k = max(0, math.floor(t / P))
        while k * P < t or (not inclusive and k * P == t):
            k += 1
        while k > 0 and ((k - 1) * P > t or (inclusive and (k - 1) * P == t)):
            k -= 1
        return k

    def _wake(self, k: int) -> None:
        """A sample (``k >= 0``: at ``k * period``) or a wake at an event or a
        predicted overlap (``k < 0``). The arms' records are read first (an
        arm may have changed since the last wake: its predictions are then
        replaced), then the overlaps due by now are raised."""
        self.wakes += 1
        now = self.kernel.now
        arms = self.arms
        keys = [c.state() for c in arms]
        changed = [a for a, key in enumerate(keys) if key != self._keys[a]]
        refresh = self._refresh
        while refresh and refresh[0][0] <= now:
            _t, a, ver = heapq.heappop(refresh)
            if self._ver[a] == ver and a not in changed:
                changed.append(a)  # uses further ahead are due to be listed
        if changed:
            self._update_zones(sorted(changed), keys, now)
        self._zones_due(now)
        nxt = self.kernel.peek()
        if k >= 0 or nxt == math.inf:
            self._collisions(k, now, keys)
        if nxt == math.inf:
            return  # the run is over: nothing left to change
        moving = any(c.moving() for c in arms)
        settle = moving or any(self._sampled[a] != keys[a] for a in range(len(arms)))
        if settle:  # the next sample (events until then are read there)
            wake_k = self._grid_after(now)
            wake_at = wake_k * self.period
        else:  # nothing moves: nothing changes before the next event
            wake_at, wake_k = nxt, -1
        due = self._next_due()
        if due < wake_at:
            wake_at, wake_k = due, -1
        self.kernel.schedule(wake_at, self._wake, wake_k, absolute=True, priority=MONITOR_PRIORITY)

    # ------------------------------------------------------------ collisions
    def _poses(self, a: int, key: Any, k: int) -> tuple[FloatArray, ...]:
        """Arm ``a`` at sample ``k``: (n, 3) shape centres, (n, 4, 4) shape
        poses and the (n, 3) ends of the shapes' capsules."""
        ent = self._pos[a]
        moving = bool(key[2])
        if ent is not None and ent[0] == key and (not moving or 0 <= k - ent[1] < len(ent[2])):
            i = k - ent[1] if moving else 0
            return ent[2][i], ent[3][i], ent[4][i], ent[5][i]
        ctl = self.arms[a]
        now = self.kernel.now
        rec = ctl.open_record(now)
        if moving and k >= 0:  # a few samples ahead, while this segment lasts
            times = np.arange(k, k + self.lookahead, dtype=float) * self.period
        else:
            times = np.array([now])
        tfs = self.cc.cell.arms[a].shape_transforms(_record_joints(rec, times))
        centres = np.ascontiguousarray(tfs[:, :, :3, 3])
        p0, p1 = self.geo.ends(a, tfs)
        self._pos[a] = (key, k, centres, tfs, p0, p1) if k >= 0 or not moving else None
        return centres[0], tfs[0], p0[0], p1[0]

    def _collisions(self, k: int, now: float, keys: list[Any]) -> None:
        geo = self.geo
        off = geo.offsets
        dirty = []
        for a in range(len(self.arms)):
            state = (keys[a], k) if keys[a][2] else keys[a]
            if state == self._sampled[a]:
                continue
            self._sampled[a] = state
            c, _tfs, p0, p1 = self._poses(a, keys[a], k)
            sl = slice(off[a], off[a + 1])
            self._centres[sl] = c
            self._p0[sl] = p0
            self._p1[sl] = p1
            dirty.append(a)
        if not dirty:
            return
        self.samples += 1
        dkey = tuple(dirty)
        rows = self._rows.get(dkey)
        if rows is None:
            rows = np.concatenate([np.arange(off[a], off[a + 1], dtype=np.int64) for a in dirty])
            self._rows[dkey] = rows
        self.pair_tests += len(dirty) * (len(self.arms) - 1)
        out = np.zeros((len(self.arms), len(self.arms)), dtype=np.bool_)
        if not _touching_pairs(
            self._centres, self._p0, self._p1, rows, geo.r2, geo.rc, geo.arm_of, out
        ):
            return
        for a, b in np.argwhere(out).tolist():
            pair = (self._sampled[a], self._sampled[b])
            if self._decided.get((a, b)) == pair:
                continue  # neither arm moved since FCL found this pair apart
            self._decided[(a, b)] = pair
            for z in (a, b):
                if self._posed[z] != self._sampled[z]:
                    tfs = self._poses(z, keys[z], k)[1]
                    geo.world.set_group_transforms(geo.names[z], tfs)
                    self._posed[z] = self._sampled[z]
            if geo.collide(a, b):
                self._fail(geo.violation(a, b, now), now, now, (geo.names[a], geo.names[b]))

    @property
    def fcl_checks(self) -> int:
        """Arm pairs decided by FCL."""
        return self.geo.fcl_checks

    # ------------------------------------------------------------ zones
    def _update_zones(self, changed: list[int], keys: list[Any], now: float) -> None:
        p = self.p
        for a in changed:
            self._keys[a] = keys[a]
            self._ver[a] += 1
            ctl = self.arms[a]
            new: list[Use] = []
            for rec in ctl.records[self._nrec[a] :]:
                if rec.leg is not None:
                    self._first_move[a] = min(self._first_move[a], rec.start)
                    new.extend(self._windows.uses(rec))
            self._nrec[a] = len(ctl.records)
            rec = ctl.open_record(now)
            current = self._windows.uses(rec, math.inf)
            if not self._start_closed[a]:
                first = min(self._first_move[a], ctl.failed_at)
                if rec.leg is not None:
                    first = min(first, rec.start)
                if math.isfinite(first):
                    new.extend(_static_uses(p, ctl, first))
                    self._start_closed[a] = True
                else:
                    current.extend(_static_uses(p, ctl, math.inf))
            log = ctl.tasks
            if len(log) > self._tasks_seen[a]:  # tasks started since (in start order)
                self._open_tasks[a].extend(itertools.islice(log.items(), self._tasks_seen[a], None))
                self._tasks_seen[a] = len(log)
            still = []
            for t, _entry in self._open_tasks[a]:
                entry = log[t]  # the record as it is now (replaced as the task goes on)
                start, end, m = entry.start, entry.end, entry.mode
                if math.isfinite(end) or ctl.failed:
                    stop = end if math.isfinite(end) else max(start, ctl.failed_at)
                    new.extend(
                        (("holding tool", p.tool_names[i]), start, stop) for i in p.mode_tools[m]
                    )
                else:
                    current.extend(
                        (("holding tool", p.tool_names[i]), start, math.inf)
                        for i in p.mode_tools[m]
                    )
                    still.append((t, entry))
            self._open_tasks[a] = still
            # uses that start more than ``horizon`` ahead are listed later
            ahead = now + self.horizon * (1.0 + 1e-9) + 1e-9
            later = [u for u in current if u[1] > ahead]
            if later:
                current = [u for u in current if u[1] <= ahead]
                first = min(u[1] for u in later) - self.horizon
                heapq.heappush(self._refresh, (first, a, self._ver[a]))
            mine = (a, self._ver[a])
            for use in new:
                self._against(a, use, None)
            for use in current:
                self._against(a, use, mine)
            for key, s, e in new:
                bisect.insort(self._closed.setdefault(key, {}).setdefault(a, []), (e, s))
            cur = self._current
            for key in self._current_keys[a]:
                del cur[key][a]
            keys_a = self._current_keys[a] = set()
            for key, s, e in current:
                cur.setdefault(key, {}).setdefault(a, []).append((s, e))
                keys_a.add(key)

    def _against(self, a: int, use: Use, mine: Any) -> None:
        """Predict when ``use`` of arm ``a`` and another arm's use of the same
        resource overlap by more than ``tol``."""
        key, s, e = use
        tol = self.tol
        closed = self._closed.get(key)
        if closed is not None:
            for b, items in closed.items():
                if b == a:
                    continue
                for e2, s2 in reversed(items):
                    if e2 <= s + tol:
                        break
                    self._overlap(key, a, s, e, mine, b, s2, e2, None)
        current = self._current.get(key)
        if current is not None:
            for b, spans in current.items():
                if b == a:
                    continue
                for s2, e2 in spans:
                    self._overlap(key, a, s, e, mine, b, s2, e2, (b, self._ver[b]))

    def _overlap(
        self,
        key: tuple[str, str],
        a: int,
        s1: float,
        e1: float,
        v1: Any,
        b: int,
        s2: float,
        e2: float,
        v2: Any,
    ) -> None:
        start, end = max(s1, s2), min(e1, e2)
        if end - start > self.tol:
            first, second = (a, b) if (s1, a) <= (s2, b) else (b, a)
            heapq.heappush(
                self._due,
                (start + self.tol, key, next(self._seq), first, second, start, end, v1, v2),
            )

    def _valid(self, v: Any) -> bool:
        return v is None or self._ver[v[0]] == v[1]

    def _next_violation(self) -> float:
        due = self._due
        while due and not (self._valid(due[0][7]) and self._valid(due[0][8])):
            heapq.heappop(due)
        return due[0][0] if due else math.inf

    def _next_due(self) -> float:
        """When the monitor must look again without a kernel event: a
        predicted overlap, or uses further ahead to list."""
        refresh = self._refresh
        while refresh and self._ver[refresh[0][1]] != refresh[0][2]:
            heapq.heappop(refresh)
        return min(self._next_violation(), refresh[0][0] if refresh else math.inf)

    def _zones_due(self, now: float) -> None:
        while self._next_violation() <= now:
            _t, (what, name), _n, a, b, start, end, _v1, _v2 = heapq.heappop(self._due)
            na, nb = self.arms[a].name, self.arms[b].name
            stop = end if end <= now else math.inf
            self._fail(_message(what, name, na, nb, start, stop), start, now, (na, nb))

    # ------------------------------------------------------------ failing
    def _fail(self, msg: str, t: float, now: float, names: tuple[str, str]) -> None:
        self.trace.add(now, "monitor", detail=msg)
        self.trace.sort()
        raise SafetyViolation(msg, time=t, found=now, arms=names, trace=self.trace)
