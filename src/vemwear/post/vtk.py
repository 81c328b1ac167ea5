"""ParaView output: one ``.vtu`` file per time level and a ``.pvd`` collection.

For a run of order k = 2 that kept all its dofs, every ``.vtu`` holds the refined
visualisation mesh of :mod:`vemwear.post.quadratic` instead (triangles through the vertex
averages and edge midpoints, the quadratic field sampled there).

Every ``.vtu`` holds the polygonal mesh (triangles, quads and general polygons) with

point data
    ``displacement`` (3 components, z = 0, for the *Warp By Vector* filter),
    ``wear``, ``u_nu``, ``penetration`` (``u_nu - wear``), ``p_rigid`` (rigid-layer
    pressure), ``p_soft`` (soft-layer pressure) at the contact nodes and 0 elsewhere, and
    ``contact`` (1 at the contact nodes, 0 elsewhere);
cell data
    ``strain``: the strain of the projection, ``eps(Pi u_h)`` (constant per cell, paper
    3.8), as a 3x3 tensor (9 components, row-major; the out-of-plane entries are 0);
    ``stress``: ``sigma = 2 eta eps + lam tr(eps) I`` in plane strain, as a 3x3
    tensor with ``sigma_zz = lam tr(eps)``; ``von_mises``: the von Mises stress of that
    tensor; ``cell_id``: the cell index in the :class:`~vemwear.mesh.Mesh`.

The ``.pvd`` file lists the levels with their times, so ParaView shows the run as a
time series; the ``.vtu`` files live in a sibling directory named like the series.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np
from numpy.typing import NDArray

from ..mesh.io import to_meshio
from ..mesh.polymesh import Mesh
from ..util.atomic import write_atomic
from ..vem.local import Material, strain_stress
from ..vem.projection import Projection
from .pointdata import contact_point_data

if TYPE_CHECKING:
    from ..simulate.loop import Result

__all__ = ["cell_strain_stress", "level_fields", "write_vtk_series"]


def cell_strain_stress(
    mesh: Mesh,
    u: NDArray[np.float64],
    material: Material,
    projection: Projection | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Projected strain, plane-strain stress and von Mises stress per cell.

    Parameters
    ----------
    mesh : Mesh
    u : (n_points, 2) array
        Vertex displacements.
    material : Material
        Lamé coefficients ``lam``, ``eta``.
    projection : Projection, optional
        ``Pi`` of ``mesh`` (:class:`~vemwear.vem.projection.Projection`), if already built.

    Returns
    -------
    strain, stress : (n_cells, 3, 3) arrays
        ``eps(Pi u)`` (the symmetric part of the gradient of the projection) and
        ``sigma = 2 eta eps + lam tr(eps) I`` with ``sigma_zz = lam tr(eps)``
        (plane strain).
    von_mises : (n_cells,) array
        ``sqrt(((s_xx - s_yy)^2 + (s_yy - s_zz)^2 + (s_zz - s_xx)^2) / 2 + 3 s_xy^2)``.
    """
    E = (Projection(mesh) if projection is None else projection).strain(u)
    return strain_stress(E, material)


def _block_order(mesh: Mesh) -> list[NDArray[np.int64]]:
    """Cell ids of the meshio blocks of :func:`~vemwear.mesh.io.to_meshio`, in block order."""
    return [ids for _n, (ids, _v) in sorted(mesh.groups.items())]


def _levels(levels: Iterable[int] | None, L: int) -> list[int]:
    if levels is None:
        return list(range(L))
    out: list[int] = []
    for lv in levels:
        i = int(lv)
        if not -L <= i < L:
            raise IndexError(f"level {lv} is out of range for a run with {L} time levels")
        out.append(i % L)
    return sorted(set(out))


def level_fields(
    result: Result, level: int, projection: Projection | None = None
) -> tuple[dict[str, NDArray[np.float64]], dict[str, NDArray[np.float64]]]:
    """The point data and the cell data (in cell order) of one stored level, as listed
    in the module docstring (without ``cell_id``)."""
    mesh = result.problem.mesh
    n = mesh.n_points
    nodes = np.asarray(result.contact_nodes)
    vert = nodes < n  # k = 2: the vertex values only (edge midpoints are ids >= n)
    nodes = nodes[vert]
    u = np.asarray(result.displacement(level))
    disp = np.zeros((n, 3))
    disp[:, :2] = u
    point_data = {"displacement": disp, **contact_point_data(result, level, n, nodes, vert)}
    proj = projection if projection is not None else Projection(mesh)
    strain, stress, vm = cell_strain_stress(mesh, u, result.problem.material, proj)
    cells = {"strain": strain.reshape(-1, 9), "stress": stress.reshape(-1, 9), "von_mises": vm}
    return point_data, cells


