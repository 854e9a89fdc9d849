"""Hypothesis strategies shared by the tests."""

from __future__ import annotations

import math
from typing import Any

from hypothesis import strategies as st

from tasklib.pose import quat_from_rpy
from tasklib.tdl import CELL_FRAME, Frame, Segment, TDLDocument, Trajectory, Waypoint

names = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,10}", fullmatch=True).filter(
    lambda s: s != CELL_FRAME
)
coords = st.floats(allow_nan=False, allow_infinity=False, width=64)
small_coords = st.floats(-10.0, 10.0, allow_nan=False)
angles = st.floats(-2 * math.pi, 2 * math.pi, allow_nan=False)
fractions = st.floats(1e-6, 1.0, allow_nan=False)  # speeds: at least 1e-6 of the top speed


@st.composite
def unit_quats(draw: st.DrawFn) -> tuple[float, float, float, float]:
    return quat_from_rpy(draw(angles), draw(angles), draw(angles))


points3 = st.tuples(coords, coords, coords)


@st.composite
def waypoints(draw: st.DrawFn) -> Waypoint:
    return Waypoint(
        draw(points3),
        draw(st.none() | unit_quats()),
        draw(st.booleans()),
        draw(st.none() | fractions),
    )


@st.composite
def segments(draw: st.DrawFn) -> Segment:
    return Segment(
        tuple(draw(st.lists(waypoints(), min_size=1, max_size=4))),
        draw(st.sampled_from(["taught", "learned"])),
        draw(st.none() | st.text(max_size=12)),
        draw(st.sampled_from(["linear", "axis"])),
        draw(st.none() | fractions),
    )


@st.composite
def tdl_documents(draw: st.DrawFn) -> TDLDocument:
    frame_names = draw(st.lists(names, max_size=4, unique=True))
    frames = []
    for i, name in enumerate(frame_names):
        parent = draw(st.sampled_from([CELL_FRAME, *frame_names[:i]]))
        frames.append(Frame(name, draw(points3), draw(unit_quats()), parent))
    traj_names = draw(st.lists(names, max_size=4, unique=True))
    trajs = [
        Trajectory(
            name,
            tuple(draw(st.lists(segments(), min_size=1, max_size=3))),
            draw(st.sampled_from([CELL_FRAME, *frame_names])),
            draw(fractions),
        )
        for name in traj_names
    ]
    return TDLDocument(tuple(frames), tuple(trajs))


TDL_TOKENS = [
    "frame",
    "trajectory",
    "taught",
    "learned",
    "via",
    "stop",
    "quat",
    "rpy",
    "speed",
    "interp",
    "linear",
    "axis",
    "in",
    "cell",
    "=",
    "{",
    "}",
    "(",
    ")",
    ",",
    "0",
    "1",
    "-2.5e3",
    "1e999",
    "0.5",
    "x",
    "y",
    '"rec"',
    "# c\n",
    "\n",
    "@",
    '"',
]
tdl_token_soup = st.lists(st.sampled_from(TDL_TOKENS), max_size=40).map(" ".join)


# ------------------------------------------------------------- task steps

from tasklib.arrivals import (  # noqa: E402
    Feeder,
    FixedArrivals,
    PoissonArrivals,
    TraceArrivals,
    UniformArrivals,
)
from tasklib.model import Part, PartGroup, Task, TaskSet  # noqa: E402
from tasklib.pose import Pose  # noqa: E402
from tasklib.steps import (  # noqa: E402
    Actuate,
    Approach,
    Depart,
    Detect,
    Dwell,
    ForceSearch,
    Grasp,
    Insert,
    Move,
    Release,
    SetFlag,
    UseTool,
    WaitFlag,
)

PART_NAMES = ("pa", "pb", "pc")
positive = st.floats(1e-9, 1e6, allow_nan=False)
nonneg = st.floats(0.0, 1e6, allow_nan=False)


@st.composite
def poses(draw: st.DrawFn) -> Pose:
    return Pose(draw(points3), draw(unit_quats()))


