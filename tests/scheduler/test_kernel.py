"""The placement kernel: compiled and plain Python agree; placements are valid."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from scheduler import Model, Window, validate
from scheduler.generate import random_problem
from scheduler.kernel import compile_problem, decode, expand, jit_enabled, to_schedule
from scheduler.search import Evaluator, priority_order

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import json, sys
import numpy as np
from scheduler.generate import random_problem
from scheduler.kernel import compile_problem, decode, expand_blocking, seq_decode, to_schedule, jit_enabled
from scheduler.search import priority_order
out = []
for seed in range(6):
    # seeds 3..5 carry the generator's blocking oracle (chronological decoding with detours)
    p = random_problem(4, 40, 5, 2, seed=seed, start_zones=True, blocking=seed >= 3)
    inst = compile_problem(p)
    order = priority_order(p)
    for waits in (True, False):
        code, st = decode(inst, order, np.full(p.n_tasks, -1), waits=waits)
        s = to_schedule(inst, st)
        out.append([code, s.mode.tolist(), s.start.tolist(), [w.tolist() for w in s.waits],
                    s.blocking.tolist()])
    seqs = np.zeros((p.n_arms, p.n_tasks), dtype=np.int64)
    n = np.zeros(p.n_arms, dtype=np.int64)
    for t in np.argsort(st.t_start, kind="stable"):
        a = int(p.mode_arm[st.t_mode[t]])
        seqs[a, n[a]] = t
        n[a] += 1
    ok, st2, o = seq_decode(inst, seqs, n, st.t_mode.copy())
    out.append([ok, st2.t_start.tolist(), o.tolist()])
    if p.blocking is not None:
        _c, part = decode(inst, order[:10], np.full(p.n_tasks, -1))
        ct = np.repeat(order[10:20], 1)
        cm = np.array([p.task_modes[t][0] for t in ct])
        out.append([x.tolist() for x in expand_blocking(inst, part, ct, cm)])
print(json.dumps({"jit": jit_enabled(), "out": out}))
"""


def run(env_extra: dict[str, str]) -> dict:  # type: ignore[type-arg]
    env = {**os.environ, **env_extra}
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    )
    return json.loads(proc.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def test_compiled_and_plain_python_agree() -> None:
    fast = run({})
    slow = run({"MULTIARM_NO_JIT": "1"})
    assert fast["jit"] and not slow["jit"]
    assert fast["out"] == slow["out"]


def test_decoded_schedules_validate_and_use_waits() -> None:
    assert jit_enabled()
    used_waits = 0
    for seed in range(15):
        p = random_problem(4, 60, 6, 2, seed=seed, start_zones=seed % 2 == 0)
        code, st = decode(compile_problem(p), priority_order(p), np.full(p.n_tasks, -1))
        assert code == 0
        s = to_schedule(compile_problem(p), st)
        validate(p, s)
        used_waits += s.total_wait() > 0
    assert used_waits > 0  # the kernel does wait at borders when it helps


def test_blocked_tasks_are_deferred_until_a_start_zone_frees() -> None:
    # arm B stands in exclusive zone E; task "need_e" (arm A) needs E; B's own task comes
    # later in the list: the decoder defers need_e until B has left.
    m = Model()
    m.add_zone("E")
    m.add_arm("A")
    m.add_arm("B", start_zones=["E"])
    m.add_task("need_e")
    m.add_mode("need_e", "A", 2.0, windows=[Window("E", 0.0, 2.0)])
    m.add_task("b_work")
    m.add_mode("b_work", "B", 5.0)
    p = m.build()
    code, st = decode(compile_problem(p), np.array([0, 1]), np.full(2, -1))
    assert code == 0
    s = to_schedule(compile_problem(p), st)
    assert validate(p, s) == 5.0 and s.start[0] == 0.0  # B leaves E at 0 for its task
    # an arm that never leaves keeps the zone for good: nothing can be placed there
    m2 = Model()
    m2.add_zone("E")
    m2.add_arm("A")
    m2.add_arm("B", start_zones=["E"])
    m2.add_task("need_e")
    m2.add_mode("need_e", "A", 2.0, windows=[Window("E", 0.0, 2.0)])
    p2 = m2.build()
    code, _ = decode(compile_problem(p2), np.array([0]), np.full(1, -1))
    assert code == -1


def test_expand_matches_single_placements() -> None:
    p = random_problem(3, 30, 4, 1, seed=2)
    ev = Evaluator(p)
    _ok, st = ev.decode(priority_order(p)[:10])
    cand_t, cand_m = [], []
    for t in range(p.n_tasks):
        if st.t_mode[t] < 0 and all(st.t_mode[q] >= 0 for q in p.task_preds[t]):
            for m in p.task_modes[t]:
                cand_t.append(t)
                cand_m.append(m)
    S, end, k, _w, waits = expand(compile_problem(p), st, np.array(cand_t), np.array(cand_m))
    for i, (t, m) in enumerate(zip(cand_t, cand_m, strict=True)):
        S1, e1, k1, waits1 = compile_problem(p).query(
            st, t, m, compile_problem(p).earliest(st, t, False)
        )
        assert (S1, e1, k1) == (S[i], end[i], k[i])
        assert np.allclose(waits1, waits[i][: len(waits1)])
