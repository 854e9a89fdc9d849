"""Faults and disturbances injected into a simulated run, described as data.

Every record is a frozen dataclass checked on construction
(:class:`~multiarm.errors.ValidationError` naming the field:
``EmergencyStop.at: must be ...``). A :class:`FaultPlan` is a tuple of
records, built directly, from plain dicts (:meth:`FaultPlan.from_dicts`,
errors name the field path: ``faults[0].at: must be ...``; read from a file,
the file first: ``faults.toml: faults[0].at: must be ...``), or drawn at
random with a seed (:meth:`FaultPlan.sample`).

* :class:`ArmFailure` -- the arm stops for good at ``at``; its interrupted
  task and every task planned on it are reassigned by a re-solve.
* :class:`Crash` -- a crash of ``force`` newtons on the wrist (S1.7): above
  the force threshold in force (low in free motion, raised during an
  insertion search, :mod:`workcell.sim.control.force`) the drive stops at once by
  itself (reflex arc, S1.2), the coordinator is told afterwards (an alarm);
  the arm stands for ``recovery`` seconds, then goes on.
* :class:`LostSync` -- a stepper axis loses ``steps`` steps (S1.5, S1.6):
  the tracked position is silently wrong until the arm is homed again at
  the end of its task (homing time from the drive).
* :class:`MessageLoss` -- every frame (of the given kinds) is lost or
  corrupted with a probability; the sender retransmits after a timeout, so
  no message is lost for good.
* :class:`LatePart` -- a part arrives ``delay`` seconds after its expected
  time (``inf``: never); the tasks it gates wait, and the plan is re-solved.
* :class:`EmergencyStop` -- an alarm broadcast at ``at``: every arm stops
  along its steepest allowed deceleration and resumes after ``duration``.
* :class:`ActivateZones` -- an active-zone change (S2.5): applied only once
  every arm has stopped; arms are held meanwhile.

Examples
--------
>>> plan = FaultPlan.from_dicts([{"kind": "arm_failure", "arm": "left", "at": 12.0},
...                              {"kind": "message_loss", "probability": 0.1}])
>>> [type(f).__name__ for f in plan]
['ArmFailure', 'MessageLoss']
>>> FaultPlan.from_dicts([{"kind": "crash", "arm": "left"}])
Traceback (most recent call last):
...
multiarm.errors.ValidationError: faults[0]: missing field 'at' (a crash record needs arm, at)
>>> FaultPlan.from_dicts([{"kind": "emergency_stop", "at": -1.0, "duration": 1.0}])
Traceback (most recent call last):
...
multiarm.errors.ValidationError: faults[0].at: must be in [0, 1e+06] seconds, got -1.0
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from multiarm.errors import ValidationError
from workcell.sim.comms.medium import MESSAGE_BYTES

if TYPE_CHECKING:
    from workcell.cell import Cell

__all__ = [
    "MESSAGE_KINDS",
    "ActivateZones",
    "ArmFailure",
    "Crash",
    "EmergencyStop",
    "Fault",
    "FaultPlan",
    "LatePart",
    "LostSync",
    "MessageLoss",
    "check_fault_names",
]


MAX_SECONDS = 1e6
"""Largest time or duration of a fault record, seconds (11.6 days; ``inf``
where a record allows it). Physical ranges: :data:`MAX_FORCE`,
:data:`MAX_LOSS`."""
MAX_FORCE = 1e6
"""Largest crash force, newtons."""
MAX_LOSS = 0.999
"""Largest message-loss probability. A work cap, not a physical one: each
frame is sent ``1 / (1 - p)`` times on average, and the run's events grow
with it (the supersigma cell's greedy plan: 0.4 s lossless, 2.1 s at 0.9,
14.5 s at 0.99; at 0.999 a run takes minutes, at 0.99999 hours). A link that
loses more is down: model it as an :class:`ArmFailure`."""
MESSAGE_KINDS: tuple[str, ...] = tuple(sorted(MESSAGE_BYTES))
"""The message kinds the coordination protocol sends (S2.7): the names a
:class:`MessageLoss` record's ``kinds`` may list."""


