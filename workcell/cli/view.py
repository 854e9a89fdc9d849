"""``multiarm view RUN_DIR``: the 3D replay page of a run directory.

The arguments and the call live in :mod:`workcell.replay.command`; a run
directory written by ``multiarm simulate --out DIR`` or ``multiarm demo``
holds ``replay.json`` (and ``replay.html`` already).
"""

from workcell.replay.command import add_arguments, run

__all__ = ["add_arguments", "run"]
