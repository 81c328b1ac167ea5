"""Lowest-order virtual elements (k = 1) for 3D linear elasticity on polyhedra.

docs/method.md, "3D (k = 1)". On a cell K with vertices ``x_1, ..., x_n`` (the distinct
vertices of its faces, in increasing id order: :attr:`Mesh3D.cell_vertex_ids`), vertex
average ``xbar`` and ``d_i = x_i - xbar``, local dof ``3 i + c`` is component c at x_i.

* **Strain (3.8).** ``eps(Pi v) = |K|^-1 int_dK sym(v (x) n) ds = |K|^-1 sum_i sym(v_i (x) q_i)``
  with the cell vertex normal weights ``q_i = sum_{F ∋ x_i} s_F w_i^F nu_F`` (``s_F`` the
  face's sign in K, ``nu_F`` its right-hand unit normal, ``w_i^F`` the face vertex weights
  of :mod:`vemwear.vem.quadrature3d`, exact for linear fields on planar faces). The volume
  is ``|K| = (1/3) sum_i d_i . q_i`` (``int_dK (x - xbar) . n = 3 |K|``), so that
  ``sum_i d_i (x) q_i = |K| I`` holds to round-off and Pi reproduces linear fields.
* **Rigid motion (3.9)-(3.10).** ``Pi v(x) = vbar + G (x - xbar)``, ``G = E + W(omega)``,
  ``W(omega) d = omega x d``; (3.9) gives the value ``vbar`` (the vertex average of v) at
  ``xbar``, and (3.10), given (3.9), is ``sum_i d_i x G d_i = sum_i d_i x v_i``. Since
  ``d x (omega x d) = (|d|^2 I - d d^T) omega``,
  ``omega = M^-1 (sum_i d_i x v_i - sum_i d_i x E d_i)``, ``M = tr(S) I - S``,
  ``S = sum_i d_i d_i^T`` (M is positive definite unless the vertices are collinear).
* **Bilinear form (3.11).** ``a_h^K = |K| B^T D B + s_K (I - P)^T (I - P)``, P the vertex
  values of Pi (the dofi-dofi stabilization). The weight ``s_K`` scales like the
  consistency term, which in 3D is ``O(h_K)``: ``"paper"`` takes ``h_K`` (the paper's
  unit weight times ``h_K^(d-2)``), ``"eta"`` takes ``2 eta h_K``, ``"trace"`` takes
  ``tr(K_c) / (3 n)``.
* **Loads (3.3).** Each vertex of K receives ``|K| P_0^K f1 / n``; a boundary face F gives
  its vertex i ``w_i^F P_0^F f2``.

Work is batched by vertex count (cells of equal n share one dense batch) and the
face-to-cell sums are segment sums over the flattened (cell, face, vertex) entries: no
Python loop over cells.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..mesh.polyhedra import Mesh3D
from ..util.arrays import members
from ..util.arrays import unique as _unique
from .local import STABILIZATIONS, Material
from .quadrature3d import (
    Field3,
    cell_face_entries,
    cell_means3d,
    face_geometry,
    face_means,
    segment_sum,
)

__all__ = [
    "CHUNK3",
    "CellGeometry",
    "LinearFields3D",
    "LocalProjection3D",
    "Projection3D",
    "body_force_vector3d",
    "cell_geometry",
    "elasticity_matrix",
    "element_matrices3d",
    "face_load_vector3d",
    "local_projection3d",
    "stiffness3d",
]

#: Cells per batch of local matrices in :func:`stiffness3d`: small batches reuse their
#: temporaries (a few MB) instead of mapping fresh ones, whose page faults cost more
#: than the arithmetic (as :data:`vemwear.vem.assembly.CHUNK` in 2D).
CHUNK3 = 256

#: The Levi-Civita symbol.
LEVI_CIVITA = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    LEVI_CIVITA[_i, _j, _k], LEVI_CIVITA[_i, _k, _j] = 1.0, -1.0

#: Voigt order (xx, yy, zz, 2 yz, 2 xz, 2 xy).
VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def elasticity_matrix(material: Material) -> NDArray[np.float64]:
    """The 6x6 matrix of ``sigma = 2 eta eps + lam tr(eps) I`` in Voigt notation
    (xx, yy, zz, 2yz, 2xz, 2xy)."""
    D = np.zeros((6, 6))
    D[:3, :3] = material.lam
    D[np.arange(3), np.arange(3)] += 2.0 * material.eta
    D[np.arange(3, 6), np.arange(3, 6)] = material.eta
    return D


class CellGeometry(NamedTuple):
    """Vertex normal weights, volumes and vertex averages of every cell (:func:`cell_geometry`).

    ``offsets``/``vertices`` are :attr:`Mesh3D.cell_vertex_offsets`/``cell_vertex_ids``; ``q``
    is aligned with ``vertices``: ``int_dK v (x) n ds = sum_i v(x_i) (x) q[offsets[K] + i]``.
    """

    offsets: NDArray[np.int64]
    vertices: NDArray[np.int64]
    q: NDArray[np.float64]  # (V, 3)
    volume: NDArray[np.float64]  # (n_cells,)
    xbar: NDArray[np.float64]  # (n_cells, 3)

    @property
    def sizes(self) -> NDArray[np.int64]:
        return np.diff(self.offsets)

    def groups(self) -> dict[int, tuple[NDArray[np.int64], NDArray[np.int64]]]:
        """Cells by vertex count: ``n -> (cell ids (m,), slots (m, n))``, slots indexing
        ``vertices`` and ``q``."""
        sizes = self.sizes
        out = {}
        for n in _unique(sizes):
            ids = np.flatnonzero(sizes == n)
            out[int(n)] = (ids, self.offsets[ids][:, None] + np.arange(n))
        return out


def cell_geometry(mesh: Mesh3D, rule: str = "enhanced") -> CellGeometry:
    """The cell vertex normal weights ``q_i`` of (3.8), volumes and vertex averages.

    Parameters
    ----------
    mesh : Mesh3D
    rule : {"enhanced", "fan"}
        The face vertex weights (:func:`~vemwear.vem.quadrature3d.face_geometry`).
    """
    fg = face_geometry(mesh, rule)
    off, verts = mesh.cell_vertex_offsets, mesh.cell_vertex_ids
    nc, npts = mesh.n_cells, mesh.n_points
    cell_v = np.repeat(np.arange(nc), np.diff(off))
    keys = cell_v * npts + verts  # increasing
    ce = cell_face_entries(mesh)
    slot = np.searchsorted(keys, ce.cell * npts + mesh.face_vertices[ce.entry])
    contrib = (ce.sign * fg.weights[ce.entry])[:, None] * fg.normal[fg.face[ce.entry]]
    q = segment_sum(slot, contrib, len(verts))
    xbar = segment_sum(cell_v, mesh.points[verts], nc) / np.diff(off)[:, None]
    d = mesh.points[verts] - xbar[cell_v]
    volume = np.bincount(cell_v, np.einsum("vc,vc->v", d, q), minlength=nc) / 3.0
    return CellGeometry(off, verts, q, volume, xbar)


class LocalProjection3D(NamedTuple):
    """Pi on a batch of m cells with n vertices each (:func:`local_projection3d`)."""

    xbar: NDArray[np.float64]  # (m, 3)
    rel: NDArray[np.float64]  # (m, n, 3) d_i = x_i - xbar
    strain: NDArray[np.float64]  # (m, 3, 3, n, 3): E_ab = sum_ic strain[:, a, b, i, c] v_ic
    gradient: NDArray[np.float64]  # (m, 3, 3, n, 3): G_ab likewise (strain + rotation)


def _cross_weights(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``out[m, p, i, c] = eps_pac v[m, i, a]``: the weights of ``u_i`` in ``v_i x u_i``,
    written entry by entry (each a single term, as the sum over a gives it)."""
    m, n, _ = v.shape
    out = np.zeros((m, 3, n, 3))
    for p, a, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        out[:, p, :, c] = v[:, :, a]
        out[:, p, :, a] = -v[:, :, c]
    return out


