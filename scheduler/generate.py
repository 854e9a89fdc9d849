"""Seeded generators of scheduling problems with zones, tools and setups.

:func:`random_problem` makes problems like a multi-arm cell's: arms of
different speeds and capabilities, tasks with precedence and release times,
zone windows in exclusive and shared zones, tools, travel setup times, and
optionally arms starting inside zones and a blocking oracle. All numbers are
integers (so CP-SAT solves the exact problem), travel is Manhattan distance
on a grid times a power-of-two slowness (so setups obey the triangle
inequality), and the same seed gives the same problem.

Examples
--------
>>> p = random_problem(3, 12, 3, 1, seed=4)
>>> (p.n_arms, p.n_tasks, p.n_zones, p.n_tools) == (3, 12, 3, 1)
True
>>> random_problem(3, 12, 3, 1, seed=4).to_dict() == p.to_dict()
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import Seed, as_rng
from scheduler.problem import Model, Problem, Window
from scheduler.setup import TravelSetup

__all__ = ["MAX_TASKS", "GridBlocking", "random_problem"]

MAX_TASKS = 20_000
"""Most tasks :func:`random_problem` makes (its time grows about
quadratically: 0.65 s for 1,000 tasks, 26 s for 10,000 on a loaded machine)."""

_CAPS = ("gripper", "vacuum", "force_sensor", "camera")


@dataclass(frozen=True)
class GridBlocking:
    """A synthetic blocking oracle on the generator's grid: a parked arm whose
    pose lies within ``reach`` (Manhattan) of a mode's task location forces a
    detour of ``cost`` seconds."""

    task_xy: np.ndarray
    home_xy: np.ndarray
    mode_task: np.ndarray
    reach: int = 1
    cost_s: float = 3.0

    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        """``cost_s`` when the parked arm stands within ``reach`` grid steps
        (Manhattan) of the task's location, else 0 (see ``BlockingOracle.cost``)."""
        where = self.home_xy[arm] if pose_task < 0 else self.task_xy[pose_task]
        d = int(np.abs(self.task_xy[int(self.mode_task[mode])] - where).sum())
        return self.cost_s if d <= self.reach else 0.0


