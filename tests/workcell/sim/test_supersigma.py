"""MICROBUS rules (S1.3, S1.4), the CCU (S1.1, S1.9), the demo (S1.8), S1.10."""

from __future__ import annotations

import pytest

from multiarm.errors import UsageError, ValidationError
from workcell.sim.comms.devices import (
    ForceController,
    GripperController,
    MotorController,
)
from workcell.sim.comms.microbus import ACTUATE, COMMAND_TIME, MOVE
from workcell.sim.control.supersigma import (
    ABORT_FORCE,
    ABORT_RAIL,
    BUSY,
    CCU,
    FREE,
    Command,
    Controller,
    Microbus,
    Piece,
    StepProfile,
    bus_load_table,
    chess_sort,
    move_time,
    status_lines_needed,
    steps_args,
)
from workcell.sim.events.loop import EventLoop, ProcessGenerator


def _bus(n: int = 2) -> tuple[EventLoop, Microbus, list[MotorController]]:
    k = EventLoop()
    bus = Microbus(k)
    motors = [MotorController(i + 1, f"m{i}") for i in range(n)]
    for m in motors:
        bus.add(m)
    return k, bus, motors


def test_command_is_at_most_five_bytes_with_address_first() -> None:
    c = Command(200, MOVE, steps_args(-5))
    assert c.encode()[0] == 200 and len(c.encode()) == 4
    assert len(Command(1, 0, b"abc").encode()) == 5
    with pytest.raises(ValidationError, match="at most 5"):
        Command(1, 0, b"abcd")
    with pytest.raises(ValidationError, match="address 256"):
        Command(256, 0)


def test_busy_controller_is_deaf_and_the_command_is_lost() -> None:
    k, bus, (m, _) = _bus()
    assert bus.send(Command(1, MOVE, steps_args(1000)))
    assert bus.status(1) == BUSY
    t = k.now + COMMAND_TIME
    assert not bus.send(Command(1, MOVE, steps_args(50)), at=t)
    assert bus.lost == 1
    k.run()
    assert m.position == 1000  # the second move was never heard
    assert bus.status(1) == FREE


def test_one_command_reaches_one_controller() -> None:
    k, bus, (m0, m1) = _bus()
    bus.send(Command(2, MOVE, steps_args(300)))
    k.run()
    assert (m0.position, m1.position) == (0, 300)
    assert (m0.commands, m1.commands) == (0, 1)
    with pytest.raises(ValidationError, match="no controller at address 9"):
        bus.send(Command(9, MOVE, steps_args(1)))


def test_rate_cap_10000_commands_per_second() -> None:
    k, bus, _ = _bus()
    bus.send(Command(1, MOVE, steps_args(10)))
    with pytest.raises(UsageError, match="10000 commands/s"):
        bus.send(Command(2, MOVE, steps_args(10)), at=k.now + 0.5 * COMMAND_TIME)
    assert bus.send(Command(2, MOVE, steps_args(10)), at=k.now + COMMAND_TIME)


def test_answers_only_on_request_and_the_bus_waits_for_them() -> None:
    k, bus, (_m, _) = _bus()
    bus.send(Command(1, MOVE, steps_args(-1234)))
    k.run()
    assert bus.bytes_answered == 0  # nothing flows unasked
    t = k.now
    data = bus.request(1)
    assert data is not None and int.from_bytes(data, "big", signed=True) == -1234
    assert bus.bytes_answered == 2
    assert bus.free_at == pytest.approx(t + COMMAND_TIME + 2 * COMMAND_TIME / 5)
    with pytest.raises(UsageError, match="busy"):
        bus.request(2)
    # a busy controller does not answer
    bus.send(Command(2, MOVE, steps_args(5000)), at=bus.free_at)
    k.run(until=bus.free_at + 0.01)
    assert bus.request(2) is None


