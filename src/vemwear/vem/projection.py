"""The projection Pi of (3.8)-(3.10), lowest order (k = 1), as an operator.

The formulas below are those of docs/method.md, section 2.

On a cell K with vertices ``x_1, ..., x_n`` (counter-clockwise), vertex average
``xbar`` and ``d_i = x_i - xbar``, the projection of a virtual element function v with
vertex values ``v_i`` is the linear field

    ``Pi v(x) = vbar + G (x - xbar)``,  ``G = E + rotation J``,  ``J = [[0, -1], [1, 0]]``,

where

* ``E = eps(Pi v) = 1/|K| int_dK sym(v (x) n) ds = 1/|K| sum_i sym(v_i (x) q_i)`` is fixed
  by (3.8) (v is linear on the edges; ``q_i`` are the vertex normal weights of
  :func:`geometry`);
* ``vbar = (1/n) sum_i v_i``, the value at ``xbar``, is fixed by (3.9);
* the rotation is fixed by (3.10). Given (3.9), (3.10) is
  ``sum_i d_i x Pi v(x_i) = sum_i d_i x v_i``, and since ``d x J d = |d|^2``:

      ``rotation = (sum_i d_i x v_i - sum_i d_i x E d_i) / sum_i |d_i|^2``.

Everything is linear in the dofs. :func:`local_projection` writes the gradient ``G`` of a
batch of cells of equal vertex count as weights on the dofs (one formula for the
rotation, :func:`rotation_weights`); the element matrices
(:func:`vemwear.vem.local.element_matrices`) and the global operator :class:`Projection`
(dofs -> the linear field of every cell; its evaluation at points) are both built from
it.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..mesh.locate import locate_cells
from ..mesh.polymesh import Mesh

__all__ = [
    "LinearFields",
    "LocalProjection",
    "Projection",
    "geometry",
    "local_projection",
    "project",
    "projection_matrix",
    "rotation_weights",
    "strain_operator",
]


def geometry(
    X: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Areas, vertex averages and the vertex normal weights of a batch of polygons.

    Parameters
    ----------
    X : (m, n, 2) array
        Vertex coordinates, counter-clockwise.

    Returns
    -------
    area : (m,) array
    xbar : (m, 2) array, the vertex average (3.9)
    q : (m, n, 2) array, ``q_i = (|e_{i-1}| n_{i-1} + |e_i| n_i) / 2`` so that
        ``int_dK v (x) n ds = sum_i v_i (x) q_i`` for v linear on edges.
    """
    xbar = X.mean(axis=1)
    Y = X - xbar[:, None, :]  # relative coordinates keep the shoelace sum accurate
    Yn = np.roll(Y, -1, axis=1)
    area = 0.5 * np.sum(Y[..., 0] * Yn[..., 1] - Yn[..., 0] * Y[..., 1], axis=1)
    d = Yn - Y
    N = np.stack([d[..., 1], -d[..., 0]], axis=-1)  # |e| n for counter-clockwise cells
    q = 0.5 * (N + np.roll(N, 1, axis=1))
    return area, xbar, q


