"""workcell.simulate: the simulated coordination and control layers (S2.2-S2.7, S2.12).

The golden trace is regenerated with
``MULTIARM_REGEN_GOLDEN=1 .venv/bin/python -m pytest -p no:xdist -q
tests/workcell/sim/test_simulate.py -k golden`` (then review the diff).

The golden trace changed when S2.12's geometric check became frames of the
medium (``workcell.sim.protocol.exchange``, routed by
``workcell.sim.protocol.channel``): every departure is now a
``departure_request`` and a ``departure`` frame (and the other records of
the exchange are frames too), so they show as message rows with their
sizes, and the 10 % message loss of the scenario now also hits them: a
lost request or answer holds its arm until it is sent again 5 ms later,
and each arm's stream waits for a lost frame before it takes the later
ones. The executed makespan went from 164.669378 s to 166.316795 s. Before
that change the golden trace had stayed byte for byte the same when the
check became records on an instant channel, which showed that the
coordinator's book, built from the arms' reports alone, equals what it used
to read from the controllers.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from multiarm.errors import UsageError, ValidationError
from scheduler import Plan, Schedule, solve, validate
from workcell import compile_cell, load_example
from workcell.sim import (
    MESSAGE_BYTES,
    ActivateZones,
    Crash,
    EmergencyStop,
    FaultPlan,
    LostSync,
    MessageLoss,
    SafetyViolation,
    SimOptions,
    SimResult,
    simulate,
)
from workcell.sim.control.controller import INTERNAL_MESSAGES, pipeline_offset
from workcell.sim.events.trace import COLUMNS, Trace, TraceEvent
from workcell.sim.harness.simulate import check_control_bound

GOLDEN = Path(__file__).parent / "golden" / "supersigma_trace.json"


@pytest.fixture(scope="module")
def supersigma() -> Any:
    return compile_cell(load_example("supersigma"))


@pytest.fixture(scope="module")
def scara4() -> Any:
    return compile_cell(load_example("scara4"))


@pytest.fixture(scope="module")
def plans(supersigma: Any, scara4: Any) -> dict[str, dict[str, Schedule]]:
    out: dict[str, dict[str, Schedule]] = {}
    for name, cc in (("supersigma", supersigma), ("scara4", scara4)):
        out[name] = {}
        for solver, limit in (("greedy", 1.0), ("tree", 1.0), ("cpsat", 4.0)):
            r = solve(cc.problem, solver, time_limit=limit, seed=0)
            if r.schedule is not None:
                out[name][solver] = r.schedule
    return out


def _cc(name: str, supersigma: Any, scara4: Any) -> Any:
    return supersigma if name == "supersigma" else scara4


# ------------------------------------------------------------ fidelity


@pytest.mark.parametrize("cell", ["supersigma", "scara4"])
def test_the_executed_makespan_is_the_planned_one(
    cell: str, supersigma: Any, scara4: Any, plans: Any
) -> None:
    """Ideal medium, no fault, the S2.12 geometric check on: the compile's
    arm-pair zones keep arms that could meet apart in the plan, so the
    coordinator never has to stop an arm for geometry and executes exactly
    the schedule's timing (every solver's schedule)."""
    cc = _cc(cell, supersigma, scara4)
    assert {"greedy", "tree"} <= set(plans[cell])
    for solver, plan in plans[cell].items():
        r = simulate(cc, plan, options=SimOptions(monitor=False))
        assert r.metrics.failed_tasks == 0, solver
        assert abs(r.metrics.executed_makespan - plan.makespan) < 1e-6, solver
        assert not [e for e in r.trace if e.kind in ("sleep", "detour") and "geometr" in e.detail]
        assert r.executed is not None
        np.testing.assert_allclose(r.executed.start, plan.start, atol=1e-6)
        np.testing.assert_allclose(r.executed.end, plan.end, atol=1e-6)
        assert abs(validate(cc.problem, r.executed) - plan.makespan) < 1e-6
        # and the same without the geometric check
        off = simulate(cc, plan, options=SimOptions(monitor=False, geometry_guard=False))
        np.testing.assert_allclose(off.executed.start, plan.start, atol=1e-6)  # type: ignore[union-attr]


@pytest.mark.parametrize("cell", ["supersigma", "scara4"])
def test_coordinator_runs_are_safe_and_lose_nothing(
    cell: str, supersigma: Any, scara4: Any, plans: Any
) -> None:
    """With the geometric check and the safety monitor on: every task
    completes on time, the monitor stays silent (it raises otherwise), and
    every arm's utilisation is busy time / executed makespan, in [0, 1]."""
    cc = _cc(cell, supersigma, scara4)
    plan = plans[cell]["greedy"]
    r = simulate(cc, plan)
    assert r.metrics.done_tasks == cc.problem.n_tasks
    assert abs(r.metrics.executed_makespan - plan.makespan) < 1e-6
    assert all(0.0 <= u <= 1.0 for u in r.metrics.utilisation.values())


