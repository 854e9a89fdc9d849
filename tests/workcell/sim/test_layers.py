"""The simulation's layers (S2.1) and its protocol state machines.

The import contracts of ``pyproject.toml`` (ids ``sim-layers``,
``sim-independent``, ``sim-monitor``) hold, and can fail: a copy of the tree
with one forbidden import breaks them. The state machines' tables are
consistent, refuse illegal transitions, and are the diagrams of
``docs/simulation.md``.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from multiarm.errors import InternalError, UsageError
from workcell.sim.protocol.states import (
    ARM_MACHINE,
    MACHINES,
    TASK_MACHINE,
    ArmState,
    Machine,
    TaskState,
    markdown,
    mermaid,
)

ROOT = Path(__file__).resolve().parents[3]
PACKAGES = ["multiarm", "tasklib", "zones", "scheduler", "workcell"]
SIM_CONTRACTS = ["sim-layers", "sim-independent", "sim-monitor"]
MAX_LINES = 600


def _lint(root: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    lint = Path(sys.executable).with_name("lint-imports")
    args = [str(lint), "--no-cache", str(root / "pyproject.toml")]
    for c in SIM_CONTRACTS:
        args += ["--contract", c]
    return subprocess.run(args, cwd=root, capture_output=True, text=True, check=False, env=env)


def test_the_sim_contracts_hold() -> None:
    proc = _lint(ROOT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f"{len(SIM_CONTRACTS)} kept, 0 broken" in proc.stdout


@pytest.mark.parametrize(
    ("where", "code", "broken"),
    [
        # coordination reaching into a controller
        (
            "workcell/sim/coordination",
            "import workcell.sim.control.controller\n",
            "workcell.sim.coordination._bad -> workcell.sim.control.controller",
        ),
        # the monitor reading a controller instead of its published records
        (
            "workcell/sim/harness",
            "import workcell.sim.control.controller\n",
            "",
        ),
        # the event layer importing upwards
        (
            "workcell/sim/events",
            "import workcell.sim.comms.medium\n",
            "workcell.sim.events._bad -> workcell.sim.comms.medium",
        ),
    ],
)
def test_a_forbidden_import_breaks_a_sim_contract(
    tmp_path: Path, where: str, code: str, broken: str
) -> None:
    for pkg in PACKAGES:
        shutil.copytree(ROOT / pkg, tmp_path / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    if where == "workcell/sim/harness":  # the monitor itself gains the import
        mon = tmp_path / where / "monitor.py"
        mon.write_text(mon.read_text() + "\n" + code)
        broken = "workcell.sim.harness.monitor -> workcell.sim.control.controller"
    else:
        (tmp_path / where / "_bad.py").write_text(code)
    proc = _lint(tmp_path, env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"})
    assert proc.returncode != 0, proc.stdout
    assert broken in proc.stdout
    assert "0 broken" not in proc.stdout


def test_no_module_of_the_simulation_is_over_600_lines() -> None:
    long = {
        str(p.relative_to(ROOT)): n
        for p in (ROOT / "workcell" / "sim").rglob("*.py")
        if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, long


# ------------------------------------------------------------ state machines


@pytest.mark.parametrize("machine", MACHINES, ids=lambda m: m.name)
def test_every_state_is_reachable_and_the_table_names_only_its_states(machine: Machine) -> None:
    names = set(machine.states)
    assert machine.initial in names
    assert {a for a, _b, _w in machine.transitions} <= names
    assert {b for _a, b, _w in machine.transitions} <= names
    seen, todo = {machine.initial}, [machine.initial]
    while todo:
        s = todo.pop()
        for a, b, _why in machine.transitions:
            if a == s and b not in seen:
                seen.add(b)
                todo.append(b)
    assert seen == names
    assert len(set((a, b) for a, b, _ in machine.transitions)) == len(machine.transitions)
    # the printed table has one line per transition, in order
    lines = machine.table().splitlines()
    assert lines == [f"{a} -> {b}: {w}" for a, b, w in machine.transitions]


def test_a_finished_task_never_changes_state() -> None:
    for end in (TaskState.DONE, TaskState.FAILED):
        for new in TaskState:
            if new is not end:
                assert not TASK_MACHINE.allowed(end, new)
                with pytest.raises(InternalError, match=f"task: illegal transition {end} -> {new}"):
                    TASK_MACHINE.check(end, new)
    # a task is done only after it ran
    with pytest.raises(InternalError, match="dispatched -> done"):
        TASK_MACHINE.check(TaskState.DISPATCHED, TaskState.DONE)
    with pytest.raises(InternalError, match="pending -> done"):
        TASK_MACHINE.check(TaskState.PENDING, TaskState.DONE)


def test_a_failed_arm_stays_failed() -> None:
    for new in ArmState:
        if new is not ArmState.FAILED:
            with pytest.raises(InternalError, match="arm: illegal transition failed"):
                ARM_MACHINE.check(ArmState.FAILED, new)
    ARM_MACHINE.check(ArmState.FAILED, ArmState.FAILED)  # staying put is no transition


def test_the_state_enums_are_the_tables_states() -> None:
    assert TASK_MACHINE.states == tuple(s.value for s in TaskState)
    assert ARM_MACHINE.states == tuple(s.value for s in ArmState)
    assert TaskState.DONE == "done"  # the coordinator's records keep their strings


def test_the_docs_diagrams_are_generated_from_the_tables() -> None:
    text = (ROOT / "docs" / "simulation.md").read_text()
    found = re.search(
        r"<!-- state machines: begin -->\n(.*?)<!-- state machines: end -->", text, flags=re.S
    )
    assert found is not None, "docs/simulation.md lacks the state machine markers"
    assert found.group(1).strip() == markdown().strip()
    for m in MACHINES:
        assert mermaid(m) in text
        assert mermaid(m).count("-->") == len(m.transitions) + 1


# ------------------------------------------------------------ coordination policies


def test_the_policy_registry_is_what_simulate_accepts(cell: Any, plan: Any) -> None:
    from workcell.sim import simulate
    from workcell.sim.coordination.centralized import Coordinator
    from workcell.sim.coordination.distributed import DistributedPolicy
    from workcell.sim.coordination.policy import POLICIES, make_policy, register_policy
    from workcell.sim.harness.options import COORDINATION_POLICIES

    assert sorted(POLICIES) == sorted(COORDINATION_POLICIES) == ["centralized", "distributed"]
    assert POLICIES["centralized"] is Coordinator
    assert POLICIES["distributed"] is DistributedPolicy
    with pytest.raises(UsageError, match="already registered"):
        register_policy("centralized", Coordinator)
    with pytest.raises(UsageError, match="unknown coordination policy 'gossip'"):
        make_policy("gossip", cell, plan, None, None, None, [])  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="unknown coordination policy 'gossip'"):
        simulate(cell, plan, coordination="gossip")
