"""Validity checks of a mesh, each raising :class:`MeshError` that names cells or vertices."""

from __future__ import annotations

import hashlib
from collections import OrderedDict

import numpy as np
from numpy.typing import NDArray

from ..util.arrays import isin as _isin
from ..util.arrays import unique as _unique
from .polymesh import Mesh, MeshError

_SHOW = 10


def _ids(a: NDArray) -> str:
    """The first few ids (or id pairs) of a list, for messages."""
    a = np.asarray(a)
    more = f" and {len(a) - _SHOW} more" if len(a) > _SHOW else ""
    return f"{a[:_SHOW].tolist()}{more}"


def _scale(mesh: Mesh) -> float:
    ext = mesh.points.max(axis=0) - mesh.points.min(axis=0)
    return float(max(np.max(ext), np.finfo(float).tiny))


def _apart(points: NDArray[np.float64], tol: float) -> bool:
    """True when no two points are within ``tol`` of each other, by sorting: the distinct
    x coordinates more than ``tol`` apart, and the points of equal x more than ``tol``
    apart in y (a close pair has close x and y). False: a closer look is needed."""
    x, y = points[:, 0], points[:, 1]
    xs = _unique(x)
    if len(xs) > 1 and np.diff(xs).min() <= tol:
        return False
    order = np.lexsort((y, x))  # by x, then y: a close pair of equal x is adjacent
    same_x = x[order][1:] == x[order][:-1]
    return not np.any(np.diff(y[order])[same_x] <= tol)


def check_cells(mesh: Mesh, rtol: float = 1e-12) -> None:
    """Cells are counter-clockwise, non-degenerate, simple, with distinct vertices."""
    for _n, (ids, verts) in mesh.groups.items():
        s = np.sort(verts, axis=1)
        rep = np.any(s[:, 1:] == s[:, :-1], axis=1)
        if np.any(rep):
            raise MeshError(f"cells {_ids(ids[rep])} list a vertex twice")
    area = mesh.cell_areas
    tiny = rtol * mesh.cell_diameters**2
    if np.any(np.abs(area) <= tiny):
        raise MeshError(
            f"cells {_ids(np.flatnonzero(np.abs(area) <= tiny))} are degenerate (zero area)"
        )
    if np.any(area < 0):
        raise MeshError(
            f"cells {_ids(np.flatnonzero(area < 0))} are clockwise; cells must be counter-clockwise"
        )
    check_simple(mesh)


def crossing_sides(
    X: NDArray[np.float64], eps: float
) -> tuple[NDArray[np.bool_], NDArray[np.int64], NDArray[np.int64]]:
    """Which non-adjacent sides ``i < j`` of the polygons ``X`` (m, n, 2) meet.

    Returns the (m, n_pairs) mask and the side pairs ``i``, ``j``; segment
    parameters within ``[-eps, 1 + eps]`` count as meeting, parallel sides never. Sides
    whose angle has a sine below 1e-10 count as parallel: two pieces of one straight
    side (hanging nodes on a sloped side) are parallel only to round-off, and the
    parameters of such a pair are quotients of round-off.
    """
    n = X.shape[1]
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))  # the last side is adjacent to the first
    i, j = i[keep], j[keep]
    B = np.roll(X, -1, axis=1)
    p, r = X[:, i], B[:, i] - X[:, i]
    q, s = X[:, j], B[:, j] - X[:, j]
    rxs = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    qp = q - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qp[..., 0] * s[..., 1] - qp[..., 1] * s[..., 0]) / rxs
        u = (qp[..., 0] * r[..., 1] - qp[..., 1] * r[..., 0]) / rxs
    parallel = np.abs(rxs) <= 1e-10 * np.hypot(r[..., 0], r[..., 1]) * np.hypot(
        s[..., 0], s[..., 1]
    )
    hit = ~parallel & (t >= -eps) & (t <= 1 + eps) & (u >= -eps) & (u <= 1 + eps)
    return hit, i, j