def _bad(record: object, field: str, text: str) -> ValidationError:
    """The error of field ``field`` of ``record``: ``"Record.field: text"``.

    :meth:`FaultPlan.from_dicts` turns the ``Record.`` prefix into the
    record's path (``faults[i].field: text``); :func:`_field_path` is the
    one place that reads it back.
    """
    return ValidationError(f"{type(record).__name__}.{field}: {text}")


def _field_path(exc: ValidationError, cls: type[Any], where: str) -> str:
    """The message of a record's own check with its path: ``where.field: text``."""
    text = str(exc)
    prefix = f"{cls.__name__}."
    return f"{where}.{text[len(prefix) :]}" if text.startswith(prefix) else f"{where}: {text}"


def _time(record: object, field: str, *, allow_inf: bool = False) -> float:
    value = getattr(record, field)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _bad(record, field, f"must be a number of seconds, got {value!r}")
    v = float(value)
    if math.isnan(v) or (not 0 <= v <= MAX_SECONDS and not (allow_inf and v == math.inf)):
        raise _bad(
            record,
            field,
            f"must be in [0, {MAX_SECONDS:g}] seconds{' or inf' if allow_inf else ''}, "
            f"got {value!r}",
        )
    object.__setattr__(record, field, v)
    return v


def _name(record: object, field: str) -> None:
    value = getattr(record, field)
    if not isinstance(value, str) or not value:
        raise _bad(record, field, f"must be a non-empty string, got {value!r}")


@dataclass(frozen=True, slots=True)
class ArmFailure:
    """Arm ``arm`` fails for good at time ``at`` (seconds)."""

    kind: ClassVar[str] = "arm_failure"
    arm: str
    at: float

    def __post_init__(self) -> None:
        _name(self, "arm")
        _time(self, "at")


@dataclass(frozen=True, slots=True)
class Crash:
    """A crash pushing ``force`` newtons on ``arm``'s wrist at ``at``: if the
    arm moves or pushes then and the force is above the threshold in force,
    a reflex-arc stop (S1.2, S1.7); it stands ``recovery`` seconds.

    ``force`` defaults to :data:`CRASH_FORCE` (50 N: above the default
    free-motion threshold, 5 N, and the built-in insertions' raised ones)."""

    kind: ClassVar[str] = "crash"
    arm: str
    at: float
    recovery: float = 1.0
    force: float = 50.0

    def __post_init__(self) -> None:
        _name(self, "arm")
        _time(self, "at")
        _time(self, "recovery")
        f = self.force
        if isinstance(f, bool) or not isinstance(f, int | float) or not 0 <= f <= MAX_FORCE:
            raise _bad(self, "force", f"must be in [0, {MAX_FORCE:g}] newtons, got {f!r}")
        object.__setattr__(self, "force", float(f))


@dataclass(frozen=True, slots=True)
class LostSync:
    """Stepper axis ``axis`` of ``arm`` loses ``steps`` steps at ``at`` (S1.6)."""

    kind: ClassVar[str] = "lost_sync"
    arm: str
    axis: int
    at: float
    steps: int = 40

    def __post_init__(self) -> None:
        _name(self, "arm")
        if isinstance(self.axis, bool) or not isinstance(self.axis, int) or self.axis < 0:
            raise _bad(self, "axis", f"must be an integer >= 0, got {self.axis!r}")
        _time(self, "at")
        s = self.steps
        if isinstance(s, bool) or not isinstance(s, int) or not 1 <= s <= 10**6:
            raise _bad(self, "steps", f"must be an integer in [1, 1e6], got {s!r}")


