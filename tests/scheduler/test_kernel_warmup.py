"""The one-time compile: announced once, before it starts, and never again;
stale machine code of an edited kernel file is never loaded."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from scheduler.kernel import COMPILE_NOTE, api, drop_stale_cache, jit_enabled, warm_up


def test_a_compile_is_announced_once(monkeypatch: pytest.MonkeyPatch) -> None:
    assert jit_enabled()
    monkeypatch.setattr(api, "_WARM", False)
    monkeypatch.setattr(api, "_cached_on_disk", lambda: False)
    said: list[str] = []
    spent = warm_up(said.append)
    assert said == [COMPILE_NOTE]
    assert "once per machine" in COMPILE_NOTE and "about a minute" in COMPILE_NOTE
    assert spent > 0.0
    assert warm_up(said.append) == 0.0 and len(said) == 1


def test_the_default_announcement_is_a_log_message(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(api, "_WARM", False)
    monkeypatch.setattr(api, "_cached_on_disk", lambda: False)
    with caplog.at_level(logging.INFO, logger="scheduler.kernel"):
        warm_up()
    assert [r.getMessage() for r in caplog.records if r.levelno == logging.INFO] == [COMPILE_NOTE]


def test_a_cached_kernel_is_loaded_silently(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(api, "_WARM", False)
    monkeypatch.setattr(api, "_cached_on_disk", lambda: True)
    said: list[str] = []
    warm_up(said.append)
    assert said == []


class _Cache:
    def __init__(self, path: Path) -> None:
        self._cache_path = str(path)


class _Dispatcher:
    def __init__(self, path: Path) -> None:
        self._cache = _Cache(path)


def test_stale_machine_code_of_an_edited_kernel_file_is_dropped(tmp_path: Path) -> None:
    src = [tmp_path / "place.py", tmp_path / "passes.py"]
    src[0].write_text("x = 1\n")
    src[1].write_text("y = 2\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    files = [cache / "passes._decode-38.py311.nbi", cache / "passes._decode-38.py311.1.nbc"]
    other = cache / "unrelated.f-1.py311.nbi"
    for f in (*files, other):
        f.write_bytes(b"0")
    d = [_Dispatcher(cache)]
    assert drop_stale_cache(d, src)  # no digest yet: dropped
    assert not any(f.exists() for f in files) and other.exists()
    for f in files:
        f.write_bytes(b"0")
    assert not drop_stale_cache(d, src)  # unchanged sources: kept
    assert all(f.exists() for f in files)
    src[0].write_text("x = 3\n")  # an edit of the placement code drops the passes too
    assert drop_stale_cache(d, src)
    assert not any(f.exists() for f in files)


_RESOLVE_AFTER_WARM_UP = """
import sys
import numba
import numpy as np
from scheduler import FrozenTask, reschedule, solve
from scheduler.generate import random_problem
from scheduler.kernel import warm_up

def loaded():
    out = {}
    for name, mod in list(sys.modules.items()):
        if name.startswith("scheduler"):
            for attr, obj in vars(mod).items():
                if isinstance(obj, numba.core.registry.CPUDispatcher):
                    out[f"{name}.{attr}"] = len(obj.overloads)
    return out

warm_up()
plans = []
for blocking in (False, True):
    p = random_problem(4, 30, 4, 1, seed=3, blocking=blocking, start_zones=blocking)
    plans.append((p, solve(p, "greedy", seed=0).schedule))
before = loaded()
for p, plan in plans:
    now = 0.4 * plan.makespan
    done = {t: FrozenTask(int(plan.mode[t]), float(plan.start[t]), float(plan.end[t]),
                          tuple(plan.waits[t].tolist()))
            for t in range(p.n_tasks) if plan.end[t] <= now}
    done = {t: f for t, f in done.items() if all(q in done for q in p.task_preds[t])}
    r = reschedule(p, now=now, previous=plan, done=done, arms_out={0}, evaluations=10, seed=0)
    assert r.schedule is not None
after = loaded()
print(sorted(k for k in after if after[k] != before.get(k, 0)))
"""


def test_a_re_solve_after_the_warm_up_loads_no_more_compiled_code() -> None:
    # in a fresh process: a function first loaded inside a re-solve (from
    # numba's disk cache, 20-40 ms) would count in the first re-solve's
    # latency in the loop (the simulation warms the kernel before a run
    # that may re-solve)
    import subprocess
    import sys

    got = subprocess.run(
        [sys.executable, "-c", _RESOLVE_AFTER_WARM_UP],
        capture_output=True,
        text=True,
        timeout=600,
        check=True,
    )
    assert got.stdout.strip() == "[]", got.stdout + got.stderr
