"""Global assembly: stiffness ``a_h`` (3.11) and the loads ``f_h`` (Section 3.3).

Global dof ``2 v + c`` is component ``c`` of the displacement at vertex ``v``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..mesh.polymesh import Mesh
from ..util.arrays import members
from .local import STABILIZATIONS, Material, element_matrices, triangle_matrices
from .quadrature import GAUSS2, Field, cell_means, eval_field

#: Cells per batch of local matrices in :func:`stiffness`: the batch's temporaries (a
#: few hundred kB for triangles) are reused from one batch to the next instead of being
#: mapped afresh, whose page faults cost more than the arithmetic (64 x 32 triangles:
#: 6.7 ms with 512, 9.4 ms with 4096; 256 x 128: 83 ms against 200 ms).
CHUNK = 512


def _dofs(verts: NDArray[np.int64]) -> NDArray[np.int64]:
    """(m, n) vertex ids -> (m, 2n) interleaved dof ids."""
    d = np.empty((verts.shape[0], 2 * verts.shape[1]), dtype=np.int64)
    d[:, 0::2] = 2 * verts
    d[:, 1::2] = 2 * verts + 1
    return d


def stiffness(
    mesh: Mesh,
    material: Material,
    stabilization: str = "paper",
    cells: NDArray[np.int64] | None = None,
) -> sp.csr_matrix:
    """Assemble the VEM stiffness matrix of ``a_h`` on all ``2 * n_points`` dofs.

    Triangles take :func:`~vemwear.vem.local.triangle_matrices` (P1, where the
    stabilization vanishes), other cells :func:`~vemwear.vem.local.element_matrices`.
    Local matrices are built group by group (cells of equal vertex count), in chunks of
    :data:`CHUNK` cells so that the batched temporaries stay small and are reused
    (fresh arrays of hundreds of MB cost more in page faults than the arithmetic), and
    scattered once into a COO matrix. ``cells`` (ids) assembles the sum over those
    cells only (one MPI rank's part), in the same global numbering.
    """
    if stabilization not in STABILIZATIONS:
        raise ValueError(
            f"unknown stabilization {stabilization!r}; expected one of {', '.join(STABILIZATIONS)}"
        )
    ndof = 2 * mesh.n_points
    index = np.int32 if ndof < 2**31 - 1 else np.int64  # less memory traffic in the scatter
    groups = _chosen(mesh.groups, mesh.n_cells, cells)
    total = sum(len(verts) * (2 * n) ** 2 for n, verts in groups)
    rows, cols = np.empty(total, dtype=index), np.empty(total, dtype=index)
    vals = np.empty(total)  # filled in place: no concatenation of the groups
    at = 0
    for n, verts in groups:
        n2 = 2 * n
        for a in range(0, len(verts), CHUNK):
            v = verts[a : a + CHUNK]
            size = len(v) * n2 * n2
            block = vals[at : at + size].reshape(len(v), n2, n2)
            if n == 3:  # P1: no stabilization (triangle_matrices), written in place
                triangle_matrices(mesh.points[v], material, out=block)
            else:
                block[...] = element_matrices(mesh.points[v], material, stabilization)[0]
            d = _dofs(v).astype(index)
            # entry (i, j) of a cell's matrix: row dof i, column dof j (broadcast in place)
            rows[at : at + size].reshape(len(v), n2, n2)[...] = d[:, :, None]
            cols[at : at + size].reshape(len(v), n2, n2)[...] = d[:, None, :]
            at += size
    A = sp.coo_matrix((vals, (rows, cols)), shape=(ndof, ndof)).tocsr()
    A.sum_duplicates()
    return A


def _chosen(
    groups: dict[int, tuple[NDArray[np.int64], NDArray[np.int64]]],
    n_cells: int,
    cells: NDArray[np.int64] | None,
) -> list[tuple[int, NDArray[np.int64]]]:
    """The groups' vertex ids, of the ``cells`` only when given."""
    if cells is None:
        return [(n, verts) for n, (_ids, verts) in groups.items()]
    keep = members(cells, n_cells)
    return [(n, verts[keep[ids]]) for n, (ids, verts) in groups.items()]


def body_force_vector(mesh: Mesh, f1: Field, t: float = 0.0) -> NDArray[np.float64]:
    """``<f_1h, v> = sum_K |K| P_0 f1 · (vertex average of v)`` (paper Section 3.3, k = 1).

    Each vertex of K receives ``|K| P_0^K f1 / n_K``.
    """
    fbar = cell_means(mesh, f1, t, "body force f1")
    share = (mesh.cell_areas / mesh.cell_sizes)[:, None] * fbar  # (n_cells, 2)
    per_vertex = np.repeat(share, mesh.cell_sizes, axis=0)
    # bincount adds in the order of the vertex list, as np.add.at does, many times faster
    F = np.empty((mesh.n_points, 2))
    for c in range(2):
        F[:, c] = np.bincount(mesh.cell_vertices, per_vertex[:, c], minlength=mesh.n_points)
    return F.ravel()


def edge_load_vector(
    mesh: Mesh, edges: NDArray[np.int64], f: Field, t: float = 0.0, name: str = "traction f2"
) -> NDArray[np.float64]:
    """``int_E f · v ds`` over the given edges, by two-point Gauss on every edge
    (exact for f linear along the edge, since v is linear there)."""
    F = np.zeros((mesh.n_points, 2))
    if len(edges) == 0:
        return F.ravel()
    a, b = mesh.points[edges[:, 0]], mesh.points[edges[:, 1]]
    L = np.linalg.norm(b - a, axis=1)[:, None]
    for s in GAUSS2:
        val = eval_field(f, (1 - s) * a + s * b, t, name) * (0.5 * L)
        np.add.at(F, edges[:, 0], (1 - s) * val)
        np.add.at(F, edges[:, 1], s * val)
    return F.ravel()


def traction_vector(mesh: Mesh, f2: Field, t: float = 0.0) -> NDArray[np.float64]:
    """``int_{Gamma_N} f2 · v ds`` on the traction part."""
    return edge_load_vector(mesh, mesh.part_edges("traction"), f2, t)
