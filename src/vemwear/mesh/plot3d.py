"""Drawing a polyhedral mesh: its boundary faces coloured by boundary part."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .plot import PART_COLORS
from .polyhedra import Mesh3D

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["MAX_PLOT_FACES", "plot_mesh3d"]

#: Boundary faces above which :func:`plot_mesh3d` refuses (matplotlib's 3D drawing is slow).
MAX_PLOT_FACES = 20_000

_OTHER = ("#bababa", "#fdb863", "#b2abd2", "#80cdc1", "#f1b6da", "#dfc27d", "#c2a5cf", "#a6dba0")


def plot_mesh3d(mesh: Mesh3D, *, title: str | None = None) -> Figure:
    """The boundary faces of a polyhedral mesh in a 3D view, coloured by boundary part
    (untagged faces orange).

    Raises
    ------
    ValueError
        If the mesh has more than :data:`MAX_PLOT_FACES` boundary faces.
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    bf = mesh.boundary_faces
    if bf.size > MAX_PLOT_FACES:
        raise ValueError(
            f"{bf.size} boundary faces are too many to draw with matplotlib "
            f"(at most {MAX_PLOT_FACES}); open the .vtu file in ParaView instead"
        )
    P, off, fv = mesh.points, mesh.face_offsets, mesh.face_vertices
    tags = np.asarray(mesh.boundary_tags)
    colors = np.empty(bf.size, dtype=object)
    handles = []
    k = 0
    for name, code in zip(
        [*mesh.part_names, "untagged"], [*range(1, len(mesh.part_names) + 1), 0], strict=True
    ):
        n = int(np.sum(tags == code))
        if not n:
            continue
        if name in PART_COLORS:
            color = PART_COLORS[name]
        else:
            color = _OTHER[k % len(_OTHER)]
            k += 1
        colors[tags == code] = color
        handles.append(Patch(facecolor=color, edgecolor="k", label=f"{name} ({n})"))
    polys = [P[fv[off[f] : off[f + 1]]] for f in bf]
    lo, hi = P.min(axis=0), P.max(axis=0)
    aspect = tuple(np.maximum(hi - lo, 1e-12 * max(float(np.max(hi - lo)), 1.0)))
    fig = Figure(figsize=(12, 5.5))
    # from above (sides xmax, ymin, zmax in front) and from below (xmin, ymax, zmin)
    for i, (elev, azim) in enumerate(((25.0, -60.0), (-25.0, 120.0))):
        ax = fig.add_subplot(1, 2, i + 1, projection="3d")
        ax.add_collection3d(
            Poly3DCollection(
                polys, facecolors=list(colors), edgecolors="k", linewidths=0.3, alpha=1.0
            )
        )
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(aspect)
        ax.view_init(elev=elev, azim=azim)
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_zlabel("z")
        ax.set_title("from above" if elev > 0 else "from below", fontsize="medium")
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 6), fontsize="small")
    if title is not None:
        fig.suptitle(title)
    return fig
