"""The built-in example task sets exercise what the reference cells need."""

from __future__ import annotations

import pytest

from multiarm.errors import ValidationError
from tasklib import TaskSet, load_example
from tasklib.examples import scara4
from tasklib.steps import Detect, Insert, SetFlag, WaitFlag


def test_supersigma(supersigma_tasks: TaskSet) -> None:
    ts = supersigma_tasks
    steps = [s for t in ts.tasks for s in t.steps]
    assert sum(isinstance(s, Insert) for s in steps) == 1  # one force-search insertion (S1.7)
    detect = [s for s in steps if isinstance(s, Detect)]
    assert len(detect) == 1 and detect[0].mode == "measure"  # chess pieces (S1.8)
    assert any(isinstance(s, SetFlag) for s in steps) and any(
        isinstance(s, WaitFlag) for s in steps
    )
    assert ts.tools() == ("screwdriver",)
    # the board's pieces are found by the detector: imprecise feeder
    board = next(f for f in ts.feeders if f.id == "board")
    assert board.position_sigma > 0.005
    # every TDL trajectory resolves into the cell
    for name in ts.trajectories.names():
        r = ts.trajectories.resolve(name)
        assert r.positions.shape[1] == 3


def test_scara4_parts_arrive_in_varying_order(scara4_tasks: TaskSet) -> None:
    ts = scara4_tasks
    assert len(ts.groups) == 2
    orders = {
        tuple(a.part for a in ts.sample_arrivals(seed=s) if a.part.startswith(("housing", "shaft")))
        for s in range(10)
    }
    assert len(orders) > 3
    pred = ts.precedence()
    assert set(pred["place_cover1"]) == {"mount_impeller1", "press_seal1"}  # the group
    assert pred["insert_shaft1"] == ("place_housing1",)  # part prerequisite
    with pytest.raises(ValidationError):
        scara4(0)


def test_cell8_is_about_200_tasks(cell8_tasks: TaskSet) -> None:
    s = cell8_tasks.summary()
    assert s["tasks"] == 200
    assert s["depth"] >= 4
    assert len(cell8_tasks.tools()) >= 2


def test_unknown_example() -> None:
    with pytest.raises(ValidationError, match="unknown example 'nope'"):
        load_example("nope")


def test_generated_sites_place_every_product_at_a_site() -> None:
    from tasklib.examples import CELL8_SITES, generate_taskset

    ts = generate_taskset(60, seed=3, sites=CELL8_SITES)
    trays = {f.position for f in ts.feeders}
    assert trays <= {tuple(float(v) for v in f) for f, _ in CELL8_SITES}
    moves = {name for t in ts.tasks for name in t.trajectories()}
    assert moves and all(m.startswith(("to_site", "out_site")) for m in moves)


def test_expected_arrivals_follow_each_model(cell8_tasks: TaskSet) -> None:
    ts = load_example("scara4")
    exp = ts.expected_arrivals()
    assert exp["housing1"] == 10.0  # uniform on [0, 20]
    assert exp["cover1"] == 15.0 and exp["cover2"] == 25.0  # ordered Poisson, rate 0.1 from 5 s
    assert set(cell8_tasks.expected_arrivals()) == {p for f in cell8_tasks.feeders for p in f.parts}
