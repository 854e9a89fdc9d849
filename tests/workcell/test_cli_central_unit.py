"""`multiarm simulate --central-unit`: the plan also runs on the SUPERSIGMA CCU (S1)."""

from __future__ import annotations

from pathlib import Path

import pytest

from workcell.cli import main


def test_the_plan_runs_under_the_central_unit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["simulate", "supersigma", "--solver", "greedy", "--out", str(tmp_path)]
    assert main([*argv, "--central-unit"]) == 0
    out = capsys.readouterr().out
    assert "under the SUPERSIGMA central unit and MICROBUS (S1):" in out
    header, _, row = out.split("MICROBUS (S1):")[1].strip().splitlines()[:3]
    assert header.split()[:4] == ["planned", "(s)", "executed", "(s)"]
    planned, executed, commands = (float(v) for v in row.split()[:3])
    assert executed >= planned > 0 and commands > 0
    assert row.split()[-1] == "0"  # no command lost to a busy controller
    assert main(argv) == 0
    assert "central unit" not in capsys.readouterr().out
