"""Built-in example task sets for the reference cells.

* ``"supersigma"``: a SUPERSIGMA-like two-arm Cartesian cell (SEEDS.md S1):
  base, pin and cap fed to a shared fixture, one pin insertion under force
  search (S1.7), a screwing task with the one screwdriver, and the chess-piece
  demo of S1.8 (scan a board with the object detector, measure the pieces,
  sort them). Built with the procedural API, as a user of the paper's C
  library would.
* ``"scara4"``: a four-arm SCARA cell assembling two pumps around a central
  assembly zone; parts arrive in varying order; the description is
  part-driven (S2.11), with a part group (impeller and seal must both be in
  before the cover goes on).
* ``"cell8"``: a generated task set of about 200 tasks for the 8-arm scale
  cell (:func:`generate_taskset` with a fixed seed).
* ``"urdf_cell"``: two products (base plate, pin, screw) assembled on one
  shared fixture by two UR5 and a Panda read from URDF; written with the
  procedural API.

Examples
--------
>>> load_example("supersigma").summary()["tasks"]
10
>>> sorted(EXAMPLES)
['cell8', 'scara4', 'supersigma', 'urdf_cell']
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Sequence
from importlib import resources

from multiarm.errors import ValidationError
from multiarm.types import Point3, Seed, as_rng
from tasklib import capi as c
from tasklib.arrivals import FixedArrivals, PoissonArrivals, UniformArrivals
from tasklib.model import TaskSet

__all__ = [
    "EXAMPLES",
    "cell8",
    "generate_taskset",
    "load_example",
    "scara4",
    "supersigma",
    "urdf_cell",
]


def _tdl_text(name: str) -> str:
    return resources.files(__name__).joinpath(name).read_text(encoding="utf-8")


DOWN = (0.0, 1.0, 0.0, 0.0)
"""Tool pointing down: a half turn about x (quaternion w, x, y, z)."""


def supersigma() -> TaskSet:
    """The two-arm Cartesian example (SUPERSIGMA-like, SEEDS.md S1)."""
    ts = c.taskset_open(
        "supersigma",
        "Two-arm Cartesian cell: base-pin-cap assembly with force-search insertion "
        "and the object-detector chess-piece demo.",
    )
    c.tdl_add(ts, _tdl_text("supersigma.tdl"), "supersigma.tdl")
    c.feeder_add(ts, "base_feeder", ["base"], (0.20, 0.30, 0.05), FixedArrivals((("base", 0.0),)))
    c.feeder_add(
        ts, "pin_feeder", ["pin"], (1.80, 0.30, 0.05), FixedArrivals((("pin", 2.0),)), 0.0005
    )
    c.feeder_add(ts, "cap_feeder", ["cap"], (1.80, 0.90, 0.05), FixedArrivals((("cap", 6.0),)))
    pieces = ["king", "queen", "rook", "pawn"]
    # The pieces lie on a line of the board, positions known only roughly:
    # they are found with the object detector (S1.8), not by an exact feeder.
    c.feeder_add(ts, "board", pieces, (0.30, 1.00, 0.02), position_sigma=0.01)
    for pid in ["base", "pin", "cap", *pieces]:
        c.part_add(ts, pid)
    for pid in ["fixtured_base", "pinned_base", "capped", "assembly"]:
        c.part_add(ts, pid)

    fixture = (1.00, 0.60, 0.10)
    t = c.task_open(ts, "place_base", description="base from its feeder into the fixture")
    c.task_consume(t, "base")
    c.task_produce(t, "fixtured_base")
    c.task_move(t, (0.20, 0.30, 0.20, *DOWN))
    c.task_approach(t, (0.20, 0.30, 0.05, *DOWN), 0.15)
    c.task_grasp(t, "base")
    c.task_depart(t, 0.15)
    c.task_move(t, trajectory="base_to_fixture")
    c.task_approach(t, (*fixture, *DOWN), 0.20)
    c.task_release(t, "base")
    c.task_actuate(t, "fixture_clamp", "close", 0.5)
    c.task_depart(t, 0.20)
    c.task_close(t)

    t = c.task_open(ts, "insert_pin", description="pin into the base's hole, force-guided (S1.7)")
    c.task_consume(t, "pin", "fixtured_base")
    c.task_produce(t, "pinned_base")
    c.task_move(t, (1.80, 0.30, 0.20, *DOWN))
    c.task_approach(t, (1.80, 0.30, 0.05, *DOWN), 0.15)
    c.task_grasp(t, "pin")
    c.task_depart(t, 0.15)
    c.task_move(t, trajectory="pin_to_fixture")
    c.task_insert(
        t, "pin", (1.00, 0.60, 0.12, *DOWN), depth=0.02, max_tries=13, step=0.0004, threshold=25.0
    )
    c.task_release(t, "pin")
    c.task_depart(t, 0.18)
    c.task_close(t)

    t = c.task_open(ts, "place_cap")
    c.task_consume(t, "cap", "pinned_base")
    c.task_produce(t, "capped")
    c.task_move(t, (1.80, 0.90, 0.20, *DOWN))
    c.task_approach(t, (1.80, 0.90, 0.05, *DOWN), 0.15)
    c.task_grasp(t, "cap")
    c.task_depart(t, 0.15)
    c.task_move(t, trajectory="cap_to_fixture")
    c.task_approach(t, (1.00, 0.60, 0.14, *DOWN), 0.16)
    c.task_release(t, "cap")
    c.task_depart(t, 0.16)
    c.task_close(t)

    t = c.task_open(ts, "screw_cap", tool="screwdriver")
    c.task_consume(t, "capped")
    c.task_produce(t, "assembly")
    c.task_move(t, (1.00, 0.60, 0.30, *DOWN))
    c.task_approach(t, (1.00, 0.60, 0.15, *DOWN), 0.15)
    c.task_use_tool(t, "screwdriver", 2.5)
    c.task_depart(t, 0.15)
    c.task_close(t)

    t = c.task_open(ts, "unload", description="assembly to the out-going conveyor")
    c.task_consume(t, "assembly")
    c.task_actuate(t, "fixture_clamp", "open", 0.5)
    c.task_approach(t, (*fixture, *DOWN), 0.20)
    c.task_grasp(t)
    c.task_move(t, trajectory="fixture_to_conveyor")
    c.task_release(t)
    c.task_actuate(t, "conveyor", "advance", 1.0)
    c.task_close(t)

    # S1.8 chess-piece demo: one scan measures every piece on the line.
    t = c.task_open(ts, "scan_board", description="find and measure the pieces (S1.8)")
    c.task_move(t, trajectory="over_board")
    c.task_detect(t, (0.30, 1.00, 0.14, *DOWN), (0.90, 1.00, 0.14, *DOWN), "measure", 0.15)
    c.task_set_flag(t, "board_measured")
    c.task_close(t)
    for i, piece in enumerate(pieces):
        x = 0.35 + 0.15 * i
        t = c.task_open(ts, f"sort_{piece}", description=f"{piece} into the bin of its height")
        c.task_consume(t, piece)
        c.task_wait_flag(t, "board_measured")
        c.task_move(t, (x, 1.00, 0.15, *DOWN))
        c.task_approach(t, (x, 1.00, 0.03, *DOWN), 0.12)
        c.task_grasp(t, piece, 0.25)
        c.task_depart(t, 0.12)
        c.task_move(t, trajectory="board_to_bins")
        c.task_release(t, piece)
        c.task_close(t)
    return c.taskset_close(ts)


def scara4(n_products: int = 2) -> TaskSet:
    """The four-arm SCARA example: ``n_products`` pumps around a central zone.

    Part-driven (S2.11): each part carries its prerequisites and tasks; the
    cover's task belongs to the group of the impeller and the seal, two
    independent parts that must both be in. Parts arrive in varying order:
    housings, shafts, impellers and seals come from one tray at uniform
    random times, screws from a bowl feeder as a Poisson stream.
    """
    if n_products < 1:
        raise ValidationError(f"scara4 needs n_products >= 1, got {n_products}")
    ts = c.taskset_open(
        "scara4",
        f"Four SCARA arms assembling {n_products} pump(s) in a shared central zone; "
        "parts arrive in varying order.",
    )
    c.tdl_add(ts, _tdl_text("scara4.tdl"), "scara4.tdl")
    tray_parts, screws, covers = [], [], []
    for k in range(1, n_products + 1):
        tray_parts += [f"housing{k}", f"shaft{k}", f"impeller{k}", f"seal{k}"]
        covers.append(f"cover{k}")
        screws += [f"screw{k}_{j}" for j in range(1, 5)]
    c.feeder_add(ts, "tray", tray_parts, (0.0, -0.45, 0.02), UniformArrivals(0.0, 20.0), 0.002)
    c.feeder_add(
        ts, "cover_rack", covers, (0.45, 0.0, 0.05), PoissonArrivals(0.1, start=5.0, ordered=True)
    )
    c.feeder_add(ts, "screw_bowl", screws, (-0.45, 0.0, 0.02), PoissonArrivals(1.0))
    centre = (0.0, 0.0, 0.05)

    def pick_place(
        t: c.TaskHandle, part: str, pick: tuple[float, float, float], approach_to: str
    ) -> None:
        c.task_move(t, (pick[0], pick[1], 0.15, *DOWN))
        c.task_approach(t, (*pick, *DOWN), 0.12)
        c.task_grasp(t, part)
        c.task_depart(t, 0.12)
        c.task_move(t, trajectory=approach_to)

    for k in range(1, n_products + 1):
        angle = 2 * math.pi * (k - 1) / max(n_products, 1)
        slot = (0.08 * math.cos(angle), 0.08 * math.sin(angle), centre[2])
        housing, shaft, impeller, seal, cover = (
            f"housing{k}",
            f"shaft{k}",
            f"impeller{k}",
            f"seal{k}",
            f"cover{k}",
        )
        c.part_add(ts, housing)
        c.part_add(ts, shaft, [housing])
        c.part_add(ts, impeller, [shaft])
        c.part_add(ts, seal, [housing])
        c.part_add(ts, cover)
        c.group_add(ts, f"closure{k}", [impeller, seal], "impeller and seal both in")
        for j in range(1, 5):
            c.part_add(ts, f"screw{k}_{j}")
        c.part_add(ts, f"pump{k}")

        t = c.task_open(ts, f"place_housing{k}", part=housing)
        c.task_consume(t, housing)
        pick_place(t, housing, (-0.05, -0.45, 0.02), "tray_to_centre")
        c.task_approach(t, (*slot, *DOWN), 0.10)
        c.task_release(t, housing)
        c.task_depart(t, 0.10)
        c.task_close(t)

        t = c.task_open(ts, f"insert_shaft{k}", part=shaft)
        c.task_consume(t, shaft)
        pick_place(t, shaft, (0.0, -0.45, 0.02), "tray_to_centre")
        c.task_insert(
            t, shaft, (slot[0], slot[1], 0.09, *DOWN), depth=0.03, max_tries=9, step=0.0003
        )
        c.task_release(t, shaft)
        c.task_depart(t, 0.10)
        c.task_close(t)

        t = c.task_open(ts, f"mount_impeller{k}", ["vacuum"], part=impeller)
        c.task_consume(t, impeller)
        pick_place(t, impeller, (0.05, -0.45, 0.02), "tray_to_centre")
        c.task_approach(t, (slot[0], slot[1], 0.11, *DOWN), 0.08)
        c.task_release(t, impeller)
        c.task_depart(t, 0.08)
        c.task_close(t)

        t = c.task_open(ts, f"press_seal{k}", tool="press", part=seal)
        c.task_consume(t, seal)
        pick_place(t, seal, (0.10, -0.45, 0.02), "tray_to_centre")
        c.task_approach(t, (slot[0], slot[1], 0.08, *DOWN), 0.08)
        c.task_release(t, seal)
        c.task_use_tool(t, "press", 1.5)
        c.task_depart(t, 0.08)
        c.task_close(t)

        t = c.task_open(ts, f"place_cover{k}", group=f"closure{k}")
        c.task_consume(t, cover)
        pick_place(t, cover, (0.45, 0.0, 0.05), "rack_to_centre")
        c.task_approach(t, (slot[0], slot[1], 0.13, *DOWN), 0.08)
        c.task_release(t, cover)
        c.task_depart(t, 0.08)
        c.task_close(t)

        for j in range(1, 5):
            a = angle + math.pi / 2 * j
            hole = (slot[0] + 0.03 * math.cos(a), slot[1] + 0.03 * math.sin(a), 0.13)
            t = c.task_open(ts, f"screw{k}_{j}", tool="screwdriver")
            c.task_require(t, f"place_cover{k}")
            c.task_consume(t, f"screw{k}_{j}")
            c.task_move(t, trajectory="bowl_pick")
            c.task_grasp(t, f"screw{k}_{j}", 0.15)
            c.task_move(t, (hole[0], hole[1], 0.20, *DOWN))
            c.task_approach(t, (*hole, *DOWN), 0.07)
            c.task_use_tool(t, "screwdriver", 1.2)
            c.task_depart(t, 0.07)
            c.task_close(t)

        t = c.task_open(ts, f"test_unload{k}", ["camera"])
        c.task_require(t, *[f"screw{k}_{j}" for j in range(1, 5)])
        c.task_produce(t, f"pump{k}")
        c.task_actuate(t, "leak_tester", f"test_slot{k}", 3.0)
        c.task_approach(t, (*slot, *DOWN), 0.12)
        c.task_grasp(t, None, 0.3)
        c.task_move(t, trajectory="centre_to_out")
        c.task_release(t)
        c.task_close(t)
    return c.taskset_close(ts)


_CAPS = ("vacuum", "camera", "dual_gripper")
_TOOLS = ("screwdriver", "glue_gun", "press")


MAX_TASKS = 100_000
"""Most tasks :func:`generate_taskset` makes (a larger request is a typo, not a cell)."""


def generate_taskset(
    n_tasks: int = 200,
    seed: Seed = 0,
    *,
    name: str | None = None,
    parts_per_product: tuple[int, int] = (5, 9),
    tool_probability: float = 0.25,
    insert_probability: float = 0.3,
    capability_probability: float = 0.2,
    sites: Sequence[tuple[Point3, Point3]] | None = None,
) -> TaskSet:
    """A random but valid part-driven task set with about ``n_tasks`` tasks.

    Products are generated one after the other until ``n_tasks`` tasks exist
    (the last product may be cut short, never below one task). Each product
    is a random tree of fed parts (a part's parent is a prerequisite); each
    part has one or two tasks in a chain; sibling leaves form part groups with
    a joining task; an unload task finishes the product. Tools, force
    insertions and extra capabilities are drawn with the given
    probabilities; arrivals are Poisson streams per product tray.

    Parameters
    ----------
    n_tasks : int
        Number of tasks, exactly (1 .. :data:`MAX_TASKS`).
    seed : int or numpy.random.Generator
        The same seed gives the same task set.
    sites : sequence of (feeder position, station position), optional
        Where products are made in a concrete cell. Without it, each
        product's tray lies uniformly in [-1.5, 1.5]^2 and its station in
        [-0.5, 0.5]^2 around the origin, and every product shares the
        trajectories ``to_station``/``to_out``; with it, each product picks
        one site (uniformly), its tray and station are the site's, and its
        moves follow the site's own trajectories ``to_site{k}`` (down onto
        the station) and ``out_site{k}`` (back up), so a cell can place
        arms that reach every site.

    Examples
    --------
    >>> generate_taskset(50, seed=1) == generate_taskset(50, seed=1)
    True
    >>> len(generate_taskset(37, seed=2).tasks)
    37
    """
    given: object = n_tasks
    if (
        isinstance(given, bool)
        or not isinstance(given, numbers.Integral)
        or not 1 <= int(given) <= MAX_TASKS
    ):
        raise ValidationError(f"generate_taskset needs n_tasks in [1, {MAX_TASKS}], got {given!r}")
    rng = as_rng(seed)
    ts = c.taskset_open(name or f"generated{n_tasks}", f"generated: {n_tasks} tasks")
    if sites is None:
        c.tdl_add(
            ts,
            "trajectory to_station { taught { via (0, 0, 0.4) stop (0, 0, 0.2) } }\n"
            "trajectory to_out { taught interp linear { via (0, 0, 0.4) stop (1.5, 0, 0.3) } }\n",
        )
    else:
        if not sites:
            raise ValidationError("generate_taskset needs at least one site")
        lines = []
        for k, (_, (sx, sy, sz)) in enumerate(sites):
            lines.append(f"frame site{k} = ({sx!r}, {sy!r}, {sz!r})")
            lines.append(
                f"trajectory to_site{k} {{ frame site{k} taught {{ via (0, 0, 0.3) stop (0, 0, 0.15) }} }}"
            )
            lines.append(
                f"trajectory out_site{k} {{ frame site{k} taught interp linear {{ stop (0, 0, 0.3) }} }}"
            )
        c.tdl_add(ts, "\n".join(lines) + "\n", "sites.tdl")
    count = 0
    product = 0
    while count < n_tasks:
        product += 1
        lo, hi = parts_per_product
        n_parts = int(rng.integers(lo, hi + 1))
        parts = [f"p{product}_{i}" for i in range(n_parts)]
        parent = [-1] + [int(rng.integers(0, i)) for i in range(1, n_parts)]
        if sites is None:
            site = -1
            fx, fy = float(rng.uniform(-1.5, 1.5)), float(rng.uniform(-1.5, 1.5))
            fz = 0.02
        else:
            site = int(rng.integers(len(sites)))
            fx, fy, fz = (float(v) for v in sites[site][0])
        to_station = "to_station" if site < 0 else f"to_site{site}"
        to_out = "to_out" if site < 0 else f"out_site{site}"
        c.feeder_add(
            ts,
            f"tray{product}",
            parts,
            (fx, fy, fz),
            PoissonArrivals(float(rng.uniform(0.2, 1.0)), start=float(rng.uniform(0, 30))),
            float(rng.choice([0.0, 0.0005, 0.002])),
        )
        if sites is None:
            station = (float(rng.uniform(-0.5, 0.5)), float(rng.uniform(-0.5, 0.5)), 0.05)
        else:
            sx, sy, sz = (float(v) for v in sites[site][1])
            station = (sx, sy, sz)
        last_of: dict[int, str] = {}
        children: dict[int, list[int]] = {}
        for i in range(1, n_parts):
            children.setdefault(parent[i], []).append(i)
        # A part's parent in the tree is its prerequisite: the parent is
        # assembled first and the part goes onto it.
        for i, pid in enumerate(parts):
            c.part_add(ts, pid, [parts[parent[i]]] if parent[i] >= 0 else [])
        for i, pid in enumerate(parts):
            n_own = 1 if rng.random() < 0.6 else 2
            for j in range(n_own):
                if count >= n_tasks:
                    break
                tid = f"t{product}_{i}_{j}"
                caps = [x for x in _CAPS if rng.random() < capability_probability / len(_CAPS) * 2]
                tool = str(rng.choice(_TOOLS)) if rng.random() < tool_probability else None
                t = c.task_open(ts, tid, caps, tool, part=pid)
                if j == 0:
                    c.task_consume(t, pid)
                    c.task_move(t, (fx, fy, fz + 0.13, *DOWN))
                    c.task_approach(t, (fx, fy, fz, *DOWN), 0.1)
                    c.task_grasp(t, pid, float(rng.uniform(0.2, 0.5)))
                    c.task_depart(t, 0.1)
                    c.task_move(t, trajectory=to_station)
                    if rng.random() < insert_probability:
                        c.task_insert(
                            t,
                            pid,
                            (*station, *DOWN),
                            depth=float(rng.uniform(0.005, 0.03)),
                            max_tries=int(rng.integers(3, 13)),
                        )
                    else:
                        c.task_approach(t, (*station, *DOWN), 0.08)
                    c.task_release(t, pid)
                else:
                    c.task_require(t, last_of[i])
                    c.task_move(t, (station[0], station[1], station[2] + 0.15, *DOWN))
                    c.task_approach(t, (*station, *DOWN), 0.1)
                if tool is not None:
                    c.task_use_tool(t, tool, float(rng.uniform(0.5, 3.0)))
                else:
                    c.task_dwell(t, float(rng.uniform(0.0, 1.0)))
                c.task_depart(t, 0.1)
                c.task_close(t)
                last_of[i] = tid
                count += 1
        # Sibling leaves that were all given a task form a part group with a
        # joining task (S2.11: tasks of a set of independent parts).
        for p, kids in children.items():
            leaves = [k for k in kids if k not in children and k in last_of]
            if len(leaves) >= 2 and count < n_tasks:
                gid = f"g{product}_{p}"
                c.group_add(ts, gid, [parts[k] for k in leaves])
                t = c.task_open(ts, f"join{product}_{p}", group=gid)
                c.task_move(t, (station[0], station[1], station[2] + 0.15, *DOWN))
                c.task_dwell(t, float(rng.uniform(0.5, 2.0)))
                c.task_close(t)
                count += 1
        if count < n_tasks and last_of:
            t = c.task_open(ts, f"unload{product}")
            c.task_require(t, *[last_of[i] for i in sorted(last_of)])
            c.task_approach(t, (*station, *DOWN), 0.1)
            c.task_grasp(t)
            c.task_move(t, trajectory=to_out)
            c.task_release(t)
            c.task_close(t)
            count += 1
    return c.taskset_close(ts)


CELL8_SITES: tuple[tuple[Point3, Point3], ...] = tuple(
    ((x - 0.1, 1.1, 0.05), (x + 0.1, 0.92, 0.05)) for x in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5)
)
"""The 8-arm cell's work sites on its central conveyor (y = 0.8..1.2 m, x = 0..4 m):
(tray, station) pairs every half metre, each within reach of the arms of both
rows standing next to it."""


def cell8() -> TaskSet:
    """200 generated tasks for the 8-arm scale cell (seed 8), made at :data:`CELL8_SITES`."""
    return generate_taskset(200, seed=8, name="cell8", sites=CELL8_SITES)


def urdf_cell(n_products: int = 2) -> TaskSet:
    """Two UR5 and a Panda (URDF arms) assembling ``n_products`` products on one fixture.

    Per product: a base plate comes on the conveyor and is placed in the
    fixture, a pin from the tray is inserted under force search (S1.7), a
    screw is driven with the one screwdriver, and the finished product goes
    back onto the conveyor. The fixture holds one product at a time.
    """
    if n_products < 1:
        raise ValidationError(f"urdf_cell needs n_products >= 1, got {n_products}")
    ts = c.taskset_open(
        "urdf_cell",
        f"Two UR5 and a Panda assembling {n_products} product(s) on a shared fixture.",
    )
    bases = [f"base{k}" for k in range(1, n_products + 1)]
    pins = [f"pin{k}" for k in range(1, n_products + 1)]
    c.feeder_add(
        ts, "conveyor_in", bases, (-0.3, 0.55, 0.02), FixedArrivals(tuple((b, 0.0) for b in bases))
    )
    c.feeder_add(ts, "pin_tray", pins, (0.32, -0.4, 0.02), FixedArrivals(()), 0.0005)
    fixture = (0.0, 0.0, 0.08)
    out = (0.3, 0.55, 0.06)
    previous: str | None = None
    for k in range(1, n_products + 1):
        base, pin, done = f"base{k}", f"pin{k}", f"product{k}"
        c.part_add(ts, base)
        c.part_add(ts, pin, [base])
        c.part_add(ts, f"screw{k}")
        c.part_add(ts, done)

        t = c.task_open(ts, f"place_base{k}", part=base)
        if previous is not None:
            c.task_require(t, previous)  # the fixture holds one product
        c.task_consume(t, base)
        c.task_move(t, (-0.3, 0.55, 0.2, *DOWN))
        c.task_approach(t, (-0.3, 0.55, 0.04, *DOWN), 0.15)
        c.task_grasp(t, base)
        c.task_depart(t, 0.15)
        c.task_move(t, (0.0, 0.0, 0.25, *DOWN))
        c.task_approach(t, (*fixture, *DOWN), 0.15)
        c.task_release(t, base)
        c.task_actuate(t, "fixture_clamp", "close", 0.5)
        c.task_depart(t, 0.15)
        c.task_close(t)

        t = c.task_open(ts, f"insert_pin{k}", ["force_sensor"], part=pin)
        c.task_consume(t, pin)
        c.task_move(t, (0.32, -0.4, 0.2, *DOWN))
        c.task_approach(t, (0.32, -0.4, 0.04, *DOWN), 0.14)
        c.task_grasp(t, pin)
        c.task_depart(t, 0.14)
        c.task_move(t, (0.0, 0.0, 0.28, *DOWN))
        c.task_insert(t, pin, (0.0, 0.0, 0.14, *DOWN), depth=0.03, max_tries=9, step=0.0005)
        c.task_release(t, pin)
        c.task_depart(t, 0.12)
        c.task_close(t)

        t = c.task_open(ts, f"screw{k}", tool="screwdriver")
        c.task_require(t, f"insert_pin{k}")
        c.task_move(t, (0.04, 0.0, 0.25, *DOWN))
        c.task_approach(t, (0.04, 0.0, 0.12, *DOWN), 0.1)
        c.task_use_tool(t, "screwdriver", 1.5)
        c.task_depart(t, 0.1)
        c.task_close(t)

        t = c.task_open(ts, f"unload{k}")
        c.task_require(t, f"screw{k}")
        c.task_produce(t, done)
        c.task_actuate(t, "fixture_clamp", "open", 0.5)
        c.task_move(t, (0.0, 0.0, 0.25, *DOWN))
        c.task_approach(t, (*fixture, *DOWN), 0.15)
        c.task_grasp(t, None, 0.3)
        c.task_depart(t, 0.15)
        c.task_move(t, (out[0], out[1], 0.22, *DOWN))
        c.task_approach(t, (*out, *DOWN), 0.12)
        c.task_release(t)
        c.task_depart(t, 0.12)
        c.task_close(t)
        previous = f"unload{k}"
    return c.taskset_close(ts)


EXAMPLES: dict[str, Callable[[], TaskSet]] = {
    "supersigma": supersigma,
    "scara4": scara4,
    "cell8": cell8,
    "urdf_cell": urdf_cell,
}


def load_example(name: str) -> TaskSet:
    """The built-in example task set ``name`` (see :data:`EXAMPLES`)."""
    try:
        make = EXAMPLES[name]
    except KeyError:
        raise ValidationError(
            f"unknown example {name!r} (known: {', '.join(sorted(EXAMPLES))})"
        ) from None
    return make()
