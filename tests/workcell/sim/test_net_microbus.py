"""MICROBUS rules (S1.3), status lines and the OR-ed interrupt (S1.4), the
reflex arc's report path (S1.2), and the S1.10 table's shape."""

from __future__ import annotations

import pytest

from multiarm.errors import UsageError
from workcell.sim.comms.devices import (
    DetectorController,
    ForceController,
    GripperController,
    MotorController,
)
from workcell.sim.comms.microbus import BYTE_TIME, COMMAND_TIME, MOVE
from workcell.sim.control.supersigma import (
    ABORT_FORCE,
    ABORT_RAIL,
    BUSY,
    CCU,
    FREE,
    PAPER_TABLE,
    Command,
    Microbus,
    bus_load_table,
    status_lines_needed,
    steps_args,
)
from workcell.sim.events.loop import EventLoop, ProcessGenerator


def irq(bus: Microbus) -> bool:
    """The interrupt line, read afresh (a function, so no narrowing)."""
    return bus.interrupt


def test_status_codes_are_the_papers() -> None:
    assert (FREE, BUSY, ABORT_RAIL, ABORT_FORCE) == ((0, 0), (0, 1), (1, 0), (1, 1))


def test_interrupt_is_the_or_of_every_a_line() -> None:
    k = EventLoop()
    bus = Microbus(k)
    bus.add(MotorController(1, "a", rail=(-10, 10)))
    bus.add(MotorController(2, "b", rail=(-10, 10)))
    c = bus.add(MotorController(3, "c"))
    assert isinstance(c, MotorController)
    raised: list[str] = []
    bus.on_interrupt(lambda ctrl: raised.append(ctrl.name))
    bus.send(Command(3, MOVE, steps_args(20_000)))  # busy: B high, A low
    assert bus.status(3) == BUSY and not irq(bus)
    bus.send(Command(1, MOVE, steps_args(50)), at=k.now + COMMAND_TIME)
    bus.send(Command(2, MOVE, steps_args(-50)), at=k.now + 2 * COMMAND_TIME)
    k.run(until=1.0)
    assert bus.status(1) == ABORT_RAIL and bus.status(2) == ABORT_RAIL
    assert bus.status(3) == BUSY  # still moving: no interrupt from B lines
    assert raised == ["a", "b"]
    assert irq(bus)
    bus.acknowledge(1)
    assert irq(bus)  # b's A line still holds it
    bus.acknowledge(2)
    assert not irq(bus)
    k.run()
    assert bus.status(3) == FREE and not irq(bus)
    assert raised == ["a", "b"] and c.position == 20_000


def test_an_aborted_controller_is_free_and_listens() -> None:
    k = EventLoop()
    bus = Microbus(k)
    m = bus.add(MotorController(1, "x", rail=(-100, 100)))
    assert isinstance(m, MotorController)
    bus.send(Command(1, MOVE, steps_args(500)))
    k.run()
    assert bus.status(1) == ABORT_RAIL and m.free
    assert bus.send(Command(1, MOVE, steps_args(-50)))  # heard: (1, 0) is free
    assert bus.status(1) == BUSY and not bus.interrupt
    k.run()
    assert m.position == 50 and bus.status(1) == FREE


def test_a_busy_controller_misses_the_command_others_hear_theirs() -> None:
    k = EventLoop()
    bus = Microbus(k)
    x = bus.add(MotorController(1, "x"))
    y = bus.add(MotorController(2, "y"))
    assert isinstance(x, MotorController) and isinstance(y, MotorController)
    assert bus.send(Command(1, MOVE, steps_args(2000)))
    assert not bus.send(Command(1, MOVE, steps_args(7)), at=COMMAND_TIME)  # deaf
    assert bus.send(Command(2, MOVE, steps_args(7)), at=2 * COMMAND_TIME)  # free: hears
    k.run()
    assert (x.position, y.position, bus.lost) == (2000, 7, 1)
    assert (x.commands, y.commands) == (1, 1)


