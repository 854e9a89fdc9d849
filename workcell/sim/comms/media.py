"""Media by name: the one entry point the simulation uses to build a medium.

``make_medium(name, kernel, stations, **params)`` returns a
:class:`workcell.sim.comms.medium.Medium` with stations ``0..n-1``; station 0 is
the coordinator, stations 1..N the arms in the cell's arm order. The names,
in :data:`MEDIA`, and the parameters each accepts (every one optional):

===============  ==========================================================
name             parameters (defaults)
===============  ==========================================================
``ideal``        none: zero delay
``fixed``        ``latency`` (1e-3 s)
``csma-dcr``     ``bus_length`` (100 m, stations evenly spaced along it,
                 the coordinator at one end) or ``positions`` (metres, one
                 per station), ``rate`` (10e6 b/s), ``slot_time``
                 (51.2e-6 s), ``ifs`` (9.6e-6 s), ``jam_bits`` (32),
                 ``propagation_speed`` (2e8 m/s), ``detect_delay``
                 (epsilon, 0 s), ``min_frame_bytes`` (0), ``order``
                 (resolution order, station number), ``priority_chain``
                 (True)
``ethernet``     as ``csma-dcr``, plus ``max_attempts`` (16) and
                 ``backoff_limit`` (10); ``priority_chain`` defaults to False
``multibus2``    ``bandwidth`` (40e6 B/s), ``unsolicited_payload`` (20 B),
                 ``arbitration`` (0.2e-6 s), ``mpc_latency`` (2e-6 s),
                 ``solicited_kinds`` (``("trajectory",)``)
``serial-star``  ``rate`` (9600 b/s), ``header_bytes`` (4), ``hub`` (0)
``serial-bus``   ``rate`` (9600 b/s), ``header_bytes`` (4)
===============  ==========================================================

Every medium also accepts ``seed`` (int or Generator, default 0): the random
source of Ethernet's backoff, ignored by the deterministic media, so a caller
can pass one seed whatever the medium; without one a run still replays. Names are case-insensitive and ``_`` may stand
for ``-`` (``"csma_dcr"``). An unknown name, an unknown parameter or a bad
value raises :class:`multiarm.errors.UsageError` naming the choices.

Examples
--------
>>> from workcell.sim.events.loop import EventLoop
>>> from workcell.sim.comms.medium import Frame
>>> k = EventLoop()
>>> m = make_medium("csma-dcr", k, 10)
>>> _ = m.send(Frame(src=1, dst=0, size=51, kind="position"))
>>> k.run()
>>> round(m.stats.max() * 1e6, 2)   # 51 bytes at 10 Mb/s + 100/9 m of propagation
40.86
>>> make_medium("token-bus", k, 3)
Traceback (most recent call last):
...
multiarm.errors.UsageError: unknown medium 'token-bus'; choose one of: ideal, fixed, csma-dcr, ethernet, multibus2, serial-star, serial-bus
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from multiarm.errors import UsageError, ValidationError
from workcell.sim.comms.ethernet import EthernetMedium, EthernetParams, Mode
from workcell.sim.comms.medium import FixedLatencyMedium, IdealMedium, Medium
from workcell.sim.comms.multibus import MultibusII
from workcell.sim.comms.serial import SerialBus, SerialStar
from workcell.sim.events.loop import EventLoop

__all__ = ["MEDIA", "MEDIUM_PARAMS", "make_medium"]

MEDIA: tuple[str, ...] = (
    "ideal",
    "fixed",
    "csma-dcr",
    "ethernet",
    "multibus2",
    "serial-star",
    "serial-bus",
)
"""The medium names :func:`make_medium` accepts."""

_ETHER_PHY = (
    "rate",
    "slot_time",
    "ifs",
    "jam_bits",
    "propagation_speed",
    "detect_delay",
    "min_frame_bytes",
)
_ETHER_MAC = ("bus_length", "positions", "order", "priority_chain")

MEDIUM_PARAMS: dict[str, tuple[str, ...]] = {
    "ideal": (),
    "fixed": ("latency",),
    "csma-dcr": (*_ETHER_MAC, *_ETHER_PHY),
    "ethernet": (*_ETHER_MAC, *_ETHER_PHY, "max_attempts", "backoff_limit"),
    "multibus2": (
        "bandwidth",
        "unsolicited_payload",
        "arbitration",
        "mpc_latency",
        "solicited_kinds",
    ),
    "serial-star": ("rate", "header_bytes", "hub"),
    "serial-bus": ("rate", "header_bytes"),
}
"""Parameters each medium accepts besides ``seed``."""


def _ethernet(
    mode: Mode, kernel: EventLoop, stations: int | Sequence[int], p: dict[str, Any]
) -> Medium:
    n = stations if isinstance(stations, int) else len(stations)
    if not isinstance(stations, int) and list(stations) != list(range(n)):
        raise ValidationError(f"stations must be numbered 0..n-1, got {list(stations)}")
    if "positions" in p and "bus_length" in p:
        raise ValidationError("give bus_length or positions, not both")
    positions = p.pop("positions", None)
    bus_length = float(p.pop("bus_length", 100.0))
    if positions is not None:
        if len(positions) != n:
            raise ValidationError(f"positions: {len(positions)} given for {n} stations")
    else:
        if not (bus_length > 0 and np.isfinite(bus_length)):
            raise ValidationError(f"bus_length must be > 0 metres, got {bus_length!r}")
        if n < 2:
            raise ValidationError(f"needs >= 2 stations, got {n}")
        positions = np.linspace(0.0, bus_length, n)
    phy = {k: p.pop(k) for k in (*_ETHER_PHY, "max_attempts", "backoff_limit") if k in p}
    params = EthernetParams(**phy)
    return EthernetMedium(
        kernel,
        positions,
        mode=mode,
        params=params,
        order=p.pop("order", None),
        priority_chain=p.pop("priority_chain", None),
        seed=p.pop("seed", 0),
    )


_BUILDERS: dict[str, Callable[[EventLoop, int | Sequence[int], dict[str, Any]], Medium]] = {
    "ideal": lambda k, s, p: IdealMedium(k, s),
    "fixed": lambda k, s, p: FixedLatencyMedium(k, s, float(p.get("latency", 1e-3))),
    "csma-dcr": lambda k, s, p: _ethernet("csma_dcr", k, s, p),
    "ethernet": lambda k, s, p: _ethernet("csma_cd", k, s, p),
    "multibus2": lambda k, s, p: MultibusII(k, s, **{x: v for x, v in p.items() if x != "seed"}),
    "serial-star": lambda k, s, p: SerialStar(k, s, **{x: v for x, v in p.items() if x != "seed"}),
    "serial-bus": lambda k, s, p: SerialBus(k, s, **{x: v for x, v in p.items() if x != "seed"}),
}


def normalise_name(name: object) -> str:
    """The canonical medium name for ``name``.

    Parameters
    ----------
    name : str
        A medium name, any case, ``_`` or ``-``.

    Returns
    -------
    str
        One of :data:`MEDIA`.

    Raises
    ------
    UsageError
        For anything else, naming the choices.

    Examples
    --------
    >>> normalise_name("CSMA_DCR")
    'csma-dcr'
    """
    key = name.strip().lower().replace("_", "-") if isinstance(name, str) else None
    if key not in _BUILDERS:
        raise UsageError(f"unknown medium {name!r}; choose one of: {', '.join(MEDIA)}")
    return key


def make_medium(
    name: str, kernel: EventLoop, stations: int | Sequence[int], **params: Any
) -> Medium:
    """Build the medium called ``name`` (see the module docstring).

    Parameters
    ----------
    name : str
        One of :data:`MEDIA`.
    kernel : EventLoop
        The simulation kernel.
    stations : int or sequence of int
        Number of stations, or the list ``0..n-1``; station 0 is the
        coordinator.
    **params
        The medium's parameters (:data:`MEDIUM_PARAMS`) and ``seed``.

    Returns
    -------
    Medium
        A fresh medium attached to ``kernel``.

    Raises
    ------
    UsageError
        For an unknown name or parameter (the message lists the choices) or a
        bad value (the message names the medium and the parameter).

    Examples
    --------
    >>> from workcell.sim.events.loop import EventLoop
    >>> m = make_medium("fixed", EventLoop(), 3, latency=2e-3)
    >>> m.latency, m.n_stations
    (0.002, 3)
    >>> make_medium("serial-bus", EventLoop(), 3, baud=9600)
    Traceback (most recent call last):
    ...
    multiarm.errors.UsageError: medium 'serial-bus': unknown parameter 'baud'; accepted: rate, header_bytes, seed
    """
    key = normalise_name(name)
    allowed = MEDIUM_PARAMS[key]
    for p in params:
        if p not in allowed and p != "seed":
            raise UsageError(
                f"medium {key!r}: unknown parameter {p!r}; accepted: "
                f"{', '.join((*allowed, 'seed'))}"
            )
    try:
        return _BUILDERS[key](kernel, stations, dict(params))
    except (ValidationError, TypeError, ValueError) as exc:
        raise UsageError(f"medium {key!r}: {exc}") from exc


def describe(name: str) -> Mapping[str, tuple[str, ...]]:
    """The parameters ``name`` accepts, keyed by its canonical name.

    Parameters
    ----------
    name : str
        A medium name.

    Returns
    -------
    mapping
        ``{canonical_name: parameters}``.

    Examples
    --------
    >>> describe("fixed")
    {'fixed': ('latency', 'seed')}
    """
    key = normalise_name(name)
    return {key: (*MEDIUM_PARAMS[key], "seed")}
