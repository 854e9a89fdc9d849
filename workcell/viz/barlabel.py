"""Names written on bars, shown only where they fit (matplotlib).

A :class:`BarLabel` is a text centred on a bar of a Gantt chart that decides
at every draw whether it fits inside its bar, in display units (the text's
extent against the bar's, after the layout and at the output's resolution):
a name never spills over a neighbouring task. Imported by
:mod:`workcell.viz.plots` only when a chart is drawn, since matplotlib is an
optional dependency (``multiarm[analysis]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.backend_bases import RendererBase
from matplotlib.patches import Rectangle
from matplotlib.text import Text

__all__ = ["LABEL_FONTSIZE", "BarLabel"]

LABEL_FONTSIZE = 6.5
"""Points: the size of task names on bars."""


class BarLabel(Text):
    """A text centred on ``bar``, drawn only when it fits inside it.

    Parameters
    ----------
    bar : matplotlib.patches.Rectangle
    text : str
    **kwargs
        Passed to :class:`matplotlib.text.Text` (``color``, ``gid``, ...).

    Attributes
    ----------
    bar : matplotlib.patches.Rectangle
    shown : bool or None
        Whether the last draw drew the text (None before the first draw).
    """

    def __init__(self, bar: Rectangle, text: str, **kwargs: Any) -> None:
        kwargs.setdefault("fontsize", LABEL_FONTSIZE)
        super().__init__(
            bar.get_x() + bar.get_width() / 2,
            bar.get_y() + bar.get_height() / 2,
            text,
            ha="center",
            va="center",
            clip_on=True,
            **kwargs,
        )
        self.bar = bar
        self.shown: bool | None = None
        self.set_in_layout(False)  # inside the axes: no say in the layout

    def fits(self, renderer: RendererBase) -> bool:
        """Whether the text, with a margin of 2 points each side, lies inside the bar."""
        tb = super().get_window_extent(renderer)
        bb = self.bar.get_window_extent(renderer)
        margin = float(np.asarray(renderer.points_to_pixels(2.0), dtype=float))
        return bool(tb.width + 2 * margin <= bb.width and tb.height <= bb.height)

    def draw(self, renderer: RendererBase) -> None:
        """Draw the text if it is visible and fits its bar (sets :attr:`shown`)."""
        self.shown = bool(self.get_visible()) and self.fits(renderer)
        if self.shown:
            super().draw(renderer)
