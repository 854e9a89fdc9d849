"""Deprecated module path: use :mod:`workcell.sim.harness.simulate` (this shim stays for one release)."""

import warnings

from workcell.sim.harness.simulate import *  # noqa: F403
from workcell.sim.harness.simulate import __all__ as __all__

warnings.warn(
    "workcell.sim.run moved to workcell.sim.harness.simulate",
    DeprecationWarning,
    stacklevel=2,
)
