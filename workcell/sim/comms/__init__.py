"""The communication layer of the simulation (S2.1, S2.8, S2.9, S1.3).

* :mod:`.medium` -- frames (:class:`Frame`, with per-link sequence numbers)
  and the medium interface (:class:`Medium`), the ideal and fixed-latency
  media;
* :mod:`.link` -- :class:`Link`, the coordination messages' sender: sequence
  numbers, loss, retransmission and the receiver's stale-frame filter;
* the networks below, and the SUPERSIGMA MICROBUS (:mod:`.microbus`, S1.3).

Every network class here is a :class:`workcell.sim.comms.medium.Medium`:

* :class:`SerialStar`, :class:`SerialBus` -- serial lines (:mod:`.serial`);
* :class:`MultibusII` -- parallel bus message passing (:mod:`.multibus`);
* :class:`EthernetMedium` -- CSMA/CD or CSMA/DCR on one bus (:mod:`.ethernet`).

:func:`make_medium` builds any of them (and the ideal and fixed-latency
media) by name, one of :data:`MEDIA` (:mod:`.media`).

:func:`dcr_bound` is the S2.9 worst-case delay; :func:`dcr_rounds` and
:func:`ethernet_rounds` are fast batch contention simulators for delay
statistics over millions of rounds.

Examples
--------
>>> round(dcr_bound() * 1e6)
604
"""

from workcell.sim.comms.batch import ethernet_rounds
from workcell.sim.comms.dcr import REDUCED, dcr_bound, dcr_rounds, min_slot_time
from workcell.sim.comms.ethernet import EthernetMedium, EthernetParams, TransmitChain
from workcell.sim.comms.media import MEDIA, MEDIUM_PARAMS, make_medium
from workcell.sim.comms.medium import (
    BROADCAST,
    MESSAGE_BYTES,
    BaseMedium,
    DelayStats,
    FixedLatencyMedium,
    Frame,
    IdealMedium,
    Medium,
    trajectory_bytes,
)
from workcell.sim.comms.multibus import MultibusII, unsolicited_count
from workcell.sim.comms.serial import SerialBus, SerialStar, line_time

__all__ = [
    "BROADCAST",
    "MEDIA",
    "MEDIUM_PARAMS",
    "MESSAGE_BYTES",
    "REDUCED",
    "BaseMedium",
    "DelayStats",
    "EthernetMedium",
    "EthernetParams",
    "FixedLatencyMedium",
    "Frame",
    "IdealMedium",
    "Medium",
    "MultibusII",
    "SerialBus",
    "SerialStar",
    "TransmitChain",
    "dcr_bound",
    "dcr_rounds",
    "ethernet_rounds",
    "line_time",
    "make_medium",
    "min_slot_time",
    "trajectory_bytes",
    "unsolicited_count",
]
