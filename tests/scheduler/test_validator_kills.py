"""Hand cases that a weakened validator would accept (each names the weakening it kills).

Every schedule here breaks exactly one rule by a small margin; ``validate``
must name it. The first schedule of each pair is the valid neighbour, so a
validator that refuses everything cannot pass either.
"""

from __future__ import annotations

import pytest

from multiarm.errors import ScheduleError
from scheduler import Model, Schedule, Window, validate


def _two_arms_one_zone(policy: str = "exclusive", kind: str = "occupy"):  # type: ignore[no-untyped-def]
    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_zone("z", policy)  # type: ignore[arg-type]
    m.add_task("t1")
    m.add_task("t2")
    m.add_mode("t1", "a", 4.0, windows=[Window("z", 1.0, 3.0, kind)])  # type: ignore[arg-type]
    m.add_mode("t2", "b", 4.0, windows=[Window("z", 1.0, 3.0, kind)])  # type: ignore[arg-type]
    return m.build()


def test_an_overlap_shorter_than_a_second_is_refused() -> None:
    # kills: "overlaps shorter than 1 s tolerated"
    p = _two_arms_one_zone()
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 2.0]))  # touching: fine
    with pytest.raises(ScheduleError, match="both inside exclusive zone 'z'"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 1.9]))  # 0.1 s overlap


def test_move_windows_in_an_exclusive_zone_exclude_each_other() -> None:
    # kills: "move windows in exclusive zones ignored"
    p = _two_arms_one_zone("exclusive", "move")
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 2.0]))
    with pytest.raises(ScheduleError, match="exclusive zone 'z'"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 1.5]))


def test_shared_zone_moves_overlapping_briefly_are_refused() -> None:
    p = _two_arms_one_zone("shared", "move")
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 2.0]))
    with pytest.raises(ScheduleError, match="moving in shared zone 'z'"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 1.8]))


def test_arm_availability_is_respected() -> None:
    # kills: "arm availability ignored"
    m = Model()
    m.add_arm("a", available=5.0)
    m.add_task("t")
    m.add_mode("t", "a", 2.0)
    p = m.build()
    validate(p, Schedule.from_starts(p, [0], [5.0]))
    with pytest.raises(ScheduleError, match="becomes available"):
        validate(p, Schedule.from_starts(p, [0], [4.5]))


def _tool_problem():  # type: ignore[no-untyped-def]
    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_zone("z")
    m.add_tool("k")
    m.add_task("t1")
    m.add_task("t2")
    # t1 has a border at 1.0 (a window starts there): it may wait there
    m.add_mode("t1", "a", 3.0, windows=[Window("z", 1.0, 2.0)], tools=["k"])
    m.add_mode("t2", "b", 2.0, tools=["k"])
    return m.build()


def test_tools_are_held_until_the_real_end_including_waits() -> None:
    # kills: "tools released at start + duration ignoring waits and detours"
    p = _tool_problem()
    waited = Schedule.from_starts(p, [0, 1], [0.0, 5.0], waits=[[2.0], []])  # t1 ends at 5
    validate(p, waited)
    early = Schedule.from_starts(p, [0, 1], [0.0, 3.5], waits=[[2.0], []])  # t2 at 3.5 < 5
    with pytest.raises(ScheduleError, match="holding tool 'k'"):
        validate(p, early)


def test_two_arms_never_hold_one_tool() -> None:
    # kills: "a tool-conflict skip"
    p = _tool_problem()
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 3.0]))
    with pytest.raises(ScheduleError, match="holding tool 'k'"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 2.99]))


class _Table:
    """A blocking oracle from a dict {(mode, arm, pose): cost}; 0 elsewhere."""

    def __init__(self, costs: dict[tuple[int, int, int], float]) -> None:
        self.costs = costs

    def cost(self, mode: int, arm: int, pose_task: int) -> float:
        return self.costs.get((mode, arm, pose_task), 0.0)


def _blocked(costs: dict[tuple[int, int, int], float]):  # type: ignore[no-untyped-def]
    m = Model()
    for a in ("a", "b", "c"):
        m.add_arm(a)
    m.add_task("t")
    m.add_mode("t", "a", 2.0)
    m.set_blocking(_Table(costs))
    return m.build()


def test_the_initial_pose_can_block() -> None:
    # kills: "the initial pose never blocking"
    p = _blocked({(0, 1, -1): 1.5})
    validate(p, Schedule.from_starts(p, [0], [0.0], blocking=[1.5]))
    with pytest.raises(ScheduleError, match=r"force 1\.5"):
        validate(p, Schedule.from_starts(p, [0], [0.0], blocking=[0.0]))