def test_answers_only_on_request_with_known_lengths() -> None:
    k = EventLoop()
    bus = Microbus(k)
    bus.add(MotorController(1, "x"))
    bus.add(ForceController(2, "f", force=lambda t: (1.0, -2.0, 3.0)))
    bus.add(DetectorController(3, "d", beam=lambda: True))
    bus.add(GripperController(4, "g", stroke_time=0.01))
    t = 0.0
    for i in range(20):  # a busy program: moves and grips, nothing asked
        bus.send(Command(1, MOVE, steps_args(5)), at=t)
        t = bus.free_at
        k.run(until=t + 0.1)
        t = k.now
        bus.send(Command(4, 0x20, bytes((i % 2,))), at=t)
        k.run(until=t + 0.1)
        t = k.now
    assert bus.bytes_answered == 0 and bus.commands == 40
    lengths = {}
    for addr in (1, 2, 3):
        t0 = k.now
        data = bus.request(addr, 1)
        assert data is not None
        lengths[addr] = len(data)
        # the bus carries the request and then the whole answer; nothing else
        assert bus.free_at == pytest.approx(t0 + COMMAND_TIME + len(data) * BYTE_TIME)
        with pytest.raises(UsageError, match="bus busy"):
            bus.send(Command(1, MOVE, steps_args(1)), at=bus.free_at - 1e-6)
        k.run(until=bus.free_at)
    assert lengths == {1: 2, 2: 2, 3: 1}
    assert bus.bytes_answered == 5
    with pytest.raises(UsageError, match="no answer"):
        bus.request(4)


def test_reflex_arc_stops_first_and_tells_the_ccu_after() -> None:
    k = EventLoop()
    bus = Microbus(k)
    z = bus.add(MotorController(1, "z"))
    assert isinstance(z, MotorController)
    crash = [False]
    f = ForceController(2, "f", force=lambda t: (0.0, 0.0, 90.0 if crash[0] else 0.0), guards=(z,))
    bus.add(f)
    ccu = CCU(k, bus)
    bus.send(Command(1, MOVE, steps_args(20_000)))
    k.run(until=0.3)
    crash[0] = True
    assert f.check(k.now)  # the controller decides alone
    stopped_at = z.position
    assert 0 < stopped_at < 20_000
    assert ccu.aborts == [(0.3, "z", ABORT_FORCE)]  # told, not asked
    k.run()
    assert z.position == stopped_at  # the old move never completes


def test_ccu_never_exceeds_10000_commands_per_second() -> None:
    k = EventLoop()
    bus = Microbus(k)
    for a in range(10):
        bus.add(GripperController(a, f"g{a}", stroke_time=0.0), segment=a // 5)
    bus.check_configuration()
    ccu = CCU(k, bus, statement_time=0.0)

    def box(c: CCU) -> ProcessGenerator:
        for i in range(300):
            yield from c.actuate(i % 10, bool(i % 2))

    rep = ccu.run({"fast": box})
    assert rep.commands == 300 and rep.lost == 0
    assert rep.rate <= 10_000.0 * (1 + 1e-9)
    assert rep.rate > 9_000.0  # the bus, not the program, is the limit here
    assert rep.saturation == pytest.approx(rep.rate / 10_000.0)


def test_status_multiplexing_figures() -> None:
    assert status_lines_needed(80) == (16, 16)  # 16 in + 16 out serve 80
    assert status_lines_needed(256) == (16, 18)  # 2 more out bits serve 256
    assert status_lines_needed(81) == (16, 17)


def test_bus_load_table_has_the_papers_shape() -> None:
    rows = bus_load_table()
    by = {r["program"]: r for r in rows}
    assert list(by) == list(PAPER_TABLE)
    for name, r in by.items():
        arms, _commands, _seconds, _rate, psat = PAPER_TABLE[name]
        assert r["arms"] == arms
        assert r["saturation"] < 0.0025  # far below 1 %
        assert r["rate"] == pytest.approx(r["commands"] / r["seconds"])
        assert r["saturation"] == pytest.approx(r["rate"] / 10_000.0)
        assert r["paper_saturation"] == pytest.approx(psat / 100)
        assert 1 / 3 < r["saturation"] / r["paper_saturation"] < 3, name
        assert r["idle"] >= 0.5, name  # the CCU idles at least half the time
        assert r["lost"] == 0
    # the same ranking as the paper: SCP2B, PRCO, SCP1B, ORD
    ours = sorted(by, key=lambda n: -by[n]["rate"])
    paper = sorted(PAPER_TABLE, key=lambda n: -PAPER_TABLE[n][3])
    assert ours == paper == ["SCP2B", "PRCO", "SCP1B", "ORD"]
    # the two-arm short-move program is the busiest, as in the paper
    assert max(by.values(), key=lambda r: r["rate"])["program"] == "SCP2B"
    assert by["SCP2B"]["rate"] > 1.5 * max(r["rate"] for n, r in by.items() if n != "SCP2B")
