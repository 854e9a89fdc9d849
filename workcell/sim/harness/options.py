"""``SimOptions``: the settings of one :func:`workcell.simulate` run.

One frozen record, checked on construction: a bad value raises
:class:`~multiarm.errors.UsageError` naming the field.

Examples
--------
>>> SimOptions(resolve=False).resolve
False
>>> SimOptions(tick=0.0)
Traceback (most recent call last):
...
multiarm.errors.UsageError: SimOptions.tick must be None or a period in [1e-05, 0.1] seconds, got 0.0
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

from multiarm.errors import UsageError
from workcell.sim.control.force import FREE_THRESHOLD, HOLE_SIGMA, check_insertion
from workcell.sim.protocol.exchange import ArmView

__all__ = ["CONTROL_TIME", "COORDINATION_POLICIES", "RANGES", "GuardAnswer", "SimOptions"]

CONTROL_TIME = 1.25e-4
"""Seconds of one CPU's time to control one arm for one sampling period
(S2.2: an i860 ran 8 four-axis SCARA arms at 1 ms, so at most 1/8 ms each)."""

COORDINATION_POLICIES: tuple[str, ...] = ("centralized", "distributed")
"""The coordination policies :func:`workcell.simulate` knows (S2.7's
centralized coordinator)."""


GuardAnswer = Callable[[ArmView, Sequence[ArmView]], Sequence[int]]
"""``answer(mover, book) -> indices of the arms in mover's way``: a stand-in
for the coordinator's geometric check (:attr:`SimOptions.guard_answer`);
``mover`` is the departure request's view, ``book`` the coordination's
views of every arm with ``mover`` in its own place."""


RANGES: dict[str, tuple[float, float]] = {
    "resolve_budget": (1e-6, 1e6),
    "tick": (1e-5, 0.1),
    "monitor_period": (1e-4, 1.0),
    "control_time": (1e-7, 0.1),
    "detour_checks": (1, 10_000_000),
}
"""Physical range of each numeric field, seconds unless said: a controller
samples every 10 us to 100 ms (S2.2: 1 ms), the monitor at least once a
second and at most every 0.1 ms (finer samples cost time without finding
more); ``detour_checks`` counts configuration checks (about 10 us each, so
at most about 100 s of planning per detour)."""


def _positive(name: str, value: object, unit: str) -> float:
    lo, hi = RANGES[name]
    if isinstance(value, bool) or not isinstance(value, int | float) or not lo <= value <= hi:
        raise UsageError(f"SimOptions.{name} must be in [{lo:g}, {hi:g}] {unit}, got {value!r}")
    return float(value)


def _flag(name: str, value: object) -> bool:
    if not isinstance(value, bool):
        raise UsageError(f"SimOptions.{name} must be True or False, got {value!r}")
    return value


@dataclass(frozen=True, slots=True)
class SimOptions:
    """How :func:`workcell.simulate` runs (every field optional).

    Attributes
    ----------
    resolve : bool
        Re-solve (:func:`scheduler.reschedule`) when an arm fails, a part
        comes late or a detour costs more than planned. ``False`` keeps the
        plan: the following tasks wait, a failed arm's tasks are reported
        failed (for comparing runs with and without re-solving).
    resolve_budget : float
        Real-time budget of one re-solve, seconds (latency measured and
        reported against it; decisions never depend on wall time).
    resolve_evaluations : int, optional
        Work limit of one re-solve (schedules decoded by the local search);
        default ``max(5, 2000 // tasks)``.
    tick : float, optional
        Sampling period (seconds) to model every controller tick (S2.3);
        ``None``: event level (idle ticks skipped; the pipeline offset is
        then computed for a 1 ms period).
    monitor : bool or {"live", "post"}
        The independent safety monitor: ``True`` or ``"live"`` checks
        during the run and stops it at the first violating sample;
        ``"post"`` checks the finished run; ``False``: off.
    monitor_period : float
        Seconds between the monitor's collision samples.
    control_time : float
        Per-arm control time per sampling period (S2.2 bound, checked when
        ``tick`` is given).
    insertion : {"planned", "drawn"}
        ``"planned"``: every insertion takes the tries the compile planned.
        ``"drawn"``: each insert step's hole position error is drawn (seeded
        per task) and the force-guided search simulated (S1.7).
    insertion_sigma : float
        Standard deviation of a hole's lateral position error, metres per
        axis (``insertion="drawn"``).
    insertion_tolerance : float, optional
        A try lands when within this many metres of the hole on both axes;
        default half the search step.
    force_threshold : float or mapping of str -> float
        The wrist force sensors' free-motion threshold, newtons (one value,
        or per arm name; kept as a read-only mapping).
    zone_protocol : bool
        ``True``: the coordinator grants zones and tools through the zone
        manager in plan order (S2.5-S2.7). ``False`` grants every request at
        once and skips the schedule check: an ablation for testing the
        safety monitor, which must then catch the broken invariants.
    geometry_guard : bool
        ``True``: the coordinator's geometric check before each motion
        (S2.6, S2.12: stop, detour, back off). ``False`` lets arms move
        into each other: an ablation for testing the safety monitor.
    detours : bool
        ``True``: an arm the geometric check stops, with only standing arms
        in its way, gets S2.12's alternative trajectory (an OMPL path around
        them over the stretch of its motion that touches them). ``False``:
        it waits for the way to clear, or the standing arms back off (S2.6):
        an ablation for comparing runs with and without detours.
    detour_checks : int
        Work limit of one detour search, configuration checks: a search
        that needs more answers "no detour" (the same seed plans the same
        path on any machine).
    guard_answer : callable, optional
        ``guard_answer(mover, book) -> indices of the arms in mover's way``
        (``mover``: the view the arm sent with its departure request,
        ``book``: the coordination's last reported view of every arm, the
        mover in its own place; both
        :class:`~workcell.sim.protocol.exchange.ArmView`), asked in
        place of the coordinator's geometric check before each motion; only
        with ``geometry_guard``. ``None``: the check decides. An ablation for
        tests that need geometric stops (oscillating, permanent, on one
        stretch) that no built-in cell produces.
    strict : bool
        On a stall (an arm with work, no stop in force and no event pending:
        a bug of the simulator itself) raise
        :class:`~multiarm.errors.InternalError` instead of failing the task
        with a cause of kind ``"stall"`` (for tests and campaigns).
    """

    resolve: bool = True
    resolve_budget: float = 0.015
    resolve_evaluations: int | None = None
    tick: float | None = None
    monitor: bool | str = True
    monitor_period: float = 0.02
    control_time: float = CONTROL_TIME
    insertion: str = "planned"
    insertion_sigma: float = HOLE_SIGMA
    insertion_tolerance: float | None = None
    force_threshold: float | Mapping[str, float] = FREE_THRESHOLD
    zone_protocol: bool = True
    geometry_guard: bool = True
    detours: bool = True
    detour_checks: int = 10_000
    guard_answer: GuardAnswer | None = None
    strict: bool = False

    def __post_init__(self) -> None:
        for name in ("resolve", "zone_protocol", "geometry_guard", "detours", "strict"):
            _flag(name, getattr(self, name))
        lo, hi = RANGES["detour_checks"]
        dc = self.detour_checks
        if isinstance(dc, bool) or not isinstance(dc, int) or not lo <= dc <= hi:
            raise UsageError(
                f"SimOptions.detour_checks must be an integer in [{lo:g}, {hi:g}] "
                f"configuration checks, got {dc!r}"
            )
        if self.guard_answer is not None and not callable(self.guard_answer):
            raise UsageError(
                "SimOptions.guard_answer must be None or a callable (mover, arms) -> arm "
                f"indices, got {self.guard_answer!r}"
            )
        if not (isinstance(self.monitor, bool) or self.monitor in ("live", "post")):
            raise UsageError(
                f"SimOptions.monitor must be True, False, 'live' or 'post', got {self.monitor!r}"
            )
        object.__setattr__(
            self, "resolve_budget", _positive("resolve_budget", self.resolve_budget, "seconds")
        )
        object.__setattr__(
            self, "monitor_period", _positive("monitor_period", self.monitor_period, "seconds")
        )
        object.__setattr__(
            self, "control_time", _positive("control_time", self.control_time, "seconds")
        )
        ev = self.resolve_evaluations
        if ev is not None and (isinstance(ev, bool) or not isinstance(ev, int) or ev < 1):
            raise UsageError(
                f"SimOptions.resolve_evaluations must be None or an integer >= 1, got {ev!r}"
            )
        tick = self.tick
        if tick is not None:
            lo, hi = RANGES["tick"]
            if isinstance(tick, bool) or not isinstance(tick, int | float) or not lo <= tick <= hi:
                raise UsageError(
                    f"SimOptions.tick must be None or a period in [{lo:g}, {hi:g}] seconds, "
                    f"got {tick!r}"
                )
            object.__setattr__(self, "tick", float(tick))
        try:
            check_insertion(self.insertion, self.insertion_sigma, self.insertion_tolerance)
        except UsageError as exc:
            raise UsageError(str(exc).replace("simulate: ", "SimOptions.", 1)) from None
        ft = self.force_threshold
        values = list(ft.values()) if isinstance(ft, Mapping) else [ft]
        for v in values:
            if isinstance(v, bool) or not isinstance(v, int | float) or not 1e-6 <= v <= 1e6:
                raise UsageError(
                    "SimOptions.force_threshold must be a number in [1e-06, 1e+06] newtons or a "
                    f"mapping arm name -> newtons, got {ft!r}"
                )
        if isinstance(ft, Mapping):
            object.__setattr__(self, "force_threshold", MappingProxyType(dict(ft)))
