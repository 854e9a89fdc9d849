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

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import Seed, as_rng
from scheduler.families import random_routes_problem, random_stations_problem
from scheduler.problem import Model, Problem, Window
from scheduler.setup import MatrixSetup, TravelSetup

__all__ = [
    "GENERATORS",
    "MAX_TASKS",
    "GridBlocking",
    "generate_problem",
    "metric_closure",
    "random_line_problem",
    "random_problem",
    "random_setup_fjsp",
]

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


def metric_closure(times: np.ndarray) -> np.ndarray:
    """Shortest-path closure of a setup block: ``out[i, j] <= out[i, k] + out[k, j]``.

    Parameters
    ----------
    times : ndarray, shape (n + 1, n)
        Row 0 from the initial pose, row ``i + 1`` from task ``i``, column
        ``j`` to task ``j`` (the diagonal is ignored).

    Returns
    -------
    ndarray
        The same shape, every entry replaced by the shortest chain of direct
        setups (Floyd-Warshall over the tasks), so the triangle inequality
        holds, from the initial pose too. Integer input stays integral.
    """
    n = times.shape[1]
    d = np.array(times[1:], dtype=float)
    np.fill_diagonal(d, 0.0)
    for k in range(n):
        d = np.minimum(d, d[:, k : k + 1] + d[k : k + 1, :])
    home = np.array(times[0], dtype=float)
    home = np.minimum(home, (home[:, None] + d).min(axis=0))
    out = np.vstack([home[None, :], d])
    return out


def random_setup_fjsp(
    n_machines: int = 5,
    n_ops: int = 30,
    seed: Seed = 0,
    *,
    ops_per_job: tuple[int, int] = (2, 6),
    flexibility: float = 0.4,
    max_time: int = 20,
    setup_fraction: float = 0.5,
) -> Problem:
    """A random FJSP with sequence-dependent setup times (SDST-FJSP).

    Jobs of ``ops_per_job`` chained operations (the last job is cut to make
    ``n_ops`` in all), each operation on at least one machine (every other
    machine with probability ``flexibility``), processing times drawn per
    machine uniformly from ``1..max_time`` (Brandimarte-like). The setup of
    machine ``m`` between two operations is drawn uniformly from
    ``0..round(setup_fraction * max_time)`` (``setup_fraction`` is the
    largest raw setup as a fraction of the largest processing time), per
    machine and ordered pair (asymmetric), plus one from the machine's
    initial state to each operation; each machine's matrix is then replaced
    by its shortest-path closure (:func:`metric_closure`), so the triangle
    inequality holds and every value stays an integer (CP-SAT solves the
    exact problem). A :class:`~scheduler.setup.MatrixSetup`; no zones or
    tools. The same seed gives the same problem.

    Parameters
    ----------
    n_machines, n_ops : int
        Machines (arms) and operations (tasks).
    seed : int or Generator
    ops_per_job : (int, int)
        Least and most operations of a job.
    flexibility : float
        Probability that an operation may also run on any other machine.
    max_time : int
        Largest processing time.
    setup_fraction : float
        Largest raw setup time as a fraction of ``max_time``. When it rounds
        to no setup at all (below ``0.5 / max_time``), the problem is a plain
        FJSP without a setup matrix.

    Returns
    -------
    Problem

    Raises
    ------
    ValidationError
        A size or parameter out of range.

    Examples
    --------
    >>> p = random_setup_fjsp(3, 8, seed=1)
    >>> (p.n_arms, p.n_tasks, p.n_zones), p.setup.times.shape
    ((3, 8, 0), (3, 9, 8))
    >>> bool(p._setup.is_metric())
    True
    """
    for what, n, least, most in (
        ("n_machines", n_machines, 1, 1_000),
        ("n_ops", n_ops, 1, 2_000),
        ("max_time", max_time, 1, 1_000_000),
    ):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not least <= n <= most:
            raise ValidationError(
                f"random_setup_fjsp: {what} must be an integer in [{least}, {most}], got {n!r}"
            )
    lo, hi = ops_per_job
    if not 1 <= lo <= hi:
        raise ValidationError(
            f"random_setup_fjsp: ops_per_job must be 1 <= lo <= hi, got {ops_per_job!r}"
        )
    for what, x in (("flexibility", flexibility), ("setup_fraction", setup_fraction)):
        if not (isinstance(x, int | float) and 0.0 <= x <= 10.0):
            raise ValidationError(f"random_setup_fjsp: {what} must be in [0, 10], got {x!r}")
    rng = as_rng(seed)
    m = Model(f"sdst-{n_machines}x{n_ops}")
    for k in range(n_machines):
        m.add_arm(f"M{k + 1}")
    left, job = n_ops, 0
    while left > 0:
        size = min(left, int(rng.integers(lo, hi + 1)))
        prev = None
        for o in range(size):
            t = m.add_task(
                f"J{job + 1}.O{o + 1}", predecessors=[prev] if prev is not None else [], group=job
            )
            first = int(rng.integers(n_machines))
            machines = [k for k in range(n_machines) if k == first or rng.random() < flexibility]
            for k in machines:
                m.add_mode(t, k, float(rng.integers(1, max_time + 1)))
            prev = t
        left -= size
        job += 1
    top = round(setup_fraction * max_time)
    if top == 0:  # no setups at all: a plain FJSP (no setup matrix of zeros)
        return m.build()
    raw = rng.integers(0, top + 1, size=(n_machines, n_ops + 1, n_ops))
    times = np.stack([metric_closure(raw[k]) for k in range(n_machines)])
    m.set_setup(MatrixSetup(times))
    return m.build()