def step_strategy(
    trajectory: str | None, tool: str | None, set_flags: bool = True
) -> st.SearchStrategy[object]:
    part = st.none() | st.sampled_from(PART_NAMES)
    options = [
        st.builds(
            Move, target=poses(), interpolation=st.sampled_from(["linear", "axis"]), speed=fractions
        ),
        st.builds(Approach, poses(), positive, fractions),
        st.builds(Depart, positive, fractions),
        st.builds(Grasp, part, nonneg),
        st.builds(Release, part, nonneg),
        st.builds(
            Insert,
            st.sampled_from(PART_NAMES),
            poses(),
            positive,
            fractions,
            st.builds(
                ForceSearch,
                st.integers(1, 50),
                positive,
                st.sampled_from(["spiral", "grid"]),
                positive,
                positive,
            ),
        ),
        st.builds(Actuate, names, names, nonneg),
        st.builds(
            Detect, poses(), poses(), st.sampled_from(["search", "measure"]), fractions, part
        ),
        st.builds(SetFlag, st.just("f1")) if set_flags else st.builds(Dwell, nonneg),
        st.builds(WaitFlag, st.just("f1"), st.none() | positive),
        st.builds(Dwell, nonneg),
    ]
    if trajectory is not None:
        options.append(st.builds(Move, trajectory=st.just(trajectory), speed=fractions))
    if tool is not None:
        options.append(st.builds(UseTool, st.just(tool), positive))
    return st.one_of(options)


arrival_models = st.one_of(
    st.just(FixedArrivals(())),
    st.builds(PoissonArrivals, positive, nonneg, st.booleans()),
    st.tuples(nonneg, nonneg).map(lambda lh: UniformArrivals(min(lh), max(lh))),
    st.builds(
        lambda ts: TraceArrivals(tuple((t, p) for t, p in zip(ts, PART_NAMES, strict=False))),
        st.lists(nonneg, min_size=3, max_size=3),
    ),
)


@st.composite
def task_sets(draw: st.DrawFn) -> TaskSet:
    """Small random task sets using every record and step kind."""
    doc = draw(tdl_documents())
    traj = doc.trajectories[0].name if doc.trajectories else None
    n = draw(st.integers(1, 5))
    tasks = []
    for i in range(n):
        tool = draw(st.none() | st.sampled_from(["press", "drill"]))
        # only t0 (which has no prerequisite) raises the flag, so flag edges
        # never close a cycle with the prerequisites
        steps = draw(st.lists(step_strategy(traj, tool, set_flags=i == 0), min_size=1, max_size=5))
        prereqs = (
            draw(st.lists(st.sampled_from([f"t{j}" for j in range(i)]), unique=True)) if i else []
        )
        tasks.append(
            Task(
                f"t{i}",
                tuple(steps),
                tuple(draw(st.lists(names, unique=True, max_size=2))),
                tool,
                tuple(prereqs),
                tuple(draw(st.lists(st.sampled_from(PART_NAMES), unique=True, max_size=2))),
                (),
                draw(st.text(max_size=10)),
            )
        )
    # the flag is waited for only if someone sets it
    if any(isinstance(s, WaitFlag) for t in tasks for s in t.steps) and not any(
        isinstance(s, SetFlag) for t in tasks for s in t.steps
    ):
        tasks[0] = Task(
            tasks[0].id,
            (*tasks[0].steps, SetFlag("f1")),
            tasks[0].capabilities,
            tasks[0].tool,
            tasks[0].prerequisites,
            tasks[0].consumes,
            (),
            tasks[0].description,
        )
    feeder = Feeder("tray", PART_NAMES, draw(points3), draw(arrival_models), draw(nonneg))
    parts = (Part("pa"), Part("pb", ("pa",)), Part("pc", ("pa",)))
    groups = (PartGroup("g", ("pb", "pc")),) if draw(st.booleans()) else ()
    # avoid flag cycles: a waiter listing the setter as successor is possible
    # only through prerequisites, which go to earlier tasks; setter is t0.
    return TaskSet(
        "random", tuple(tasks), parts, (feeder,), groups, doc, draw(st.text(max_size=20))
    )


# ------------------------------------------------------------------ zones

from zones.geometry import AABox, Cylinder, HalfSpaces, Hull, OBox, Sphere, Union  # noqa: E402
from zones.model import Phase, Tool, Wall, Zone, ZoneMap  # noqa: E402


