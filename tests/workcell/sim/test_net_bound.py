"""The S2.9 delay bound: the paper's 604 us, the open parameters, the reduced
case, and simulated CSMA/DCR delays never above the bound."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import workcell
from multiarm.errors import ValidationError
from workcell.sim.comms import (
    REDUCED,
    EthernetMedium,
    EthernetParams,
    dcr_bound,
    dcr_rounds,
    min_slot_time,
)
from workcell.sim.comms.medium import Frame
from workcell.sim.events.loop import EventLoop

US = 1e-6


def test_stable_name_is_the_paper_worst_case() -> None:
    assert workcell.dcr_bound is dcr_bound
    assert abs(workcell.dcr_bound() - 604 * US) <= 1 * US


def test_mixed_form_term_by_term() -> None:
    # one 148-byte trajectory from the coordinator + 9 position reports of 51
    # bytes, 10 Mb/s, 100 m at 2e8 m/s, IFS 9.6, jam 32 bits, epsilon = jam
    r, tau, ifs, jam, eps = 10e6, 0.5 * US, 9.6 * US, 3.2 * US, 3.2 * US
    gamma = 2 * tau + jam + eps
    traj = 148 * 8 / r + tau + ifs
    pos = 51 * 8 / r + tau + ifs
    assert dcr_bound() == pytest.approx(traj + 9 * pos + ifs + gamma + tau, rel=1e-12)
    # the plain form D_max = N (X/R + tau + IFS) + IFS + gamma + tau with X = X_t
    assert dcr_bound(mixed=False) == pytest.approx(10 * traj + ifs + gamma + tau, rel=1e-12)
    # all trajectories == mixed form with position_bytes = trajectory_bytes
    assert dcr_bound(mixed=False) == pytest.approx(dcr_bound(position_bytes=148), rel=1e-12)


@pytest.mark.parametrize(
    ("reading", "kwargs", "micros"),
    [
        ("paper defaults (eps = jam, no extra preamble, 2e8 m/s, N = 10)", {}, 604.1),
        ("eps = 0", {"epsilon": 0.0}, 600.9),
        ("eps = 3.1 us", {"epsilon": 3.1 * US}, 604.0),
        ("preamble added again", {"count_preamble": True}, 668.1),
        ("N = 9 (robots only)", {"n_stations": 9}, 553.2),
        ("propagation at c", {"propagation_speed": 3e8}, 601.93),
        ("2500 m bus", {"bus_length": 2500.0}, 760.1),
    ],
)
def test_open_parameters(reading: str, kwargs: dict[str, Any], micros: float) -> None:
    """Every reading the paper leaves open, with its value (docs/networks.md)."""
    assert dcr_bound(**kwargs) == pytest.approx(micros * US, abs=0.01 * US), reading


def test_only_the_chosen_reading_reproduces_604() -> None:
    readings: dict[str, dict[str, Any]] = {
        "default": {},
        "preamble": {"count_preamble": True},
        "robots only": {"n_stations": 9},
        "no epsilon": {"epsilon": 0.0},
    }
    close = {name: abs(dcr_bound(**kw) - 604 * US) <= 1 * US for name, kw in readings.items()}
    assert close == {"default": True, "preamble": False, "robots only": False, "no epsilon": False}


def test_reduced_case() -> None:
    assert REDUCED == {"rate": 20e6, "ifs": 3.2e-6, "slot_time": 3.2e-6}
    d = dcr_bound(**REDUCED)
    # X_t/R = 59.2, X_p/R = 20.4, gamma = 1.0 + 1.6 + 1.6 us
    expected = (59.2 + 0.5 + 3.2) + 9 * (20.4 + 0.5 + 3.2) + 3.2 + 4.2 + 0.5
    assert d == pytest.approx(expected * US, abs=1e-12)
    assert d == pytest.approx(287.7 * US, abs=0.01 * US)
    # each change alone: rate 358.1, IFS 533.7
    assert dcr_bound(rate=20e6) == pytest.approx(358.1 * US, abs=0.01 * US)
    assert dcr_bound(ifs=3.2e-6) == pytest.approx(533.7 * US, abs=0.01 * US)


def test_slot_must_exceed_jam_plus_two_tau() -> None:
    assert min_slot_time(100.0, rate=20e6) == pytest.approx(2.6 * US)
    assert min_slot_time(100.0) == pytest.approx(4.2 * US)
    assert min_slot_time(100.0) < 51.2 * US  # the standard slot has room
    with pytest.raises(ValidationError, match=r"slot_time 2.6 us must exceed jam \+ 2 tau"):
        dcr_bound(rate=20e6, slot_time=2.6e-6)
    assert dcr_bound(rate=20e6, slot_time=2.7e-6) == dcr_bound(rate=20e6)
    with pytest.raises(ValidationError, match="slot_time"):
        dcr_rounds(10, bus_length=1000.0, **REDUCED)  # 1000 m needs 11.6 us


def test_bound_grows_with_stations_and_length() -> None:
    ns = [dcr_bound(n_stations=n) for n in range(1, 30)]
    assert all(b > a for a, b in itertools.pairwise(ns))
    ls = [dcr_bound(bus_length=x) for x in (10.0, 100.0, 500.0, 2500.0)]
    assert all(b > a for a, b in itertools.pairwise(ls))


def test_bound_rejects_bad_values() -> None:
    bad: list[dict[str, Any]] = [
        {"bus_length": -1.0},
        {"propagation_speed": 0.0},
        {"epsilon": -1e-6},
    ]
    for kw in bad:
        with pytest.raises(ValidationError, match="dcr_bound"):
            dcr_bound(**kw)


def test_full_load_rounds_reach_the_bound_less_ifs_and_tau() -> None:
    # at full load with 5-point trajectories every round is the worst case
    d = dcr_rounds(50, trajectory_points=(5, 5), seed=0)
    assert d.max() == pytest.approx(dcr_bound() - 9.6 * US - 0.5 * US, rel=1e-12)


@settings(max_examples=20, deadline=None)
@given(
    n=st.integers(2, 10),
    spread=st.sampled_from([0.0, 2e-6, 30e-6, 300e-6]),
    seed=st.integers(0, 10_000),
)
def test_event_dcr_reduced_never_exceeds_bound(n: int, spread: float, seed: int) -> None:
    rng = np.random.default_rng(seed)
    positions = np.sort(rng.uniform(0.0, 100.0, n))
    k = EventLoop()
    m = EthernetMedium(k, positions, mode="csma_dcr", params=EthernetParams(**REDUCED))
    for s in range(n):
        size = 148 if s == 0 else 51
        f = Frame(s, (s + 1) % n, size, "trajectory" if s == 0 else "position")
        k.schedule(float(rng.uniform(0.0, spread)), m.send, f)
    k.run()
    assert m.stats.count == n
    assert m.stats.max() <= dcr_bound(n_stations=n, **REDUCED)


def test_csma_cd_on_the_same_contention_breaks_the_bound() -> None:
    # the contrast that makes the DCR property meaningful: the same 10 frames
    # sent at once, under binary exponential backoff
    worst = 0.0
    for seed in range(5):
        k = EventLoop()
        m = EthernetMedium(k, np.linspace(0.0, 100.0, 10), mode="csma_cd", seed=seed)
        for s in range(10):
            m.send(Frame(s, (s + 1) % 10, 148 if s == 0 else 51))
        k.run()
        worst = max(worst, m.stats.max())
    assert worst > dcr_bound()


def test_silent_turns_cost_what_they_are_given() -> None:
    # at full load no turn is silent: the option changes nothing
    full = dcr_rounds(200, load=1.0, seed=3)
    assert np.array_equal(full, dcr_rounds(200, load=1.0, seed=3, empty_slot=51.2e-6))
    # partly loaded: each silent station before a frame adds its slot
    free = dcr_rounds(4000, load=0.3, seed=3)
    slotted = dcr_rounds(4000, load=0.3, seed=3, empty_slot=51.2e-6)
    assert free.shape == slotted.shape and np.all(slotted >= free)
    assert slotted.max() > free.max()
    # with the standard slot the 10-station worst case stays under D_max:
    # 7.4 + 128.5 + 8 x 51.2 + 50.9 = 596.4 us
    assert slotted.max() <= dcr_bound()
    with pytest.raises(ValidationError, match="empty_slot"):
        dcr_rounds(10, load=0.5, empty_slot=-1.0)
