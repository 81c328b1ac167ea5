"""Prolongation of coarse functions to the points of a nested fine mesh.

:func:`prolongation` carries a virtual element function (its vertex values) of a coarse
mesh to fine points, :func:`contact_prolongation` the wear along Gamma_C. Both are
sparse matrices, built once per pair of meshes and applied to every time level
(:class:`vemwear.post.compare.Comparison`). They give the secondary error variants of
Example 5.5 (docs/method.md, section 7); the primary ones compare the projections Pi
(3.8)-(3.10) of both solutions and need no prolongation.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from ..mesh.locate import (
    NonNestedMeshError,
    extent_tol,
    inside_polygons,
    padded_edges,
    point_segment_distance,
    vertex_averages,
)
from ..mesh.polymesh import Mesh

__all__ = ["contact_prolongation", "prolongation"]


def prolongation(
    coarse: Mesh,
    fine_points: ArrayLike,
    *,
    tol: float | None = None,
    candidates: int = 12,
    cells: ArrayLike | None = None,
    vertices: ArrayLike | None = None,
) -> sp.csr_matrix:
    """The linear map from coarse vertex values to values at fine points (nested meshes).

    A VEM function ``v`` of the coarse mesh is known on the cell boundaries (linear on
    every edge) but not inside the cells. The prolongation takes, at a fine point,
    ``v`` itself if the point is a coarse vertex or lies on a coarse edge (linear
    interpolation along the edge, exact), and the mean value interpolant (Floater's
    generalized barycentric coordinates: linear on the edges, exact for linear fields,
    defined on any simple polygon) of the vertex values of the coarse cell containing
    it otherwise. The result is a continuous function of the fine mesh.

    Parameters
    ----------
    coarse : Mesh
    fine_points : (q, 2) array_like
        Points inside the coarse mesh (typically the vertices of a nested fine mesh).
    tol : float, optional
        Distance under which a point is on an edge; default ``1e-9`` times the diameter
        of the bounding box of the coarse mesh.
    candidates : int
        Number of nearest cells (by vertex average) tried for every point.
    cells : (q,) array_like of int, optional
        For every point, a coarse cell whose closure should contain it (-1: none known),
        e.g. the coarse cell of a fine cell around a fine vertex
        (:func:`~vemwear.mesh.locate.nested_cells`). It is tried first; only the points
        it does not hold are searched among the nearest cells.
    vertices : (n_coarse,) array_like of int, optional
        The index of the fine point at every coarse vertex, if known
        (:func:`~vemwear.mesh.locate.match_vertices`): those points take the vertex
        values without a search, and no other point is a coarse vertex.

    Returns
    -------
    (2 q, 2 n_coarse) sparse matrix
        Acting on the interleaved vertex values ``(v_x, v_y)``.

    Raises
    ------
    NonNestedMeshError
        If a point lies in no coarse cell.
    """
    X = np.asarray(fine_points, dtype=float)
    q = len(X)
    C = coarse.points
    tol = extent_tol(C, tol)
    rows: list[NDArray[np.int64]] = []
    cols: list[NDArray[np.int64]] = []
    vals: list[NDArray[np.float64]] = []

    def add(pts: NDArray[np.int64], verts: NDArray[np.int64], w: NDArray[np.float64]) -> None:
        for c in range(2):
            rows.append(2 * pts + c)
            cols.append(2 * verts + c)
            vals.append(w)

    # 1. coarse vertices
    if vertices is None:
        dist, near = cKDTree(C).query(X, k=1)
        hit = np.flatnonzero(dist <= tol)
        add(hit, near[hit], np.ones(len(hit)))
        todo = np.flatnonzero(dist > tol)
    else:
        at = np.asarray(vertices, dtype=np.int64).reshape(coarse.n_points)
        add(at, np.arange(len(at)), np.ones(len(at)))
        rest = np.ones(q, dtype=bool)
        rest[at] = False
        todo = np.flatnonzero(rest)
    # 2. points on a coarse edge or inside a coarse cell
    V, Vn = padded_edges(coarse)  # (nc, nmax), padded with degenerate edges
    nmax = V.shape[1]

    def claim(todo: NDArray[np.int64], owner: NDArray[np.int64]) -> NDArray[np.bool_]:
        """Add the rows of the points ``todo`` that lie on the boundary of (or inside)
        their cell of ``owner``; returns the mask of the points left."""
        P = X[todo][:, None, :]
        A, B = C[V[owner]], C[Vn[owner]]  # (t, nmax, 2): edges A -> B, closing edge last
        de, s = point_segment_distance(P, A, B)
        j = np.argmin(de, axis=1)
        t_all = np.arange(len(todo))
        on_edge = de[t_all, j] <= tol
        if np.any(on_edge):
            t_ = np.flatnonzero(on_edge)
            sj = s[t_, j[t_]]
            add(todo[t_], V[owner[t_], j[t_]], 1.0 - sj)
            add(todo[t_], Vn[owner[t_], j[t_]], sj)
        inside = inside_polygons(P, A, B) & ~on_edge
        if np.any(inside):
            # mean value coordinates: w_i = (tan(a_{i-1}/2) + tan(a_i/2)) / r_i, with a_i the
            # angle at x of the edge (A_i, B_i); tan(a/2) = cross / (r_A r_B + dot)
            # (sums over the two coordinates written out: the same numbers, faster)
            t_ = np.flatnonzero(inside)
            Pt, At, Bt = P[t_], A[t_], B[t_]
            ax, ay = At[..., 0] - Pt[..., 0], At[..., 1] - Pt[..., 1]
            bx, by = Bt[..., 0] - Pt[..., 0], Bt[..., 1] - Pt[..., 1]
            rA, rB = np.sqrt(ax * ax + ay * ay), np.sqrt(bx * bx + by * by)
            tan = (ax * by - ay * bx) / (rA * rB + (ax * bx + ay * by))  # 0 if degenerate
            tA, tB = tan / rA, tan / rB  # contributions to the edge's two ends
            tot = np.sum(tA + tB, axis=1)[:, None]
            pts = np.repeat(todo[t_], nmax)
            add(
                np.concatenate([pts, pts]),
                np.concatenate([V[owner[t_]].ravel(), Vn[owner[t_]].ravel()]),
                np.concatenate([(tA / tot).ravel(), (tB / tot).ravel()]),
            )
        return ~(on_edge | inside)

    if cells is not None and todo.size:
        hint = np.asarray(cells, dtype=np.int64).reshape(q)[todo]
        known = hint >= 0
        left = claim(todo[known], hint[known])
        todo = np.sort(np.concatenate([todo[known][left], todo[~known]]))
    k = min(int(candidates), coarse.n_cells)
    if todo.size:
        _d, cand = cKDTree(vertex_averages(coarse)).query(X[todo], k=k)
        cand = np.asarray(cand).reshape(len(todo), k)
        for r in range(k):
            keep = claim(todo, cand[:, r])
            todo, cand = todo[keep], cand[keep]
            if todo.size == 0:
                break
    if todo.size:
        b = int(todo[0])
        raise NonNestedMeshError(
            f"{todo.size} fine points lie in none of the {k} nearest coarse cells (first: "
            f"{X[b].tolist()}); are the meshes nested and covering the same domain?"
        )
    M = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * q, 2 * coarse.n_points),
    )
    M.sum_duplicates()
    return M


def contact_prolongation(
    coarse: Mesh, coarse_nodes: ArrayLike, fine_points: ArrayLike, *, tol: float | None = None
) -> sp.csr_matrix:
    """The linear map from wear values at the coarse contact nodes to values at fine points
    on Gamma_C (piecewise linear interpolation along the coarse contact edges; the
    clamped end of Gamma_C carries 0).

    Returns
    -------
    (q, m_coarse) sparse matrix

    Raises
    ------
    NonNestedMeshError
        If a point is on no coarse contact edge.
    """
    X = np.asarray(fine_points, dtype=float)
    nodes = np.asarray(coarse_nodes, dtype=np.int64)
    C = coarse.points
    tol = extent_tol(C, tol)
    index = -np.ones(coarse.n_points, dtype=np.int64)
    index[nodes] = np.arange(len(nodes))
    e = coarse.part_edges("contact")
    k = min(4, len(e))
    _d, cand = cKDTree(0.5 * (C[e[:, 0]] + C[e[:, 1]])).query(X, k=k)
    cand = np.asarray(cand).reshape(len(X), k)
    de, s = point_segment_distance(X[:, None, :], C[e[cand, 0]], C[e[cand, 1]])
    j = np.argmin(de, axis=1)
    r = np.arange(len(X))
    if np.any(de[r, j] > tol):
        b = int(np.flatnonzero(de[r, j] > tol)[0])
        raise NonNestedMeshError(f"point {X[b].tolist()} is on no coarse contact edge")
    edge = cand[r, j]
    sj = s[r, j]
    rows, cols, vals = [], [], []
    for end, w in ((0, 1.0 - sj), (1, sj)):
        col = index[e[edge, end]]
        ok = col >= 0  # the clamped end of Gamma_C: w = 0
        rows.append(r[ok])
        cols.append(col[ok])
        vals.append(w[ok])
    M = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(len(X), len(nodes)),
    )
    M.sum_duplicates()
    return M