def test_status_codes_and_or_ed_interrupt() -> None:
    k = EventLoop()
    bus = Microbus(k)
    rail = bus.add(MotorController(1, "x", rail=(-100, 100)))
    z = bus.add(MotorController(2, "z"))
    assert isinstance(rail, MotorController) and isinstance(z, MotorController)
    pushes = [0.0]
    f = ForceController(3, "f", force=lambda t: (0.0, 0.0, pushes[0]), guards=(z,))
    bus.add(f)
    seen: list[tuple[str, tuple[int, int]]] = []
    bus.on_interrupt(lambda c: seen.append((c.name, c.status_ab)))

    def irq() -> bool:
        return bus.interrupt

    assert not irq()
    bus.send(Command(1, MOVE, steps_args(500)))  # runs into the rail switch
    k.run()
    assert bus.status(1) == ABORT_RAIL and rail.position == 100
    assert irq()
    bus.acknowledge(1)
    assert not irq()
    bus.send(Command(2, MOVE, steps_args(4000)))
    k.run(until=k.now + 0.1)
    pushes[0] = 50.0  # crash: above the 20 N threshold
    assert f.check(k.now)
    assert bus.status(2) == ABORT_FORCE and 0 < z.position < 4000
    k.run()
    assert bus.status(2) == ABORT_FORCE  # the old move's end does not clear it
    assert seen == [("x", ABORT_RAIL), ("z", ABORT_FORCE)]


def test_segments_and_line_count() -> None:
    k = EventLoop()
    bus = Microbus(k)
    for a in range(11):
        bus.add(GripperController(a, f"g{a}"), segment=0)
    with pytest.raises(ValidationError, match="segment 0 has 11 controllers"):
        bus.check_configuration()
    with pytest.raises(ValidationError, match="address 3 used"):
        bus.add(GripperController(3, "again"))
    assert status_lines_needed(80) == (16, 16)
    assert status_lines_needed(256) == (16, 18)
    assert status_lines_needed(81)[1] > 16
    with pytest.raises(ValidationError):
        status_lines_needed(257)


def test_step_profile_shapes() -> None:
    p = StepProfile()
    assert move_time(p.short, p) == pytest.approx(p.short / p.v_low)
    # triangle below v_max, trapezoid above: time grows linearly at v_max
    long1, long2 = move_time(20_000, p), move_time(30_000, p)
    assert long2 - long1 == pytest.approx(10_000 / p.v_max)
    assert move_time(-500, p) == move_time(500, p)


def test_unknown_opcode_is_refused() -> None:
    _k, bus, _ = _bus()
    with pytest.raises(ValidationError, match="unknown op-code"):
        bus.send(Command(1, ACTUATE, b"\x01"))
    assert isinstance(Controller(5, "c"), Controller)


def test_ccu_checks_status_first_and_never_loses_commands() -> None:
    k, bus, (m0, m1) = _bus()
    ccu = CCU(k, bus)

    def box(c: CCU) -> ProcessGenerator:
        for _ in range(5):
            yield from c.move(1, 200)  # each waits for the previous to end
        yield from c.move(2, 10)

    rep = ccu.run({"a": box})
    assert bus.lost == 0 and m0.position == 1000 and m1.position == 10
    assert rep.commands == 6
    assert rep.seconds >= 5 * move_time(200)


def test_flags_synchronise_boxes() -> None:
    k, bus, (_m0, _m1) = _bus()
    ccu = CCU(k, bus)
    order: list[str] = []

    def first(c: CCU) -> ProcessGenerator:
        yield from c.move(1, 3000)
        yield from c.wait(1)
        order.append("first done")
        yield from c.set_flag("go")

    def second(c: CCU) -> ProcessGenerator:
        yield from c.wait_flag("go")
        order.append("second starts")
        yield from c.move(2, 5)

    ccu.run({"first": first, "second": second})
    assert order == ["first done", "second starts"]


def test_chess_demo_finds_measures_and_sorts() -> None:
    pieces = [Piece(60.0, 0.0, 35.0), Piece(180.0, 0.0, 55.0), Piece(320.0, 0.0, 80.0)]
    found, rep = chess_sort(pieces)
    assert [round(x) for x, _, _ in found] == [60, 180, 320]
    assert [h for _, h, _ in found] == pytest.approx([34.0, 54.0, 78.0], abs=2.0)
    assert [b for _, _, b in found] == [0, 1, 2]
    assert rep.lost == 0


def test_bus_load_table_shape() -> None:
    rows = bus_load_table()
    assert [r["program"] for r in rows] == ["ORD", "SCP1B", "SCP2B", "PRCO"]
    assert [r["arms"] for r in rows] == [1, 1, 2, 2]
    assert all(0 < r["saturation"] < 0.01 for r in rows)
    assert max(rows, key=lambda r: r["rate"])["program"] == "SCP2B"
    assert all(r["idle"] >= 0.5 and r["lost"] == 0 for r in rows)
    assert all(r["rate"] == pytest.approx(r["commands"] / r["seconds"]) for r in rows)
