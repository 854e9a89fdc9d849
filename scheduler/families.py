"""Two more seeded generators of zone-constrained problems, unlike :mod:`scheduler.generate`'s.

They exist to test the solvers on structures they were not developed on
(the race rule of :class:`scheduler.tree.TreeOptions` was tuned on
``routes`` only; ``stations`` is the untuned family). Both make integer
data, so CP-SAT solves the exact problem, and the same seed gives the same
problem.

* :func:`random_routes_problem` ("routes"): a flexible job shop with zones.
  Jobs are chains of operations; each operation may run on its own random
  subset of the arms, with arm-dependent durations, and enters its zone for
  a sub-interval of the operation whose shape is drawn per operation (the
  whole operation, the start only, the end only, a middle part, or several
  windows in one or two zones). No setups.
* :func:`random_stations_problem` ("stations"): assembly kits (in-trees:
  feeder tasks, then one assembly task needing all of them) at exclusive
  stations placed on a grid, reached through shared corridors crossed with
  ``move`` windows at the start and end of a task, arms of unequal speed
  (travel and work), and the travel between stations as setup times.

Examples
--------
>>> p = random_routes_problem(3, 20, 3, 1, seed=2)
>>> (p.n_arms, p.n_tasks, p.n_zones, p.n_tools)
(3, 20, 3, 1)
>>> random_routes_problem(3, 20, 3, 1, seed=2).to_dict() == p.to_dict()
True
>>> q = random_stations_problem(4, 30, 4, 2, seed=5)
>>> (q.n_arms, q.n_tasks, q.n_zones, q.n_tools)
(4, 30, 4, 2)
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import Seed, as_rng
from scheduler.problem import Model, Problem, Window
from scheduler.setup import TravelSetup

__all__ = ["ROUTE_SHAPES", "random_routes_problem", "random_stations_problem"]

ROUTE_SHAPES = ("whole", "start", "end", "middle", "several")
"""The window shapes of a ``routes`` operation's zone use."""


def _check_sizes(who: str, sizes: tuple[tuple[str, object, int, int], ...]) -> None:
    for what, n, least, most in sizes:
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not least <= n <= most:
            raise ValidationError(
                f"{who}: {what} must be an integer in [{least}, {most}], got {n!r}"
            )


def _check_shares(who: str, shares: tuple[tuple[str, object], ...]) -> None:
    for what, x in shares:
        if isinstance(x, bool) or not (isinstance(x, int | float) and 0.0 <= x <= 1.0):
            raise ValidationError(f"{who}: {what} must be in [0, 1], got {x!r}")


