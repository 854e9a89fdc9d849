"""Feeders and part-arrival models (SEEDS.md S2.11: parts arrive in no fixed
order, time or position).

A :class:`Feeder` supplies a list of parts at a place in the cell; its
``arrival`` model says when each part shows up, and ``position_sigma`` how far
from the nominal place an arriving part may lie (isotropic normal error, one
standard deviation in metres per axis). Random models draw only from the
generator passed to :meth:`sample`; the same seed gives the same arrivals.

Examples
--------
>>> f = Feeder("tray", ("a", "b", "c"), (0.0, 0.5, 0.0), PoissonArrivals(rate=0.5))
>>> [a.part for a in f.sample(seed=1)] == [a.part for a in f.sample(seed=1)]
True
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike, fspath
from typing import ClassVar, TypeAlias

import numpy as np

from multiarm.errors import FormatError, ValidationError
from multiarm.types import FloatArray, Point3, Seed, as_rng
from tasklib.pose import Pose

__all__ = [
    "ARRIVAL_MODELS",
    "ArrivalModel",
    "Feeder",
    "FixedArrivals",
    "PartArrival",
    "PoissonArrivals",
    "TraceArrivals",
    "UniformArrivals",
]


def _finite_nonneg(v: float, what: str) -> float:
    x = float(v)
    if not (math.isfinite(x) and x >= 0.0):
        raise ValidationError(f"{what} must be finite and >= 0, got {v!r}")
    return x


@dataclass(frozen=True, slots=True)
class FixedArrivals:
    """Every part arrives at a given time: ``times`` is ``((part, t), ...)``."""

    model: ClassVar[str] = "fixed"
    times: tuple[tuple[str, float], ...]

    def __post_init__(self) -> None:
        cleaned = []
        for item in self.times:
            try:
                part, t = item
            except (TypeError, ValueError):
                raise ValidationError(
                    f"fixed arrival entries are (part, time), got {item!r}"
                ) from None
            cleaned.append((str(part), _finite_nonneg(t, f"arrival time of part {part!r}")))
        object.__setattr__(self, "times", tuple(cleaned))
        seen = [p for p, _ in cleaned]
        dup = {p for p in seen if seen.count(p) > 1}
        if dup:
            raise ValidationError(f"fixed arrivals list part {sorted(dup)[0]!r} twice")

    def parts(self) -> tuple[str, ...]:
        return tuple(p for p, _ in self.times)

    def sample(self, parts: Sequence[str], rng: np.random.Generator) -> dict[str, float]:
        table = dict(self.times)
        missing = [p for p in parts if p not in table]
        if missing:
            raise ValidationError(f"fixed arrivals give no time for part {missing[0]!r}")
        return {p: table[p] for p in parts}

    def expected(self, parts: Sequence[str]) -> dict[str, float]:
        """Each part's expected arrival time: its fixed time."""
        return self.sample(parts, np.random.default_rng(0))


@dataclass(frozen=True, slots=True)
class PoissonArrivals:
    """Parts arrive one by one with exponential gaps of mean ``1/rate`` seconds,
    from ``start``; in random order unless ``ordered`` (then in the feeder's order).
    """

    model: ClassVar[str] = "poisson"
    rate: float
    start: float = 0.0
    ordered: bool = False

    def __post_init__(self) -> None:
        r = float(self.rate)
        if not (math.isfinite(r) and r > 0):
            raise ValidationError(f"poisson arrival rate must be finite and > 0, got {self.rate!r}")
        object.__setattr__(self, "rate", r)
        object.__setattr__(self, "start", _finite_nonneg(self.start, "poisson arrival start"))
        object.__setattr__(self, "ordered", bool(self.ordered))

    def sample(self, parts: Sequence[str], rng: np.random.Generator) -> dict[str, float]:
        times = self.start + np.cumsum(rng.exponential(1.0 / self.rate, size=len(parts)))
        order = list(parts) if self.ordered else [parts[i] for i in rng.permutation(len(parts))]
        return {p: float(t) for p, t in zip(order, times, strict=True)}

    def expected(self, parts: Sequence[str]) -> dict[str, float]:
        """Each part's expected arrival time.

        The k-th arrival (1-based) is expected at ``start + k / rate``; in
        feeder order when ``ordered``, else every part is equally likely to
        be any of the n arrivals, so each expects ``start + (n + 1) / (2 rate)``.

        Examples
        --------
        >>> PoissonArrivals(2.0, start=1.0, ordered=True).expected(["a", "b"])
        {'a': 1.5, 'b': 2.0}
        >>> PoissonArrivals(2.0, start=1.0).expected(["a", "b"])
        {'a': 1.75, 'b': 1.75}
        """
        n = len(parts)
        if self.ordered:
            return {p: self.start + (k + 1) / self.rate for k, p in enumerate(parts)}
        return {p: self.start + (n + 1) / (2 * self.rate) for p in parts}


