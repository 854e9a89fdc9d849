"""Deprecated module path: use :mod:`workcell.sim.control.supersigma` (this shim stays for one release)."""

import warnings

from workcell.sim.control.supersigma import *  # noqa: F403
from workcell.sim.control.supersigma import __all__ as __all__

warnings.warn(
    "workcell.sim.supersigma moved to workcell.sim.control.supersigma",
    DeprecationWarning,
    stacklevel=2,
)
