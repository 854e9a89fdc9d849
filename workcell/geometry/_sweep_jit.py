"""Deprecated path of :mod:`workcell.geometry._zone_sweep_jit`, kept one release.

Every name read from this module is the one of ``_zone_sweep_jit`` and warns
(``DeprecationWarning``).
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

from workcell.geometry import _zone_sweep_jit as _new

if TYPE_CHECKING:  # the names as typed in _zone_sweep_jit (at run time __getattr__ hands them on)
    from workcell.geometry._zone_sweep_jit import capsules_touch as capsules_touch


def __getattr__(name: str) -> Any:
    value = getattr(_new, name)
    warnings.warn(
        f"workcell.geometry._sweep_jit.{name} is deprecated: "
        f"import it from workcell.geometry._zone_sweep_jit",
        DeprecationWarning,
        stacklevel=2,
    )
    return value
