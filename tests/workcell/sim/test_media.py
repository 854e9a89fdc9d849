"""Media: ideal, fixed latency, serial star and bus, Multibus II (S2.8)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from multiarm.errors import ValidationError
from workcell.sim.comms import MultibusII, SerialBus, SerialStar, unsolicited_count
from workcell.sim.comms.medium import (
    BROADCAST,
    FixedLatencyMedium,
    Frame,
    IdealMedium,
    Medium,
    trajectory_bytes,
)
from workcell.sim.events.loop import EventLoop


def _collect(m: Medium, stations: range) -> list[tuple[int, int, str, float]]:
    got: list[tuple[int, int, str, float]] = []
    for s in stations:
        m.attach(s, _recorder(got, s))
    return got


def _recorder(got: list[tuple[int, int, str, float]], s: int) -> Callable[[Frame, float], None]:
    def rx(f: Frame, t: float) -> None:
        got.append((s, f.src, f.kind, t))

    return rx


def test_ideal_and_fixed_latency() -> None:
    k = EventLoop()
    ideal = IdealMedium(k, 3)
    fixed = FixedLatencyMedium(k, 3, latency=0.25)
    assert isinstance(ideal, Medium) and isinstance(fixed, Medium)
    g1 = _collect(ideal, range(3))
    g2 = _collect(fixed, range(3))
    k.schedule(1.0, lambda: ideal.send(Frame(0, 2, 10, "sleep")))
    k.schedule(1.0, lambda: fixed.send(Frame(1, BROADCAST, 28, "alarm")))
    k.run()
    assert g1 == [(2, 0, "sleep", 1.0)]
    assert g2 == [(0, 1, "alarm", 1.25), (2, 1, "alarm", 1.25)]
    assert fixed.stats.count == 2 and fixed.stats.max() == pytest.approx(0.25)
    assert ideal.stats.max() == 0.0


def test_frame_and_station_validation() -> None:
    with pytest.raises(ValidationError, match="size"):
        Frame(0, 1, 0)
    with pytest.raises(ValidationError, match="both 1"):
        Frame(1, 1, 10)
    k = EventLoop()
    m = IdealMedium(k, 2)
    with pytest.raises(ValidationError, match="station 5"):
        m.send(Frame(0, 5, 10))
    with pytest.raises(ValidationError, match=">= 2 stations"):
        IdealMedium(k, 1)
    with pytest.raises(ValidationError, match="latency"):
        FixedLatencyMedium(k, 2, latency=-1.0)
    assert trajectory_bytes(5) == 148


@pytest.mark.parametrize("rate", [9600.0, 19200.0, 115200.0])
def test_serial_line_time_is_ten_bits_per_byte(rate: float) -> None:
    k = EventLoop()
    m = SerialStar(k, 3, rate=rate, header_bytes=0)
    m.send(Frame(1, 0, 51, "position"))
    k.run()
    assert m.stats.max() == pytest.approx(51 * 10 / rate)
    k2 = EventLoop()
    m2 = SerialStar(k2, 3, rate=rate, header_bytes=4)
    m2.send(Frame(1, 0, 51, "position"))
    k2.run()
    assert m2.stats.max() == pytest.approx(55 * 10 / rate)


def test_serial_star_fifo_per_line_and_full_duplex() -> None:
    k = EventLoop()
    m = SerialStar(k, 3, rate=10_000.0, header_bytes=0)
    got = _collect(m, range(3))
    m.send(Frame(1, 0, 100, "a"))  # 0.1 s on line 1 up
    m.send(Frame(1, 0, 100, "b"))  # queues behind a
    m.send(Frame(2, 0, 100, "c"))  # own line: no wait
    m.send(Frame(0, 1, 100, "d"))  # line 1 down: full duplex, no wait
    k.run()
    times = {kind: t for _, _, kind, t in got}
    assert times == pytest.approx({"a": 0.1, "b": 0.2, "c": 0.1, "d": 0.1})


def test_serial_star_relays_between_robots() -> None:
    k = EventLoop()
    m = SerialStar(k, 3, rate=10_000.0, header_bytes=0)
    got = _collect(m, range(3))
    m.send(Frame(1, 2, 50, "x"))
    k.run()
    assert [g[:3] for g in got] == [(2, 1, "x")]
    assert got[0][3] == pytest.approx(0.1)  # two hops of 0.05 s


def test_serial_bus_is_shared() -> None:
    k = EventLoop()
    m = SerialBus(k, 4, rate=10_000.0, header_bytes=0)
    got = _collect(m, range(4))
    m.send(Frame(1, 0, 50, "a"))
    m.send(Frame(2, 3, 50, "b"))
    k.run()
    assert [(s, kind, round(t, 6)) for s, _, kind, t in got] == [(0, "a", 0.05), (3, "b", 0.1)]


def test_multibus_splits_into_20_byte_unsolicited_messages() -> None:
    assert [unsolicited_count(n) for n in (1, 20, 21, 51, 60, 61)] == [1, 1, 2, 3, 3, 4]
    k = EventLoop()
    m = MultibusII(k, 3, arbitration=0.0, mpc_latency=0.0)
    m.send(Frame(1, 0, 51, "position"))
    k.run()
    assert m.transfers == 3
    assert m.stats.max() == pytest.approx(3 * 32 / 40e6)
    m.send(Frame(2, 0, 20, "zone_request"))
    k.run()
    assert m.transfers == 4


def test_multibus_trajectory_is_solicited_and_alarm_broadcast() -> None:
    k = EventLoop()
    m = MultibusII(k, 4)
    got = _collect(m, range(4))
    m.send(Frame(0, 1, 148, "trajectory"))
    k.run()
    assert m.transfers == 2 + 5  # request + grant + ceil(148 / 32) data packets
    m.send(Frame(0, BROADCAST, 10, "alarm"))
    k.run()
    assert m.transfers == 8  # one unsolicited broadcast reaches all
    assert sorted(s for s, _, kind, _ in got if kind == "alarm") == [1, 2, 3]


def test_multibus_queues_on_the_shared_bus() -> None:
    k = EventLoop()
    m = MultibusII(k, 3, arbitration=0.0, mpc_latency=0.0)
    m.send(Frame(1, 0, 20, "a"))
    m.send(Frame(2, 0, 20, "b"))
    k.run()
    assert list(m.stats.delays()) == pytest.approx([32 / 40e6, 64 / 40e6])
