"""Deprecated module path: use :mod:`workcell.sim.control.supersigma.schedule` (this shim stays for one release)."""

import warnings

from workcell.sim.control.supersigma.schedule import *  # noqa: F403
from workcell.sim.control.supersigma.schedule import __all__ as __all__

warnings.warn(
    "workcell.sim.supersigma.schedule moved to workcell.sim.control.supersigma.schedule",
    DeprecationWarning,
    stacklevel=2,
)
