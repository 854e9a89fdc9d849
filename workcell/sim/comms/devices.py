"""The SUPERSIGMA device controllers on the MICROBUS (S1.5, S1.7, S1.8): a
stepper axis, the wrist force sensor, a gripper, a beam detector."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from workcell.sim.comms.microbus import (
    ABORT_FORCE,
    ABORT_RAIL,
    ACTUATE,
    BUSY,
    MOVE,
    SET_THRESHOLD,
    Command,
    Controller,
    StepProfile,
    move_time,
)

__all__ = ["DetectorController", "ForceController", "GripperController", "MotorController"]


class MotorController(Controller):
    """A stepper axis (S1.5): MOVE steps with the controller's own profile;
    READ answers the 16-bit position in 2 bytes.

    Parameters
    ----------
    address : int
        0..255.
    name : str
        Axis name.
    profile : StepProfile, optional
        Speed profile.
    rail : (int, int), optional
        Positions of the end-of-rail switches, steps.
    """

    answer_bytes = 2

    def __init__(
        self,
        address: int,
        name: str,
        profile: StepProfile | None = None,
        rail: tuple[int, int] = (-30_000, 30_000),
    ) -> None:
        super().__init__(address, name)
        self.profile = profile if profile is not None else StepProfile()
        self.rail = rail
        self.position = 0
        self._target = 0
        self._start = 0.0
        self._end = 0.0
        self._trip = False

    def execute(self, cmd: Command, now: float) -> float:
        if cmd.opcode != MOVE or len(cmd.args) != 2:
            return super().execute(cmd, now)
        steps = int.from_bytes(cmd.args, "big", signed=True)
        lo, hi = self.rail
        target = self.position + steps
        stop = min(max(target, lo), hi)
        duration = move_time(stop - self.position, self.profile)
        self._target = stop
        self._start, self._end = now, now + duration
        self._trip = stop != target  # the rail switch trips at the end of the run
        return duration

    def finish(self, now: float) -> None:
        self.position = self._target
        if self._trip:
            self._trip = False
            self.abort(ABORT_RAIL)
            return
        super().finish(now)

    def abort(self, code: tuple[int, int]) -> None:
        """Reflex arc (S1.2): stop now by the controller's own decision and
        raise the A line; the CCU learns it by the OR-ed interrupt.

        Parameters
        ----------
        code : (int, int)
            :data:`ABORT_RAIL` or :data:`ABORT_FORCE`.
        """
        if self.bus is None:
            return
        now = self.bus.kernel.now
        if self.status_ab == BUSY and self._end > now:  # stopped on the way
            frac = min(1.0, (now - self._start) / max(self._end - self._start, 1e-12))
            self._target = self.position + round((self._target - self.position) * frac)
            self._trip = False
        self.position = self._target
        self._end = now
        self.run_id += 1
        self.bus.raise_a(self, code)

    def answer(self, cmd: Command) -> bytes:
        return (self.position & 0xFFFF).to_bytes(2, "big")


class ForceController(Controller):
    """Wrist force sensor (S1.7): READ axis k answers 2 bytes (newtons,
    signed); SET_THRESHOLD axis, value. Above threshold it trips the reflex
    arc of the motors it guards.

    Parameters
    ----------
    address : int
        0..255.
    name : str
        Name.
    force : callable, optional
        ``force(t) -> (fx, fy, fz)`` newtons (default zero).
    guards : sequence of MotorController, optional
        Motors stopped when a threshold is passed.
    """

    answer_bytes = 2

    def __init__(
        self,
        address: int,
        name: str,
        force: Callable[[float], tuple[float, float, float]] | None = None,
        guards: Sequence[MotorController] = (),
    ) -> None:
        super().__init__(address, name)
        self.force = force if force is not None else (lambda t: (0.0, 0.0, 0.0))
        self.thresholds = [20, 20, 20]
        self.guards = list(guards)

    def execute(self, cmd: Command, now: float) -> float:
        if cmd.opcode == SET_THRESHOLD and len(cmd.args) == 2:
            self.thresholds[cmd.args[0] % 3] = cmd.args[1]
            return 0.0
        return super().execute(cmd, now)

    def check(self, now: float) -> bool:
        """Sample the forces; on excess, stop the guarded moving motors.

        Parameters
        ----------
        now : float
            Seconds.

        Returns
        -------
        bool
            Whether a threshold was passed.
        """
        f = self.force(now)
        if any(abs(f[i]) > self.thresholds[i] for i in range(3)):
            for m in self.guards:
                if m.status_ab == BUSY:
                    m.abort(ABORT_FORCE)
            return True
        return False

    def answer(self, cmd: Command) -> bytes:
        axis = cmd.args[0] % 3 if cmd.args else 0
        value = round(self.force(self.bus.kernel.now if self.bus else 0.0)[axis])
        return max(-(2**15), min(2**15 - 1, value)).to_bytes(2, "big", signed=True)


class GripperController(Controller):
    """Gripper: ACTUATE 1 closes, 0 opens; busy ``stroke_time`` seconds.

    Parameters
    ----------
    address : int
        0..255.
    name : str
        Name.
    stroke_time : float, optional
        Seconds (default 0.2).
    """

    def __init__(self, address: int, name: str, stroke_time: float = 0.2) -> None:
        super().__init__(address, name)
        self.stroke_time = stroke_time
        self.closed = False

    def execute(self, cmd: Command, now: float) -> float:
        if cmd.opcode != ACTUATE or len(cmd.args) != 1:
            return super().execute(cmd, now)
        self.closed = bool(cmd.args[0])
        return self.stroke_time


class DetectorController(Controller):
    """Lamp/photodiode pair in the fingers (S1.8): READ answers 1 byte, 1 if
    the beam is broken at the hand's current position.

    Parameters
    ----------
    address : int
        0..255.
    name : str
        Name.
    beam : callable
        ``beam() -> bool``: whether something is between the fingers now
        (the cell model knows where the hand is).
    """

    answer_bytes = 1

    def __init__(self, address: int, name: str, beam: Callable[[], bool]) -> None:
        super().__init__(address, name)
        self.beam = beam

    def answer(self, cmd: Command) -> bytes:
        return b"\x01" if self.beam() else b"\x00"
