"""Deprecated module path: use :mod:`workcell.sim.comms` (this shim stays for one release)."""

import warnings

from workcell.sim.comms import *  # noqa: F403
from workcell.sim.comms import __all__ as __all__

warnings.warn(
    "workcell.sim.network moved to workcell.sim.comms",
    DeprecationWarning,
    stacklevel=2,
)
