"""Point location in a polygonal mesh: containing cells, matching vertices, nested meshes.

All searches start from a KD-tree (of vertices or of vertex averages) and confirm the
candidates with exact tests batched over the points: the crossing-number test for
"inside a polygon" and the distance to the cells' edges for points on cell boundaries.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .polymesh import Mesh

__all__ = [
    "NonNestedMeshError",
    "extent_tol",
    "inside_polygons",
    "interior_points",
    "locate_cells",
    "match_vertices",
    "nested_cells",
    "padded_edges",
    "point_segment_distance",
    "vertex_averages",
]


class NonNestedMeshError(ValueError):
    """A mesh that should be nested in another is not (a vertex or a cell of the fine mesh
    has no place in the coarse one)."""


def extent_tol(points: NDArray[np.float64], tol: float | None) -> float:
    """``tol``, or ``1e-9`` times the diameter of the bounding box of ``points``."""
    if tol is not None:
        return float(tol)
    span = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 1.0
    return 1e-9 * max(span, 1e-300)


def point_segment_distance(
    P: NDArray[np.float64], A: NDArray[np.float64], B: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Distance of points P to segments AB (broadcast) and the parameter s in [0, 1] of the
    foot of the perpendicular, ``A + s (B - A)``."""
    # sums over the two coordinates written out: reductions over an axis of length 2 are
    # slow, and these are the same numbers
    d = B - A
    d0, d1 = d[..., 0], d[..., 1]
    dd = np.maximum(d0 * d0 + d1 * d1, 1e-300)
    pa = P - A
    s = np.clip((pa[..., 0] * d0 + pa[..., 1] * d1) / dd, 0.0, 1.0)
    r = P - (A + s[..., None] * d)
    return np.sqrt(r[..., 0] * r[..., 0] + r[..., 1] * r[..., 1]), s


def vertex_averages(mesh: Mesh) -> NDArray[np.float64]:
    """(n_cells, 2) vertex average of every cell."""
    xbar = np.zeros((mesh.n_cells, 2))
    np.add.at(xbar, mesh.edge_cells, mesh.points[mesh.cell_vertices])
    return xbar / mesh.cell_sizes[:, None]


def padded_edges(mesh: Mesh) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """(n_cells, n_max) vertex ids ``V`` and ``Vn``: edge ``i`` of a cell runs from
    ``V[:, i]`` to ``Vn[:, i]`` (closing edge last); the lanes past a cell's vertex count
    are degenerate edges ``v_0 -> v_0``, which no point test sees."""
    sizes = mesh.cell_sizes
    lane = np.arange(int(sizes.max()))[None, :]
    pad = np.minimum(lane, sizes[:, None] - 1)
    V = mesh.cell_vertices[mesh.cell_offsets[:-1, None] + pad]
    nxt = np.where(lane < sizes[:, None] - 1, pad + 1, 0)  # edge i: v_i -> v_{i+1 mod n}
    Vn = mesh.cell_vertices[mesh.cell_offsets[:-1, None] + nxt]
    return np.where(lane < sizes[:, None], V, Vn), Vn