@dataclass(frozen=True, slots=True)
class UniformArrivals:
    """Each part arrives independently at a uniform time in ``[low, high]``."""

    model: ClassVar[str] = "uniform"
    low: float
    high: float

    def __post_init__(self) -> None:
        lo = _finite_nonneg(self.low, "uniform arrival low")
        hi = _finite_nonneg(self.high, "uniform arrival high")
        if hi < lo:
            raise ValidationError(f"uniform arrivals need low <= high, got [{lo}, {hi}]")
        object.__setattr__(self, "low", lo)
        object.__setattr__(self, "high", hi)

    def sample(self, parts: Sequence[str], rng: np.random.Generator) -> dict[str, float]:
        t = rng.uniform(self.low, self.high, size=len(parts))
        return {p: float(x) for p, x in zip(parts, t, strict=True)}

    def expected(self, parts: Sequence[str]) -> dict[str, float]:
        """Each part's expected arrival time: the middle of ``[low, high]``."""
        return {p: (self.low + self.high) / 2 for p in parts}


@dataclass(frozen=True, slots=True)
class TraceArrivals:
    """Arrivals replayed from a recorded trace: ``events`` is ``((t, part), ...)``."""

    model: ClassVar[str] = "trace"
    events: tuple[tuple[float, str], ...]
    source: str | None = None

    def __post_init__(self) -> None:
        cleaned = []
        for item in self.events:
            try:
                t, part = item
            except (TypeError, ValueError):
                raise ValidationError(f"trace events are (time, part), got {item!r}") from None
            cleaned.append((_finite_nonneg(t, f"trace time of part {part!r}"), str(part)))
        object.__setattr__(self, "events", tuple(cleaned))
        seen = [p for _, p in cleaned]
        dup = {p for p in seen if seen.count(p) > 1}
        if dup:
            raise ValidationError(f"arrival trace lists part {sorted(dup)[0]!r} twice")

    @classmethod
    def from_csv(cls, path: str | PathLike[str]) -> TraceArrivals:
        """Read a trace from a CSV file with columns ``time,part`` (header required)."""
        name = fspath(path)
        try:
            with open(name, newline="", encoding="utf-8") as fh:
                rows = list(csv.reader(fh))
        except OSError as exc:
            raise FormatError(f"cannot read arrival trace: {exc.strerror}", filename=name) from None
        if not rows or [c.strip() for c in rows[0]] != ["time", "part"]:
            raise FormatError(
                "arrival trace must start with the header 'time,part'", filename=name, line=1
            )
        events = []
        for i, row in enumerate(rows[1:], start=2):
            if not row or all(not c.strip() for c in row):
                continue
            if len(row) != 2:
                raise FormatError(f"expected 2 columns, got {len(row)}", filename=name, line=i)
            try:
                t = float(row[0])
            except ValueError:
                raise FormatError(
                    f"time {row[0]!r} is not a number", filename=name, line=i
                ) from None
            events.append((t, row[1].strip()))
        try:
            return cls(tuple(events), source=name)
        except ValidationError as exc:
            raise FormatError(str(exc), filename=name) from None

    def sample(self, parts: Sequence[str], rng: np.random.Generator) -> dict[str, float]:
        table = {p: t for t, p in self.events}
        missing = [p for p in parts if p not in table]
        if missing:
            raise ValidationError(f"arrival trace has no event for part {missing[0]!r}")
        return {p: table[p] for p in parts}

    def expected(self, parts: Sequence[str]) -> dict[str, float]:
        """Each part's arrival time in the trace (a trace is one known outcome)."""
        return self.sample(parts, np.random.default_rng(0))