def local_projection3d(
    X: NDArray[np.float64], q: NDArray[np.float64], volume: NDArray[np.float64]
) -> LocalProjection3D:
    """The strain (3.8) and gradient (3.8)-(3.10) of ``Pi v`` as weights on the dofs.

    Parameters
    ----------
    X, q : (m, n, 3) arrays
        Vertex coordinates and cell vertex normal weights.
    volume : (m,) array
    """
    m, n, _ = X.shape
    xbar = X.mean(axis=1)
    d = X - xbar[:, None, :]
    qa = q / volume[:, None, None]
    # Ew[:, a, b, i, c] = (delta_ac qa_ib + delta_bc qa_ia) / 2, entry by entry
    half = 0.5 * qa.transpose(0, 2, 1)  # (m, 3, n)
    Ew = np.zeros((m, 3, 3, n, 3))
    for c in range(3):
        Ew[:, c, :, :, c] += half
        Ew[:, :, c, :, c] += half
    S = np.matmul(d.transpose(0, 2, 1), d)
    M = np.trace(S, axis1=1, axis2=2)[:, None, None] * np.eye(3) - S
    C = _cross_weights(d)  # sum_i d_i x v_i
    # sum_j d_j x E d_j with E = sym(sum_i v_i (x) qa_i): the weight of v_i is
    # (1/2) [(S qa_i) x . + eps_pab S_ax qa_ib] (sum_j d_j x (qa_i (d_j . v_i)) =
    # (S-weighted) qa_i): two small products instead of a five-index sum
    Z = np.zeros((m, 3, 3, 3))  # Z[:, p, b, x] = eps_pab S_ax
    for p, a, b in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        Z[:, p, b] = S[:, a]
        Z[:, p, a] = -S[:, b]
    T = 0.5 * (_cross_weights(np.matmul(qa, S)) + np.matmul(qa[:, None], Z))
    omega = np.linalg.solve(M, (C - T).reshape(m, 3, -1)).reshape(C.shape)
    Gw = Ew.copy()  # + W(omega): Gw[:, a, b] += eps_apb omega_p
    for a, p, b in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        Gw[:, a, b] += omega[:, p]
        Gw[:, b, a] -= omega[:, p]
    return LocalProjection3D(xbar, d, Ew, Gw)


