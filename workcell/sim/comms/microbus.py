"""MICROBUS and the device controllers of SUPERSIGMA (S1.1-S1.5, S1.7, S1.8).

The bus rules (S1.3), each enforced here:

* a command is at most 5 bytes, byte 1 the address of its one target
  (0..255, so at most 256 controllers) -- :class:`Command`;
* at most 10 controllers per bus segment before a regenerator --
  :meth:`Microbus.check_configuration`;
* only *free* controllers listen: a command sent to a busy controller is
  lost (counted in :attr:`Microbus.lost`), so the CCU must check the status
  lines first;
* at most 10,000 commands/s: a command holds the bus for 100 us;
  sending earlier raises :class:`~multiarm.errors.UsageError`;
* answers flow only on request ("speak when requested"): :meth:`Microbus.request`
  sends a request command and the bus stays busy until the whole answer
  (whose length the CCU knows: 2 bytes for a motor's 16-bit position) has
  arrived, at 20 us per byte (5 bytes per 100 us).

Status lines (S1.4): two per controller, (A, B) = (0, 0) free, (0, 1) busy,
(1, 0) free but last command aborted at a rail limit, (1, 1) free but aborted
on excessive force. They are read as flags (:meth:`Microbus.status`); all A
lines are OR-ed into one CCU interrupt (:attr:`Microbus.interrupt`,
callbacks via :meth:`Microbus.on_interrupt`). The reflex arc (S1.2): on a
rail switch or excessive force the controller stops its motor itself
(steepest allowed deceleration) and only then raises A: the CCU is told,
not asked.

Examples
--------
>>> from workcell.sim.events.loop import EventLoop
>>> from workcell.sim.comms.devices import MotorController
>>> k = EventLoop()
>>> bus = Microbus(k)
>>> m = bus.add(MotorController(1, "x"))
>>> bus.send(Command(1, MOVE, steps_args(1000)))
True
>>> bus.status(1)
(0, 1)
>>> bus.send(Command(1, MOVE, steps_args(10)), at=k.now + 1e-4)  # busy: deaf
False
>>> k.run()
>>> bus.status(1), m.position
((0, 0), 1000)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

from multiarm.errors import UsageError, ValidationError
from workcell.sim.events.loop import EventLoop

__all__ = [
    "ABORT_FORCE",
    "ABORT_RAIL",
    "ACTUATE",
    "BUSY",
    "BYTE_TIME",
    "COMMAND_TIME",
    "FREE",
    "MOVE",
    "READ",
    "SET_THRESHOLD",
    "Command",
    "Controller",
    "Microbus",
    "StepProfile",
    "move_time",
    "status_lines_needed",
    "steps_args",
]

_C = TypeVar("_C", bound="Controller")

FREE = (0, 0)
BUSY = (0, 1)
ABORT_RAIL = (1, 0)
ABORT_FORCE = (1, 1)

MOVE = 0x10
"""Op-code: move a motor ``steps`` (signed 16-bit) with the controller's profile."""
ACTUATE = 0x20
"""Op-code: switch an actuator (gripper close/open, lamp on/off): one arg byte."""
READ = 0x30
"""Op-code: request an answer (position, force on an axis, detector state)."""
SET_THRESHOLD = 0x40
"""Op-code: set a force threshold (axis byte + 8-bit threshold in newtons)."""

COMMAND_TIME = 1e-4
"""Seconds a command holds the bus (10,000 commands/s)."""
BYTE_TIME = COMMAND_TIME / 5
"""Seconds per answer byte on the bus."""


def steps_args(steps: int) -> bytes:
    """Encode a signed step count as two bytes (big-endian, two's complement).

    Parameters
    ----------
    steps : int
        -32768..32767.

    Returns
    -------
    bytes
        Two bytes.

    Raises
    ------
    ValidationError
        Outside the 16-bit range.

    Examples
    --------
    >>> steps_args(-2).hex()
    'fffe'
    """
    if not -(2**15) <= steps < 2**15:
        raise ValidationError(f"steps_args: {steps} steps do not fit 16 bits")
    return steps.to_bytes(2, "big", signed=True)


