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
    shapes = p.shapes
    T = p.n_tasks
    waits = []
    blocking = np.zeros(T)
    modes, starts, ends = st.t_mode.tolist(), st.t_start.tolist(), st.t_end.tolist()
    for t in range(T):
        sh = shapes[modes[t]]
        w = st.t_waits[t, : len(sh.borders)]
        waits.append(w)
        b = max(0.0, ends[t] - starts[t] - sh.length(w))
        if b > 1e-12 * max(1.0, abs(ends[t])):
            blocking[t] = b
    # Schedule copies the arrays (and every wait row) into read-only ones
    return Schedule(st.t_mode, st.t_start, st.t_end, tuple(waits), blocking)
