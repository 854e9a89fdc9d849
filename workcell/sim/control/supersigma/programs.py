"""A SUPERSIGMA cell, the object-detector demo and the S1.10 bus-load programs.

:class:`SigmaCell` builds a Cartesian robot of one or two arms on a MICROBUS:
per arm three stepper axes (x, y, z; S1.5), a gripper, a wrist force sensor
(S1.7) and a lamp/photodiode object detector (S1.8), six controllers on the
arm's own bus segment. The hand's coordinates are always known from the step
counts (``mm_per_step`` = 0.0375). Axes of one arm move without coordination
(S1.9): a hand move sends one command per axis that changes and then waits
for all of them.

:func:`chess_sort` is the S1.8 demo: scan a line with the beam low, find the
pieces, measure each one's height by lowering the beam from above, and sort
the pieces into bins by height.

:func:`bus_load_table` runs four programs written after the paper's
descriptions (S1.10) and reports commands, seconds, commands/s and
saturation (commands/s over 10,000) next to the paper's figures:

* ``ORD`` -- one arm, long moves: 24 parts from a feeder into a 4 x 6 pallet;
* ``SCP1B`` -- one arm: 10 pegs inserted into holes whose position is not
  well known, with raised force thresholds and repeated tries at slightly
  different positions (S1.7);
* ``SCP2B`` -- two arms continuously moving over very short distances
  (60-400 steps, 2.25-15 mm, next to a travel of 500 mm) for 160 moves
  each, alternating x and y;
* ``PRCO`` -- two arms, a long program: arm 0 brings 16 parts to a buffer,
  arm 1 takes each one, measures its height with the detector and puts it in
  one of two bins; the arms are synchronised by flags.

The programs are not tuned to the paper's numbers.

Examples
--------
>>> rows = bus_load_table()
>>> [r["program"] for r in rows]
['ORD', 'SCP1B', 'SCP2B', 'PRCO']
>>> max(rows, key=lambda r: r["rate"])["program"]
'SCP2B'
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from multiarm.errors import ValidationError
from multiarm.types import Seed, as_rng
from workcell.sim.comms.devices import (
    DetectorController,
    ForceController,
    GripperController,
    MotorController,
)
from workcell.sim.comms.microbus import (
    Microbus,
    StepProfile,
)
from workcell.sim.control.supersigma.ccu import CCU, Box, RunReport
from workcell.sim.events.loop import EventLoop, ProcessGenerator

__all__ = ["PAPER_TABLE", "Piece", "SigmaCell", "bus_load_table", "chess_sort", "run_program"]

PAPER_TABLE: dict[str, tuple[int, int, int, float, float]] = {
    "ORD": (1, 751, 167, 4.5, 0.045),
    "SCP1B": (1, 328, 56, 5.86, 0.059),
    "SCP2B": (2, 394, 36, 10.94, 0.109),
    "PRCO": (2, 1600, 260, 6.15, 0.062),
}
"""The paper's table (S1.10): arms, commands, seconds, commands/s, saturation %."""


@dataclass(frozen=True, slots=True)
class Piece:
    """A part standing on the table.

    Parameters
    ----------
    x, y : float
        Centre, millimetres.
    height : float
        Millimetres.
    radius : float, optional
        Millimetres.
    """

    x: float
    y: float
    height: float
    radius: float = 8.0


