"""Centroidal Voronoi meshes of polygonal domains.

The cells are the Voronoi regions of ``n`` seeds, intersected exactly with a
polygonal domain (convex or not), after Lloyd iterations that move every seed to
the centroid of its clipped region (a centroidal Voronoi tessellation, as in
PolyMesher, but with exact clipping instead of reflected seeds).

Algorithm
---------
1. Seeds: a hexagonal lattice (the centroidal Voronoi tessellation of the plane)
   with a random shift and a random jitter of half a spacing, its spacing chosen
   by bisection so that exactly ``n`` points fall inside the domain
   (deterministic for a given ``seed``). Lloyd iterations then only smooth the
   jitter and the layer along the boundary: a few iterations reach the quality
   that dozens reach from random points.
2. Voronoi regions come from a Delaunay triangulation of the seeds and eight far
   away auxiliary points (so every region of a seed is bounded): the region of
   seed ``p`` has the circumcentres of the triangles around ``p`` as vertices, in
   the angular order of the triangle fan.
3. A region whose circumscribed disk about its seed stays inside the domain is
   an interior cell and is used as is. Every other region is intersected with the
   domain by Sutherland-Hodgman clipping of the *domain polygon* against the
   half-planes ``{x : |x - p| <= |x - q|}`` of the region's Delaunay neighbours
   ``q``; this is exact for any simple domain polygon because the clip window (the
   region) is convex. All clipped regions are processed together, one half-plane
   per pass, with NumPy.
4. Every vertex carries a combinatorial key: the Delaunay triangle of a Voronoi
   vertex, the index of a domain corner, or the pair (Delaunay edge, domain side)
   of a point where a Voronoi edge crosses a domain side. Neighbouring cells hence
   share vertex ids exactly; coordinates are recomputed once per key (a crossing
   point is placed exactly on its domain side).
5. During the Lloyd iterations only the regions that meet the boundary are
   ordered and clipped; the centroid of every other region is summed from its
   Delaunay triangles (:func:`_interior_centroids`), so an iteration costs little
   more than the triangulation.
6. Vertices closer than ``collapse_tol`` times the average cell size are merged
   (priority: domain corner, then boundary point, then interior point, so the
   boundary is not moved), which removes tiny edges from clipping and from
   near-degenerate Voronoi vertices, without letting a cell drop below three
   vertices.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .checks import check_cells, check_conforming, check_vertices, crossing_sides
from .polymesh import Mesh, MeshError

__all__ = [
    "as_domain",
    "l_shape_domain",
    "point_in_domain",
    "rectangle_domain",
    "voronoi_from_seeds",
    "voronoi_mesh",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

# classes of mesh vertices used by the merging step
_INTERIOR, _SIDE, _CORNER = 0, 1, 2


# --------------------------------------------------------------------------- domains
def rectangle_domain(
    size: Sequence[float] = (2.0, 1.0), origin: Sequence[float] = (0.0, 0.0)
) -> FloatArray:
    """Counter-clockwise corners of the rectangle ``origin + [0, lx] x [0, ly]``.

    Parameters
    ----------
    size : (lx, ly)
        Side lengths, positive.
    origin : (x0, y0)
        Lower-left corner.

    Returns
    -------
    (4, 2) float array
    """
    lx, ly = (float(s) for s in size)
    if lx <= 0 or ly <= 0:
        raise ValueError(f"size must be positive, got {tuple(size)}")
    x0, y0 = (float(o) for o in origin)
    return np.array([[x0, y0], [x0 + lx, y0], [x0 + lx, y0 + ly], [x0, y0 + ly]])


def l_shape_domain(
    size: Sequence[float] = (2.0, 2.0),
    notch: Sequence[float] = (1.0, 1.0),
    origin: Sequence[float] = (0.0, 0.0),
) -> FloatArray:
    """Counter-clockwise corners of an L-shaped domain.

    The domain is the rectangle ``origin + [0, lx] x [0, ly]`` without its
    upper-right part ``[lx - nx, lx] x [ly - ny, ly]``; the re-entrant corner is
    ``origin + (lx - nx, ly - ny)``.

    Parameters
    ----------
    size : (lx, ly)
        Bounding box of the L.
    notch : (nx, ny)
        Size of the removed upper-right rectangle, ``0 < nx < lx``, ``0 < ny < ly``.
    origin : (x0, y0)
        Lower-left corner.

    Returns
    -------
    (6, 2) float array
    """
    lx, ly = (float(s) for s in size)
    nx, ny = (float(s) for s in notch)
    if not (0 < nx < lx and 0 < ny < ly):
        raise ValueError(f"notch {tuple(notch)} must be smaller than size {tuple(size)}")
    x0, y0 = (float(o) for o in origin)
    pts = np.array(
        [[0, 0], [lx, 0], [lx, ly - ny], [lx - nx, ly - ny], [lx - nx, ly], [0, ly]], dtype=float
    )
    return pts + np.array([x0, y0])


def _polygon_area(p: FloatArray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def as_domain(domain: ArrayLike) -> FloatArray:
    """Validate a domain polygon and return it as a ``(k, 2)`` float array.

    Parameters
    ----------
    domain : (k, 2) array_like
        Corners of a simple polygon, counter-clockwise, without repetition of the
        first corner at the end.

    Raises
    ------
    ValueError
        If the polygon has fewer than three corners, repeated or non-finite
        corners, crossing sides, or is clockwise.
    """
    d = np.array(domain, dtype=float)
    if d.ndim != 2 or d.shape[1] != 2 or len(d) < 3:
        raise ValueError(f"domain must be a (k, 2) array with k >= 3, got shape {d.shape}")
    if not np.all(np.isfinite(d)):
        raise ValueError("domain corners must be finite")
    if len(d) > 3 and np.allclose(d[0], d[-1]):
        raise ValueError("do not repeat the first domain corner at the end")
    scale = float(np.max(np.ptp(d, axis=0)))
    nxt = np.roll(d, -1, axis=0)
    if np.any(np.linalg.norm(nxt - d, axis=1) <= 1e-12 * scale):
        raise ValueError("domain has repeated consecutive corners")
    hit, i, j = crossing_sides(d[None], eps=0.0)
    if np.any(hit):
        a, b = i[hit[0]][0], j[hit[0]][0]
        raise ValueError(f"domain sides {a} and {b} cross; use a simple polygon")
    if _polygon_area(d) <= 0:
        raise ValueError("domain corners must be listed counter-clockwise (positive area)")
    return d


def point_in_domain(points: ArrayLike, domain: ArrayLike) -> NDArray[np.bool_]:
    """Even-odd test: which points lie inside the polygon ``domain``.

    Points on the boundary may be reported either way.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    dom = np.asarray(domain, dtype=float)
    a, b = dom, np.roll(dom, -1, axis=0)
    out = np.zeros(len(pts), dtype=bool)
    chunk = max(1, 2_000_000 // len(dom))
    for s in range(0, len(pts), chunk):
        x = pts[s : s + chunk, 0:1]
        y = pts[s : s + chunk, 1:2]
        straddle = (a[None, :, 1] > y) != (b[None, :, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (
                b[None, :, 1] - a[None, :, 1]
            )
        out[s : s + chunk] = (np.sum(straddle & (x < xc), axis=1) % 2) == 1
    return out


def _nearest_sides(points: FloatArray, dom: FloatArray) -> tuple[IntArray, FloatArray, FloatArray]:
    """The side of the polygon nearest to every point (the first of equally near ones),
    the parameter in [0, 1] of the nearest point on it, and the distance."""
    a, b = dom, np.roll(dom, -1, axis=0)
    ab = b - a
    L2 = np.sum(ab * ab, axis=1)
    side = np.zeros(len(points), dtype=np.int64)
    par = np.zeros(len(points))
    dist = np.full(len(points), np.inf)
    chunk = max(1, 2_000_000 // len(dom))
    for s in range(0, len(points), chunk):
        p = points[s : s + chunk, None, :]
        t = np.clip(np.sum((p - a) * ab, axis=2) / L2, 0.0, 1.0)
        d = p - (a + t[..., None] * ab)
        dd = np.sqrt(np.sum(d * d, axis=2))
        k = np.argmin(dd, axis=1)
        rows = np.arange(len(k))
        side[s : s + chunk], par[s : s + chunk], dist[s : s + chunk] = k, t[rows, k], dd[rows, k]
    return side, par, dist


# --------------------------------------------------------------------------- Voronoi fans
@dataclass
class _Fans:
    """Voronoi regions of the seeds as Delaunay triangle fans (CSR by seed)."""

    pts: FloatArray  # seeds followed by the auxiliary far points
    centres: FloatArray  # circumcentre of every Delaunay triangle
    offsets: IntArray  # fan of seed i: tri[offsets[i]:offsets[i+1]], counter-clockwise
    tri: IntArray
    simplices: IntArray  # Delaunay triangles (T, 3)
    seed_of: IntArray  # seed of every fan position

    def neighbours(self, pos: IntArray) -> IntArray:
        """Seed across the Voronoi edge from fan position ``pos`` to the next one."""
        v = self.seed_of[pos]
        nxt = pos + 1
        wrap = nxt == self.offsets[v + 1]
        nxt[wrap] = self.offsets[v[wrap]]
        A, B = self.simplices[self.tri[pos]], self.simplices[self.tri[nxt]]
        common = np.any(A[:, :, None] == B[:, None, :], axis=2) & (A != v[:, None])
        if not np.all(np.sum(common, axis=1) == 1):
            raise MeshError("inconsistent Delaunay fans (degenerate seeds)")
        return A[np.arange(len(A)), np.argmax(common, axis=1)]


def _circumcentres(P: FloatArray) -> FloatArray:
    a = P[:, 0]
    b = P[:, 1] - a
    c = P[:, 2] - a
    bb = np.sum(b * b, axis=1)
    cc = np.sum(c * c, axis=1)
    D = 2.0 * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
    ux = (c[:, 1] * bb - b[:, 1] * cc) / D
    uy = (b[:, 0] * cc - c[:, 0] * bb) / D
    return a + np.column_stack([ux, uy])


@dataclass
class _Triangulation:
    """Delaunay triangulation of the seeds and eight far auxiliary points."""

    pts: FloatArray  # seeds followed by the auxiliary far points
    simplices: IntArray  # (T, 3), counter-clockwise
    centres: FloatArray  # (T, 2) circumcentres
    n: int  # number of seeds


def _triangulate(seeds: FloatArray, centre: FloatArray, radius: float) -> _Triangulation:
    from scipy.spatial import Delaunay

    ang = np.arange(8) * (np.pi / 4)
    far = centre + radius * np.column_stack([np.cos(ang), np.sin(ang)])
    pts = np.vstack([seeds, far])
    tri = Delaunay(pts)
    if len(tri.coplanar):
        bad = np.unique(tri.coplanar[:, 0])
        raise MeshError(f"seeds {bad[:10].tolist()} coincide with other seeds")
    S = tri.simplices.astype(np.int64)
    P = pts[S]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    S[cw] = S[cw][:, ::-1]
    return _Triangulation(pts, S, _circumcentres(pts[S]), len(seeds))


def _fans(tr: _Triangulation, only: NDArray[np.bool_] | None = None) -> _Fans:
    """Fans of all seeds, or of the seeds in ``only`` (the others get empty fans)."""
    n, S, pts = tr.n, tr.simplices, tr.pts
    v = S.ravel()
    t = np.repeat(np.arange(len(S)), 3)
    keep = v < n
    if only is not None:
        keep[keep] = only[v[keep]]
    v, t = v[keep], t[keep]
    g = pts[S[t]].mean(axis=1) - pts[v]
    order = np.lexsort((np.arctan2(g[:, 1], g[:, 0]), v))
    v, t = v[order], t[order]
    counts = np.bincount(v, minlength=n)
    if np.any(counts[only] < 3 if only is not None else counts < 3):
        raise MeshError("a seed has fewer than three Delaunay triangles (degenerate seeds)")
    offsets = np.concatenate([[0], np.cumsum(counts)])
    return _Fans(pts, tr.centres, offsets, t, S, v)


def _interior_centroids(tr: _Triangulation) -> FloatArray:
    """Centroids of the unclipped Voronoi regions, without ordering the fans.

    The region of seed ``a`` is the union over its Delaunay triangles ``abc`` of the
    quadrilaterals ``a, m_ab, C, m_ca`` (C the circumcentre, m the edge midpoints),
    with signed areas when C lies outside the triangle.
    """
    n, S, pts, C = tr.n, tr.simplices, tr.pts, tr.centres
    P = pts[S]
    area = np.zeros(n)
    mom = np.zeros((n, 2))
    for k in range(3):
        a, b, c = P[:, k], P[:, (k + 1) % 3], P[:, (k + 2) % 3]
        u1, u2, u3 = 0.5 * (b - a), C - a, 0.5 * (c - a)
        c12 = u1[:, 0] * u2[:, 1] - u1[:, 1] * u2[:, 0]
        c23 = u2[:, 0] * u3[:, 1] - u2[:, 1] * u3[:, 0]
        mx = c12 * (u1[:, 0] + u2[:, 0]) + c23 * (u2[:, 0] + u3[:, 0])
        my = c12 * (u1[:, 1] + u2[:, 1]) + c23 * (u2[:, 1] + u3[:, 1])
        v = S[:, k]
        sel = v < n
        v = v[sel]
        area += np.bincount(v, weights=(c12 + c23)[sel], minlength=n)
        mom[:, 0] += np.bincount(v, weights=mx[sel], minlength=n)
        mom[:, 1] += np.bincount(v, weights=my[sel], minlength=n)
    with np.errstate(divide="ignore", invalid="ignore"):
        return pts[:n] + mom / (3.0 * area[:, None])


# --------------------------------------------------------------------------- clipping
@dataclass
class _Clipped:
    offsets: IntArray
    xy: FloatArray
    key: IntArray
    bridge: NDArray[np.bool_]  # per polygon: the intersection has several components


def _clip(fans: _Fans, cells: IntArray, dom: FloatArray) -> _Clipped:
    """Intersect the Voronoi regions ``cells`` with the domain polygon (vectorized).

    The domain polygon is clipped, for all regions at once, by the half-plane of
    the k-th Voronoi edge of each region (pass k). Vertex keys:
    ``t`` (Delaunay triangle, a Voronoi vertex), ``T + j`` (domain corner j),
    ``T + k + pair * k + s`` (Voronoi edge ``pair`` crossing domain side ``s``),
    negative for a (rare, normally clipped away) crossing of two non-adjacent
    Voronoi edge lines.
    """
    m, k = len(cells), len(dom)
    T = len(fans.centres)
    Np = len(fans.pts)
    seeds = fans.pts[cells]
    f0 = fans.offsets[cells]
    nf = fans.offsets[cells + 1] - f0
    xy = np.tile(dom, (m, 1))
    key = np.tile(T + np.arange(k, dtype=np.int64), m)
    sup = np.tile(-(np.arange(k, dtype=np.int64) + 1), m)  # edge support: -(side+1) or pass index
    off = np.arange(m + 1, dtype=np.int64) * k
    base = np.concatenate([[0], np.cumsum(nf)[:-1]])
    nb = fans.neighbours(_segments(f0, nf))  # neighbour across each Voronoi edge
    junk = 0
    for step in range(int(nf.max())):
        active = nf > step
        q = nb[base + np.minimum(step, nf - 1)]
        qq = fans.pts[q]
        w = qq - seeds
        mid = 0.5 * (seeds + qq)
        pair = np.minimum(cells, q) * Np + np.maximum(cells, q)
        lens = np.diff(off)
        gp = np.repeat(np.arange(m), lens)
        N = len(xy)
        # inside: closer to the seed than to q; bitwise antisymmetric in (seed, q)
        d = -((xy[:, 0] - mid[gp, 0]) * w[gp, 0] + (xy[:, 1] - mid[gp, 1]) * w[gp, 1])
        d[~active[gp]] = 1.0
        inside = d >= 0
        nx = np.arange(1, N + 1)
        nx[off[1:] - 1] = off[:-1]
        cross = inside != inside[nx]
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = np.where(cross, d / (d - d[nx]), 0.0)
        ixy = xy + tt[:, None] * (xy[nx] - xy)
        ikey = np.zeros(N, dtype=np.int64)
        side = sup < 0
        ikey[side] = T + k + pair[gp[side]] * k + (-sup[side] - 1)
        nfg = nf[gp]
        ridge = ~side
        prev = ridge & (sup == (step - 1) % nfg)
        nxtr = ridge & (sup == (step + 1) % nfg)
        ikey[prev] = fans.tri[(f0 + np.minimum(step, nf - 1))[gp[prev]]]
        ikey[nxtr] = fans.tri[(f0 + (step + 1) % nf)[gp[nxtr]]]
        other = np.flatnonzero(ridge & ~prev & ~nxtr & cross)
        ikey[other] = -(junk + 1 + np.arange(len(other)))
        junk += len(other)
        isup = np.where(inside, step, sup)
        emit = np.column_stack([inside, cross]).ravel()
        xy = np.stack([xy, ixy], axis=1).reshape(-1, 2)[emit]
        key = np.column_stack([key, ikey]).ravel()[emit]
        sup = np.column_stack([sup, isup]).ravel()[emit]
        cnt = np.bincount(gp, weights=inside.astype(float) + cross, minlength=m).astype(np.int64)
        off = np.concatenate([[0], np.cumsum(cnt)])
    scale = float(np.max(np.ptp(dom, axis=0)) + np.max(np.abs(dom)))
    off, xy, key, sup = _remove_spikes(off, xy, key, sup, scale)
    lens = np.diff(off)
    if np.any(lens < 3):
        bad = cells[lens < 3]
        raise MeshError(f"Voronoi regions of seeds {bad[:10].tolist()} do not meet the domain")
    # an edge on a Voronoi line running against the region orientation is a zero-width
    # bridge between two components of (region intersected with a non-convex domain)
    gp = np.repeat(np.arange(m), lens)
    nx = np.arange(1, len(xy) + 1)
    nx[off[1:] - 1] = off[:-1]
    e = xy[nx] - xy
    ridge = sup >= 0
    w = fans.pts[nb[base[gp] + np.where(ridge, sup, 0)]] - seeds[gp]
    along = w[:, 1] * e[:, 0] - w[:, 0] * e[:, 1]  # (left normal of e) . w, < 0 on a true edge
    elen = np.linalg.norm(e, axis=1)
    wlen = np.linalg.norm(w, axis=1)
    bad_edge = ridge & (along > 1e-9 * elen * wlen)
    bridge = np.bincount(gp[bad_edge], minlength=m) > 0
    return _Clipped(off, xy, key, bridge)


def _remove_spikes(
    off: IntArray, xy: FloatArray, key: IntArray, sup: IntArray, scale: float
) -> tuple[IntArray, FloatArray, IntArray, IntArray]:
    """Remove repeated vertices and tips of zero-width spikes from clipped polygons.

    Clipping a non-convex polygon leaves degenerate "bridges" along the clip
    lines; those whose far end is clipped away later become spikes (a vertex where
    the boundary turns back on itself), which are removed here until none is left.
    """
    for _ in range(64):
        m = len(off) - 1
        lens = np.diff(off)
        gp = np.repeat(np.arange(m), lens)
        N = len(xy)
        nx = np.arange(1, N + 1)
        nx[off[1:] - 1] = off[:-1]
        pv = np.arange(-1, N - 1)
        pv[off[:-1]] = off[1:] - 1
        e1 = xy - xy[pv]
        e2 = xy[nx] - xy
        l1 = np.hypot(e1[:, 0], e1[:, 1])
        l2 = np.hypot(e2[:, 0], e2[:, 1])
        cr = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
        dot = np.sum(e1 * e2, axis=1)
        dup = l2 <= 1e-12 * scale
        tip = (np.abs(cr) <= 1e-8 * l1 * l2) & (dot < 0)
        drop = dup | tip
        # never reduce a polygon below a triangle: there, drop duplicates only, or nothing
        few = (lens - np.bincount(gp[drop], minlength=m)) < 3
        drop = np.where(few[gp], dup, drop)
        few = (lens - np.bincount(gp[drop], minlength=m)) < 3
        drop &= ~few[gp]
        if not np.any(drop):
            break
        keep = ~drop
        cnt = np.bincount(gp[keep], minlength=m)
        off = np.concatenate([[0], np.cumsum(cnt)])
        xy, key, sup = xy[keep], key[keep], sup[keep]
    return off, xy, key, sup


def _area_centroid(off: IntArray, xy: FloatArray) -> tuple[FloatArray, FloatArray]:
    m = len(off) - 1
    gp = np.repeat(np.arange(m), np.diff(off))
    nx = np.arange(1, len(xy) + 1)
    nx[off[1:] - 1] = off[:-1]
    # shift by the first vertex of each polygon to limit cancellation
    ref = xy[off[:-1]][gp]
    a, b = xy - ref, xy[nx] - ref
    cr = a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]
    area = 0.5 * np.bincount(gp, weights=cr, minlength=m)
    cx = np.bincount(gp, weights=(a[:, 0] + b[:, 0]) * cr, minlength=m)
    cy = np.bincount(gp, weights=(a[:, 1] + b[:, 1]) * cr, minlength=m)
    with np.errstate(divide="ignore", invalid="ignore"):
        cen = np.column_stack([cx, cy]) / (6.0 * area[:, None])
    return area, cen + xy[off[:-1]]


@dataclass
class _Diagram:
    tri: _Triangulation
    fans: _Fans
    boundary: NDArray[np.bool_]  # per seed: region clipped by the domain
    clipped: _Clipped  # polygons of the boundary cells (in order of np.flatnonzero(boundary))


def _diagram(
    seeds: FloatArray, dom: FloatArray, dist: FloatArray | None = None, full: bool = True
) -> _Diagram:
    """The clipped Voronoi diagram; with ``full=False`` (Lloyd iterations) only the
    regions that meet the domain boundary get ordered fans."""
    lo, hi = dom.min(axis=0), dom.max(axis=0)
    diam = float(np.linalg.norm(hi - lo))
    tr = _triangulate(seeds, 0.5 * (lo + hi), 4.0 * diam)
    if dist is None:
        dist = _nearest_sides(seeds, dom)[2]
    # the circumscribed disk about a seed of its region: every Voronoi vertex of the
    # region is a circumcentre at the circumradius of its triangle from the seed
    radius = np.linalg.norm(tr.centres - tr.pts[tr.simplices[:, 0]], axis=1)
    R = np.zeros(tr.n)
    for k in range(3):
        v = tr.simplices[:, k]
        sel = v < tr.n
        np.maximum.at(R, v[sel], radius[sel])
    boundary = R >= dist - 1e-12 * diam
    fans = _fans(tr, None if full else boundary)
    clipped = _clip(fans, np.flatnonzero(boundary), dom)
    return _Diagram(tr, fans, boundary, clipped)


def _centroids(dg: _Diagram) -> FloatArray:
    """Centroids of the cells of the diagram (of the clipped polygon for boundary cells)."""
    cen = _interior_centroids(dg.tri)
    cen[dg.boundary] = _area_centroid(dg.clipped.offsets, dg.clipped.xy)[1]
    return cen


# --------------------------------------------------------------------------- assembly
def _segments(starts: IntArray, lens: IntArray) -> IntArray:
    """Concatenation of ``arange(starts[i], starts[i] + lens[i])`` over ``i``."""
    lens = np.asarray(lens, dtype=np.int64)
    excl = np.concatenate([[0], np.cumsum(lens)[:-1]])
    return np.repeat(np.asarray(starts, dtype=np.int64) - excl, lens) + np.arange(lens.sum())


def _assemble(
    dg: _Diagram, dom: FloatArray, collapse: float
) -> tuple[FloatArray, IntArray, IntArray]:
    """Global vertex ids from the keys, canonical coordinates, then merging."""
    fans, cl = dg.fans, dg.clipped
    T, k, Np = len(fans.centres), len(dom), len(fans.pts)
    lens = np.diff(fans.offsets).copy()
    bids = np.flatnonzero(dg.boundary)
    lens[bids] = np.diff(cl.offsets)
    off = np.concatenate([[0], np.cumsum(lens)])
    keys = np.empty(off[-1], dtype=np.int64)
    xy = np.empty((off[-1], 2))
    inner = np.flatnonzero(~dg.boundary)
    li = np.diff(fans.offsets)[inner]
    src = _segments(fans.offsets[inner], li)
    dst = _segments(off[inner], li)
    keys[dst] = fans.tri[src]
    xy[dst] = fans.centres[fans.tri[src]]
    dst = _segments(off[bids], np.diff(cl.offsets))
    keys[dst] = cl.key
    xy[dst] = cl.xy
    ukeys, first, inv = np.unique(keys, return_index=True, return_inverse=True)
    P = xy[first].copy()
    cls = np.zeros(len(ukeys), dtype=np.int8)
    tag = np.full(len(ukeys), -1, dtype=np.int64)  # corner id or side id
    vv = (ukeys >= 0) & (ukeys < T)
    P[vv] = fans.centres[ukeys[vv]]
    corner = (ukeys >= T) & (ukeys < T + k)
    P[corner] = dom[ukeys[corner] - T]
    cls[corner] = _CORNER
    tag[corner] = ukeys[corner] - T
    crs = ukeys >= T + k
    c = ukeys[crs] - T - k
    pair, s = c // k, c % k
    a, b = fans.pts[pair // Np], fans.pts[pair % Np]
    A, B = dom[s], dom[(s + 1) % k]
    w, mid = b - a, 0.5 * (a + b)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.sum((mid - A) * w, axis=1) / np.sum((B - A) * w, axis=1)
    t = np.clip(np.nan_to_num(t, nan=0.5), 0.0, 1.0)
    P[crs] = A + t[:, None] * (B - A)
    cls[crs] = _SIDE
    tag[crs] = s
    return _merge(P, cls, tag, inv.astype(np.int64), off, dom, collapse)


def _merge(
    P: FloatArray,
    cls: NDArray[np.int8],
    tag: IntArray,
    cv: IntArray,
    off: IntArray,
    dom: FloatArray,
    tol: float,
) -> tuple[FloatArray, IntArray, IntArray]:
    """Merge vertices closer than ``tol``; boundary points win, cells keep >= 3 vertices."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    k = len(dom)
    nP = len(P)
    frozen = np.zeros(nP, dtype=bool)
    scale = float(np.max(np.ptp(dom, axis=0)))
    tiny = 1e-12 * scale
    all_pairs = cKDTree(P).query_pairs(max(tol, tiny), output_type="ndarray")
    if len(all_pairs):
        dd = np.linalg.norm(P[all_pairs[:, 0]] - P[all_pairs[:, 1]], axis=1)
    else:
        dd = np.zeros(0)
    for _attempt in range(4):
        pairs = all_pairs[(dd <= tiny) | ~(frozen[all_pairs[:, 0]] | frozen[all_pairs[:, 1]])]
        i, j = pairs[:, 0], pairs[:, 1]
        ci, cj, ti, tj = cls[i], cls[j], tag[i], tag[j]
        ok = np.ones(len(pairs), dtype=bool)
        ok &= ~((ci == _SIDE) & (cj == _SIDE) & (ti != tj))
        ok &= ~((ci == _CORNER) & (cj == _CORNER))
        for cc_, sc_, tc_, ts_ in ((ci, cj, ti, tj), (cj, ci, tj, ti)):
            bad = (cc_ == _CORNER) & (sc_ == _SIDE) & (ts_ != tc_) & (ts_ != (tc_ - 1) % k)
            ok &= ~bad
        i, j = i[ok], j[ok]
        G = coo_matrix((np.ones(len(i)), (i, j)), shape=(nP, nP))
        ncomp, lab = connected_components(G, directed=False)
        # validity of each component: one corner at most, sides compatible
        n_corner = np.bincount(lab, weights=cls == _CORNER, minlength=ncomp)
        corner_of = np.full(ncomp, -1, dtype=np.int64)
        isc = cls == _CORNER
        corner_of[lab[isc]] = tag[isc]
        iss = cls == _SIDE
        side_lab, side_tag = lab[iss], tag[iss]
        side_min = np.full(ncomp, np.iinfo(np.int64).max)
        side_max = np.full(ncomp, -1)
        np.minimum.at(side_min, side_lab, side_tag)
        np.maximum.at(side_max, side_lab, side_tag)
        co = corner_of[side_lab]
        compat = np.where(co >= 0, (side_tag == co) | (side_tag == (co - 1) % k), True)
        invalid = n_corner > 1
        invalid |= (corner_of < 0) & (side_max >= 0) & (side_min != side_max)
        invalid[side_lab[~compat]] = True
        # representative: highest class, then lowest id
        order = np.lexsort((np.arange(nP), -cls.astype(np.int64), lab))
        first = np.ones(nP, dtype=bool)
        first[1:] = lab[order[1:]] != lab[order[:-1]]
        rep_of_comp = np.empty(ncomp, dtype=np.int64)
        rep_of_comp[lab[order[first]]] = order[first]
        rep = rep_of_comp[lab]
        rep[invalid[lab]] = np.arange(nP)[invalid[lab]]
        new = rep[cv]
        m = len(off) - 1
        gp = np.repeat(np.arange(m), np.diff(off))
        nx = np.arange(1, len(new) + 1)
        nx[off[1:] - 1] = off[:-1]
        keep = new != new[nx]
        cnt = np.bincount(gp[keep], minlength=m)
        noff = np.concatenate([[0], np.cumsum(cnt)])
        ncv = new[keep]
        bad = cnt < 3
        # a vertex listed twice in a cell after merging
        srt = np.lexsort((ncv, gp[keep]))
        dup = (ncv[srt][1:] == ncv[srt][:-1]) & (gp[keep][srt][1:] == gp[keep][srt][:-1])
        bad[gp[keep][srt][1:][dup]] = True
        moved = np.bincount(gp, weights=rep[cv] != cv, minlength=m) > 0
        check = np.flatnonzero(moved & ~bad)
        if len(check):
            bad[check[_invalid_polygons(P, noff, ncv, check)]] = True
        if not np.any(bad):
            used, newid = np.unique(ncv, return_inverse=True)
            return P[used], noff, newid.astype(np.int64)
        bc = np.flatnonzero(bad)
        idx = np.concatenate([np.arange(off[c], off[c + 1]) for c in bc])
        frozen[cv[idx]] = True
    raise MeshError("could not merge close vertices without degenerating cells")


def _invalid_polygons(
    points: FloatArray, off: IntArray, cv: IntArray, cells: IntArray
) -> NDArray[np.bool_]:
    """Which of ``cells`` are not simple counter-clockwise polygons (area <= 0 or crossing)."""
    lens = off[cells + 1] - off[cells]
    out = np.zeros(len(cells), dtype=bool)
    for n in np.unique(lens):
        sel = np.flatnonzero(lens == n)
        idx = off[cells[sel]][:, None] + np.arange(n)
        X = points[cv[idx]]
        B = np.roll(X, -1, axis=1)
        area = 0.5 * np.sum(X[..., 0] * B[..., 1] - B[..., 0] * X[..., 1], axis=1)
        out[sel] = (area <= 0) | np.any(crossing_sides(X, eps=1e-9)[0], axis=1)
    return out


def _snap_boundary(points: FloatArray, mesh: Mesh, dom: FloatArray) -> FloatArray:
    """Project vertices of boundary edges exactly onto the nearest domain side."""
    v = np.unique(mesh.boundary_edges)
    s, tt, _dist = _nearest_sides(points[v], dom)
    a, b = dom, np.roll(dom, -1, axis=0)
    best = a[s] + tt[:, None] * (b - a)[s]
    best = np.where((tt == 0.0)[:, None], a[s], best)
    best = np.where((tt == 1.0)[:, None], b[s], best)
    # points at a corner up to rounding become the corner exactly
    dc = np.linalg.norm(best[:, None, :] - dom[None], axis=2)
    c = np.argmin(dc, axis=1)
    near = dc[np.arange(len(v)), c] <= 1e-10 * float(np.max(np.ptp(dom, axis=0)))
    best[near] = dom[c[near]]
    out = points.copy()
    out[v] = best
    return out


def _build(dg: _Diagram, dom: FloatArray, collapse: float, validate: bool) -> Mesh:
    P, off, cv = _assemble(dg, dom, collapse)
    mesh = Mesh(P, off, cv)
    mesh = Mesh(_snap_boundary(P, mesh, dom), off, cv)
    if validate:
        check_vertices(mesh)
        check_cells(mesh)
        check_conforming(mesh)
    return mesh


# --------------------------------------------------------------------------- public API
def _initial_seeds(dom: FloatArray, n: int, rng: np.random.Generator) -> FloatArray:
    """``n`` points in the domain: a randomly shifted and jittered hexagonal lattice.

    The hexagonal lattice is the centroidal Voronoi tessellation of the plane, so
    Lloyd iterations start close to their limit and only have to smooth the jitter
    and the layer along the boundary. The spacing is found by bisection so that
    exactly ``n`` lattice points fall inside (the jitter of a lattice point is fixed,
    in units of the spacing, before the bisection); when no spacing gives exactly
    ``n``, the surplus of the nearest larger count is removed at random points.
    """
    lo, hi = dom.min(axis=0), dom.max(axis=0)
    area = _polygon_area(dom)
    a0 = float(np.sqrt(2.0 * area / (np.sqrt(3.0) * n)))
    a_min = 0.5 * a0
    ni = int(np.ceil((hi[0] - lo[0]) / a_min)) + 3
    nj = int(np.ceil((hi[1] - lo[1]) / (a_min * np.sqrt(3.0) / 2))) + 3
    j, i = np.divmod(np.arange(ni * nj, dtype=np.int64), ni)
    unit = np.column_stack([i + 0.5 * (j % 2), j * (np.sqrt(3.0) / 2)]) - 1.0
    unit += rng.random(2) + _JITTER * (rng.random((len(unit), 2)) - 0.5)

    box = len(dom) == 4 and np.all(np.isin(dom, (lo, hi)).reshape(4, 2), axis=None)

    def inside(a: float) -> NDArray[np.bool_]:
        x = lo + a * unit
        ok = np.all((x > lo) & (x < hi), axis=1)
        if not box:
            ok[ok] = point_in_domain(x[ok], dom)
        return ok

    lo_a, hi_a = a_min, 2.0 * a0  # many points at lo_a, few at hi_a
    best = inside(lo_a)
    if best.sum() < n:  # pragma: no cover - the lattice covers the box at half the spacing
        raise MeshError(f"could not place {n} initial seeds in the domain")
    for _ in range(48):
        a = 0.5 * (lo_a + hi_a)
        ok = inside(a)
        k = int(ok.sum())
        if k >= n:
            lo_a, best = a, ok
            if k == n:
                break
        else:
            hi_a = a
    pts = lo_a * unit[best]
    pts += lo
    if len(pts) > n:
        pts = pts[np.sort(rng.choice(len(pts), size=n, replace=False))]
    return pts[_morton_order(pts)]


#: Jitter of the initial lattice points, uniform in a square of this many spacings.
_JITTER = 0.5


def _morton_order(p: FloatArray, bits: int = 16) -> IntArray:
    """Z-order of points (spatial locality speeds up the Delaunay triangulation)."""
    lo = p.min(axis=0)
    ext = max(float(np.max(p.max(axis=0) - lo)), np.finfo(float).tiny)
    q = ((p - lo) / ext * (2**bits - 1)).astype(np.int64)
    code = np.zeros(len(p), dtype=np.int64)
    for b in range(bits):
        code |= ((q[:, 0] >> b) & 1) << (2 * b) | ((q[:, 1] >> b) & 1) << (2 * b + 1)
    return np.argsort(code, kind="stable")


def voronoi_from_seeds(
    domain: ArrayLike,
    seeds: ArrayLike,
    *,
    collapse_tol: float = 0.05,
    validate: bool = True,
) -> Mesh:
    """Mesh of the Voronoi regions of given seeds, clipped to a polygonal domain.

    Parameters
    ----------
    domain : (k, 2) array_like
        Counter-clockwise corners of a simple polygon (see :func:`as_domain`).
    seeds : (n, 2) array_like
        Distinct points inside the domain or on its boundary; cell ``i`` is the
        region of ``seeds[i]``.
    collapse_tol : float
        Vertices closer than ``collapse_tol * sqrt(|domain| / n)`` are merged.
    validate : bool
        Run :func:`~vemwear.mesh.checks.check_cells`, ``check_vertices`` and
        ``check_conforming`` on the result.

    Returns
    -------
    Mesh
        ``n`` counter-clockwise cells, boundary untagged.

    Raises
    ------
    MeshError
        If a region intersected with a non-convex domain has several components
        (move the seeds, e.g. by Lloyd iterations) or the seeds are degenerate.
    """
    dom = as_domain(domain)
    s = np.array(seeds, dtype=float)
    if s.ndim != 2 or s.shape[1] != 2 or len(s) < 1:
        raise ValueError(f"seeds must be an (n, 2) array, got shape {s.shape}")
    dist = _nearest_sides(s, dom)[2]
    scale = float(np.max(np.ptp(dom, axis=0)))
    out = ~point_in_domain(s, dom) & (dist > 1e-9 * scale)
    if np.any(out):
        raise ValueError(f"seeds {np.flatnonzero(out)[:10].tolist()} lie outside the domain")
    dg = _diagram(s, dom, dist)
    if np.any(dg.clipped.bridge):
        cells = np.flatnonzero(dg.boundary)[dg.clipped.bridge]
        raise MeshError(
            f"the Voronoi regions of seeds {cells[:10].tolist()} cut the domain into several "
            "pieces; move these seeds (e.g. by Lloyd iterations)"
        )
    size = np.sqrt(_polygon_area(dom) / len(s))
    return _build(dg, dom, collapse_tol * size, validate)


def voronoi_mesh(
    domain: ArrayLike,
    n_cells: int,
    seed: int | None = 0,
    lloyd_iterations: int | None = None,
    *,
    lloyd_tol: float = 1e-4,
    collapse_tol: float = 0.05,
    validate: bool = True,
    return_seeds: bool = False,
) -> Mesh | tuple[Mesh, FloatArray]:
    """Centroidal Voronoi mesh of a polygonal domain with exactly ``n_cells`` cells.

    Parameters
    ----------
    domain : (k, 2) array_like
        Counter-clockwise corners of a simple polygon, convex or not; see
        :func:`rectangle_domain` and :func:`l_shape_domain`. Every corner becomes
        a mesh vertex and every boundary edge lies on a side of the domain.
    n_cells : int
        Number of cells (>= 1).
    seed : int or None
        Seed of the random shift and jitter of the initial lattice; the mesh is a
        deterministic function of ``(domain, n_cells, seed, ...)``.
    lloyd_iterations : int or None
        Maximal number of Lloyd iterations (seed -> centroid of its clipped cell);
        by default 30 up to 10000 cells, fewer above (``300000 // n_cells``, at
        least 3), which bounds the cost while keeping the quality (see Notes).
    lloyd_tol : float
        Stop earlier when no seed moves by more than ``lloyd_tol`` times the
        average cell size ``sqrt(|domain| / n_cells)``.
    collapse_tol : float
        Vertices closer than ``collapse_tol`` times the average cell size
        ``sqrt(|domain| / n_cells)`` are merged (no tiny edges from clipping or
        from nearly co-circular seeds), unless that would make a cell invalid.
        Larger values raise A1's ``gamma2`` (about 0.035 for 0.05, 0.07 for 0.1,
        0.008 for 0.01 on 2048 cells) at the price of cells a little further
        from the exact Voronoi cells.
    validate : bool
        Check the result (cells, vertices, conformity); raises :class:`MeshError`.
    return_seeds : bool
        Also return the final seeds (one per cell).

    Returns
    -------
    Mesh or (Mesh, (n_cells, 2) float array)
        Counter-clockwise, conforming cells, numbered along a Z-order curve of
        their seeds (neighbouring cells have close ids); boundary untagged (use
        :meth:`Mesh.with_boundary` or :func:`~vemwear.mesh.boundary.tag_rectangle`).

    Notes
    -----
    Cost per Lloyd iteration: one Delaunay triangulation (Qhull, about 0.5 s for
    100000 seeds on one core) plus vectorized centroids and the clipping of the
    cells that touch the boundary. From the jittered hexagonal lattice, three
    iterations give ``rho_K / h_K >= 0.21`` (mean 0.41) on 100000 cells of the
    rectangle, and 30 give ``>= 0.27`` (mean 0.42) on 2048 cells
    (``benchmarks/bench_mesher.py`` prints the quality report). If, in a non-convex
    domain, a clipped cell falls apart into several pieces, up to 20 extra Lloyd
    iterations are run (this only happens for poorly distributed seeds).
    """
    n = int(n_cells)
    if n < 1:
        raise ValueError(f"n_cells must be positive, got {n_cells}")
    if lloyd_iterations is None:
        lloyd_iterations = int(np.clip(300_000 // n, 3, 30))
    if lloyd_iterations < 0:
        raise ValueError("lloyd_iterations must be >= 0")
    dom = as_domain(domain)
    rng = np.random.default_rng(seed)
    seeds = _initial_seeds(dom, n, rng)
    size = float(np.sqrt(_polygon_area(dom) / n))
    it = 0
    extra = 0
    while True:
        last = it >= lloyd_iterations
        dg = _diagram(seeds, dom, full=last)
        split = bool(np.any(dg.clipped.bridge))
        if last and not split:
            break
        if it >= lloyd_iterations:
            extra += 1
            if extra > 20:
                raise MeshError(
                    "Lloyd iterations did not separate Voronoi cells cut in pieces by the domain"
                )
        cen = _centroids(dg)
        ok = point_in_domain(cen, dom) & np.all(np.isfinite(cen), axis=1)
        new = np.where(ok[:, None], cen, seeds)
        move = float(np.max(np.linalg.norm(new - seeds, axis=1)))
        seeds = new
        it += 1
        if move < lloyd_tol * size and it < lloyd_iterations:
            it = lloyd_iterations  # converged: one more diagram, then stop
    mesh = _build(dg, dom, collapse_tol * size, validate)
    return (mesh, seeds) if return_seeds else mesh
