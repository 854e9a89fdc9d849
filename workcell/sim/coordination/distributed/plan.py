"""What every peer derives from the plan it holds (a replica at each arm).

Every peer holds the same plan, so every peer computes the same resource
orders: per resource, its uses (:class:`~workcell.sim.protocol.messages.Piece`)
sorted by their planned time, the start zones an arm stands in first. These
orders are the priorities of the peers' mutual exclusion
(:mod:`.peer`): a use may begin once every use placed before it is over, as
the centralized coordinator's plan-order rule (S2.5-S2.7).
"""

from __future__ import annotations

import bisect
import itertools
import math
from typing import NamedTuple

import numpy as np

from scheduler import Problem, Schedule
from workcell.compile import CompiledCell
from workcell.sim.protocol.exchange import ArmView
from workcell.sim.protocol.messages import Leg, Piece, Station
from workcell.sim.protocol.peers import Resource

__all__ = ["PieceUse", "arm_of", "build_legs", "resource_orders", "task_pieces"]


class PieceUse(NamedTuple):
    """One use of a resource by a task under a plan (frozen).

    Attributes
    ----------
    piece : Piece
    start, end : float
        Offsets in the task where it is acquired and given back, seconds.
    wall : float
        The plan's time of the acquire, seconds.
    """

    piece: Piece
    start: float
    end: float
    wall: float


def arm_of(p: Problem, plan: Schedule, t: int) -> int:
    """The arm the plan gives task ``t``."""
    return int(p.mode_arm[int(plan.mode[t])])


def task_pieces(p: Problem, plan: Schedule, t: int) -> list[PieceUse]:
    """Every resource use of task ``t`` under ``plan`` (as the centralized
    coordinator cuts them: exclusive zones whole, moves in shared zones cut
    at the borders where the plan waits, tools for the whole task)."""
    m = int(plan.mode[t])
    sh = p.shapes[m]
    S = float(plan.start[t])
    wl = plan.waits[t].tolist()
    Z = p.n_zones
    borders = sh.borders
    cw = [0.0]
    for x in wl:
        cw.append(cw[-1] + x)
    out: list[PieceUse] = []
    for r, s, e in sh.exclusive:
        out.append(
            PieceUse(Piece("zone", r, t, s), s, e, S + s + cw[bisect.bisect_right(borders, s)])
        )
    wait_at = dict(zip(borders, wl, strict=True))
    for r, s, e in sh.moves:
        cuts = [b for b in borders if s < b < e and wait_at[b] > 0]
        for p0, p1 in itertools.pairwise([s, *cuts, e]):
            wall = S + p0 + cw[bisect.bisect_right(borders, p0)]
            out.append(PieceUse(Piece("move", r - Z, t, p0), p0, p1, wall))
    for r in sh.tools:
        out.append(PieceUse(Piece("tool", r - 2 * Z, t, 0.0), 0.0, sh.duration, S))
    return out


def resource_orders(p: Problem, plan: Schedule) -> dict[Resource, list[Piece]]:
    """Per resource, its uses in plan order (start zones first)."""
    orders: dict[Resource, list[tuple[float, int, float, Piece]]] = {}
    for a in range(p.n_arms):
        for z in p.arm_start_zones[a]:
            if p.zone_exclusive[z]:
                piece = Piece("zone", int(z), -1 - a, 0.0)
                orders.setdefault(("zone", int(z)), []).append((-math.inf, -1, 0.0, piece))
    for t in range(p.n_tasks):
        for piece, _s, _e, wall in task_pieces(p, plan, t):
            orders.setdefault((piece.kind, piece.resource), []).append((wall, t, piece.tau, piece))
    return {k: [x[3] for x in sorted(v, key=lambda x: x[:3])] for k, v in orders.items()}


def build_legs(
    cc: CompiledCell,
    plan: Schedule,
    arm: ArmView,
    t: int,
    first_task: bool,
    pieces: list[PieceUse] | None = None,
) -> list[Leg]:
    """The legs of task ``t`` (travel from where the arm stands, then the
    task), with the plan's times at the start and at every border, and the
    resource uses at their stations (as the S2.7 trajectory message);
    ``arm`` is the arm's own view (where it stands). Both policies build
    their trajectory messages with it; ``pieces`` are the task's uses under
    ``plan`` when the caller has them already (:func:`task_pieces`)."""
    p = cc.problem
    a = arm.index
    m = int(plan.mode[t])
    cm = cc.modes[m]
    S = float(plan.start[t])
    sh = p.shapes[m]
    w = plan.waits[t]
    stations: dict[float, Station] = {0.0: Station(0.0, notbefore=S, start=True)}
    for j, b in enumerate(sh.borders):
        stations[b] = Station(b, notbefore=S + b + float(np.sum(w[: j + 1])), border=j)
    D = float(cm.trajectory.duration)
    end = Station(D, end=True)
    for piece, s, e, _wall in task_pieces(p, plan, t) if pieces is None else pieces:
        stations.setdefault(s, Station(s)).acquire.append(piece)
        if e >= D:
            end.release.append(piece)
        else:
            stations.setdefault(e, Station(e)).release.append(piece)
    stations.pop(D, None)
    task_st = [stations[k] for k in sorted(stations)] + [end]
    legs: list[Leg] = []
    model = cc.cell.arms[a]
    travel = model.move(arm.q, cm.q_start, model.interpolation)
    first: list[Piece] = []
    if first_task:  # leaving the start zones
        first = [
            Piece("zone", int(z), -1 - a, 0.0) for z in p.arm_start_zones[a] if p.zone_exclusive[z]
        ]
    if travel.duration > 0:
        legs.append(
            Leg(
                "travel",
                t,
                -1,
                travel,
                [Station(0.0, release=first), Station(travel.duration, end=True)],
            )
        )
    else:
        task_st[0].release.extend(first)
    legs.append(Leg("task", t, m, cm.trajectory, task_st))
    return legs
