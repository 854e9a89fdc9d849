"""The simulation's fast paths give exactly what the plain computations give.

The geometric guard (S2.12) keeps each arm's constant capsule data and
bounds swept boxes in one compiled pass; the event loop pauses the cyclic
garbage collector while it runs. Seeded random inputs, bit-for-bit equality.
"""

from __future__ import annotations

import gc
from typing import Any

import numpy as np
import pytest

from workcell.geometry.zone_sweep import _segments
from workcell.sim.coordination.guard import GeometryGuard, _swept_box
from workcell.sim.events.loop import EventLoop


@pytest.mark.parametrize("seed", range(5))
def test_swept_box_is_the_numpy_bounds(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, s = int(rng.integers(1, 40)), int(rng.integers(1, 9))
    p0, p1 = rng.normal(size=(2, n, s, 3)) * 10.0 ** rng.uniform(-3, 1)
    grow = float(rng.uniform(0.0, 0.2))
    box = _swept_box(p0, p1, grow)
    lo = np.minimum(p0.min(axis=(0, 1)), p1.min(axis=(0, 1))) - grow
    hi = np.maximum(p0.max(axis=(0, 1)), p1.max(axis=(0, 1))) + grow
    assert np.array_equal(box, np.concatenate([lo, hi]))


@pytest.mark.parametrize("name", ["cell", "scara4"])
def test_guard_capsule_ends_are_those_of_the_zone_sweep(
    name: str, request: pytest.FixtureRequest
) -> None:
    cc: Any = request.getfixturevalue(name)
    guard = GeometryGuard(cc)
    rng = np.random.default_rng(7)
    for a, arm in enumerate(cc.cell.arms):
        lim = np.asarray(arm.joint_limits, dtype=float)
        q = rng.uniform(lim[:, 0], lim[:, 1], size=(int(rng.integers(1, 30)), arm.dof))
        mine = guard._ends(a, q)
        ref = _segments(arm, q, guard.capsules[a][0])
        assert np.array_equal(mine[0], ref[0]) and np.array_equal(mine[1], ref[1])


def test_the_loop_pauses_the_collector_and_restores_it() -> None:
    seen: list[bool] = []
    k = EventLoop()
    k.schedule(1.0, lambda: seen.append(gc.isenabled()))
    was = gc.isenabled()
    try:
        gc.enable()
        k.run()
        assert seen == [False] and gc.isenabled()

        def boom() -> None:
            raise RuntimeError("callback failed")

        k.schedule(1.0, boom)
        with pytest.raises(RuntimeError):
            k.run()
        assert gc.isenabled()  # restored when a callback raises
        gc.disable()
        k.schedule(1.0, lambda: seen.append(gc.isenabled()))
        k.run()
        assert not gc.isenabled()  # left as it was found
    finally:
        if was:
            gc.enable()
        else:  # pragma: no cover - the suite runs with the collector on
            gc.disable()
