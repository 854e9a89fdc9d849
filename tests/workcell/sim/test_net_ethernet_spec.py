"""Ethernet CSMA/CD against its specification (IEEE 802.3 at 10 Mb/s, S2.8):
slot 51.2 us, IFS 9.6 us, 32-bit jam, backoff r in [0, 2^min(n, 10) - 1],
16 attempts then drop; 1-persistent deferral; the delay tail against the
CSMA/DCR bound as load grows."""

from __future__ import annotations

import numpy as np
import pytest

from workcell.sim.comms import EthernetMedium, EthernetParams, dcr_bound, ethernet_rounds
from workcell.sim.comms.medium import Frame
from workcell.sim.events.loop import EventLoop

US = 1e-6


class ScriptedRng:
    """Backoff draws from a script; records (low, high) of every draw."""

    def __init__(self, values: list[int] | None = None) -> None:
        self.values = list(values) if values else []
        self.draws: list[tuple[int, int]] = []

    def integers(self, low: int, high: int) -> int:
        self.draws.append((low, high))
        return self.values.pop(0) if self.values else 0


def test_standard_parameters() -> None:
    p = EthernetParams()
    assert p.rate == 10e6
    assert p.slot_time == pytest.approx(512 / 10e6) == pytest.approx(51.2 * US)
    assert p.ifs == pytest.approx(96 / 10e6) == pytest.approx(9.6 * US)
    assert p.jam_bits == 32
    assert p.max_attempts == 16 and p.backoff_limit == 10


def _pair(params: EthernetParams, script: list[int], size: int = 28) -> list[float]:
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 100.0], mode="csma_cd", params=params)
    m._rng = ScriptedRng(script)  # type: ignore[assignment]
    m.send(Frame(0, 1, size))
    m.send(Frame(1, 0, size))
    k.run()
    assert m.collisions == 1
    return sorted(float(d) for d in m.stats.delays())


@pytest.mark.parametrize(
    ("params", "jam", "eps", "slot", "ifs"),
    [
        (EthernetParams(), 3.2, 0.0, 51.2, 9.6),
        (EthernetParams(detect_delay=1e-6), 3.2, 1.0, 51.2, 9.6),
        (EthernetParams(jam_bits=64), 6.4, 0.0, 51.2, 9.6),
        (EthernetParams(slot_time=100e-6), 3.2, 0.0, 100.0, 9.6),
        (EthernetParams(ifs=3.2e-6), 3.2, 0.0, 51.2, 3.2),
    ],
)
def test_collision_jam_ifs_and_slot_timing(
    params: EthernetParams, jam: float, eps: float, slot: float, ifs: float
) -> None:
    # two stations 100 m apart (d = 0.5 us) send 28 bytes (22.4 us) at t = 0;
    # they collide, each stops after d + eps + jam; the one drawing r = 0
    # defers until the other's jam has passed (+ d) and one IFS; the one
    # drawing r = 1 retries one slot after its own jam
    d, x = 0.5, 22.4
    stop = d + eps + jam
    first = stop + d + ifs + x + d
    second = stop + slot + x + d
    assert _pair(params, [0, 1]) == pytest.approx([first * US, second * US], abs=1e-12)


def test_deferral_waits_for_carrier_end_plus_ifs() -> None:
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 100.0], mode="csma_cd", seed=0)
    m.send(Frame(0, 1, 148))
    k.schedule(10 * US, m.send, Frame(1, 0, 51))  # hears the carrier since 0.5 us
    k.run()
    assert m.collisions == 0
    d0, d1 = (float(v) for v in m.stats.delays())
    assert d0 == pytest.approx((118.4 + 0.5) * US)
    # the carrier ends at station 1 at 118.9 us; + IFS = 128.5; + 40.8 + 0.5
    assert d1 == pytest.approx((128.5 + 40.8 + 0.5 - 10.0) * US)


def test_backoff_window_doubles_up_to_1024_then_sixteen_attempts_drop() -> None:
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 100.0], mode="csma_cd")
    rng = ScriptedRng()  # always r = 0: the two collide again every time
    m._rng = rng  # type: ignore[assignment]
    dropped: list[tuple[int, str]] = []
    m.on_drop(lambda f, why: dropped.append((f.src, why)))
    m.send(Frame(0, 1, 64))
    m.send(Frame(1, 0, 64))
    k.run()
    # after the n-th collision the draw is in [0, 2^min(n, 10)); 15 backoffs
    # per frame, the 16th collision drops it
    per_station = [2 ** min(n, 10) for n in range(1, 16)]
    assert sorted(h for _, h in rng.draws) == sorted(per_station * 2)
    assert all(lo == 0 for lo, _ in rng.draws)
    assert sorted(dropped) == [
        (0, "excessive collisions (16 attempts)"),
        (1, "excessive collisions (16 attempts)"),
    ]
    assert m.stats.count == 0 and m.stats.drops == 2


def test_attempt_limit_is_a_parameter() -> None:
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 100.0], params=EthernetParams(max_attempts=3))
    rng = ScriptedRng()
    m._rng = rng  # type: ignore[assignment]
    m.send(Frame(0, 1, 64))
    m.send(Frame(1, 0, 64))
    k.run()
    assert len(rng.draws) == 4 and m.stats.drops == 2


def test_a_station_after_a_success_starts_afresh() -> None:
    # the attempt counter is per frame: a frame sent after a collided one
    # has its backoff window start again at [0, 1]
    k = EventLoop()
    m = EthernetMedium(k, [0.0, 100.0], mode="csma_cd")
    rng = ScriptedRng([0, 1, 0, 1])
    m._rng = rng  # type: ignore[assignment]
    m.send(Frame(0, 1, 64))
    m.send(Frame(1, 0, 64))
    k.run()
    assert [h for _, h in rng.draws] == [2, 2]
    rng.draws.clear()
    m.send(Frame(0, 1, 64))
    m.send(Frame(1, 0, 64))
    k.run()
    assert [h for _, h in rng.draws] == [2, 2]


def test_backoff_draws_are_uniform_over_the_window() -> None:
    # the real generator: after collision n, r spans the whole [0, 2^n - 1]
    k = EventLoop()
    n = 30
    m = EthernetMedium(k, np.linspace(0.0, 100.0, n), mode="csma_cd", seed=4)
    seen: dict[int, list[int]] = {}
    real = m._rng

    class Spy:
        def integers(self, low: int, high: int) -> int:
            v = int(real.integers(low, high))
            seen.setdefault(high, []).append(v)
            return v

    m._rng = Spy()  # type: ignore[assignment]
    for s in range(n):
        m.send(Frame(s, (s + 1) % n, 64))
    k.run()
    assert m.stats.count == n
    for high in (2, 4, 8):
        vals = seen[high]
        assert min(vals) == 0 and max(vals) == high - 1
        assert len(set(vals)) == high  # every value of the window drawn


def test_ethernet_tail_exceeds_the_dcr_bound_as_load_grows() -> None:
    bound = dcr_bound()
    p99 = []
    for load in (0.1, 0.5, 1.0):
        d = ethernet_rounds(3000, n_stations=10, load=load, seed=7)
        p99.append(float(np.nanpercentile(d, 99)))
    assert p99[0] < p99[1] < p99[2]
    assert p99[2] > bound  # at full load 1 % of frames wait longer than D_max
    full = ethernet_rounds(3000, n_stations=10, load=1.0, seed=7)
    assert float(np.mean(full > bound)) > 0.2
