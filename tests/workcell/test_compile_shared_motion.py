"""The compile times and sweeps a motion repeated by several tasks once per
arm, and the zone sweep hands out one trajectory's samples once."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from workcell import compile_cell, load_example
from workcell.arms import JointTrajectory
from workcell.geometry import sample_trajectory, zone_windows
from workcell.program import expand_task


def _motion_of(program: Any) -> tuple[Any, ...]:
    return tuple(
        (
            s.kind,
            None if s.target is None else s.target.tolist(),
            s.interpolation,
            s.speed,
            s.duration,
            s.label,
            s.step,
        )
        for s in program.segments
    )


@pytest.fixture(scope="module")
def compiled() -> Any:
    return compile_cell(load_example("urdf_cell"))


def test_modes_share_a_motion_exactly_when_their_programs_move_alike(compiled: Any) -> None:
    """Two modes of one arm share their trajectory if and only if their tasks'
    programs have the same moves and dwells; urdf_cell repeats every task for
    a second product, so half its modes share."""
    cell = compiled.cell
    ts = cell.taskset
    programs = {t.id: _motion_of(expand_task(t, ts.trajectories, cell.plan_with)) for t in ts.tasks}
    modes = compiled.modes
    shared = 0
    for i, a in enumerate(modes):
        for b in modes[i + 1 :]:
            if a.arm != b.arm:
                continue
            same = programs[a.task] == programs[b.task]
            assert (a.trajectory is b.trajectory) == same, (a.task, b.task, a.arm)
            if same:
                shared += 1
                assert a.windows == b.windows and a.duration == b.duration
                assert np.array_equal(a.q_start, b.q_start) and np.array_equal(a.q_end, b.q_end)
    assert shared == len(modes) // 2


def test_shared_windows_are_each_modes_own_sweep(compiled: Any) -> None:
    """Each mode's SDL zone windows are its own trajectory's sweep (active
    zones; occupy windows, and move windows in shared zones)."""
    cell = compiled.cell
    zm = cell.zone_map
    shared, active = ~zm.exclusive_mask(), zm.active_mask()
    names = set(zm.zone_names())
    for cm in compiled.modes:
        zw = zone_windows(cell.arm(cm.arm), cm.trajectory, zm, padding=cell.padding)
        want = set()
        for w in zw.windows:
            if not active[w.zone_id]:
                continue
            spans = [("occupy", s) for s in w.occupied]
            if shared[w.zone_id]:
                spans += [("move", s) for s in w.moving]
            for kind, (s, e) in spans:
                s, e = max(0.0, s), min(cm.duration, e)
                if e > s:
                    want.add((w.zone, round(s, 12), round(e, 12), kind))
        got = {
            (w.zone, round(w.start, 12), round(w.end, 12), w.kind)
            for w in cm.windows
            if w.zone in names
        }
        assert got == want, (cm.task, cm.arm)


def test_samples_are_read_only_and_equal_for_an_equal_trajectory(compiled: Any) -> None:
    """The samples of a trajectory are handed out again (read-only) for the
    same arm, padding and grid; an equal trajectory built anew samples to
    the same values, and another padding to other samples."""
    cm = max(compiled.modes, key=lambda m: len(m.trajectory.segments))
    arm = compiled.cell.arm(cm.arm)
    t1, q1 = sample_trajectory(arm, cm.trajectory, 0.01)
    t2, q2 = sample_trajectory(arm, cm.trajectory, 0.01)
    assert t2 is t1 and q2 is q1
    assert not t1.flags.writeable and not q1.flags.writeable
    with pytest.raises(ValueError):
        q1[0, 0] = 1.0
    fresh = JointTrajectory.build(cm.trajectory.segments)
    t3, q3 = sample_trajectory(arm, fresh, 0.01)
    assert t3 is not t1 and np.array_equal(t3, t1) and np.array_equal(q3, q1)
    t4, _ = sample_trajectory(arm, cm.trajectory, 0.005)
    assert len(t4) > len(t1)
    gaps = arm.displacement_bound(np.diff(q1, axis=0))
    assert gaps.max() <= 0.01
