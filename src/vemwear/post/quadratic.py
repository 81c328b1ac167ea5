"""ParaView output of k = 2: the quadratic field sampled on a refined visualisation mesh.

Every cell K with n vertices is split into 2n triangles through its vertex average
``c_K`` and the midpoints ``m_e`` of its edges: ``(c_K, x_i, m_i)`` and
``(c_K, m_i, x_{i+1})`` for the edge ``e_i = [x_i, x_{i+1}]`` (counter-clockwise as the
cell). The points are the vertices (ids ``0 ... n_p - 1``), the edge midpoints
(``n_p + e`` for the row e of :attr:`vemwear.mesh.Mesh.edges`) and the vertex averages
(``n_p + n_e + K``): the points of :attr:`vemwear.vem.space.P2Space.dof_points`, and a
k = 2 contact node ``n_p + e`` (a midpoint) is the point of the same id.

Point values (docs/method.md, section 9, "ParaView output of k = 2"): the vertex dofs at
the vertices; the value of the edge's quadratic at a midpoint, ``(6 m_e - v_a - v_b) / 4``
(``m_e`` the edge mean); ``Pi u`` (:func:`~vemwear.vem.dofs2.project2`) at the vertex
average, the one point where the virtual function itself has no value from the dofs.
ParaView interpolates linearly on the sub-triangles. The cell data of a sub-triangle are
the strain and stress of ``Pi u`` of its cell at the sub-triangle's centroid, and its
``cell_id`` is the cell's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..mesh.locate import vertex_averages
from ..vem.dofs2 import edge_ids, numbering2, project2
from ..vem.local import strain_stress
from .pointdata import contact_point_data

if TYPE_CHECKING:
    from ..mesh.polymesh import Mesh
    from ..simulate.loop import Result

__all__ = ["RefinedMesh", "has_quadratic_dofs", "refined_level_fields", "refined_mesh"]


class RefinedMesh(NamedTuple):
    """The visualisation mesh of k = 2 (module docstring)."""

    points: NDArray[np.float64]  # (n_p + n_e + n_c, 2)
    triangles: NDArray[np.int64]  # (2 sum n_K, 3)
    parent: NDArray[np.int64]  # (2 sum n_K,) the cell of every triangle


def refined_mesh(mesh: Mesh) -> RefinedMesh:
    """The vertices, edge midpoints and vertex averages, and the 2n triangles of every
    n-gon (module docstring)."""
    E = mesh.edges
    npt, ne = mesh.n_points, len(E)
    pts = np.concatenate(
        [mesh.points, 0.5 * (mesh.points[E[:, 0]] + mesh.points[E[:, 1]]), vertex_averages(mesh)]
    )
    de = mesh.directed_edges
    cell = mesh.edge_cells
    mid = npt + edge_ids(mesh, de[:, 0], de[:, 1])
    c = npt + ne + cell
    tris = np.stack(
        [np.column_stack([c, de[:, 0], mid]), np.column_stack([c, mid, de[:, 1]])], axis=1
    ).reshape(-1, 3)
    return RefinedMesh(pts, tris.astype(np.int64), np.repeat(cell, 2).astype(np.int64))


def has_quadratic_dofs(result: Result) -> bool:
    """Whether the run is of order k = 2 and kept all the dofs (:attr:`Result.dofs`)."""
    dofs = getattr(result, "dofs", None)
    return bool(getattr(result.problem, "order", 1) == 2 and dofs is not None)


def refined_level_fields(
    result: Result, level: int, refined: RefinedMesh | None = None
) -> tuple[dict[str, NDArray[np.float64]], dict[str, NDArray[np.float64]]]:
    """Point data on the refined points and cell data per sub-triangle of one stored level
    of a k = 2 run, with the names of :func:`vemwear.post.vtk.level_fields` (without
    ``cell_id``).

    Raises
    ------
    ValueError
        If the run has no dofs of k = 2 (:func:`has_quadratic_dofs`).
    KeyError
        If the level's displacement was not stored.
    """
    if not has_quadratic_dofs(result) or result.dofs is None:
        raise ValueError("refined_level_fields: the run has no dofs of k = 2")
    mesh = result.problem.mesh
    rm = refined_mesh(mesh) if refined is None else refined
    lv = int(level) % len(result.t)
    where = np.flatnonzero(result.u_levels == lv)
    if where.size == 0:
        raise KeyError(f"the displacement at level {lv} (t = {result.t[lv]:g}) was not stored")
    dofs = np.asarray(result.dofs[where[0]], dtype=float)
    num = numbering2(mesh)
    V = dofs[: num.edge_offset].reshape(-1, 2)
    M = dofs[num.edge_offset : num.cell_offset].reshape(-1, 2)
    E = mesh.edges
    pi = project2(mesh, result.problem.material, dofs)
    cells = np.arange(mesh.n_cells)
    centre, _ = pi.at(rm.points[num.n_points + num.n_edges :], cells)
    u = np.concatenate([V, (6.0 * M - V[E[:, 0]] - V[E[:, 1]]) / 4.0, centre])
    disp = np.zeros((len(u), 3))
    disp[:, :2] = u
    point_data: dict[str, NDArray[np.float64]] = {"displacement": disp}
    nodes = np.asarray(result.contact_nodes, dtype=np.int64)  # midpoints: n_p + e, as here
    point_data.update(contact_point_data(result, lv, len(u), nodes))
    centroids = rm.points[rm.triangles].mean(axis=1)
    _, grad = pi.at(centroids, rm.parent)
    strain, stress, vm = strain_stress(
        0.5 * (grad + grad.transpose(0, 2, 1)), result.problem.material
    )
    cell_data = {"strain": strain.reshape(-1, 9), "stress": stress.reshape(-1, 9), "von_mises": vm}
    return point_data, cell_data
