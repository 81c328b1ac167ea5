"""Centroidal Voronoi polyhedra clipped to a box, with an exact cell count.

Algorithm
---------
1. Seeds: ``n`` points of the Halton sequence in bases 2, 3, 5 with a random shift
   modulo 1 (a Cranley-Patterson rotation, deterministic for a given ``seed``), scaled to
   the box: evenly spread from the start, so that a few Lloyd iterations suffice.
2. Clipping by mirrors: the seeds near each of the six sides are mirrored across it.
   Inside the box no mirror is closer than the seed it mirrors, so the Voronoi cell of a
   seed among seeds and mirrors is its cell clipped to the box, the sides cut by the
   bisectors of the seed and its mirrors. Only seeds within 1.5 cell sizes of a side
   are mirrored (3 before the first Lloyd iteration); if then a cell is unbounded or
   leaves the box, those within 3, and then all seeds.
3. The diagram is read off the Delaunay tetrahedra of seeds and mirrors
   (:class:`scipy.spatial.Delaunay`, Qhull): its vertices are the circumcentres of the
   Delaunay facets (one per facet of cospherical points, which Qhull cuts into
   tetrahedra), the face between two points the ring of circumcentres around their
   Delaunay edge. Faces are those between two seeds (stored once, oriented from the
   lower seed to the higher, sign +1 in the first cell and -1 in the second) or between
   a seed and its own mirror (a boundary face), numbered by their pair of seeds; faces
   between a seed and another seed's mirror have no area and are dropped. Every loop is
   ordered by the angle of its vertices around the vertex average, counter-clockwise
   about the normal. All of this is array work over all edges at once, which makes the
   mesher a small multiple of Qhull's own time (:class:`scipy.spatial.Voronoi` builds
   Python lists of every ridge, as long again as its Qhull call).
4. Lloyd iterations move every seed to the centroid of its cell
   (:func:`~vemwear.mesh.geometry3d.cell_geometry`).
5. Vertices closer than ``collapse_tol`` times the cell size are merged (the degenerate
   Voronoi vertices that mirroring makes on the sides come out as near-copies), those on
   sides snapped onto them, repeated vertices removed from the loops and faces left with
   fewer than three vertices dropped.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..util.arrays import isin as _isin
from ..util.arrays import unique as _unique
from .generate3d import tag_box
from .geometry3d import cell_geometry, cross_rows, loop_next, loop_owner, take_loops
from .polyhedra import Mesh3D
from .polymesh import MeshError

__all__ = ["box_voronoi", "halton"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def halton(n: int, dim: int = 3, seed: int | None = 0) -> FloatArray:
    """``n`` points of the Halton sequence in ``[0, 1)^dim``, randomly shifted modulo 1."""
    bases = [2, 3, 5, 7, 11, 13][:dim]
    i = np.arange(1, n + 1, dtype=np.int64)
    out = np.zeros((n, dim))
    for d, b in enumerate(bases):
        k, f = i.copy(), 1.0
        while np.any(k > 0):
            f /= b
            out[:, d] += f * (k % b)
            k //= b
    shift = np.random.default_rng(seed).random(dim) if seed is not None else np.zeros(dim)
    return np.asarray((out + shift) % 1.0)


#: The six edges of a tetrahedron, as pairs of its vertex slots.
_TET_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])


def _centres(
    allp: FloatArray, simplices: IntArray, neighbors: IntArray, equations: FloatArray
) -> tuple[FloatArray, IntArray]:
    """The Voronoi vertices: the circumcentres of the Delaunay facets, and the facet of
    every tetrahedron.

    Qhull triangulates a facet of five or more cospherical points (the mirrors make
    many) into neighbouring tetrahedra with the facet's hyperplane, some of them flat;
    the facet's vertex is the circumcentre of its largest tetrahedron. Facets are
    numbered in the order of their first tetrahedron.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nt = len(simplices)
    A = allp[simplices[:, 0]]
    u, v, w = (allp[simplices[:, j]] - A for j in (1, 2, 3))
    vw = cross_rows(v, w)
    det = np.einsum("ij,ij->i", u, vw)
    t, j = np.nonzero(neighbors > np.arange(nt)[:, None])  # each pair once
    nb = neighbors[t, j]
    same = np.all(equations[t] == equations[nb], axis=1)
    g = coo_matrix((np.ones(int(same.sum())), (t[same], nb[same])), shape=(nt, nt))
    _, facet = connected_components(g, directed=False)  # numbered by first tetrahedron
    facet = facet.astype(np.int64)
    order = np.lexsort((-np.abs(det), facet))  # per facet, the largest tetrahedron first
    first = np.ones(nt, dtype=bool)
    first[1:] = facet[order[1:]] != facet[order[:-1]]
    best = order[first]
    A, u, v, w, vw, det = A[best], u[best], v[best], w[best], vw[best], det[best]
    num = (
        np.einsum("ij,ij->i", u, u)[:, None] * vw
        + np.einsum("ij,ij->i", v, v)[:, None] * cross_rows(w, u)
        + np.einsum("ij,ij->i", w, w)[:, None] * cross_rows(u, v)
    )
    return np.asarray(A + num / (2.0 * det)[:, None]), facet


