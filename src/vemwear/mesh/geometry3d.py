"""Geometry of polyhedral meshes: faces, cells, edges, all vectorized over the mesh.

Faces of any vertex count are handled together through their concatenated vertex loops
(CSR arrays ``offsets``, ``vertices``): a face is cut into the triangles of the fan around
its vertex average ``c``, ``(c, v_i, v_{i+1})``. Its *area vector* is the sum of the
triangles' area vectors (for a planar face: area times unit normal, by the right-hand rule
along the loop; the same as Newell's normal for any loop), its centroid the average of the
triangles' centroids weighted by their areas projected on the face normal (exact for any
planar simple polygon, convex or not). Cells are cut into the tetrahedra
``(x_K, c_f, v_i, v_{i+1})`` over their signed faces, ``x_K`` the average of the cells'
face points: their signed volumes sum to the cell's volume (the divergence theorem), and
their centroids weighted by them to its centroid, for any closed cell.

The functions take plain arrays, so that generators can use them before a
:class:`~vemwear.mesh.polyhedra.Mesh3D` exists; the mesh exposes them as cached properties.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..util.arrays import unique as _unique

__all__ = [
    "cell_geometry",
    "cross_rows",
    "face_geometry",
    "face_planarity",
    "group_max_distance",
    "loop_next",
    "loop_owner",
    "reverse_loops",
    "take_loops",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def loop_owner(offsets: IntArray) -> IntArray:
    """The loop (face) of every entry of a CSR array of loops."""
    return np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))


def loop_next(offsets: IntArray) -> IntArray:
    """Index of the next entry of every entry in its loop (the last goes to the first)."""
    nxt = np.arange(1, offsets[-1] + 1, dtype=np.int64)
    if len(offsets) > 1:
        nxt[offsets[1:] - 1] = offsets[:-1]
    return nxt


def take_loops(offsets: IntArray, values: IntArray, which: IntArray) -> tuple[IntArray, IntArray]:
    """The loops ``which`` of a CSR array, as a new CSR array (in that order)."""
    which = np.asarray(which, dtype=np.int64)
    sizes = np.diff(offsets)[which]
    out = np.zeros(len(which) + 1, dtype=np.int64)
    np.cumsum(sizes, out=out[1:])
    idx = np.repeat(offsets[which] - out[:-1], sizes) + np.arange(out[-1])
    return out, values[idx]


def reverse_loops(offsets: IntArray, values: IntArray, flip: NDArray[np.bool_]) -> IntArray:
    """The loop values with the loops ``flip`` reversed (first vertex kept first)."""
    owner = loop_owner(offsets)
    local = np.arange(offsets[-1]) - offsets[owner]
    size = np.diff(offsets)[owner]
    src = offsets[owner] + np.where(flip[owner], (size - local) % size, local)
    return values[src]


def cross_rows(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise cross products of (m, 3) arrays: the products and differences of
    :func:`numpy.cross`, without its broadcasting and copies."""
    out = np.empty((len(a), 3))
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.subtract(a[:, j] * b[:, k], a[:, k] * b[:, j], out=out[:, i])
    return out


def _segment_sum(values: NDArray, owner: IntArray, n: int) -> NDArray:
    """Sums of the rows of ``values`` (m,) or (m, k) per owner ``0..n-1``."""
    if values.ndim == 1:
        return np.bincount(owner, weights=values, minlength=n)
    return np.stack(
        [np.bincount(owner, weights=values[:, j], minlength=n) for j in range(values.shape[1])],
        axis=1,
    )