@pytest.mark.slow
def test_cell8_runs_as_planned_with_the_geometric_check_on() -> None:
    """cell8 (8 SCARAs, 200 tasks), greedy plan, ideal medium, no fault, the
    geometric check on: every task completes at its planned time (the
    compile's arm-pair zones; without them arms stalled in geometric
    deadlocks); an arm failure then loses only the tasks no working arm can
    do and their successors."""
    from workcell.sim import ArmFailure

    cc = compile_cell(load_example("cell8"))
    p = cc.problem
    plan = solve(p, "greedy", seed=0).schedule
    r = simulate(cc, plan, options=SimOptions(monitor=False))
    assert r.metrics.failed_tasks == 0
    assert abs(r.metrics.executed_makespan - plan.makespan) < 1e-6
    assert r.executed is not None
    np.testing.assert_allclose(r.executed.start, plan.start, atol=1e-6)
    a = p.arm_names.index("s4")
    f = simulate(
        cc, plan, faults=[ArmFailure("s4", 0.6 * plan.makespan)], options=SimOptions(monitor=False)
    )
    status = dict(zip(f.tasks_frame()["task"], f.tasks_frame()["status"], strict=True))
    dead: dict[int, bool] = {}
    for t in p.topological_order:
        dead[t] = status[p.task_names[t]] != "done" and (
            all(int(p.mode_arm[m]) == a for m in p.task_modes[t])
            or any(dead[q] for q in p.task_preds[t])
        )
    assert f.metrics.failed_tasks == sum(dead.values())


def test_tick_mode_models_every_tick_with_the_same_decisions(supersigma: Any, plans: Any) -> None:
    plan = plans["supersigma"]["greedy"]
    ev = simulate(supersigma, plan, options=SimOptions(monitor=False, geometry_guard=False))
    tk = simulate(
        supersigma, plan, options=SimOptions(tick=1e-3, monitor=False, geometry_guard=False)
    )
    assert tk.metrics.executed_makespan == ev.metrics.executed_makespan
    assert tk.metrics.ticks >= int(0.9 * ev.metrics.executed_makespan / 1e-3)
    assert ev.metrics.ticks == 0


def test_the_same_seed_gives_the_same_trace(supersigma: Any, plans: Any) -> None:
    plan = plans["supersigma"]["greedy"]
    faults = [MessageLoss(0.2), Crash("left", 20.0, 0.5)]
    a = simulate(supersigma, plan, seed=5, faults=faults, options=SimOptions(monitor=False))
    b = simulate(supersigma, plan, seed=5, faults=faults, options=SimOptions(monitor=False))
    c = simulate(supersigma, plan, seed=6, faults=faults, options=SimOptions(monitor=False))
    assert a.trace.to_json() == b.trace.to_json()
    assert a.trace.to_json() != c.trace.to_json()
    assert a.metrics.retransmissions > 0


