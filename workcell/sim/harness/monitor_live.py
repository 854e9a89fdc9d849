"""The safety monitor as an event-loop process: it checks while the run goes on.

The rules are those of :mod:`workcell.sim.harness.monitor` (which checks a
finished run); this module samples them live and raises at the first
violating sample. It reads only the arms' published motion records
(:class:`~workcell.sim.protocol.records.MotionLog`).
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

from multiarm.types import FloatArray
from scheduler import Problem
from workcell.compile import CompiledCell
from workcell.sim.events.loop import EventLoop
from workcell.sim.events.trace import Trace
from workcell.sim.harness.monitor import (
    MONITOR_PRIORITY,
    MonitorGeometry,
    SafetyViolation,
    Use,
    ZoneWindows,
    record_joints,
    static_uses,
    touching_pairs,
    violation_message,
)
from workcell.sim.harness.monitor_geometry import first_touching_sample
from workcell.sim.protocol.records import MotionLog, TaskRecord

__all__ = ["LiveMonitor"]


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
        self.geo = MonitorGeometry(compiled)
        self._windows = ZoneWindows(self.p)
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
        keys: list[Any] = [c.state() for c in arms]
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
        sampled = self._sampled
        due = self._next_due()
        if not (moving or any(sampled[a] != keys[a] for a in range(len(arms)))):
            # nothing moves: nothing changes before the next event
            wake_at, wake_k = nxt, -1
        elif any(sampled[a] != keys[a] and not keys[a][2] for a in range(len(arms))):
            # an arm came to rest or changed: the next sample
            wake_k = self._grid_after(now)
            wake_at = wake_k * self.period
        else:  # the next sample some pair may touch at, or that sees the next event
            wake_k = self._next_sample(now, nxt, due, keys)
            wake_at = wake_k * self.period
        if due < wake_at:
            wake_at, wake_k = due, -1
        self.kernel.schedule(wake_at, self._wake, wake_k, absolute=True, priority=MONITOR_PRIORITY)

    # ------------------------------------------------------------ collisions
    def _next_sample(self, now: float, nxt: float, due: float, keys: list[Any]) -> int:
        """The next sample to wake for while some arm moves and every arm at
        rest has been sampled: the first at which a moving arm's shapes pass
        the pre-tests against another arm's (its segment in progress going
        on as it goes), or else the first that sees the next kernel event
        (the records cannot change before it), or the one at or after
        ``due``. The samples skipped are decided here, in compiled batches;
        at each of them every pair would pass the pre-tests apart, so the
        old wake there could only have found nothing."""
        first = self._grid_after(now)
        limit = max(first, self._grid_after(nxt, inclusive=True)) if nxt < math.inf else first
        if due < limit * self.period:
            limit = max(first, self._grid_after(due, inclusive=True))
        movers = [a for a in range(len(self.arms)) if keys[a][2]]
        if not movers:
            return first
        geo = self.geo
        off = geo.offsets
        rows = self._rows_of(tuple(movers))
        k = first
        while k < limit:
            n = min(limit - k, self.lookahead)
            c = np.empty((n, *self._centres.shape))
            p0 = np.empty_like(c)
            p1 = np.empty_like(c)
            c[:] = self._centres
            p0[:] = self._p0
            p1[:] = self._p1
            for a in movers:
                wc, w0, w1 = self._window(a, keys[a], k, n)
                sl = slice(off[a], off[a + 1])
                c[:, sl] = wc
                p0[:, sl] = w0
                p1[:, sl] = w1
            hit = first_touching_sample(c, p0, p1, rows, geo.r2, geo.rc, geo.arm_of)
            if hit >= 0:
                self.samples += hit
                return k + hit
            self.samples += n
            k += n
        return limit

    def _rows_of(self, arms: tuple[int, ...]) -> npt.NDArray[np.int64]:
        """The shape rows of ``arms`` (cached)."""
        rows = self._rows.get(arms)
        if rows is None:
            off = self.geo.offsets
            rows = np.concatenate([np.arange(off[a], off[a + 1], dtype=np.int64) for a in arms])
            self._rows[arms] = rows
        return rows

    def _window(self, a: int, key: Any, k: int, n: int) -> tuple[FloatArray, ...]:
        """Moving arm ``a`` at samples ``k .. k + n - 1``: (n, shapes, 3)
        centres and capsule ends (from the positions computed ahead, or
        computed now for at least ``lookahead`` samples)."""
        ent = self._pos[a]
        if ent is None or ent[0] != key or not (k - ent[1] >= 0 and k + n - ent[1] <= len(ent[2])):
            self._fill(a, key, k, max(n, self.lookahead))
            ent = self._pos[a]
            assert ent is not None
        i = k - ent[1]
        return ent[2][i : i + n], ent[4][i : i + n], ent[5][i : i + n]

    def _fill(self, a: int, key: Any, k: int, n: int) -> None:
        """Compute moving arm ``a``'s positions at samples ``k .. k + n - 1``."""
        rec = self.arms[a].open_record(self.kernel.now)
        times = np.arange(k, k + n, dtype=float) * self.period
        tfs = self.cc.cell.arms[a].shape_transforms(record_joints(rec, times))
        centres = np.ascontiguousarray(tfs[:, :, :3, 3])
        p0, p1 = self.geo.ends(a, tfs)
        self._pos[a] = (key, k, centres, tfs, p0, p1)

    def _poses(self, a: int, key: Any, k: int) -> tuple[FloatArray, ...]:
        """Arm ``a`` at sample ``k``: (n, 3) shape centres, (n, 4, 4) shape
        poses and the (n, 3) ends of the shapes' capsules."""
        ent = self._pos[a]
        moving = bool(key[2])
        if ent is not None and ent[0] == key and (not moving or 0 <= k - ent[1] < len(ent[2])):
            i = k - ent[1] if moving else 0
            return ent[2][i], ent[3][i], ent[4][i], ent[5][i]
        if moving and k >= 0:  # a few samples ahead, while this segment lasts
            self._fill(a, key, k, self.lookahead)
            ent = self._pos[a]
            assert ent is not None
            return ent[2][0], ent[3][0], ent[4][0], ent[5][0]
        now = self.kernel.now
        rec = self.arms[a].open_record(now)
        tfs = self.cc.cell.arms[a].shape_transforms(record_joints(rec, np.array([now])))
        centres = np.ascontiguousarray(tfs[:, :, :3, 3])
        p0, p1 = self.geo.ends(a, tfs)
        self._pos[a] = None if moving else (key, k, centres, tfs, p0, p1)
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
        rows = self._rows_of(tuple(dirty))
        self.pair_tests += len(dirty) * (len(self.arms) - 1)
        out = np.zeros((len(self.arms), len(self.arms)), dtype=np.bool_)
        if not touching_pairs(
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
                    new.extend(static_uses(p, ctl, first))
                    self._start_closed[a] = True
                else:
                    current.extend(static_uses(p, ctl, math.inf))
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
            closed = self._closed
            for key, s, e in new:
                items = closed.setdefault(key, {}).setdefault(a, [])
                if not items or items[-1] <= (e, s):
                    items.append((e, s))  # uses mostly close in time order
                else:
                    bisect.insort(items, (e, s))
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
            after = s + tol
            for b, items in closed.items():
                if b == a or items[-1][0] <= after:
                    continue  # (sorted by end: none of b's ends after ``use`` starts)
                for e2, s2 in reversed(items):
                    if e2 <= after:
                        break
                    self._overlap(key, a, s, e, mine, b, s2, e2, None)
        current = self._current.get(key)
        if current is not None:
            ver = self._ver
            for b, spans in current.items():
                if b == a:
                    continue
                for s2, e2 in spans:
                    if min(e, e2) - max(s, s2) > tol:
                        self._overlap(key, a, s, e, mine, b, s2, e2, (b, ver[b]))

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
            self._fail(violation_message(what, name, na, nb, start, stop), start, now, (na, nb))

    # ------------------------------------------------------------ failing
    def _fail(self, msg: str, t: float, now: float, names: tuple[str, str]) -> None:
        self.trace.add(now, "monitor", detail=msg)
        self.trace.sort()
        raise SafetyViolation(msg, time=t, found=now, arms=names, trace=self.trace)
