"""The bounded fuzz run of the test suite, and the replay of every crash reproducer.

Every target of :mod:`tests.fuzz.targets` runs under atheris in one process
for a few thousand inputs in all (the long campaign is ``make fuzz``); each
file under
``tests/fuzz/crashes/<target>/`` (an input that once escaped our error
family, or hung) is replayed and must now load or raise an error of ours
that names its place. The seeds themselves are replayed the same way.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from tests.fuzz.targets import ALL, HERE, KNOWN_FOREIGN, TARGETS, seed_files

# Inputs of the bounded run, all targets in one process (the seeds of every
# target first: about 120); the compile harness stops at ALL_CAPS["compile"].
BOUNDED_RUNS = 2500

CRASHES = HERE / "crashes"


def _crash_files() -> list[object]:
    out: list[object] = []
    for folder in sorted(p for p in CRASHES.iterdir() if p.is_dir()):
        for f in sorted(folder.iterdir()):
            marks = []
            if f.name in KNOWN_FOREIGN.get(folder.name, ()):
                # an out-of-memory or hang would exhaust the run; the compile
                # harness leaves the pending values out (PENDING_RANGES)
                if f.name.startswith(("oom-", "timeout-")) or folder.name == "compile":
                    marks.append(pytest.mark.skip(reason="known finding (KNOWN_FOREIGN)"))
                else:
                    marks.append(
                        pytest.mark.xfail(strict=True, reason="known finding (KNOWN_FOREIGN)")
                    )
            out.append(pytest.param(folder.name, f, id=f"{folder.name}/{f.name}", marks=marks))
    return out


@pytest.mark.parametrize(("target", "path"), _crash_files())
def test_crash_reproducer_raises_only_our_errors(target: str, path: Path, tmp_path: Path) -> None:
    t0 = time.perf_counter()
    TARGETS[target](path.read_bytes(), tmp_path)
    assert time.perf_counter() - t0 < 10.0, "a reproducer of a hang still takes > 10 s"


@pytest.mark.parametrize("target", sorted(TARGETS))
def test_seeds_load_or_raise_only_our_errors(target: str, tmp_path: Path) -> None:
    files = seed_files(target)
    if target != "compile":
        assert files, f"target {target!r} has no seeds"
    for f in files:
        TARGETS[target](f.read_bytes(), tmp_path)


def test_every_crash_folder_is_a_target() -> None:
    folders = {p.name for p in CRASHES.iterdir() if p.is_dir()}
    assert folders <= set(TARGETS), folders - set(TARGETS)
    for target, names in KNOWN_FOREIGN.items():
        for name in names:
            assert (CRASHES / target / name).is_file(), f"{target}/{name} is listed but missing"


def test_bounded_fuzz_run_of_every_target_in_one_process() -> None:
    """One atheris process runs every target (:class:`tests.fuzz.targets.Multiplex`:
    an input's first byte picks the target) from their seeds: one start-up and one
    instrumentation instead of one per target."""
    pytest.importorskip("atheris", reason="atheris (dev extra) has wheels for Linux and macOS only")
    from tests.fuzz.campaign import fuzz_target

    r = fuzz_target(ALL, runs=BOUNDED_RUNS, max_time=240, timeout=10)
    assert r.status == "ok", f"{r.status}\n{r.log}"
    assert r.inputs == BOUNDED_RUNS, r.log
    assert r.per_target is not None, r.log
    assert set(r.per_target) == set(TARGETS)
    starved = [name for name, n in r.per_target.items() if n < 2]
    assert not starved, (starved, r.per_target)
