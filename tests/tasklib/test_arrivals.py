"""Feeders and arrival models (S2.11: no fixed order, time or position)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from multiarm.errors import FormatError, ValidationError
from tasklib.arrivals import (
    Feeder,
    FixedArrivals,
    PoissonArrivals,
    TraceArrivals,
    UniformArrivals,
)

PARTS = ("a", "b", "c", "d", "e", "f")


def test_default_arrival_is_everything_at_zero() -> None:
    f = Feeder("f", PARTS)
    assert [a.time for a in f.sample()] == [0.0] * len(PARTS)
    assert all(a.position == (0.0, 0.0, 0.0) for a in f.sample())


def test_fixed_arrivals_sorted_by_time() -> None:
    f = Feeder("f", ("a", "b"), arrival=FixedArrivals((("a", 5.0), ("b", 1.0))))
    assert [(a.part, a.time) for a in f.sample()] == [("b", 1.0), ("a", 5.0)]
    with pytest.raises(ValidationError, match="does not supply"):
        Feeder("f", ("a",), arrival=FixedArrivals((("z", 1.0),)))
    g = Feeder("f", ("a", "b"), arrival=FixedArrivals((("a", 5.0),)))
    with pytest.raises(ValidationError, match="no time for part 'b'"):
        g.sample()


def test_poisson_seeded_and_order_varies() -> None:
    f = Feeder("f", PARTS, arrival=PoissonArrivals(rate=2.0, start=3.0))
    a1, a2 = f.sample(seed=7), f.sample(seed=7)
    assert a1 == a2
    assert all(a.time > 3.0 for a in a1)
    orders = {tuple(a.part for a in f.sample(seed=s)) for s in range(20)}
    assert len(orders) > 5  # parts arrive in varying order
    ordered = Feeder("f", PARTS, arrival=PoissonArrivals(rate=2.0, ordered=True))
    assert {tuple(a.part for a in ordered.sample(seed=s)) for s in range(10)} == {PARTS}


def test_poisson_rate_is_respected() -> None:
    f = Feeder("f", tuple(f"p{i}" for i in range(4000)), arrival=PoissonArrivals(rate=4.0))
    times = np.array(sorted(a.time for a in f.sample(seed=1)))
    gaps = np.diff(np.concatenate([[0.0], times]))
    assert gaps.mean() == pytest.approx(0.25, rel=0.05)


def test_uniform_bounds() -> None:
    f = Feeder("f", PARTS, arrival=UniformArrivals(2.0, 4.0))
    times = [a.time for s in range(10) for a in f.sample(seed=s)]
    assert min(times) >= 2.0 and max(times) <= 4.0
    with pytest.raises(ValidationError, match="low <= high"):
        UniformArrivals(4.0, 2.0)


def test_position_uncertainty() -> None:
    f = Feeder("f", tuple(f"p{i}" for i in range(3000)), (1.0, 2.0, 0.0), position_sigma=0.01)
    pos = np.array([a.position for a in f.sample(seed=3)])
    assert pos.mean(axis=0) == pytest.approx([1.0, 2.0, 0.0], abs=1e-3)
    assert pos.std(axis=0) == pytest.approx([0.01] * 3, rel=0.1)


def test_trace_csv(tmp_path: Path) -> None:
    p = tmp_path / "trace.csv"
    p.write_text("time,part\n1.5,b\n0.5,a\n\n")
    tr = TraceArrivals.from_csv(p)
    assert tr.events == ((1.5, "b"), (0.5, "a"))
    f = Feeder("f", ("a", "b"), arrival=tr)
    assert [a.part for a in f.sample()] == ["a", "b"]
    p.write_text("t,p\n")
    with pytest.raises(FormatError, match="header"):
        TraceArrivals.from_csv(p)
    p.write_text("time,part\nsoon,a\n")
    with pytest.raises(FormatError, match="not a number") as info:
        TraceArrivals.from_csv(p)
    assert info.value.line == 2
    p.write_text("time,part\n1,a\n2,a\n")
    with pytest.raises(FormatError, match="twice"):
        TraceArrivals.from_csv(p)
    with pytest.raises(FormatError, match="cannot read"):
        TraceArrivals.from_csv(tmp_path / "none.csv")


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Feeder("", ("a",)), "feeder id"),
        (lambda: Feeder("f", ()), "supplies no part"),
        (lambda: Feeder("f", ("a", "a")), "twice"),
        (lambda: Feeder("f", ("a",), position_sigma=-1), "position_sigma"),
        (lambda: PoissonArrivals(rate=0), "rate"),
        (lambda: FixedArrivals((("a", -1.0),)), "arrival time"),
        (lambda: FixedArrivals((("a", 1.0), ("a", 2.0))), "twice"),
        (lambda: Feeder("f", ("a",), (0, 0)), "3 coordinates"),  # type: ignore[arg-type]
    ],
)
def test_bad_feeders(make, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValidationError, match=message):
        make()
