"""The one throttle of the geometric look-again (both policies, S2.6, S2.12)."""

from __future__ import annotations

import itertools

from hypothesis import given, settings
from hypothesis import strategies as st

from workcell.sim.coordination.throttle import Throttle
from workcell.sim.events.loop import EventLoop


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    limit=st.integers(1, 6),
    max_stalled=st.integers(0, 5),
    progress_at=st.sets(st.integers(0, 12), max_size=4),
)
def test_a_look_that_always_pokes_again_ends(
    limit: int, max_stalled: int, progress_at: set[int]
) -> None:
    """A look that pokes again every time (nothing ever clears) never runs
    the kernel forever: at most ``limit`` looks per instant (and the
    deferred one), a deferred look
    one period later, and after ``max_stalled`` deferred looks with no
    progress the looks stop; each progress allows ``max_stalled`` more."""
    k = EventLoop()
    looks: list[float] = []

    def look() -> None:
        if len(looks) in progress_at:
            th.progress()
        looks.append(k.now)
        th.poke()

    th = Throttle(k, look, limit=limit, max_stalled=max_stalled, period=0.25)
    th.poke()
    k.run(until=100.0)
    assert not th.pending
    instants = sorted(set(looks))
    # the deferred look itself is not counted at its instant
    assert all(looks.count(t) <= limit + (t > 0) for t in instants)
    assert all(b - a == 0.25 for a, b in itertools.pairwise(instants))
    assert len(instants) <= 1 + max_stalled * (1 + len(progress_at))
    if not progress_at:
        assert len(instants) == 1 + max_stalled
