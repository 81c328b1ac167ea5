"""Marking and graded refinement for adaptive meshes (docs/method.md, section 11).

* :func:`dorfler_marking`: the bulk criterion of Dörfler (1996), the fewest cells whose
  indicators carry the fraction theta of the estimate.
* :func:`neighbour_pairs`: the pairs of cells that share an edge piece (a hanging node is
  a vertex of both cells, so every piece is a directed edge of one cell whose reverse is
  a directed edge of the other).
* :func:`graded_closure`, :func:`refine_tree` and :func:`refine_graded`: refine the
  marked cells and as many others as needed so that the refinement levels of neighbours
  differ by at most ``max_difference`` (one hanging node per side for the default 1);
  :class:`CellTree` records the levels and the families of children, for coarsening
  (:mod:`vemwear.mesh.coarsen`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .curves import BoundaryCurve
from .polymesh import Mesh
from .refine import refine_cells

__all__ = [
    "CellTree",
    "dorfler_marking",
    "graded_closure",
    "neighbour_pairs",
    "refine_graded",
    "refine_tree",
]

IntArray = NDArray[np.int64]


def dorfler_marking(indicators: ArrayLike, theta: float) -> IntArray:
    """The fewest cells whose squared indicators sum to at least ``theta`` times the total.

    Parameters
    ----------
    indicators : (n_cells,) array_like
        Squared indicators ``eta_K^2`` (>= 0).
    theta : float
        Bulk fraction in (0, 1].

    Returns
    -------
    (m,) int array
        Marked cells, largest indicator first (ties broken by cell id).
    """
    eta2 = np.asarray(indicators, dtype=float).ravel()
    if not 0.0 < theta <= 1.0:
        raise ValueError(f"theta must lie in (0, 1], got {theta}")
    if eta2.size and (not np.all(np.isfinite(eta2)) or eta2.min() < 0):
        bad = int(np.flatnonzero(~np.isfinite(eta2) | (eta2 < 0))[0])
        raise ValueError(f"indicators must be finite and >= 0; cell {bad} has {eta2[bad]}")
    total = float(eta2.sum())
    if total == 0.0:
        return np.zeros(0, dtype=np.int64)
    order = np.lexsort((np.arange(eta2.size), -eta2))
    cum = np.cumsum(eta2[order])
    m = int(np.searchsorted(cum, theta * total * (1.0 - 1e-12))) + 1
    return order[: min(m, eta2.size)].astype(np.int64)


def neighbour_pairs(mesh: Mesh) -> IntArray:
    """Ordered pairs (K, K') of cells sharing an edge piece, each pair once per piece;
    shape (m, 2)."""
    twin = mesh.edge_twins
    rows = np.flatnonzero(twin >= 0)
    return np.column_stack([mesh.edge_cells[rows], mesh.edge_cells[twin[rows]]])


def graded_closure(
    mesh: Mesh, level: ArrayLike, marked: ArrayLike, max_difference: int = 1
) -> IntArray:
    """The marked cells and the neighbours that must be refined with them.

    A cell of level l that is refined gives children of level l + 1; a neighbour of level
    below ``l + 1 - max_difference`` is then refined as well, and so on until no pair of
    neighbours in the refined mesh differs by more than ``max_difference`` (levels of a
    mesh that was graded before).

    Parameters
    ----------
    mesh : Mesh
    level : (n_cells,) int array_like
        Refinement level of every cell.
    marked : array_like of int
        Cells to refine.
    max_difference : int
        Largest level difference of neighbours (>= 1).

    Returns
    -------
    (m,) int array
        Sorted ids of the cells to refine.
    """
    if max_difference < 1:
        raise ValueError(f"max_difference must be >= 1, got {max_difference}")
    lev = np.asarray(level, dtype=np.int64)
    if lev.shape != (mesh.n_cells,):
        raise ValueError(f"level must have one entry per cell ({mesh.n_cells}), got {lev.shape}")
    pairs = neighbour_pairs(mesh)
    a, b = pairs[:, 0], pairs[:, 1]
    refine = np.zeros(mesh.n_cells, dtype=bool)
    refine[np.asarray(marked, dtype=np.int64)] = True
    while True:
        new = lev + refine
        # a neighbour b of a refined a that falls too far behind a's children
        need = refine[a] & ~refine[b] & (new[a] - new[b] > max_difference)
        if not np.any(need):
            return np.flatnonzero(refine).astype(np.int64)
        refine[b[need]] = True


@dataclass(frozen=True)
class CellTree:
    """The refinement history of the cells of an adaptive mesh.

    Attributes
    ----------
    level : (n_cells,) int array
        Refinement level (0 on the initial mesh).
    family : (n_cells,) int array
        The refinement the cell was born in (its siblings share it); -1 on the initial mesh.
    parent_family : (n_families,) int array
        For every refinement, the family of the cell that was refined.
    born : (n_families,) int array
        For every refinement, the number of children it made.
    """

    level: IntArray
    family: IntArray
    parent_family: IntArray
    born: IntArray

    @classmethod
    def initial(cls, n_cells: int) -> CellTree:
        """Every cell of an initial mesh: level 0, no family."""
        none = np.zeros(0, np.int64)
        return cls(np.zeros(n_cells, np.int64), np.full(n_cells, -1, np.int64), none, none)


def refine_tree(
    mesh: Mesh,
    tree: CellTree,
    marked: ArrayLike,
    max_difference: int = 1,
    curve: BoundaryCurve | None = None,
) -> tuple[Mesh, CellTree, IntArray]:
    """Refine the marked cells and their graded closure; the new mesh, its tree, and for
    every new cell the old cell it comes from (new boundary vertices on ``curve``, see
    :func:`~vemwear.mesh.refine.refine_cells`)."""
    cells = graded_closure(mesh, tree.level, marked, max_difference)
    new, parent = refine_cells(mesh, cells, return_parent=True, curve=curve)
    split = np.zeros(mesh.n_cells, dtype=bool)
    split[cells] = True
    rank = np.cumsum(split) - 1  # the k-th refined cell starts family n_families + k
    nf = len(tree.parent_family)
    child = split[parent]
    family = np.where(child, nf + rank[parent], tree.family[parent])
    level = tree.level[parent] + child
    pf = np.concatenate([tree.parent_family, tree.family[cells]])
    born = np.concatenate([tree.born, np.bincount(rank[parent[child]], minlength=len(cells))])
    return new, CellTree(level, family, pf, born), parent


def refine_graded(
    mesh: Mesh,
    level: ArrayLike,
    marked: ArrayLike,
    max_difference: int = 1,
    curve: BoundaryCurve | None = None,
) -> tuple[Mesh, IntArray, IntArray]:
    """Refine the marked cells and their :func:`graded_closure` by one level (new
    boundary vertices on ``curve``, see :func:`~vemwear.mesh.refine.refine_cells`).

    Returns
    -------
    mesh : Mesh
        The refined mesh (:func:`~vemwear.mesh.refine.refine_cells`).
    level : (n_new_cells,) int array
        The level of every new cell.
    parent : (n_new_cells,) int array
        The cell of the old mesh every new cell comes from.
    """
    lev = np.asarray(level, dtype=np.int64)
    tree = CellTree(
        lev, np.full(len(lev), -1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)
    )
    new, tree2, parent = refine_tree(mesh, tree, marked, max_difference, curve)
    return new, tree2.level, parent
