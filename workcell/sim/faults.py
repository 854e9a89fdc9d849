"""Deprecated module path: use :mod:`workcell.sim.harness.faults` (this shim stays for one release)."""

import warnings

from workcell.sim.harness.faults import *  # noqa: F403
from workcell.sim.harness.faults import __all__ as __all__

warnings.warn(
    "workcell.sim.faults moved to workcell.sim.harness.faults",
    DeprecationWarning,
    stacklevel=2,
)
