"""Media by name: workcell.sim.comms.make_medium and MEDIA (S2.8, S2.9)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from multiarm.errors import UsageError
from workcell.sim.comms import (
    MEDIA,
    MEDIUM_PARAMS,
    EthernetMedium,
    MultibusII,
    SerialBus,
    SerialStar,
    make_medium,
)
from workcell.sim.comms.medium import BROADCAST, FixedLatencyMedium, Frame, IdealMedium, Medium
from workcell.sim.comms.serial import line_time
from workcell.sim.events.loop import EventLoop

EXPECTED = {
    "ideal": IdealMedium,
    "fixed": FixedLatencyMedium,
    "csma-dcr": EthernetMedium,
    "ethernet": EthernetMedium,
    "multibus2": MultibusII,
    "serial-star": SerialStar,
    "serial-bus": SerialBus,
}


def test_media_names_are_the_contract() -> None:
    assert MEDIA == (
        "ideal",
        "fixed",
        "csma-dcr",
        "ethernet",
        "multibus2",
        "serial-star",
        "serial-bus",
    )
    assert set(MEDIUM_PARAMS) == set(MEDIA)


def _recorder(log: list[tuple[int, int, str]], station: int) -> Callable[[Frame, float], None]:
    def rx(frame: Frame, time: float) -> None:
        log.append((frame.src, station, frame.kind))

    return rx


@pytest.mark.parametrize("name", MEDIA)
def test_every_medium_delivers_both_ways(name: str) -> None:
    k = EventLoop()
    m = make_medium(name, k, 4, seed=1)
    assert isinstance(m, EXPECTED[name])
    assert isinstance(m, Medium)
    assert m.n_stations == 4
    got: list[tuple[int, int, str]] = []
    for s in range(4):
        m.attach(s, _recorder(got, s))
    m.send(Frame(src=0, dst=2, size=148, kind="trajectory"))
    m.send(Frame(src=3, dst=0, size=51, kind="position"))
    k.run()
    assert sorted(got) == [(0, 2, "trajectory"), (3, 0, "position")]
    assert m.stats.count == 2
    if name == "ideal":
        assert m.stats.max() == 0.0
    else:
        assert m.stats.max() > 0.0


@pytest.mark.parametrize("name", MEDIA)
def test_broadcast_from_the_coordinator_reaches_every_arm(name: str) -> None:
    k = EventLoop()
    m = make_medium(name, k, [0, 1, 2, 3])
    seen: list[tuple[int, int, str]] = []
    for s in range(4):
        m.attach(s, _recorder(seen, s))
    m.send(Frame(src=0, dst=BROADCAST, size=28, kind="alarm"))
    k.run()
    assert sorted(station for _, station, _ in seen) == [1, 2, 3]


def test_unknown_name_lists_the_choices() -> None:
    with pytest.raises(UsageError, match=r"unknown medium 'token-bus'; choose one of: ideal, "):
        make_medium("token-bus", EventLoop(), 3)
    with pytest.raises(UsageError, match="serial-star, serial-bus"):
        make_medium("", EventLoop(), 3)


def test_names_are_normalised() -> None:
    m = make_medium("CSMA_DCR", EventLoop(), 3)
    assert isinstance(m, EthernetMedium) and m.mode == "csma_dcr"
    m2 = make_medium("Serial_Star", EventLoop(), 3)
    assert isinstance(m2, SerialStar)


def test_unknown_parameter_names_the_accepted_ones() -> None:
    with pytest.raises(UsageError, match=r"'serial-bus': unknown parameter 'baud'; accepted: rate"):
        make_medium("serial-bus", EventLoop(), 3, baud=9600)
    with pytest.raises(UsageError, match=r"'ideal': unknown parameter 'latency'"):
        make_medium("ideal", EventLoop(), 3, latency=1.0)
    with pytest.raises(UsageError, match="max_attempts"):  # CSMA/DCR never gives up
        make_medium("csma-dcr", EventLoop(), 3, max_attempts=4)


@pytest.mark.parametrize(
    ("name", "params", "match"),
    [
        ("fixed", {"latency": -1.0}, "latency must be >= 0"),
        ("ethernet", {"rate": 0.0}, "rate must be > 0"),
        ("csma-dcr", {"bus_length": -5.0}, "bus_length must be > 0"),
        ("csma-dcr", {"positions": [0.0, 1.0]}, "2 given for 3 stations"),
        ("csma-dcr", {"positions": [0.0, 1.0, 2.0], "bus_length": 2.0}, "not both"),
        ("ethernet", {"order": [0, 0, 1]}, "not a permutation"),
        ("multibus2", {"bandwidth": 0.0}, "bandwidth"),
        ("serial-star", {"hub": 7}, "station 7 not in 0..2"),
        ("serial-bus", {"header_bytes": -1}, "header_bytes"),
        ("fixed", {"latency": "fast"}, "fixed"),
    ],
)
def test_bad_values_are_usage_errors(name: str, params: dict[str, object], match: str) -> None:
    with pytest.raises(UsageError, match=match):
        make_medium(name, EventLoop(), 3, **params)


def test_bad_station_lists() -> None:
    with pytest.raises(UsageError, match=r"0\.\.n-1"):
        make_medium("ethernet", EventLoop(), [1, 2, 3])
    with pytest.raises(UsageError, match=">= 2 stations"):
        make_medium("serial-bus", EventLoop(), 1)


def test_parameters_reach_the_medium() -> None:
    k = EventLoop()
    m = make_medium("serial-bus", k, 3, rate=19200.0, header_bytes=0)
    m.send(Frame(src=1, dst=0, size=51, kind="position"))
    k.run()
    assert m.stats.max() == pytest.approx(line_time(51, 19200.0, 0))
    e = make_medium("csma-dcr", EventLoop(), 5, bus_length=400.0, ifs=3.2e-6, rate=20e6)
    assert isinstance(e, EthernetMedium)
    assert e.tau == pytest.approx(400.0 / 2e8)
    assert e.params.ifs == 3.2e-6 and e.params.rate == 20e6
    assert e.positions[0] == 0.0  # the coordinator at one end
    mb = make_medium("multibus2", EventLoop(), 3, unsolicited_payload=10)
    assert isinstance(mb, MultibusII) and mb.payload == 10


def test_chain_order_defaults() -> None:
    dcr = make_medium("csma-dcr", EventLoop(), 3)
    cd = make_medium("ethernet", EventLoop(), 3)
    assert isinstance(dcr, EthernetMedium) and isinstance(cd, EthernetMedium)
    assert dcr.chains[0].by_priority and not cd.chains[0].by_priority
    cd2 = make_medium("ethernet", EventLoop(), 3, priority_chain=True)
    assert isinstance(cd2, EthernetMedium) and cd2.chains[0].by_priority


def test_serial_star_hub_is_station_zero() -> None:
    k = EventLoop()
    m = make_medium("serial-star", k, 3, header_bytes=0)
    m.send(Frame(src=1, dst=2, size=50, kind="position"))  # relayed by the coordinator
    k.run()
    assert m.stats.max() == pytest.approx(2 * line_time(50, 9600.0, 0))


def _ethernet_delays(seed: int) -> list[float]:
    k = EventLoop()
    m = make_medium("ethernet", k, 6, seed=seed)
    for s in range(1, 6):
        m.send(Frame(src=s, dst=0, size=51, kind="position"))
    k.run()
    return [float(d) for d in m.stats.delays()]


def test_ethernet_seed_replays() -> None:
    assert _ethernet_delays(3) == _ethernet_delays(3)
    assert len(_ethernet_delays(3)) == 5