def random_routes_problem(
    n_arms: int = 3,
    n_tasks: int = 30,
    n_zones: int = 3,
    n_tools: int = 1,
    seed: Seed = 0,
    *,
    zone_fraction: float = 0.7,
    shared_fraction: float = 0.3,
    tool_fraction: float = 0.2,
    release_fraction: float = 0.2,
    flexibility: float = 0.5,
) -> Problem:
    """A flexible job shop whose operations use zones for part of their time.

    Jobs are chains of 2 to 6 operations (the last job is cut to make
    ``n_tasks``); a share ``release_fraction`` of the jobs arrives later
    (release uniform in ``[0, 4 * n_tasks / n_arms)``). Each operation runs
    on one random arm and on every other arm with probability
    ``flexibility``; its duration on arm ``a`` is its base time (uniform
    5..30) times the arm's factor (0.8, 1 or 1.25) times a noise in
    [0.85, 1.2], rounded (at least 2). With probability ``zone_fraction`` it
    uses a zone (uniform over ``n_zones``; each zone shared with probability
    ``shared_fraction``, else exclusive) in one of :data:`ROUTE_SHAPES`,
    drawn uniformly: the whole operation; the first or last 20-60 % of it;
    a middle part; or *several*: the first and the last 15-40 % in one zone,
    or the start in one zone and the end in another. The shape's fractions
    are drawn per operation and scaled to each arm's duration. In a shared
    zone each window is a ``move`` (excluding other moves) or an ``occupy``
    window with a ``move`` in its middle half. A share ``tool_fraction`` of
    the operations holds one of ``n_tools`` tools. No setups.

    Parameters
    ----------
    n_arms, n_tasks, n_zones, n_tools : int
    seed : int or Generator
    zone_fraction, shared_fraction, tool_fraction, release_fraction, flexibility : float
        Shares in [0, 1] (see above).

    Returns
    -------
    Problem

    Raises
    ------
    ValidationError
        A size or share out of range.
    """
    who = "random_routes_problem"
    _check_sizes(
        who,
        (
            ("n_arms", n_arms, 1, 1_000),
            ("n_tasks", n_tasks, 1, 5_000),
            ("n_zones", n_zones, 0, 1_000),
            ("n_tools", n_tools, 0, 1_000),
        ),
    )
    _check_shares(
        who,
        (
            ("zone_fraction", zone_fraction),
            ("shared_fraction", shared_fraction),
            ("tool_fraction", tool_fraction),
            ("release_fraction", release_fraction),
            ("flexibility", flexibility),
        ),
    )
    rng = as_rng(seed)
    m = Model(f"routes-{n_arms}x{n_tasks}x{n_zones}")
    factor = rng.choice([0.8, 1.0, 1.25], size=n_arms)
    for a in range(n_arms):
        m.add_arm(f"arm{a}")
    shared = [bool(rng.random() < shared_fraction) for _ in range(n_zones)]
    for z in range(n_zones):
        m.add_zone(f"z{z}", "shared" if shared[z] else "exclusive")
    for k in range(n_tools):
        m.add_tool(f"tool{k}")
    span = max(10, 4 * n_tasks // max(1, n_arms))
    t = 0
    job = 0
    while t < n_tasks:
        size = min(n_tasks - t, int(rng.integers(2, 7)))
        release = float(rng.integers(0, span)) if rng.random() < release_fraction else 0.0
        for o in range(size):
            m.add_task(
                f"j{job}.{o}",
                release=release if o == 0 else 0.0,
                predecessors=[t - 1] if o else [],
                group=job,
            )
            t += 1
        job += 1
    for task in range(n_tasks):
        first = int(rng.integers(n_arms))
        arms = [a for a in range(n_arms) if a == first or rng.random() < flexibility]
        base = int(rng.integers(5, 31))
        # the zone use, as fractions of the duration: [(zone, lo, hi), ...]
        use: list[tuple[int, float, float]] = []
        if n_zones and rng.random() < zone_fraction:
            z = int(rng.integers(n_zones))
            shape = ROUTE_SHAPES[int(rng.integers(len(ROUTE_SHAPES)))]
            if shape == "whole":
                use = [(z, 0.0, 1.0)]
            elif shape == "start":
                use = [(z, 0.0, float(rng.uniform(0.2, 0.6)))]
            elif shape == "end":
                use = [(z, 1.0 - float(rng.uniform(0.2, 0.6)), 1.0)]
            elif shape == "middle":
                lo = float(rng.uniform(0.1, 0.5))
                use = [(z, lo, lo + float(rng.uniform(0.2, 0.9 - lo)))]
            else:
                z2 = int(rng.integers(n_zones)) if rng.random() < 0.5 else z
                use = [
                    (z, 0.0, float(rng.uniform(0.15, 0.4))),
                    (z2, 1.0 - float(rng.uniform(0.15, 0.4)), 1.0),
                ]
        kinds = [
            ("move" if rng.random() < 0.5 else "occupy") if shared[z] else "occupy"
            for z, _, _ in use
        ]
        tool = (
            [f"tool{int(rng.integers(n_tools))}"]
            if n_tools and rng.random() < tool_fraction
            else []
        )
        for a in arms:
            d = max(2, round(base * float(factor[a]) * float(rng.uniform(0.85, 1.2))))
            wins = []
            for (z, lo, hi), kind in zip(use, kinds, strict=True):
                s = min(round(lo * d), d - 1)
                e = max(s + 1, min(round(hi * d), d))
                if kind == "move":
                    wins.append(Window(f"z{z}", s, e, "move"))
                    continue
                wins.append(Window(f"z{z}", s, e, "occupy"))
                if shared[z] and e - s >= 2:  # an occupy window with a movement in its middle
                    q = (e - s) // 4
                    wins.append(Window(f"z{z}", s + q, max(s + q + 1, e - q), "move"))
            m.add_mode(task, a, float(d), windows=wins, tools=tool)
    return m.build()


def random_stations_problem(
    n_arms: int = 3,
    n_tasks: int = 30,
    n_zones: int = 3,
    n_tools: int = 1,
    seed: Seed = 0,
    *,
    shared_fraction: float = 0.4,
    tool_fraction: float = 0.2,
    release_fraction: float = 0.2,
    reach: int = 8,
) -> Problem:
    """Assembly kits at exclusive stations, reached through shared corridors.

    ``round(shared_fraction * n_zones)`` of the zones (at most
    ``n_zones - 1``) are shared *corridors*, the others exclusive
    *stations* at random points of a 10 x 10 grid, each behind a random
    corridor with probability 1/2. Arms stand at random points with a
    travel slowness of 1 or 2 seconds per grid step and a work factor of 1,
    1.25 or 1.5. Tasks form kits of 2 to 5: feeder tasks, then one assembly
    task that needs all of them (an in-tree; the last kit is cut to make
    ``n_tasks``); a share ``release_fraction`` of the kits arrives later.
    A task is at a station (or, with probability 0.2, at a free point), and
    every arm whose home lies within ``reach`` grid steps (Manhattan) of
    it may do it (the nearest arm if none). On arm ``a`` a mode lasts
    ``approach + work + retreat``: approach and retreat 1-3 steps at the
    arm's slowness, work 3-15 times its work factor; it occupies its station
    from the end of the approach to the start of the retreat, and moves
    through the station's corridor during the approach and the retreat (two
    ``move`` windows). A share ``tool_fraction`` of the tasks holds one of
    ``n_tools`` tools. Setups are the Manhattan travel between task points
    at the arm's slowness (from its home before its first task), so they
    obey the triangle inequality and stay integers.

    Parameters
    ----------
    n_arms, n_tasks, n_zones, n_tools : int
    seed : int or Generator
    shared_fraction, tool_fraction, release_fraction : float
        Shares in [0, 1] (see above).
    reach : int
        How far (grid steps) from its home an arm works.

    Returns
    -------
    Problem

    Raises
    ------
    ValidationError
        A size, share or reach out of range.
    """
    who = "random_stations_problem"
    _check_sizes(
        who,
        (
            ("n_arms", n_arms, 1, 1_000),
            ("n_tasks", n_tasks, 1, 5_000),
            ("n_zones", n_zones, 0, 1_000),
            ("n_tools", n_tools, 0, 1_000),
            ("reach", reach, 1, 1_000),
        ),
    )
    _check_shares(
        who,
        (
            ("shared_fraction", shared_fraction),
            ("tool_fraction", tool_fraction),
            ("release_fraction", release_fraction),
        ),
    )
    rng = as_rng(seed)
    m = Model(f"stations-{n_arms}x{n_tasks}x{n_zones}")
    n_corr = min(max(0, n_zones - 1), round(shared_fraction * n_zones))
    corridors = list(range(n_corr))
    stations = list(range(n_corr, n_zones))
    for z in range(n_zones):
        m.add_zone(f"z{z}", "shared" if z in corridors else "exclusive")
    for k in range(n_tools):
        m.add_tool(f"tool{k}")
    slow = rng.choice([1, 2], size=n_arms)
    work_factor = rng.choice([1.0, 1.25, 1.5], size=n_arms)
    home = rng.integers(0, 11, size=(n_arms, 2))
    for a in range(n_arms):
        m.add_arm(f"arm{a}")
    where = rng.integers(0, 11, size=(len(stations), 2))
    behind = [
        int(corridors[int(rng.integers(len(corridors)))])
        if corridors and rng.random() < 0.5
        else -1
        for _ in stations
    ]
    span = max(10, 5 * n_tasks // max(1, n_arms))
    t = 0
    kit = 0
    while t < n_tasks:
        size = min(n_tasks - t, int(rng.integers(2, 6)))
        release = float(rng.integers(0, span)) if rng.random() < release_fraction else 0.0
        for o in range(size):
            last = o == size - 1 and size > 1
            m.add_task(
                f"k{kit}.{'a' if last else o}",
                release=0.0 if last else release,
                predecessors=list(range(t - o, t)) if last else [],
                group=kit,
            )
            t += 1
        kit += 1
    point = np.zeros((n_tasks, 2), dtype=np.int64)
    for task in range(n_tasks):
        st = int(rng.integers(len(stations))) if stations and rng.random() >= 0.2 else -1
        point[task] = where[st] if st >= 0 else rng.integers(0, 11, size=2)
        dist = np.abs(home - point[task]).sum(axis=1)
        arms = [a for a in range(n_arms) if dist[a] <= reach] or [int(np.argmin(dist))]
        steps_in, steps_out = int(rng.integers(1, 4)), int(rng.integers(1, 4))
        work = int(rng.integers(3, 16))
        tool = (
            [f"tool{int(rng.integers(n_tools))}"]
            if n_tools and rng.random() < tool_fraction
            else []
        )
        for a in arms:
            go, back = steps_in * int(slow[a]), steps_out * int(slow[a])
            w = max(1, round(work * float(work_factor[a])))
            d = go + w + back
            wins: list[Window] = []
            if st >= 0:
                wins.append(Window(f"z{stations[st]}", go, go + w, "occupy"))
                if behind[st] >= 0:
                    kind: Literal["occupy", "move"] = "move"
                    wins.append(Window(f"z{behind[st]}", 0, go, kind))
                    wins.append(Window(f"z{behind[st]}", go + w, d, kind))
            m.add_mode(task, a, float(d), windows=wins, tools=tool)
    problem = m.build()
    pts = np.zeros((problem.n_modes, 3))
    pts[:, :2] = point[np.asarray(problem.mode_task)]
    homes = np.zeros((n_arms, 3))
    homes[:, :2] = home
    m.set_setup(
        TravelSetup(pts, pts, homes, speed=1.0 / slow.astype(float), base=0.0, metric="manhattan")
    )
    return m.build()
