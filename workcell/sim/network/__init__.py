"""Network media for the simulated cell (S2.8, S2.9).

Every class here is a :class:`workcell.sim.medium.Medium`:

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

from workcell.sim.network.batch import ethernet_rounds
from workcell.sim.network.dcr import REDUCED, dcr_bound, dcr_rounds, min_slot_time
from workcell.sim.network.ethernet import EthernetMedium, EthernetParams, TransmitChain
from workcell.sim.network.media import MEDIA, MEDIUM_PARAMS, make_medium
from workcell.sim.network.multibus import MultibusII, unsolicited_count
from workcell.sim.network.serial import SerialBus, SerialStar, line_time

__all__ = [
    "MEDIA",
    "MEDIUM_PARAMS",
    "REDUCED",
    "EthernetMedium",
    "EthernetParams",
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
    "unsolicited_count",
]
