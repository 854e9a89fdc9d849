"""A mutation check of the validator: every listed weakening is killed by the hand cases.

Each mutant is a small source edit of one function of the validator's logic
(:func:`scheduler.validate` and the helpers it relies on), compiled into a
copy and patched in for one run of the hand cases of
``test_validator_kills.py``. A mutant is killed when at least one hand case
fails: an invalid schedule accepted, or a valid neighbour refused. Production
code carries no test switch: the copies live only here.

``python -m tests.scheduler.test_validator_mutants`` prints the kill count.
"""

from __future__ import annotations

import inspect
import textwrap
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import cached_property
from typing import Any, NamedTuple

import pytest

import scheduler.schedule as sched_mod
import scheduler.timing as timing_mod
from multiarm.errors import ScheduleError
from tests.scheduler import test_validator_kills as kills


class Mutant(NamedTuple):
    name: str
    owner: Any  # the module or class that holds the function
    attr: str
    old: str
    new: str


_V = (sched_mod, "validate")
_R = (sched_mod.Schedule, "reservation_rows")

MUTANTS: list[Mutant] = [
    Mutant(
        "overlaps shorter than 1 s tolerated",
        *_V,
        "s2 >= e1 - tol",
        "s2 >= e1 - 1.0",
    ),
    Mutant("tolerance of half a second", *_V, "tol: float = 1e-6", "tol: float = 0.5"),
    Mutant(
        "arm availability ignored",
        *_V,
        "prev, ready = -1, float(p.arm_available[a])",
        "prev, ready = -1, 0.0",
    ),
    Mutant(
        "travel between tasks ignored",
        *_V,
        "need = ready + p.setup_time(a, prev, t)",
        "need = ready",
    ),
    Mutant("releases ignored", *_V, "if start[t] < release[t] - tol:", "if False:"),
    Mutant("precedence ignored", *_V, "if start[t] < end[q] - tol:", "if False:"),
    Mutant("ends not checked", *_V, "if abs(end[t] - expect) > tol:", "if False:"),
    Mutant("ends ignoring the detour", *_V, "sh.length(w) + blk[t]", "sh.length(w)"),
    Mutant("negative waits accepted", *_V, "or x < -tol", ""),
    Mutant("a mode of another task accepted", *_V, "or mode_task[m] != t:", ":"),
    Mutant("charged detours not checked", *_V, "if s.blocking[t] < need - tol:", "if False:"),
    Mutant(
        "a tool-conflict skip",
        *_V,
        "    for (kind, name), items in groups.items():\n",
        "    for (kind, name), items in groups.items():\n        if kind == 'tool':\n            continue\n",
    ),
    Mutant(
        "shared-zone movement not checked",
        *_V,
        "    for (kind, name), items in groups.items():\n",
        "    for (kind, name), items in groups.items():\n        if kind == 'move':\n            continue\n",
    ),
    Mutant(
        "exclusive zones not checked",
        *_V,
        "    for (kind, name), items in groups.items():\n",
        "    for (kind, name), items in groups.items():\n        if kind == 'zone':\n            continue\n",
    ),
    Mutant(
        "detours combined by max instead of sum",
        sched_mod,
        "blocking_required",
        "total += c",
        "total = max(total, c)",
    ),
    Mutant(
        "the initial pose never blocking",
        sched_mod,
        "blocking_required",
        "if pose is None:",
        "if pose is None or pose < 0:",
    ),
    Mutant(
        "a parked arm's departure ignoring its travel",
        sched_mod,
        "park_table",
        "depart = float(schedule.start[t]) - problem.setup_time(arm, prev, t)",
        "depart = float(schedule.start[t])",
    ),
    Mutant(
        "tools released at start + duration ignoring waits and detours",
        *_R,
        "float(self.end[t]),",
        "float(self.start[t]) + float(problem.mode_duration[int(self.mode[t])]),",
    ),
    Mutant("start zones ignored", *_R, "if problem.zone_exclusive[z]:", "if False:"),
    Mutant(
        "leaving a start zone at the task's start, travel ignored",
        sched_mod.Schedule,
        "departures",
        "float(self.start[seq[0]]) - problem.setup_time(a, -1, seq[0])",
        "float(self.start[seq[0]])",
    ),
    Mutant(
        "move windows in exclusive zones ignored",
        timing_mod.Shapes,
        "modes",
        "if p.zone_exclusive[z]:",
        "if p.zone_exclusive[z] and not p.win_move[w]:",
    ),
    Mutant(
        "occupy windows in shared zones counted as movement",
        timing_mod.Shapes,
        "modes",
        "elif p.win_move[w]:",
        "else:",
    ),
    Mutant(
        "waits inside an exclusive window not holding the zone",
        timing_mod.ModeShape,
        "intervals",
        "start + e + cw[bisect.bisect_left(borders, e)],",
        "start + e + cw[bisect.bisect_left(borders, s)],",
    ),
    Mutant(
        "a waiting arm counted as moving",
        timing_mod.ModeShape,
        "intervals",
        "cuts = [b for b in borders if s < b < e and wait_at[b] > 0]",
        "cuts = []",
    ),
    Mutant(
        "waits left out of a task's length",
        timing_mod.ModeShape,
        "length",
        "sum(waits.tolist())",
        "0.0",
    ),
]


