"""Faults and disturbances injected into a simulated run, described as data.

Every record is a frozen dataclass checked on construction
(:class:`~multiarm.errors.ValidationError` naming the field). A
:class:`FaultPlan` is a tuple of records, built directly, from plain dicts
(:meth:`FaultPlan.from_dicts`, errors name the record index and field), or
drawn at random with a seed (:meth:`FaultPlan.sample`).

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
multiarm.errors.ValidationError: faults[0] (crash): missing field 'at'
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from multiarm.errors import ValidationError

__all__ = [
    "ActivateZones",
    "ArmFailure",
    "Crash",
    "EmergencyStop",
    "Fault",
    "FaultPlan",
    "LatePart",
    "LostSync",
    "MessageLoss",
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


def _time(value: object, what: str, *, allow_inf: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValidationError(f"{what} must be a number, got {value!r}")
    v = float(value)
    if math.isnan(v) or (not 0 <= v <= MAX_SECONDS and not (allow_inf and v == math.inf)):
        raise ValidationError(
            f"{what} must be in [0, {MAX_SECONDS:g}] seconds{' or inf' if allow_inf else ''}, "
            f"got {value!r}"
        )
    return v


def _name(value: object, what: str) -> str:
    if not isinstance(value, str) or not value:
        raise ValidationError(f"{what} must be a non-empty string, got {value!r}")
    return value


@dataclass(frozen=True, slots=True)
class ArmFailure:
    """Arm ``arm`` fails for good at time ``at`` (seconds)."""

    kind: ClassVar[str] = "arm_failure"
    arm: str
    at: float

    def __post_init__(self) -> None:
        _name(self.arm, "ArmFailure.arm")
        object.__setattr__(self, "at", _time(self.at, "ArmFailure.at"))


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
        _name(self.arm, "Crash.arm")
        object.__setattr__(self, "at", _time(self.at, "Crash.at"))
        object.__setattr__(self, "recovery", _time(self.recovery, "Crash.recovery"))
        f = self.force
        if isinstance(f, bool) or not isinstance(f, int | float) or not 0 <= f <= MAX_FORCE:
            raise ValidationError(f"Crash.force must be in [0, {MAX_FORCE:g}] newtons, got {f!r}")
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
        _name(self.arm, "LostSync.arm")
        if isinstance(self.axis, bool) or not isinstance(self.axis, int) or self.axis < 0:
            raise ValidationError(f"LostSync.axis must be an integer >= 0, got {self.axis!r}")
        object.__setattr__(self, "at", _time(self.at, "LostSync.at"))
        s = self.steps
        if isinstance(s, bool) or not isinstance(s, int) or not 1 <= s <= 10**6:
            raise ValidationError(f"LostSync.steps must be an integer in [1, 1e6], got {s!r}")


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
            raise ValidationError(
                f"MessageLoss.probability must be in [0, {MAX_LOSS:g}] (each frame is sent "
                f"1 / (1 - p) times on average; a dead link is an arm_failure), got {p!r}"
            )
        object.__setattr__(self, "probability", float(p))
        if self.kinds is not None:
            kinds: object = self.kinds
            if not isinstance(kinds, tuple | list) or not all(
                isinstance(k, str) and k for k in kinds
            ):
                raise ValidationError(
                    f"MessageLoss.kinds must be a list of message kinds, got {self.kinds!r}"
                )
            object.__setattr__(self, "kinds", tuple(self.kinds))
        t = _time(self.timeout, "MessageLoss.timeout")
        if t < 1e-6:
            raise ValidationError(
                f"MessageLoss.timeout must be in [1e-06, {MAX_SECONDS:g}] seconds, "
                f"got {self.timeout!r}"
            )
        object.__setattr__(self, "timeout", t)


@dataclass(frozen=True, slots=True)
class LatePart:
    """Part ``part`` arrives ``delay`` seconds late (``inf``: never)."""

    kind: ClassVar[str] = "late_part"
    part: str
    delay: float

    def __post_init__(self) -> None:
        _name(self.part, "LatePart.part")
        d = _time(self.delay, "LatePart.delay", allow_inf=True)
        if d <= 0:
            raise ValidationError(f"LatePart.delay must be > 0 seconds, got {self.delay!r}")
        object.__setattr__(self, "delay", d)


@dataclass(frozen=True, slots=True)
class EmergencyStop:
    """An alarm broadcast at ``at``: every arm stops for ``duration`` seconds."""

    kind: ClassVar[str] = "emergency_stop"
    at: float
    duration: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "at", _time(self.at, "EmergencyStop.at"))
        object.__setattr__(self, "duration", _time(self.duration, "EmergencyStop.duration"))


@dataclass(frozen=True, slots=True)
class ActivateZones:
    """From ``at`` on (once every arm has stopped, S2.5), exactly ``zones`` are active."""

    kind: ClassVar[str] = "activate_zones"
    at: float
    zones: tuple[str, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "at", _time(self.at, "ActivateZones.at"))
        zones: object = self.zones
        if not isinstance(zones, tuple | list) or not all(isinstance(z, str) and z for z in zones):
            raise ValidationError(
                f"ActivateZones.zones must be a list of zone names, got {self.zones!r}"
            )
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
            unknown = sorted(set(rec) - set(names) - {"kind"})
            if unknown:
                raise ValidationError(
                    f"faults[{i}] ({kind}): unknown field {unknown[0]!r} (known: {', '.join(names)})"
                )
            required = [
                f.name
                for f in dataclasses.fields(cls_)
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            ]
            for r in required:
                if r not in rec:
                    raise ValidationError(f"faults[{i}] ({kind}): missing field {r!r}")
            args = {k: v for k, v in rec.items() if k != "kind"}
            if isinstance(args.get("kinds"), list):
                args["kinds"] = tuple(args["kinds"])
            if isinstance(args.get("zones"), list):
                args["zones"] = tuple(args["zones"])
            try:
                out.append(cls_(**args))
            except ValidationError as exc:
                raise ValidationError(f"faults[{i}] ({kind}): {exc}") from None
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
