"""The displacement and wear errors of several coarse runs against one reference
(:meth:`vemwear.post.compare.Comparison.errors_many`), level by level of the reference.

Per coarse run, the mesh-dependent operators are built once (:func:`pairs`): the fine
vertex of every coarse vertex, the coarse cell of every fine cell, the prolongations.
When a run's mesh is nested in a finer run's mesh, these searches go through that mesh,
which is small, instead of the reference's: a fine cell inside a cell of the finer mesh
lies inside that cell's coarse cell. Then :func:`displacement_errors` walks the
reference levels once: the projection ``Pi_ref u_ref`` of a level and its norms serve
every run that has that level. Each number is the one the level alone gives.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..mesh.locate import NonNestedMeshError, match_vertices, nested_cells
from ..mesh.polymesh import Mesh
from ..vem.projection import LinearFields
from .norms import (
    ProjectedNorms,
    nested_difference_norms_sq,
    nested_offsets,
    relative_error,
    wear_error,
)
from .prolong import contact_prolongation, prolongation

__all__ = ["Pair", "displacement_errors", "pairs", "wear_errors"]

#: ``(reference levels, Pi_ref u_ref there) -> [(L2^2, H1semi^2) per level]``.
RefSq = Callable[[NDArray[np.int64], LinearFields], list[tuple[float, float]]]


@dataclass(eq=False)
class Pair:
    """A coarse run against the reference: its operators and its error arrays.

    Attributes
    ----------
    mesh : Mesh
        The coarse mesh.
    idx : (n_coarse_points,) int array
        The reference vertex of every coarse vertex.
    cells : (n_ref_cells,) int array
        The coarse cell of every reference cell.
    ic, ir : (J,) int arrays
        The common levels in the coarse and the reference grids.
    disp, wear, absolute : dict of str to (J,) arrays
        The relative and the absolute errors by variant, NaN until computed.
    Pu : sparse matrix or None
        The mean value prolongation to the reference vertices, once built.
    offsets : (dx0, dx1) or None
        :func:`~vemwear.post.norms.nested_offsets` of the two meshes, once computed.
    """

    mesh: Mesh
    idx: NDArray[np.int64]
    cells: NDArray[np.int64]
    ic: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    ir: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    disp: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    wear: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    absolute: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    Pu: sp.csr_matrix | None = None
    offsets: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    def put(self, kind: str, key: str, j: int, err_sq: float, ref_sq: float) -> None:
        """Store the error of the variant ``key`` of ``kind`` ("u" or "w") at common level
        ``j`` from the squares of the error and of the reference norm."""
        e = relative_error(math.sqrt(max(err_sq, 0.0)), math.sqrt(max(ref_sq, 0.0)))
        (self.disp if kind == "u" else self.wear)[key][j] = e.relative
        self.absolute[f"{kind}_{key}"][j] = e.error


def pairs(meshes: Sequence[Mesh], fine: Mesh, tol: float | None) -> list[Pair]:
    """The fine vertex of every coarse vertex and the coarse cell of every fine cell, for
    each coarse mesh (in the order given).

    The meshes are located from the finest: a mesh nested in a finer one already located
    is located through it (its vertices among that mesh's, its cells around that mesh's
    cells), the others directly in ``fine``.

    Raises
    ------
    NonNestedMeshError
        If a mesh is not nested in ``fine``.
    """
    done: list[Pair | None] = [None] * len(meshes)
    finer: list[Pair] = []  # located so far, finest first
    for i in sorted(range(len(meshes)), key=lambda i: -meshes[i].n_cells):
        m = meshes[i]
        p = None
        for f in reversed(finer):  # the coarsest first: the cheapest search
            if f.mesh.n_cells <= m.n_cells:
                continue
            try:
                idx = match_vertices(m.points, f.mesh.points, tol=tol)
                cells = nested_cells(m, f.mesh, tol=tol)
            except NonNestedMeshError:
                continue
            p = Pair(m, f.idx[idx], cells[f.cells])
            break
        if p is None:
            p = Pair(
                m, match_vertices(m.points, fine.points, tol=tol), nested_cells(m, fine, tol=tol)
            )
        done[i] = p
        finer.append(p)
    return [p for p in done if p is not None]


def prolongations(p: Pair, fine: Mesh, tol: float | None) -> sp.csr_matrix:
    """The mean value prolongation of the coarse mesh of ``p`` to the fine vertices."""
    # a fine vertex lies in the closure of the coarse cell of any fine cell around it
    vertex_cell = np.full(fine.n_points, -1, dtype=np.int64)
    vertex_cell[fine.cell_vertices] = p.cells[fine.edge_cells]
    return prolongation(p.mesh, fine.points, tol=tol, cells=vertex_cell, vertices=p.idx)


def displacement_errors(
    items: Sequence[tuple[Pair, ProjectedNorms, NDArray[np.float64], NDArray[np.int64]]],
    ref_u: NDArray[np.float64],
    ref_at: NDArray[np.int64],
    fine: ProjectedNorms,
    ref_sq: RefSq,
    block: int,
    tol: float | None,
    secondary: str = "common",
) -> None:
    """The displacement variants of every pair at its common levels where both
    displacements are stored, a block of reference levels at a time.

    Parameters
    ----------
    items : sequence of (Pair, ProjectedNorms, u, stored)
        Each pair with the norms of its coarse mesh, its displacements (S, n, 2) and,
        per common level, the index of its displacement in ``u`` (-1: not stored).
    ref_u : (S_ref, n_ref, 2) array
        The reference displacements.
    ref_at : (L_ref,) int array
        Per reference level, the index of its displacement in ``ref_u`` (-1: none).
    fine : ProjectedNorms
        Of the reference mesh.
    ref_sq : callable
        ``(L2^2, H1semi^2)`` of ``Pi_ref u_ref`` per level of a block of fields.
    block : int
        Reference levels per block.
    tol : float, optional
        Tolerance of the point searches of the prolongation.
    secondary : {"common", "final"}
        The secondary variants (``H1_coarse``, ``H1semi_meanvalue``) at every common
        level, or only at the last (``t = T``; NaN at the others).
    """
    todo = []  # (pair, common levels) with both displacements stored
    for p, _cn, _u, stored in items:
        todo.append(np.flatnonzero((stored >= 0) & (ref_at[p.ir] >= 0)))
    if not any(jj.size for jj in todo):
        return
    levels = np.unique(np.concatenate([p.ir[jj] for (p, *_), jj in zip(items, todo, strict=True)]))
    if secondary not in ("common", "final"):
        raise ValueError(f"secondary must be 'common' or 'final', got {secondary!r}")
    for first in range(0, len(levels), block):
        lv = levels[first : first + block]
        fr_all = fine.projection.many(ref_u[ref_at[lv]])
        ref_all = ref_sq(lv, fr_all)
        for (p, cn, u, stored), jj in zip(items, todo, strict=True):
            jj = jj[np.isin(p.ir[jj], lv)]
            if jj.size == 0:
                continue
            sel = np.searchsorted(lv, p.ir[jj])
            whole = len(sel) == len(lv)  # then sel is 0, 1, ...: the block itself
            fr = (
                fr_all
                if whole
                else LinearFields(fr_all.xbar, fr_all.value[sel], fr_all.gradient[sel])
            )
            ref = [ref_all[i] for i in sel.tolist()]
            last = secondary == "final"
            sec = np.flatnonzero(jj == len(p.ic) - 1) if last else np.arange(len(jj))
            if sec.size and p.Pu is None:
                p.Pu = prolongations(p, fine.mesh, tol)
            _levels(p, cn, fine, u[stored[jj]], ref_u[ref_at[p.ir[jj]]], fr, ref, jj, sec)


def _levels(
    p: Pair,
    cn: ProjectedNorms,
    fine: ProjectedNorms,
    uh: NDArray[np.float64],
    ur: NDArray[np.float64],
    fr: LinearFields,
    ref: list[tuple[float, float]],
    jj: NDArray[np.int64],
    sec: NDArray[np.int64],
) -> None:
    """The displacement variants of ``p`` at its common levels ``jj`` (one block), with
    the coarse and the reference displacements, ``Pi_ref u_ref`` and its norms there;
    the secondary variants at the levels ``jj[sec]``."""
    fh = cn.projection.many(uh)
    moments = (fine.area, fine.M1, fine.M2)
    if p.offsets is None:
        p.offsets = nested_offsets(fh.xbar, fr.xbar, p.cells)
    nested = [
        x.sum(axis=-1) for x in nested_difference_norms_sq(fh, fr, p.cells, moments, p.offsets)
    ]
    for i, j in enumerate(jj.tolist()):
        r_l2, r_semi = ref[i]
        l2, semi = float(nested[0][i]), float(nested[1][i])
        p.put("u", "H1", j, l2 + semi, r_l2 + r_semi)
        p.put("u", "H1semi", j, semi, r_semi)
    if sec.size == 0 or p.Pu is None:
        return
    n = len(sec)
    uh, ur = uh[sec], ur[sec]
    ur_h = ur[:, p.idx]
    diff = [x.sum(axis=-1) for x in cn.norms_sq(cn.projection.many(uh - ur_h))]
    at_h = [x.sum(axis=-1) for x in cn.norms_sq(cn.projection.many(ur_h))]
    mean = (p.Pu @ uh.reshape(n, -1).T).T - ur.reshape(n, -1)
    semi_mean = fine.seminorms_sq(fine.projection.many(mean)).sum(axis=-1)
    for i, s in enumerate(sec.tolist()):
        j = int(jj[s])
        l2, semi = float(diff[0][i]), float(diff[1][i])
        rl2, rsemi = float(at_h[0][i]), float(at_h[1][i])
        p.put("u", "H1_coarse", j, l2 + semi, rl2 + rsemi)
        p.put("u", "H1semi_meanvalue", j, float(semi_mean[i]), ref[s][1])


def wear_errors(
    p: Pair,
    coarse_nodes: NDArray[np.int64],
    coarse_wear: NDArray[np.float64],
    fine: Mesh,
    fine_nodes: NDArray[np.int64],
    fine_wear: NDArray[np.float64],
    cmap: NDArray[np.int64],
    tol: float | None,
) -> None:
    """The wear variants of ``p`` at every common level."""
    Pw = contact_prolongation(p.mesh, coarse_nodes, fine.points[fine_nodes], tol=tol)
    for j, (a, b) in enumerate(zip(p.ic.tolist(), p.ir.tolist(), strict=True)):
        wa, wb = coarse_wear[a], fine_wear[b]
        for key, e in (
            ("L2", wear_error(fine, fine_nodes, Pw @ wa, wb)),
            ("L2_coarse", wear_error(p.mesh, coarse_nodes, wa, wb[cmap])),
            ("nodal_coarse", wear_error(p.mesh, coarse_nodes, wa, wb[cmap], "nodal")),
        ):
            p.put("w", key, j, e.error**2, e.reference**2)
