"""Timing with border waits (S2.6) and the one validator of every constraint."""

from __future__ import annotations

import math

import numpy as np
import pytest

from multiarm.errors import ScheduleError
from scheduler import MatrixSetup, Model, Schedule, Window, validate
from scheduler.schedule import blocking_required


def cell(start_zone: bool = False, setup: float = 0.0, oracle: object = None):  # type: ignore[no-untyped-def]
    """Arms A, B; exclusive zone E, shared zone S, tool K."""
    m = Model()
    m.add_zone("E")
    m.add_zone("S", "shared")
    m.add_tool("K")
    m.add_arm("A")
    m.add_arm("B", start_zones=["E"] if start_zone else ())
    m.add_task("a")
    m.add_task("b")
    m.add_task("c", release=1.0)
    m.add_task("d", predecessors=["a"])
    # a on A: E occupied [2, 6), S occupied [4, 5) and [6, 9), moving [6, 8); borders 2, 4, 6
    # (4 lies inside the E window: waiting there keeps E)
    m.add_mode(
        "a",
        "A",
        10.0,
        windows=[
            Window("E", 2, 6),
            Window("S", 4, 5),
            Window("S", 6, 9),
            Window("S", 6, 8, "move"),
        ],
    )
    # b on B: in E during [0, 4)
    m.add_mode("b", "B", 4.0, windows=[Window("E", 0, 4)])
    # c: in S the whole time, moving [1, 5), and in E over [3, 4); borders 1 and 3
    for arm in ("A", "B"):
        m.add_mode(
            "c",
            arm,
            6.0,
            windows=[Window("S", 0, 6), Window("S", 1, 5, "move"), Window("E", 3, 4)],
            tools=["K"],
        )
    m.add_mode("d", "B", 2.0, tools=["K"])
    if setup:
        T = 4
        m.set_setup(MatrixSetup(np.full((2, T + 1, T), setup)))
    m.set_blocking(oracle)  # type: ignore[arg-type]
    return m.build()


def test_intervals_with_waits_by_hand() -> None:
    p = cell()
    sh = p.shapes[p.mode_of[0, 0]]
    assert sh.borders == (2.0, 4.0, 6.0)
    got = sh.intervals(0.0, np.array([1.0, 0.0, 2.0]))
    assert sorted(got) == [
        (0, 3.0, 7.0),
        (3, 9.0, 11.0),
    ]  # entered after the wait at 2, left at 6 + 1
    got = sh.intervals(0.0, np.array([0.0, 3.0, 0.0]))
    assert sorted(got) == [(0, 2.0, 9.0), (3, 9.0, 11.0)]  # waiting at 4, inside E, keeps it
    assert sh.length(np.array([1.0, 0.0, 2.0])) == 13.0
    shc = p.shapes[p.mode_of[0, 2]]
    assert shc.borders == (1.0, 3.0)
    got = shc.intervals(10.0, np.array([0.0, 2.0]))
    # movement stops during the wait at 3: two pieces; E entered after the wait
    assert sorted(got) == [(0, 15.0, 16.0), (3, 11.0, 13.0), (3, 15.0, 17.0)]
    assert shc.tools == (4,)


W0 = [[2.0, 0.0, 0.0], [], [0.0, 0.0], []]


def good(p):  # type: ignore[no-untyped-def]
    # b on B is in E over [0, 4); a on A starts at 0 and waits at its border 2 until 4: E [4, 8),
    # end 12. c on A after a: [12, 18) holding K. d on B after a, once K is free: [18, 20).
    modes = [p.mode_of[0, 0], p.mode_of[1, 1], p.mode_of[0, 2], p.mode_of[1, 3]]
    return Schedule.from_starts(p, modes, [0.0, 0.0, 12.0, 18.0], W0)


def test_a_valid_schedule() -> None:
    p = cell()
    s = good(p)
    assert validate(p, s) == 20.0
    assert s.total_wait() == 2.0
    kinds = {(r.kind, r.resource, r.task) for r in s.reservations(p)}
    assert (
        ("zone", "E", "a") in kinds and ("move", "S", "c") in kinds and ("tool", "K", "d") in kinds
    )
    d = s.to_dict(p)
    assert Schedule.from_dict(p, d) == s
    assert d["tasks"][0]["waits"] == [[2.0, 2.0]]


def replace(p, s, **kw):  # type: ignore[no-untyped-def]
    modes = kw.get("modes", s.mode.tolist())
    starts = kw.get("starts", s.start.tolist())
    waits = kw.get("waits", [w.tolist() for w in s.waits])
    return Schedule.from_starts(p, modes, starts, waits, kw.get("blocking"))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            dict(waits=[[0.0, 0.0, 0.0], [], [0.0, 0.0], []]),
            r"arms 'B' \(task 'b'\) and 'A' \(task 'a'\) are both inside exclusive zone 'E' during \[2, 4\)",
        ),
        (dict(starts=[0.0, 0.0, 0.5, 18.0]), "starts at 0.5 before its release 1"),
        (
            dict(starts=[0.0, 0.0, 12.0, 11.0]),
            "task 'd' starts at 11 before its predecessor 'a' ends at 12",
        ),
        (
            dict(starts=[0.0, 0.0, 11.0, 18.0]),
            "arm 'A' starts task 'c' at 11, but it finishes 'a' and travels until 12",
        ),
        (
            dict(starts=[0.0, 0.0, 12.0, 14.0]),
            r"arms 'A' \(task 'c'\) and 'B' \(task 'd'\) are both holding tool 'K' during \[14, 16\)",
        ),
        (dict(modes=[1, 1, 2, 4]), "task 'a' is given mode 1, which is not one of its modes"),
        (dict(waits=[[2.0], [], [0.0, 0.0], []]), "task 'a' gives 1 waits for 3 borders"),
        (dict(waits=[[-1.0, 3.0, 0.0], [], [0.0, 0.0], []]), "negative or non-finite wait"),
    ],
)
def test_each_violation_is_named(change: dict, message: str) -> None:  # type: ignore[type-arg]
    p = cell()
    bad = replace(p, good(p), **change)
    with pytest.raises(ScheduleError, match=message):
        validate(p, bad)


