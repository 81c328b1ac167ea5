"""The loop-based local refinement that :func:`vemwear.mesh.refine.refine_cells` replaced,
kept as the reference its output must match bitwise (points, cells, tags, parents).

One cell and one side at a time in Python: plain to read, slow on large meshes.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from vemwear.mesh.polymesh import Mesh, MeshError
from vemwear.mesh.refine import _centres, corners
from vemwear.util.arrays import isin as _isin
from vemwear.util.arrays import unique as _unique

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _per_cell(
    mesh: Mesh, cells: IntArray, fn: Callable[[FloatArray, IntArray], NDArray]
) -> dict[int, NDArray]:
    """``fn(vertex coordinates (m, n, 2), cell ids)`` for the given cells, batched by
    vertex count; ``{cell: row of the result}``."""
    out: dict[int, NDArray] = {}
    for ids, verts in mesh.groups.values():
        mine = _isin(ids, cells)
        if np.any(mine):
            res = fn(mesh.points[verts[mine]], ids[mine])
            out.update(zip(ids[mine].tolist(), res, strict=True))
    return out


def refine_cells_reference(
    mesh: Mesh, cell_ids: ArrayLike, *, return_parent: bool = False
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
    P = mesh.points
    nP = mesh.n_points
    new_pts: list[FloatArray] = []
    # new vertices on mesh edges: undirected edge -> list of (parameter, vertex id)
    on_edge: dict[tuple[int, int], list[tuple[float, int]]] = {}
    # refined cell -> ids of the midpoints of its geometric sides, and of its centre
    mids_of: dict[int, list[int]] = {}
    centre_of: dict[int, int] = {}

    def new_point(xy: FloatArray) -> int:
        new_pts.append(np.asarray(xy, dtype=float))
        return nP + len(new_pts) - 1

    is_corner = _per_cell(mesh, sel, lambda X, _ids: corners(X))
    for c in sel.tolist():
        V = mesh.cell(c)
        X = P[V]
        n = len(V)
        cpos = np.flatnonzero(is_corner[c])
        if len(cpos) < 3:
            raise MeshError(f"cell {c} has fewer than three corners")
        mids: list[int] = []
        for k in range(len(cpos)):
            a, b = cpos[k], cpos[(k + 1) % len(cpos)]
            chain = [(a + j) % n for j in range(((b - a) % n) + 1)]  # positions a..b
            Y = X[chain]
            seg = np.linalg.norm(np.diff(Y, axis=0), axis=1)
            s = np.concatenate([[0.0], np.cumsum(seg)])
            half = 0.5 * s[-1]
            tol = 1e-9 * s[-1]
            hit = np.flatnonzero(np.abs(s - half) <= tol)
            if hit.size:
                mids.append(int(V[chain[hit[0]]]))
                continue
            j = int(np.searchsorted(s, half) - 1)
            u, v = int(V[chain[j]]), int(V[chain[j + 1]])
            xy = 0.5 * (X[a] + X[b])
            key = (min(u, v), max(u, v))
            pu, pv = P[key[0]], P[key[1]]
            t = float(np.dot(xy - pu, pv - pu) / np.dot(pv - pu, pv - pu))
            lst = on_edge.setdefault(key, [])
            found = next((pid for (tt, pid) in lst if abs(tt - t) <= 1e-9), None)
            if found is None:
                found = new_point(xy)
                lst.append((t, found))
            mids.append(found)
        mids_of[c] = mids
    centres = _per_cell(mesh, sel, lambda X, ids: _centres(X, mesh.cell_diameters[ids]))
    for c in sel.tolist():
        centre_of[c] = new_point(centres[c])

    points = np.vstack([P, *[p[None] for p in new_pts]]) if new_pts else P.copy()

    # insert the new edge points into every cell that has the edge (refined or not)
    touched = set()
    if on_edge:
        de = mesh.directed_edges
        keys = np.sort(de, axis=1)
        nk = max(nP, 1)
        code = keys[:, 0] * nk + keys[:, 1]
        wanted = np.array([a * nk + b for (a, b) in on_edge], dtype=np.int64)
        rows = np.flatnonzero(_isin(code, wanted))
        touched = set(mesh.edge_cells[rows].tolist())

    def augmented(c: int) -> list[int]:
        V = mesh.cell(c).tolist()
        if c not in touched:
            return V
        out: list[int] = []
        n = len(V)
        for i in range(n):
            a, b = V[i], V[(i + 1) % n]
            out.append(a)
            lst = on_edge.get((min(a, b), max(a, b)))
            if lst:
                ts = sorted(lst) if a < b else sorted(lst, reverse=True)
                out.extend(pid for _t, pid in ts)
        return out

    cells: list[list[int]] = []
    parent: list[int] = []
    selset = set(sel.tolist())
    for c in range(mesh.n_cells):
        W = augmented(c)
        if c not in selset:
            cells.append(W)
            parent.append(c)
            continue
        mids, centre = mids_of[c], centre_of[c]
        pos = {v: i for i, v in enumerate(W)}
        nW = len(W)
        for j in range(len(mids)):
            start = pos[mids[j - 1]]
            stop = pos[mids[j]]
            length = (stop - start) % nW
            child = [W[(start + i) % nW] for i in range(length + 1)]
            child.append(centre)
            cells.append(child)
            parent.append(c)
    new_mesh = Mesh.from_cells(points, cells)
    new_mesh = _carry_tags(mesh, new_mesh, on_edge)
    return (new_mesh, np.asarray(parent, dtype=np.int64)) if return_parent else new_mesh


def _carry_tags(
    old: Mesh, new: Mesh, on_edge: dict[tuple[int, int], list[tuple[float, int]]]
) -> Mesh:
    """Boundary tags of ``new`` from ``old``: a half of a split edge keeps its parent's code."""
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
    for (a, b), lst in on_edge.items():
        for _t, pid in lst:
            parent_edge[pid] = a * nk + b
            is_new[pid] = True
    be = new.boundary_edges
    p, q = be[:, 0], be[:, 1]
    key = np.minimum(p, q) * nk + np.maximum(p, q)
    key = np.where(is_new[p], parent_edge[p], key)
    key = np.where(is_new[q], parent_edge[q], key)
    i = np.clip(np.searchsorted(okey, key), 0, len(okey) - 1)
    found = okey[i] == key
    tags = np.where(found, otag[i], 0).astype(np.int8)
    return Mesh(new.points, new.cell_offsets, new.cell_vertices, tags, old.part_names)
