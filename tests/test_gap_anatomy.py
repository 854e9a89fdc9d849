"""benchmarks/gap_anatomy.py: its accounts of a plan add up to the makespan."""

from __future__ import annotations

import pytest

from benchmarks.gap_anatomy import CAUSES, anatomy, bottleneck_timeline
from scheduler import solve
from scheduler.bounds import resource_bounds
from scheduler.generate import random_problem


@pytest.mark.parametrize("seed", range(4))
def test_every_account_adds_up_to_the_makespan(seed: int) -> None:
    p = random_problem(
        4, 30, 2, 1, seed=seed, zone_fraction=0.9, tool_fraction=0.3, start_zones=seed % 2 == 0
    )
    s = solve(p, "greedy", seed=seed).schedule
    an = anatomy(p, s)
    ms = an["makespan"]
    keys = ("available", "travel", "work", "waits", *CAUSES, "idle after")
    for row in an["arms"]:  # every arm's time, up to the makespan
        assert sum(row[k] for k in keys) == pytest.approx(ms, abs=1e-6)
    ch = an["chain"]
    assert ch["in tasks"] + ch["travel"] + ch["idle"] + ch["release"] == pytest.approx(ms, abs=1e-6)
    assert sum(an["hops"].values()) >= 1
    top = max(resource_bounds(p), key=lambda r: r.bound)
    tl = bottleneck_timeline(p, s, top.resource)
    parts = [v for k, v in tl.items() if k != "mode excess"]
    assert sum(parts) == pytest.approx(ms, abs=1e-6)
    assert tl["least work"] >= top.work - 1e-6 and tl["mode excess"] >= -1e-9