def check_simple(mesh: Mesh) -> None:
    """No cell boundary crosses itself (all pairs of non-adjacent edges are disjoint)."""
    for n, (ids, verts) in mesh.groups.items():
        if n < 4:
            continue
        bad = np.any(crossing_sides(mesh.points[verts], eps=1e-12)[0], axis=1)
        if np.any(bad):
            raise MeshError(f"cells {_ids(ids[bad])} are not simple polygons (their edges cross)")


def check_vertices(mesh: Mesh, rtol: float = 1e-10) -> None:
    """No two vertices coincide and every vertex belongs to a cell."""
    from scipy.spatial import cKDTree  # loaded with the first mesh: start-up time

    used = np.zeros(mesh.n_points, dtype=bool)
    used[mesh.cell_vertices] = True
    if not np.all(used):
        raise MeshError(f"vertices {_ids(np.flatnonzero(~used))} belong to no cell (dangling)")
    tol = rtol * _scale(mesh)
    if _apart(mesh.points, tol):
        return
    pairs = cKDTree(mesh.points).query_pairs(tol, output_type="ndarray")
    if len(pairs):
        raise MeshError(f"duplicate vertices (same coordinates): pairs {_ids(pairs[:, :2])}")


def check_conforming(mesh: Mesh, rtol: float = 1e-9) -> None:
    """Every interior edge is shared by exactly two cells with opposite orientation.

    A vertex that lies inside an edge of a cell must be a vertex of that cell too
    (a hanging node is a plain vertex of all cells around it).
    """
    de = mesh.directed_edges
    n = mesh.n_points
    key = de[:, 0] * n + de[:, 1]
    uniq, counts = np.unique(key, return_counts=True)
    if np.any(counts > 1):
        k = uniq[counts > 1]
        rows = np.flatnonzero(_isin(key, k))
        raise MeshError(
            f"cells {_ids(_unique(mesh.edge_cells[rows]))} overlap: they share an edge "
            "with the same orientation"
        )
    be = mesh.boundary_edges
    bv = _unique(be)
    if len(be) == 0:
        raise MeshError("the mesh has no boundary edges")
    a, b = mesh.points[be[:, 0]], mesh.points[be[:, 1]]
    mid, half = 0.5 * (a + b), 0.5 * np.linalg.norm(b - a, axis=1)
    from scipy.spatial import cKDTree

    tree = cKDTree(mesh.points[bv])
    tol = rtol * _scale(mesh)
    hits = tree.query_ball_point(mid, half * (1 - 1e-9))
    # (edge, candidate vertex) pairs, all at once: boundary vertices near each edge
    counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(hits))
    e = np.repeat(np.arange(len(be)), counts)
    c = bv[np.fromiter((i for h in hits for i in h), dtype=np.int64, count=int(counts.sum()))]
    keep = (c != be[e, 0]) & (c != be[e, 1])
    e, c = e[keep], c[keep]
    d = b[e] - a[e]
    r = mesh.points[c] - a[e]
    dist = np.abs(r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]) / (2 * half[e])
    on_edge = np.flatnonzero(dist <= tol)
    if on_edge.size:
        k = on_edge[0]
        ek, v, cell = e[k], c[k], mesh.boundary_edge_cells[e[k]]
        raise MeshError(
            f"non-conforming edge ({be[ek, 0]}, {be[ek, 1]}) of cell {cell}: vertex {v} lies "
            "on it but is not a vertex of that cell (add hanging nodes to the cell's list)"
        )
    _check_nested_pieces(mesh)  # last: the messages above are more specific


