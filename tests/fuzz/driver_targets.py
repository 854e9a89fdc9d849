"""Tiny fuzz targets with a planted finding, for the tests of the driver
(:mod:`tests.fuzz.campaign`, :mod:`tests.fuzz.run`): each finds an input
starting with ``b"boom"`` and ends the process the way a real finding can,
without libFuzzer getting to write the input. They import nothing of the
package, so a run starts in a second."""

from __future__ import annotations

import atexit
import os
import signal
from pathlib import Path

__all__ = ["killed", "raise_then_shutdown_exits"]


def raise_then_shutdown_exits(data: bytes, workdir: Path) -> None:
    """A finding (an exception) after which the interpreter's shutdown ends the
    process before libFuzzer's exit handler runs (which writes the test unit)."""
    if data.startswith(b"boom"):
        atexit.register(os._exit, 3)
        raise RuntimeError("planted finding")


def killed(data: bytes, workdir: Path) -> None:
    """A finding that kills the process outright (as the kernel's
    out-of-memory killer does): no handler of any kind runs."""
    if data.startswith(b"boom"):
        os.kill(os.getpid(), signal.SIGKILL)
