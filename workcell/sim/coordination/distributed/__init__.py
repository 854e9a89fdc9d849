"""Distributed coordination (S2.4, S2.7): one peer per arm, no coordinator.

:class:`DistributedPolicy` is registered as ``coordination="distributed"``
(:data:`workcell.sim.coordination.policy.POLICIES`); :class:`Peer` is one
arm's coordination half (:mod:`.peer`), with its own view of the arms and
its departure check (:class:`~.sight.Sight`, from frames on the medium
only); :mod:`.plan` derives the resource orders every peer holds.
"""

from workcell.sim.coordination.distributed.peer import Peer
from workcell.sim.coordination.distributed.policy import DistributedPolicy

__all__ = ["DistributedPolicy", "Peer"]
