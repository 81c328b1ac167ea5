"""Local refinement of polygonal meshes with hanging nodes.

A refined cell with ``k`` geometric corners (vertices where its boundary turns;
hanging nodes on straight sides are not corners) is split into ``k``
quadrilaterals around a centre point, through the midpoints of its ``k``
geometric sides: child ``j`` is ``(m_{j-1}, ..., corner_j, ..., m_j, centre)``
with every vertex the parent had between ``m_{j-1}`` and ``m_j`` (a child may so
carry hanging nodes). For a square this is the usual split into four squares;
a side whose midpoint is already a vertex (a hanging node left by an earlier
refinement of the neighbour) reuses it.

Every new midpoint is also inserted, as a plain vertex, into the vertex list of
the neighbouring cell that shares the edge, so the result is conforming in the
virtual element sense (paper, Remark 4.9) and passes
:func:`~vemwear.mesh.checks.check_mesh`. A boundary edge that is split keeps the
part code of its parent edge in both halves.
Given the curve of the initial mesh's boundary (:mod:`vemwear.mesh.curves`), a new
midpoint on a curved boundary edge goes onto that curve instead, so that refinement
refines the geometry too; on straight edges it stays the middle of the corners.

The centre is the centroid when it lies strictly inside the kernel of the cell
(always true for convex cells), otherwise the centre of the largest disk in the
kernel (see :func:`~vemwear.mesh.quality.kernel_disks`).

All refined cells are handled at once on the flat arrays of the mesh (sides, midpoints,
the new vertex lists), with the floating-point operations of a loop over the cells and
their sides in the same order, so the points are those of one cell at a time to the bit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..util.arrays import isin as _isin
from ..util.arrays import unique as _unique
from .curves import BoundaryCurve
from .polymesh import Mesh, MeshError
from .quality import _kernel_disk_group

__all__ = ["refine_along", "refine_cells", "refine_where"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def corners(X: FloatArray) -> NDArray[np.bool_]:
    """Geometric corners of polygons ``X`` (m, n, 2) (vertices where the boundary turns)."""
    e_in = X - np.roll(X, 1, axis=1)
    e_out = np.roll(X, -1, axis=1) - X
    cr = e_in[..., 0] * e_out[..., 1] - e_in[..., 1] * e_out[..., 0]
    dot = np.sum(e_in * e_out, axis=-1)
    scale = np.hypot(e_in[..., 0], e_in[..., 1]) * np.hypot(e_out[..., 0], e_out[..., 1])
    straight = (np.abs(cr) <= 1e-10 * scale) & (dot > 0)
    return ~straight


def _centres(X: FloatArray, diam: FloatArray) -> FloatArray:
    """Centroids of polygons ``X`` (m, n, 2) with diameters ``diam`` where strictly inside
    the kernel, else centres of the largest kernel disks."""
    B = np.roll(X, -1, axis=1)
    cr = X[..., 0] * B[..., 1] - B[..., 0] * X[..., 1]
    area = 0.5 * cr.sum(axis=1)
    c = np.column_stack(
        [np.sum((X[..., 0] + B[..., 0]) * cr, axis=1), np.sum((X[..., 1] + B[..., 1]) * cr, axis=1)]
    ) / (6 * area[:, None])
    e = B - X
    L = np.hypot(e[..., 0], e[..., 1])
    side = (e[..., 0] * (c[:, 1:2] - X[..., 1]) - e[..., 1] * (c[:, 0:1] - X[..., 0])) / L
    outside = ~np.all(side > 1e-8 * diam[:, None], axis=1)
    if np.any(outside):
        rho, cen = _kernel_disk_group(X[outside])
        if not np.all(rho > 1e-12 * diam[outside]):
            raise MeshError("cannot refine a cell that is not star-shaped with respect to a disk")
        c[outside] = cen
    return c


def _batches(mesh: Mesh, cells: IntArray) -> list[tuple[IntArray, FloatArray]]:
    """The given cells batched by vertex count: ``[(cell ids, vertex coordinates (m, n,
    2))]``, in the order of :attr:`~vemwear.mesh.polymesh.Mesh.groups`."""
    out: list[tuple[IntArray, FloatArray]] = []
    for ids, verts in mesh.groups.values():
        mine = _isin(ids, cells)
        if np.any(mine):
            out.append((ids[mine], mesh.points[verts[mine]]))
    return out


def _ranges(starts: IntArray, counts: IntArray) -> IntArray:
    """The concatenated ranges ``starts[i], ..., starts[i] + counts[i] - 1``."""
    first = np.cumsum(counts) - counts
    return np.arange(int(counts.sum()), dtype=np.int64) + np.repeat(starts - first, counts)


@overload
def refine_cells(
    mesh: Mesh,
    cell_ids: ArrayLike,
    *,
    return_parent: Literal[False] = ...,
    curve: BoundaryCurve | None = ...,
) -> Mesh: ...


@overload
def refine_cells(
    mesh: Mesh,
    cell_ids: ArrayLike,
    *,
    return_parent: Literal[True],
    curve: BoundaryCurve | None = ...,
) -> tuple[Mesh, IntArray]: ...


def refine_cells(
    mesh: Mesh,
    cell_ids: ArrayLike,
    *,
    return_parent: bool = False,
    curve: BoundaryCurve | None = None,
) -> Mesh | tuple[Mesh, IntArray]:
    """Split the given cells into quadrilaterals around their centres (one level).

    Parameters
    ----------
    mesh : Mesh
        A valid mesh (see :func:`~vemwear.mesh.checks.check_mesh`), possibly with
        hanging nodes and tagged boundary parts.
    cell_ids : array_like of int
        Cells to refine (repetitions are ignored).
    return_parent : bool
        Also return, for every new cell, the id of the cell of ``mesh`` it comes from.
    curve : BoundaryCurve, optional
        The curve of the initial mesh's boundary (:mod:`vemwear.mesh.curves`): the new
        vertices on its curved edges go onto it; elsewhere, and without it, they are the
        middles of the sides' corners.

    Returns
    -------
    Mesh or (Mesh, (n_new_cells,) int array)
        The refined mesh. Each refined cell is replaced in place by its children
        (so cell ids after it shift); the old vertices keep their ids, new vertices
        (side midpoints, then centres) are appended. Boundary tags carry over.
    """
    sel = _unique(np.asarray(cell_ids, dtype=np.int64).ravel())
    if sel.size and (sel[0] < 0 or sel[-1] >= mesh.n_cells):
        raise ValueError(f"cell ids must lie in 0..{mesh.n_cells - 1}")
    if sel.size == 0:
        same = np.arange(mesh.n_cells, dtype=np.int64)
        return (mesh, same) if return_parent else mesh
    batches = _batches(mesh, sel)
    sides = _sides(mesh, sel, batches)
    centres = np.empty((mesh.n_cells, 2))
    for ids, X in batches:
        centres[ids] = _centres(X, mesh.cell_diameters[ids])
    mids = _midpoints(mesh, sides)
    xy = mids.xy if curve is None or not curve.any else _snapped(mesh, mids, curve)
    points = np.vstack([mesh.points, xy, centres[sel]])
    offsets, vertices, parent = _split(mesh, sel, sides, mids)
    pid = mesh.n_points + np.arange(mids.code.size)
    new_mesh = _carry_tags(mesh, Mesh(points, offsets, vertices), mids.code, pid)
    return (new_mesh, parent) if return_parent else new_mesh


def _snapped(mesh: Mesh, m: _Mids, curve: BoundaryCurve) -> FloatArray:
    """The new points ``m.xy`` with those on boundary edges moved onto ``curve``."""
    nk = max(mesh.n_points, 1)
    be = np.sort(mesh.boundary_edges, axis=1)
    bkey = be[:, 0] * nk + be[:, 1]
    order = np.argsort(bkey)
    i = np.clip(np.searchsorted(bkey[order], m.code), 0, max(len(bkey) - 1, 0))
    on = bkey[order][i] == m.code if len(bkey) else np.zeros(m.code.size, dtype=bool)
    if not np.any(on):
        return m.xy
    tags = mesh.boundary_tags
    tag = np.zeros(len(bkey), np.int64) if tags is None else np.asarray(tags, np.int64)
    xy = m.xy.copy()
    xy[on] = curve.snap(m.xy[on], tag[order][i[on]])
    return xy


@dataclass(frozen=True)
class _Sides:
    """The geometric sides of the refined cells: every refined cell's positions in
    ``cell_vertices`` turned to start at its first corner, the cells in increasing order,
    so that each side is a run of positions from its corner up to the next corner."""

    row: IntArray  # (n,) the position in cell_vertices of every turned position
    nxt: IntArray  # (n,) the next turned position of the same cell (cyclic)
    start: IntArray  # (n_sides,) the turned position of every side's first corner
    last: IntArray  # (n_sides,) the turned position where every side's last edge starts
    first: IntArray  # (n_refined + 1,) offsets of the sides of every refined cell


@dataclass(frozen=True)
class _Mids:
    """The midpoints of the sides: an existing vertex, or a new point on a mesh edge."""

    hit: NDArray[np.bool_]  # (n_sides,) whether it is an existing vertex
    at: IntArray  # (n_sides,) its turned position if hit, else that of the edge holding it
    new: IntArray  # (n_sides,) the new point it is (0..m-1), -1 if hit
    xy: FloatArray  # (m, 2) the new points, numbered from mesh.n_points on
    code: IntArray  # (m,) key min * nk + max of the mesh edge (min, max) holding each
    t: FloatArray  # (m,) its parameter along that edge from min to max


def _sides(mesh: Mesh, sel: IntArray, batches: list[tuple[IntArray, FloatArray]]) -> _Sides:
    """The sides of the cells ``sel`` (sorted, distinct; ``batches`` of them by vertex
    count) between their corners."""
    off = mesh.cell_offsets
    flag = np.zeros(mesh.cell_vertices.size, dtype=bool)
    for ids, X in batches:
        flag[off[ids][:, None] + np.arange(X.shape[1])] = corners(X)
    n = mesh.cell_sizes[sel]
    begin = np.cumsum(n) - n
    rows = _ranges(off[sel], n)
    k = np.add.reduceat(flag[rows].astype(np.int64), begin)
    if np.any(k < 3):
        raise MeshError(f"cell {sel[np.argmax(k < 3)]} has fewer than three corners")
    local = rows - np.repeat(off[sel], n)
    corner0 = local[np.flatnonzero(flag[rows])[np.cumsum(k) - k]]
    nn = np.repeat(n, n)
    row = rows - local + (local + np.repeat(corner0, n)) % nn
    nxt = np.arange(1, row.size + 1, dtype=np.int64)
    nxt[begin + n - 1] = begin
    start = np.flatnonzero(flag[row])
    last = np.append(start[1:], row.size) - 1
    return _Sides(row, nxt, start, last, np.concatenate([[0], np.cumsum(k)]))


def _midpoints(mesh: Mesh, s: _Sides) -> _Mids:
    """The midpoint of every side at half its length: a vertex within 1e-9 of it relative
    to the side's length, else the middle of its two corners, one point per mesh edge
    and parameter (within 1e-9) for the two cells sharing the edge, numbered in the
    order of the sides."""
    P = mesh.points
    V = mesh.cell_vertices[s.row]
    X = P[V]
    d = X[s.nxt] - X
    seg = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
    side = np.repeat(np.arange(s.start.size), s.last - s.start + 1)
    rank = np.arange(seg.size) - s.start[side]
    # the length along each side, summed edge after edge as np.cumsum does (same bits)
    cum = seg.copy()
    by_rank = np.argsort(rank, kind="stable")
    bounds = np.cumsum(np.bincount(rank))
    for r in range(1, bounds.size):
        e = by_rank[bounds[r - 1] : bounds[r]]
        cum[e] = cum[e - 1] + seg[e]
    length = cum[s.last]
    half, tol = 0.5 * length, 1e-9 * length
    near = np.abs(cum - half[side]) <= tol[side]
    big = seg.size + 1
    node = np.minimum.reduceat(np.where(near, rank + 1, big), s.start)
    node[half <= tol] = 0  # the first corner is the midpoint of a side of length 0
    hit = node < big
    at = np.where(node == 0, s.start, s.nxt[np.minimum(s.start + node - 1, seg.size - 1)])
    # else the edge (u, v) where the length passes half of the side's
    below = np.add.reduceat((cum < half[side]).astype(np.int64), s.start) + (half > 0.0)
    at = np.where(hit, at, s.start + below - 1)
    cand = np.flatnonzero(~hit)
    edge = at[cand]
    u, v = V[edge], V[s.nxt[edge]]
    lo, hi = np.minimum(u, v), np.maximum(u, v)
    xy = 0.5 * (X[s.start[cand]] + X[s.nxt[s.last[cand]]])
    pu, dv = P[lo], P[hi] - P[lo]
    w = xy - pu
    t = (w[:, 0] * dv[:, 0] + w[:, 1] * dv[:, 1]) / (dv[:, 0] * dv[:, 0] + dv[:, 1] * dv[:, 1])
    code = lo * max(mesh.n_points, 1) + hi
    target = _first_within(code, t)
    creates = target == np.arange(cand.size)
    number = np.cumsum(creates) - 1
    new = np.full(s.start.size, -1, dtype=np.int64)
    new[cand] = number[target]
    return _Mids(hit, at, new, xy[creates], code[creates], t[creates])


def _first_within(code: IntArray, t: FloatArray) -> IntArray:
    """For every candidate point ``(edge code, parameter)`` in order, the first earlier
    candidate of the same edge that made a point and whose parameter is within 1e-9,
    else itself (it makes a point)."""
    order = np.argsort(code, kind="stable")
    ks, ts = code[order], t[order]
    head = np.ones(ks.size, dtype=bool)
    head[1:] = ks[1:] != ks[:-1]
    starts = np.flatnonzero(head)
    rank = np.arange(ks.size) - starts[np.cumsum(head) - 1]
    target = np.arange(ks.size)
    makes = np.ones(ks.size, dtype=bool)
    # at most two cells of a valid mesh share an edge: one pass, a loop over ranks anyway
    for r in range(1, int(rank.max(initial=0)) + 1):
        idx = np.flatnonzero(rank == r)
        found = np.full(idx.size, -1)
        for q in range(r):
            j = idx - (r - q)
            ok = (found < 0) & makes[j] & (np.abs(ts[j] - ts[idx]) <= 1e-9)
            found[ok] = j[ok]
        makes[idx] = found < 0
        target[idx] = np.where(found < 0, idx, found)
    out = np.empty(ks.size, dtype=np.int64)
    out[order] = order[target]
    return out


def _split(mesh: Mesh, sel: IntArray, s: _Sides, m: _Mids) -> tuple[IntArray, IntArray, IntArray]:
    """Offsets and vertices of the new cells, and the old cell of each: the new points
    inserted into every cell along its edges, each refined cell split at its midpoints."""
    cv, de = mesh.cell_vertices, mesh.directed_edges
    n_new = m.code.size
    nk = max(mesh.n_points, 1)
    # the new points of every mesh edge, from its lower vertex id to its higher
    along = np.lexsort((m.t, m.code))
    key = m.code[along]
    head = np.ones(key.size, dtype=bool)
    head[1:] = key[1:] != key[:-1]
    gfirst = np.flatnonzero(head)
    gkey, gcount = key[gfirst], np.diff(np.append(gfirst, key.size))
    ecode = np.minimum(de[:, 0], de[:, 1]) * nk + np.maximum(de[:, 0], de[:, 1])
    g = np.minimum(np.searchsorted(gkey, ecode), max(gkey.size - 1, 0))
    cnt = np.where(gkey[g] == ecode, gcount[g], 0) if gkey.size else np.zeros_like(ecode)
    wpos = np.arange(cv.size) + np.cumsum(cnt) - cnt  # the old vertices in the new lists
    W = np.empty(cv.size + int(cnt.sum()), dtype=np.int64)
    W[wpos] = cv
    er = np.repeat(np.arange(cnt.size), cnt)
    i = np.arange(er.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    fwd = de[:, 0] < de[:, 1]
    W[wpos[er] + 1 + i] = (
        mesh.n_points + along[gfirst[g[er]] + np.where(fwd[er], i, cnt[er] - 1 - i)]
    )
    woff = np.append(wpos[mesh.cell_offsets[:-1]], W.size)
    nW = np.diff(woff)
    # the place of every side's midpoint in its cell's new list
    r = s.row[m.at]
    rank = np.empty(n_new, dtype=np.int64)
    rank[along] = np.arange(n_new) - np.repeat(gfirst, gcount)
    k = rank[np.maximum(m.new, 0)] if n_new else np.zeros_like(r)
    k = np.where(fwd[r], k, cnt[r] - 1 - k)
    wm = np.where(m.hit, wpos[r], wpos[r] + 1 + k)
    # child j of a refined cell runs from midpoint j - 1 to midpoint j, then the centre
    K = np.diff(s.first)
    owner = np.repeat(sel, K)
    prev = np.arange(owner.size) - 1
    prev[s.first[:-1]] = s.first[1:] - 1
    lo = wm[prev] - woff[owner]
    span = (wm - woff[owner] - lo) % nW[owner] + 1
    nout = np.ones(mesh.n_cells, dtype=np.int64)
    nout[sel] = K
    parent = np.repeat(np.arange(mesh.n_cells, dtype=np.int64), nout)
    refined = np.zeros(mesh.n_cells, dtype=bool)
    refined[sel] = True
    child = np.flatnonzero(refined[parent])
    first, count = np.zeros(parent.size, dtype=np.int64), nW[parent]
    first[child], count[child] = lo, span
    centre = np.full(parent.size, -1, dtype=np.int64)
    centre[child] = mesh.n_points + n_new + np.repeat(np.arange(sel.size), K)
    size = count + (centre >= 0)
    offsets = np.concatenate([[0], np.cumsum(size)])
    o = np.repeat(np.arange(parent.size), size)
    j = np.arange(o.size) - offsets[o]
    c = parent[o]
    verts = np.where(j < count[o], W[woff[c] + (first[o] + j) % nW[c]], centre[o])
    return offsets, verts, parent


def _carry_tags(old: Mesh, new: Mesh, code: IntArray, pid: IntArray) -> Mesh:
    """Boundary tags of ``new`` from ``old``: a half of a split edge keeps its parent's
    code (``pid``: the new points on old edges, ``code``: key min * nk + max of each)."""
    old_tags = old.boundary_tags
    if old_tags is None or not np.any(old_tags):
        return new
    nk = max(old.n_points, 1)
    ob = np.sort(old.boundary_edges, axis=1)
    okey = ob[:, 0] * nk + ob[:, 1]
    order = np.argsort(okey)
    okey, otag = okey[order], old_tags[order]
    parent_edge = np.arange(new.n_points, dtype=np.int64)  # new vertex -> an old edge key
    is_new = np.zeros(new.n_points, dtype=bool)
    parent_edge[pid] = code
    is_new[pid] = True
    be = new.boundary_edges
    p, q = be[:, 0], be[:, 1]
    key = np.minimum(p, q) * nk + np.maximum(p, q)
    key = np.where(is_new[p], parent_edge[p], key)
    key = np.where(is_new[q], parent_edge[q], key)
    i = np.clip(np.searchsorted(okey, key), 0, len(okey) - 1)
    found = okey[i] == key
    tags = np.where(found, otag[i], 0).astype(np.int8)
    return new._retagged(tags, old.part_names)


def refine_along(
    mesh: Mesh, part: str = "contact", levels: int = 1, *, touching: str = "edge"
) -> Mesh:
    """Refine the cells along a boundary part, ``levels`` times.

    Parameters
    ----------
    mesh : Mesh
        Mesh with tagged boundary parts.
    part : str
        ``"clamped"``, ``"traction"`` or ``"contact"``.
    levels : int
        Number of successive refinements; each level refines the cells along the
        part in the current mesh, so the cell size there is divided by
        ``2 ** levels`` (for quadrilaterals).
    touching : {"edge", "vertex"}
        Refine the cells that own an edge of the part, or also those that only
        share a vertex with it.

    Returns
    -------
    Mesh
    """
    code = mesh.part_code(part)
    if touching not in ("edge", "vertex"):
        raise ValueError(f"touching must be 'edge' or 'vertex', got {touching!r}")
    if not np.any(mesh.boundary_tags == code):
        raise MeshError(f"the mesh has no {part!r} boundary edges to refine along")
    for _ in range(int(levels)):
        if touching == "edge":
            cells = mesh.boundary_edge_cells[mesh.boundary_tags == code]
        else:
            vs = mesh.part_vertices(part)
            cells = mesh.edge_cells[_isin(mesh.directed_edges[:, 0], vs)]
        mesh = refine_cells(mesh, _unique(cells))
    return mesh


def refine_where(
    mesh: Mesh,
    predicate: Callable[[FloatArray], NDArray[np.bool_]],
    levels: int = 1,
) -> Mesh:
    """Refine the cells whose vertex average satisfies ``predicate``, ``levels`` times.

    Parameters
    ----------
    mesh : Mesh
    predicate : callable
        Maps an (m, 2) array of cell vertex averages to an (m,) boolean array.
    levels : int
        Repeat on the new mesh (the children where the predicate still holds).

    Returns
    -------
    Mesh
    """
    if not callable(predicate):
        raise TypeError("predicate must be callable; use refine_cells for explicit ids")
    for _ in range(int(levels)):
        cen = np.zeros((mesh.n_cells, 2))
        np.add.at(cen, mesh.edge_cells, mesh.points[mesh.cell_vertices])
        cen /= mesh.cell_sizes[:, None]
        hit = np.flatnonzero(np.asarray(predicate(cen), dtype=bool))
        mesh = refine_cells(mesh, hit)
    return mesh
