"""Drawing a mesh: cells, boundary parts, hanging nodes and the A1 quality of each cell."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from .polymesh import Mesh
from .quality import QualityReport, hanging_nodes, quality_report

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["PART_COLORS", "PART_SYMBOLS", "plot_mesh"]

PART_COLORS: dict[str, str] = {
    "clamped": "#2166ac",
    "traction": "#1b7837",
    "contact": "#b2182b",
    "untagged": "#ff7f00",
}
PART_SYMBOLS: dict[str, str] = {
    "clamped": r"$\Gamma_D$",
    "traction": r"$\Gamma_N$",
    "contact": r"$\Gamma_C$",
}


def plot_mesh(
    mesh: Mesh,
    path: str | os.PathLike[str] | None = None,
    *,
    quality: bool | QualityReport = False,
    title: str | None = None,
) -> Figure:
    """Draw a mesh with its boundary parts coloured (and optionally ``rho_K / h_K``).

    Parameters
    ----------
    mesh : Mesh
    path : path, optional
        Save the figure there (format from the suffix, 150 dpi).
    quality : bool or QualityReport
        Colour every cell by ``rho_K / h_K`` of assumption A1 (a report may be
        passed to avoid recomputing it).
    title : str, optional
        Default: cell counts and mesh size.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    P = mesh.points
    lo, hi = P.min(axis=0), P.max(axis=0)
    ext = np.maximum(hi - lo, 1e-300)
    aspect = float(ext[1] / ext[0])
    width = 9.0
    fig = Figure(
        figsize=(width, min(max((width - 2.0) * aspect, 2.0), 9.0) + 1.6), layout="constrained"
    )
    ax = fig.subplots()
    lw = float(np.clip(12.0 / np.sqrt(max(mesh.n_cells, 1)), 0.1, 0.8))
    polys = PolyCollection([P[c] for c in mesh.cells], closed=True, linewidths=lw)
    if quality is not False:
        rep = quality if not isinstance(quality, bool) else quality_report(mesh)
        polys.set_array(rep.rho_ratio)
        polys.set_cmap("viridis")
        polys.set_clim(0.0, max(0.5, float(rep.rho_ratio.max())))
        polys.set_edgecolor("0.25")
        ax.add_collection(polys)
        cb = fig.colorbar(polys, ax=ax, shrink=0.9, pad=0.02)
        cb.set_label(r"$\rho_K / h_K$ (assumption A1)")
        extra = (
            f"; $\\gamma_1$ = min $\\rho_K/h_K$ = {rep.gamma1:.3g}, $\\gamma_2$ = {rep.gamma2:.3g}"
        )
    else:
        polys.set_facecolor("#f2f2f2")
        polys.set_edgecolor("0.35")
        ax.add_collection(polys)
        extra = ""
    handles = []
    be = mesh.boundary_edges
    extra_colors = iter(["#762a83", "#e08214", "#35978f", "#c51b7d", "#8c510a", "#4d4d4d"] * 20)
    colors = {**{n: next(extra_colors) for n in mesh.part_names}, **PART_COLORS}
    for name in (*mesh.part_names, "untagged"):
        code = 0 if name == "untagged" else mesh.part_code(name)
        sel = np.asarray(mesh.boundary_tags == code, dtype=bool)
        if not np.any(sel):
            continue
        ax.add_collection(
            LineCollection(
                P[be[sel]],
                colors=colors[name],
                linewidths=3.0,
                linestyles="--" if name == "untagged" else "-",
                capstyle="butt",
                zorder=3,
            )
        )
        label = f"{name} {PART_SYMBOLS.get(name, '')} ({int(sel.sum())} edges)"
        handles.append(
            Line2D(
                [],
                [],
                color=colors[name],
                lw=3.0,
                ls="--" if name == "untagged" else "-",
                label=label,
            )
        )
    hang = hanging_nodes(mesh)
    if hang.size:
        ax.plot(P[hang, 0], P[hang, 1], "o", ms=3.0, mfc="white", mec="k", mew=0.7, zorder=4)
        handles.append(
            Line2D(
                [],
                [],
                ls="",
                marker="o",
                ms=4.0,
                mfc="white",
                mec="k",
                label=f"hanging nodes ({hang.size})",
            )
        )
    pad = 0.02 * float(ext.max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$x_1$")
    ax.set_ylabel(r"$x_2$")
    if handles:
        fig.legend(
            handles=handles,
            loc="outside lower center",
            ncols=min(len(handles), 4),
            frameon=False,
            fontsize="small",
        )
    if title is None:
        counts = ", ".join(f"{len(i)} {n}-gons" for n, (i, _v) in sorted(mesh.groups.items()))
        title = f"{mesh.n_cells} cells ({counts}), {mesh.n_points} vertices, h = {mesh.h:.3g}"
    ax.set_title(title + extra, fontsize="medium")
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig


# ---------------------------------------------------------------------------- commands