def test_every_message_type_is_exercised(supersigma: Any, plans: Any) -> None:
    plan = plans["supersigma"]["greedy"]
    faults = [
        Crash("left", 3.0, 0.5),
        EmergencyStop(40.0, 1.0),
        ActivateZones(60.0, tuple(supersigma.cell.zone_map.zone_names())),
        LostSync("right", 0, 10.0),
        MessageLoss(0.05),
    ]
    r = simulate(supersigma, plan, faults=faults, seed=1)
    seen = {e.message for e in r.trace if e.kind == "message"}
    # every S2.7 message and the S2.12 records of every departure (the
    # excursion and failure orders need a geometric conflict or a failure)
    rare = {"detour", "back_off", "come_back", "release_hold", "fail"}
    assert set(MESSAGE_BYTES) - rare <= seen
    assert set(INTERNAL_MESSAGES) <= seen
    sizes = {e.message: e.size for e in r.trace if e.kind == "message" and e.src != e.dst}
    assert sizes["position"] == 51 and sizes["trajectory"] == 148
    assert r.metrics.done_tasks == supersigma.problem.n_tasks


def test_oscillating_geometric_stops_cannot_spin_without_time_advancing(
    scara4: Any, plans: Any
) -> None:
    """A guard whose answer changes at every look (the arm in the way
    alternates) made the coordinator re-check forever at one instant. Now
    the re-checks at one instant are bounded, later ones wait a guard period,
    and after a bounded number of those the stopped arms stay stopped: the
    run ends, its tasks failed with the cause (work limit: guard calls).
    The answer comes from ``SimOptions.guard_answer``, detours are off."""
    calls = [0]

    def blockers(mover: Any, arms: Sequence[Any]) -> list[int]:
        calls[0] += 1
        if calls[0] > 100_000:
            raise RuntimeError("work limit: the coordinator keeps re-checking")
        others = [o.index for o in arms if o is not mover]
        return [others[calls[0] % len(others)]]

    options = SimOptions(monitor=False, detours=False, guard_answer=blockers)
    r = simulate(scara4, plans["scara4"]["greedy"], options=options)
    assert calls[0] < 20_000
    assert r.metrics.done_tasks == 0
    causes = set(r.tasks_frame()["cause"])
    assert any("unresolved geometric deadlock" in c for c in causes)


def test_utilisation_is_busy_time_over_the_executed_makespan(supersigma: Any, plans: Any) -> None:
    """Every arm stops for good on its way to its second task (the guard's
    answer stubbed through ``SimOptions.guard_answer``, detours off) while the
    run goes on (an emergency stop late in the plan): the arms stand on their
    legs long after the last completed task, and that time is not counted.
    Utilisation stays busy time / executed makespan, in [0, 1]."""
    plan = plans["supersigma"]["greedy"]
    p = supersigma.problem
    first = {
        a: min((t for t in range(p.n_tasks) if plan.arms(p)[t] == a), key=lambda t: plan.start[t])
        for a in set(plan.arms(p).tolist())
    }

    def blockers(mover: Any, arms: Sequence[Any]) -> list[int]:
        if mover.leg is None or mover.leg.task == first.get(mover.index):
            return []
        return [o.index for o in arms if o is not mover][:1]

    late = 0.9 * plan.makespan
    options = SimOptions(monitor=False, detours=False, guard_answer=blockers)
    r = simulate(supersigma, plan, faults=[EmergencyStop(late, 1.0)], options=options)
    m = r.metrics
    assert 0 < m.done_tasks < p.n_tasks and m.executed_makespan < 0.5 * late
    assert set(m.utilisation) == set(p.arm_names)
    for arm, share in m.utilisation.items():
        assert 0.0 <= share <= 1.0, (arm, share)
    # the arms that worked were on a leg from their first departure to the end
    tf = r.tasks_frame()
    done = tf[tf["status"] == "done"]
    for arm in set(done["arm"]):
        assert m.utilisation[arm] > 0.5


