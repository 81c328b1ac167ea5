"""ParaView output of an adaptive run (docs/method.md, section 11): every level on the
mesh it was computed on.

:func:`write_adaptive_series` writes one ``.vtu`` per owned level of every segment of
:func:`~vemwear.simulate.adaptive_time.simulate_adaptive`, each with its own mesh and the
fields of :func:`~vemwear.post.vtk.level_fields`, plus the cell data ``level`` (the
refinement level of every cell) and ``cell_id``, and one ``.pvd`` collection of all of
them in time order, so ParaView plays the run with the mesh changing under it.
A segment's levels are found among the rows its result keeps (all levels up to its last
in memory, the owned ones when read back from ``result.h5``:
:func:`~vemwear.post.adaptive_stream.read_adaptive`).

:func:`write_adaptive_xdmf` writes the same levels as one XDMF series
(``<name>.xdmf`` + ``<name>.h5``, :func:`~vemwear.post.xdmf.write_xdmf_meshes`): every
mesh once, hanging nodes as vertices of its polygons (the ``Mixed`` topology), with the
cell data ``level``, and every level's grid on its mesh.

:func:`plot_adaptive_profiles` draws the wear and the pressure along Gamma_C at some
times, each on the contact nodes of the mesh of its level, and :func:`plot_meshes` the
first and the last mesh.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import meshio
import numpy as np
from numpy.typing import NDArray

from ..mesh.io import to_meshio
from ..vem.projection import Projection
from .vtk import _block_order, finish_series, level_fields, series_dir

if TYPE_CHECKING:
    from ..simulate.adaptive_time import Segment

__all__ = [
    "owned_rows",
    "owner",
    "plot_adaptive_profiles",
    "plot_meshes",
    "write_adaptive_series",
]


def owned_rows(segments: list[Segment]) -> list[list[int]]:
    """For every segment, the rows of its result that hold the levels it owns."""
    out = []
    for k, seg in enumerate(segments):
        levels = seg.result.levels
        assert levels is not None
        own = np.arange(seg.first, seg.last + 1 if k == len(segments) - 1 else seg.last)
        out.append([int(r) for r in np.searchsorted(levels, own)])
    return out


def write_adaptive_xdmf(
    segments: list[Segment], outdir: str | os.PathLike[str], name: str = "solution"
) -> Path:
    """Write the levels of an adaptive run as one XDMF series (module docstring).

    Returns
    -------
    Path
        The ``.xdmf`` file.
    """
    from .xdmf import write_xdmf_meshes

    if not segments:
        raise ValueError("xdmf: an adaptive run without segments")
    parts = [
        (seg.result, rows, {"level": seg.tree.level.astype(np.float64)})
        for seg, rows in zip(segments, owned_rows(segments), strict=True)
    ]
    return write_xdmf_meshes(parts, outdir, name)


def owner(segments: list[Segment], level: int) -> tuple[Segment, int]:
    """The segment that owns ``level`` and the row of its result that holds it."""
    for k, seg in enumerate(segments):
        if seg.first <= level < seg.last or (k == len(segments) - 1 and level == seg.last):
            levels = seg.result.levels
            assert levels is not None
            return seg, int(np.searchsorted(levels, level))
    raise ValueError(f"level {level} is not a level of the adaptive run")


def write_adaptive_series(
    segments: list[Segment], outdir: str | os.PathLike[str], name: str = "adaptive"
) -> Path:
    """Write the levels of an adaptive run as one ParaView series.

    Parameters
    ----------
    segments : list of Segment
        The run (:func:`~vemwear.simulate.adaptive_time.simulate_adaptive`).
    outdir : path
        Output directory; created if missing.
    name : str
        Base name: ``outdir/<name>/<name>_NNNN.vtu`` per level ``NNNN``, and
        ``outdir/<name>.pvd``, written last, atomically; stale ``.vtu`` files of the
        series are removed.

    Returns
    -------
    Path
        The ``.pvd`` file.
    """
    if not segments:
        raise ValueError("vtk: an adaptive run without segments")
    out, sub = series_dir(outdir, name)
    width = max(4, len(str(segments[-1].last)))
    entries: list[tuple[float, str]] = []
    for k, seg in enumerate(segments):
        mesh = seg.problem.mesh
        res = seg.result
        base = to_meshio(mesh, with_boundary=False)
        order = _block_order(mesh)
        proj = Projection(mesh)
        final = k == len(segments) - 1
        assert res.levels is not None
        for lv in range(seg.first, seg.last + 1 if final else seg.last):
            row = int(np.searchsorted(res.levels, lv))
            point_data, cells = level_fields(res, row, proj)
            cells = {**cells, "level": seg.tree.level.astype(np.float64)}
            cell_data: dict[str, list[NDArray[Any]]] = {
                key: [v[ids] for ids in order] for key, v in cells.items()
            }
            cell_data["cell_id"] = [ids.astype(np.int64) for ids in order]
            fname = f"{name}_{lv:0{width}d}.vtu"
            m = meshio.Mesh(base.points, base.cells, point_data=point_data, cell_data=cell_data)
            meshio.write(sub / fname, m, file_format="vtu")
            entries.append((float(res.t[row]), f"{name}/{fname}"))
    return finish_series(out, name, entries)


def plot_adaptive_profiles(
    segments: list[Segment], times: Sequence[float], path: str | os.PathLike[str]
) -> None:
    """Wear ``w`` and pressure ``p_soft + p_rigid`` along Gamma_C at ``times`` (time
    levels of the run), each on the contact nodes of the mesh of its level, against x_1."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    t = segments[-1].problem.time.t
    levels = [int(np.argmin(np.abs(t - x))) for x in times]
    fig = Figure(figsize=(10.0, 3.9), layout="constrained")
    axes = fig.subplots(1, 2)
    cmap = colormaps["viridis"]
    for j, lv in enumerate(levels):
        seg, row = owner(segments, lv)
        res = seg.result
        x = np.asarray(res.contact_points)[:, 0]
        order = np.argsort(x, kind="stable")
        color = cmap(0.85 - 0.85 * j / max(len(levels) - 1, 1))
        label = f"$t$ = {t[lv]:g} ({len(x)} nodes)"
        pressure = res.p_soft[row] + res.p_rigid[row]
        for ax, y in zip(axes, (res.wear[row], pressure), strict=True):
            ax.plot(x[order], y[order], color=color, lw=1.4, marker=".", ms=3, label=label)
    for ax, what in zip(axes, (r"wear $w$", r"pressure $p_{soft} + p_{rigid}$"), strict=True):
        ax.set_xlabel(r"$x_1$")
        ax.set_ylabel(what)
        ax.grid(True, lw=0.4, alpha=0.5)
    axes[0].legend(loc="best", frameon=False, fontsize=8)
    fig.suptitle("Wear and pressure on the adaptive meshes")
    fig.savefig(path, dpi=150)


def plot_meshes(segments: list[Segment], path: str | os.PathLike[str]) -> None:
    """The first and the last mesh of an adaptive run, one above the other."""
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure

    picks = [segments[0], segments[-1]]
    fig = Figure(figsize=(8.0, 7.0), layout="constrained")
    axes = fig.subplots(2, 1)
    for ax, seg in zip(axes, picks, strict=True):
        mesh = seg.problem.mesh
        verts = np.split(np.asarray(mesh.cell_vertices), np.asarray(mesh.cell_offsets)[1:-1])
        polys = [mesh.points[v] for v in verts]
        level = seg.tree.level.astype(float)
        pc = PolyCollection(polys, array=level, cmap="Blues", edgecolors="k", linewidths=0.3)
        pc.set_clim(0, max(float(segments[-1].tree.level.max()), 1.0))
        ax.add_collection(pc)
        ax.autoscale_view()
        ax.set_aspect("equal")
        ax.set_title(
            f"levels {seg.first} .. {seg.last}: {mesh.n_cells} cells, "
            f"{seg.problem.space.n_dofs} dofs"
        )
        fig.colorbar(pc, ax=ax, label="refinement level")
    fig.savefig(path, dpi=150)