def _diagram(
    seeds: FloatArray, lo: FloatArray, hi: FloatArray, layer: float
) -> tuple[FloatArray, IntArray, IntArray, IntArray, IntArray, NDArray[np.int8]] | None:
    """Clipped Voronoi cells: points, face CSR and the (cell, face, sign) entries.

    The Voronoi diagram is read off the Delaunay tetrahedra of the seeds and mirrors:
    its vertices are their circumcentres, the face between seeds ``a < b`` is the ring
    of circumcentres of the tetrahedra around the Delaunay edge ``(a, b)``; faces are
    numbered by ``(a, b)``. None if a cell of a seed is unbounded (an edge on the
    convex hull) or leaves the box (too few mirrors).
    """
    from scipy.spatial import Delaunay

    n = len(seeds)
    pts, src = [seeds], [np.arange(n)]
    for d in range(3):
        for plane in (lo[d], hi[d]):
            near = np.flatnonzero(np.abs(seeds[:, d] - plane) < layer)
            m = seeds[near].copy()
            m[:, d] = 2 * plane - m[:, d]
            pts.append(m)
            src.append(near)
    allp, origin = np.vstack(pts), np.concatenate(src)
    N = len(allp)
    tri = Delaunay(allp, qhull_options="Qbb Qc Qz Q12")
    S = np.asarray(tri.simplices, dtype=np.int64)
    E = S[:, _TET_EDGES]  # (n_tets, 6, 2)
    a = np.minimum(E[..., 0], E[..., 1]).ravel()
    b = np.maximum(E[..., 0], E[..., 1]).ravel()
    inner = b < n
    sel = np.flatnonzero(inner | ((a < n) & (b >= n) & (origin[b] == a)))
    P, facet = _centres(allp, S, np.asarray(tri.neighbors), np.asarray(tri.equations))
    # the ring of an edge, each facet once (its tetrahedra share its one vertex): a
    # single sort of (edge, facet) keys, whose edges come out in order
    nP = len(P)
    key, vid = a[sel] * N + b[sel], facet[sel // 6]
    if float(N) * N * nP < 2.0**62:
        key, vid = np.divmod(_unique(key * nP + vid), nP)
    else:  # the combined key would overflow
        o = np.lexsort((vid, key))
        key, vid = key[o], vid[o]
        keep = np.ones(len(key), dtype=bool)
        keep[1:] = (key[1:] != key[:-1]) | (vid[1:] != vid[:-1])
        key, vid = key[keep], vid[keep]
    new = np.ones(len(key), dtype=bool)
    new[1:] = key[1:] != key[:-1]
    foff = np.append(np.flatnonzero(new), len(key)).astype(np.int64)
    fa, fb = np.divmod(key[new], N)
    H = np.asarray(tri.convex_hull, dtype=np.int64)
    hull = np.concatenate([np.sort(H[:, p], axis=1) for p in ([0, 1], [0, 2], [1, 2])])
    if np.any(_isin(key[new], hull[:, 0] * N + hull[:, 1])):
        return None
    tol = 1e-9 * float(np.max(hi - lo))
    used = _unique(vid)
    if np.any(P[used] < lo - tol) or np.any(P[used] > hi + tol):
        return None
    remap = np.full(len(P), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    P, fv = P[used], remap[vid]
    # order every loop counter-clockwise about the direction from seed a to seed b
    normal = allp[fb] - allp[fa]
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    axis = np.eye(3)[np.argmin(np.abs(normal), axis=1)]
    u = cross_rows(normal, axis)
    u /= np.linalg.norm(u, axis=1)[:, None]
    w = cross_rows(normal, u)
    owner = loop_owner(foff)
    tot = np.stack([np.bincount(owner, weights=P[fv, d], minlength=len(fa)) for d in range(3)], 1)
    avg = tot / np.diff(foff)[:, None]  # the vertex average of every loop
    r = P[fv] - avg[owner]
    angle = np.arctan2(np.einsum("ij,ij->i", r, w[owner]), np.einsum("ij,ij->i", r, u[owner]))
    fv = fv[np.lexsort((angle, owner))]
    inside = fb < n
    nf = len(fa)
    cells = np.concatenate([fa, fb[inside]])
    faces = np.concatenate([np.arange(nf), np.flatnonzero(inside)])
    signs = np.concatenate([np.ones(nf, np.int8), -np.ones(int(inside.sum()), np.int8)])
    order = np.argsort(cells, kind="stable")
    coff = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(cells, minlength=n), out=coff[1:])
    return P, foff, fv, coff, faces[order], signs[order]


def _clipped(seeds: FloatArray, lo: FloatArray, hi: FloatArray, h: float, first: bool = False):
    # wider layers of mirrors cost more Delaunay work; the seeds before Lloyd's first
    # step, less even, often need more than 1.5 h
    for layer in (3.0 * h,) if first else (1.5 * h, 3.0 * h):
        out = _diagram(seeds, lo, hi, layer)
        if out is not None:
            return out
    return _diagram(seeds, lo, hi, np.inf)


def _merge(
    P: FloatArray, foff: IntArray, fv: IntArray, lo: FloatArray, hi: FloatArray, tol: float
) -> tuple[FloatArray, IntArray, IntArray, NDArray[np.bool_]]:
    """Merge close vertices, snap to the sides; the faces kept (>= 3 vertices)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(P).query_pairs(tol, output_type="ndarray")
    n = len(P)
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    nc, comp = connected_components(g, directed=False)
    cnt = np.bincount(comp, minlength=nc).astype(float)
    Q = np.column_stack(
        [np.bincount(comp, weights=P[:, d], minlength=nc) for d in range(3)]
    ).astype(np.float64)
    Q /= cnt[:, None]
    snap = 1e-9 * float(np.max(hi - lo)) + tol
    for d in range(3):
        on_lo = np.zeros(nc, dtype=bool)
        on_hi = np.zeros(nc, dtype=bool)
        np.logical_or.at(on_lo, comp, np.abs(P[:, d] - lo[d]) <= snap)
        np.logical_or.at(on_hi, comp, np.abs(P[:, d] - hi[d]) <= snap)
        Q[on_lo, d], Q[on_hi, d] = lo[d], hi[d]
    fv = comp[fv]
    keep_entry = fv != fv[loop_next(foff)]
    owner = loop_owner(foff)
    sizes = np.bincount(owner[keep_entry], minlength=len(foff) - 1)
    fv = fv[keep_entry]
    kept = sizes >= 3
    off = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=off[1:])
    off, fv = take_loops(off, fv, np.flatnonzero(kept))
    used = _unique(fv)
    remap = np.full(nc, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return Q[used], off, remap[fv], kept


def box_voronoi(
    size: tuple[float, float, float] = (2.0, 1.0, 1.0),
    n_cells: int = 256,
    seed: int | None = 0,
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0),
    *,
    seeds: ArrayLike | None = None,
    lloyd_iterations: int = 4,
    collapse_tol: float = 1e-9,
) -> Mesh3D:
    """Centroidal Voronoi polyhedra of a box, exactly ``n_cells`` of them, sides tagged.

    Parameters
    ----------
    size : (float, float, float)
        Side lengths ``(lx, ly, lz)``.
    n_cells : int
        Number of cells.
    seed : int or None
        Seed of the random shift of the Halton points (None: no shift).
    origin : (float, float, float)
        The corner with the smallest coordinates.
    seeds : (n, 3) array, optional
        The seeds instead of Halton points (``n_cells`` and ``seed`` are ignored);
        distinct and strictly inside the box.
    lloyd_iterations : int
        Lloyd iterations (moving the seeds to their cells' centroids).
    collapse_tol : float
        Merge vertices closer than this times the cell size ``(|box| / n)^(1/3)``.

    Returns
    -------
    Mesh3D
        Cell ``k`` is the cell of seed ``k``; the six sides are the parts
        ``xmin`` ... ``zmax``.
    """
    if len(size) != 3 or len(origin) != 3:
        raise ValueError("size and origin need three entries each")
    lo = np.asarray(origin, dtype=float)
    ext = np.asarray(size, dtype=float)
    if not np.all(ext > 0):
        raise ValueError(f"size must be positive, got {list(size)}")
    hi = lo + ext
    if seeds is not None:
        X = np.asarray(seeds, dtype=float)
        if X.ndim != 2 or X.shape[1] != 3 or len(X) < 1:
            raise ValueError("seeds must be an (n, 3) array")
        if np.any(X <= lo) or np.any(X >= hi):
            raise ValueError("seeds must lie strictly inside the box")
    else:
        if int(n_cells) < 1:
            raise ValueError(f"n_cells must be >= 1, got {n_cells}")
        X = lo + ext * halton(int(n_cells), 3, seed)
        X = np.clip(X, lo + 1e-6 * ext, hi - 1e-6 * ext)
    if int(lloyd_iterations) < 0 or not collapse_tol >= 0:
        raise ValueError("lloyd_iterations and collapse_tol must be >= 0")
    n = len(X)
    if n < 2:  # Qhull needs points in general position: one cell is the box
        raise ValueError("box_voronoi needs at least 2 cells (one cell: use box_hexahedra)")
    h = float(np.prod(ext) / n) ** (1 / 3)
    for i in range(int(lloyd_iterations)):
        P, foff, fv, coff, cf, cs = _clipped(X, lo, hi, h, first=i == 0)
        ent = np.repeat(np.arange(n), np.diff(coff))
        _, X = cell_geometry(P, foff, fv, ent, cf, cs, n)
    P, foff, fv, coff, cf, cs = _clipped(X, lo, hi, h)
    P, foff, fv, kept = _merge(P, foff, fv, lo, hi, collapse_tol * h)
    new_id = np.cumsum(kept) - 1
    ent = np.repeat(np.arange(n), np.diff(coff))
    ok = kept[cf]
    coff = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(ent[ok], minlength=n), out=coff[1:])
    mesh = Mesh3D(P, foff, fv, coff, new_id[cf[ok]], cs[ok])
    if mesh.n_cells != n:  # pragma: no cover - every seed has a cell
        raise MeshError(f"box_voronoi made {mesh.n_cells} cells instead of {n}")
    return tag_box(mesh)
