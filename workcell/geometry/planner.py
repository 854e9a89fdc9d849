"""Collision-free detours in joint space with OMPL (SEEDS.md S2.6, S2.12).

When an arm's path is blocked by another arm standing still (geometric
deadlock, S2.6), the coordinator may answer "continue with an alternative
trajectory" (S2.12). :func:`plan_detour` computes it: a joint-space path from
``q_start`` to ``q_goal`` that keeps the arm's collision shapes clear of a
set of obstacles (typically the other arm's shapes at its parked pose).

This is the only module of the package that imports :mod:`ompl`.

* The joint space is an OMPL ``RealVectorStateSpace`` bounded by the joint
  limits (revolute joints have limits, so they are not wrapped).
* Collision checks go through :class:`workcell.geometry.world.CollisionWorld`
  (FCL): the arm's shapes, moved by ``arm.shape_transforms``, against the
  obstacles' broadphase manager, first hit only.
* Edges are checked by a motion validator that interpolates the straight
  joint-space segment in steps whose displacement bound
  (``arm.displacement_bound``) is at most ``resolution`` metres, with one
  vectorised forward-kinematics call per edge. With ``clearance >=
  resolution`` the check is exact in the conservative direction: every
  point of the arm is within ``resolution`` of a checked pose, and those
  poses keep ``clearance`` from every obstacle (the same argument as the
  zone sweep, :mod:`workcell.geometry.zone_sweep`). A coarser resolution is faster
  and, with clearance, rejects some paths that exist (the S2.12 compromise).
* Prepared obstacles and contexts are cached per (arm, obstacle set); OMPL
  objects are made per call and dropped at its end (``notes/deps.md`` §1).

Determinism
-----------
OMPL draws every random seed from one process-wide generator seeded by
``ompl.util.RNG.setSeed``; a seed set after random numbers were first drawn
logs "Random number generation already started" but still reseeds that
generator, so every OMPL object created *afterwards* (state space, sampler,
planner, simplifier) gets reproducible seeds. Each call therefore sets the
seed first and then builds a fresh space, setup and planner: the same
``seed`` gives the same path, whatever ran before (tested). Two caveats:
a wall-clock ``budget`` that expires mid-search cuts the search at a
machine-dependent point (use ``max_checks`` for a reproducible work limit),
and OMPL ignores the seed 0, so the seed given to OMPL is ``seed + 1``.

Examples
--------
>>> import numpy as np
>>> from workcell.arms.base import LinkShape
>>> from tests.workcell.geometry.fake_arm import PlanarArm
>>> arm = PlanarArm()
>>> post = np.eye(4)
>>> post[:3, 3] = (0.45, 0.2, 0.1)
>>> obstacles = ObstacleSet([(LinkShape("post", "box", (0.05, 0.05, 0.4), 0), post)])
>>> res = plan_detour(arm, np.array([0.0, 0.0]), np.array([1.2, 0.0]), obstacles, budget=2.0)
>>> res.status
'solved'
>>> check_path(arm, res.path, obstacles, step=0.002)
True
>>> plan_detour(arm, np.array([0.0, 0.0]), np.array([-0.5, 0.0]), obstacles).status
'direct'
"""

from __future__ import annotations

import itertools
import math
import time
from collections import OrderedDict
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import FloatArray, IntArray, Transform
from workcell.arms._kinematics_jit import frame_products
from workcell.arms.base import Arm, LinkShape, shape_frames
from workcell.geometry._zone_sweep_jit import capsules_touch, pose_near, segment_points
from workcell.geometry.world import CollisionWorld
from workcell.geometry.zone_sweep import JointTrajectoryLike, _shape_capsules, sample_trajectory

__all__ = [
    "DetourPlanner",
    "DetourResult",
    "DetourStatus",
    "ObstacleSet",
    "check_path",
    "first_contact",
    "plan_detour",
    "write_ompl_benchmark_log",
]

DetourStatus = Literal[
    "direct", "solved", "start_in_collision", "goal_in_collision", "timeout", "unverified"
]
"""Outcome of :func:`plan_detour`."""