class SigmaCell:
    """A SUPERSIGMA cell of one or more arms on one MICROBUS (the original
    has two; up to 25 fit the 256 addresses, 10 per arm).

    Parameters
    ----------
    arms : int, optional
        1..25 (arm a uses addresses 10 a + 1 .. 10 a + 6, on segment a).
    pieces : sequence of Piece, optional
        Parts on the table (seen by the detectors).
    z_home : float, optional
        Height of the hand at step 0 of the z axis, millimetres.
    statement_time : float, optional
        CCU time per statement, seconds.
    profile : StepProfile, optional
        Stepper profile of every axis.

    Attributes
    ----------
    kernel : EventLoop
    bus : Microbus
    ccu : CCU
    """

    def __init__(
        self,
        arms: int = 1,
        pieces: Sequence[Piece] = (),
        z_home: float = 150.0,
        statement_time: float = 1e-3,
        profile: StepProfile | None = None,
    ) -> None:
        if not 1 <= arms <= 25:
            raise ValidationError(f"SigmaCell: arms must be 1..25, got {arms}")
        self.kernel = EventLoop()
        self.bus = Microbus(self.kernel)
        self.profile = profile if profile is not None else StepProfile()
        self.z_home = z_home
        self.pieces = list(pieces)
        self.holes: list[tuple[float, float]] = []
        self.surface = 30.0
        self.motors: list[tuple[MotorController, MotorController, MotorController]] = []
        for a in range(arms):
            base = 10 * a
            axes = tuple(
                MotorController(base + i + 1, f"arm{a}.{n}", self.profile)
                for i, n in enumerate("xyz")
            )
            mx, my, mz = axes
            self.motors.append((mx, my, mz))
            for m in axes:
                self.bus.add(m, segment=a)
            self.bus.add(GripperController(base + 4, f"arm{a}.gripper"), segment=a)
            self.bus.add(
                ForceController(
                    base + 5, f"arm{a}.force", force=self._force_of(a), guards=(mx, my, mz)
                ),
                segment=a,
            )
            self.bus.add(
                DetectorController(base + 6, f"arm{a}.detector", beam=self._beam_of(a)),
                segment=a,
            )
        self.bus.check_configuration()
        self.ccu = CCU(self.kernel, self.bus, statement_time=statement_time)

    # ---------------------------------------------------------- geometry --
    def hand(self, arm: int) -> tuple[float, float, float]:
        """The hand's coordinates from the step counts, millimetres.

        Parameters
        ----------
        arm : int
            Arm index.

        Returns
        -------
        (float, float, float)
            x, y, z.
        """
        mm = self.profile.mm_per_step
        mx, my, mz = self.motors[arm]
        return mx.position * mm, my.position * mm, self.z_home + mz.position * mm

    def _beam_of(self, arm: int) -> Any:
        def beam() -> bool:
            x, y, z = self.hand(arm)
            return any(
                abs(x - p.x) <= p.radius and abs(y - p.y) <= p.radius and z < p.height
                for p in self.pieces
            )

        return beam

    def _force_of(self, arm: int) -> Any:
        def force(t: float) -> tuple[float, float, float]:
            x, y, z = self.hand(arm)
            if z >= self.surface:
                return (0.0, 0.0, 0.0)
            inside = any(abs(x - hx) <= 0.5 and abs(y - hy) <= 0.5 for hx, hy in self.holes)
            return (0.0, 0.0, 0.0 if inside else 60.0)

        return force

    # ---------------------------------------------------- box statements --
    def addr(self, arm: int, device: str) -> int:
        """Bus address of a device of an arm.

        Parameters
        ----------
        arm : int
            Arm index.
        device : {"x", "y", "z", "gripper", "force", "detector"}
            Device.

        Returns
        -------
        int
            Address.
        """
        return 10 * arm + ("x", "y", "z", "gripper", "force", "detector").index(device) + 1

    def goto(
        self,
        arm: int,
        x: float | None = None,
        y: float | None = None,
        z: float | None = None,
        wait: bool = True,
    ) -> ProcessGenerator:
        """Move the hand to absolute coordinates (mm), one command per axis
        that changes, axes in parallel; then wait for all (unless ``wait``
        is false).

        Parameters
        ----------
        arm : int
            Arm.
        x, y, z : float, optional
            Targets, millimetres (None: keep).
        wait : bool, optional
            Wait until every axis has stopped.

        Yields
        ------
        float
            Delays.
        """
        mm = self.profile.mm_per_step
        targets = (x, y, None if z is None else z - self.z_home)
        moved = []
        for motor, target in zip(self.motors[arm], targets, strict=True):
            if target is None:
                continue
            steps = round(target / mm) - motor.position
            if steps != 0:
                yield from self.ccu.move(motor.address, steps)
                moved.append(motor.address)
        if wait:
            for a in moved:
                yield from self.ccu.wait(a)

    def grip(self, arm: int, close: bool) -> ProcessGenerator:
        """Close or open the gripper and wait for the stroke.

        Parameters
        ----------
        arm : int
            Arm.
        close : bool
            Close.

        Yields
        ------
        float
            Delays.
        """
        a = self.addr(arm, "gripper")
        yield from self.ccu.actuate(a, close)
        yield from self.ccu.wait(a)

    def measure_height(
        self, arm: int, top: float = 100.0, step: float = 2.0
    ) -> Any:  # Generator[float, Any, float]
        """Lower the beam from ``top`` in ``step`` mm until it is broken (S1.8).

        Parameters
        ----------
        arm : int
            Arm (the hand must be over the part).
        top : float, optional
            Start height, mm.
        step : float, optional
            Resolution, mm.

        Returns
        -------
        float
            Measured height (the first beam height that is broken), mm;
            0 when nothing is found.
        """
        z = top
        while z > 0:
            yield from self.goto(arm, z=z)
            if (yield from self.ccu.read(self.addr(arm, "detector"))):
                return z
            z -= step
        return 0.0


