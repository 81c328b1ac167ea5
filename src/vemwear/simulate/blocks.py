"""The blocks of the stiffness K that a run keeps, assembled once.

A run solves with K on the free dofs and reads two couplings with the constrained dofs:
``K_fc`` (the lifting of prescribed values, ``K_fc u_c(t)``, and the reactions) and
``K_cc`` (the reactions to prescribed values). The whole matrix is not kept: in 3D it is
as large as the free block, a tenth of the factors; :func:`whole_stiffness` makes it
again when asked.

In an MPI run of the petsc backend (docs/mpi.md) K on the free dofs is kept by the
ranks, and this process assembles only the cells along the contact and the constrained
dofs: K's rows there, ``K_fc`` and ``K_cc`` are bitwise those of the whole matrix
(:meth:`.cellparts.CellAssembly.around`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from ..util.arrays import unique as _unique
from .cellparts import CellAssembly

if TYPE_CHECKING:
    from .problem import Problem

__all__ = [
    "DataError",
    "StiffnessBlocks",
    "cell_assembly",
    "stiffness_blocks",
    "whole_stiffness",
]


class DataError(ValueError):
    """Data that give non-finite numbers (an overflow), named with the quantity."""


@dataclasses.dataclass(frozen=True)
class StiffnessBlocks:
    """K on the free dofs (a SciPy matrix, or the MPI ranks' operator of it), and its
    couplings with the constrained dofs: ``K_fc`` (free x constrained) and ``K_cc``
    (constrained x constrained; empty when every prescribed value is zero)."""

    K: Any
    K_fc: sp.csr_matrix
    K_cc: sp.csr_matrix


def whole_stiffness(problem: Problem) -> sp.csr_matrix:
    """The stiffness on all dofs, with the rigid parts' ties (docs/method.md 1d)."""
    ties = problem.constraints.ties
    with np.errstate(all="ignore"):
        K = problem.space.stiffness(problem.material, problem.stabilization)
        return K if ties is None else ties.tie(K)  # Q^T K Q


def stiffness_blocks(problem: Problem, assembly: CellAssembly | None = None) -> StiffnessBlocks:
    """The blocks of K a run keeps: from the whole matrix, which is not kept; or, given
    the ``assembly`` of K by cells (:func:`cell_assembly`), K kept by the MPI ranks,
    which assemble it from their cells, and the rest from the cells along the contact
    and the constrained dofs.

    Raises
    ------
    DataError
        When the material gives non-finite entries.
    """
    con = problem.constraints
    if assembly is not None:
        return _distributed(problem, assembly)
    K_full = whole_stiffness(problem)
    _check_finite(problem, K_full)
    K_rows = K_full[con.free]  # the rows of the free dofs, sliced once
    K = K_rows[:, con.free].tocsr()
    K_cc = sp.csr_matrix((0, 0)) if con.zero else K_full[con.dofs][:, con.dofs].tocsr()
    return StiffnessBlocks(K, K_rows[:, con.dofs].tocsr(), K_cc)


def _distributed(problem: Problem, assembly: CellAssembly) -> StiffnessBlocks:
    """K kept by the MPI ranks (:class:`~vemwear.solvers.backends.petsc_operator.
    PetscStiffness`) with its rows at the contact dofs; the constrained dofs' blocks."""
    from ..solvers.backends.petsc_operator import PetscStiffness

    con, cb, space = problem.constraints, problem.contact, problem.space
    if cb.trace is None:
        contact = (int(space.dim) * cb.nodes[:, None] + np.arange(space.dim)).ravel()
    else:
        contact = _unique(sp.csr_matrix(cb.trace).indices)
    near = assembly.around(np.union1d(contact, con.dofs))
    _check_finite(problem, near)
    index = -np.ones(space.n_dofs, dtype=np.int64)
    index[con.free] = np.arange(len(con.free))
    at = index[contact]
    at = _unique(at[at >= 0])  # the free contact dofs, increasing
    near_rows = near[con.free]
    K_fc = near_rows[:, con.dofs].tocsr()
    K_cc = sp.csr_matrix((0, 0)) if con.zero else near[con.dofs][:, con.dofs].tocsr()
    rows = near_rows[at][:, con.free].tocsr()
    del near, near_rows
    return StiffnessBlocks(PetscStiffness(assembly, at, rows), K_fc, K_cc)


def cell_assembly(problem: Problem) -> CellAssembly:
    """K on the free dofs as a sum over cells (what the MPI ranks assemble)."""
    con = problem.constraints
    return CellAssembly(problem.space, problem.material, problem.stabilization, con.free, con.ties)


def _check_finite(problem: Problem, K: sp.csr_matrix) -> None:
    if not np.all(np.isfinite(K.data)):
        mat = problem.material
        raise DataError(
            f"[material] lam = {mat.lam:g}, eta = {mat.eta:g} give a stiffness matrix with "
            "non-finite entries (an overflow); use values of a sensible scale"
        )
