"""A fixed layout of a figure's panels, measured once.

Matplotlib's constrained layout measures every text of every axes in two passes and
draws the figure twice on saving: for a grid of maps with colour bars that is most of
the figure's cost. Here the panels have a given size in inches; their decorations (tick
labels, axis labels, titles) are measured once at that size, the margins and gaps are
the largest of them plus a pad, the figure's size follows, and saving draws it once.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.legend import Legend
    from matplotlib.text import Text

__all__ = ["place_grid", "renderer"]

#: Space (inches) between the decorations of neighbouring panels, and at the edges.
GAP = 0.12
PAD = 0.06


_PARSER: list[Any] = []


def renderer(fig: Figure) -> Any:
    """The Agg renderer of ``fig`` at its size and dpi (the figure gets an Agg canvas,
    as saving to PNG gives it), which saving at that dpi reuses.

    Every such renderer parses mathtext with one parser: its cache keeps the parsed
    labels from the measuring renderer to the drawing one and from figure to figure
    (each renderer otherwise has its own, and parsing is a large part of a first draw).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    r = canvas.get_renderer()
    if hasattr(r, "mathtext_parser"):
        if not _PARSER:
            _PARSER.append(r.mathtext_parser)
        r.mathtext_parser = _PARSER[0]
    return r


def _overhang(axes: Sequence[Axes], r: Any, dpi: float) -> NDArray[np.float64]:
    """How far the decorations of axes sharing one box reach beyond it (inches): left,
    right, bottom, top. The texts' whole extents count (a title or an axis label wider
    than its panel keeps its neighbour's distance); the artists inside are left out."""
    out = np.zeros(4)
    for ax in axes:
        tb = ax.get_tightbbox(r, bbox_extra_artists=[])
        if tb is None:
            continue
        p = ax.get_window_extent(r)  # after the aspect was applied
        out = np.maximum(out, [p.x0 - tb.x0, tb.x1 - p.x1, p.y0 - tb.y0, tb.y1 - p.y1])
    return out / dpi


def place_grid(
    fig: Figure,
    grid: Sequence[Sequence[Axes | Sequence[Axes]]],
    panel: tuple[float, float],
    *,
    colorbars: Sequence[Axes] = (),
    colorbar_width: float = 0.14,
    suptitle: Text | None = None,
    legend: Legend | None = None,
) -> None:
    """Place a grid of panels of one size and set the figure's size around them.

    Parameters
    ----------
    fig : Figure
        Without a layout engine.
    grid : rows of axes
        Every entry an Axes or a sequence of Axes sharing one box (``twinx``).
    panel : (float, float)
        Width and height of every panel (inches).
    colorbars : sequence of Axes
        One per row, to the right of the row, as high as its panels.
    colorbar_width : float
        Their width (inches).
    suptitle : Text, optional
        The figure's title, set at the top centre.
    legend : Legend, optional
        A figure legend, set at the bottom centre.
    """
    r = renderer(fig)
    dpi = float(fig.dpi)
    cells = [[(c,) if not isinstance(c, Sequence) else tuple(c) for c in row] for row in grid]
    nr, nc = len(cells), len(cells[0])
    pw, ph = panel
    W0, H0 = fig.get_size_inches()
    for row in cells:  # the panels at their size: the ticks are chosen for it
        for c in row:
            for ax in c:
                ax.set_position((0.0, 0.0, pw / W0, ph / H0))
    for cax in colorbars:
        cax.set_position((0.0, 0.0, colorbar_width / W0, ph / H0))
    O = np.array([[_overhang(c, r, dpi) for c in row] for row in cells])  # (nr, nc, 4)
    C = np.array([_overhang((cax,), r, dpi) for cax in colorbars]).reshape(-1, 4)
    # horizontal: margins and gaps from the widest decorations of every column
    gaps_x = [float((O[:, j, 1] + O[:, j + 1, 0]).max()) + GAP for j in range(nc - 1)]
    left = PAD + float(O[:, 0, 0].max())
    right = PAD + float(O[:, -1, 1].max())
    if len(C):
        cb_gap = right - PAD + GAP + float(C[:, 0].max())
        right = cb_gap + colorbar_width + float(C[:, 1].max()) + PAD
    # vertical: the decorations of the panels and the colour bars of every row
    V = np.concatenate([O[:, :, 2:], C[:, None, 2:]], axis=1) if len(C) else O[:, :, 2:]
    gaps_y = [float((V[i, :, 0] + V[i + 1, :, 1]).max()) + GAP for i in range(nr - 1)]
    top = PAD + float(V[0, :, 1].max())
    bottom = PAD + float(V[-1, :, 0].max())
    if suptitle is not None:
        top += suptitle.get_window_extent(r).height / dpi + GAP
    if legend is not None:
        bottom += legend.get_window_extent(r).height / dpi + GAP
    W = left + nc * pw + sum(gaps_x) + right
    H = top + nr * ph + sum(gaps_y) + bottom
    if legend is not None:  # a legend wider than the panels widens the figure
        W = max(W, legend.get_window_extent(r).width / dpi + 2 * PAD)
    fig.set_size_inches(W, H)
    renderer(fig)  # the one that saving at fig.dpi draws with
    x0 = np.cumsum([left, *(pw + g for g in gaps_x)])
    y0 = H - np.cumsum([top + ph, *(ph + g for g in gaps_y)])
    for i, row in enumerate(cells):
        for j, c in enumerate(row):
            for ax in c:
                ax.set_position((x0[j] / W, y0[i] / H, pw / W, ph / H))
    for i, cax in enumerate(colorbars):
        cax.set_position(((x0[-1] + pw + cb_gap) / W, y0[i] / H, colorbar_width / W, ph / H))
    if suptitle is not None:
        suptitle.set_position((0.5, 1.0 - PAD / H))
        suptitle.set_verticalalignment("top")
    if legend is not None:
        legend.set_bbox_to_anchor((0.5, PAD / H), transform=fig.transFigure)