_FAST_MOTION_PLANNERS = frozenset(
    {"RRTConnect", "RRT", "PRM", "PRMstar", "RRTstar", "InformedRRTstar", "SORRTstar"}
)
"""Planners that only call ``checkMotion(s1, s2)`` and can use the batched validator.

Others (the KPIECE family, BIT*, FMT*, ...) may ask for the last valid state
of a failed edge, which a Python motion validator cannot return; they use
OMPL's own discrete validator over the single-state checker instead (slower,
same resolution).
"""

_CACHE_SIZE = 32


# ------------------------------------------------------------------ records


@dataclass(frozen=True, slots=True)
class DetourResult:
    """What :func:`plan_detour` found.

    Attributes
    ----------
    status : {"direct", "solved", "start_in_collision", "goal_in_collision", "timeout", \
"unverified"}
        ``direct``: the straight joint-space segment is already free (no
        planning); ``solved``: a detour was planned; the other values mean
        there is no path (``path`` is empty); ``unverified``: OMPL found a
        path, but neither it nor its unsimplified form passes the edge check
        (:meth:`DetourPlanner.path_free`).
    path : (K, dof) float
        Joint vectors from ``q_start`` to ``q_goal`` (both included),
        simplified and checked edge by edge; (0, dof) when there is none.
    planning_time : float
        Wall time of the whole call, seconds (the process's one-time import
        of OMPL excluded).
    n_checks : int
        Arm configurations checked for collision.
    planner : str
    seed : int
    """

    status: DetourStatus
    path: FloatArray
    planning_time: float
    n_checks: int
    planner: str
    seed: int

    @property
    def solved(self) -> bool:
        """True for ``direct`` and ``solved``."""
        return self.status in ("direct", "solved")

    def length(self) -> float:
        """Joint-space length of the path (sum of edge norms); 0 without a path."""
        if len(self.path) < 2:
            return 0.0
        return float(np.linalg.norm(np.diff(self.path, axis=0), axis=1).sum())


@dataclass(frozen=True, eq=False, init=False)
class ObstacleSet:
    """Obstacles for detour planning: shapes at fixed world poses.

    Build it once (e.g. with :meth:`from_arm` for an arm parked at a pose) and
    pass the same object to many :func:`plan_detour` calls: the FCL objects
    and the planning context are cached per (arm, obstacle set) identity.

    Parameters
    ----------
    items : sequence of (LinkShape, (4, 4) float)
        Each shape with the world pose of its centre.
    name : str
        Used in object names and messages.
    """

    items: tuple[tuple[LinkShape, Transform], ...]
    name: str = "obstacles"

    def __init__(
        self, items: Iterable[tuple[LinkShape, Transform]], name: str = "obstacles"
    ) -> None:
        checked: list[tuple[LinkShape, Transform]] = []
        for i, item in enumerate(items):
            try:
                shape, tf = item
            except (TypeError, ValueError):
                raise ValidationError(
                    f"obstacle {i} of {name!r} must be a (LinkShape, 4x4 transform) pair"
                ) from None
            t = np.array(tf, dtype=float)
            if t.shape != (4, 4) or not np.all(np.isfinite(t)):
                raise ValidationError(
                    f"obstacle {i} ({getattr(shape, 'name', '?')!r}) of {name!r}: "
                    f"transform must be a finite (4, 4) array"
                )
            t.setflags(write=False)
            checked.append((shape, t))
        object.__setattr__(self, "items", tuple(checked))
        object.__setattr__(self, "name", name)

    @classmethod
    def from_arm(cls, arm: Arm, q: FloatArray, padding: float = 0.0) -> ObstacleSet:
        """The shapes of ``arm`` standing at ``q`` (e.g. an arm parked in a zone).

        Parameters
        ----------
        arm : Arm
        q : (dof,) float
        padding : float, metres
            Grow every shape (capsule/sphere/cylinder radius; box sides by
            ``2 padding``).
        """
        tfs = arm.shape_transforms(np.asarray(q, dtype=float)[None, :])[0]
        items = []
        for s, t in zip(arm.shapes, tfs, strict=True):
            items.append((_grow(s, padding), t))
        return cls(items, name=arm.name)

    def __len__(self) -> int:
        return len(self.items)


def _grow(s: LinkShape, padding: float) -> LinkShape:
    if padding == 0:
        return s
    size = list(s.size)
    if s.kind == "box":
        size = [v + 2 * padding for v in size]
    else:
        size[0] += padding
        if s.kind == "cylinder":
            size[1] += 2 * padding
    return LinkShape(s.name, s.kind, tuple(size), s.frame, s.offset)