@dataclass(frozen=True, slots=True)
class MessageLoss:
    """Each frame (of ``kinds``, default every kind) is lost with ``probability``;
    the sender retransmits after ``timeout`` seconds."""

    kind: ClassVar[str] = "message_loss"
    probability: float
    kinds: tuple[str, ...] | None = None
    timeout: float = 0.005

    def __post_init__(self) -> None:
        p = self.probability
        if isinstance(p, bool) or not isinstance(p, int | float) or not 0.0 <= p <= MAX_LOSS:
            raise _bad(
                self,
                "probability",
                f"must be in [0, {MAX_LOSS:g}] (each frame is sent 1 / (1 - p) times on "
                f"average; a dead link is an arm_failure), got {p!r}",
            )
        object.__setattr__(self, "probability", float(p))
        if self.kinds is not None:
            kinds: object = self.kinds
            if not isinstance(kinds, tuple | list) or not all(
                isinstance(k, str) and k for k in kinds
            ):
                raise _bad(self, "kinds", f"must be a list of message kinds, got {self.kinds!r}")
            object.__setattr__(self, "kinds", tuple(self.kinds))
        timeout = self.timeout
        if _time(self, "timeout") < 1e-6:
            raise _bad(
                self, "timeout", f"must be in [1e-06, {MAX_SECONDS:g}] seconds, got {timeout!r}"
            )


@dataclass(frozen=True, slots=True)
class LatePart:
    """Part ``part`` arrives ``delay`` seconds late (``inf``: never)."""

    kind: ClassVar[str] = "late_part"
    part: str
    delay: float

    def __post_init__(self) -> None:
        _name(self, "part")
        delay = self.delay
        if _time(self, "delay", allow_inf=True) <= 0:
            raise _bad(self, "delay", f"must be > 0 seconds, got {delay!r}")


@dataclass(frozen=True, slots=True)
class EmergencyStop:
    """An alarm broadcast at ``at``: every arm stops for ``duration`` seconds."""

    kind: ClassVar[str] = "emergency_stop"
    at: float
    duration: float

    def __post_init__(self) -> None:
        _time(self, "at")
        _time(self, "duration")


@dataclass(frozen=True, slots=True)
class ActivateZones:
    """From ``at`` on (once every arm has stopped, S2.5), exactly ``zones`` are active."""

    kind: ClassVar[str] = "activate_zones"
    at: float
    zones: tuple[str, ...]

    def __post_init__(self) -> None:
        _time(self, "at")
        zones: object = self.zones
        if not isinstance(zones, tuple | list) or not all(isinstance(z, str) and z for z in zones):
            raise _bad(self, "zones", f"must be a list of zone names, got {self.zones!r}")
        object.__setattr__(self, "zones", tuple(self.zones))


Fault = ArmFailure | Crash | LostSync | MessageLoss | LatePart | EmergencyStop | ActivateZones
"""Any fault record."""

_KINDS: dict[str, type[Any]] = {
    c.kind: c
    for c in (ArmFailure, Crash, LostSync, MessageLoss, LatePart, EmergencyStop, ActivateZones)
}