@st.composite
def _inside(
    draw: st.DrawFn, lo: tuple[float, ...], hi: tuple[float, ...]
) -> tuple[float, float, float]:
    return tuple(draw(st.floats(l, h)) for l, h in zip(lo, hi, strict=True))  # type: ignore[return-value]


@st.composite
def zone_shapes(
    draw: st.DrawFn, lo: tuple[float, ...], hi: tuple[float, ...], walls: list[str], depth: int = 0
) -> object:
    span = [h - l for l, h in zip(lo, hi, strict=True)]
    kind = draw(
        st.sampled_from(
            ["aabox", "obox", "cyl", "sphere", "hull", "walls", "union"]
            if depth == 0
            else ["aabox", "sphere", "cyl"]
        )
    )
    if kind == "aabox":
        a = [draw(st.floats(l, l + 0.45 * s)) for l, s in zip(lo, span, strict=True)]
        b = [draw(st.floats(l + 0.55 * s, h)) for l, h, s in zip(lo, hi, span, strict=True)]
        return AABox(tuple(a), tuple(b))  # type: ignore[arg-type]
    centre = [l + s / 2 + draw(st.floats(-0.1, 0.1)) * s for l, s in zip(lo, span, strict=True)]
    small = min(span) * draw(st.floats(0.05, 0.2))
    if kind == "obox":
        size = tuple(small * draw(st.floats(0.5, 1.0)) for _ in range(3))
        return OBox(tuple(centre), size, draw(st.floats(-math.pi, math.pi)))  # type: ignore[arg-type]
    if kind == "cyl":
        return Cylinder(tuple(centre), small, small * draw(st.floats(0.5, 2.0)))  # type: ignore[arg-type]
    if kind == "sphere":
        return Sphere(tuple(centre), small)  # type: ignore[arg-type]
    if kind == "hull":
        pts = [
            tuple(c + small * draw(st.floats(-1, 1)) for c in centre)
            for _ in range(draw(st.integers(4, 8)))
        ]
        pts += [
            (centre[0] - small, centre[1] - small, centre[2] - small),
            (centre[0] + small, centre[1], centre[2]),
            (centre[0], centre[1] + small, centre[2]),
            (centre[0], centre[1], centre[2] + small),
        ]
        return Hull(tuple(pts))  # type: ignore[arg-type]
    if kind == "walls" and walls:
        chosen = draw(
            st.lists(st.sampled_from(walls), min_size=1, max_size=min(3, len(walls)), unique=True)
        )
        return HalfSpaces(tuple((w, draw(st.sampled_from([1, -1]))) for w in chosen))
    parts = draw(st.lists(zone_shapes(lo, hi, walls, depth + 1), min_size=1, max_size=3))
    return Union(tuple(parts))  # type: ignore[arg-type]


@st.composite
def zone_maps(draw: st.DrawFn) -> ZoneMap:
    lo = tuple(draw(st.floats(-5, 0)) for _ in range(3))
    hi = tuple(l + draw(st.floats(0.5, 5)) for l in lo)
    wall_names = draw(st.lists(names, max_size=3, unique=True))
    walls = []
    for w in wall_names:
        p = draw(_inside(lo, hi))
        if draw(st.booleans()):
            axis = draw(st.integers(0, 2))
            point = [0.0, 0.0, 0.0]
            point[axis] = p[axis]
            normal = [0.0, 0.0, 0.0]
            normal[axis] = 1.0
            walls.append(Wall(w, tuple(point), tuple(normal)))  # type: ignore[arg-type]
        else:
            n = (draw(st.floats(-1, 1)), draw(st.floats(-1, 1)), draw(st.floats(0.1, 1)))
            walls.append(Wall(w, p, n))
    zone_names = draw(st.lists(names, min_size=1, max_size=5, unique=True))
    zones = [
        Zone(
            z,
            draw(zone_shapes(lo, hi, wall_names)),
            draw(st.sampled_from(["exclusive", "shared"])),
            draw(st.none() | st.floats(0.01, 5.0)),
        )
        for z in zone_names
    ]
    tools = [Tool(t, draw(_inside(lo, hi))) for t in draw(st.lists(names, max_size=2, unique=True))]
    active = draw(st.none() | st.lists(st.sampled_from(zone_names), unique=True).map(tuple))
    phases = [
        Phase(p, tuple(draw(st.lists(st.sampled_from(zone_names), unique=True))))
        for p in draw(st.lists(names, max_size=2, unique=True))
    ]
    return ZoneMap((lo, hi), tuple(zones), tuple(walls), tuple(tools), active, tuple(phases))  # type: ignore[arg-type]