def test_detours_around_two_parked_arms_add_up() -> None:
    # kills: "detours combined by max instead of sum"
    p = _blocked({(0, 1, -1): 1.5, (0, 2, -1): 1.0})
    validate(p, Schedule.from_starts(p, [0], [0.0], blocking=[2.5]))
    with pytest.raises(ScheduleError, match=r"force 2\.5"):
        validate(p, Schedule.from_starts(p, [0], [0.0], blocking=[1.5]))


def test_an_arm_stays_parked_until_it_leaves_for_its_next_task_travel_included() -> None:
    # kills: "a parked arm's departure ignoring its travel"
    from scheduler import MatrixSetup

    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_task("t")  # a's task
    m.add_task("u")  # b's task, which leaves b's initial pose
    m.add_mode("t", "a", 2.0)
    m.add_mode("u", "b", 1.0)
    # b travels 3 s from its initial pose to u; a-mode 0 is blocked by b at its initial pose
    import numpy as np

    times = np.zeros((2, 3, 2))
    times[1, 0, 1] = 3.0
    m.set_setup(MatrixSetup(times))
    m.set_blocking(_Table({(0, 1, -1): 2.0}))
    p = m.build()
    # b starts u at 4, so it leaves its initial pose at 4 - 3 = 1: a's task at 0.5 is blocked
    validate(p, Schedule.from_starts(p, [0, 1], [0.5, 4.0], blocking=[2.0, 0.0]))
    with pytest.raises(ScheduleError, match="force 2"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.5, 4.0], blocking=[0.0, 0.0]))
    # from 1 on, b is travelling, no longer parked: a's task at 2 owes no detour
    validate(p, Schedule.from_starts(p, [0, 1], [2.0, 4.0], blocking=[0.0, 0.0]))


def _one_arm_chain(release: float = 0.0, travel: float = 0.0):  # type: ignore[no-untyped-def]
    import numpy as np

    from scheduler import MatrixSetup

    m = Model()
    m.add_arm("a")
    m.add_task("t1")
    m.add_task("t2", release=release, predecessors=["t1"])
    m.add_mode("t1", "a", 4.0, windows=[Window("z", 1.0, 3.0)])
    m.add_mode("t2", "a", 2.0)
    m.add_zone("z")
    if travel:
        times = np.zeros((1, 3, 2))
        times[0, 1, 1] = travel  # from t1's end pose to t2
        m.set_setup(MatrixSetup(times))
    return m.build()


def test_releases_are_respected() -> None:
    m = Model()
    m.add_arm("a")
    m.add_task("t", release=2.0)
    m.add_mode("t", "a", 1.0)
    p = m.build()
    validate(p, Schedule.from_starts(p, [0], [2.0]))
    with pytest.raises(ScheduleError, match="before its release 2"):
        validate(p, Schedule.from_starts(p, [0], [1.9]))


def test_precedence_is_respected_across_arms() -> None:
    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_task("t1")
    m.add_task("t2", predecessors=["t1"])
    m.add_mode("t1", "a", 4.0)
    m.add_mode("t2", "b", 1.0)
    p = m.build()
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 4.0]))
    with pytest.raises(ScheduleError, match="before its predecessor 't1' ends at 4"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 3.9]))


def test_travel_between_tasks_of_one_arm_is_respected() -> None:
    p = _one_arm_chain(travel=1.5)
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 5.5]))
    with pytest.raises(ScheduleError, match=r"travels until 5\.5"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 5.0]))


def test_ends_must_match_start_duration_and_waits() -> None:
    import numpy as np

    p = _one_arm_chain()
    good = Schedule.from_starts(p, [0, 1], [0.0, 4.0])
    validate(p, good)
    short = Schedule(good.mode, good.start, np.array([4.0, 5.9]), good.waits, good.blocking)
    with pytest.raises(ScheduleError, match=r"'t2' ends at 5\.9"):
        validate(p, short)


def test_negative_waits_are_refused() -> None:
    p = _one_arm_chain()
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 5.0], waits=[[1.0], []]))
    with pytest.raises(ScheduleError, match="negative or non-finite wait"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 3.0], waits=[[-1.0], []]))


def test_a_mode_of_another_task_is_refused() -> None:
    p = _one_arm_chain()
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 4.0]))
    bad = Schedule.from_starts(p, [1, 1], [0.0, 4.0])
    with pytest.raises(ScheduleError, match="'t1' is given mode 1"):
        validate(p, bad)


