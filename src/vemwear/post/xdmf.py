"""ParaView output as one XDMF time series: ``solution.xdmf`` + ``solution.h5``.

The light data (``.xdmf``, XDMF 3 XML) describes a temporal collection of grids that
share one mesh; the heavy data (``.h5``) holds the mesh once and the fields of every
stored level, written level by level, so a long series needs neither one file per
level nor all levels in memory. The fields are those of the VTU series
(:mod:`vemwear.post.vtk`): point data ``displacement`` (3 components), ``wear``,
``u_nu``, ``penetration``, ``p_rigid``, ``p_soft``, ``contact``; cell data ``strain``,
``stress`` (3x3 tensors), ``von_mises``, ``cell_id``.

For a run of order k = 2 that kept all its dofs (:attr:`vemwear.simulate.Result.dofs`),
the grid is the refined visualisation mesh of :mod:`vemwear.post.quadratic` instead (a
``Triangle`` topology: every n-gon split into 2n triangles through its vertex average and
edge midpoints), with the quadratic field's values at the midpoints and ``Pi u`` at the
vertex averages; ``cell_id`` is then the cell of every triangle.

The cells are written as an XDMF ``Mixed`` topology: triangles (type 4) and
quadrilaterals (type 5) as such, every other polygon as type 3 followed by its vertex
count. meshio's XDMF writer has no general polygons, so the XML is written here; the
heavy data goes through h5py. Both files are written under temporary names and renamed
into place when complete, the ``.h5`` first.

:func:`write_xdmf_meshes` writes levels computed on several meshes (an adaptive run,
:mod:`vemwear.post.adaptive`) the same way, every mesh once (``/mesh_000``, ...) and
every level's grid on its mesh.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import quoteattr

import numpy as np
from numpy.typing import NDArray

from ..util.atomic import atomic_file
from ..vem.projection import Projection
from .quadratic import has_quadratic_dofs, refined_level_fields, refined_mesh
from .vtk import level_fields

if TYPE_CHECKING:
    from ..mesh.polymesh import Mesh
    from ..simulate.loop import Result

__all__ = ["mixed_topology", "write_xdmf_meshes", "write_xdmf_series"]

_TRIANGLE, _QUAD, _POLYGON = 4, 5, 3


def mixed_topology(mesh: Mesh) -> NDArray[np.int64]:
    """The cells as one XDMF ``Mixed`` topology array (in cell order)."""
    off, verts = mesh.cell_offsets, mesh.cell_vertices
    counts = np.diff(off)
    head = np.where(counts == 3, 1, np.where(counts == 4, 1, 2))  # entries before the ids
    start = np.concatenate([[0], np.cumsum(head + counts)])
    out = np.empty(start[-1], dtype=np.int64)
    kind = np.where(counts == 3, _TRIANGLE, np.where(counts == 4, _QUAD, _POLYGON))
    out[start[:-1]] = kind
    poly = head == 2
    out[start[:-1][poly] + 1] = counts[poly]
    # vertex ids: position of each id = start of its cell + head + its index in the cell
    cell_of = np.repeat(np.arange(len(counts)), counts)
    local = np.arange(len(verts)) - np.repeat(off[:-1], counts)
    out[start[:-1][cell_of] + head[cell_of] + local] = verts
    return out


def _item(dims: tuple[int, ...], dtype: Any, h5name: str, path: str) -> str:
    kind = "Int" if np.issubdtype(dtype, np.integer) else "Float"
    d = " ".join(map(str, dims))
    return (
        f'<DataItem Dimensions="{d}" NumberType="{kind}" Precision="8" Format="HDF">'
        f"{h5name}:{path}</DataItem>"
    )


def _attribute(name: str, center: str, value: NDArray[Any], h5name: str, path: str) -> str:
    kind = {1: "Scalar", 3: "Vector", 9: "Tensor"}[1 if value.ndim == 1 else value.shape[1]]
    return (
        f'<Attribute Name={quoteattr(name)} AttributeType="{kind}" Center="{center}">'
        f"{_item(value.shape, value.dtype, h5name, path)}</Attribute>"
    )


def write_xdmf_series(
    result: Result,
    outdir: str | os.PathLike[str],
    levels: Iterable[int] | None = None,
    name: str = "solution",
) -> Path:
    """Write the stored levels of a run as ``<name>.xdmf`` + ``<name>.h5``.

    Parameters
    ----------
    result : Result
        The run.
    outdir : path
        Output directory; created if missing.
    levels : iterable of int, optional
        Rows of the result to write (each with a stored displacement); default: every
        row in ``result.u_levels``.
    name : str
        Base name of the two files.

    Returns
    -------
    Path
        The ``.xdmf`` file.
    """
    chosen = [int(v) for v in (result.u_levels if levels is None else levels)]
    return write_xdmf_meshes([(result, chosen, {})], outdir, name, shared=True)


def write_xdmf_meshes(
    parts: list[tuple[Result, list[int], dict[str, NDArray[Any]]]],
    outdir: str | os.PathLike[str],
    name: str = "solution",
    *,
    shared: bool = False,
) -> Path:
    """Write levels computed on several meshes as one temporal collection.

    Parameters
    ----------
    parts : list of (Result, rows, cell data)
        Every mesh once: a result on it, the rows to write (in time order across the
        parts), and cell data of the mesh written with every row (e.g. the refinement
        ``level``).
    outdir : path
        Output directory; created if missing.
    name : str
        Base name of the two files.
    shared : bool
        One mesh, stored as ``/mesh`` (the layout of :func:`write_xdmf_series`); else
        the k-th part's mesh is ``/mesh_k`` (k from 000).

    Returns
    -------
    Path
        The ``.xdmf`` file.
    """
    import h5py

    if not name or os.sep in name or (os.altsep and os.altsep in name):
        raise ValueError(f"xdmf: series name must be a plain file name, got {name!r}")
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    h5name = f"{name}.h5"
    grids: list[str] = []
    with atomic_file(out / h5name) as tmp_h5:
        with h5py.File(tmp_h5, "w") as f:
            j = 0
            for k, (result, rows, extra) in enumerate(parts):
                where = "/mesh" if shared else f"/mesh_{k:03d}"
                grids += _grids(f, h5name, where, result, rows, extra, name, j, shared)
                j += len(rows)
    text = (
        '<?xml version="1.0"?>\n<Xdmf Version="3.0">\n<Domain>\n'
        f'<Grid Name="{name}" GridType="Collection" CollectionType="Temporal">\n'
        + "\n".join(grids)
        + "\n</Grid>\n</Domain>\n</Xdmf>\n"
    )
    with atomic_file(out / f"{name}.xdmf") as tmp_x:
        tmp_x.write_text(text, encoding="utf-8")
    return out / f"{name}.xdmf"


def _grids(
    f: Any,
    h5name: str,
    where: str,
    result: Result,
    rows: list[int],
    extra: dict[str, NDArray[Any]],
    name: str,
    j0: int,
    shared: bool,
) -> list[str]:
    """Write one mesh at ``where`` and its rows as ``/levels/j`` (j from ``j0``); the
    XML of their grids, named by the row (``shared``) or the time level."""
    mesh = result.problem.mesh
    projection = Projection(mesh)
    refined = refined_mesh(mesh) if has_quadratic_dofs(result) else None
    if refined is None:
        topo, points = mixed_topology(mesh), np.asarray(mesh.points, dtype=np.float64)
        cell_id = np.arange(mesh.n_cells, dtype=np.int64)
        kind, n_elements = "Mixed", mesh.n_cells
    else:
        topo, points = refined.triangles, np.asarray(refined.points, dtype=np.float64)
        cell_id, kind, n_elements = refined.parent, "Triangle", len(refined.triangles)
    mesh_items = (
        f'<Topology TopologyType="{kind}" NumberOfElements="{n_elements}">'
        f"{_item(topo.shape, topo.dtype, h5name, f'{where}/topology')}</Topology>"
        f'<Geometry GeometryType="XY">'
        f"{_item(points.shape, points.dtype, h5name, f'{where}/points')}</Geometry>"
    )
    f[f"{where}/topology"] = topo
    f[f"{where}/points"] = points
    f[f"{where}/cell_id"] = cell_id
    fixed = [_attribute("cell_id", "Cell", cell_id, h5name, f"{where}/cell_id")]
    for key, value in extra.items():
        f[f"{where}/{key}"] = value[cell_id]
        fixed.append(_attribute(key, "Cell", value[cell_id], h5name, f"{where}/{key}"))
    grids = []
    for j, lv in enumerate(rows, start=j0):
        point_data, cell_data = (
            level_fields(result, lv, projection)
            if refined is None
            else refined_level_fields(result, lv, refined)
        )
        attrs = []
        for center, fields in (("Node", point_data), ("Cell", cell_data)):
            for key, value in fields.items():
                path = f"/levels/{j}/{key}"
                f[path] = np.asarray(value, dtype=np.float64)
                attrs.append(_attribute(key, center, f[path][()], h5name, path))
        label = lv if shared or result.levels is None else int(result.levels[lv])
        grids.append(
            f'<Grid Name="{name}_{label}" GridType="Uniform">'
            f'<Time Value="{float(result.t[lv])!r}"/>{mesh_items}{"".join(attrs + fixed)}</Grid>'
        )
    return grids