def test_a_blocked_arm_continues_with_an_alternative_trajectory(
    supersigma: Any, plans: Any
) -> None:
    """S2.12 "continue with alternative trajectory": the guard (its answer
    stubbed through ``SimOptions.guard_answer``) reports the standing arm in the way of the mover's next stretch of its
    first task; the coordinator plans an OMPL detour around that arm to the
    next station, the mover takes it and goes on with its task from there;
    the detour costs more than the plan charged, so the plan is re-solved."""
    p = supersigma.problem
    plan = plans["supersigma"]["greedy"]
    arms = plan.arms(p)
    mover = int(arms[int(np.argmin(plan.start))])
    other = 1 - mover
    task = min((t for t in range(p.n_tasks) if arms[t] == mover), key=lambda t: plan.start[t])
    seen: list[str] = []

    def blockers(ctl: Any, all_arms: Sequence[Any]) -> list[int]:
        leg = ctl.leg
        if ctl.index != mover or leg is None:
            return []
        seen.append(leg.kind)
        if (
            leg.kind == "task"
            and leg.task == task
            and ctl.k == 1
            and ctl.tau < leg.stations[1].tau - 1e-9  # the asking arm stands at tau
            and not all_arms[other].running
        ):
            return [other]
        return []

    # the monitor checks the detour against the standing arm
    r = simulate(supersigma, plan, options=SimOptions(guard_answer=blockers))
    detours = [e for e in r.trace if e.kind == "detour"]
    assert len(detours) == 1 and r.metrics.detours == 1
    assert detours[0].arm == p.arm_names[mover] and detours[0].task == p.task_names[task]
    assert "alternative trajectory around arm" in detours[0].detail
    assert "detour" in seen  # the detour leg was checked too, then the task went on
    assert r.metrics.done_tasks == p.n_tasks
    resolves = [e.detail for e in r.trace if e.kind == "resolve"]
    if detours[0].delay > float(plan.blocking[task]):
        assert resolves and "costs more than planned" in resolves[0]


# ------------------------------------------------------------ the monitor


def _sequential(cc: Any, arm: int) -> tuple[list[int], list[float]]:
    """Every task on ``arm`` one after the other (a valid plan)."""
    p = cc.problem
    modes, starts = [0] * p.n_tasks, [0.0] * p.n_tasks
    end = [0.0] * p.n_tasks
    ready, prev = 0.0, -1
    for t in p.topological_order:
        m = int(p.mode_of[arm, t])
        s = max([ready + p.setup_time(arm, prev, t)] + [end[q] for q in p.task_preds[t]])
        modes[t], starts[t] = m, s
        end[t] = s + float(p.mode_duration[m])
        ready, prev = end[t], t
    return modes, starts


def test_the_monitor_fires_on_a_run_that_breaks_the_zone_invariants(supersigma: Any) -> None:
    p = supersigma.problem
    left, right = p.arm_names.index("left"), p.arm_names.index("right")
    modes, starts = _sequential(supersigma, left)
    king, queen = p.task_names.index("sort_king"), p.task_names.index("sort_queen")
    good = Schedule.from_starts(p, modes, starts)
    validate(p, good)
    # sort_queen on the right arm, at the very time sort_king starts on the left:
    # both need the exclusive zone 'board' at once
    modes[queen] = int(p.mode_of[right, queen])
    starts[queen] = starts[king] + 5.0
    bad = Schedule.from_starts(p, modes, starts)
    with pytest.raises(ValidationError):
        validate(p, bad)
    # (the earliest broken invariant: both arms moving in the shared zone 'fixture')
    with pytest.raises(
        SafetyViolation,
        match=r"'left' and 'right' both moving in shared zone 'fixture' from t = 53\.8159 s",
    ):
        simulate(supersigma, bad, options=SimOptions(zone_protocol=False, geometry_guard=False))
    # the same run with the coordinator's zone checks: safe
    r = simulate(supersigma, good)
    assert r.metrics.done_tasks == p.n_tasks


# ------------------------------------------------------------ errors


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("resolve", "yes"),
        ("resolve_budget", 0.0),
        ("resolve_evaluations", 0),
        ("tick", -1e-3),
        ("monitor", "sometimes"),
        ("monitor_period", math.inf),
        ("control_time", 0),
        ("insertion", "sampled"),
        ("insertion_sigma", -1.0),
        ("insertion_tolerance", 0.0),
        ("force_threshold", "strong"),
        ("zone_protocol", 1),
        ("geometry_guard", None),
        ("strict", "no"),
    ],
)
def test_sim_options_are_checked_and_name_the_field(field: str, value: Any) -> None:
    with pytest.raises(UsageError, match=rf"SimOptions\.{field} must"):
        SimOptions(**{field: value})