def _start_zone_problem(travel: float = 0.0):  # type: ignore[no-untyped-def]
    import numpy as np

    from scheduler import MatrixSetup

    m = Model()
    m.add_zone("z")
    m.add_arm("a")
    m.add_arm("b", start_zones=["z"])  # b stands in z until it leaves for its task
    m.add_task("ta")
    m.add_task("tb")
    m.add_mode("ta", "a", 2.0, windows=[Window("z", 0.0, 2.0)])
    m.add_mode("tb", "b", 1.0)
    if travel:
        times = np.zeros((2, 3, 2))
        times[1, 0, 1] = travel  # b: from its initial pose to tb
        m.set_setup(MatrixSetup(times))
    return m.build()


def test_an_arm_stands_in_its_start_zone_until_it_leaves() -> None:
    p = _start_zone_problem()
    validate(p, Schedule.from_starts(p, [0, 1], [3.0, 3.0]))  # b leaves at 3, a enters at 3
    with pytest.raises(ScheduleError, match=r"standing \(start zone\)"):
        validate(p, Schedule.from_starts(p, [0, 1], [2.5, 3.0]))


def test_an_arm_leaves_its_start_zone_when_its_travel_begins() -> None:
    # b travels 2 s to tb at 5: it leaves z at 3, so a may enter at 3
    p = _start_zone_problem(travel=2.0)
    validate(p, Schedule.from_starts(p, [0, 1], [3.0, 5.0]))
    with pytest.raises(ScheduleError, match=r"standing \(start zone\)"):
        validate(p, Schedule.from_starts(p, [0, 1], [2.5, 5.0]))


def test_a_parked_arm_with_no_detour_forbids_the_task() -> None:
    import math

    p = _blocked({(0, 1, -1): math.inf})
    with pytest.raises(ScheduleError, match="in its way with no detour"):
        validate(p, Schedule.from_starts(p, [0], [0.0], blocking=[5.0]))
    q = _blocked({(0, 1, -1): 0.5})
    validate(q, Schedule.from_starts(q, [0], [0.0], blocking=[0.5]))


def test_shared_zone_occupants_that_do_not_move_may_overlap() -> None:
    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_zone("z", "shared")
    m.add_task("t1")
    m.add_task("t2")
    m.add_mode("t1", "a", 4.0, windows=[Window("z", 1.0, 3.0, "occupy")])
    m.add_mode("t2", "b", 4.0, windows=[Window("z", 1.0, 3.0, "move")])
    m.add_task("t3")
    m.add_mode("t3", "a", 4.0, windows=[Window("z", 1.0, 3.0, "move")])
    p = m.build()
    validate(p, Schedule.from_starts(p, [0, 1, 2], [0.0, 0.5, 4.0]))  # occupy + move overlap
    with pytest.raises(ScheduleError, match="moving in shared zone 'z'"):
        validate(p, Schedule.from_starts(p, [0, 1, 2], [0.0, 2.5, 4.0]))  # t2 and t3 move


def _wait_inside(policy: str, kind: str):  # type: ignore[no-untyped-def]
    # a's mode: 4 s, a window in z over [1, 3) and a border at 2 (its window in y)
    m = Model()
    m.add_arm("a")
    m.add_arm("b")
    m.add_zone("z", policy)  # type: ignore[arg-type]
    m.add_zone("y")
    m.add_task("ta")
    m.add_task("tb")
    m.add_mode("ta", "a", 4.0, windows=[Window("z", 1.0, 3.0, kind), Window("y", 2.0, 3.0)])  # type: ignore[arg-type]
    m.add_mode("tb", "b", 1.0, windows=[Window("z", 0.0, 1.0, kind)])  # type: ignore[arg-type]
    return m.build()


def test_waiting_inside_an_exclusive_zone_keeps_it() -> None:
    # a waits 2 s at its border 2, inside z: it holds z over [1, 5)
    p = _wait_inside("exclusive", "occupy")
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 5.0], waits=[[0.0, 2.0], []]))
    with pytest.raises(ScheduleError, match="exclusive zone 'z'"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 4.5], waits=[[0.0, 2.0], []]))


def test_a_waiting_arm_does_not_move() -> None:
    # a moves in shared z over [1, 2) and [4, 5): b may move there in between
    p = _wait_inside("shared", "move")
    validate(p, Schedule.from_starts(p, [0, 1], [0.0, 2.5], waits=[[0.0, 2.0], []]))
    with pytest.raises(ScheduleError, match="moving in shared zone 'z'"):
        validate(p, Schedule.from_starts(p, [0, 1], [0.0, 4.5], waits=[[0.0, 2.0], []]))
