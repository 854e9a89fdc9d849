"""The SUPERSIGMA central control unit and its task language (S1.1, S1.9).

The CCU alone decides (S1.1): it runs a program of task *boxes* -- parallel
tasks synchronised by flags (S1.9) -- on one processor, turning each robot
statement into MICROBUS commands. A box is a generator function taking the
:class:`CCU`; its statements are the CCU's generator methods, called with
``yield from``:

==================  =========================================================
statement           bus traffic
==================  =========================================================
``move(a, steps)``  wait until controller ``a`` is free (status lines), 1 command
``actuate(a, on)``  wait until free, 1 command
``set_threshold``   wait until free, 1 command
``read(a, arg)``    wait until free, 1 request + the answer bytes
``wait(a)``         poll the status lines until ``a`` is free (no command)
``set_flag(f)``     none
``wait_flag(f)``    none (re-checked every ``poll_interval``)
``wait_until(t)``   none (idle until time ``t``)
==================  =========================================================

Every statement but ``wait`` also costs ``statement_time`` of the CCU's
processor (an interpreted, BASIC-like language); boxes share that processor.
``wait`` only reads the status lines every ``poll_interval``: that time
counts as idle, the controllers being busy with earlier commands (S1.10:
the CCU idles at least half the time), and is reported by
:attr:`RunReport.idle_share`. The CCU never
sends to a busy controller (it checks the status lines first, S1.3) and
waits for the bus (10,000 commands/s). An A line (rail limit or excessive
force) reaches it as an interrupt; it records it, acknowledges the line and
the box goes on (the program can look at :attr:`CCU.aborts`).

Examples
--------
>>> from workcell.sim.events.loop import EventLoop
>>> from workcell.sim.comms.devices import MotorController
>>> from workcell.sim.comms.microbus import Microbus
>>> k = EventLoop()
>>> bus = Microbus(k)
>>> _ = bus.add(MotorController(1, "x"))
>>> ccu = CCU(k, bus)
>>> def box(c):
...     yield from c.move(1, 400)
...     yield from c.move(1, -100)
...     pos = yield from c.read(1)
...     c.note("position", pos)
>>> report = ccu.run({"main": box})
>>> report.commands, ccu.notes
(3, [('position', 300)])
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Mapping
from dataclasses import dataclass
from typing import Any

from multiarm.errors import ValidationError
from workcell.sim.comms.microbus import (
    ACTUATE,
    MOVE,
    SET_THRESHOLD,
    Command,
    Controller,
    Microbus,
    steps_args,
)
from workcell.sim.events.loop import EventLoop, ProcessGenerator

__all__ = ["CCU", "Box", "RunReport"]

Box = Callable[["CCU"], ProcessGenerator]
"""A task box: a generator function of the CCU."""


@dataclass(frozen=True, slots=True)
class RunReport:
    """What a program run did, in the layout of the S1.10 table.

    Parameters
    ----------
    commands : int
        MICROBUS commands (requests included).
    seconds : float
        Virtual run time.
    cpu_busy : float
        Seconds the CCU processor worked.
    answer_bytes : int
        Answer bytes read.
    lost : int
        Commands lost to busy controllers (0 for a correct CCU).
    aborts : int
        Reflex-arc aborts reported.
    """

    commands: int
    seconds: float
    cpu_busy: float
    answer_bytes: int
    lost: int
    aborts: int

    @property
    def rate(self) -> float:
        """Commands per second."""
        return self.commands / self.seconds if self.seconds > 0 else 0.0

    @property
    def saturation(self) -> float:
        """Commands/s over the 10,000 commands/s maximum (a fraction)."""
        return self.rate / 10_000.0

    @property
    def idle_share(self) -> float:
        """Fraction of the run the CCU processor was idle."""
        return 1.0 - self.cpu_busy / self.seconds if self.seconds > 0 else 1.0


class CCU:
    """The central control unit (see the module docstring).

    Parameters
    ----------
    kernel : EventLoop
        The kernel.
    bus : Microbus
        The bus.
    statement_time : float, optional
        CCU processor time per statement, seconds (default 1e-3).
    poll_interval : float, optional
        Status-line and flag polling period, seconds (default 1e-3).

    Attributes
    ----------
    flags : dict of str to bool
        The synchronisation flags.
    aborts : list of (float, str, (int, int))
        Reported aborts: time, controller, status code.
    notes : list of (str, object)
        What programs chose to record (e.g. measured heights).
    """

    def __init__(
        self,
        kernel: EventLoop,
        bus: Microbus,
        statement_time: float = 1e-3,
        poll_interval: float = 1e-3,
    ) -> None:
        if statement_time < 0 or poll_interval <= 0:
            raise ValidationError(
                f"CCU: statement_time={statement_time!r} must be >= 0, "
                f"poll_interval={poll_interval!r} > 0"
            )
        self.kernel = kernel
        self.bus = bus
        self.statement_time = statement_time
        self.poll_interval = poll_interval
        self.flags: dict[str, bool] = {}
        self.aborts: list[tuple[float, str, tuple[int, int]]] = []
        self.notes: list[tuple[str, object]] = []
        self.cpu_busy = 0.0
        self._cpu_free_at = kernel.now
        bus.on_interrupt(self._interrupt)

    def _interrupt(self, ctrl: Controller) -> None:
        self.aborts.append((self.kernel.now, ctrl.name, ctrl.status_ab))

    # ------------------------------------------------------------ helpers --
    def _cpu(self) -> Generator[float, Any, None]:
        start = max(self.kernel.now, self._cpu_free_at)
        self._cpu_free_at = start + self.statement_time
        self.cpu_busy += self.statement_time
        wait = self._cpu_free_at - self.kernel.now
        if wait > 0:
            yield wait

    def _ready(self, address: int) -> Generator[float, Any, None]:
        """Wait until ``address`` is free and the bus is free."""
        yield from self.wait(address)
        while self.kernel.now < self.bus.free_at:
            yield self.bus.free_at - self.kernel.now
            yield from self.wait(address)

    # --------------------------------------------------------- statements --
    def wait(self, address: int) -> Generator[float, Any, tuple[int, int]]:
        """WAIT: poll the status lines until controller ``address`` is free;
        an abort code is recorded and acknowledged.

        Parameters
        ----------
        address : int
            The controller.

        Returns
        -------
        (int, int)
            The status read when it became free.
        """
        status = self.bus.status(address)
        while status[1] == 1 and status[0] == 0:
            yield self.poll_interval
            status = self.bus.status(address)
        if status[0] == 1:
            self.bus.acknowledge(address)
        return status

    def move(self, address: int, steps: int) -> ProcessGenerator:
        """MOVE an axis by ``steps`` (the controller chooses the profile).

        Parameters
        ----------
        address : int
            Motor controller.
        steps : int
            Signed steps.

        Yields
        ------
        float
            Delays (the statement's waits).
        """
        yield from self._cpu()
        yield from self._ready(address)
        self.bus.send(Command(address, MOVE, steps_args(steps)))

    def actuate(self, address: int, on: bool) -> ProcessGenerator:
        """ACTUATE a device (gripper close/open, lamp on/off).

        Parameters
        ----------
        address : int
            Controller.
        on : bool
            Close / switch on.

        Yields
        ------
        float
            Delays.
        """
        yield from self._cpu()
        yield from self._ready(address)
        self.bus.send(Command(address, ACTUATE, bytes((int(on),))))

    def set_threshold(self, address: int, axis: int, newtons: int) -> ProcessGenerator:
        """SET THRESHOLD of a force sensor axis (S1.7).

        Parameters
        ----------
        address : int
            Force controller.
        axis : int
            0, 1, 2.
        newtons : int
            0..255.

        Yields
        ------
        float
            Delays.
        """
        yield from self._cpu()
        yield from self._ready(address)
        self.bus.send(Command(address, SET_THRESHOLD, bytes((axis, newtons))))

    def read(self, address: int, arg: int = 0) -> Generator[float, Any, int]:
        """READ a controller's answer: a motor's position (16 bits signed), a
        force (16 bits signed), or the detector's beam (0/1).

        Parameters
        ----------
        address : int
            Controller.
        arg : int, optional
            Argument byte (force axis).

        Returns
        -------
        int
            The decoded answer.
        """
        yield from self._cpu()
        yield from self._ready(address)
        data = self.bus.request(address, arg)
        if data is None:  # pragma: no cover - _ready guarantees a free controller
            raise ValidationError(f"CCU.read: controller {address} was busy")
        yield self.bus.free_at - self.kernel.now  # the answer takes the bus
        return int.from_bytes(data, "big", signed=len(data) == 2)

    def set_flag(self, name: str, value: bool = True) -> ProcessGenerator:
        """SET FLAG.

        Parameters
        ----------
        name : str
            Flag.
        value : bool, optional
            New value.

        Yields
        ------
        float
            Delays.
        """
        yield from self._cpu()
        self.flags[name] = value

    def wait_flag(self, name: str, value: bool = True, consume: bool = True) -> ProcessGenerator:
        """WAIT FLAG until ``flags[name] == value`` (then, by default, it is
        consumed: set back to ``not value``).

        Parameters
        ----------
        name : str
            Flag.
        value : bool, optional
            Value waited for.
        consume : bool, optional
            Reset the flag once seen (a hand-over between two boxes); False
            leaves it for every other box waiting on it (an event that stays
            true, such as "task done").

        Yields
        ------
        float
            Delays.
        """
        yield from self._cpu()
        while self.flags.get(name, False) != value:
            yield self.poll_interval
        if consume:
            self.flags[name] = not value

    def wait_until(self, t: float) -> ProcessGenerator:
        """WAIT TIME: idle until the virtual time ``t`` (no bus traffic).

        Parameters
        ----------
        t : float
            Seconds.

        Yields
        ------
        float
            Delays.
        """
        yield from self._cpu()
        if t > self.kernel.now:
            yield t - self.kernel.now

    def note(self, key: str, value: object) -> None:
        """Record a result of the program (no bus traffic).

        Parameters
        ----------
        key : str
            Label.
        value : object
            Value.
        """
        self.notes.append((key, value))

    # ---------------------------------------------------------------- run --
    def run(self, boxes: Mapping[str, Box], until: float | None = None) -> RunReport:
        """Run the boxes in parallel until all end (waiting for the devices).

        Parameters
        ----------
        boxes : mapping of str to Box
            Task boxes by name.
        until : float, optional
            Stop at this virtual time.

        Returns
        -------
        RunReport
            Counts for the run (this CCU's bus, from the run's start).
        """
        t0 = self.kernel.now
        c0, b0, l0, a0 = self.bus.commands, self.bus.bytes_answered, self.bus.lost, len(self.aborts)
        busy0 = self.cpu_busy
        procs = [self.kernel.process(box(self)) for box in boxes.values()]
        ends: list[float] = []

        def waiter() -> ProcessGenerator:
            yield from procs
            for a in list(self.bus.controllers):
                yield from self.wait(a)
            ends.append(self.kernel.now)

        self.kernel.process(waiter())
        self.kernel.run(until=until)
        end = ends[0] if ends else self.kernel.now
        return RunReport(
            commands=self.bus.commands - c0,
            seconds=end - t0,
            cpu_busy=self.cpu_busy - busy0,
            answer_bytes=self.bus.bytes_answered - b0,
            lost=self.bus.lost - l0,
            aborts=len(self.aborts) - a0,
        )
