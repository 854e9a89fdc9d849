"""The hot path: placing tasks on arm and resource timelines, compiled by numba.

The kernel is a small package, one job per module:

* :mod:`~scheduler.kernel.arrays`: a :class:`~scheduler.problem.Problem`
  compiled into flat arrays bundled in typed tuples (:class:`Arrays`,
  :class:`State`, ...) and wrapped in an :class:`Instance`, built once per
  problem by :func:`compile_problem` and cached here;
* :mod:`~scheduler.kernel.place`: the earliest placement of one task on the
  arm gaps and the zone and tool timelines (waits at zone borders, start
  zones, the blocking oracle's detours);
* :mod:`~scheduler.kernel.passes`: whole passes (list decoding, batched
  queries, arm-sequence decoding), with their Python entry points in
  :mod:`~scheduler.kernel.api`;
* :mod:`~scheduler.kernel.build`: the :class:`~scheduler.schedule.Schedule`
  of a complete state;
* :mod:`~scheduler.kernel.critical`: the critical chain of a complete state
  (what the local search moves);
* :mod:`~scheduler.kernel.moves_jit`: the local search's moves around that
  chain (continued through the list when decoding is chronological);
* :mod:`~scheduler.kernel.resume`: chunked list decoding that resumes from a
  saved prefix (the local search's decoder).

``MULTIARM_NO_JIT=1`` (or ``NUMBA_DISABLE_JIT=1``) runs the same code as
plain Python, which ``benchmarks/bench_kernel.py`` uses to measure what the
compilation buys. The first compile takes about a minute once per machine
(numba's on-disk cache keeps it); :func:`warm_up` does it up front and
announces it (:data:`COMPILE_NOTE`; the ``multiarm`` command shows it on
stderr), so that solvers can start their clock afterwards.

With a blocking oracle, its answers live in an array
(:class:`OracleTable`) the compiled decoders read; unknown answers are asked
from Python between passes, and a cell may pre-fill the table
(:meth:`Instance.prefill_blocking`, or a ``table()`` method on the oracle).

Examples
--------
>>> import numpy as np
>>> from scheduler.generate import random_problem
>>> p = random_problem(3, 12, 2, 1, seed=0)
>>> inst = compile_problem(p)
>>> code, st = decode(inst, np.arange(p.n_tasks), np.full(p.n_tasks, -1))
>>> code, bool(np.all(st.t_mode >= 0))
(0, True)
"""

from __future__ import annotations

import warnings
from pathlib import Path

from scheduler.kernel import critical as _critical
from scheduler.kernel import moves_jit as _moves_jit
from scheduler.kernel import passes as _passes
from scheduler.kernel import place as _place
from scheduler.kernel import resume as _resume
from scheduler.kernel._jit import EPS, INF, drop_stale_cache, jit_enabled
from scheduler.kernel.api import (
    COMPILE_NOTE,
    decode,
    expand,
    expand_blocking,
    place_blocking,
    seq_decode,
    warm_up,
)
from scheduler.kernel.arrays import (
    Arrays,
    Ctx,
    Instance,
    OracleTable,
    Scratch,
    State,
    compile_problem,
)
from scheduler.kernel.build import to_schedule
from scheduler.kernel.critical import critical_chain

drop_stale_cache(
    (
        _passes._decode,
        _place._query,
        _critical._chain,
        _resume._decode_chunks,
        _moves_jit._neighbour_moves,
    ),
    [
        Path(_place.__file__),
        Path(_passes.__file__),
        Path(_critical.__file__),
        Path(_resume.__file__),
        Path(_moves_jit.__file__),
    ],
)

__all__ = [
    "COMPILE_NOTE",
    "EPS",
    "INF",
    "Arrays",
    "Ctx",
    "Instance",
    "OracleTable",
    "Scratch",
    "State",
    "compile_problem",
    "critical_chain",
    "decode",
    "drop_stale_cache",
    "expand",
    "expand_blocking",
    "jit_enabled",
    "place_blocking",
    "seq_decode",
    "to_schedule",
    "warm_up",
]


def __getattr__(name: str) -> object:
    """``compiled``: the former name of :func:`compile_problem` (deprecated, one release)."""
    if name == "compiled":
        warnings.warn(
            "scheduler.kernel.compiled is deprecated: use scheduler.kernel.compile_problem",
            DeprecationWarning,
            stacklevel=2,
        )
        return compile_problem
    raise AttributeError(f"module 'scheduler.kernel' has no attribute {name!r}")