def inside_polygons(
    P: NDArray[np.float64], A: NDArray[np.float64], B: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Crossing-number test of the points P (t, 1, 2) in the polygons of edges A -> B
    (t, n, 2); degenerate edges are ignored."""
    y = P[..., 1]
    cross = (A[..., 1] > y) != (B[..., 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = A[..., 0] + (y - A[..., 1]) * (B[..., 0] - A[..., 0]) / (B[..., 1] - A[..., 1])
    return np.sum(cross & (P[..., 0] < xint), axis=1) % 2 == 1


def locate_cells(mesh: Mesh, points: ArrayLike, k: int = 12) -> NDArray[np.int64]:
    """The cell containing each point (-1 for points outside the mesh).

    Candidates are the ``k`` cells with the nearest vertex averages (a KD-tree); the
    first candidate that contains the point by the crossing-number test wins. A point
    on cell boundaries (or the domain boundary) that no test claims goes to the
    candidate whose boundary is nearest, within ``1e-9`` of the mesh extent.

    Parameters
    ----------
    mesh : Mesh
    points : (q, 2) array_like
    k : int
        Number of candidate cells per point.

    Returns
    -------
    (q,) int array
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    k = min(int(k), mesh.n_cells)
    from scipy.spatial import cKDTree  # start-up time: only when points are located

    _d, cand = cKDTree(vertex_averages(mesh)).query(pts, k=k)
    cand = np.asarray(cand).reshape(len(pts), k)
    V, Vn = padded_edges(mesh)
    C = mesh.points
    cell = -np.ones(len(pts), dtype=np.int64)
    for j in range(k):
        todo = np.flatnonzero(cell < 0)
        if todo.size == 0:
            break
        c = cand[todo, j]
        hit = inside_polygons(pts[todo][:, None, :], C[V[c]], C[Vn[c]])
        cell[todo[hit]] = c[hit]
    todo = np.flatnonzero(cell < 0)
    if todo.size:
        P = pts[todo][:, None, :]
        dist = np.stack(
            [
                point_segment_distance(P, C[V[cand[todo, j]]], C[Vn[cand[todo, j]]])[0].min(axis=1)
                for j in range(k)
            ],
            axis=1,
        )
        best = np.argmin(dist, axis=1)
        tol = 1e-9 * float(np.ptp(mesh.points, axis=0).max())
        ok = dist[np.arange(len(todo)), best] <= tol
        cell[todo[ok]] = cand[todo[ok], best[ok]]
    return cell


def match_vertices(
    coarse_points: ArrayLike, fine_points: ArrayLike, *, tol: float | None = None
) -> NDArray[np.int64]:
    """For every coarse vertex, the index of the fine vertex at the same place.

    Parameters
    ----------
    coarse_points, fine_points : (n, 2) array_like
        Vertex coordinates.
    tol : float, optional
        Largest accepted distance; default ``1e-9`` times the diameter of the bounding
        box of the fine points.

    Returns
    -------
    (n_coarse,) int array

    Raises
    ------
    NonNestedMeshError
        If a coarse vertex has no fine vertex within ``tol``; the message gives the
        number of such vertices and the first of them.
    """
    C = np.asarray(coarse_points, dtype=float)
    F = np.asarray(fine_points, dtype=float)
    tol = extent_tol(F, tol)
    from scipy.spatial import cKDTree

    dist, idx = cKDTree(F).query(C, k=1)
    bad = np.flatnonzero(~(dist <= tol))
    if bad.size:
        b = int(bad[0])
        raise NonNestedMeshError(
            f"the meshes are not nested: {bad.size} of {len(C)} coarse vertices are not "
            f"vertices of the fine mesh (first: vertex {b} at {C[b].tolist()}, nearest fine "
            f"vertex at distance {float(dist[b]):.3g} > tol {tol:.3g})"
        )
    return np.asarray(idx, dtype=np.int64)


def interior_points(mesh: Mesh) -> NDArray[np.float64]:
    """(n_cells, 2) a point inside every cell: the centroid of the largest triangle
    ``(xbar, x_i, x_{i+1})`` of the fan from the vertex average (inside whenever the cell
    is star-shaped with respect to its vertex average, e.g. convex)."""
    out = np.zeros((mesh.n_cells, 2))
    for _n, (ids, verts) in mesh.groups.items():
        X = mesh.points[verts]
        xbar = X.mean(axis=1)
        a = X - xbar[:, None, :]
        b = np.roll(a, -1, axis=1)
        area = a[..., 0] * b[..., 1] - b[..., 0] * a[..., 1]
        i = np.argmax(area, axis=1)
        r = np.arange(len(ids))
        out[ids] = xbar + (a[r, i] + b[r, i]) / 3.0
    return out


def nested_cells(coarse: Mesh, fine: Mesh, *, tol: float | None = None) -> NDArray[np.int64]:
    """For every cell of ``fine``, the cell of ``coarse`` that contains it (nested meshes).

    The coarse cell is the one containing an interior point of the fine cell
    (:func:`interior_points`); then every vertex of the fine cell is checked to lie in
    that coarse cell or on its boundary (within ``tol``).

    Parameters
    ----------
    coarse, fine : Mesh
    tol : float, optional
        Default ``1e-9`` times the diameter of the bounding box of the coarse mesh.

    Returns
    -------
    (fine.n_cells,) int array

    Raises
    ------
    NonNestedMeshError
        If a fine cell is not inside one coarse cell; the message names the first one.
    """
    tol = extent_tol(coarse.points, tol)
    V, Vn = padded_edges(coarse)
    C = coarse.points
    from scipy.spatial import cKDTree

    # an interior point of a fine cell lies strictly inside one coarse cell, so the order
    # in which cells are tried does not matter: the cell with the nearest vertex average
    # first (it holds most points), the full search of locate_cells for the others
    pts = interior_points(fine)
    _d, near = cKDTree(vertex_averages(coarse)).query(pts, k=1)
    near = np.asarray(near, dtype=np.int64)
    hit = inside_polygons(pts[:, None, :], C[V[near]], C[Vn[near]])
    cell = np.where(hit, near, -1)
    if not np.all(hit):
        cell[~hit] = locate_cells(coarse, pts[~hit])
    out = np.flatnonzero(cell < 0)
    if out.size:
        f = int(out[0])
        raise NonNestedMeshError(
            f"the meshes are not nested: {out.size} fine cells lie outside the coarse mesh "
            f"(first: cell {f} with vertices {fine.points[fine.cell(f)].tolist()})"
        )
    # every (fine vertex, coarse cell) pair once: the fine cells around a fine vertex lie
    # mostly in one coarse cell
    verts, owner = fine.cell_vertices, cell[fine.edge_cells]
    key = verts * coarse.n_cells + owner
    pairs, first = np.unique(key, return_index=True)
    P = fine.points[verts[first]][:, None, :]
    A, B = C[V[owner[first]]], C[Vn[owner[first]]]
    ok = inside_polygons(P, A, B)
    b = np.flatnonzero(~ok)  # on the coarse cell's boundary, or outside
    ok[b] = point_segment_distance(P[b], A[b], B[b])[0].min(axis=1) <= tol
    if not np.all(ok):
        j = int(np.flatnonzero(np.isin(key, pairs[~ok]))[0])
        f = int(fine.edge_cells[j])
        raise NonNestedMeshError(
            f"the meshes are not nested: fine cell {f} (vertex {int(verts[j])} at "
            f"{fine.points[verts[j]].tolist()}) is not inside coarse cell {int(owner[j])}"
        )
    return cell
