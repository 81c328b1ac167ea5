"""Global assembly: stiffness ``a_h`` (3.11), load ``f_h`` (Section 3.3), projected strains.

Global dof ``2 v + c`` is component ``c`` of the displacement at vertex ``v``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh
from .local import Material, element_matrices, fan, geometry

#: A vector field given as a constant 2-vector or a callable ``f(x, t)`` on (m, 2) points.
Field = ArrayLike | Callable[[NDArray[np.float64], float], ArrayLike]


def _dofs(verts: NDArray[np.int64]) -> NDArray[np.int64]:
    """(m, n) vertex ids -> (m, 2n) interleaved dof ids."""
    d = np.empty((verts.shape[0], 2 * verts.shape[1]), dtype=np.int64)
    d[:, 0::2] = 2 * verts
    d[:, 1::2] = 2 * verts + 1
    return d


def stiffness(mesh: Mesh, material: Material, stabilization: str = "paper") -> sp.csr_matrix:
    """Assemble the VEM stiffness matrix of ``a_h`` on all ``2 * n_points`` dofs.

    Local matrices are built group by group (cells of equal vertex count) and
    scattered once into a COO matrix.
    """
    rows, cols, vals = [], [], []
    ndof = 2 * mesh.n_points
    index = np.int32 if ndof < 2**31 - 1 else np.int64  # less memory traffic in the scatter
    for _n, (_ids, verts) in mesh.groups.items():
        K, _B, _P, _a = element_matrices(mesh.points[verts], material, stabilization)
        d = _dofs(verts).astype(index)
        rows.append(np.repeat(d, d.shape[1], axis=1).ravel())
        cols.append(np.tile(d, (1, d.shape[1])).ravel())
        vals.append(K.ravel())
    A = sp.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(ndof, ndof)
    ).tocsr()
    A.sum_duplicates()
    return A


def _eval_field(f: Field, x: NDArray[np.float64], t: float, name: str) -> NDArray[np.float64]:
    if callable(f):
        v = np.asarray(f(x, t), dtype=float)
        v = np.broadcast_to(v, (len(x), 2)) if v.shape == (2,) else v
    else:
        v = np.broadcast_to(np.asarray(f, dtype=float), (len(x), 2))
    if v.shape != (len(x), 2):
        raise ValueError(f"{name} must give a 2-vector per point, got shape {v.shape}")
    return v


# Degree-2 rule on a triangle (barycentric edge midpoints), exact for quadratics.
_TRI_BARY = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])


def cell_means(mesh: Mesh, f: Field, t: float = 0.0, name: str = "f") -> NDArray[np.float64]:
    """``P_0^K f`` for every cell: the cell mean, by a degree-2 rule on the fan of triangles
    from the vertex average (signed areas make it exact for quadratics on any simple cell)."""
    out = np.zeros((mesh.n_cells, 2))
    if not callable(f):
        out[:] = _eval_field(f, np.zeros((1, 2)), t, name)[0]
        return out
    for _n, (ids, verts) in mesh.groups.items():
        fn = fan(mesh.points[verts])
        acc = np.zeros((len(ids), 2))
        for b in _TRI_BARY:
            pts = b[0] * fn.xbar[:, None, :] + b[1] * fn.X + b[2] * fn.X_next  # (m, n, 2)
            val = _eval_field(f, pts.reshape(-1, 2), t, name).reshape(pts.shape)
            acc += np.sum(val * fn.area[..., None], axis=1) / 3.0
        out[ids] = acc / fn.area.sum(axis=1)[:, None]
    return out


def body_force_vector(mesh: Mesh, f1: Field, t: float = 0.0) -> NDArray[np.float64]:
    """``<f_1h, v> = sum_K |K| P_0 f1 . (vertex average of v)`` (paper Section 3.3, k = 1).

    Each vertex of K receives ``|K| P_0^K f1 / n_K``.
    """
    fbar = cell_means(mesh, f1, t, "body force f1")
    share = (mesh.cell_areas / mesh.cell_sizes)[:, None] * fbar  # (n_cells, 2)
    per_vertex = np.repeat(share, mesh.cell_sizes, axis=0)
    F = np.zeros((mesh.n_points, 2))
    np.add.at(F, mesh.cell_vertices, per_vertex)
    return F.ravel()


_GAUSS2 = np.array([0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0)])


def edge_load_vector(
    mesh: Mesh, edges: NDArray[np.int64], f: Field, t: float = 0.0, name: str = "traction f2"
) -> NDArray[np.float64]:
    """``int_E f . v ds`` over the given edges, by two-point Gauss on every edge
    (exact for f linear along the edge, since v is linear there)."""
    F = np.zeros((mesh.n_points, 2))
    if len(edges) == 0:
        return F.ravel()
    a, b = mesh.points[edges[:, 0]], mesh.points[edges[:, 1]]
    L = np.linalg.norm(b - a, axis=1)[:, None]
    for s in _GAUSS2:
        val = _eval_field(f, (1 - s) * a + s * b, t, name) * (0.5 * L)
        np.add.at(F, edges[:, 0], (1 - s) * val)
        np.add.at(F, edges[:, 1], s * val)
    return F.ravel()


def traction_vector(mesh: Mesh, f2: Field, t: float = 0.0) -> NDArray[np.float64]:
    """``int_{Gamma_N} f2 . v ds`` on the traction part."""
    return edge_load_vector(mesh, mesh.part_edges("traction"), f2, t)


def projection_coefficients(mesh: Mesh, u: NDArray[np.float64]):
    """The linear field ``Pi u`` on every cell: ``Pi u(x) = vbar_K + G_K (x - xbar_K)``.

    ``G = E + omega J`` with ``E = eps(Pi u)`` from (3.8) and ``omega`` from (3.10):
    ``omega = (sum_i d_i x u_i - sum_i d_i x E d_i) / sum_i |d_i|^2``, ``d_i = x_i - xbar``.

    Returns
    -------
    xbar, vbar : (n_cells, 2) arrays (vertex averages of coordinates and of u, 3.9)
    G : (n_cells, 2, 2) array, ``G[k, i, j] = d_j (Pi u)_i`` on cell k
    """
    U = np.asarray(u, dtype=float).reshape(mesh.n_points, 2)
    xbar_all = np.zeros((mesh.n_cells, 2))
    vbar_all = np.zeros((mesh.n_cells, 2))
    G = np.zeros((mesh.n_cells, 2, 2))
    for _n, (ids, verts) in mesh.groups.items():
        X, V = mesh.points[verts], U[verts]
        area, xbar, q = geometry(X)
        # eps(Pi u) = 1/|K| sum_i sym(u_i (x) q_i)
        M = np.einsum("mia,mib->mab", V, q) / area[:, None, None]
        E = 0.5 * (M + M.transpose(0, 2, 1))
        d = X - xbar[:, None, :]
        Ed = np.einsum("mab,mib->mia", E, d)
        cross = lambda a, b: a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]  # noqa: E731
        omega = np.sum(cross(d, V) - cross(d, Ed), axis=1) / np.sum(d**2, axis=(1, 2))
        G[ids] = E
        G[ids, 0, 1] -= omega
        G[ids, 1, 0] += omega
        xbar_all[ids], vbar_all[ids] = xbar, V.mean(axis=1)
    return xbar_all, vbar_all, G
