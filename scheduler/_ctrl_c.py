"""Ctrl-C during a solve: noted at once, so it is never lost.

Python's own SIGINT handler raises KeyboardInterrupt in the main thread at
the next bytecode boundary, wherever that is. Two kinds of places there
lost a Ctrl-C during a tree search that races CP-SAT (about 1 instant in
25 of ``tests/scheduler/test_tree_ctrl_c.py``):

* **code that swallows the exception.** A KeyboardInterrupt raised inside
  a finaliser the garbage collector runs at that instant (``__del__``, a
  ``weakref.finalize`` callback, of which numba's compiler makes many)
  is printed as "Exception ignored in ..." and dropped: it never reached
  the search, which ran on to its time limit and returned
  ``interrupted=False``;
* **code left half done.** Raised inside ``threading.Thread.start`` after
  the new thread exists but before it has set its ident, the racing CP-SAT
  thread (or a CP-SAT solve's helper thread, :func:`scheduler.cpsat.run_solver`)
  looked never started, was not stopped, and searched on to its limit after
  the solve returned. Raised inside ``threading.Condition.wait`` (under
  every ``Event.wait``) while it takes its lock back, it left the lock
  released, and the ``with`` around it raised ``RuntimeError: release
  unlocked lock`` instead: the solve crashed. Raised inside numba's compiler, it can leave the
  compiler broken for the rest of the process (the kernel warm-up is
  therefore a :func:`deferred` block). Raised inside the Python that
  compiled code calls back (numba unpickles its constants for each call
  that takes a ``numpy.random.Generator``), it made the call end in
  ``SystemError: ... returned a result with an exception set`` or the
  process in a segmentation fault (``multiarm simulate`` interrupted during
  the local search's moves): such calls are :func:`atomic`.

While a solve runs, :func:`guard` replaces Python's handler (only when it
is Python's own, on the main thread) with one that first *notes* the
Ctrl-C in :attr:`CtrlC.hit` — the search loops poll it, through
:class:`StopEvent` — and then raises KeyboardInterrupt as before, except
inside a :func:`deferred` block, which raises it at its end. The handler
takes no lock (a handler that waits on a lock its own thread holds hangs).
A second Ctrl-C raises at once, as Python's default does, except inside an
:func:`atomic` block, where it waits for the block's end as the first does
(a SIGINT every fraction of a millisecond during the moves crashed the
process there once a first one had been noted); after the solve the
previous handler is back.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = ["CtrlC", "StopEvent", "atomic", "current", "deferred", "guard"]


class CtrlC:
    """The Ctrl-C state of one solve (shared by the solves nested in it)."""

    __slots__ = ("_atomic", "_defer", "_pending", "active", "hit")

    def __init__(self, active: bool) -> None:
        self.active = active
        """Whether the handler is installed (False: ``hit`` never turns True)."""
        self.hit = False
        """Set by the first Ctrl-C during the solve, whatever became of its exception."""
        self._defer = 0
        self._atomic = 0
        self._pending = False


_NONE = CtrlC(False)
_ACTIVE: list[CtrlC] = []


def current() -> CtrlC:
    """The running solve's :class:`CtrlC` (an inactive one outside any guard,
    and on any thread but the main one)."""
    if not _ACTIVE or threading.current_thread() is not threading.main_thread():
        return _NONE
    return _ACTIVE[-1]


def _on_sigint(signum: int, frame: FrameType | None) -> None:
    c = current()
    if c.active and c._atomic:
        # inside a compiled call's callback even a second Ctrl-C waits for the
        # call's end (raised in there, it can crash the process: atomic)
        c.hit = True
        c._pending = True
        return
    if c.hit or not c.active:  # a second Ctrl-C: Python's default, at once
        raise KeyboardInterrupt
    c.hit = True
    if c._defer:
        c._pending = True  # raised at the end of the deferred block
        return
    raise KeyboardInterrupt


@contextmanager
def guard() -> Iterator[CtrlC]:
    """Note Ctrl-C for the duration of a solve (nested guards share the outer one).

    Installs the handler only on the main thread and only over Python's own
    handler (a program's own SIGINT handler stays in charge); otherwise the
    :class:`CtrlC` yielded is inactive and Ctrl-C behaves as before.
    """
    if threading.current_thread() is not threading.main_thread():
        yield _NONE
        return
    if _ACTIVE:
        yield _ACTIVE[-1]
        return
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield _NONE
        return
    c = CtrlC(True)
    _ACTIVE.append(c)
    previous = signal.signal(signal.SIGINT, _on_sigint)
    try:
        yield c
    finally:
        signal.signal(signal.SIGINT, previous)
        _ACTIVE.pop()


@contextmanager
def deferred(reraise: bool = True) -> Iterator[None]:
    """A block a first Ctrl-C must not break in the middle of (a thread's
    start, a wait on an Event): it is noted at once and raised as
    KeyboardInterrupt at the end, or only noted (``reraise=False``: the block
    reads :attr:`CtrlC.hit` itself)."""
    c = current()
    c._defer += 1
    try:
        yield
    finally:
        c._defer -= 1
        if not c._defer and c._pending:
            c._pending = False
            if reraise:
                raise KeyboardInterrupt


@contextmanager
def atomic() -> Iterator[None]:
    """A compiled call that calls back into Python, which a Ctrl-C must not
    enter: a SIGINT during it raises KeyboardInterrupt at its end.

    Inside a solve (:func:`guard`) it is a :func:`deferred` block in which a
    second Ctrl-C is deferred too (elsewhere a second one raises at once: in
    here that could crash the process, and the block is one compiled call);
    outside one, on the main thread under Python's own handler, a handler
    that only notes the SIGINT is in place for the block; elsewhere nothing
    changes.
    """
    c = current()
    if c.active:
        with deferred():
            c._atomic += 1
            try:
                yield
            finally:
                c._atomic -= 1
        return
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield
        return
    hit: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, _frame: hit.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if hit:
        raise KeyboardInterrupt


class StopEvent(threading.Event):
    """A stop request the search loops poll (``Evaluator.stop``): set by
    :meth:`set`, or by a Ctrl-C during the solve ``ctrl_c`` belongs to. Only
    :meth:`is_set` sees the Ctrl-C (it reads a flag, taking no lock)."""

    def __init__(self, ctrl_c: CtrlC) -> None:
        super().__init__()
        self._ctrl_c = ctrl_c

    def is_set(self) -> bool:
        return self._ctrl_c.hit or super().is_set()