def test_sim_options_and_the_result_are_frozen_records(supersigma: Any, plans: Any) -> None:
    opts = SimOptions(resolve=False, force_threshold={"left": 8.0})
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.resolve = True  # type: ignore[misc]
    with pytest.raises(TypeError):
        opts.force_threshold["left"] = 1.0  # type: ignore[index]
    plan = plans["supersigma"]["greedy"]
    r = simulate(supersigma, plan, options=SimOptions(monitor=False))
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.seed = 3  # type: ignore[misc]
    assert isinstance(r.plan, Plan) and r.plan.problem is supersigma.problem
    assert r.plan.makespan == pytest.approx(plan.makespan)


def test_an_unknown_policy_is_refused_listing_the_known_ones(supersigma: Any, plans: Any) -> None:
    plan = plans["supersigma"]["greedy"]
    with pytest.raises(
        UsageError,
        match=r"unknown coordination policy 'gossip' \(known: centralized, distributed\)",
    ):
        simulate(supersigma, plan, coordination="gossip")
    with pytest.raises(UsageError, match="options must be a SimOptions"):
        simulate(supersigma, plan, options={"resolve": False})  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        simulate(supersigma, plan, 0)  # type: ignore[misc]


def test_bad_arguments_give_our_errors(supersigma: Any, plans: Any) -> None:
    plan = plans["supersigma"]["greedy"]
    with pytest.raises(UsageError, match="seed"):
        simulate(supersigma, plan, seed=-1)
    with pytest.raises(UsageError, match="tick"):
        simulate(supersigma, plan, options=SimOptions(tick=0.0))
    with pytest.raises(UsageError, match="resolve_budget"):
        simulate(supersigma, plan, options=SimOptions(resolve_budget=0))
    with pytest.raises(UsageError, match="schedule"):
        simulate(supersigma, "plan")  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="cell"):
        simulate(42, plan)  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="nope"):
        simulate(supersigma, plan, medium="nope")
    with pytest.raises(ValidationError, match=r"^faults: faults\[0\]\.arm: unknown arm 'middle'"):
        simulate(supersigma, plan, faults=[Crash("middle", 1.0)])
    with pytest.raises(ValidationError, match=r"^faults: faults\[0\]\.part: unknown part 'gear'"):
        simulate(supersigma, plan, faults=[{"kind": "late_part", "part": "gear", "delay": 3}])
    with pytest.raises(ValidationError, match=r"faults\[1\]: missing field 'at'"):
        simulate(
            supersigma,
            plan,
            faults=[{"kind": "message_loss", "probability": 0.1}, {"kind": "crash", "arm": "left"}],
        )


def test_the_centralized_control_bound_is_checked(scara4: Any, plans: Any) -> None:
    """S2.2: arms <= sampling period / per-arm control time (8 SCARAs at 1 ms)."""
    assert check_control_bound(8, 1e-3) == 8
    with pytest.raises(UsageError, match=r"9 arms exceed .* = 8 arms"):
        check_control_bound(9, 1e-3)
    with pytest.raises(UsageError, match=r"4 arms exceed .* 0\.0003 s / 0\.000125 s = 2 arms"):
        simulate(scara4, plans["scara4"]["greedy"], options=SimOptions(tick=3e-4))


def test_pipeline_offset_comes_from_top_speed_and_steepest_stop() -> None:
    """S2.3: a default stepper axis stops from 15,000 steps/s to its 1,000
    steps/s start rate along stop_accel = 4 m/s^2 (106,667 steps/s^2) in
    0.13125 s: 132 points at 1 ms; a 1 m/s servo braking at 4 m/s^2: 250."""
    from workcell.arms.profiles import ServoDrive, StepperDrive

    assert pipeline_offset([StepperDrive()], 1e-3) == 132
    assert pipeline_offset([ServoDrive(1.0, 4.0), StepperDrive()], 1e-3) == 250
    assert pipeline_offset([StepperDrive()], 2e-3) == 66
    with pytest.raises(ValidationError, match="sampling period"):
        pipeline_offset([StepperDrive()], 0.0)


# ------------------------------------------------------------ outputs