@dataclass(frozen=True, slots=True)
class Command:
    """One MICROBUS command: address byte + op-code byte + up to 3 argument bytes.

    Parameters
    ----------
    address : int
        Target controller, 0..255 (byte 1).
    opcode : int
        0..255 (byte 2).
    args : bytes, optional
        At most 3 bytes.

    Raises
    ------
    ValidationError
        For an address or op-code outside a byte or more than 5 bytes in all.

    Examples
    --------
    >>> Command(7, MOVE, steps_args(400)).encode().hex()
    '07100190'
    """

    address: int
    opcode: int
    args: bytes = b""

    def __post_init__(self) -> None:
        if not 0 <= self.address <= 255:
            raise ValidationError(f"Command: address {self.address} not in 0..255 (one byte)")
        if not 0 <= self.opcode <= 255:
            raise ValidationError(f"Command: op-code {self.opcode} not in 0..255")
        if 2 + len(self.args) > 5:
            raise ValidationError(
                f"Command to {self.address}: {2 + len(self.args)} bytes, a command is at most 5"
            )

    def encode(self) -> bytes:
        """The bytes on the bus, address first.

        Returns
        -------
        bytes
            2..5 bytes.
        """
        return bytes((self.address, self.opcode)) + self.args


@dataclass(frozen=True, slots=True)
class StepProfile:
    """The S1.5 stepper controller's speed profile (units: steps, seconds).

    Parameters
    ----------
    v_low : float
        Constant speed of very short moves and start speed of profiles, steps/s.
    v_max : float
        Top speed, steps/s (15,000 = about 560 mm/s at 0.0375 mm/step).
    accel : float
        Acceleration, steps/s^2.
    short : int
        Moves of at most this many steps run at ``v_low``.
    mm_per_step : float
        Arm travel per step, millimetres.
    """

    v_low: float = 500.0
    v_max: float = 15_000.0
    accel: float = 50_000.0
    short: int = 20
    mm_per_step: float = 0.0375


def move_time(steps: int, profile: StepProfile | None = None) -> float:
    """Duration of a move of ``steps`` (S1.5): constant low speed when very
    short, else a triangle (accelerate to a peak, decelerate), or a trapezoid
    when the peak would pass ``v_max``. Closed form; the one function to swap
    for a finer stepper model.

    Parameters
    ----------
    steps : int
        Signed step count (the sign is the direction).
    profile : StepProfile, optional
        Speed profile.

    Returns
    -------
    float
        Seconds.

    Examples
    --------
    >>> move_time(10)          # short: 10 / 500
    0.02
    >>> round(move_time(1000), 4)   # triangle: peak sqrt(500^2 + 5e7) = 7089
    0.2635
    >>> round(move_time(20000), 3)  # trapezoid
    1.614
    """
    p = profile if profile is not None else StepProfile()
    n = abs(steps)
    if n == 0:
        return 0.0
    if n <= p.short:
        return n / p.v_low
    peak = math.sqrt(p.v_low**2 + p.accel * n)
    if peak <= p.v_max:
        return 2 * (peak - p.v_low) / p.accel
    ramp = (p.v_max**2 - p.v_low**2) / (2 * p.accel)
    return 2 * (p.v_max - p.v_low) / p.accel + (n - 2 * ramp) / p.v_max


