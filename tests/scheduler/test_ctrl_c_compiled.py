"""A Ctrl-C during a compiled call that calls back into Python.

numba unpickles constants in Python for each call of the local search's
move functions (they take a ``numpy.random.Generator``). A KeyboardInterrupt
raised in there made the call end in ``SystemError: ... returned a result
with an exception set``, or the process in a segmentation fault: one
``multiarm simulate`` interrupted during the tree search ended by SIGSEGV,
another by that SystemError (``tests/workcell/test_cli_behaviour.py``,
``test_ctrl_c_ends_cleanly_with_status_130``). The calls are now
``scheduler._ctrl_c.atomic``: the KeyboardInterrupt comes after them.

Campaigns: SIGINTs every fraction of a millisecond while the moves are
computed over and over, outside a solve (Python's own handler) and inside
one (``_ctrl_c.guard``, whose first Ctrl-C is the one deferred), at seeded
periods. Without the fix the first one ends in a segmentation fault.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np
import pytest

from scheduler import _ctrl_c, solve
from scheduler.generate import random_problem
from scheduler.kernel.moves_jit import neighbour_moves
from scheduler.search import Evaluator

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="SIGINT is POSIX")


def _moves_call() -> Callable[[], object]:
    p = random_problem(4, 30, 4, 1, seed=0, blocking=True, start_zones=True)
    plan = solve(p, "greedy", seed=0).schedule
    assert plan is not None
    ev = Evaluator(p)
    order = np.argsort(plan.start, kind="stable").astype(np.int64)
    sol = ev.evaluate(order, np.asarray(plan.mode, dtype=np.int64))
    assert sol is not None and sol.state is not None
    rng = np.random.default_rng(0)
    return lambda: neighbour_moves(ev.inst, sol.state, sol.order, sol.modes, rng, chrono=True)


@contextmanager
def _sigints(period: float) -> Iterator[None]:
    """SIGINT every ``period`` seconds (sent from a SIGALRM handler, so the
    SIGINT's handler runs where Python's next bytecode is: often inside the
    compiled call's callback)."""
    before = signal.signal(signal.SIGALRM, lambda _s, _f: os.kill(os.getpid(), signal.SIGINT))
    signal.setitimer(signal.ITIMER_REAL, period, period)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, before)


def _hammer(call: Callable[[], object], done: Callable[[], bool], period: float) -> dict[str, int]:
    """Call until ``done`` under SIGINTs every ``period`` seconds: how many
    calls were followed by a KeyboardInterrupt, and how many ended in
    SystemError."""
    n = {"seen": 0, "errors": 0}
    try:
        with _sigints(period):
            while True:
                try:  # a SIGINT may also land between the calls, in this loop itself
                    while not done():
                        try:
                            call()
                        except KeyboardInterrupt:
                            n["seen"] += 1
                        except SystemError:
                            n["errors"] += 1
                    break
                except KeyboardInterrupt:
                    continue
    except KeyboardInterrupt:  # one sent just before the timer stopped
        pass
    return n


def test_sigints_outside_a_solve_come_after_the_compiled_call() -> None:
    call = _moves_call()
    call()  # compiled before the SIGINTs
    for period in (0.0007, 0.0011, 0.0013):
        end = time.perf_counter() + 0.4
        n = _hammer(call, lambda end=end: time.perf_counter() >= end, period)
        assert n["errors"] == 0, f"period {period}: {n['errors']} calls ended in SystemError"
        assert n["seen"] > 0


def test_a_first_ctrl_c_inside_a_solve_comes_after_the_compiled_call() -> None:
    call = _moves_call()
    call()
    errors = 0
    for period in np.random.default_rng(11).uniform(0.0002, 0.003, size=40).tolist():
        with _ctrl_c.guard() as c:
            assert c.active
            # the first SIGINT of a solve is the one deferred (a second raises
            # at once, as Python's own handler does)
            errors += _hammer(call, lambda c=c: c.hit, period)["errors"]
    assert errors == 0


def test_a_second_ctrl_c_inside_a_compiled_call_waits_for_its_end() -> None:
    """Once a first Ctrl-C is noted, a second raises at once, but not inside an
    ``atomic`` block (a compiled call's callback, where it could crash the
    process): there it is raised at the block's end. Before the fix the
    campaign above ended in a segmentation fault now and then on a slow
    machine (a call outlasting the SIGINT period)."""
    with _ctrl_c.guard() as c:
        assert c.active
        c.hit = True  # as after a first Ctrl-C
        reached: list[bool] = []
        with pytest.raises(KeyboardInterrupt), _ctrl_c.atomic():
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(10_000):  # the handler runs between these bytecodes
                pass
            reached.append(True)
        assert reached == [True]
        # outside the block a second Ctrl-C raises at once, as Python's own does
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(10_000):
                pass
