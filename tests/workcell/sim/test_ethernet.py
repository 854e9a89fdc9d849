"""Ethernet CSMA/CD and CSMA/DCR, the S2.9 bound and the transmit chain."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from multiarm.errors import ValidationError
from workcell.sim.comms import (
    REDUCED,
    EthernetMedium,
    EthernetParams,
    TransmitChain,
    dcr_bound,
    dcr_rounds,
    ethernet_rounds,
    min_slot_time,
)
from workcell.sim.comms.medium import Frame
from workcell.sim.events.loop import EventLoop


class SpyRng:
    """Wraps a Generator and records every backoff draw (low, high, value)."""

    def __init__(self, seed: int, zero: bool = False) -> None:
        self.rng = np.random.default_rng(seed)
        self.zero = zero
        self.draws: list[tuple[int, int, int]] = []

    def integers(self, low: int, high: int) -> int:
        v = 0 if self.zero else int(self.rng.integers(low, high))
        self.draws.append((low, high, v))
        return v


def _all_at_once(
    n: int, mode: Any, seed: int = 0, sizes: list[int] | None = None
) -> tuple[EventLoop, EthernetMedium, list[str]]:
    k = EventLoop()
    m = EthernetMedium(k, np.linspace(0.0, 100.0, n), mode=mode, seed=seed)
    dropped: list[str] = []
    m.on_drop(lambda f, why: dropped.append(why))
    for s in range(n):
        size = sizes[s] if sizes else (148 if s == 0 else 51)
        m.send(Frame(s, (s + 1) % n, size))
    return k, m, dropped


# ------------------------------------------------------------- the bound --
def test_604_microseconds_reproduced() -> None:
    assert dcr_bound() == pytest.approx(604e-6, abs=1e-6)
    assert dcr_bound() == pytest.approx(604.1e-6, abs=1e-9)
    # the arithmetic of the docstring, term by term
    tau, ifs = 0.5e-6, 9.6e-6
    gamma = 2 * tau + 3.2e-6 + 3.2e-6
    expected = (118.4e-6 + tau + ifs) + 9 * (40.8e-6 + tau + ifs) + ifs + gamma + tau
    assert dcr_bound() == pytest.approx(expected, rel=1e-12)
    # the other readings do not reproduce the paper
    assert abs(dcr_bound(count_preamble=True) - 604e-6) > 50e-6
    assert abs(dcr_bound(n_stations=9) - 604e-6) > 40e-6
    assert abs(dcr_bound(epsilon=0.0) - 604e-6) > 3e-6


def test_reduced_parameters() -> None:
    d = dcr_bound(**REDUCED)
    assert d == pytest.approx(287.7e-6, abs=1e-9)
    assert d < dcr_bound() / 2
    assert min_slot_time(100.0, rate=20e6) == pytest.approx(2.6e-6)
    assert min_slot_time(100.0) < 51.2e-6


def test_bound_validation() -> None:
    with pytest.raises(ValidationError, match="n_stations"):
        dcr_bound(n_stations=0)
    with pytest.raises(ValidationError, match="rate"):
        dcr_bound(rate=0.0)


@settings(max_examples=30, deadline=None)
@given(
    n=st.integers(2, 12),
    load=st.floats(0.05, 1.0),
    length=st.floats(1.0, 2500.0),
    fast=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_batch_dcr_never_exceeds_bound(
    n: int, load: float, length: float, fast: bool, seed: int
) -> None:
    # REDUCED's 3.2 us slot only suits short buses: take its rate and IFS
    kw: dict[str, Any] = {"rate": REDUCED["rate"], "ifs": REDUCED["ifs"]} if fast else {}
    d = dcr_rounds(300, n_stations=n, load=load, bus_length=length, seed=seed, **kw)
    assert d.size > 0
    assert d.max() <= dcr_bound(n_stations=n, bus_length=length, **kw)


@settings(max_examples=25, deadline=None)
@given(
    positions=st.lists(st.floats(0.0, 100.0), min_size=2, max_size=10),
    traj_points=st.integers(1, 5),
    eps=st.floats(0.0, 3.2e-6),
    order_seed=st.integers(0, 1000),
    spread=st.sampled_from([0.0, 0.4e-6, 50e-6, 600e-6]),
)
def test_event_dcr_never_exceeds_bound(
    positions: list[float], traj_points: int, eps: float, order_seed: int, spread: float
) -> None:
    # one frame per station, sent at random instants within `spread` seconds
    n = len(positions)
    k = EventLoop()
    rng = np.random.default_rng(order_seed)
    order = list(rng.permutation(n))
    m = EthernetMedium(
        k, positions, mode="csma_dcr", params=EthernetParams(detect_delay=eps), order=order
    )
    for s in range(n):
        size = 28 + 24 * traj_points if s == 0 else 51
        f = Frame(s, (s + 1) % n, size, "trajectory" if s == 0 else "position")
        k.schedule(float(rng.uniform(0.0, spread)), m.send, f)
    k.run()
    assert m.stats.count == n and m.stats.drops == 0
    bound = dcr_bound(n_stations=n, bus_length=100.0, epsilon=eps)
    assert m.stats.max() <= bound


def test_event_dcr_is_close_to_the_bound_for_the_paper_case() -> None:
    k, m, _ = _all_at_once(10, "csma_dcr")
    k.run()
    assert m.epochs == 1 and m.stats.count == 10
    # the bound adds one IFS + tau for a frame arriving just after the start
    assert dcr_bound(epsilon=0.0) - 25e-6 < m.stats.max() <= dcr_bound(epsilon=0.0)


def test_dcr_resolution_follows_the_fixed_order() -> None:
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 30.0, 60.0, 90.0], mode="csma_dcr", order=[2, 0, 3, 1])
    sent: list[int] = []
    for s in range(4):
        m.attach(s, lambda f, t: sent.append(f.src))
    for s in range(4):
        m.send(Frame(s, (s + 1) % 4, 64))
    k.run()
    assert sent == [2, 0, 3, 1]


# ------------------------------------------------------------- CSMA/CD ----
def test_csma_cd_delivers_everything_with_backoff() -> None:
    k, m, dropped = _all_at_once(10, "csma_cd", seed=3)
    k.run()
    assert m.stats.count == 10 and not dropped and m.collisions > 0
    assert m.epochs == 0


def test_backoff_range_follows_the_standard() -> None:
    k, m, _ = _all_at_once(24, "csma_cd", seed=11)
    spy = SpyRng(11)
    m._rng = spy  # type: ignore[assignment]
    k.run()
    assert m.stats.count == 24
    # (low, high) of draw after the n-th collision is [0, 2^min(n, 10))
    highs = {high for _, high, _ in spy.draws}
    assert highs <= {2**k for k in range(1, 11)}
    assert all(0 <= v < high and low == 0 for low, high, v in spy.draws)
    # statistics with a fixed seed: the first retry is 0 or 1 slots, evenly
    first = [v for _, high, v in spy.draws if high == 2]
    assert len(first) >= 24
    assert 0.3 < np.mean(first) < 0.7


def test_sixteen_attempts_then_drop() -> None:
    k, m, dropped = _all_at_once(2, "csma_cd")
    spy = SpyRng(0, zero=True)  # always 0 slots: the two collide every time
    m._rng = spy  # type: ignore[assignment]
    k.run()
    assert m.stats.count == 0 and m.stats.drops == 2
    assert dropped == ["excessive collisions (16 attempts)"] * 2
    # 15 backoffs per frame, then the 16th collision drops it
    assert len(spy.draws) == 30
    assert max(high for _, high, _ in spy.draws) == 2**10


def test_ethernet_batch_statistics() -> None:
    kw: dict[str, Any] = {"n_stations": 2, "trajectory_points": (1, 1), "seed": 5}
    d = ethernet_rounds(2000, **kw)
    assert d.shape == (4000,) and not np.isnan(d).any()
    assert np.array_equal(d, ethernet_rounds(2000, **kw))
    # two stations: after the first collision each picks 0 or 1 slot; half the
    # time they differ and the first frame goes at the second try, after
    # gamma + IFS + X/R + tau <= 59.1 us; a second collision costs >= 75 us
    one_try = np.mean(np.sort(d.reshape(-1, 2), axis=1)[:, 0] < 65e-6)
    assert 0.45 < one_try < 0.55
    # a plain-Python run of the same kernel gives the same numbers
    d3 = ethernet_rounds(50, n_stations=4, seed=2, jit=False)
    d4 = ethernet_rounds(50, n_stations=4, seed=2, jit=True)
    assert np.array_equal(d3, d4, equal_nan=True)


def test_ethernet_batch_drops_after_16_attempts() -> None:
    # a slot of 0 makes every retry collide: all frames dropped
    d = ethernet_rounds(10, n_stations=3, slot_time=0.0, seed=0)
    assert np.isnan(d).all()


# -------------------------------------------------------- transmit chain --
def test_urgent_frame_goes_second_not_first() -> None:
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 100.0], mode="csma_dcr")
    order: list[str] = []
    m.attach(1, lambda f, t: order.append(f.kind))
    m.send(Frame(0, 1, 148, "trajectory-a", priority=5))
    m.send(Frame(0, 1, 148, "trajectory-b", priority=5))
    m.send(Frame(0, 1, 28, "alarm", priority=0))
    k.run()
    assert order == ["trajectory-a", "alarm", "trajectory-b"]


def test_fifo_chain_keeps_arrival_order() -> None:
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 100.0], mode="csma_cd")
    order: list[str] = []
    m.attach(1, lambda f, t: order.append(f.kind))
    for kind, prio in (("a", 5), ("b", 5), ("alarm", 0)):
        m.send(Frame(0, 1, 64, kind, priority=prio))
    k.run()
    assert order == ["a", "b", "alarm"]


def test_transmit_chain_unit() -> None:
    c = TransmitChain(by_priority=True)
    with pytest.raises(ValidationError, match="empty"):
        c.pop()
    c.push(Frame(0, 1, 10, "low", priority=9))
    c.push(Frame(0, 1, 10, "mid", priority=5))
    c.push(Frame(0, 1, 10, "urgent", priority=0))
    assert len(c) == 3
    assert [c.pop().kind for _ in range(3)] == ["low", "urgent", "mid"]
