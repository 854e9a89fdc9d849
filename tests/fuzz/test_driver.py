"""The fuzz driver keeps the input of every finding (tests/fuzz/campaign.py,
tests/fuzz/run.py).

A compile campaign once stopped at a finding whose input libFuzzer never
wrote: the exception was printed, but the process ended before libFuzzer's
exit handler (which writes the test unit) ran. The target process now writes
the input itself before the exception leaves the target, and the input being
run before each run, so that even a killed process leaves it. Each case here
runs a tiny target with a planted finding (``tests/fuzz/driver_targets.py``)
that ends the process in one of those ways; a run takes about a second.
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("atheris", reason="atheris (dev extra) has wheels for Linux and macOS only")

from tests.fuzz.campaign import fuzz_target

PLANTED = b"boom!"


@pytest.mark.parametrize(
    ("target", "status", "kind"),
    [
        ("raise_then_shutdown_exits", "crash", "crash"),
        ("killed", "killed (signal 9)", "lost"),
    ],
)
def test_a_finding_s_input_is_kept_when_libfuzzer_writes_none(
    target: str, status: str, kind: str, tmp_path: Path
) -> None:
    artifacts, crashes = tmp_path / "artifacts", tmp_path / "crashes"
    r = fuzz_target(
        f"tests.fuzz.driver_targets:{target}",
        runs=200,
        max_time=60,
        artifacts=artifacts,
        seeds=[("plain", b"hello"), ("planted", PLANTED)],
        crashes=crashes,
    )
    assert r.status == status, r.log
    assert "Test unit written to" not in r.log  # libFuzzer kept nothing itself
    assert r.artifact is not None, r.log
    unit = Path(r.artifact)
    assert unit.parent == artifacts
    assert unit.name.startswith(f"{target}-{kind}-")
    assert unit.read_bytes() == PLANTED
    kept = sorted((crashes / target).iterdir())
    assert [k.read_bytes() for k in kept] == [PLANTED]
    assert kept[0].suffix == ".bin"
    # the input being run is not left behind as if it were a finding
    assert not (artifacts / f"{target}-current").exists()


def test_a_run_without_finding_keeps_nothing(tmp_path: Path) -> None:
    artifacts, crashes = tmp_path / "artifacts", tmp_path / "crashes"
    r = fuzz_target(
        "tests.fuzz.driver_targets:killed",
        runs=50,
        max_time=60,
        artifacts=artifacts,
        seeds=[("plain", b"hello")],
        crashes=crashes,
    )
    # mutations of "hello" do not start with "boom" within 50 runs (seeded)
    assert r.status == "ok", r.log
    assert r.artifact is None
    assert list(artifacts.iterdir()) == []
    assert not crashes.exists()