ArrivalModel: TypeAlias = FixedArrivals | PoissonArrivals | UniformArrivals | TraceArrivals
"""Any arrival model."""

ARRIVAL_MODELS: dict[str, type] = {
    c.model: c for c in (FixedArrivals, PoissonArrivals, UniformArrivals, TraceArrivals)
}


@dataclass(frozen=True, slots=True)
class PartArrival:
    """One sampled arrival: ``part`` from ``feeder`` at ``time`` seconds,
    lying at ``position`` (metres, cell frame; nominal place + sampled error)."""

    part: str
    feeder: str
    time: float
    position: Point3


@dataclass(frozen=True, slots=True)
class Feeder:
    """A place where parts enter the cell.

    Parameters
    ----------
    id : str
    parts : tuple of str
        The parts it supplies (each part has at most one feeder).
    position : (3,) float, metres
        Nominal pick-up position in the cell frame.
    arrival : ArrivalModel
        When the parts arrive (defaults to all at time 0).
    position_sigma : float, metres
        Standard deviation of an arriving part's position error per axis;
        0 for an exact feeder. Large values model parts that must be found
        with the object detector (S1.8).
    """

    id: str
    parts: tuple[str, ...]
    position: Point3 = (0.0, 0.0, 0.0)
    arrival: ArrivalModel = FixedArrivals(())
    position_sigma: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not self.id:
            raise ValidationError(f"feeder id must be a non-empty name, got {self.id!r}")
        object.__setattr__(self, "parts", tuple(self.parts))
        if not self.parts:
            raise ValidationError(f"feeder {self.id!r} supplies no part")
        if len(set(self.parts)) != len(self.parts):
            raise ValidationError(f"feeder {self.id!r} lists a part twice")
        object.__setattr__(self, "position", Pose(self.position).position)
        if not isinstance(self.arrival, tuple(ARRIVAL_MODELS.values())):
            raise ValidationError(f"feeder {self.id!r}: arrival must be an arrival model")
        if isinstance(self.arrival, FixedArrivals) and not self.arrival.times:
            object.__setattr__(self, "arrival", FixedArrivals(tuple((p, 0.0) for p in self.parts)))
        if isinstance(self.arrival, FixedArrivals):
            extra = set(self.arrival.parts()) - set(self.parts)
            if extra:
                raise ValidationError(
                    f"feeder {self.id!r}: fixed arrivals name part {sorted(extra)[0]!r} it does not supply"
                )
        object.__setattr__(
            self,
            "position_sigma",
            _finite_nonneg(self.position_sigma, f"feeder {self.id!r} position_sigma"),
        )

    def sample(self, seed: Seed = 0) -> tuple[PartArrival, ...]:
        """Sample the arrivals of this feeder's parts, sorted by time."""
        rng = as_rng(seed)
        try:
            times = self.arrival.sample(self.parts, rng)
        except ValidationError as exc:
            raise ValidationError(f"feeder {self.id!r}: {exc}") from None
        base = np.asarray(self.position)
        errors: FloatArray = (
            rng.normal(0.0, self.position_sigma, size=(len(self.parts), 3))
            if self.position_sigma > 0
            else np.zeros((len(self.parts), 3))
        )
        out = []
        for p, err in zip(self.parts, errors, strict=True):
            x, y, z = (base + err).tolist()
            out.append(PartArrival(p, self.id, times[p], (x, y, z)))
        out.sort(key=lambda a: (a.time, a.part))
        return tuple(out)

    def expected(self) -> dict[str, float]:
        """Each supplied part's expected arrival time (seconds), by part id.

        Fixed and traced times are exact; a Poisson stream's k-th part is
        expected at ``start + k / rate``; a uniform window's middle.

        Examples
        --------
        >>> Feeder("tray", ("a", "b"), arrival=UniformArrivals(2.0, 4.0)).expected()
        {'a': 3.0, 'b': 3.0}
        """
        try:
            return self.arrival.expected(self.parts)
        except ValidationError as exc:
            raise ValidationError(f"feeder {self.id!r}: {exc}") from None