def strain_operator(area: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """``B`` with ``(eps_xx, eps_yy, 2 eps_xy)(Pi v) = B @ v`` (3.8); shape (m, 3, 2n)."""
    m, n, _ = q.shape
    B = np.zeros((m, 3, 2 * n))
    qa = q / area[:, None, None]
    B[:, 0, 0::2] = qa[..., 0]
    B[:, 1, 1::2] = qa[..., 1]
    B[:, 2, 0::2] = qa[..., 1]
    B[:, 2, 1::2] = qa[..., 0]
    return B


def _strain_weights(
    qa: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``E_xx, E_yy, E_xy`` of ``Pi v`` as weights (m, n, 2) on the dofs ``v_ic`` (3.8):
    ``E_ab = sum_i (v_ia qa_ib + v_ib qa_ia) / 2`` with ``qa = q / |K|``."""
    qx, qy = qa[..., 0], qa[..., 1]
    zero = np.zeros_like(qx)
    exx = np.stack([qx, zero], axis=-1)
    eyy = np.stack([zero, qy], axis=-1)
    exy = 0.5 * np.stack([qy, qx], axis=-1)
    return exx, eyy, exy


def rotation_weights(rel: NDArray[np.float64], qa: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation of ``Pi v`` fixed by (3.10), as weights on the dofs.

    ``rotation = (sum_i d_i x v_i - sum_i d_i x E d_i) / sum_i |d_i|^2`` with ``E`` the
    strain (3.8). For a symmetric E, ``sum_i d_i x E d_i = E_xy (S_xx - S_yy) + (E_yy -
    E_xx) S_xy`` with the second moments ``S_ab = sum_i d_ia d_ib``.

    Parameters
    ----------
    rel : (m, n, 2) array
        ``d_i = x_i - xbar``.
    qa : (m, n, 2) array
        The vertex normal weights divided by the area, ``q_i / |K|``.

    Returns
    -------
    (m, n, 2) array
        ``R`` with ``rotation = sum_{i, c} R[:, i, c] v_ic``.
    """
    dx, dy = rel[..., 0], rel[..., 1]
    Sxx, Syy, Sxy = (
        np.sum(a * b, axis=1)[:, None, None] for a, b in ((dx, dx), (dy, dy), (dx, dy))
    )
    exx, eyy, exy = _strain_weights(qa)
    d_cross_e = np.stack([-dy, dx], axis=-1)  # d_i x e_c
    return (d_cross_e - (exy * (Sxx - Syy) + (eyy - exx) * Sxy)) / (Sxx + Syy)


class LocalProjection(NamedTuple):
    """``Pi`` on a batch of ``m`` cells with ``n`` vertices each (:func:`local_projection`)."""

    area: NDArray[np.float64]  # (m,)
    xbar: NDArray[np.float64]  # (m, 2) vertex averages
    rel: NDArray[np.float64]  # (m, n, 2) d_i = x_i - xbar
    q: NDArray[np.float64]  # (m, n, 2) vertex normal weights
    gradient: NDArray[np.float64]  # (m, 2, 2, n, 2): G_ab = sum_ic gradient[:, a, b, i, c] v_ic


def local_projection(X: NDArray[np.float64]) -> LocalProjection:
    """The gradient ``G = E + rotation J`` of ``Pi v`` as weights on the dofs (3.8), (3.10).

    Parameters
    ----------
    X : (m, n, 2) array
        Vertex coordinates, counter-clockwise.
    """
    area, xbar, q = geometry(X)
    rel = X - xbar[:, None, :]
    qa = q / area[:, None, None]
    exx, eyy, exy = _strain_weights(qa)
    R = rotation_weights(rel, qa)
    m, n, _ = X.shape
    Gw = np.empty((m, 2, 2, n, 2))
    Gw[:, 0, 0], Gw[:, 1, 1] = exx, eyy
    Gw[:, 0, 1], Gw[:, 1, 0] = exy - R, exy + R
    return LocalProjection(area, xbar, rel, q, Gw)


def projection_matrix(lp: LocalProjection) -> NDArray[np.float64]:
    """The matrix of the vertex values of ``Pi v`` in terms of the dofs of v.

    ``(Pi v)(x_j)_a = vbar_a + sum_b d_jb G_ab``; shape (m, 2n, 2n), dofs interleaved
    ``(v_x1, v_y1, v_x2, ...)``: one batched product of the ``d_j`` with the gradient
    weights, plus ``1/n`` (the vertex average, 3.9) on the entries with ``a = c``.
    """
    m, n, _ = lp.rel.shape
    G = np.ascontiguousarray(lp.gradient.transpose(0, 2, 1, 3, 4)).reshape(m, 2, 4 * n)
    P = np.matmul(lp.rel, G).reshape(m, n, 2, n, 2)  # [j, a, i, c]
    for a in range(2):
        P[:, :, a, :, a] += 1.0 / n
    return P.reshape(m, 2 * n, 2 * n)


class LinearFields(NamedTuple):
    """A linear field per cell, ``value + gradient (x - xbar)`` on cell k (e.g. ``Pi u``);
    :meth:`Projection.many` puts a leading axis of fields on ``value`` and ``gradient``
    (the properties and :meth:`at` take one field)."""

    xbar: NDArray[np.float64]  # (n_cells, 2) expansion points, the vertex averages
    value: NDArray[np.float64]  # (n_cells, 2) the values at xbar (3.9: the vertex averages)
    gradient: NDArray[np.float64]  # (n_cells, 2, 2), gradient[k, i, j] = d_j (Pi u)_i

    @property
    def strain(self) -> NDArray[np.float64]:
        """(n_cells, 2, 2) symmetric part of the gradient, ``eps(Pi u)`` (3.8)."""
        return 0.5 * (self.gradient + self.gradient.transpose(0, 2, 1))

    @property
    def rotation(self) -> NDArray[np.float64]:
        """(n_cells,) the rotation of (3.10): half the antisymmetric part, ``(G_yx - G_xy) / 2``."""
        return 0.5 * (self.gradient[:, 1, 0] - self.gradient[:, 0, 1])

    def at(self, points: ArrayLike, cells: ArrayLike) -> NDArray[np.float64]:
        """The field of ``cells[j]`` at ``points[j]``; (len(points), 2)."""
        x = np.asarray(points, dtype=float).reshape(-1, 2)
        c = np.asarray(cells, dtype=np.int64)
        return self.value[c] + np.einsum("nij,nj->ni", self.gradient[c], x - self.xbar[c])


class Projection:
    """``Pi`` of (3.8)-(3.10) on a mesh: from the dofs of a displacement (the vertex values,
    ``2 n_points``, interleaved) to the linear field of every cell.

    The map is one sparse matrix of shape ``(6 n_cells, 2 n_points)`` (:attr:`matrix`):
    rows ``6 k + (0, 1)`` give the value at the vertex average of cell k (3.9), rows
    ``6 k + 2 + (2 i + j)`` the gradient entry ``d_j (Pi u)_i`` (strain (3.8) plus rotation
    (3.10)). It is built group by group from :func:`local_projection`, once per mesh;
    every field then costs one sparse product.

    Parameters
    ----------
    mesh : Mesh
    """

    def __init__(self, mesh: Mesh) -> None:
        self.mesh = mesh
        nc = mesh.n_cells
        self.xbar = np.zeros((nc, 2))
        self.area = np.zeros(nc)
        # the CSR arrays written in place, cell by cell: rows 6k, 6k + 1 hold n entries,
        # rows 6k + 2 ... 6k + 5 hold 2n, each row's columns ascending (no COO
        # temporaries, no sort of all entries)
        sizes = mesh.cell_sizes
        row_len = (sizes[:, None] * np.array([1, 1, 2, 2, 2, 2])).ravel()
        indptr = np.concatenate([[0], np.cumsum(row_len)])
        start = indptr[:-1:6]  # the first entry of every cell
        indices = np.empty(
            int(indptr[-1]), dtype=np.int32 if 2 * mesh.n_points < 2**31 else np.int64
        )
        data = np.empty(int(indptr[-1]))
        for n, (ids, verts) in mesh.groups.items():
            lp = local_projection(mesh.points[verts])
            self.xbar[ids], self.area[ids] = lp.xbar, lp.area
            m = len(ids)
            order = np.argsort(verts, axis=1, kind="stable")  # ascending columns
            v = np.take_along_axis(verts, order, axis=1)
            # gradient: (m, 4, n, 2) weights on the dofs (v_ic), vertices in column order
            Gw = np.take_along_axis(lp.gradient.reshape(m, 4, n, 2), order[:, None, :, None], 2)
            dofs = (2 * v[:, :, None] + np.arange(2)).reshape(m, 2 * n)
            # value at xbar: (1/n) sum_i v_ic for component c; then the gradient rows
            s0 = int(start[ids[0]]) if m else 0
            if np.array_equal(start[ids], s0 + 10 * n * np.arange(m)):
                # the group's cells in a row (a mesh of one cell shape): written in place
                ind = indices[s0 : s0 + 10 * n * m].reshape(m, 10 * n)
                dat = data[s0 : s0 + 10 * n * m].reshape(m, 10 * n)
                ind[:, :n], ind[:, n : 2 * n] = 2 * v, 2 * v + 1
                ind[:, 2 * n :].reshape(m, 4, 2 * n)[:] = dofs[:, None, :]
                dat[:, : 2 * n] = 1.0 / n
                dat[:, 2 * n :] = Gw.reshape(m, 8 * n)
                continue
            pos = start[ids][:, None] + np.arange(10 * n)
            indices[pos] = np.concatenate([2 * v, 2 * v + 1, np.tile(dofs, 4)], axis=1)
            data[pos] = np.concatenate([np.full((m, 2 * n), 1.0 / n), Gw.reshape(m, 8 * n)], axis=1)
        self.matrix: sp.csr_matrix = sp.csr_matrix(
            (data, indices, indptr), shape=(6 * nc, 2 * mesh.n_points)
        )
        self._entry_major: sp.csr_matrix | None = None  # for many(), built on first use

    def __call__(self, u: ArrayLike) -> LinearFields:
        """``Pi u`` on every cell.

        Parameters
        ----------
        u : (n_points, 2) or (2 n_points,) array_like
            The vertex values (the dofs).
        """
        v = np.asarray(u, dtype=float).reshape(-1)
        if v.size != self.matrix.shape[1]:
            raise ValueError(
                f"projection: u has {v.size} entries, expected 2 x {self.mesh.n_points} "
                "(two per vertex)"
            )
        c = (self.matrix @ v).reshape(-1, 6)
        return LinearFields(self.xbar, c[:, :2], c[:, 2:].reshape(-1, 2, 2))

    def many(self, u: ArrayLike) -> LinearFields:
        """``Pi u`` on every cell for a block of fields (e.g. the time levels of a run): one
        sparse matrix times dense matrix product, every entry summed in the order of
        :meth:`__call__` (the same numbers).

        Parameters
        ----------
        u : (B, n_points, 2) or (B, 2 n_points) array_like
            The vertex values of ``B`` fields.

        Returns
        -------
        LinearFields
            With ``value`` of shape (B, n_cells, 2) and ``gradient`` (B, n_cells, 2, 2)
            (``xbar`` shared, (n_cells, 2)).
        """
        v = np.asarray(u, dtype=float)
        v = v.reshape(len(v), -1)
        if v.shape[1] != self.matrix.shape[1]:
            raise ValueError(
                f"projection: the fields have {v.shape[1]} entries, expected 2 x "
                f"{self.mesh.n_points} (two per vertex)"
            )
        # entry-major (6, B, n_cells): every entry of every field contiguous over the cells
        # (the rows of the matrix taken entry by entry; no copy for one field)
        if self._entry_major is None:
            nc = self.matrix.shape[0] // 6
            self._entry_major = self.matrix[np.arange(6 * nc).reshape(nc, 6).T.ravel()]
        m = len(v)
        c = np.ascontiguousarray((self._entry_major @ v.T).reshape(6, -1, m).transpose(0, 2, 1))
        value = c[:2].transpose(1, 2, 0)
        return LinearFields(self.xbar, value, c[2:].reshape(2, 2, m, -1).transpose(2, 3, 0, 1))

    def strain(self, u: ArrayLike) -> NDArray[np.float64]:
        """(n_cells, 2, 2) the cell strains ``eps(Pi u)`` (3.8)."""
        return self(u).strain

    def evaluate(
        self, u: ArrayLike, points: ArrayLike, cells: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """``Pi u`` of the containing cell at every point.

        Parameters
        ----------
        u : (n_points, 2) array_like
        points : (q, 2) array_like
        cells : (q,) array_like of int, optional
            The containing cells, if known (default:
            :func:`~vemwear.mesh.locate.locate_cells`).

        Returns
        -------
        (q, 2) array

        Raises
        ------
        ValueError
            If a point lies outside the mesh.
        """
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        c = locate_cells(self.mesh, pts) if cells is None else np.asarray(cells, dtype=np.int64)
        if np.any(c < 0):
            bad = pts[c < 0][:3].tolist()
            raise ValueError(f"projection: points {bad} lie outside the mesh")
        return self(u).at(pts, c)


def project(mesh: Mesh, u: ArrayLike) -> LinearFields:
    """``Pi u`` on every cell of ``mesh`` (one field; for many, keep a :class:`Projection`)."""
    return Projection(mesh)(u)
