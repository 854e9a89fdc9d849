"""Regression: with re-solving off, a failed task's record carries the time its
failure became known.

``SimOptions(resolve=False)`` with an arm failure logged the ``task_failed``
records of the failed arm's tasks, and of the tasks after them, at the
kernel's horizon (``10 * makespan + 1e4`` s: 11463 s on ``scara4``), far past
the end of the run, and the task interrupted by the failure twice. Now the
coordinator fails them at the instant it learns they can no longer run under
the kept plan: a task of the failed arm at the arm's failure, a task after a
failed task when that predecessor failed. With re-solving on, the tasks no
working arm can do any more (and those after them) were logged at the
horizon too; they now fail at the re-solve that drops them. Checked over a seeded campaign of
failure times (uniform over the plan, and exactly at task starts and ends of
the fault-free run) on ``scara4`` and ``supersigma``, with one and two arms
failing, through the public records only (the trace and the tasks frame).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from workcell.sim import ArmFailure, SimOptions, simulate

KEPT = SimOptions(resolve=False, monitor=False)


def _episodes(cc: Any, plan: Any, seed: int, n: int) -> list[list[ArmFailure]]:
    """``n`` seeded fault plans: one or two arm failures at times drawn
    uniform over the plan or exactly at a task start or end of the
    fault-free run."""
    rng = np.random.default_rng(seed)
    ref = simulate(cc, plan, options=SimOptions(monitor=False)).tasks_frame()
    edges = np.concatenate([ref["start"].to_numpy(), ref["end"].to_numpy()])
    arms = list(cc.problem.arm_names)
    out: list[list[ArmFailure]] = []
    for i in range(n):
        k = 1 + int(rng.integers(2))
        chosen = rng.choice(len(arms), size=k, replace=False)
        faults = []
        for j, a in enumerate(chosen):
            if (i + j) % 2 == 0:
                at = float(edges[int(rng.integers(len(edges)))])
            else:
                at = float(rng.uniform(0.0, plan.makespan))
            faults.append(ArmFailure(arms[int(a)], at))
        out.append(faults)
    return out


def _check(r: Any, faults: list[ArmFailure]) -> None:
    failed_at = {f.arm: f.at for f in faults}
    tf = r.tasks_frame().set_index("task")
    lost = tf[tf["status"] == "failed"]
    # (re-solving on, a task interrupted by its arm's failure is noted, then
    # reassigned: that note is not its failure)
    records = [
        e
        for e in r.trace
        if e.kind == "task_failed" and not e.detail.endswith("reassigned by a re-solve")
    ]
    # one record per failed task, with the cause the tasks frame gives
    assert sorted(e.task for e in records) == sorted(lost.index), [e.task for e in records]
    when = {e.task: e.time for e in records}
    for e in records:
        assert e.detail == lost.loc[e.task, "cause"]
        assert e.time <= max(failed_at.values()) + 1e-9, (e.time, e.task, e.detail)
    for task, row in lost.iterrows():
        kind, cause = row["cause_kind"], row["cause"]
        if kind == "arm_out":  # its arm failed: known at the arm's failure
            assert when[task] == failed_at[row["arm"]], (task, cause)
        elif kind == "predecessor":  # known when the named predecessor failed
            pred = cause.split("'")[1]
            assert pred in when, (task, cause)
            assert when[task] == when[pred], (task, cause)
        else:  # every capable arm failed: known at the last of those failures
            assert kind == "arm_failed", (task, kind, cause)
            assert when[task] in set(failed_at.values()), (task, cause)


@pytest.mark.parametrize(
    ("name", "seed", "resolve", "n"),
    [("scara4", 0, False, 4), ("supersigma", 1, False, 5), ("supersigma", 2, True, 4)],
)
def test_failed_tasks_are_logged_when_their_failure_became_known(
    name: str, seed: int, resolve: bool, n: int, request: pytest.FixtureRequest
) -> None:
    """Re-solving off: every failed task. Re-solving on: the tasks no working
    arm can do (every capable arm failed) and the tasks after them, which
    the re-solve at the failure drops, fail then too (they were logged at
    the horizon as well)."""
    cc = request.getfixturevalue("scara4" if name == "scara4" else "cell")
    plan = request.getfixturevalue("scara4_plan" if name == "scara4" else "plan")
    options = SimOptions(resolve=resolve, monitor=False)
    for faults in _episodes(cc, plan, seed, n):
        r = simulate(cc, plan, faults=faults, options=options)
        _check(r, faults)


def test_the_arm_failure_time_is_the_record_time_not_the_horizon(
    scara4: Any, scara4_plan: Any
) -> None:
    """The case first seen: one arm of ``scara4`` fails a third of the way
    into the plan; before the fix its tasks were logged at 11463 s."""
    at = 0.3 * scara4_plan.makespan
    r = simulate(scara4, scara4_plan, faults=[ArmFailure("sw", at)], options=KEPT)
    times = {e.time for e in r.trace if e.kind == "task_failed"}
    assert r.metrics.failed_tasks > 0 and times == {at}