def run_program(cell: SigmaCell, boxes: dict[str, Box]) -> RunReport:
    """Run task boxes on the cell's CCU.

    Parameters
    ----------
    cell : SigmaCell
        The cell.
    boxes : dict of str to Box
        Task boxes.

    Returns
    -------
    RunReport
        Counts of the run.
    """
    return cell.ccu.run(boxes)


def chess_sort(
    pieces: Sequence[Piece],
    line_y: float = 0.0,
    x_range: tuple[float, float] = (0.0, 400.0),
    scan_step: float = 5.0,
    bins: Sequence[float] = (45.0, 65.0),
) -> tuple[list[tuple[float, float, int]], RunReport]:
    """The S1.8 demo: find chess pieces on a line, measure their heights and
    sort them into bins.

    Parameters
    ----------
    pieces : sequence of Piece
        Pieces on the table (the program does not know them).
    line_y : float, optional
        The line searched, mm.
    x_range : (float, float), optional
        Scanned x interval, mm.
    scan_step : float, optional
        Scan resolution, mm.
    bins : sequence of float, optional
        Height thresholds between bins, mm (bin i holds heights below
        ``bins[i]``; the last bin the rest).

    Returns
    -------
    found : list of (float, float, int)
        Per piece found: x centre (mm), measured height (mm), bin.
    report : RunReport
        Bus counts.

    Examples
    --------
    >>> found, rep = chess_sort([Piece(100.0, 0.0, 40.0), Piece(250.0, 0.0, 70.0)])
    >>> [(round(x), h, b) for x, h, b in found]
    [(100, 38.0, 0), (250, 68.0, 2)]
    """
    cell = SigmaCell(1, pieces)
    found: list[tuple[float, float, int]] = []

    def box(ccu: CCU) -> ProcessGenerator:
        det = cell.addr(0, "detector")
        yield from cell.goto(0, x=x_range[0], y=line_y, z=5.0)
        hits: list[float] = []
        x = x_range[0]
        while x <= x_range[1]:
            yield from cell.goto(0, x=x)
            if (yield from ccu.read(det)):
                hits.append(x)
            x += scan_step
        groups: list[list[float]] = []
        for h in hits:
            if groups and h - groups[-1][-1] <= scan_step + 1e-9:
                groups[-1].append(h)
            else:
                groups.append([h])
        for g in groups:
            centre = (g[0] + g[-1]) / 2
            yield from cell.goto(0, z=110.0)
            yield from cell.goto(0, x=centre)
            height = yield from cell.measure_height(0, top=100.0, step=2.0)
            b = int(np.searchsorted(np.asarray(bins), height, side="right"))
            found.append((centre, float(height), b))
            ccu.note("piece", (centre, height, b))
            # pick it up and put it in its bin
            yield from cell.goto(0, z=height / 2)
            yield from cell.grip(0, True)
            cell.pieces = [p for p in cell.pieces if abs(p.x - centre) > p.radius]
            yield from cell.goto(0, z=110.0)
            yield from cell.goto(0, x=100.0 * b, y=line_y + 200.0)
            yield from cell.goto(0, z=20.0)
            yield from cell.grip(0, False)
            yield from cell.goto(0, z=110.0)
            yield from cell.goto(0, y=line_y)

    report = run_program(cell, {"chess": box})
    return found, report


