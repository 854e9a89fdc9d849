"""Building the :class:`~scheduler.schedule.Schedule` of a complete kernel state."""

from __future__ import annotations

import numpy as np

from scheduler.kernel.compile import Instance, State
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
    >>> from scheduler.kernel import compiled, decode
    >>> p = random_problem(2, 6, 1, 0, seed=0)
    >>> code, st = decode(compiled(p), np.arange(6), np.full(6, -1))
    >>> code, len(to_schedule(compiled(p), st).start)
    (0, 6)
    """
    p = inst.problem
    shapes = p.shapes
    T = p.n_tasks
    waits = []
    blocking = np.zeros(T)
    for t in range(T):
        m = int(st.t_mode[t])
        sh = shapes[m]
        w = st.t_waits[t, : len(sh.borders)].copy()
        waits.append(w)
        blocking[t] = max(0.0, float(st.t_end[t]) - float(st.t_start[t]) - sh.length(w))
        if blocking[t] <= 1e-12 * max(1.0, abs(float(st.t_end[t]))):
            blocking[t] = 0.0
    return Schedule(st.t_mode.copy(), st.t_start.copy(), st.t_end.copy(), tuple(waits), blocking)