def _pvd_text(entries: list[tuple[float, str]]) -> str:
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
    ]
    for t, fname in entries:
        lines.append(f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(fname)}/>')
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


def write_vtk_series(
    result: Result,
    outdir: str | os.PathLike[str],
    levels: Iterable[int] | None = None,
    name: str = "solution",
) -> Path:
    """Write the run as a ParaView time series.

    Writes ``outdir/<name>/<name>_NNNN.vtu`` for every chosen level ``NNNN`` and the
    collection ``outdir/<name>.pvd`` (relative file names, ``timestep`` = ``t_n``).
    Older ``<name>_<digits>.vtu`` files in ``outdir/<name>/`` that are not part of this
    series are removed; the ``.pvd`` is written last, under a temporary name renamed
    into place.

    Parameters
    ----------
    result : Result
        The run.
    outdir : path
        Output directory; created if missing.
    levels : iterable of int, optional
        Time level indices to write (negative indices count from the end); all by
        default.
    name : str
        Base name of the series.

    Returns
    -------
    Path
        The ``.pvd`` file.
    """
    mesh = result.problem.mesh
    projection = Projection(mesh)
    from .quadratic import has_quadratic_dofs, refined_level_fields, refined_mesh

    refined = refined_mesh(mesh) if has_quadratic_dofs(result) else None
    if refined is None:
        base = to_meshio(mesh, with_boundary=False)
        order = _block_order(mesh)
    else:  # k = 2: the refined visualisation mesh of vemwear.post.quadratic
        pts3 = np.column_stack([refined.points, np.zeros(len(refined.points))])
        base = meshio.Mesh(pts3, [("triangle", refined.triangles)])
        order = [np.arange(len(refined.triangles))]
    cell_id = [ids.astype(np.int64) for ids in order] if refined is None else [refined.parent]

    def write_level(lv: int, path: Path) -> None:
        point_data, cells = (
            level_fields(result, lv, projection)
            if refined is None
            else refined_level_fields(result, lv, refined)
        )
        cell_data: dict[str, list[NDArray[Any]]] = {
            k: [v[ids] for ids in order] for k, v in cells.items()
        }
        cell_data["cell_id"] = cell_id
        m = meshio.Mesh(base.points, base.cells, point_data=point_data, cell_data=cell_data)
        meshio.write(path, m, file_format="vtu")

    return write_series(result, outdir, levels, name, write_level)


def write_series(
    result: Result,
    outdir: str | os.PathLike[str],
    levels: Iterable[int] | None,
    name: str,
    write_level: Callable[[int, Path], None],
) -> Path:
    """A ParaView series of ``result``: ``write_level(level, path)`` writes the ``.vtu`` of
    each chosen level into ``outdir/<name>/``; stale ``<name>_<digits>.vtu`` files there
    are removed and ``outdir/<name>.pvd`` is written last, atomically (the skeleton of
    :func:`write_vtk_series` and of the 3D series of :mod:`vemwear.post.vtk3d`)."""
    out, sub = series_dir(outdir, name)
    L = len(result.t)
    # by default every level whose displacement was stored
    chosen = [int(v) for v in result.u_levels] if levels is None else _levels(levels, L)
    width = max(4, len(str(L - 1)))
    entries: list[tuple[float, str]] = []
    for lv in chosen:
        fname = f"{name}_{lv:0{width}d}.vtu"
        write_level(lv, sub / fname)
        entries.append((float(result.t[lv]), f"{name}/{fname}"))
    return finish_series(out, name, entries)


def series_dir(outdir: str | os.PathLike[str], name: str) -> tuple[Path, Path]:
    """``outdir`` and the directory ``outdir/<name>`` of a series' ``.vtu`` files (made
    if missing); ``name`` must be a plain file name."""
    if not name or os.sep in name or (os.altsep and os.altsep in name):
        raise ValueError(f"vtk: series name must be a plain file name, got {name!r}")
    out = Path(outdir)
    (out / name).mkdir(parents=True, exist_ok=True)
    return out, out / name


def finish_series(out: Path, name: str, entries: list[tuple[float, str]]) -> Path:
    """End a series whose ``.vtu`` files ``entries`` ((t, relative path)) are written:
    remove stale ``<name>_<digits>.vtu`` files of an earlier series, then write
    ``out/<name>.pvd`` atomically (last: a reader never sees a missing level)."""
    written = {Path(f).name for _t, f in entries}
    pattern = re.compile(re.escape(name) + r"_\d+\.vtu")
    for stale in (out / name).iterdir():
        if stale.is_file() and pattern.fullmatch(stale.name) and stale.name not in written:
            stale.unlink()
    pvd = out / f"{name}.pvd"
    write_atomic(pvd, _pvd_text(entries))
    return pvd