# --------------------------------------------------------- S1.10 programs --
def _ord() -> tuple[SigmaCell, dict[str, Box]]:
    cell = SigmaCell(1)

    def box(ccu: CCU) -> ProcessGenerator:
        for i in range(24):
            yield from cell.goto(0, x=50.0, y=50.0, z=100.0)
            yield from cell.goto(0, z=10.0)
            yield from cell.grip(0, True)
            yield from cell.goto(0, z=100.0)
            yield from cell.goto(0, x=300.0 + 50.0 * (i % 4), y=200.0 + 40.0 * (i // 4))
            yield from cell.goto(0, z=15.0)
            yield from cell.grip(0, False)
            yield from cell.goto(0, z=100.0)

    return cell, {"ord": box}


def _scp1b(seed: Seed) -> tuple[SigmaCell, dict[str, Box]]:
    cell = SigmaCell(1)
    rng = as_rng(seed)
    offsets = rng.uniform(-1.2, 1.2, size=10)  # hole position errors, mm
    cell.holes = [(200.0 + 20.0 * i + float(offsets[i]), 150.0) for i in range(10)]
    force = cell.addr(0, "force")

    def box(ccu: CCU) -> ProcessGenerator:
        for i in range(10):
            hole_x = 200.0 + 20.0 * i
            yield from cell.goto(0, x=60.0, y=60.0, z=60.0)
            yield from cell.goto(0, z=20.0)
            yield from cell.grip(0, True)
            yield from cell.goto(0, z=60.0)
            yield from cell.goto(0, x=hole_x, y=150.0)
            yield from ccu.set_threshold(force, 2, 120)  # pushing: raise the threshold
            for dx in (0.0, 0.5, -0.5, 1.0, -1.0, 1.5, -1.5):
                yield from cell.goto(0, x=hole_x + dx)
                yield from cell.goto(0, z=28.0)
                f = yield from ccu.read(force, 2)
                if f < 30:  # no resistance: the peg is in the hole
                    break
                yield from cell.goto(0, z=32.0)
            yield from ccu.set_threshold(force, 2, 20)  # back to crash detection
            yield from cell.grip(0, False)
            yield from cell.goto(0, z=60.0)

    return cell, {"scp1b": box}


def _scp2b() -> tuple[SigmaCell, dict[str, Box]]:
    cell = SigmaCell(2)
    # a few millimetres per move (2.25-15 mm), short next to the 500 mm travel
    pattern = (60, 200, -60, -200, 120, 400, -120, -400)

    def arm_box(arm: int) -> Box:
        def box(ccu: CCU) -> ProcessGenerator:
            for i in range(160):
                axis = cell.addr(arm, "x" if i % 2 == 0 else "y")
                yield from ccu.move(axis, pattern[i % len(pattern)])
                yield from ccu.wait(axis)

        return box

    return cell, {"arm0": arm_box(0), "arm1": arm_box(1)}


def _prco() -> tuple[SigmaCell, dict[str, Box]]:
    heights = [30.0 + 5.0 * (i % 9) for i in range(16)]
    cell = SigmaCell(2)
    buffer_x, buffer_y = 250.0, 150.0

    def feeder(ccu: CCU) -> ProcessGenerator:
        for i in range(16):
            yield from cell.goto(0, x=20.0, y=20.0 + 10.0 * (i % 4), z=90.0)
            yield from cell.goto(0, z=10.0)
            yield from cell.grip(0, True)
            yield from cell.goto(0, z=90.0)
            yield from ccu.wait_flag("buffer_free")
            yield from cell.goto(0, x=buffer_x - 50.0, y=buffer_y)
            yield from cell.goto(0, z=10.0)
            yield from cell.grip(0, False)
            cell.pieces.append(Piece(buffer_x - 50.0, buffer_y, heights[i]))
            yield from cell.goto(0, z=90.0)
            yield from cell.goto(0, x=20.0)
            yield from ccu.set_flag("part_ready")

    def sorter(ccu: CCU) -> ProcessGenerator:
        yield from ccu.set_flag("buffer_free")
        for _ in range(16):
            yield from ccu.wait_flag("part_ready")
            yield from cell.goto(1, x=buffer_x - 50.0, y=buffer_y, z=100.0)
            h = yield from cell.measure_height(1, top=80.0, step=4.0)
            yield from cell.goto(1, z=h / 2)
            yield from cell.grip(1, True)
            cell.pieces = []
            yield from ccu.set_flag("buffer_free")
            yield from cell.goto(1, z=100.0)
            yield from cell.goto(1, x=400.0 + (60.0 if h >= 50.0 else 0.0), y=300.0)
            yield from cell.goto(1, z=20.0)
            yield from cell.grip(1, False)
            yield from cell.goto(1, z=100.0)

    return cell, {"feeder": feeder, "sorter": sorter}


def bus_load_table(seed: Seed = 0) -> list[dict[str, Any]]:
    """Run ORD, SCP1B, SCP2B and PRCO and tabulate the bus load (S1.10).

    Parameters
    ----------
    seed : int or Generator, optional
        Seed of SCP1B's hole position errors.

    Returns
    -------
    list of dict
        One row per program: ``program``, ``arms``, ``commands``,
        ``seconds``, ``rate`` (commands/s), ``saturation`` (fraction of
        10,000 commands/s), ``idle`` (CCU idle share), ``lost``, and the
        paper's ``paper_commands``, ``paper_seconds``, ``paper_rate``,
        ``paper_saturation`` (fraction).
    """
    rows = []
    for name, build in (
        ("ORD", _ord),
        ("SCP1B", lambda: _scp1b(seed)),
        ("SCP2B", _scp2b),
        ("PRCO", _prco),
    ):
        cell, boxes = build()
        rep = run_program(cell, boxes)
        arms, pc, ps, pr, psat = PAPER_TABLE[name]
        rows.append(
            {
                "program": name,
                "arms": arms,
                "commands": rep.commands,
                "seconds": rep.seconds,
                "rate": rep.rate,
                "saturation": rep.saturation,
                "idle": rep.idle_share,
                "lost": rep.lost,
                "paper_commands": pc,
                "paper_seconds": ps,
                "paper_rate": pr,
                "paper_saturation": psat / 100,
            }
        )
    return rows
