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

The domain helpers live in :mod:`.domains`, steps 2-5 (the clipped diagram) in
:mod:`.voronoi_diagram`; this module seeds, iterates and assembles the mesh.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..util.arrays import isin as _isin
from ..util.arrays import unique as _unique
from .checks import check_cells, check_conforming, check_vertices, crossing_sides
from .domains import (
    _nearest_sides,
    _polygon_area,
    as_domain,
    l_shape_domain,
    point_in_domain,
    rectangle_domain,
)
from .polymesh import Mesh, MeshError
from .voronoi_diagram import _centroids, _Diagram, _diagram, _segments

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


# --------------------------------------------------------------------------- assembly
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
    for n in _unique(lens):
        sel = np.flatnonzero(lens == n)
        idx = off[cells[sel]][:, None] + np.arange(n)
        X = points[cv[idx]]
        B = np.roll(X, -1, axis=1)
        area = 0.5 * np.sum(X[..., 0] * B[..., 1] - B[..., 0] * X[..., 1], axis=1)
        out[sel] = (area <= 0) | np.any(crossing_sides(X, eps=1e-9)[0], axis=1)
    return out


def _boundary_vertices(off: IntArray, cv: IntArray, n_points: int) -> IntArray:
    """Vertices of the edges that only one cell has (their reverse is in no cell)."""
    nxt = np.arange(1, len(cv) + 1)
    nxt[off[1:] - 1] = off[:-1]
    a, b = cv, cv[nxt]
    fwd = np.sort(a * n_points + b)
    rev = b * n_points + a
    pos = np.minimum(np.searchsorted(fwd, rev), len(fwd) - 1)
    lone = fwd[pos] != rev
    return _unique(np.concatenate([a[lone], b[lone]]))


def _snap_boundary(points: FloatArray, v: IntArray, dom: FloatArray) -> FloatArray:
    """Project the boundary vertices ``v`` exactly onto the nearest domain side."""
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
    mesh = Mesh(_snap_boundary(P, _boundary_vertices(off, cv, len(P)), dom), off, cv)
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

    box = len(dom) == 4 and np.all(_isin(dom, (lo, hi)).reshape(4, 2), axis=None)

    def inside(a: float) -> NDArray[np.bool_]:
        x = lo + a * unit
        ok = np.all((x > lo) & (x < hi), axis=1)
        if not box:
            ok[ok] = point_in_domain(x[ok], dom)
        return ok

    if box:  # point p is inside for spacings below a_max(p): take the n-th largest
        ext = hi - lo
        with np.errstate(divide="ignore"):
            a_max = np.where(np.all(unit > 0, axis=1), np.min(ext / unit, axis=1), 0.0)
        order = np.argsort(-a_max, kind="stable")
        if a_max[order[n - 1]] > 0 and (n == len(order) or a_max[order[n]] < a_max[order[n - 1]]):
            a = 0.5 * (a_max[order[n - 1]] + (a_max[order[n]] if n < len(order) else 0.0))
            a = min(a, a_max[order[n - 1]] * (1 - 1e-12))
            pts = lo + a * unit[np.sort(order[:n])]
            return pts[_morton_order(pts)]
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

    Examples
    --------
    An L-shaped domain (a non-convex polygon) in exactly 20 cells:

    >>> from vemwear.mesh import l_shape_domain, voronoi_mesh
    >>> mesh = voronoi_mesh(l_shape_domain(), 20, seed=1)
    >>> mesh.n_cells
    20
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