def face_geometry(
    points: FloatArray, offsets: IntArray, vertices: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Area vectors, centroids and vertex averages of faces given as vertex loops.

    Parameters
    ----------
    points : (n_points, 3) float array
    offsets, vertices : int arrays
        The loops in CSR form (face ``f`` is ``vertices[offsets[f]:offsets[f + 1]]``).

    Returns
    -------
    area_vectors : (n_faces, 3) float array
        Area times unit right-hand normal (its norm is the face area).
    centroids : (n_faces, 3) float array
        Area centroids (the vertex average for a face of zero area).
    averages : (n_faces, 3) float array
        Vertex averages (the fan centres).
    """
    nf = len(offsets) - 1
    owner = loop_owner(offsets)
    sizes = np.diff(offsets).astype(float)
    X = points[vertices]
    c = _segment_sum(X, owner, nf) / np.maximum(sizes, 1)[:, None]
    a = X - c[owner]
    b = points[vertices[loop_next(offsets)]] - c[owner]
    tri = 0.5 * cross_rows(a, b)  # area vectors of the fan triangles
    A = _segment_sum(tri, owner, nf)
    norm = np.linalg.norm(A, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = np.where(norm[:, None] > 0, A / norm[:, None], 0.0)
    w = np.einsum("ij,ij->i", tri, n[owner])  # signed triangle areas in the face plane
    s = _segment_sum(w[:, None] * (a + b) / 3.0, owner, nf)
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where(norm[:, None] > 0, s / norm[:, None], 0.0)
    return A, c + shift, c


def cell_geometry(
    points: FloatArray,
    face_offsets: IntArray,
    face_vertices: IntArray,
    entry_cells: IntArray,
    entry_faces: IntArray,
    entry_signs: NDArray,
    n_cells: int,
    faces: tuple[FloatArray, FloatArray, FloatArray] | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Volumes and centroids of cells given by signed faces.

    Parameters
    ----------
    points : (n_points, 3) float array
    face_offsets, face_vertices : int arrays
        The faces' vertex loops (CSR).
    entry_cells, entry_faces, entry_signs : (m,) arrays
        The cell, face and sign (+1: the face's right-hand normal points out of the
        cell) of every (cell, face) incidence.
    n_cells : int
    faces : tuple, optional
        :func:`face_geometry` of the faces, if already known.

    Returns
    -------
    volumes : (n_cells,) float array
        Signed volumes (positive for correctly oriented closed cells).
    centroids : (n_cells, 3) float array
    """
    _a, _cent, c = (
        faces if faces is not None else face_geometry(points, face_offsets, face_vertices)
    )
    sign = np.asarray(entry_signs, dtype=float)
    count = np.bincount(entry_cells, minlength=n_cells).astype(float)
    xk = _segment_sum(c[entry_faces], entry_cells, n_cells) / np.maximum(count, 1)[:, None]
    # the fan triangles of every face of every cell: entries repeated by the face sizes
    sizes = np.diff(face_offsets)[entry_faces]
    e = np.repeat(np.arange(len(entry_faces)), sizes)
    start = np.repeat(face_offsets[entry_faces] - np.cumsum(sizes) + sizes, sizes)
    k = start + np.arange(int(sizes.sum()))  # entries of face_vertices, loop by loop
    nxt = loop_next(face_offsets)[k]
    f, cell = entry_faces[e], entry_cells[e]
    base = c[f] - xk[cell]
    p, q = points[face_vertices[k]] - xk[cell], points[face_vertices[nxt]] - xk[cell]
    vol = sign[e] * np.einsum("ij,ij->i", base, cross_rows(p - base, q - base)) / 6.0
    V = np.bincount(cell, weights=vol, minlength=n_cells).astype(np.float64)
    m = _segment_sum(vol[:, None] * (base + p + q) / 4.0, cell, n_cells)
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where(V[:, None] != 0, m / V[:, None], 0.0)
    return V, np.asarray(xk + shift, dtype=np.float64)


def group_max_distance(
    points: FloatArray, offsets: IntArray, ids: IntArray, max_pairs: int = 4_000_000
) -> FloatArray:
    """Largest distance between two points of every group (CSR ``offsets``, ``ids``).

    Groups of the same size are handled together (a loop over the distinct sizes and
    chunks, not over groups); 0 for groups of fewer than two points.
    """
    n = len(offsets) - 1
    sizes = np.diff(offsets)
    out = np.zeros(n)
    for s in _unique(sizes):
        if s < 2:
            continue
        g = np.flatnonzero(sizes == s)
        i, j = np.triu_indices(int(s), k=1)
        step = max(1, max_pairs // len(i))
        for lo in range(0, len(g), step):
            gg = g[lo : lo + step]
            X = points[ids[offsets[gg][:, None] + np.arange(s)]]
            out[gg] = np.sqrt(np.max(np.sum((X[:, i] - X[:, j]) ** 2, axis=-1), axis=1))
    return out


def face_planarity(
    points: FloatArray,
    offsets: IntArray,
    vertices: IntArray,
    faces: tuple[FloatArray, FloatArray, FloatArray] | None = None,
) -> FloatArray:
    """Largest distance of a face's vertices to its plane, over the face's diameter.

    The plane passes through the face's vertex average, normal to its area vector
    (Newell's normal, the best plane of a nearly planar loop). A face of zero area
    gets ``inf``.
    """
    A, _cent, c = faces if faces is not None else face_geometry(points, offsets, vertices)
    owner = loop_owner(offsets)
    norm = np.linalg.norm(A, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = A / norm[:, None]
    d = np.abs(np.einsum("ij,ij->i", points[vertices] - c[owner], n[owner]))
    dmax = np.zeros(len(offsets) - 1)
    np.maximum.at(dmax, owner, np.nan_to_num(d, nan=np.inf))
    diam = group_max_distance(points, offsets, vertices)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = dmax / diam
    return np.where(norm > 0, out, np.inf)
