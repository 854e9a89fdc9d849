"""The 3D replay of a simulated run in the browser (docs/replay.md).

* :func:`write_html`: one self-contained HTML file (works offline): the cell
  in 3D with the arms posed at each time, the zones coloured by state
  (free, occupied, moving, waiting), a time slider with play and pause, a
  Gantt strip with a cursor in sync, and the faults marked; colours and
  fault marks as in every plot of a run (:mod:`workcell.style`).
* :func:`build_replay`, :class:`ReplayData`: the same as a JSON document
  that a run directory holds (:func:`save_replay`, :func:`load_replay`), so
  that ``multiarm view RUN_DIR`` rebuilds the page from files alone.
* :func:`show`: the page in a notebook.
* :mod:`workcell.replay.command`: the ``view`` command.

Nothing here imports the simulator (a run is read through
:class:`RunLike`), so the simulator may import this package.
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path
from typing import Any

from workcell.replay.data import (
    FORMAT,
    REPLAY_FILE,
    STATE_COLOURS,
    ReplayData,
    RunLike,
    build_replay,
    load_replay,
)
from workcell.replay.page import render_html, show, write_html

__all__ = [
    "FORMAT",
    "REPLAY_FILE",
    "STATE_COLOURS",
    "ReplayData",
    "RunLike",
    "build_replay",
    "load_replay",
    "render_html",
    "save_replay",
    "show",
    "write_html",
]


def save_replay(
    result: RunLike, cell_or_compiled: Any, directory: str | PathLike[str], **options: Any
) -> Path:
    """Write the replay document of a run into a run directory (:data:`REPLAY_FILE`).

    Parameters
    ----------
    result : workcell.SimResult
    cell_or_compiled : Cell or CompiledCell
    directory : path-like
        Created if missing.
    **options
        ``rate``, ``max_frames``, ``geometry``, ``title`` (:func:`build_replay`).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    return build_replay(result, cell_or_compiled, **options).save(directory)