def element_matrices3d(
    X: NDArray[np.float64],
    q: NDArray[np.float64],
    volume: NDArray[np.float64],
    material: Material,
    stabilization: str = "paper",
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Local stiffness matrices ``a_h^K`` (3.11) of a batch of cells with n vertices each.

    Parameters
    ----------
    X, q : (m, n, 3) arrays
        Vertex coordinates and cell vertex normal weights (:func:`cell_geometry`).
    volume : (m,) array
    material : Material
    stabilization : {"paper", "eta", "trace"}
        ``s_K = h_K``, ``2 eta h_K`` or ``tr(K_c) / (3n)`` (module docstring).

    Returns
    -------
    K : (m, 3n, 3n) local stiffness
    B : (m, 6, 3n) Voigt strain operator of Pi
    P : (m, 3n, 3n) vertex values of Pi v in terms of the dofs
    """
    if stabilization not in STABILIZATIONS:
        raise ValueError(
            f"unknown stabilization {stabilization!r}; expected one of {', '.join(STABILIZATIONS)}"
        )
    m, n, _ = X.shape
    lp = local_projection3d(X, q, volume)
    Ew = lp.strain.reshape(m, 3, 3, 3 * n)
    B = np.stack([(1.0 if a == b else 2.0) * Ew[:, a, b] for a, b in VOIGT], axis=1)
    K = np.matmul(B.transpose(0, 2, 1), np.einsum("ij,mjk->mik", elasticity_matrix(material), B))
    K *= volume[:, None, None]
    # P = U V has rank 12: U (3n, 12) the values at the vertices of the vertex average
    # and of the gradient (rows j a: delta_ac, d_jb delta_aa'), V (12, 3n) their weights
    # on the dofs, so (I - P)^T (I - P) = I - P - P^T + V^T (U^T U) V costs O(n^2), not
    # the O(n^3) of the product of two 3n x 3n matrices
    V = np.concatenate(
        [
            np.broadcast_to(np.tile(np.eye(3), n) / n, (m, 3, 3 * n)),
            lp.gradient.reshape(m, 9, 3 * n),
        ],
        axis=1,
    )
    U4 = np.zeros((m, n, 3, 12))
    U4[:, :, np.arange(3), np.arange(3)] = 1.0
    for a in range(3):
        U4[:, :, a, 3 + 3 * a : 6 + 3 * a] = lp.rel
    U = U4.reshape(m, 3 * n, 12)
    P = np.matmul(U, V)
    S = np.matmul(V.transpose(0, 2, 1), np.matmul(np.matmul(U.transpose(0, 2, 1), U), V))
    S -= P
    S -= P.transpose(0, 2, 1)
    S[:, np.arange(3 * n), np.arange(3 * n)] += 1.0
    if stabilization == "trace":
        s = np.trace(K, axis1=1, axis2=2) / (3 * n)
    else:
        diff = X[:, :, None, :] - X[:, None, :, :]
        h = np.sqrt(np.max(np.einsum("mijc,mijc->mij", diff, diff), axis=(1, 2)))
        s = h if stabilization == "paper" else 2.0 * material.eta * h
    K += s[:, None, None] * S
    return K, B, P


def stiffness3d(
    mesh: Mesh3D,
    material: Material,
    stabilization: str = "paper",
    rule: str = "enhanced",
    geometry: CellGeometry | None = None,
    cells: NDArray[np.int64] | None = None,
) -> sp.csr_matrix:
    """The stiffness of ``a_h`` (3.11) on all ``3 n_points`` dofs (dof ``3 v + c``).

    Local matrices are built by vertex count in chunks of :data:`CHUNK3` cells and
    summed by vertex pair: each cell gives ``n^2`` 3 x 3 blocks, the blocks of equal
    (row vertex, column vertex) are summed in cell order, and the block matrix is
    converted to CSR (sorted indices, no repeated entries). Sorting the ``n^2`` pairs
    of a cell instead of its ``9 n^2`` scalar triplets makes this 2-3 times faster than
    a COO-to-CSR conversion of the triplets (whose sums agree to round-off). ``cells``
    (ids) assembles the sum over those cells only (one MPI rank's part), in the same
    global numbering.
    """
    cg = cell_geometry(mesh, rule) if geometry is None else geometry
    nv = mesh.n_points
    groups = cg.groups()
    if cells is not None:
        keep = members(cells, len(cg.sizes))
        groups = {n: (ids[keep[ids]], sl[keep[ids]]) for n, (ids, sl) in groups.items()}
    total = int(sum(len(ids) * n * n for n, (ids, _sl) in groups.items()))
    keys = np.empty(total, dtype=np.int64)  # row vertex * nv + column vertex
    blocks = np.empty((total, 3, 3))
    at = 0
    for n, (ids, slots) in groups.items():
        for a in range(0, len(ids), CHUNK3):
            sl = slots[a : a + CHUNK3]
            v = cg.vertices[sl].astype(np.int64)
            size = len(v) * n * n
            Ke = element_matrices3d(
                mesh.points[v], cg.q[sl], cg.volume[ids[a : a + CHUNK3]], material, stabilization
            )[0]
            # local dof 3 i + c: block (i, j) holds Ke[3 i + c, 3 j + d] at (c, d)
            blocks[at : at + size].reshape(len(v), n, n, 3, 3)[...] = Ke.reshape(
                len(v), n, 3, n, 3
            ).transpose(0, 1, 3, 2, 4)
            keys[at : at + size].reshape(len(v), n, n)[...] = v[:, :, None] * nv + v[:, None, :]
            at += size
    order = np.argsort(keys)
    sk = keys[order]
    first = np.empty(total, dtype=bool)
    first[:1] = True
    np.not_equal(sk[1:], sk[:-1], out=first[1:])
    pairs = sk[first]
    slot = np.empty(total, dtype=np.int64)  # each cell block's place among the pairs
    slot[order] = np.cumsum(first) - 1
    del order, sk, first
    # bincount adds in input (cell) order, entry by entry, without a sorted copy
    flat = blocks.reshape(total, 9)
    data = np.empty((len(pairs), 9))
    for e in range(9):
        data[:, e] = np.bincount(slot, weights=flat[:, e], minlength=len(pairs))
    del blocks, flat, slot
    index = np.int32 if 3 * nv < 2**31 - 1 else np.int64
    indptr = np.zeros(nv + 1, dtype=index)
    np.cumsum(np.bincount(pairs // nv, minlength=nv), out=indptr[1:])
    B = sp.bsr_matrix(
        (data.reshape(-1, 3, 3), (pairs % nv).astype(index), indptr), shape=(3 * nv, 3 * nv)
    )
    return B.tocsr()


def body_force_vector3d(
    mesh: Mesh3D, f1: Field3, t: float = 0.0, geometry: CellGeometry | None = None
) -> NDArray[np.float64]:
    """``<f_1h, v> = sum_K |K| P_0^K f1 . (vertex average of v)`` (Section 3.3, k = 1):
    each vertex of K receives ``|K| P_0^K f1 / n_K``. Returns (3 n_points,)."""
    cg = cell_geometry(mesh) if geometry is None else geometry
    fbar = cell_means3d(mesh, f1, t, "body force f1")
    share = np.repeat((cg.volume / cg.sizes)[:, None] * fbar, cg.sizes, axis=0)
    F = segment_sum(cg.vertices, share, mesh.n_points)
    return F.ravel()


def face_load_vector3d(
    mesh: Mesh3D,
    faces: ArrayLike,
    f: Field3,
    t: float = 0.0,
    rule: str = "enhanced",
    name: str = "traction f2",
) -> NDArray[np.float64]:
    """``int_F P_0^F f . v ds`` over the given faces: vertex i of F receives
    ``w_i^F P_0^F f`` (exact for f constant on F; for the enhanced rule, exact for every v
    of the enhanced face space). Returns (3 n_points,)."""
    faces = np.asarray(faces, dtype=np.int64)
    if len(faces) == 0:
        return np.zeros(3 * mesh.n_points)
    fg = face_geometry(mesh, rule)
    fm = face_means(mesh, faces, f, t, name, geometry=fg)
    pick = np.full(mesh.n_faces, -1)
    pick[faces] = np.arange(len(faces))
    e = np.flatnonzero(pick[fg.face] >= 0)
    val = fg.weights[e][:, None] * fm[pick[fg.face[e]]]
    return segment_sum(mesh.face_vertices[e], val, mesh.n_points).ravel()


class LinearFields3D(NamedTuple):
    """A linear field per cell, ``value + gradient (x - xbar)`` on cell k (e.g. ``Pi u``)."""

    xbar: NDArray[np.float64]  # (n_cells, 3) the vertex averages
    value: NDArray[np.float64]  # (n_cells, 3) values at xbar (3.9)
    gradient: NDArray[np.float64]  # (n_cells, 3, 3), gradient[k, i, j] = d_j (Pi u)_i

    @property
    def strain(self) -> NDArray[np.float64]:
        """(n_cells, 3, 3) ``eps(Pi u)`` (3.8)."""
        return 0.5 * (self.gradient + self.gradient.transpose(0, 2, 1))

    @property
    def rotation(self) -> NDArray[np.float64]:
        """(n_cells, 3) the rotation vector omega of (3.10), ``W(omega) = skew(gradient)``."""
        G = self.gradient
        return 0.5 * np.stack(
            [G[:, 2, 1] - G[:, 1, 2], G[:, 0, 2] - G[:, 2, 0], G[:, 1, 0] - G[:, 0, 1]], axis=1
        )

    def at(self, points: ArrayLike, cells: ArrayLike) -> NDArray[np.float64]:
        """The field of ``cells[j]`` at ``points[j]``; (len(points), 3)."""
        x = np.asarray(points, dtype=float).reshape(-1, 3)
        c = np.asarray(cells, dtype=np.int64)
        return self.value[c] + np.einsum("nij,nj->ni", self.gradient[c], x - self.xbar[c])


class Projection3D:
    """Pi of (3.8)-(3.10) on a 3D mesh as one sparse matrix ``(12 n_cells, 3 n_points)``:
    rows ``12 k + c`` the value at the vertex average of cell k, rows ``12 k + 3 + 3 i + j``
    the gradient entry ``d_j (Pi u)_i``.

    Parameters
    ----------
    mesh : Mesh3D
    rule : {"enhanced", "fan"}
    geometry : CellGeometry, optional
        ``cell_geometry(mesh, rule)``, if already computed.
    """

    def __init__(
        self, mesh: Mesh3D, rule: str = "enhanced", geometry: CellGeometry | None = None
    ) -> None:
        self.mesh = mesh
        cg = cell_geometry(mesh, rule) if geometry is None else geometry
        self.xbar, self.volume = cg.xbar, cg.volume
        rows, cols, vals = [], [], []
        for n, (ids, slots) in cg.groups().items():
            v = cg.vertices[slots]
            lp = local_projection3d(mesh.points[v], cg.q[slots], cg.volume[ids])
            m = len(ids)
            dofs = 3 * v[:, :, None] + np.arange(3)  # (m, n, 3)
            for c in range(3):
                rows.append(np.repeat(12 * ids + c, n))
                cols.append(dofs[:, :, c].ravel())
                vals.append(np.full(m * n, 1.0 / n))
            Gw = lp.gradient.reshape(m, 9, n, 3)
            r = 12 * ids[:, None, None, None] + 3 + np.arange(9)[None, :, None, None]
            rows.append(np.broadcast_to(r, Gw.shape).ravel())
            cols.append(np.broadcast_to(dofs[:, None], Gw.shape).ravel())
            vals.append(Gw.ravel())
        self.matrix: sp.csr_matrix = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(12 * mesh.n_cells, 3 * mesh.n_points),
        )

    def __call__(self, u: ArrayLike) -> LinearFields3D:
        """Pi u on every cell; ``u`` (n_points, 3) or (3 n_points,), the vertex values."""
        v = np.asarray(u, dtype=float).reshape(-1)
        if v.size != self.matrix.shape[1]:
            raise ValueError(
                f"projection: u has {v.size} entries, expected 3 x {self.mesh.n_points}"
            )
        c = (self.matrix @ v).reshape(-1, 12)
        return LinearFields3D(self.xbar, c[:, :3], c[:, 3:].reshape(-1, 3, 3))