def test_end_must_match_duration() -> None:
    p = cell()
    s = good(p)
    bad = Schedule(s.mode, s.start, s.end + np.array([0, 0, 0, 1.0]), s.waits, s.blocking)
    with pytest.raises(
        ScheduleError,
        match="task 'd' ends at 21, but start \\+ duration \\+ waits \\+ blocking = 20",
    ):
        validate(p, bad)
    with pytest.raises(ScheduleError, match="covers 3 tasks"):
        validate(p, Schedule(s.mode[:3], s.start[:3], s.end[:3], s.waits[:3], s.blocking[:3]))


def test_shared_zone_many_stand_one_moves() -> None:
    p = cell()
    modes = [p.mode_of[0, 0], p.mode_of[1, 1], p.mode_of[1, 2], p.mode_of[1, 3]]
    # c on B from 5: in S over [5, 11), moving [6, 10); a (waiting 2 at border 2) moves in S
    # over [8, 10): both move there at once
    s = Schedule.from_starts(p, modes, [0.0, 0.0, 5.0, 12.0], W0)
    with pytest.raises(ScheduleError, match=r"both moving in shared zone 'S' during \[8, 10\)"):
        validate(p, s)
    # a also waits 2 at border 6 (standing in S, not moving) until c's movement ends: valid
    s = Schedule.from_starts(p, modes, [0.0, 0.0, 5.0, 14.0], [[2.0, 0.0, 2.0], [], [0.0, 0.0], []])
    assert validate(p, s) == 16.0


def test_waiting_inside_an_exclusive_zone_keeps_it() -> None:
    p = cell()
    modes = [p.mode_of[0, 0], p.mode_of[1, 1], p.mode_of[0, 2], p.mode_of[1, 3]]
    # a waits 3 at border 4, inside its E window: it holds E over [2, 9), not [2, 6)
    s = Schedule.from_starts(
        p, modes, [0.0, 7.0, 13.0, 19.0], [[0.0, 3.0, 0.0], [], [0.0, 0.0], []]
    )
    with pytest.raises(
        ScheduleError,
        match=r"'A' \(task 'a'\) and 'B' \(task 'b'\) are both inside exclusive zone 'E' during \[7, 9\)",
    ):
        validate(p, s)
    ok = Schedule.from_starts(
        p, modes, [0.0, 9.0, 13.0, 19.0], [[0.0, 3.0, 0.0], [], [0.0, 0.0], []]
    )
    assert validate(p, ok) == 21.0


def test_start_zone_held_until_departure() -> None:
    p = cell(start_zone=True)  # B stands in E at the start
    assert validate(p, good(p)) == 20.0  # B leaves E for b at once
    # b only at 12: B stands in E until then, a's E window [4, 8) is refused
    s2 = Schedule.from_starts(
        p,
        [p.mode_of[0, 0], p.mode_of[1, 1], p.mode_of[0, 2], p.mode_of[1, 3]],
        [0.0, 12.0, 12.0, 18.0],
        W0,
    )
    with pytest.raises(
        ScheduleError,
        match=r"arms 'B' \(standing \(start zone\)\) and 'A' \(task 'a'\) are both inside exclusive zone 'E' during \[4, 8\)",
    ):
        validate(p, s2)


def test_setup_times() -> None:
    p = cell(setup=1.0)
    with pytest.raises(
        ScheduleError,
        match="arm 'A' starts task 'a' at 0, but it becomes available and travels until 1",
    ):
        validate(p, good(p))
    # every move takes 1 s: a and b at 1, a waits until b leaves E at 5; c at 14; d at 20
    s = replace(p, good(p), starts=[1.0, 1.0, 14.0, 20.0])
    assert validate(p, s) == 22.0


class Oracle:
    def __init__(self, cost: float) -> None:
        self.c = cost
        self.calls = 0

    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        self.calls += 1
        # arm B parked after b (task 1) is in the way of task c (task 2) on arm A
        return self.c if (arm == 1 and pose_task == 1) else 0.0


def test_blocking_costs_are_required() -> None:
    p = cell(oracle=Oracle(3.0))
    s = good(p)
    # at c's start (12) B has finished b (at 4) and waits for d (at 18): parked after b, in c's way
    assert blocking_required(p, s, 2) == (3.0, [(1, 1)])
    with pytest.raises(
        ScheduleError,
        match="task 'c' is charged 0 s of detour, but the arms parked in its way force 3 s",
    ):
        validate(p, s)
    charged = replace(p, s, starts=[0.0, 0.0, 12.0, 21.0], blocking=[0, 0, 3.0, 0])
    assert validate(p, charged) == 23.0
    # B still working on b at 12: not parked, nothing needed
    busy = replace(p, s, starts=[0.0, 9.0, 12.0, 18.0])
    assert blocking_required(p, busy, 2) == (0.0, [])
    assert validate(p, busy) == 20.0
    impossible = cell(oracle=Oracle(math.inf))
    with pytest.raises(
        ScheduleError, match="arm 'B' is parked at the end pose of 'b', in its way with no detour"
    ):
        validate(impossible, good(impossible))
