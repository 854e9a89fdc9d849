"""Deprecated module path: use :mod:`workcell.sim.events.loop` (this shim stays for one release)."""

import warnings

from workcell.sim.events.loop import *  # noqa: F403
from workcell.sim.events.loop import __all__ as __all__

warnings.warn(
    "workcell.sim.kernel moved to workcell.sim.events.loop",
    DeprecationWarning,
    stacklevel=2,
)
