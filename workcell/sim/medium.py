"""Deprecated module path: use :mod:`workcell.sim.comms.medium` (this shim stays for one release)."""

import warnings

from workcell.sim.comms.medium import *  # noqa: F403
from workcell.sim.comms.medium import __all__ as __all__

warnings.warn(
    "workcell.sim.medium moved to workcell.sim.comms.medium",
    DeprecationWarning,
    stacklevel=2,
)
