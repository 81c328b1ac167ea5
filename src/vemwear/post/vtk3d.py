"""ParaView output of a 3D run: a PVD collection of VTU files with polyhedron cells.

meshio's XDMF writer has no general polyhedra (and XDMF's own ``Polyhedron`` topology is
not read by every ParaView reader), so a 3D run is always written as
``<name>.pvd`` + ``<name>/<name>_NNNN.vtu``, one VTU file per stored level, through
:class:`vemwear.mesh.io3d.VTUWriter3D` (the mesh encoded once for all levels; VTK
polyhedron cells, faces listed outward; the boundary parts as field data). Point
data: ``displacement`` (3 components), ``wear``, ``u_nu``, ``penetration``, ``p_rigid``,
``p_soft``, ``contact`` (1 on the contact nodes; the contact quantities are 0
elsewhere); cell data: ``strain`` and ``stress`` (3x3 tensors of
the projection ``Pi u``, ``sigma = 2 eta eps + lam tr(eps) I``), ``von_mises`` and
``cell_id``.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..mesh.io3d import VTUWriter3D
from ..util.atomic import atomic_file
from ..vem.local import strain_stress
from .pointdata import contact_point_data
from .vtk import write_series

if TYPE_CHECKING:
    from ..simulate.loop import Result

__all__ = ["level_fields3d", "write_vtk_series3d"]


def level_fields3d(
    result: Result, level: int
) -> tuple[dict[str, NDArray[np.float64]], dict[str, NDArray[np.float64]]]:
    """The point data and the cell data (in cell order) of one stored level of a 3D run."""
    pr = result.problem
    n = pr.mesh.n_points
    nodes = np.asarray(result.contact_nodes)
    u = np.asarray(result.displacement(level), dtype=float)
    point_data = {"displacement": u, **contact_point_data(result, level, n, nodes)}
    E = pr.space.projection(pr.material, u).strain  # type: ignore[union-attr, arg-type]
    strain, stress, vm = strain_stress(E, pr.material)
    cells = {"strain": strain.reshape(-1, 9), "stress": stress.reshape(-1, 9), "von_mises": vm}
    return point_data, cells


def write_vtk_series3d(
    result: Result,
    outdir: str | os.PathLike[str],
    levels: Iterable[int] | None = None,
    name: str = "solution",
) -> Path:
    """Write a 3D run as a ParaView time series of polyhedral VTU files.

    As :func:`vemwear.post.vtk.write_vtk_series`: ``outdir/<name>/<name>_NNNN.vtu`` for
    every chosen level and the collection ``outdir/<name>.pvd``, written last under a
    temporary name; stale ``<name>_<digits>.vtu`` files removed.

    Parameters
    ----------
    result : Result
        A run on a :class:`~vemwear.mesh.polyhedra.Mesh3D`.
    outdir : path
        Output directory; created if missing.
    levels : iterable of int, optional
        Rows of the result to write (each with a stored displacement); default: every
        row in ``result.u_levels``.
    name : str
        Base name of the series.

    Returns
    -------
    Path
        The ``.pvd`` file.
    """
    write = VTUWriter3D(result.problem.mesh)  # type: ignore[arg-type]

    def write_level(lv: int, path: Path) -> None:
        point_data, cell_data = level_fields3d(result, lv)
        with atomic_file(path) as tmp:
            write(tmp, point_data, cell_data)

    return write_series(result, outdir, levels, name, write_level)