class FaultPlan(Sequence[Fault]):
    """An immutable sequence of fault records (module docstring).

    Parameters
    ----------
    faults : iterable of fault records

    Raises
    ------
    ValidationError
        For an item that is not a fault record (named by index).
    """

    __slots__ = ("_faults",)

    def __init__(self, faults: Sequence[Fault] = ()) -> None:
        items = tuple(faults)
        for i, f in enumerate(items):
            if not isinstance(f, tuple(_KINDS.values())):
                raise ValidationError(
                    f"faults[{i}]: expected a fault record ({', '.join(sorted(_KINDS))}), got {f!r}"
                )
        self._faults: tuple[Fault, ...] = items

    def __len__(self) -> int:
        return len(self._faults)

    def __getitem__(self, i: int) -> Fault:  # type: ignore[override]
        return self._faults[i]

    def __iter__(self) -> Iterator[Fault]:
        return iter(self._faults)

    def __repr__(self) -> str:
        return f"FaultPlan({list(self._faults)!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, FaultPlan) and self._faults == other._faults

    def __hash__(self) -> int:
        return hash(self._faults)

    @classmethod
    def from_dicts(cls, records: Sequence[Mapping[str, Any]]) -> FaultPlan:
        """Build from plain dicts ``{"kind": "arm_failure", "arm": ..., "at": ...}``.

        Raises
        ------
        ValidationError
            Naming the record index and field.
        """
        if isinstance(records, str | bytes) or not isinstance(  # type: ignore[unreachable]
            records, Sequence
        ):
            raise ValidationError(f"faults: expected a list of records, got {records!r}")
        out: list[Fault] = []
        for i, rec in enumerate(records):
            if not isinstance(rec, Mapping):
                raise ValidationError(f"faults[{i}]: expected a table, got {rec!r}")
            kind = rec.get("kind")
            if not isinstance(kind, str) or kind not in _KINDS:
                raise ValidationError(
                    f"faults[{i}].kind: unknown fault kind {kind!r} (known: {', '.join(sorted(_KINDS))})"
                )
            cls_ = _KINDS[kind]
            names = [f.name for f in dataclasses.fields(cls_)]
            unknown = sorted(set(rec) - set(names) - {"kind"}, key=str)
            if unknown:
                raise ValidationError(
                    f"faults[{i}]: unknown field {unknown[0]!r} of a {kind} record "
                    f"(known: kind, {', '.join(names)})"
                )
            required = [
                f.name
                for f in dataclasses.fields(cls_)
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            ]
            for r in required:
                if r not in rec:
                    raise ValidationError(
                        f"faults[{i}]: missing field {r!r} (a {kind} record needs "
                        f"{', '.join(required)})"
                    )
            args = {k: v for k, v in rec.items() if k != "kind"}
            if isinstance(args.get("kinds"), list):
                args["kinds"] = tuple(args["kinds"])
            if isinstance(args.get("zones"), list):
                args["zones"] = tuple(args["zones"])
            try:
                out.append(cls_(**args))
            except ValidationError as exc:
                raise ValidationError(_field_path(exc, cls_, f"faults[{i}]")) from None
        return cls(out)

    def to_dicts(self) -> list[dict[str, Any]]:
        """Inverse of :meth:`from_dicts`."""
        out = []
        for f in self._faults:
            d: dict[str, Any] = {"kind": f.kind}
            d.update(
                {
                    k.name: (list(v) if isinstance(v, tuple) else v)
                    for k in dataclasses.fields(f)
                    for v in [getattr(f, k.name)]
                }
            )
            out.append(d)
        return out

    @classmethod
    def sample(
        cls,
        arms: Sequence[str],
        horizon: float,
        seed: int | np.random.Generator = 0,
        *,
        n: int = 2,
        kinds: Sequence[str] = ("crash", "emergency_stop", "message_loss", "arm_failure"),
    ) -> FaultPlan:
        """``n`` random records of the given kinds within ``[0, horizon)`` seconds.

        At most one :class:`ArmFailure` (never of every arm) and at most one
        :class:`MessageLoss` (a second draw of either becomes a crash).

        Examples
        --------
        >>> FaultPlan.sample(["a", "b"], 10.0, seed=1) == FaultPlan.sample(["a", "b"], 10.0, seed=1)
        True
        """
        if not arms:
            raise ValidationError("FaultPlan.sample: needs at least one arm")
        for k in kinds:
            if k not in _KINDS or k in ("late_part", "lost_sync", "activate_zones"):
                raise ValidationError(f"FaultPlan.sample: cannot sample fault kind {k!r}")
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        out: list[Fault] = []
        failed = lossy = False
        for _ in range(n):
            kind = str(kinds[int(rng.integers(len(kinds)))])
            at = float(rng.uniform(0.0, horizon))
            arm = str(arms[int(rng.integers(len(arms)))])
            if (kind == "arm_failure" and (failed or len(arms) < 2)) or (
                kind == "message_loss" and lossy
            ):
                kind = "crash"
            lossy = lossy or kind == "message_loss"
            if kind == "arm_failure":
                failed = True
                out.append(ArmFailure(arm, at))
            elif kind == "crash":
                out.append(Crash(arm, at, float(rng.uniform(0.2, 2.0))))
            elif kind == "emergency_stop":
                out.append(EmergencyStop(at, float(rng.uniform(0.1, 2.0))))
            else:
                out.append(MessageLoss(float(rng.uniform(0.0, 0.3))))
        return cls(out)


