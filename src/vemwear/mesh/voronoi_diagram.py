"""The Voronoi diagram of seeds clipped to a polygonal domain (the mesher's geometry).

Voronoi regions as fans of Delaunay triangles (:func:`_triangulate`, :func:`_fans`),
their exact intersection with the domain (:func:`_clip`), and the centroids used by
the Lloyd iterations (:func:`_centroids`); :mod:`.voronoi` turns a diagram into a
conforming mesh. Steps 2-5 of the algorithm described in :mod:`.voronoi`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..util.arrays import unique as _unique
from .domains import _nearest_sides
from .polymesh import MeshError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


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
        bad = _unique(tri.coplanar[:, 0])
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
    return np.asarray(area, dtype=np.float64), cen + xy[off[:-1]]


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


def _segments(starts: IntArray, lens: IntArray) -> IntArray:
    """Concatenation of ``arange(starts[i], starts[i] + lens[i])`` over ``i``."""
    lens = np.asarray(lens, dtype=np.int64)
    excl = np.concatenate([[0], np.cumsum(lens)[:-1]])
    return np.repeat(np.asarray(starts, dtype=np.int64) - excl, lens) + np.arange(lens.sum())