def _function(owner: Any, attr: str) -> Callable[..., Any]:
    obj = inspect.getattr_static(owner, attr)
    if isinstance(obj, cached_property):
        return obj.func
    return obj  # type: ignore[no-any-return]


def _mutated(mutant: Mutant) -> Any:
    """The mutated copy of the function (wrapped like the original)."""
    fn = _function(mutant.owner, mutant.attr)
    src = textwrap.dedent(inspect.getsource(fn))
    count = src.count(mutant.old)
    assert count == 1, f"{mutant.name}: {mutant.old!r} found {count} times in {fn.__qualname__}"
    src = src.replace(mutant.old, mutant.new)
    src = "\n".join(ln for ln in src.splitlines() if not ln.lstrip().startswith("@cached_property"))
    ns: dict[str, Any] = dict(inspect.getmodule(fn).__dict__)
    exec(
        compile("from __future__ import annotations\n" + src, f"<mutant {mutant.name}>", "exec"), ns
    )
    new = ns[fn.__name__]
    if isinstance(inspect.getattr_static(mutant.owner, mutant.attr), cached_property):
        prop = cached_property(new)
        prop.__set_name__(mutant.owner, mutant.attr)
        return prop
    return new


@contextmanager
def _applied(mutant: Mutant) -> Iterator[None]:
    mp = pytest.MonkeyPatch()
    try:
        new = _mutated(mutant)
        mp.setattr(mutant.owner, mutant.attr, new)
        if mutant.owner is sched_mod and mutant.attr == "validate":
            mp.setattr(kills, "validate", new)  # the hand cases' own reference
        yield
    finally:
        mp.undo()


HAND_CASES = [f for n, f in sorted(vars(kills).items()) if n.startswith("test_") and callable(f)]


def killers(mutant: Mutant) -> list[str]:
    """The hand cases that fail with ``mutant`` applied."""
    out = []
    with _applied(mutant):
        for case in HAND_CASES:
            try:
                case()
            except (AssertionError, ScheduleError, pytest.fail.Exception):
                out.append(case.__name__)
    return out


def test_the_hand_cases_pass_on_the_real_validator() -> None:
    assert len(HAND_CASES) >= 20
    for case in HAND_CASES:
        case()


@pytest.mark.parametrize("mutant", MUTANTS, ids=[m.name for m in MUTANTS])
def test_every_mutant_is_killed(mutant: Mutant) -> None:
    assert killers(mutant), f"mutant survived: {mutant.name}"


def test_the_real_functions_are_restored() -> None:
    for m in MUTANTS:
        with _applied(m):
            assert _function(m.owner, m.attr).__code__.co_filename.startswith("<mutant")
    assert sched_mod.validate is getattr(kills, "validate")  # noqa: B009
    for m in MUTANTS:
        assert not _function(m.owner, m.attr).__code__.co_filename.startswith("<mutant")


def main() -> None:
    killed = 0
    for m in MUTANTS:
        who = killers(m)
        killed += bool(who)
        print(f"{'killed ' if who else 'SURVIVED'} {m.name}: {', '.join(who) or '-'}")
    print(f"{killed} of {len(MUTANTS)} validator mutants killed")


if __name__ == "__main__":
    main()
