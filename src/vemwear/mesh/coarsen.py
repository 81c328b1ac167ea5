"""Coarsening of adaptive meshes: the children of a refined cell merged back
(docs/method.md, section 11).

A :class:`~vemwear.mesh.adapt.CellTree` keeps, next to a mesh, the refinement level of
every cell and the *family* it was born in (one family per refined cell: its children;
:func:`~vemwear.mesh.adapt.refine_tree` records them); :func:`coarsen_tree` merges every
family whose cells are all present, all leaves, and all marked for coarsening, as long as
no neighbour is then more than ``max_difference`` levels finer than the merged cell.

The merged cell is the union of its children: its boundary is the children's directed
edges whose reverse is not among them, chained into one counter-clockwise polygon. The
centre of the parent disappears with the children's interior edges; a side midpoint that
no cell needs any more (a vertex that lies on a straight side of every cell that holds
it, between two boundary pieces of the same part if on the boundary) is removed, so that
refining and coarsening a region gives back the mesh it started from (with its vertices
renumbered). On a curved boundary (:mod:`vemwear.mesh.curves`) the new boundary vertex of
a refined cell lies on the curve, not on the cell's side; given the curve, a boundary
vertex that only the merged cell holds and that is the curve's point of its two boundary
neighbours' middle (the point refinement made there) is removed too, and the merged cell
gets back its chord.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .adapt import CellTree, neighbour_pairs
from .curves import BoundaryCurve
from .polymesh import Mesh, MeshError
from .refine import corners

__all__ = ["coarsen_tree", "coarsening_marking"]

IntArray = NDArray[np.int64]


def coarsening_marking(indicators: ArrayLike, fraction: float) -> IntArray:
    """The most cells, smallest indicators first, whose squared indicators sum to at most
    ``fraction`` of the total: the cells the estimate can spare (Dörfler's criterion from
    below).

    Parameters
    ----------
    indicators : (n_cells,) array_like
        Squared indicators ``eta_K^2`` (>= 0).
    fraction : float
        In [0, 1).
    """
    eta2 = np.asarray(indicators, dtype=float).ravel()
    if not 0.0 <= fraction < 1.0:
        raise ValueError(f"the coarsening fraction must lie in [0, 1), got {fraction}")
    order = np.lexsort((np.arange(eta2.size), eta2))
    cum = np.cumsum(eta2[order])
    m = int(np.searchsorted(cum, fraction * float(eta2.sum()), side="right"))
    return order[:m].astype(np.int64)


def coarsen_tree(
    mesh: Mesh,
    tree: CellTree,
    marked: ArrayLike,
    max_difference: int = 1,
    curve: BoundaryCurve | None = None,
) -> tuple[Mesh, CellTree, IntArray]:
    """Merge the families whose cells are all marked (module docstring).

    Parameters
    ----------
    mesh : Mesh
    tree : CellTree
        Of ``mesh``.
    marked : array_like of int
        Cells marked for coarsening.
    max_difference : int
        Largest level difference of neighbours after the merge.
    curve : BoundaryCurve, optional
        The curve the refinement put the boundary vertices on.

    Returns
    -------
    mesh : Mesh
    tree : CellTree
    owner : (n_old_cells,) int array
        The new cell of every old cell.
    """
    nc = mesh.n_cells
    fam = tree.family
    if len(tree.parent_family) == 0:  # nothing was refined
        return mesh, tree, np.arange(nc, dtype=np.int64)
    want = np.zeros(nc, dtype=bool)
    want[np.asarray(marked, dtype=np.int64)] = True
    # a family may merge when all its children are present (none refined further) and
    # all are marked
    nf = len(tree.parent_family)
    member = fam >= 0
    present = np.bincount(fam[member], minlength=nf)
    marked_n = np.bincount(fam[member & want], minlength=nf)
    ok = (present == tree.born) & (marked_n == tree.born) & (tree.born > 0)
    # the merged cells have level - 1: a neighbour more than max_difference finer forbids
    pairs = neighbour_pairs(mesh)
    a, b = pairs[:, 0], pairs[:, 1]
    fa = fam[a]
    bad = (fa >= 0) & (tree.level[b] > tree.level[a] - 1 + max_difference)
    ok[fa[bad]] = False
    merge = ok[np.where(fam >= 0, fam, 0)] & (fam >= 0)
    if not np.any(merge):
        return mesh, tree, np.arange(nc, dtype=np.int64)
    return _merge(mesh, tree, merge, curve)


def _merge(
    mesh: Mesh, tree: CellTree, merge: NDArray[np.bool_], curve: BoundaryCurve | None
) -> tuple[Mesh, CellTree, IntArray]:
    fam = tree.family
    cells = mesh.cells
    new_cells: list[list[int]] = []
    owner = np.empty(mesh.n_cells, dtype=np.int64)
    level, family = [], []
    seen: dict[int, int] = {}
    members: dict[int, list[int]] = {}
    for c in np.flatnonzero(merge).tolist():
        members.setdefault(int(fam[c]), []).append(c)
    for c in range(mesh.n_cells):
        if not merge[c]:
            owner[c] = len(new_cells)
            new_cells.append(cells[c].tolist())
            level.append(int(tree.level[c]))
            family.append(int(fam[c]))
            continue
        f = int(fam[c])
        if f in seen:
            owner[c] = seen[f]
            continue
        seen[f] = owner[c] = len(new_cells)
        new_cells.append(_union([cells[k] for k in members[f]], f))
        level.append(int(tree.level[c]) - 1)
        family.append(int(tree.parent_family[f]))
    mesh2 = _drop_unneeded(mesh, new_cells, curve)
    tree2 = CellTree(np.array(level), np.array(family), tree.parent_family, tree.born)
    return mesh2, tree2, owner


def _union(children: list[NDArray[np.int64]], f: int) -> list[int]:
    """The counter-clockwise boundary of the union of cells sharing edges."""
    nxt: dict[int, int] = {}
    edges = set()
    for ch in children:
        for a, b in zip(ch.tolist(), np.roll(ch, -1).tolist(), strict=True):
            edges.add((a, b))
    for a, b in edges:
        if (b, a) not in edges:
            if a in nxt:
                raise MeshError(f"the children of refinement {f} do not form one polygon")
            nxt[a] = b
    start = min(nxt)
    out = [start]
    while nxt[out[-1]] != start:
        out.append(nxt[out[-1]])
        if len(out) > len(nxt):
            raise MeshError(f"the children of refinement {f} do not form one polygon")
    return out


def _drop_unneeded(mesh: Mesh, cells: list[list[int]], curve: BoundaryCurve | None) -> Mesh:
    """The mesh of ``cells`` (vertex ids of ``mesh``) without the vertices no cell uses and
    without the vertices that lie on a straight side of every cell holding them (and
    between boundary pieces of one part) or, given the curve, that refinement put onto it
    (module docstring), with the boundary tags carried over."""
    tmp = Mesh.from_cells(mesh.points, cells)
    # a vertex is needed where some cell turns at it
    need = np.zeros(mesh.n_points, dtype=bool)
    for _n, (_ids, verts) in tmp.groups.items():
        corner = corners(mesh.points[verts])
        need[verts[corner]] = True
    used = np.zeros(mesh.n_points, dtype=bool)
    used[tmp.cell_vertices] = True
    # boundary vertices between two parts are needed; the tags come from the old mesh's
    # boundary edges, each vertex's two boundary pieces
    tag_at = _boundary_tag_of(mesh)
    be = tmp.boundary_edges
    tags = tag_at(be)
    first = np.full(mesh.n_points, -1, dtype=np.int64)
    first[be[:, 0]] = tags
    last = np.full(mesh.n_points, -1, dtype=np.int64)
    last[be[:, 1]] = tags
    on_b = np.zeros(mesh.n_points, dtype=bool)
    on_b[be[:, 0]] = True
    need |= on_b & (first != last)
    if curve is not None and curve.any:
        need &= ~_snapped_midpoints(mesh.points, tmp, be, first == last, first, curve)
    drop = used & ~need
    if np.any(drop):
        cells = [[v for v in c if not drop[v]] for c in cells]
    keep = used & ~drop
    new_id = np.cumsum(keep) - 1
    cells = [new_id[np.asarray(c)].tolist() for c in cells]
    out = Mesh.from_cells(mesh.points[keep], cells)
    # the tags: every boundary edge of the result lies on one old boundary edge chain
    old_tags = tag_at(np.flatnonzero(keep)[out.boundary_edges])
    return Mesh(out.points, out.cell_offsets, out.cell_vertices, old_tags, mesh.part_names)


def _snapped_midpoints(
    P: NDArray[np.float64],
    tmp: Mesh,
    be: NDArray[np.int64],
    inside_part: NDArray[np.bool_],
    tag: NDArray[np.int64],
    curve: BoundaryCurve,
) -> NDArray[np.bool_]:
    """The boundary vertices of ``tmp`` (vertex ids of points ``P``) that one cell holds,
    inside one part, and that are the curve's point at the middle of their two boundary
    neighbours."""
    n = len(P)
    holders = np.bincount(tmp.cell_vertices, minlength=n)
    before = np.full(n, -1, dtype=np.int64)
    before[be[:, 1]] = be[:, 0]
    after = np.full(n, -1, dtype=np.int64)
    after[be[:, 0]] = be[:, 1]
    v = np.flatnonzero((before >= 0) & (after >= 0) & (holders == 1) & inside_part)
    out = np.zeros(n, dtype=bool)
    if v.size == 0:
        return out
    a, b = P[before[v]], P[after[v]]
    snapped = curve.snap(0.5 * (a + b), tag[v])
    gap = np.linalg.norm(snapped - P[v], axis=1)
    moved = np.linalg.norm(snapped - 0.5 * (a + b), axis=1) > 0
    out[v] = moved & (gap <= 1e-9 * np.linalg.norm(b - a, axis=1))
    return out


def _boundary_tag_of(mesh: Mesh) -> Callable[[NDArray[np.int64]], NDArray[np.int8]]:
    """A function giving, for directed edges (m, 2) of vertex ids of ``mesh`` that lie
    along its boundary, the tag of the old boundary edge that starts at the edge's first
    vertex and runs towards its second."""
    be = mesh.boundary_edges
    start = np.full(mesh.n_points, -1, dtype=np.int64)
    start[be[:, 0]] = np.arange(len(be))
    tags = np.asarray(mesh.boundary_tags, dtype=np.int64)

    def tag(edges: NDArray[np.int64]) -> NDArray[np.int8]:
        row = start[edges[:, 0]]
        if np.any(row < 0):
            raise MeshError("a boundary edge of the coarsened mesh is not on the old boundary")
        return tags[row].astype(np.int8)

    return tag
