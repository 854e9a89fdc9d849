"""The independent safety monitor of a simulated run.

The monitor shares no code path with the coordinator: it never reads the
zone manager, the plan or the coordinator's grants. It reads only what the
arms physically did -- each arm's record of its own motion (which
trajectory, from which offset, moving or standing, over which interval of
time; the actual joints including any lost steps) -- and the compiled cell
(arm geometry, the modes' zone windows and tools). From these it checks,
at every sample:

* **collisions**: no two arms touch, with FCL (:class:`workcell.geometry.CollisionWorld`,
  the only module that imports it) on the arms' collision shapes; a cheap
  bounding-sphere test picks the samples FCL decides;
* **zone invariants**: at most one arm inside each exclusive zone, at most
  one arm moving in each shared zone, at most one holder of each tool. An
  arm is inside a zone while its trajectory is within the zone's occupancy
  window (an arm stopped exactly at the window's start border is outside,
  waiting), and moves in a shared zone while its trajectory advances within
  a move window. An arm holds a task's tools from the task's start to its
  end; an arm that fails is retracted to its home joints and gives its
  tools back at the failure (its record ends there).

Any violation fails the run loudly with :class:`SafetyViolation` (and is
recorded in the trace as a ``"monitor"`` event).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from multiarm.errors import MultiarmError
from multiarm.types import FloatArray
from scheduler import Problem
from workcell.compile import CompiledCell
from workcell.geometry import CollisionWorld
from workcell.sim.controller import ArmController
from workcell.sim.trace import Trace

__all__ = ["SafetyMonitor", "SafetyViolation"]


class SafetyViolation(MultiarmError, RuntimeError):
    """The safety monitor saw two arms collide or a zone invariant broken."""


class SafetyMonitor:
    """Checks a finished run (module docstring).

    Parameters
    ----------
    compiled : CompiledCell
    period : float
        Sampling period of the collision check, seconds.
    tol : float
        Time tolerance of the zone checks, seconds.
    """

    def __init__(self, compiled: CompiledCell, period: float = 0.02, tol: float = 1e-6) -> None:
        self.cc = compiled
        self.period = float(period)
        self.tol = float(tol)
        self.world = CollisionWorld()
        cell = compiled.cell
        for arm, q in zip(cell.arms, cell.start, strict=True):
            self.world.add_arm(arm, q=q)
        self.radii = [np.array([s.radius() for s in arm.shapes]) for arm in cell.arms]
        self.samples = 0
        self.fcl_checks = 0

    # ------------------------------------------------------------ positions
    @staticmethod
    def joints(ctl: ArmController, times: FloatArray) -> FloatArray:
        """(N, dof) actual joints of an arm at ``times`` from its motion record."""
        out = np.repeat(ctl.home_q[None, :], len(times), axis=0)
        for t0, t1, leg, tau0, moving, extra in ctl.motion:
            sel = np.flatnonzero((times >= t0) & (times < t1))
            if not len(sel):
                continue
            if leg is None:
                out[sel] = extra
                continue
            tau = tau0 + (times[sel] - t0) if moving else np.full(len(sel), tau0)
            out[sel] = leg.trajectory.sample(tau) + extra
        if ctl.motion:  # after the last record: where it stands
            t0, t1, leg, tau0, moving, extra = ctl.motion[-1]
            sel = np.flatnonzero(times >= t1)
            if len(sel):
                if leg is None:
                    out[sel] = extra
                else:
                    end = tau0 + (t1 - t0) if moving else tau0
                    out[sel] = leg.trajectory.sample(np.array([end]))[0] + extra
        return out

    # ------------------------------------------------------------ checks
    def check(self, arms: Sequence[ArmController], t_end: float, trace: Trace) -> None:
        """Check the whole run up to ``t_end``.

        Raises
        ------
        SafetyViolation
            Naming the arms, the zone or shapes, and the time.
        """
        try:
            self._zones(arms)
            self._collisions(arms, t_end)
        except SafetyViolation as exc:
            trace.add(t_end, "monitor", detail=str(exc))
            raise

    def _collisions(self, arms: Sequence[ArmController], t_end: float) -> None:
        cell = self.cc.cell
        n = max(1, math.ceil(t_end / self.period) + 1)
        times = np.minimum(np.arange(n) * self.period, t_end)
        self.samples += n
        centres = []
        tfs_all = []
        for ctl, arm in zip(arms, cell.arms, strict=True):
            q = self.joints(ctl, times)
            tfs = arm.shape_transforms(q)
            tfs_all.append(tfs)
            centres.append(tfs[:, :, :3, 3])
        for a in range(len(arms)):
            for b in range(a + 1, len(arms)):
                d = np.linalg.norm(centres[a][:, :, None, :] - centres[b][:, None, :, :], axis=-1)
                near = d - (self.radii[a][:, None] + self.radii[b][None, :]) <= 0.0
                for i in np.flatnonzero(near.any(axis=(1, 2))):
                    self.fcl_checks += 1
                    na, nb = cell.arms[a].name, cell.arms[b].name
                    self.world.set_group_transforms(na, tfs_all[a][i])
                    self.world.set_group_transforms(nb, tfs_all[b][i])
                    if self.world.collide(na, nb):
                        pairs = self.world.colliding_pairs(na, nb)
                        raise SafetyViolation(
                            f"arms {na!r} and {nb!r} collide at t = {times[i]:.6g} s "
                            f"({', '.join(f'{x} - {y}' for x, y in pairs)})"
                        )

    def _zones(self, arms: Sequence[ArmController]) -> None:
        p: Problem = self.cc.problem
        Z = p.n_zones
        use: dict[tuple[str, str], list[tuple[float, float, str]]] = {}
        for ctl in arms:
            first_move = math.inf
            for t0, t1, leg, tau0, moving, _extra in ctl.motion:
                if leg is None:
                    continue
                first_move = min(first_move, t0)
                if leg.kind != "task":
                    continue
                sh = p.shapes[leg.mode]
                ta, tb = tau0, tau0 + (t1 - t0) if moving else tau0
                for r, s, e in sh.exclusive:
                    if moving:
                        lo, hi = max(s, ta), min(e, tb)
                        if hi > lo:
                            use.setdefault(("inside exclusive zone", p.zone_names[r]), []).append(
                                (t0 + lo - ta, t0 + hi - ta, ctl.name)
                            )
                    elif s < ta < e and t1 > t0:
                        use.setdefault(("inside exclusive zone", p.zone_names[r]), []).append(
                            (t0, t1, ctl.name)
                        )
                if moving:
                    for r, s, e in sh.moves:
                        lo, hi = max(s, ta), min(e, tb)
                        if hi > lo:
                            use.setdefault(
                                ("moving in shared zone", p.zone_names[r - Z]), []
                            ).append((t0 + lo - ta, t0 + hi - ta, ctl.name))
            a = ctl.index
            first_move = min(first_move, ctl.failed_at)  # a failed arm is retracted
            for z in p.arm_start_zones[a]:
                if p.zone_exclusive[z] and first_move > 0:
                    use.setdefault(("inside exclusive zone", p.zone_names[z]), []).append(
                        (0.0, first_move, ctl.name)
                    )
            for t, (start, end, _w, m) in ctl.task_log.items():
                if math.isfinite(end):
                    stop = end
                elif ctl.failed:
                    # interrupted by the arm's failure: the arm is retracted
                    # to its home joints and gives its tools back at once
                    stop = max(start, ctl.failed_at)
                else:
                    stop = ctl.motion[-1][1] if ctl.motion else start
                for k in p.mode_tools[m]:
                    use.setdefault(("holding tool", p.tool_names[k]), []).append(
                        (start, stop, ctl.name)
                    )
                del t
        tol = self.tol
        for (what, name), items in use.items():
            items.sort()
            for i, (_s1, e1, a1) in enumerate(items):
                for s2, e2, a2 in items[i + 1 :]:
                    if s2 >= e1 - tol:
                        break
                    if a1 != a2 and min(e1, e2) - s2 > tol:
                        raise SafetyViolation(
                            f"arms {a1!r} and {a2!r} both {what} {name!r} during "
                            f"[{s2:.6g}, {min(e1, e2):.6g}) s"
                        )