def status_lines_needed(
    n_controllers: int, status_per_read: int = 5, bus_out_bits: int = 12
) -> tuple[int, int]:
    """CCU input and output bits needed to read the status lines of
    ``n_controllers`` through a multiplexer (S1.4).

    Model (an assumption that reproduces both of the paper's figures): one
    16-bit input word carries the (A, B) lines of ``status_per_read`` = 5
    controllers (10 bits; the other 6 carry the bus handshake and the OR-ed
    interrupt); the word is chosen by a binary group address on the output
    bits, next to ``bus_out_bits`` = 12 bus bits (8 data + 4 control).

    Parameters
    ----------
    n_controllers : int
        1..256.
    status_per_read : int, optional
        Controllers per input word.
    bus_out_bits : int, optional
        Output bits used by the bus itself.

    Returns
    -------
    (int, int)
        (input bits, output bits).

    Raises
    ------
    ValidationError
        Outside 1..256.

    Examples
    --------
    >>> status_lines_needed(80), status_lines_needed(256)
    ((16, 16), (16, 18))
    """
    if not 1 <= n_controllers <= 256:
        raise ValidationError(f"status_lines_needed: {n_controllers} controllers not in 1..256")
    groups = -(-n_controllers // status_per_read)
    select = max(1, math.ceil(math.log2(groups))) if groups > 1 else 0
    return 16, bus_out_bits + select


class Controller:
    """A device controller ("ganglion", S1.1) on the MICROBUS.

    Parameters
    ----------
    address : int
        0..255.
    name : str
        For messages.

    Attributes
    ----------
    status_ab : (int, int)
        The two status lines.
    commands : int
        Commands received (heard) so far.
    """

    answer_bytes = 0
    """Length of this controller's answer to READ (the CCU knows it)."""

    def __init__(self, address: int, name: str) -> None:
        if not 0 <= address <= 255:
            raise ValidationError(f"controller {name!r}: address {address} not in 0..255")
        self.address = address
        self.name = name
        self.status_ab: tuple[int, int] = FREE
        self.commands = 0
        self.run_id = 0
        self.bus: Microbus | None = None

    @property
    def free(self) -> bool:
        """Whether the controller listens (B line low)."""
        return self.status_ab[1] == 0

    def execute(self, cmd: Command, now: float) -> float:
        """Start ``cmd``; return how long the controller stays busy, seconds.

        Parameters
        ----------
        cmd : Command
            The command.
        now : float
            Virtual time, seconds.

        Returns
        -------
        float
            Seconds busy (0: done at once).

        Raises
        ------
        ValidationError
            For an op-code this controller does not know.
        """
        raise ValidationError(f"controller {self.name!r}: unknown op-code {cmd.opcode:#x}")

    def answer(self, cmd: Command) -> bytes:
        """The answer to a READ request.

        Parameters
        ----------
        cmd : Command
            The request.

        Returns
        -------
        bytes
            Exactly :attr:`answer_bytes` bytes.

        Raises
        ------
        UsageError
            If the controller has nothing to say.
        """
        raise UsageError(f"controller {self.name!r} has no answer")

    def finish(self, now: float) -> None:
        """The running command ends (status back to free unless aborted).

        Parameters
        ----------
        now : float
            Seconds.
        """
        if self.status_ab == BUSY:
            self.status_ab = FREE


class Microbus:
    """The shared 8-bit bus from the CCU to every controller (S1.3, S1.4).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    command_time : float, optional
        Seconds a command holds the bus (default 1e-4: 10,000 commands/s).
    segment_size : int, optional
        Controllers per segment before a regenerator (default 10).

    Attributes
    ----------
    commands : int
        Commands put on the bus (requests included).
    lost : int
        Commands sent to a busy (deaf) controller.
    bytes_answered : int
        Answer bytes carried.
    """

    def __init__(
        self, kernel: EventLoop, command_time: float = COMMAND_TIME, segment_size: int = 10
    ) -> None:
        self.kernel = kernel
        self.command_time = command_time
        self.byte_time = command_time / 5
        self.segment_size = segment_size
        self.controllers: dict[int, Controller] = {}
        self.segments: dict[int, int] = {}
        self.free_at = -math.inf
        self.commands = 0
        self.lost = 0
        self.bytes_answered = 0
        self._interrupt_cbs: list[Callable[[Controller], object]] = []

    # -------------------------------------------------------- configuration --
    def add(self, controller: _C, segment: int = 0) -> _C:
        """Attach ``controller`` on bus ``segment``.

        Parameters
        ----------
        controller : Controller
            Its address must be unused.
        segment : int, optional
            Bus segment (between regenerators).

        Returns
        -------
        Controller
            ``controller``.

        Raises
        ------
        ValidationError
            For an address already used.
        """
        if controller.address in self.controllers:
            raise ValidationError(
                f"Microbus: address {controller.address} used by "
                f"{self.controllers[controller.address].name!r} and {controller.name!r}"
            )
        self.controllers[controller.address] = controller
        self.segments[controller.address] = segment
        controller.bus = self
        return controller

    def check_configuration(self) -> None:
        """Check the S1.3/S1.4 limits: <= 256 controllers, <= 10 per segment.

        Raises
        ------
        ValidationError
            Naming the segment that is too long.
        """
        if len(self.controllers) > 256:
            raise ValidationError(f"Microbus: {len(self.controllers)} controllers, at most 256")
        counts: dict[int, int] = {}
        for seg in self.segments.values():
            counts[seg] = counts.get(seg, 0) + 1
        for seg, c in sorted(counts.items()):
            if c > self.segment_size:
                raise ValidationError(
                    f"Microbus: segment {seg} has {c} controllers; at most "
                    f"{self.segment_size} before a regenerator"
                )

    # ----------------------------------------------------------------- bus --
    def _controller(self, address: int) -> Controller:
        try:
            return self.controllers[address]
        except KeyError:
            raise ValidationError(f"Microbus: no controller at address {address}") from None

    def _take_bus(self, at: float | None) -> float:
        t = self.kernel.now if at is None else at
        if t < self.free_at - 1e-12:
            raise UsageError(
                f"Microbus: bus busy until {self.free_at:.6f} s, command at {t:.6f} s "
                f"(at most {1 / self.command_time:.0f} commands/s)"
            )
        self.commands += 1
        self.free_at = t + self.command_time
        return t

    def send(self, cmd: Command, at: float | None = None) -> bool:
        """Put ``cmd`` on the bus now (or at ``at`` >= now, for look-ahead).

        Parameters
        ----------
        cmd : Command
            The command.
        at : float, optional
            Time of sending, seconds (default now).

        Returns
        -------
        bool
            Whether the target heard it (False: it was busy, the command is lost).

        Raises
        ------
        UsageError
            If the bus is still busy (10,000 commands/s).
        ValidationError
            For an unknown address.
        """
        ctrl = self._controller(cmd.address)
        t = self._take_bus(at)
        if not ctrl.free:
            self.lost += 1
            return False
        ctrl.commands += 1
        ctrl.status_ab = BUSY
        duration = ctrl.execute(cmd, t)
        ctrl.run_id += 1
        self.kernel.schedule(
            t + self.command_time + duration, self._finish, ctrl, ctrl.run_id, absolute=True
        )
        return True

    def _finish(self, ctrl: Controller, run_id: int) -> None:
        if ctrl.run_id == run_id:  # not cut short by the reflex arc
            ctrl.finish(self.kernel.now)

    def request(self, address: int, arg: int = 0) -> bytes | None:
        """Ask controller ``address`` to speak (READ); the bus stays busy
        until the whole answer is in.

        Parameters
        ----------
        address : int
            The controller.
        arg : int, optional
            Argument byte (e.g. the force axis).

        Returns
        -------
        bytes or None
            The answer (``answer_bytes`` long), or None if the controller was
            busy and did not hear the request.

        Raises
        ------
        UsageError
            If the bus is busy.
        """
        ctrl = self._controller(address)
        t = self._take_bus(None)
        if not ctrl.free:
            self.lost += 1
            return None
        cmd = Command(address, READ, bytes((arg,)))
        data = ctrl.answer(cmd)
        if len(data) != ctrl.answer_bytes:  # pragma: no cover - controller bug
            raise UsageError(f"controller {ctrl.name!r} answered {len(data)} bytes")
        self.bytes_answered += len(data)
        self.free_at = t + self.command_time + len(data) * self.byte_time
        return data

    # -------------------------------------------------------- status lines --
    def status(self, address: int) -> tuple[int, int]:
        """The (A, B) status lines of one controller, read as flags.

        Parameters
        ----------
        address : int
            The controller.

        Returns
        -------
        (int, int)
            :data:`FREE`, :data:`BUSY`, :data:`ABORT_RAIL` or :data:`ABORT_FORCE`.
        """
        return self._controller(address).status_ab

    @property
    def interrupt(self) -> bool:
        """The OR of every A line (the CCU's one interrupt input)."""
        return any(c.status_ab[0] for c in self.controllers.values())

    def on_interrupt(self, callback: Callable[[Controller], object]) -> None:
        """Call ``callback(controller)`` when an A line rises.

        Parameters
        ----------
        callback : callable
            Receives the controller that aborted.
        """
        self._interrupt_cbs.append(callback)

    def acknowledge(self, address: int) -> None:
        """The CCU clears a controller's A line after handling the abort.

        Parameters
        ----------
        address : int
            The controller.
        """
        ctrl = self._controller(address)
        ctrl.status_ab = FREE

    def raise_a(self, ctrl: Controller, code: tuple[int, int]) -> None:
        ctrl.status_ab = code
        for cb in self._interrupt_cbs:
            cb(ctrl)