def as_plan(faults: FaultPlan | Sequence[Fault] | Sequence[Mapping[str, Any]] | None) -> FaultPlan:
    """A :class:`FaultPlan` from None, a plan, records or dicts.

    Raises
    ------
    ValidationError
        For anything else (named by index).
    """
    if faults is None:
        return FaultPlan()
    if isinstance(faults, FaultPlan):
        return faults
    if isinstance(faults, str | bytes) or not isinstance(  # type: ignore[unreachable]
        faults, Sequence
    ):
        raise ValidationError(
            f"faults must be None, a FaultPlan or a list of fault records, got {faults!r}"
        )
    items = list(faults)
    if items and all(isinstance(x, Mapping) for x in items):
        return FaultPlan.from_dicts(items)  # type: ignore[arg-type]
    return FaultPlan(items)  # type: ignore[arg-type]


def _unknown(where: str, what: str, value: str, known: Sequence[str]) -> ValidationError:
    close = difflib.get_close_matches(value, known, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    shown = ", ".join(known) if known else "none"
    return ValidationError(f"{where}: unknown {what} {value!r}{hint}; known: {shown}")


def check_fault_names(plan: FaultPlan, cell: Cell, *, source: str | None = None) -> None:
    """Refuse records of ``plan`` whose names do not fit ``cell``.

    The one implementation of these checks: :func:`workcell.faultcheck.check_faults`
    calls it before compiling, :func:`~workcell.sim.simulate` before running
    (the same messages). Refused: an arm, part or zone the cell does not
    have; a lost-sync axis the arm does not have or that is not a stepper
    axis; a message kind the protocol does not send (:data:`MESSAGE_KINDS`);
    two failures of one arm; more than one :class:`MessageLoss` record.

    Parameters
    ----------
    plan : FaultPlan
    cell : workcell.Cell
    source : str, optional
        The fault file's name, the first word of every message (``"faults"``
        when not given).

    Raises
    ------
    ValidationError
        ``"SOURCE: faults[i].field: what is wrong"``.
    """
    from workcell.arms.profiles import StepperDrive

    top = source if source is not None else "faults"
    arms = tuple(a.name for a in cell.arms)
    parts = sorted(set(cell.taskset.expected_arrivals()) | {x.id for x in cell.taskset.parts})
    zones = cell.zone_map.zone_names()  # the arm-pair zones are never activated
    failed: dict[str, int] = {}
    lossy: int | None = None
    for i, f in enumerate(plan):
        at = f"{top}: faults[{i}]"
        if isinstance(f, ArmFailure | Crash | LostSync) and f.arm not in arms:
            raise _unknown(f"{at}.arm", "arm", f.arm, arms)
        if isinstance(f, ArmFailure):
            if f.arm in failed:
                j = failed[f.arm]
                first = plan[j]
                assert isinstance(first, ArmFailure)
                raise ValidationError(
                    f"{at}.arm: arm {f.arm!r} already fails for good at {first.at:g} s "
                    f"(faults[{j}]); an arm fails once"
                )
            failed[f.arm] = i
        if isinstance(f, LostSync):
            arm = cell.arm(f.arm)
            if f.axis >= arm.dof:
                raise ValidationError(
                    f"{at}.axis: arm {f.arm!r} has axes 0 .. {arm.dof - 1}, not {f.axis}"
                )
            if not isinstance(arm.drives[f.axis], StepperDrive):
                raise ValidationError(
                    f"{at}.axis: axis {f.axis} of arm {f.arm!r} is a servo joint; only "
                    "stepper axes lose synchronism (S1.6)"
                )
        if isinstance(f, LatePart) and f.part not in parts:
            raise _unknown(f"{at}.part", "part", f.part, parts)
        if isinstance(f, ActivateZones):
            for k, z in enumerate(f.zones):
                if z not in zones:
                    raise _unknown(f"{at}.zones[{k}]", "zone", z, zones)
        if isinstance(f, MessageLoss):
            if lossy is not None:
                raise ValidationError(
                    f"{at}: a second message_loss record (the first is faults[{lossy}]); "
                    "give one record with every kind it applies to"
                )
            lossy = i
            for k, kind in enumerate(f.kinds or ()):
                if kind not in MESSAGE_KINDS:
                    raise _unknown(f"{at}.kinds[{k}]", "message kind", kind, MESSAGE_KINDS)
