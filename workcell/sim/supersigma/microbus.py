"""Deprecated module path: use :mod:`workcell.sim.comms.microbus` (this shim stays for one release)."""

import warnings

from workcell.sim.comms.microbus import *  # noqa: F403
from workcell.sim.comms.microbus import __all__ as __all__

warnings.warn(
    "workcell.sim.supersigma.microbus moved to workcell.sim.comms.microbus",
    DeprecationWarning,
    stacklevel=2,
)
