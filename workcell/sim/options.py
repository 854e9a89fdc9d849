"""Deprecated module path: use :mod:`workcell.sim.harness.options` (this shim stays for one release)."""

import warnings

from workcell.sim.harness.options import *  # noqa: F403
from workcell.sim.harness.options import __all__ as __all__

warnings.warn(
    "workcell.sim.options moved to workcell.sim.harness.options",
    DeprecationWarning,
    stacklevel=2,
)
