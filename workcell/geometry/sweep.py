"""Deprecated path of :mod:`workcell.geometry.zone_sweep` (the zone sweep), kept one release.

*Sweep* also names a parameter sweep (:mod:`workcell.experiments`), so the
geometric one lives in :mod:`workcell.geometry.zone_sweep`. Every name read
from this module is the one of ``zone_sweep`` and warns
(``DeprecationWarning``); import it from ``workcell.geometry.zone_sweep``.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

from workcell.geometry import zone_sweep as _new

if TYPE_CHECKING:  # the names as typed in zone_sweep (at run time __getattr__ hands them on)
    from workcell.geometry.zone_sweep import *  # noqa: F403
    from workcell.geometry.zone_sweep import _segment_distances as _segment_distances
    from workcell.geometry.zone_sweep import _segments as _segments
    from workcell.geometry.zone_sweep import _shape_capsules as _shape_capsules


def __getattr__(name: str) -> Any:
    value = getattr(_new, name)  # AttributeError for a name zone_sweep does not have
    warnings.warn(
        f"workcell.geometry.sweep.{name} is deprecated: "
        f"import it from workcell.geometry.zone_sweep",
        DeprecationWarning,
        stacklevel=2,
    )
    return value