def _check_nested_pieces(mesh: Mesh) -> None:
    """Pieces of the mesh (cells connected through shared edges) must not lie inside
    one another: a cell placed inside another cell shares no edge with it."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    twin = mesh.edge_twins
    has = twin >= 0
    a, b = mesh.edge_cells[has], mesh.edge_cells[twin[has]]
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(mesh.n_cells, mesh.n_cells))
    npieces, piece = connected_components(graph, directed=False)
    if npieces == 1:
        return
    # only now: importing matplotlib costs a mesh read from a file about half a second
    from matplotlib.path import Path

    be, owner = mesh.boundary_edges, piece[mesh.boundary_edge_cells]
    for k in range(npieces):
        edges = be[owner == k]
        succ = dict(zip(edges[:, 0].tolist(), edges[:, 1].tolist(), strict=True))
        loops, seen = [], set()
        for v0 in succ:  # the outer loop is the one with the largest signed area
            if v0 in seen:
                continue
            loop, v = [], v0
            while v not in seen and v in succ:
                seen.add(v)
                loop.append(v)
                v = succ[v]
            loops.append(loop)
        outer = max(loops, key=lambda lp: _signed_area(mesh.points[lp]))
        inside = Path(mesh.points[outer]).contains_points(mesh.points)
        others = _unique(mesh.cell_vertices[piece[mesh.edge_cells] != k])
        others = others[~_isin(others, outer)]
        hit = others[inside[others]]
        if hit.size:
            cells = np.flatnonzero(piece == k)
            raise MeshError(
                f"cells overlap: vertex {hit[0]} of another piece of the mesh lies inside the "
                f"piece made of cells {_ids(cells)}"
            )


def _xy(mesh: Mesh, edge: NDArray[np.int64]) -> str:
    a, b = mesh.points[edge[0]], mesh.points[edge[1]]
    return f"{a[0]:.6g}, {a[1]:.6g}) to ({b[0]:.6g}, {b[1]:.6g}"


def _signed_area(p: NDArray[np.float64]) -> float:
    q = np.roll(p, -1, axis=0)
    return 0.5 * float(np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def check_boundary(mesh: Mesh, require: tuple[str, ...] = ("clamped",)) -> None:
    """Every boundary edge is tagged and the required parts are present."""
    untagged = np.flatnonzero(mesh.boundary_tags == 0)
    if untagged.size:
        e = mesh.boundary_edges[untagged]
        raise MeshError(
            f"{untagged.size} boundary edges have no boundary part, e.g. edges "
            f"{_ids(e[:3].tolist())} (vertex ids) from ({_xy(mesh, e[0])}); put them in a "
            "part: a clamped, displacement, traction, free or contact part, or 'rest'"
        )
    for name in require:
        if not mesh.has_part(name):
            raise MeshError(f"the mesh has no {name!r} boundary edges")


#: Digests of the geometries that passed the checks of vertices, cells and conformity
#: (the last few: runs of a study build the same mesh again and again).
_PASSED: OrderedDict[bytes, None] = OrderedDict()


def _geometry_digest(mesh: Mesh) -> bytes:
    h = hashlib.blake2b(digest_size=20)
    for a in (mesh.points, mesh.cell_offsets, mesh.cell_vertices):
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(np.ascontiguousarray(a).data)
    return h.digest()


def _passed(key: bytes) -> None:
    _PASSED[key] = None
    while len(_PASSED) > 8:
        _PASSED.popitem(last=False)


def known_valid(mesh: Mesh) -> Mesh:
    """Record that the geometry of ``mesh`` passes the checks of vertices, cells and
    conformity, without running them: for the meshes of generators that are valid by
    construction (a structured grid of a rectangle). Returns ``mesh``."""
    _passed(_geometry_digest(mesh))
    return mesh


def check_mesh(mesh: Mesh, require: tuple[str, ...] = ("clamped",)) -> None:
    """Run every check: vertices, cells, conformity and boundary parts.

    The first three depend on the geometry alone; a geometry that passed them (or that
    a generator built valid, :func:`known_valid`) is recognised by a digest of its
    arrays and not checked again.
    """
    key = _geometry_digest(mesh)
    if key in _PASSED:
        _PASSED.move_to_end(key)
    else:
        check_vertices(mesh)
        check_cells(mesh)
        check_conforming(mesh)
        _passed(key)
    check_boundary(mesh, require)
