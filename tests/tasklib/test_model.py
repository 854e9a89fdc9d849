"""Task-set records and validation (S2.10, S2.11): every defect is caught and named."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st

from multiarm.errors import CycleError, ValidationError
from tasklib import generate_taskset
from tasklib.arrivals import Feeder
from tasklib.model import Part, PartGroup, Task, TaskSet
from tasklib.pose import Pose
from tasklib.steps import Dwell, Grasp, Move, SetFlag, UseTool, WaitFlag
from tasklib.tdl import parse_tdl

D = (Dwell(1.0),)


def small() -> TaskSet:
    """A valid part-driven task set touching every kind of record."""
    return TaskSet(
        "small",
        (
            Task("base", (Grasp("b"), Move(trajectory="t")), consumes=("b",), produces=("sub",)),
            Task("left", (Grasp("l"),), consumes=("l", "sub")),
            Task("right", (Grasp("r"), SetFlag("go"))),
            Task("join", D),
            Task(
                "finish",
                (WaitFlag("go"), UseTool("press", 1.0)),
                tool="press",
                prerequisites=("join",),
            ),
        ),
        (
            Part("b", tasks=("base",)),
            Part("l", ("b",), ("left",)),
            Part("r", ("b",), ("right",)),
            Part("sub"),
        ),
        (Feeder("tray", ("b", "l", "r")),),
        (PartGroup("lr", ("l", "r"), ("join",)),),
        parse_tdl("trajectory t { taught { stop (0, 0, 1) } }"),
    )


def test_small_is_valid_and_precedence_folds_every_source() -> None:
    ts = small()
    pred = ts.precedence()
    assert pred["left"] == ("base",)  # part l needs part b (and the sub it consumes)
    assert set(pred["join"]) == {"left", "right"}  # group of l and r
    assert pred["finish"] == ("join",)
    assert ts.flag_edges() == (("right", "finish", "go"),)
    assert ts.depth() == 4
    assert ts.tools() == ("press",)
    assert ts.capabilities() == {"gripper", "tool_changer"}
    assert ts.gating_parts("base") == ("b",)
    assert ts.task("join").steps == D
    with pytest.raises(ValidationError, match="unknown task 'zz'"):
        ts.task("zz")


def test_taskless_fed_prerequisite_gates_by_arrival() -> None:
    ts = TaskSet(
        "g",
        (Task("t", D),),
        (Part("raw"), Part("p", ("raw",), ("t",))),
        (Feeder("f", ("raw",)),),
    )
    assert ts.gating_parts("t") == ("raw",)


def replace_task(
    ts: TaskSet, tid: str, extra_parts: tuple[Part, ...] = (), **changes: object
) -> TaskSet:
    tasks = tuple(dataclasses.replace(t, **changes) if t.id == tid else t for t in ts.tasks)
    return dataclasses.replace(ts, tasks=tasks, parts=(*ts.parts, *extra_parts))


DEFECTS: dict[str, tuple[Callable[[TaskSet], TaskSet], type[Exception], str]] = {
    "duplicate task": (
        lambda ts: dataclasses.replace(ts, tasks=(*ts.tasks, ts.tasks[0])),
        ValidationError,
        "duplicate task id 'base'",
    ),
    "duplicate part": (
        lambda ts: dataclasses.replace(ts, parts=(*ts.parts, Part("sub"))),
        ValidationError,
        "duplicate part id 'sub'",
    ),
    "unknown prerequisite": (
        lambda ts: replace_task(ts, "left", prerequisites=("ghost",)),
        ValidationError,
        "task 'left' requires unknown task 'ghost'",
    ),
    "unknown trajectory": (
        lambda ts: replace_task(ts, "join", steps=(Move(trajectory="nowhere"),)),
        ValidationError,
        "task 'join' step 1 \\(move\\) uses unknown trajectory 'nowhere'",
    ),
    "unknown part": (
        lambda ts: replace_task(ts, "join", consumes=("unobtainium",)),
        ValidationError,
        "task 'join' names unknown part 'unobtainium'",
    ),
    "never supplied": (
        lambda ts: replace_task(ts, "join", (Part("orphan"),), consumes=("orphan",)),
        ValidationError,
        "task 'join' consumes part 'orphan', which no feeder supplies",
    ),
    "cycle": (
        lambda ts: replace_task(ts, "base", prerequisites=("finish",)),
        CycleError,
        "cycle: .*base.*finish|cycle: .*finish.*base",
    ),
    "part cycle": (
        lambda ts: dataclasses.replace(
            ts,
            parts=tuple(
                dataclasses.replace(p, prerequisites=("r",)) if p.id == "b" else p for p in ts.parts
            ),
        ),
        CycleError,
        "part prerequisite cycle",
    ),
    "group not independent": (
        lambda ts: dataclasses.replace(ts, groups=(PartGroup("bad", ("b", "l")),)),
        ValidationError,
        "part group 'bad' parts are not independent: 'b' is a prerequisite of 'l'",
    ),
    "flag never set": (
        lambda ts: replace_task(ts, "join", steps=(WaitFlag("never"),)),
        ValidationError,
        "task 'join' waits for flag 'never', which no task sets",
    ),
    "fed twice": (
        lambda ts: dataclasses.replace(ts, feeders=(*ts.feeders, Feeder("tray2", ("b",)))),
        ValidationError,
        "part 'b' is supplied by feeders 'tray' and 'tray2'",
    ),
    "produced twice": (
        lambda ts: replace_task(ts, "join", produces=("sub",)),
        ValidationError,
        "part 'sub' is produced by tasks 'base' and 'join'",
    ),
    "fed and produced": (
        lambda ts: replace_task(ts, "join", produces=("r",)),
        ValidationError,
        "part 'r' is both supplied by feeder 'tray' and produced by task 'join'",
    ),
    "task owned twice": (
        lambda ts: dataclasses.replace(ts, groups=(PartGroup("lr", ("l", "r"), ("join", "left")),)),
        ValidationError,
        "task 'left' belongs to both part 'l' and part group 'lr'",
    ),
    "flag cycle": (
        lambda ts: replace_task(ts, "right", prerequisites=("finish",)),
        CycleError,
        "cycle",
    ),
}


@pytest.mark.parametrize("kind", sorted(DEFECTS))
def test_each_defect_is_caught_and_named(kind: str) -> None:
    inject, err, message = DEFECTS[kind]
    with pytest.raises(err, match=message):
        inject(small())


def test_cycle_error_carries_the_cycle() -> None:
    with pytest.raises(CycleError) as info:
        replace_task(small(), "base", prerequisites=("finish",))
    cyc = info.value.cycle
    assert cyc[0] == cyc[-1] and {"base", "finish"} <= set(cyc)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Task("t", ()), "has no step"),
        (lambda: Task("", D), "task id"),
        (lambda: Task("t", ("dwell",)), "not a step primitive"),  # type: ignore[arg-type]
        (lambda: Task("t", D, prerequisites=("t",)), "itself"),
        (lambda: Task("t", D, prerequisites="abc"), "list of names"),  # type: ignore[arg-type]
        (lambda: Task("t", D, consumes=("a", "a")), "twice"),
        (lambda: Task("t", D, consumes=("a",), produces=("a",)), "both consumes and produces"),
        (lambda: Task("t", (UseTool("drill", 1.0),)), "declares no tool"),
        (lambda: Task("t", (UseTool("drill", 1.0),), tool="press"), "declares tool 'press'"),
        (lambda: Part("p", ("p",)), "itself"),
        (lambda: PartGroup("g", ("a",)), "at least two"),
        (lambda: TaskSet("x", ()), "has no task"),
        (lambda: TaskSet("x", (Task("t", D),), parts=("p",)), "Part records"),  # type: ignore[arg-type]
    ],
)
def test_record_level_errors(make, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValidationError, match=message):
        make()


def test_non_finite_coordinates_are_rejected() -> None:
    with pytest.raises(ValidationError, match="non-finite"):
        Task("t", (Move(target=Pose((0.0, float("nan"), 0.0))),))


# ---- property: defects injected into random generated task sets are caught

Case = tuple[Callable[[], object], str, type[Exception], str]


@st.composite
def defect_cases(draw: st.DrawFn) -> Case:
    ts = generate_taskset(draw(st.integers(8, 40)), seed=draw(st.integers(0, 10_000)))
    ids = [t.id for t in ts.tasks]
    kinds = ["duplicate", "unknown", "cycle", "unsupplied", "nonfinite", "trajectory", "flag"]
    kind = draw(st.sampled_from(kinds))
    victim = draw(st.sampled_from(ids))
    old = ts.task(victim)
    if kind == "duplicate":
        return (
            lambda: dataclasses.replace(ts, tasks=(*ts.tasks, old)),
            kind,
            ValidationError,
            f"duplicate task id '{victim}'",
        )
    if kind == "unknown":
        return (
            lambda: replace_task(ts, victim, prerequisites=("no_such_task",)),
            kind,
            ValidationError,
            f"task '{victim}' requires unknown task 'no_such_task'",
        )
    if kind == "cycle":
        pred = ts.precedence()
        with_pred = [t for t in ids if pred[t]]
        if not with_pred:
            return (
                lambda: replace_task(ts, victim, prerequisites=(victim,)),
                kind,
                CycleError,
                "itself",
            )
        t = draw(st.sampled_from(with_pred))
        p = pred[t][0]
        before = ts.task(p).prerequisites
        # the cycle closes through t and p: both must be named
        return (
            lambda: replace_task(ts, p, prerequisites=(*before, t)),
            kind,
            CycleError,
            f"cycle: (?=.*'?\\b{t}\\b)(?=.*\\b{p}\\b)",
        )
    if kind == "unsupplied":
        return (
            lambda: replace_task(
                ts, victim, (Part("ghost_part"),), consumes=(*old.consumes, "ghost_part")
            ),
            kind,
            ValidationError,
            f"task '{victim}' consumes part 'ghost_part', which no feeder",
        )
    if kind == "trajectory":
        return (
            lambda: replace_task(ts, victim, steps=(*old.steps, Move(trajectory="ghost"))),
            kind,
            ValidationError,
            f"task '{victim}' step {len(old.steps) + 1} \\(move\\) uses unknown trajectory 'ghost'",
        )
    if kind == "flag":
        return (
            lambda: replace_task(ts, victim, steps=(*old.steps, WaitFlag("ghost_flag"))),
            kind,
            ValidationError,
            f"task '{victim}' waits for flag 'ghost_flag'",
        )
    coord = draw(st.sampled_from([float("inf"), float("-inf"), float("nan")]))
    return (
        lambda: replace_task(ts, victim, steps=(Move(target=Pose((0.0, coord, 0.0))),)),
        kind,
        ValidationError,
        "non-finite",
    )


@given(defect_cases())
def test_injected_defects_are_always_caught(case: Case) -> None:
    build, _kind, err, message = case
    with pytest.raises(err, match=message):
        build()


@given(st.integers(1, 120), st.integers(0, 1000))
def test_generated_task_sets_are_valid_and_sized(n: int, seed: int) -> None:
    ts = generate_taskset(n, seed=seed)
    assert len(ts.tasks) == n
    assert ts == generate_taskset(n, seed=seed)
