"""The numba switch shared by the kernel modules.

``MULTIARM_NO_JIT=1`` (or ``NUMBA_DISABLE_JIT=1``) runs the kernel as plain
Python: the same code, which ``tests/scheduler/test_kernel.py`` compares with
the compiled one and ``benchmarks/bench_kernel.py`` measures against it.
"""

from __future__ import annotations

import hashlib
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["EPS", "INF", "NO_REFCOUNT", "drop_stale_cache", "jit_enabled", "njit"]

EPS = 1e-9
"""Overlaps and time differences below this (seconds) do not count."""

INF = math.inf

_NO_JIT = os.environ.get("MULTIARM_NO_JIT", "") not in ("", "0")

if _NO_JIT:  # pragma: no cover - exercised by the kernel benchmark and test in a subprocess

    def njit(*args: Any, **kwargs: Any) -> Any:
        """Plain-Python stand-in for :func:`numba.njit` (returns the function)."""
        if args and callable(args[0]):
            return args[0]
        return lambda f: f

else:
    from numba import njit
    from numba.core.cpu import CPUTargetOptions

NO_REFCOUNT: dict[str, Any] = (
    {"_nrt": False} if not _NO_JIT and hasattr(CPUTargetOptions, "_nrt") else {}
)
"""Options of :func:`njit` for kernel functions that only read and write the
arrays they are given (no new array, no view of one): compiled without
numba's runtime, so without the atomic reference counts numba otherwise
keeps on every array a function binds or passes on (its pruning leaves them
in code with branches and loops, where they cost more than the placement
itself). numba refuses to compile such a function that would need its
runtime ("NRT required but not enabled"), so a mistake cannot go unnoticed.
``{}`` where numba has no such option (then they count references as usual)."""


def jit_enabled() -> bool:
    """Whether the kernel runs compiled by numba.

    Returns
    -------
    bool
        False when ``MULTIARM_NO_JIT`` or ``NUMBA_DISABLE_JIT`` is set.

    Examples
    --------
    >>> isinstance(jit_enabled(), bool)
    True
    """
    return not _NO_JIT and os.environ.get("NUMBA_DISABLE_JIT", "") in ("", "0")


def drop_stale_cache(dispatchers: Sequence[Any], sources: Sequence[Path]) -> bool:
    """Delete numba's cached machine code of the kernel when any of its source files changed.

    numba checks each cached function against its *own* file only: after an
    edit of :mod:`scheduler.kernel.place`, the cached passes of
    :mod:`scheduler.kernel.passes` (which inline placement code) would load
    stale. A digest of every kernel source is kept next to the cache; when it
    differs, the kernel's cache files are removed (and compiled again on use).

    Parameters
    ----------
    dispatchers : sequence of numba dispatchers
        Any compiled kernel functions (they tell where the cache lives).
    sources : sequence of Path
        The kernel's numba source files.

    Returns
    -------
    bool
        Whether cache files were dropped.
    """
    if not jit_enabled():
        return False
    digest = hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()
    dropped = False
    dirs = {getattr(getattr(d, "_cache", None), "_cache_path", None) for d in dispatchers}
    for where in filter(None, dirs):
        folder = Path(str(where))
        stamp = folder / "scheduler-kernel.sha256"
        try:
            if stamp.is_file() and stamp.read_text().strip() == digest:
                continue
            for src in sources:
                for f in folder.glob(f"{src.stem}.*.nb[ic]"):
                    f.unlink(missing_ok=True)
                    dropped = True
            folder.mkdir(parents=True, exist_ok=True)
            stamp.write_text(digest + "\n")
        except OSError:  # a read-only cache: numba then compiles in memory
            continue
    return dropped