def test_result_tables_and_files(supersigma: Any, plans: Any, tmp_path: Path) -> None:
    r = simulate(supersigma, plans["supersigma"]["greedy"], options=SimOptions(monitor=False))
    assert isinstance(r, SimResult)
    assert list(r.trace.to_dataframe().columns) == list(COLUMNS)
    # the tables and the JSON are written field by field in the order of COLUMNS
    assert tuple(f.name for f in dataclasses.fields(TraceEvent)) == COLUMNS
    events = list(r.trace)
    rows = r.trace.to_dataframe().to_dict("records")
    assert [dataclasses.asdict(e) for e in events] == rows
    tf = r.tasks_frame()
    assert list(tf.columns) == [
        "task",
        "arm",
        "mode",
        "planned_start",
        "planned_end",
        "start",
        "end",
        "status",
        "cause",
        "cause_kind",
        "plan",
    ]
    assert (tf["status"] == "done").all() and (tf["cause_kind"] == "").all()
    assert (tf["plan"] == 0).all()  # no re-solve: every row from the schedule given
    rf = r.reservations_frame()
    assert set(rf["kind"]) <= {"zone", "move", "tool"} and len(rf) > 0
    assert (rf["end"] >= rf["start"]).all()
    md = r.metrics.to_dataframe()
    assert list(md.columns) == ["metric", "key", "value"]
    s = r.metrics.summary()
    assert s["done_tasks"] == supersigma.problem.n_tasks
    d = r.save(tmp_path / "out")
    assert {f.name for f in d.iterdir()} == {"trace.json", "metrics.json", "tasks.csv"}
    back = Trace.from_json((d / "trace.json").read_text())
    assert list(back) == events
    joints = r.joints([0.0, 10.0])
    assert set(joints) == {"left", "right"} and joints["left"].shape == (2, 4)


# ------------------------------------------------------------ golden trace


def _golden_scenario(cc: Any) -> tuple[Schedule, FaultPlan]:
    data = json.loads(GOLDEN.read_text()) if GOLDEN.exists() else None
    if data is None or os.environ.get("MULTIARM_REGEN_GOLDEN"):
        plan = solve(cc.problem, "greedy", seed=0).schedule
    else:
        plan = Schedule.from_dict(cc.problem, data["plan"])
    faults = FaultPlan.from_dicts(
        [
            {"kind": "crash", "arm": "left", "at": 12.0, "recovery": 0.5},
            {"kind": "message_loss", "probability": 0.1},
            {"kind": "emergency_stop", "at": 30.0, "duration": 1.0},
        ]
    )
    return plan, faults


def _rows(trace: Trace) -> list[list[Any]]:
    return [
        [round(e.time, 6), e.kind, e.arm, e.task, e.zone, e.message, e.src, e.dst, e.size]
        for e in trace
        if e.kind != "message" or e.src != e.dst
    ]


def test_golden_trace(supersigma: Any) -> None:
    """A deterministic scenario (greedy plan, a crash, message loss, an
    emergency stop, seed 7) replays the stored trace."""
    plan, faults = _golden_scenario(supersigma)
    r = simulate(supersigma, plan, seed=7, faults=faults)
    rows = _rows(r.trace)
    if os.environ.get("MULTIARM_REGEN_GOLDEN") or not GOLDEN.exists():
        GOLDEN.write_text(
            json.dumps(
                {
                    "plan": plan.to_dict(supersigma.problem),
                    "faults": faults.to_dicts(),
                    "seed": 7,
                    "executed_makespan": round(r.metrics.executed_makespan, 6),
                    "rows": rows,
                },
                separators=(",", ":"),
            )
        )
        pytest.skip("golden trace written")
    data = json.loads(GOLDEN.read_text())
    assert round(r.metrics.executed_makespan, 6) == data["executed_makespan"]
    assert rows == data["rows"]


def test_a_medium_with_latency_delays_every_message(scara4: Any, plans: Any) -> None:
    plan = plans["scara4"]["greedy"]
    r = simulate(
        scara4, plan, medium="fixed", options=SimOptions(monitor=False, geometry_guard=False)
    )
    delays = r.metrics.message_delay
    assert len(delays) == r.metrics.messages and np.allclose(delays, 1e-3)
    assert r.metrics.done_tasks == scara4.problem.n_tasks
    assert r.metrics.executed_makespan >= plan.makespan - 1e-6
