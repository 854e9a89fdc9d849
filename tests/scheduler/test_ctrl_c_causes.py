"""The ways a Ctrl-C during a solve was lost, each replayed at its exact instant.

Python raises KeyboardInterrupt in the main thread at the next bytecode,
wherever that is (:mod:`scheduler._ctrl_c`). Measured on the tree search
racing CP-SAT (``test_tree_ctrl_c.py``), about 1 Ctrl-C in 25 was lost:

* **finaliser**: the garbage collector ran a ``weakref.finalize`` callback
  (numba's compiler makes many) at that instant; the exception raised in it
  was printed as "Exception ignored in ..." and dropped, and the search ran
  on to its time limit with ``interrupted=False``;
* **thread start**: raised inside ``threading.Thread.start`` after the new
  thread existed but before it had its ident, the thread running CP-SAT (the
  tree's racing one, or the helper of a CP-SAT solve) was taken for never
  started, was not stopped, and searched on to its limit after the solve
  returned;
* **lock restore**: raised inside ``threading.Condition.wait`` (under every
  ``Event.wait``, e.g. in ``Thread.start``) before it had taken its lock
  back, it became ``RuntimeError: release unlocked lock`` and the solve
  crashed;
* **search end**: noted inside the wait of a CP-SAT solve just as the
  search ended (after the loop's last look at the note), it was dropped
  with the deferred block, and the solve returned as complete: a sweep of
  CP-SAT runs went on after the Ctrl-C (seen once in
  ``tests/experiments/test_ctrl_c.py``).

Each case runs in a child process (signals go to the main thread), whose
SIGINT comes from inside a finaliser run during the search (through the
public ``progress`` hook) or inside the first ``Thread.start`` or
``Condition`` lock restore of the solve (found with ``sys.setprofile``; a long GIL switch interval keeps the new
thread from setting its ident before the exception is handled).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

PROMPT = 5.0
"""Seconds from SIGINT to the end of the solve, and from there to the end of
every thread the solve started, at most (the machine may be loaded)."""

LIMIT = 20.0
"""The solves' time limit: a lost Ctrl-C shows as a solve (or thread) that
runs this long."""

CHILD = textwrap.dedent(
    """
    import os, signal, sys, threading, time, weakref
    from scheduler import solve
    from scheduler.generate import random_problem

    case, solver, limit = sys.argv[1], sys.argv[2], float(sys.argv[3])
    p = random_problem(3, 14, 2, 1, seed=1)
    solve(p, solver, time_limit=0.5, seed=0)  # warm up: compiled kernels, imports
    sent = []

    def ctrl_c():
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    class Garbage:
        pass

    def in_a_finaliser(_progress):
        if not sent:  # collected at once: its finaliser runs here, the signal lands in it
            weakref.finalize(Garbage(), lambda: (ctrl_c(), time.sleep(0.2)))

    def in_thread_start(frame, event, arg):
        if (
            event == "call"
            and not sent
            and frame.f_code.co_name == "wait"
            and frame.f_back is not None
            and frame.f_back.f_code.co_name == "start"
            and frame.f_back.f_code.co_filename == threading.__file__
        ):
            ctrl_c()  # handled at the next bytecode: inside Thread.start's wait

    def in_lock_restore(frame, event, arg):
        if (
            event == "call"
            and not sent
            and frame.f_code.co_name == "_acquire_restore"
            and frame.f_code.co_filename == threading.__file__
        ):
            ctrl_c()  # handled before Condition.wait has taken its lock back

    def at_search_end(frame, event, arg):
        if (
            event == "return"
            and not sent
            and arg is True
            and frame.f_code.co_name == "wait"
            and frame.f_code.co_filename == threading.__file__
            and frame.f_back is not None
            and frame.f_back.f_code.co_name == "_run_beside"
        ):
            ctrl_c()  # handled as the wait for the finished search returns

    hooks = {
        "thread-start": in_thread_start,
        "lock-restore": in_lock_restore,
        "search-end": at_search_end,
    }
    before = set(threading.enumerate())
    if case == "finaliser":
        r = solve(p, solver, time_limit=limit, seed=0, progress=in_a_finaliser)
    else:
        # the new thread must not take the GIL before the exception is handled
        # (else it sets its ident in time, and the old check was right by luck)
        interval = sys.getswitchinterval()
        sys.setswitchinterval(1.0)
        sys.setprofile(hooks[case])
        try:
            r = solve(p, solver, time_limit=limit, seed=0)
        finally:
            sys.setprofile(None)
            sys.setswitchinterval(interval)
    back = time.perf_counter()
    left = []
    while time.perf_counter() - back < limit + 5.0:
        # listed until it ends (is_alive() is False until it has run a bytecode)
        left = [t.name for t in set(threading.enumerate()) - before]
        if not left:
            break
        time.sleep(0.02)
    print("sent", len(sent), flush=True)
    print(
        f"solve {r.stats.interrupted} {back - sent[0]:.3f} {len(left)} "
        f"{time.perf_counter() - back:.3f} {r.status.value}",
        flush=True,
    )
    """
)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT is POSIX")
@pytest.mark.parametrize(
    ("case", "solver"),
    [
        ("finaliser", "tree"),
        ("thread-start", "tree"),
        ("thread-start", "cpsat"),
        ("lock-restore", "tree"),
        ("lock-restore", "cpsat"),
        ("search-end", "cpsat"),
    ],
)
def test_a_ctrl_c_at_a_fragile_instant_is_honoured(case: str, solver: str) -> None:
    child = subprocess.run(
        [sys.executable, "-c", CHILD, case, solver, str(LIMIT)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=Path(__file__).resolve().parents[2],
        check=False,
    )
    out = child.stdout + child.stderr
    assert child.returncode == 0, out
    assert "sent 1" in child.stdout, out
    rows = [ln.split() for ln in child.stdout.splitlines() if ln.startswith("solve ")]
    assert len(rows) == 1, out
    _, interrupted, since, left, gone, status = rows[0]
    assert interrupted == "True", out
    assert float(since) < PROMPT, out
    assert int(left) == 0 and float(gone) < PROMPT, out
    if case == "finaliser":  # the search had a schedule when the Ctrl-C came: it is kept
        assert status == "feasible", out


def test_a_ctrl_c_after_the_search_loop_keeps_the_best_schedule() -> None:
    """Ctrl-C while the tree search collects the schedules found beside it
    (here: the CP-SAT fallback's, on a problem no list order decodes; work
    limited, so without a racing CP-SAT) used to end the solve with no
    schedule. A KeyboardInterrupt raised by the ``progress`` hook on the main
    thread, when the search takes that schedule, stands for it (the hook is
    called from CP-SAT's own thread first)."""
    import threading

    from scheduler import Model, Progress, TreeOptions, Window, solve
    from scheduler.schedule import validate

    m = Model("swap")  # each arm starts in the zone the other one's task needs
    m.add_zone("ZA")
    m.add_zone("ZB")
    m.add_arm("A", start_zones=["ZA"])
    m.add_arm("B", start_zones=["ZB"])
    m.add_task("ta")
    m.add_mode("ta", "A", 2.0, windows=[Window("ZB", 0.5, 1.5)])
    m.add_task("tb")
    m.add_mode("tb", "B", 2.0, windows=[Window("ZA", 0.5, 1.5)])
    p = m.build()
    seen: list[float] = []

    def ctrl_c(progress: Progress) -> None:
        seen.append(progress.objective)
        if threading.current_thread() is threading.main_thread():
            raise KeyboardInterrupt

    opt = TreeOptions(max_evaluations=300)
    r = solve(p, "tree", time_limit=None, seed=0, options=opt, progress=ctrl_c)
    assert seen and set(seen) == {2.0}  # the fallback's schedule, the only one found
    assert r.stats.interrupted is True
    assert r.schedule is not None and validate(p, r.schedule) == r.objective == 2.0
