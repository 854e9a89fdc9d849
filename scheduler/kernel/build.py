"""Building the :class:`~scheduler.schedule.Schedule` of a complete kernel state."""

from __future__ import annotations

import numpy as np

from scheduler.kernel.arrays import Instance, State
from scheduler.schedule import Schedule

__all__ = ["to_schedule"]


def to_schedule(inst: Instance, st: State) -> Schedule:
    """The schedule of a complete state.

    The blocking (detour) cost of a task is whatever its end exceeds start +
    duration + waits by.

    Parameters
    ----------
    inst : Instance
    st : State
        Every task placed.

    Returns
    -------
    Schedule

    Examples
    --------
    >>> import numpy as np
    >>> from scheduler.generate import random_problem
    >>> from scheduler.kernel import compile_problem, decode
    >>> p = random_problem(2, 6, 1, 0, seed=0)
    >>> code, st = decode(compile_problem(p), np.arange(6), np.full(6, -1))
    >>> code, len(to_schedule(compile_problem(p), st).start)
    (0, 6)
    """
    p = inst.problem
    modes = st.t_mode
    nb = inst.data.bd_ptr[modes + 1] - inst.data.bd_ptr[modes]
    # one read-only copy of the waits; each task's row is a view of it
    W = np.array(st.t_waits, dtype=np.float64)
    W.setflags(write=False)
    waits = [W[t, :k] for t, k in enumerate(nb.tolist())]
    # duration plus waits, summed as ModeShape.length sums them: one after
    # the other from the first (the zeros after a mode's borders add nothing)
    length = np.array(p.mode_duration, dtype=np.float64)[modes]
    if W.size:
        length = length + np.add.accumulate(W, axis=1)[:, -1]
    b = st.t_end - st.t_start - length
    blocking = np.where(b > 1e-12 * np.maximum(1.0, np.abs(st.t_end)), b, 0.0)
    # Schedule copies the mode, start and end arrays into read-only ones
    return Schedule(modes, st.t_start, st.t_end, tuple(waits), blocking)
