"""The local search's moves written in plain Python over the problem's
objects: the reference the compiled :mod:`scheduler.kernel.moves_jit` is
checked against (``test_moves_jit.py``). The same random draws in the same
order: ``rng.random(T)`` for the chain, ``rng.integers(k)`` per choice among
several reasons on its continuation through the list, one ``rng.permutation``
of the moves."""

from __future__ import annotations

import numpy as np

from scheduler.kernel import State, critical_chain
from scheduler.kernel.critical import task_reasons
from scheduler.kernel.moves_jit import AFTER, BEFORE, MODE
from scheduler.search import Evaluator

TOL = 1e-6


def chrono_chain(
    ev: Evaluator,
    st: State,
    order: np.ndarray,
    pos: np.ndarray,
    chain: list[tuple[int, str, int]],
    rng: np.random.Generator,
) -> list[tuple[int, str, int]]:
    """The chain continued through the list (where the list held a task)."""
    p = ev.problem
    links = p.n_tasks
    seen = {t for t, _r, _b in chain}
    out = list(chain)
    while out and out[-1][1] == "release" and links > 0:
        t = out[-1][0]
        S = float(st.t_start[t])
        release = float(p.task_release[t]) if ev.release is None else float(ev.release[t])
        i = int(pos[t])
        if i <= 0 or release + TOL >= S:
            break
        x = int(order[i - 1])
        if abs(float(st.t_start[x]) - S) > TOL or x in seen:
            break
        out[-1] = (t, "list", x)
        links -= 1
        u = x
        while links > 0:
            seen.add(u)
            rs = task_reasons(ev.inst, st, u)
            if not rs:
                out.append((u, "release", -1))
                break
            reason, by = rs[int(rng.integers(len(rs)))] if len(rs) > 1 else rs[0]
            out.append((u, reason, by))
            links -= 1
            if by in seen:
                break
            u = by
        else:
            break
    return out


def moves(
    ev: Evaluator, st: State, order: np.ndarray, current: np.ndarray, rng: np.random.Generator
) -> list[tuple[int, int, int]]:
    """The shuffled moves around the critical chain: (kind, a, b) as in
    :func:`scheduler.kernel.moves_jit.neighbour_moves`."""
    p = ev.problem
    frozen = ev.frozen
    allowed = ev.allowed
    chain = critical_chain(ev.inst, st, rng)
    pos = np.full(p.n_tasks, -1, dtype=np.int64)
    pos[order] = np.arange(len(order))
    if ev.chrono:
        chain = chrono_chain(ev, st, order, pos, chain, rng)

    def ok_mode(m: int) -> bool:
        return allowed is None or bool(allowed[m])

    out: list[tuple[int, int, int]] = []
    for t, reason, by in chain:
        if t in frozen:
            continue
        for m in p.task_modes[t]:
            if m != current[t] and ok_mode(m):
                out.append((MODE, t, m))
        if reason in ("arm", "resource", "list") and by >= 0 and by not in frozen:
            i, j = int(pos[t]), int(pos[by])
            if i > j and all(pos[q] < j for q in p.task_preds[t]):
                out.append((BEFORE, t, by))
            if j < i and all(pos[s] > i for s in p.task_succs[by]):
                out.append((AFTER, by, t))
            if reason == "resource":
                for m in p.task_modes[by]:
                    if m != current[by] and ok_mode(m):
                        out.append((MODE, by, m))
    idx = rng.permutation(len(out))
    return [out[i] for i in idx]