def _obstacle_set(obstacles: ObstacleSet | Iterable[tuple[LinkShape, Transform]]) -> ObstacleSet:
    return obstacles if isinstance(obstacles, ObstacleSet) else ObstacleSet(obstacles)


# ------------------------------------------------------------------ context


@dataclass(eq=False)
class DetourPlanner:
    """A planning context for one arm among one obstacle set (FCL objects built once).

    Parameters
    ----------
    arm : Arm
    obstacles : ObstacleSet
    resolution : float, metres
        Largest displacement bound between two checked poses of an edge.
    clearance : float, metres
        Growth of the arm's shapes for every check (see the module docstring).

    Attributes
    ----------
    n_checks : int
        Configurations checked so far (all calls).
    """

    arm: Arm
    obstacles: ObstacleSet
    resolution: float = 0.01
    clearance: float = 0.0
    n_checks: int = 0
    _world: CollisionWorld = field(init=False, repr=False)
    _lo: FloatArray = field(init=False, repr=False)
    _hi: FloatArray = field(init=False, repr=False)
    _lo_list: list[float] = field(init=False, repr=False)
    _hi_list: list[float] = field(init=False, repr=False)
    _local: FloatArray = field(init=False, repr=False)
    _idx: IntArray = field(init=False, repr=False)
    _off: FloatArray = field(init=False, repr=False)
    _hw: FloatArray = field(init=False, repr=False)
    _rad: FloatArray = field(init=False, repr=False)
    _ob0: FloatArray = field(init=False, repr=False)
    _ob1: FloatArray = field(init=False, repr=False)
    _orad: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise ValidationError(f"resolution must be > 0 m, got {self.resolution}")
        if not (math.isfinite(self.clearance) and self.clearance >= 0):
            raise ValidationError(f"clearance must be >= 0 m, got {self.clearance}")
        w = CollisionWorld()
        w.add_arm(self.arm, group="arm", padding=self.clearance)
        for i, (shape, tf) in enumerate(self.obstacles.items):
            w.add_link_shape(f"{self.obstacles.name}/{i}:{shape.name}", shape, "obstacles", tf)
        if not len(self.obstacles):
            w.add_link_shape(  # a far-away dummy keeps the group queryable
                "__none__", LinkShape("__none__", "sphere", (1e-6,), 0), "obstacles", _far()
            )
        self._world = w
        lim = np.asarray(self.arm.joint_limits, dtype=float)
        self._lo, self._hi = lim[:, 0], lim[:, 1]
        self._lo_list = (self._lo - 1e-9).tolist()
        self._hi_list = (self._hi + 1e-9).tolist()
        # Bounding capsules (as in the zone sweep): a pose whose capsules keep
        # clear of every obstacle capsule is free without asking FCL.
        self._local, rad = _shape_capsules(self.arm.shapes)
        self._rad = rad + self.clearance
        self._idx, self._off = shape_frames(self.arm)
        ends = np.concatenate([self._local, np.ones((len(self._local), 2, 1))], axis=2)
        self._hw = np.ascontiguousarray(np.einsum("sij,skj->ski", self._off, ends))
        shapes = [sh for sh, _ in self.obstacles.items]
        if shapes:
            ends, self._orad = _shape_capsules(shapes)
            tfs = np.stack([tf for _, tf in self.obstacles.items])
            self._ob0 = np.ascontiguousarray(
                np.matmul(tfs[:, :3, :3], ends[:, 0, :, None])[..., 0] + tfs[:, :3, 3]
            )
            self._ob1 = np.ascontiguousarray(
                np.matmul(tfs[:, :3, :3], ends[:, 1, :, None])[..., 0] + tfs[:, :3, 3]
            )
        else:
            self._ob0 = self._ob1 = np.zeros((0, 3))
            self._orad = np.zeros(0)

    # ----------------------------------------------------------- checks
    def first_invalid(self, qs: FloatArray) -> int:
        """Index of the first configuration (in order) in collision or off limits; -1 if none.

        Parameters
        ----------
        qs : (N, dof) float

        Returns
        -------
        int
        """
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        off = np.flatnonzero(~np.all((qs >= self._lo - 1e-9) & (qs <= self._hi + 1e-9), axis=1))
        stop = int(off[0]) if off.size else len(qs)
        hit = self._first_hit(qs[:stop]) if stop else -1
        if hit >= 0:
            return hit
        return stop if stop < len(qs) else -1

    def _first_hit(self, qs: FloatArray) -> int:
        """First colliding configuration of (N, dof) ``qs`` (limits not checked), or -1.

        A compiled bounding-capsule test clears most poses; FCL decides the
        rest exactly, in order.
        """
        fr = self.arm.frames(qs)
        pts = segment_points(fr, self._idx, self._hw)
        near = capsules_touch(pts[0], pts[1], self._rad, self._ob0, self._ob1, self._orad, 0.0)
        idx = np.flatnonzero(near)
        if idx.size:
            # shape poses only for the candidates FCL must decide
            tfs = frame_products(np.ascontiguousarray(fr[idx]), self._idx, self._off)
            k = self._world.first_collision("arm", tfs, "obstacles")
            hit = int(idx[k]) if k >= 0 else -1
        else:
            hit = -1
        self.n_checks += (hit + 1) if hit >= 0 else len(qs)
        return hit

    def _in_limits(self, q: FloatArray) -> bool:
        return all(
            lo <= v <= hi
            for v, lo, hi in zip(q.tolist(), self._lo_list, self._hi_list, strict=True)
        )

    def is_valid(self, q: FloatArray) -> bool:
        """Whether the arm at ``q`` (dof,) is within its limits and clear of the obstacles."""
        row = np.asarray(q, dtype=float).reshape(1, -1)
        if not self._in_limits(row[0]):
            return False
        # one compiled call clears most poses; the rest go to FCL
        if not pose_near(
            self.arm.frames(row),
            self._idx,
            self._hw,
            self._rad,
            self._ob0,
            self._ob1,
            self._orad,
            0.0,
        ):
            self.n_checks += 1
            return True
        return self._first_hit(row) < 0

    def edge_states(self, q0: FloatArray, q1: FloatArray) -> FloatArray:
        """Interior and end poses of the straight segment, end first.

        The number of steps ``n`` makes every step's displacement bound at
        most :attr:`resolution`; returns (n, dof): ``q1`` then
        ``q0 + k/n (q1 - q0)`` for ``k = 1 .. n-1``.
        """
        dq = np.asarray(q1, dtype=float) - np.asarray(q0, dtype=float)
        bound = float(self.arm.displacement_bound(dq[None, :])[0])
        n = max(1, math.ceil(bound / self.resolution))
        frac = np.r_[1.0, np.arange(1, n) / n]
        out: FloatArray = np.asarray(q0, dtype=float) + frac[:, None] * dq
        return out

    def segment_free(self, q0: FloatArray, q1: FloatArray) -> bool:
        """Whether the straight joint segment is free (``q0`` itself is assumed checked).

        The joint limits are a box, so with both ends inside every
        interpolated pose is inside too.
        """
        a, b = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
        if not (self._in_limits(a) and self._in_limits(b)):
            return False
        return self._first_hit(self.edge_states(a, b)) < 0

    def path_free(self, path: FloatArray) -> bool:
        """Whether every pose and every edge of a path (K, dof) is free."""
        p = np.atleast_2d(np.asarray(path, dtype=float))
        if not self.is_valid(p[0]):
            return False
        return all(self.segment_free(a, b) for a, b in itertools.pairwise(p))

    # --------------------------------------------------------- planning
    def plan(
        self,
        q_start: FloatArray,
        q_goal: FloatArray,
        *,
        budget: float = 0.1,
        seed: int = 0,
        planner: str = "RRTConnect",
        simplify: bool = True,
        max_checks: int | None = None,
    ) -> DetourResult:
        """Plan a detour; see :func:`plan_detour`."""
        _load_ompl()  # a one-time library load is not planning time
        t0 = time.perf_counter()
        checks0 = self.n_checks
        qs, qg = self._joint(q_start, "q_start"), self._joint(q_goal, "q_goal")
        if not (math.isfinite(budget) and budget > 0):
            raise ValidationError(f"budget must be > 0 s, got {budget}")
        if not isinstance(seed, int | np.integer) or seed < 0:
            raise ValidationError(f"seed must be an int >= 0, got {seed!r}")
        if max_checks is not None and max_checks < 1:
            raise ValidationError(f"max_checks must be >= 1, got {max_checks}")

        def done(status: DetourStatus, path: FloatArray) -> DetourResult:
            return DetourResult(
                status,
                path,
                time.perf_counter() - t0,
                self.n_checks - checks0,
                planner,
                int(seed),
            )

        empty = np.zeros((0, self.arm.dof))
        if not self.is_valid(qs):
            return done("start_in_collision", empty)
        if not self.is_valid(qg):
            return done("goal_in_collision", empty)
        if self.segment_free(qs, qg):
            return done("direct", np.stack([qs, qg]))
        paths = _ompl_plan(self, qs, qg, budget, int(seed), planner, simplify, max_checks, checks0)
        if not paths:
            return done("timeout", empty)
        # OMPL takes a piece of a checked edge as free (its shortcuts start
        # inside edges) and checks the two trees' edges in opposite
        # directions, so a path can miss our sampled edge check by less than
        # one sample: the simplified path, else the raw one, else none.
        for path in paths:
            path[0], path[-1] = qs, qg
            if self.path_free(path):
                return done("solved", path)
        return done("unverified", empty)

    def _joint(self, q: FloatArray, what: str) -> FloatArray:
        qq = np.asarray(q, dtype=float).reshape(-1)
        if qq.shape != (self.arm.dof,) or not np.all(np.isfinite(qq)):
            raise ValidationError(
                f"arm {self.arm.name!r}: {what} must be {self.arm.dof} finite joint values"
            )
        bad = np.flatnonzero((qq < self._lo - 1e-9) | (qq > self._hi + 1e-9))
        if bad.size:
            j = int(bad[0])
            raise ValidationError(
                f"arm {self.arm.name!r}: {what} joint {self.arm.joint_names[j]!r} = {qq[j]:.6g} "
                f"is outside its limits [{self._lo[j]:.6g}, {self._hi[j]:.6g}]"
            )
        return qq