SDL_TOKENS = [
    "cell",
    "wall",
    "zone",
    "tool",
    "rack",
    "active",
    "phase",
    "exclusive",
    "shared",
    "box",
    "center",
    "size",
    "yaw",
    "cylinder",
    "sphere",
    "radius",
    "height",
    "hull",
    "walls",
    "union",
    "mesh",
    "speed_limit",
    "point",
    "normal",
    "x",
    "y",
    "z",
    "=",
    "{",
    "}",
    "(",
    ")",
    ",",
    "+",
    "-",
    "0",
    "1",
    "0.5",
    "-2",
    "1e999",
    "a",
    "b",
    "w",
    '"m.stl"',
    "# c\n",
    "\n",
]
sdl_token_soup = st.lists(st.sampled_from(SDL_TOKENS), max_size=50).map(" ".join)


# ------------------------------------------------------- scheduling problems

from scheduler.problem import Model as _SchedModel  # noqa: E402
from scheduler.problem import Problem as _SchedProblem  # noqa: E402
from scheduler.problem import Window as _SchedWindow  # noqa: E402

WINDOW_KINDS = ("occupy", "move")
ZONE_POLICIES = ("exclusive", "shared")


@st.composite
def zone_windows(draw: st.DrawFn, duration: int, zones: tuple[str, ...]) -> list[_SchedWindow]:
    """Zone windows of one mode of ``duration`` half-seconds: any kind in any zone,
    several in one zone allowed (touching, overlapping or apart)."""
    out = []
    for _ in range(draw(st.integers(0, 3))):
        s = draw(st.integers(0, duration - 1))
        e = draw(st.integers(s + 1, duration))
        out.append(
            _SchedWindow(
                draw(st.sampled_from(zones)), s / 2, e / 2, draw(st.sampled_from(WINDOW_KINDS))
            )
        )
    return out


@st.composite
def zone_problems(
    draw: st.DrawFn, max_arms: int = 3, max_tasks: int = 6, tools: bool = True
) -> _SchedProblem:
    """Small feasible scheduling problems exercising every window kind (occupy,
    move) in every zone kind (exclusive, restricted-simultaneous ``shared``):
    move windows in exclusive zones included, several windows of a mode in one
    zone, tools, releases, precedence and arm availability. Times are multiples
    of 0.5 s (exact in binary). No start zones, so a schedule always exists
    (run every task one after the other)."""
    m = _SchedModel("hyp")
    n_arms = draw(st.integers(2, max_arms))
    for a in range(n_arms):
        m.add_arm(f"a{a}", available=draw(st.integers(0, 4)) / 2)
    # at least one zone of each policy
    extra = draw(st.lists(st.sampled_from(ZONE_POLICIES), max_size=2))
    policies = ["exclusive", "shared", *extra]
    zones = tuple(f"z{i}" for i in range(len(policies)))
    for name, pol in zip(zones, policies, strict=True):
        m.add_zone(name, pol)  # type: ignore[arg-type]
    n_tools = draw(st.integers(0, 2)) if tools else 0
    for k in range(n_tools):
        m.add_tool(f"k{k}")
    n_tasks = draw(st.integers(1, max_tasks))
    for t in range(n_tasks):
        preds = draw(st.lists(st.integers(0, t - 1), max_size=2, unique=True)) if t else []
        m.add_task(f"t{t}", release=draw(st.integers(0, 6)) / 2, predecessors=preds)
        arms = draw(st.lists(st.integers(0, n_arms - 1), min_size=1, max_size=2, unique=True))
        for a in arms:
            d = draw(st.integers(1, 10))
            held = draw(st.lists(st.integers(0, n_tools - 1), max_size=1)) if n_tools else []
            m.add_mode(
                t,
                a,
                d / 2,
                windows=draw(zone_windows(d, zones)),
                tools=[f"k{k}" for k in held],
            )
    return m.build()


# ------------------------------------------------- cell-file numeric fields