def random_problem(
    n_arms: int = 4,
    n_tasks: int = 30,
    n_zones: int = 4,
    n_tools: int = 1,
    seed: Seed = 0,
    *,
    precedence: float = 0.15,
    release_fraction: float = 0.2,
    zone_fraction: float = 0.6,
    tool_fraction: float = 0.15,
    setups: bool = True,
    start_zones: bool = False,
    blocking: bool = False,
    grid: int = 6,
) -> Problem:
    """A random problem (see the module docstring).

    Parameters
    ----------
    n_arms, n_tasks, n_zones, n_tools : int
    seed : int or Generator
    precedence : float
        Expected number of predecessors of a task among the 10 before it.
    release_fraction : float
        Share of tasks with a release time (parts arriving later).
    zone_fraction : float
        Share of tasks whose modes have zone windows (one or two zones).
    tool_fraction : float
        Share of tasks needing a tool.
    setups : bool
        Travel setup times between task locations.
    start_zones : bool
        Arms start inside distinct exclusive zones.
    blocking : bool
        Attach a :class:`GridBlocking` oracle.
    """
    for what, n, least, most in (
        ("n_arms", n_arms, 1, 1_000),
        ("n_tasks", n_tasks, 0, MAX_TASKS),
        ("n_zones", n_zones, 0, 1_000),
        ("n_tools", n_tools, 0, 1_000),
    ):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not least <= n <= most:
            raise ValidationError(
                f"random_problem: {what} must be an integer in [{least}, {most}], got {n!r}"
            )
    rng = as_rng(seed)
    m = Model(f"random-{n_arms}x{n_tasks}x{n_zones}")
    speeds = rng.choice([1.0, 1.0, 1.25, 1.5, 2.0], size=n_arms)
    caps = [{"gripper"} | {x for x in _CAPS[1:] if rng.random() < 0.5} for _ in range(n_arms)]
    zones = [m.add_zone(f"z{z}", "exclusive" if z % 2 == 0 else "shared") for z in range(n_zones)]
    for k in range(n_tools):
        m.add_tool(f"tool{k}")
    excl_zones = [z for z in zones if z % 2 == 0]
    starts = []
    if start_zones and excl_zones:
        pick = rng.permutation(len(excl_zones))
        starts = [
            [f"z{excl_zones[pick[a]]}"] if a < len(excl_zones) and rng.random() < 0.5 else []
            for a in range(n_arms)
        ]
    for a in range(n_arms):
        m.add_arm(
            f"arm{a}",
            capabilities=sorted(caps[a]),
            available=float(rng.integers(0, 3)),
            start_zones=starts[a] if starts else (),
        )
    task_xy = rng.integers(0, grid + 1, size=(n_tasks, 2))
    home_xy = rng.integers(0, grid + 1, size=(n_arms, 2))
    # releases spread over about half the expected load of an arm, so that the
    # arms' work, not the last arrival, decides the makespan
    span = max(10, int(0.5 * n_tasks * 8 / max(1, n_arms)))
    for t in range(n_tasks):
        preds = [
            q
            for q in range(max(0, t - 10), t)
            if rng.random() < precedence / 10 * 10 / max(1, min(t, 10))
        ]
        release = float(rng.integers(0, span)) if rng.random() < release_fraction else 0.0
        m.add_task(f"t{t}", release=release, predecessors=preds[:3])
    for t in range(n_tasks):
        need = {"gripper"} | ({str(rng.choice(_CAPS[1:]))} if rng.random() < 0.3 else set())
        capable = [a for a in range(n_arms) if need <= caps[a]] or [int(rng.integers(n_arms))]
        base = int(rng.integers(3, 13))
        touched = []
        if n_zones and rng.random() < zone_fraction:
            touched = list(
                rng.choice(n_zones, size=min(n_zones, 1 + int(rng.random() < 0.3)), replace=False)
            )
        layout = []
        for z in touched:
            s = int(rng.integers(0, base))
            e = int(rng.integers(s + 1, base + 1))
            layout.append((int(z), s, e))
        tool = (
            [f"tool{int(rng.integers(n_tools))}"]
            if n_tools and rng.random() < tool_fraction
            else []
        )
        for a in capable:
            f = float(speeds[a])
            d = max(1, round(base / f))
            wins = []
            for z, s, e in layout:
                s2 = min(round(s / f), d - 1)
                e2 = max(s2 + 1, min(round(e / f), d))
                if z in excl_zones or z % 2 == 0:
                    wins.append(Window(f"z{z}", s2, e2, "occupy"))
                else:
                    wins.append(Window(f"z{z}", s2, e2, "occupy"))
                    ms = s2 + int(rng.integers(0, max(1, e2 - s2)))
                    me = int(rng.integers(ms + 1, e2 + 1))
                    wins.append(Window(f"z{z}", ms, me, "move"))
            m.add_mode(t, a, float(d), windows=wins, tools=tool)
    problem = m.build()
    if starts and any(starts[a] and not (problem.mode_arm == a).any() for a in range(n_arms)):
        # an arm with no task would hold its start zone for good: keep it out of zones
        for a in range(n_arms):
            if starts[a] and not (problem.mode_arm == a).any():
                m._arms[a].start_zones = ()
        problem = m.build()
    if setups or blocking:
        pts = np.zeros((problem.n_modes, 3))
        pts[:, :2] = task_xy[problem.mode_task]
        home = np.zeros((n_arms, 3))
        home[:, :2] = home_xy
        slowness = rng.choice([0.5, 1.0], size=n_arms)  # powers of two: exact integer travel times
        setup = (
            TravelSetup(pts, pts, home, speed=slowness, base=0.0, metric="manhattan")
            if setups
            else None
        )
        m.set_setup(setup)
        if blocking:
            m.set_blocking(GridBlocking(task_xy.copy(), home_xy.copy(), problem.mode_task.copy()))
        problem = m.build()
    return problem