def random_line_problem(
    n_arms: int = 3,
    n_tasks: int = 24,
    n_zones: int = 3,
    n_tools: int = 1,
    seed: Seed = 0,
    *,
    reach: int = 14,
    stay_fraction: float = 0.5,
    shared_fraction: float = 0.5,
    tool_fraction: float = 0.2,
    release_fraction: float = 0.2,
) -> Problem:
    """A random cell of arms on a line, independent of :func:`random_problem`.

    A second, structurally different generator of zone-constrained problems.
    Arm ``a`` stands at ``x = 10 a`` on a line and reaches stations within
    ``reach``; zones are random stretches of the line (exclusive, or shared
    with probability ``shared_fraction``). Parts are jobs of one to four
    operations at stations of increasing ``x`` (a chain each, a share
    ``release_fraction`` arriving later). A mode's windows come from the
    arm's motion, so two arms doing one task touch different zones: the arm
    moves from its base to the station at one unit of length per second
    divided by its speed, works there, and either goes back (an *out and
    back* mode: two windows in each zone it crosses, the work inside the
    station's zones) or stays (a *stay* mode, with probability
    ``stay_fraction``: one window from entering until the end, and the next
    task's setup is the travel from this station). Crossing a shared zone is
    a ``move`` window, standing in it an ``occupy`` one with a ``move``
    window while working. A share ``tool_fraction`` of the operations needs
    one of ``n_tools`` tools. Setups are the travel along the line (from the
    station, or 0 after an out-and-back mode), so they obey the triangle
    inequality; every time is an integer.

    Parameters
    ----------
    n_arms, n_tasks, n_zones, n_tools : int
    seed : int or Generator
    reach : int
        How far from its base an arm works.
    stay_fraction, shared_fraction, tool_fraction, release_fraction : float
        Shares in [0, 1] (see above).

    Returns
    -------
    Problem

    Raises
    ------
    ValidationError
        A size or share out of range.

    Examples
    --------
    >>> p = random_line_problem(3, 12, 2, 1, seed=3)
    >>> (p.n_arms, p.n_tasks, p.n_zones, p.n_tools)
    (3, 12, 2, 1)
    """
    for what, n, least, most in (
        ("n_arms", n_arms, 1, 1_000),
        ("n_tasks", n_tasks, 1, 5_000),
        ("n_zones", n_zones, 0, 1_000),
        ("n_tools", n_tools, 0, 1_000),
        ("reach", reach, 1, 1_000),
    ):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not least <= n <= most:
            raise ValidationError(
                f"random_line_problem: {what} must be an integer in [{least}, {most}], got {n!r}"
            )
    for what, x in (
        ("stay_fraction", stay_fraction),
        ("shared_fraction", shared_fraction),
        ("tool_fraction", tool_fraction),
        ("release_fraction", release_fraction),
    ):
        if not (isinstance(x, int | float) and 0.0 <= x <= 1.0):
            raise ValidationError(f"random_line_problem: {what} must be in [0, 1], got {x!r}")
    rng = as_rng(seed)
    m = Model(f"line-{n_arms}x{n_tasks}x{n_zones}")
    length = 10 * (n_arms - 1)
    base = [10 * a for a in range(n_arms)]
    slow = rng.choice([1, 1, 2], size=n_arms)  # seconds per unit of length
    work_scale = rng.choice([1.0, 1.0, 1.5], size=n_arms)
    for a in range(n_arms):
        m.add_arm(f"arm{a}")
    zones = []
    for z in range(n_zones):
        lo = int(rng.integers(-reach, length + reach))
        hi = lo + int(rng.integers(2, 9))
        shared = bool(rng.random() < shared_fraction)
        zones.append((lo, hi, shared))
        m.add_zone(f"z{z}", "shared" if shared else "exclusive")
    for k in range(n_tools):
        m.add_tool(f"tool{k}")
    span = max(10, 6 * n_tasks // max(1, n_arms))
    station: list[int] = []
    t = 0
    while t < n_tasks:
        size = min(n_tasks - t, int(rng.integers(1, 5)))
        xs = np.sort(rng.integers(-reach // 2, length + reach // 2 + 1, size=size))
        release = float(rng.integers(0, span)) if rng.random() < release_fraction else 0.0
        for o in range(size):
            m.add_task(
                f"p{t - o}.{o}",
                release=release if o == 0 else 0.0,
                predecessors=[t - 1] if o else [],
                group=t - o,
            )
            station.append(int(xs[o]))
            t += 1
    mode_point: list[int] = []
    mode_stay: list[bool] = []
    for task in range(n_tasks):
        x = station[task]
        capable = [a for a in range(n_arms) if abs(x - base[a]) <= reach]
        if not capable:
            capable = [int(np.argmin([abs(x - b) for b in base]))]
        work = int(rng.integers(2, 11))
        tool = (
            [f"tool{int(rng.integers(n_tools))}"]
            if n_tools and rng.random() < tool_fraction
            else []
        )
        for a in capable:
            s = int(slow[a])
            w = max(1, round(work * float(work_scale[a])))
            dist = abs(x - base[a])
            stay = bool(rng.random() < stay_fraction)
            go = dist * s
            dur = go + w + (0 if stay else go)
            wins = []
            step = 1 if x >= base[a] else -1
            for z, (lo, hi, shared) in enumerate(zones):
                at_station = lo <= x < hi
                # the stretch of the path [base, x] inside [lo, hi): entered and left at
                p0, p1 = sorted((base[a], x))
                c0, c1 = max(p0, lo), min(p1 + 1, hi)
                if c0 >= c1 and not at_station:
                    continue
                if step > 0:
                    enter, leave = (c0 - base[a]) * s, (c1 - base[a]) * s
                else:
                    enter, leave = (base[a] - c1 + 1) * s, (base[a] - c0 + 1) * s
                enter, leave = max(0, min(enter, go)), max(0, min(leave, go))
                if at_station:
                    if stay:
                        wins.append(Window(f"z{z}", enter, dur, "occupy"))
                    else:
                        wins.append(Window(f"z{z}", enter, dur - enter, "occupy"))
                    if shared:
                        wins.append(Window(f"z{z}", go, go + w, "move"))
                    continue
                if leave <= enter:
                    continue
                kind: Literal["occupy", "move"] = "move" if shared else "occupy"
                wins.append(Window(f"z{z}", enter, leave, kind))
                if not stay:
                    wins.append(Window(f"z{z}", dur - leave, dur - enter, kind))
            m.add_mode(task, a, float(dur), windows=wins, tools=tool)
            mode_point.append(x if stay else base[a])
            mode_stay.append(stay)
    problem = m.build()
    ends = np.zeros((problem.n_modes, 3))
    starts = np.zeros((problem.n_modes, 3))
    home = np.zeros((n_arms, 3))
    home[:, 0] = base
    # a mode starts at its arm's base (its duration covers the way out) and ends
    # at the station when it stays there, else back at the base
    starts[:, 0] = np.asarray(base)[problem.mode_arm]
    ends[:, 0] = mode_point
    m.set_setup(TravelSetup(starts, ends, home, speed=1.0 / slow, base=0.0, metric="manhattan"))
    return m.build()


def _setup_fjsp(
    n_arms: int, n_tasks: int, n_zones: int, n_tools: int, seed: Seed = 0, **params: Any
) -> Problem:
    if n_zones or n_tools:
        raise ValidationError(
            f"generator 'setup_fjsp' makes no zones or tools: size needs zones = tools = 0, "
            f"got {n_zones} zones and {n_tools} tools"
        )
    return random_setup_fjsp(n_arms, n_tasks, seed, **params)


GENERATORS: dict[str, Callable[..., Problem]] = {
    "zones": random_problem,
    "line": random_line_problem,
    "setup_fjsp": _setup_fjsp,
    "routes": random_routes_problem,
    "stations": random_stations_problem,
}
"""The generators of :func:`generate_problem` by name: ``zones``
(:func:`random_problem`), ``line`` (:func:`random_line_problem`), ``setup_fjsp`` (:func:`random_setup_fjsp`, size
``[machines, operations, 0, 0]``), ``routes`` and ``stations``
(:mod:`scheduler.families`)."""


def generate_problem(
    generator: str,
    n_arms: int,
    n_tasks: int,
    n_zones: int,
    n_tools: int,
    seed: Seed = 0,
    **params: Any,
) -> Problem:
    """A problem of the named generator (a sweep's ``generated`` instances).

    Parameters
    ----------
    generator : str
        A key of :data:`GENERATORS`.
    n_arms, n_tasks, n_zones, n_tools : int
        The size (``[arms, tasks, zones, tools]`` in a sweep file).
    seed : int or Generator
    **params
        The generator's keyword arguments.

    Returns
    -------
    Problem

    Raises
    ------
    ValidationError
        An unknown generator, a size it cannot make or a bad parameter.

    Examples
    --------
    >>> generate_problem("setup_fjsp", 3, 8, 0, 0, seed=1).n_tasks
    8
    """
    fn = GENERATORS.get(generator)
    if fn is None:
        raise ValidationError(
            f"unknown generator {generator!r}: expected one of {', '.join(map(repr, GENERATORS))}"
        )
    target = random_setup_fjsp if fn is _setup_fjsp else fn
    known = {
        k
        for k, v in inspect.signature(target).parameters.items()
        if v.kind is inspect.Parameter.KEYWORD_ONLY
    }
    for k in params:
        if k not in known:
            raise ValidationError(
                f"generator {generator!r} has no parameter {k!r} (it takes: "
                f"{', '.join(sorted(known))})"
            )
    return fn(n_arms, n_tasks, n_zones, n_tools, seed, **params)