EXTREME_NUMBERS: tuple[float | int, ...] = (
    0,
    0.0,
    -0.0,
    1e-300,
    -1e-300,
    5e-324,
    1e300,
    -1e300,
    math.inf,
    -math.inf,
    math.nan,
    1e-6,
    1e6,
    2**63,
    -(2**63),
    10**30,
)
"""Values a cell file may hold that physical arithmetic trips on."""

extreme_numbers = (
    st.sampled_from(EXTREME_NUMBERS)
    | st.floats(width=64)
    | st.integers(-(2**70), 2**70)
    | st.floats(-1e-3, 1e-3)
)


def numeric_cell_data() -> dict[str, object]:
    """A cell file's data with a gantry and a SCARA in which every optional
    numeric field is present (so that each can be changed), built-in zones and
    tasks of the supersigma cell."""
    return {
        "name": "numbers",
        "zones": "builtin:supersigma",
        "tasks": "builtin:supersigma",
        "compile": {"padding": 0.005, "seed": 0, "grid": 0.3},
        "arms": {
            "g": {
                "type": "gantry",
                "base": [0.0, 0.0, 0.0, 0.0],
                "rails": {"x": [0.0, 1.85], "y": [0.0, 1.2], "z": [0.0, 0.6]},
                "height": 0.8,
                "hand": [0.06, 0.06, 0.1],
                "capabilities": ["gripper", "force_sensor", "object_detector", "tool_changer"],
                "tools": ["screwdriver"],
                "payload": 2.0,
                "start": [0.02, 0.6, 0.6, 0.0],
                "yaw_limits": [-3.14, 3.14],
                "stepper": {
                    "steps_per_turn": 400,
                    "step_length": 0.0000375,
                    "max_rate": 15000.0,
                    "low_rate": 1000.0,
                    "stop_accel": 4.0,
                    "curves": {"light": 2.0, "loaded": 1.0},
                    "short_steps": 32,
                    "homing_rate": 4000.0,
                    "switch_hysteresis": 40,
                },
            },
            "s": {
                "type": "scara",
                "base": [-0.5, -0.5, 0.0, 0.7853981633974483],
                "link_lengths": [0.45, 0.4],
                "z_range": [0.0, 0.35],
                "arm_height": 0.47,
                "max_velocity": [3.0, 4.0, 1.0, 6.0],
                "max_acceleration": [10.0, 15.0, 5.0, 30.0],
                "max_jerk": [100.0, 150.0, 50.0, 300.0],
                "joint_limits": [[-2.9, 2.9], [-2.6, 2.6], [0.0, 0.35], [-6.2, 6.2]],
                "home": [0.0, 1.5, 0.35, 0.0],
                "radius": 0.05,
                "payload": 3.0,
            },
        },
    }


def _numeric_paths(node: object, path: tuple[str | int, ...]) -> list[tuple[str | int, ...]]:
    if isinstance(node, bool):
        return []
    if isinstance(node, int | float):
        return [path]
    if isinstance(node, dict):
        return [p for k, v in node.items() for p in _numeric_paths(v, (*path, k))]
    if isinstance(node, list):
        return [p for i, v in enumerate(node) for p in _numeric_paths(v, (*path, i))]
    return []


CELL_NUMERIC_FIELDS: tuple[tuple[str | int, ...], ...] = tuple(
    _numeric_paths(numeric_cell_data(), ())
)
"""Every numeric field of :func:`numeric_cell_data`, as a key path."""


@st.composite
def cell_number_edits(
    draw: st.DrawFn, max_edits: int = 3
) -> list[tuple[tuple[str | int, ...], float | int]]:
    """One to ``max_edits`` numeric fields of :func:`numeric_cell_data` with extreme values."""
    fields = draw(
        st.lists(st.sampled_from(CELL_NUMERIC_FIELDS), min_size=1, max_size=max_edits, unique=True)
    )
    return [(f, draw(extreme_numbers)) for f in fields]


def with_edits(
    data: dict[str, object], edits: list[tuple[tuple[str | int, ...], float | int]]
) -> dict[str, object]:
    """A deep copy of ``data`` with each ``(path, value)`` of ``edits`` set."""
    import copy

    out = copy.deepcopy(data)
    for path, value in edits:
        node: Any = out
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return out
