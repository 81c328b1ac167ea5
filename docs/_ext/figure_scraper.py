"""A sphinx-gallery image scraper for the Matplotlib figures vemwear's plotting functions
return (``matplotlib.figure.Figure`` objects made without pyplot, such as
:func:`vemwear.mesh.plot.plot_mesh`'s), which the built-in scraper does not see: every
such figure bound to a name of the example is shown once, after the block that made it.
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst

_SHOWN: dict[str, set[int]] = {}


class ReturnedFigures:
    """The scraper (a class with a ``repr``, so that sphinx-gallery can cache its config)."""

    def __call__(self, block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any]) -> str:
        shown = _SHOWN.setdefault(block_vars["src_file"], set())
        paths = []
        for value in list(block_vars["example_globals"].values()):
            if (
                isinstance(value, Figure)
                and value.canvas.manager is None
                and id(value) not in shown
            ):
                shown.add(id(value))
                path = next(block_vars["image_path_iterator"])
                value.savefig(path, dpi=100)
                paths.append(path)
        return figure_rst(paths, gallery_conf["src_dir"])

    def __repr__(self) -> str:
        return "ReturnedFigures()"
