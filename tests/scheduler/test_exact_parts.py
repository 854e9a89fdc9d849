"""``scheduler.exact.prove`` split over processes (``workers``) and restricted to
some tasks' modes (``domains``).

The split proves each part (a combination of the first tasks' modes) in a
forked process from the same incumbent; the problem is proven when every part
is, and the bound is the least of the parts'. Checked against the search in one
process on seeded generated problems (arms, zones, tools, setups and waits
varied; none of them tuned anything here).
"""

from __future__ import annotations

import itertools
import threading

import pytest

from scheduler import exact, validate
from scheduler.exact import _parts, prove
from scheduler.generate import random_problem


def _problem(seed: int):  # type: ignore[no-untyped-def]
    return random_problem(
        2 + seed % 2,
        6 + seed % 3,
        1 + seed % 3,
        seed % 2,
        seed=700 + seed,
        zone_fraction=0.9,
        setups=seed % 3 != 2,
    )


@pytest.mark.parametrize("seed", range(6))
def test_the_split_proves_the_same_optimum_as_one_process(seed: int) -> None:
    p = _problem(seed)
    one = prove(p, max_nodes=5_000_000)
    two = prove(p, max_nodes=5_000_000, workers=2)
    assert one.proven and two.proven and two.reason in ("proven", "met the lower bound")
    assert two.makespan == pytest.approx(one.makespan, abs=1e-9)
    assert two.bound == pytest.approx(two.makespan)
    assert two.schedule is not None
    assert validate(p, two.schedule) == pytest.approx(two.makespan, abs=1e-9)
    counts = dict(two.counts)
    assert counts["parts"] >= 2
    # the same parts, the same work and schedule, whichever process ends first
    again = prove(p, max_nodes=5_000_000, workers=2)
    assert (again.nodes, again.makespan) == (two.nodes, two.makespan)
    assert again.schedule is not None
    assert again.schedule.mode.tolist() == two.schedule.mode.tolist()


def test_domains_restrict_the_modes_and_their_optima_cover_the_problem() -> None:
    p = _problem(1)
    full = prove(p, max_nodes=5_000_000)
    t = next(t for t in p.topological_order if len(p.task_modes[t]) >= 2)
    optima = []
    for m in p.task_modes[t]:
        part = prove(p, max_nodes=5_000_000, domains={t: [m]})
        assert part.proven and part.schedule is not None
        assert int(part.schedule.mode[t]) == m
        assert part.makespan >= full.makespan - 1e-9
        optima.append(part.makespan)
    assert min(optima) == pytest.approx(full.makespan, abs=1e-9)
    # a domain with no mode of the task: no schedule, proven (none exists)
    other = [m for m in range(p.n_modes) if m not in p.task_modes[t]][:1]
    none = prove(p, max_nodes=5_000_000, domains={t: other})
    assert none.proven and none.schedule is None


def test_the_parts_cover_every_combination_once_the_incumbents_first() -> None:
    p = _problem(4)
    inc = prove(p, max_nodes=5_000_000).schedule
    assert inc is not None
    parts = _parts(p, None, None, 8, inc)
    chosen = sorted(parts[0])
    assert len(parts) >= 8 or all(
        len(p.task_modes[t]) < 2 for t in p.topological_order if t not in chosen
    )
    combos = {tuple(d[t][0] for t in chosen) for d in parts}
    assert len(combos) == len(parts)
    assert combos == set(itertools.product(*(p.task_modes[t] for t in chosen)))
    assert all(parts[0][t] == (int(inc.mode[t]),) for t in chosen)
    # nothing to split: one mode per task
    fixed = [p.task_modes[t][0] for t in range(p.n_tasks)]
    assert _parts(p, fixed, None, 8, None) == []


def test_a_node_limit_is_shared_out_and_the_bound_stays_below_the_optimum() -> None:
    p = random_problem(3, 9, 3, 1, seed=7, zone_fraction=0.9)
    full = prove(p, max_nodes=5_000_000)
    assert full.proven
    cut = prove(p, max_nodes=80, workers=2)
    assert not cut.proven and cut.reason == "nodes"
    assert cut.bound <= full.makespan + 1e-9 <= cut.makespan + 1e-9
    assert cut.nodes <= 80 + dict(cut.counts)["parts"]


def test_one_process_where_it_may_not_fork_and_a_refused_problem_is_not_split(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    p = _problem(0)
    monkeypatch.setattr(exact, "_may_fork", lambda: False)
    res = prove(p, max_nodes=5_000_000, workers=2)
    assert res.proven and "parts" not in dict(res.counts)
    monkeypatch.undo()
    bound = random_problem(2, 5, 2, 1, seed=1, blocking=True)
    out = prove(bound, time_limit=5, workers=2)
    assert not out.proven and out.reason == "a blocking oracle is set"


def test_a_stop_set_before_the_parts_end_stops_them() -> None:
    p = random_problem(3, 12, 3, 1, seed=11, zone_fraction=0.9)
    stop = threading.Event()
    stop.set()
    res = prove(p, time_limit=60, workers=2, stop=stop)
    assert not res.proven and res.reason == "stopped"
    assert res.bound <= res.makespan


def test_a_part_that_fails_is_reported_with_its_error(monkeypatch: pytest.MonkeyPatch) -> None:
    from multiarm.errors import InternalError

    real = exact.prove

    def broken(*args, **kwargs):  # type: ignore[no-untyped-def]
        if kwargs.get("domains") is not None:  # a part's process
            raise RuntimeError("boom")
        return real(*args, **kwargs)

    monkeypatch.setattr(exact, "prove", broken)
    with pytest.raises(InternalError, match=r"part \d+ of \d+ failed: RuntimeError\('boom'\)"):
        real(_problem(0), max_nodes=5_000_000, workers=2)