def _load_ompl() -> None:
    """Import OMPL's modules (once per process; later calls cost a dict lookup)."""
    from ompl import base, geometric, util  # noqa: F401


def _far() -> Transform:
    t = np.eye(4)
    t[:3, 3] = 1e6
    return t


# -------------------------------------------------------------- OMPL glue


def _setup(
    ctx: DetourPlanner, seed: int, planner: str
) -> tuple[Any, Any, Any, list[Any], Callable[[Any], FloatArray]]:
    """Seed OMPL, then build space, SimpleSetup, planner (fresh objects, see Determinism)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(seed + 1)
    dof = ctx.arm.dof
    space = ob.RealVectorStateSpace(dof)
    bounds = ob.RealVectorBounds(dof)
    for j in range(dof):
        bounds.setLow(j, float(ctx._lo[j]))
        bounds.setHigh(j, float(ctx._hi[j]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)

    def to_np(s: Any) -> FloatArray:
        return np.array([s[j] for j in range(dof)], dtype=float)

    def valid(s: Any) -> bool:
        return bool(ctx.is_valid(to_np(s)))

    ss.setStateValidityChecker(valid)
    si = ss.getSpaceInformation()
    keep: list[Any] = []
    if planner in _FAST_MOTION_PLANNERS:

        class _Motion(ob.MotionValidator):  # type: ignore[misc]
            def checkMotion(self, s1: Any, s2: Any, *rest: Any) -> bool:
                return bool(ctx.segment_free(to_np(s1), to_np(s2)))

        mv = _Motion(si)
        keep.append(mv)
        si.setMotionValidator(mv)
    else:
        # OMPL's resolution is a fraction of the space's extent (deps.md §1).
        # bound(dq) = sum_j reach_j |dq_j| <= (sum_j reach_j) |dq|_2, so a
        # Euclidean joint step of resolution / sum_j reach_j keeps the
        # displacement bound of every step within `resolution`.
        reach = float(ctx.arm.displacement_bound(np.ones((1, dof)))[0])
        step = ctx.resolution / max(reach, 1e-12)
        si.setStateValidityCheckingResolution(min(1.0, step / space.getMaximumExtent()))
    return ss, si, _planner_class(planner), keep, to_np


def _planner_class(name: str) -> Any:
    """The ``ompl.geometric`` planner class called ``name``."""
    from ompl import base as ob
    from ompl import geometric as og

    known = sorted(
        n
        for n in dir(og)
        if isinstance(getattr(og, n), type) and issubclass(getattr(og, n), ob.Planner)
    )
    if name not in known:
        raise ValidationError(f"unknown OMPL planner {name!r} (known: {', '.join(known)})")
    return getattr(og, name)


def _ompl_plan(
    ctx: DetourPlanner,
    qs: FloatArray,
    qg: FloatArray,
    budget: float,
    seed: int,
    planner: str,
    simplify: bool,
    max_checks: int | None,
    checks0: int,
) -> list[FloatArray]:
    """The path found, simplified then raw (``simplify``), or none."""
    from ompl import base as ob
    from ompl import geometric as og

    ss, si, factory, _keep, to_np = _setup(ctx, seed, planner)
    start, goal = si.allocState(), si.allocState()
    for j in range(ctx.arm.dof):
        start[j] = float(qs[j])
        goal[j] = float(qg[j])
    ss.setStartAndGoalStates(start, goal)
    ss.setPlanner(factory(si))
    ss.setup()
    ptc = ob.timedPlannerTerminationCondition(budget)
    if max_checks is not None:
        limit = checks0 + max_checks
        work = ob.PlannerTerminationCondition(lambda: ctx.n_checks >= limit)
        ptc = ob.plannerOrTerminationCondition(ptc, work)
    status = ss.solve(ptc)
    if status.getStatus() != ob.PlannerStatus.EXACT_SOLUTION:
        return []
    path = og.PathGeometric(ss.getSolutionPath())
    raw = np.array([to_np(s) for s in path.getStates()], dtype=float)
    if simplify:
        # Vertex reduction then shortcuts, a fixed amount of work (reproducible
        # for a seed); ``simplifyMax`` shortened paths only a little more at
        # about 30x the checks (measured on scara4 detours).
        ps = og.PathSimplifier(si)
        ps.reduceVertices(path)
        ps.ropeShortcutPath(path)
    out = np.array([to_np(s) for s in path.getStates()], dtype=float)
    del path, ss, si
    return [out, raw] if simplify else [raw]


# ------------------------------------------------------------ public API

_CONTEXTS: OrderedDict[tuple[int, int, float, float], DetourPlanner] = OrderedDict()


def _context(arm: Arm, obs: ObstacleSet, resolution: float, clearance: float) -> DetourPlanner:
    key = (id(arm), id(obs), float(resolution), float(clearance))
    ctx = _CONTEXTS.get(key)
    if ctx is not None and ctx.arm is arm and ctx.obstacles is obs:
        _CONTEXTS.move_to_end(key)
        return ctx
    ctx = DetourPlanner(arm, obs, resolution=resolution, clearance=clearance)
    _CONTEXTS[key] = ctx  # holds arm and obs, so their ids are not reused meanwhile
    while len(_CONTEXTS) > _CACHE_SIZE:
        _CONTEXTS.popitem(last=False)
    return ctx


def plan_detour(
    arm: Arm,
    q_start: FloatArray,
    q_goal: FloatArray,
    obstacles: ObstacleSet | Iterable[tuple[LinkShape, Transform]],
    *,
    budget: float = 0.1,
    seed: int = 0,
    planner: str = "RRTConnect",
    resolution: float = 0.01,
    clearance: float = 0.0,
    simplify: bool = True,
    max_checks: int | None = None,
) -> DetourResult:
    """A collision-free joint-space path around obstacles (S2.6 geometric deadlock, S2.12).

    Parameters
    ----------
    arm : Arm
    q_start, q_goal : (dof,) float
        Within the joint limits.
    obstacles : ObstacleSet or iterable of (LinkShape, (4, 4) float)
        Pass an :class:`ObstacleSet` to reuse its prepared FCL objects and
        planning context across calls (a plain list is prepared per call).
    budget : float, seconds
        Wall-clock limit of the OMPL search.
    seed : int
        Same seed, same path (module docstring, "Determinism").
    planner : str
        An ``ompl.geometric`` planner class name (``"RRTConnect"``,
        ``"RRT"``, ``"PRM"``, ``"KPIECE1"``, ...).
    resolution : float, metres
        Largest displacement bound between two checked poses of an edge.
    clearance : float, metres
        Grow the arm's shapes for every check; ``clearance >= resolution``
        makes edge checks conservative.
    simplify : bool
        Shorten the path (OMPL's vertex reduction, then shortcuts).
    max_checks : int, optional
        Stop the search after that many configuration checks (a work limit
        that, unlike ``budget``, gives the same answer on every machine).

    Returns
    -------
    DetourResult
        ``start_in_collision`` / ``goal_in_collision`` are returned at once,
        ``direct`` when the straight segment is free (no planning),
        ``timeout`` when the search found nothing within its limits,
        ``unverified`` when OMPL's path (simplified and raw) fails the final
        edge check by less than a sample (taken as no path).

    Raises
    ------
    multiarm.errors.ValidationError
        For joint vectors of the wrong size or outside the limits, a bad
        budget, seed, resolution or planner name.
    """
    ctx = _context(arm, _obstacle_set(obstacles), resolution, clearance)
    return ctx.plan(
        q_start,
        q_goal,
        budget=budget,
        seed=seed,
        planner=planner,
        simplify=simplify,
        max_checks=max_checks,
    )


def check_path(
    arm: Arm,
    path: FloatArray,
    obstacles: ObstacleSet | Iterable[tuple[LinkShape, Transform]],
    step: float = 0.002,
) -> bool:
    """Independent dense check of a joint path: limits and FCL at every interpolated pose.

    Builds its own collision world (nothing shared with the planner) and
    interpolates every edge linearly so that no joint moves more than
    ``step`` (radians or metres) between two checked poses.

    Parameters
    ----------
    arm : Arm
    path : (K, dof) float
    obstacles : ObstacleSet or iterable of (LinkShape, (4, 4) float)
    step : float
        Largest joint change between checked poses.

    Returns
    -------
    bool
        True when every checked pose is within the limits and clear.

    Raises
    ------
    multiarm.errors.ValidationError
        For a non-positive step or a path of the wrong width.
    """
    if not (math.isfinite(step) and step > 0):
        raise ValidationError(f"step must be > 0, got {step}")
    p = np.atleast_2d(np.asarray(path, dtype=float))
    if p.shape[1] != arm.dof or len(p) == 0:
        raise ValidationError(f"path must be (K >= 1, {arm.dof}), got shape {p.shape}")
    pieces = [p[:1]]
    for a, b in itertools.pairwise(p):
        n = max(1, math.ceil(float(np.abs(b - a).max()) / step))
        pieces.append(a + (np.arange(1, n + 1) / n)[:, None] * (b - a))
    qs = np.concatenate(pieces)
    if not np.all(arm.within_limits(qs)):
        return False
    obs = _obstacle_set(obstacles)
    w = CollisionWorld()
    w.add_arm(arm, group="arm")
    for i, (shape, tf) in enumerate(obs.items):
        w.add_link_shape(f"o{i}", shape, "obstacles", tf)
    if not len(obs):
        return True
    tfs = arm.shape_transforms(qs)
    for k in range(len(qs)):
        w.set_group_transforms("arm", tfs[k])
        if w.collide("arm", "obstacles"):
            return False
    return True


def first_contact(
    arm: Arm,
    traj: JointTrajectoryLike,
    obstacles: ObstacleSet | Iterable[tuple[LinkShape, Transform]],
    padding: float = 0.005,
) -> float | None:
    """When a trajectory may first touch the obstacles (e.g. an arm parked in its way, S2.6).

    The trajectory is sampled as in the zone sweep
    (:func:`workcell.geometry.zone_sweep.sample_trajectory`: knots plus a grid,
    bisected until the displacement bound between samples is at most
    ``padding``) and the arm's shapes, grown by ``padding``, are checked at
    every sample. A true contact at a time ``t`` flags the sample just
    before ``t`` (the sweep's argument), so the returned time is never later
    than the first true contact, and ``None`` means the arm never touches
    the obstacles.

    Parameters
    ----------
    arm : Arm
    traj : JointTrajectoryLike
    obstacles : ObstacleSet or iterable of (LinkShape, (4, 4) float)
    padding : float, metres

    Returns
    -------
    float or None
        Seconds from the trajectory's start.

    Raises
    ------
    multiarm.errors.ValidationError
        For a bad padding or trajectory.
    """
    t, q = sample_trajectory(arm, traj, padding)
    ctx = _context(arm, _obstacle_set(obstacles), 0.01, float(padding))
    hit = ctx._first_hit(q)
    return None if hit < 0 else float(t[hit])


def write_ompl_benchmark_log(
    path: str | Path,
    arm: Arm,
    q_start: FloatArray,
    q_goal: FloatArray,
    obstacles: ObstacleSet | Iterable[tuple[LinkShape, Transform]],
    *,
    planners: Sequence[str] = ("RRTConnect", "RRT", "PRM"),
    runs: int = 5,
    budget: float = 0.5,
    seed: int = 0,
    resolution: float = 0.01,
    experiment: str = "detour",
) -> dict[str, dict[str, float]]:
    """Compare OMPL planners on one detour query with ``ompl.tools.Benchmark``.

    Writes OMPL's benchmark log format (readable by ``ompl_benchmark_statistics``
    and ``ompl.tools.readBenchmarkLog``) and returns a summary.

    Parameters
    ----------
    path : str or Path
        The log file to write.
    arm, q_start, q_goal, obstacles
        As for :func:`plan_detour`.
    planners : sequence of str
        ``ompl.geometric`` planner names.
    runs : int
        Runs per planner.
    budget : float, seconds
        Time limit per run.
    seed, resolution
        As for :func:`plan_detour`.
    experiment : str
        Experiment name in the log.

    Returns
    -------
    dict
        Per planner: ``solved`` (fraction of runs), ``time`` (median
        seconds), ``length`` (median simplified length of solved runs, NaN
        without any).

    Raises
    ------
    multiarm.errors.ValidationError
        For an unknown planner or a bad argument.
    """
    from ompl import tools as ot

    if runs < 1:
        raise ValidationError(f"runs must be >= 1, got {runs}")
    ctx = _context(arm, _obstacle_set(obstacles), resolution, 0.0)
    qs, qg = ctx._joint(q_start, "q_start"), ctx._joint(q_goal, "q_goal")
    # The batched motion validator serves the planners that allow it; the
    # first name decides the setup, so group the others separately.
    ss, si, _, _keep, _ = _setup(ctx, seed, planners[0] if planners else "RRTConnect")
    start, goal = si.allocState(), si.allocState()
    for j in range(arm.dof):
        start[j] = float(qs[j])
        goal[j] = float(qg[j])
    ss.setStartAndGoalStates(start, goal)

    bm = ot.Benchmark(ss, experiment)
    fast_setup = planners[0] in _FAST_MOTION_PLANNERS if planners else True
    for name in planners:
        factory = _planner_class(name)
        if (name in _FAST_MOTION_PLANNERS) != fast_setup:
            raise ValidationError(
                f"planner {name!r} cannot share a benchmark with {planners[0]!r}: "
                f"list planners of one kind ({', '.join(sorted(_FAST_MOTION_PLANNERS))}) "
                f"or only others"
            )
        bm.addPlanner(factory(si))
    bm.addExperimentParameter("resolution", "REAL", str(resolution))
    bm.addExperimentParameter("obstacles", "INTEGER", str(len(ctx.obstacles)))
    req = ot.Request(
        maxTime=float(budget),
        maxMem=1000.0,
        runCount=int(runs),
        displayProgress=False,
        saveConsoleOutput=False,  # else OMPL writes ompl_<host>_<date>.console in the cwd
        simplify=True,
    )
    bm.benchmark(req)
    bm.saveResultsToFile(str(path))
    summary: dict[str, dict[str, float]] = {}
    for p in bm.getRecordedExperimentData().planners:
        rows = [r.to_dict() for r in p.runs]
        solved = [str(r.get("solved BOOLEAN", "0")) in ("1", "true", "True") for r in rows]
        times = [float(r.get("time REAL", "nan")) for r in rows]
        lengths = [
            float(r.get("simplified solution length REAL", "nan"))
            for r, ok in zip(rows, solved, strict=True)
            if ok
        ]
        summary[str(p.name)] = {
            "solved": float(np.mean(solved)) if solved else 0.0,
            "time": float(np.median(times)) if times else math.nan,
            "length": float(np.median(lengths)) if lengths else math.nan,
        }
    del bm, ss, si
    return summary
