"""Where the decoder puts a wait whose standing would clash (S2.6).

An arm that must wait at a zone border stands in the zones it is in. When
that clashes with another arm's use of such a zone, the decoder lets the arm
wait at the border where it entered the zone instead (until that use is
over); only a zone held from the task's start makes the task start later.
"""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scheduler import Problem, validate
from scheduler.problem import Model, Window
from scheduler.search import Evaluator
from tests.strategies import zone_problems


def _entry_clash() -> tuple[Problem, int]:
    """Arm A's task ``ta`` crosses X (0-2 s), enters Z at 2 s and Y at 5 s.
    Y is busy until 20 s (arm B), Z from 10 to 12 s (arm B) and X from
    10 to 30 s (arm C). ``ta`` must wait for Y; standing in Z at the Y border
    would clash with B's use of Z, so it waits at the Z border until 12 s:
    it starts at 0 and ends at 25 s. Starting later instead (to stand in Z
    after 12 s) would send it through X while C holds it: a start at 30 s."""
    m = Model("wait-at-entry")
    for z in ("X", "Y", "Z"):
        m.add_zone(z, "exclusive")
    for a in ("A", "B", "C"):
        m.add_arm(a)
    tb = m.add_task("tb")
    m.add_mode(
        tb, 1, 20.0, windows=[Window("Z", 10.0, 12.0, "occupy"), Window("Y", 0.0, 20.0, "occupy")]
    )
    tx = m.add_task("tx")
    m.add_mode(tx, 2, 30.0, windows=[Window("X", 10.0, 30.0, "occupy")])
    ta = m.add_task("ta")
    m.add_mode(
        ta,
        0,
        10.0,
        windows=[
            Window("X", 0.0, 2.0, "occupy"),
            Window("Z", 2.0, 10.0, "occupy"),
            Window("Y", 5.0, 10.0, "occupy"),
        ],
    )
    return m.build(), ta


def test_a_clashing_wait_moves_to_the_border_where_the_zone_was_entered() -> None:
    p, ta = _entry_clash()
    ev = Evaluator(p)
    sol = ev.evaluate(np.arange(p.n_tasks, dtype=np.int64))
    assert sol is not None
    s = ev.schedule(sol)
    assert (s.start[ta], s.end[ta]) == (0.0, 25.0)
    assert s.waits[ta].tolist() == [10.0, 5.0]  # at the Z border until B leaves Z, then for Y
    assert validate(p, s) == 30.0


def test_without_waits_the_task_starts_after_the_clashes() -> None:
    p, ta = _entry_clash()
    ev = Evaluator(p, waits=False)
    sol = ev.evaluate(np.arange(p.n_tasks, dtype=np.int64))
    assert sol is not None
    s = ev.schedule(sol)
    assert s.start[ta] == 30.0 and validate(p, s) == 40.0


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(p=zone_problems(), seed=st.integers(0, 2**16))
def test_every_decoded_list_with_waits_validates(p: Problem, seed: int) -> None:
    rng = np.random.default_rng(seed)
    ev = Evaluator(p)
    # a random topological order: random keys, then predecessors first
    key = rng.random(p.n_tasks)
    order: list[int] = []
    left = set(range(p.n_tasks))
    while left:
        ready = [t for t in left if all(q not in left for q in p.task_preds[t])]
        t = min(ready, key=lambda x: key[x])
        order.append(t)
        left.remove(t)
    sol = ev.evaluate(np.array(order, dtype=np.int64))
    assert not any(p.arm_start_zones) and p.blocking is None  # so every list decodes
    assert sol is not None
    s = ev.schedule(sol)
    assert validate(p, s) == sol.makespan
