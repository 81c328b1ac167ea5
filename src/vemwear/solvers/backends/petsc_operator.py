"""K kept by the ranks of the MPI job, and rank 0's operator of it (:class:`PetscStiffness`).

The ranks assemble the distributed matrix from their own cells
(:func:`.petsc_cells.assemble_by_cells`) and keep it for the run: MUMPS factorizes it as
it is (:class:`.petsc.PetscSchur` given the operator), and the products ``K x`` of the
equilibrium residuals are products with it over the ranks. Rank 0 never holds the
whole K: it holds the rows of K at the contact and the constrained dofs, which it
assembles itself from the cells that touch them (:meth:`vemwear.simulate.cellparts.
CellAssembly.around`: bitwise those of the whole K), and the diagonal and the absolute
row sums of K (n numbers each), summed by each rank on its rows and gathered.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..stiffness import abs_row_sums
from .petsc_cells import assemble_by_cells
from .petsc_ranks import _Local, _matrix, _Rank, _rank

__all__ = ["PetscStiffness"]


class PetscStiffness:
    """K on the free dofs, kept by the ranks, as an operator on rank 0
    (:class:`vemwear.solvers.stiffness.Stiffness`). Made on rank 0, collectively.

    Parameters
    ----------
    assembly : :class:`vemwear.simulate.cellparts.CellAssembly`
        The recipe of K that every rank receives and assembles its cells with.
    at : (r,) increasing free dofs whose rows rank 0 holds, complete
    rows : (r, n) sparse, those rows of K (bitwise the whole K's)
    partition : the split of the cells (:class:`.petsc.PetscSchur`'s ``partition``)

    Attributes
    ----------
    matrix_id : the id of the distributed matrix on every rank
    assembly_report : how the distributed matrix was made
        (:func:`.petsc_cells.assemble_by_cells`)
    """

    def __init__(
        self,
        assembly: Any,
        at: NDArray[np.int64],
        rows: sp.csr_matrix,
        partition: str = "rows",
    ) -> None:
        st = _rank()
        if st.rank != 0:
            raise RuntimeError("PetscStiffness is made on rank 0; the other ranks run serve()")
        n = len(assembly.free)
        self.shape = (n, n)
        self.matrix_id = st.next_id
        st.next_id += 1
        with st.command("stiffness", self.matrix_id):
            made = _stiffness(st, self.matrix_id, n, assembly, partition)
        assert made is not None
        sums, diag, self.assembly_report = made
        self._at = np.asarray(at, dtype=np.int64)
        self._rows = sp.csr_matrix(rows)
        # rows held here: their sums and diagonal as the whole K's (the same sums);
        # elsewhere the ranks' rows, whose interface entries add the parts of two ranks
        self._sums = sums
        self._sums[self._at] = abs_row_sums(self._rows.indptr, self._rows.data, len(self._at))
        self._diag = diag
        self._diag[self._at] = self._rows[np.arange(len(self._at)), self._at].A1

    @property
    def nnz_rank0(self) -> int:
        """The entries of K that rank 0 holds (its rows)."""
        return int(self._rows.nnz)

    def diagonal(self) -> NDArray[np.float64]:
        return self._diag.copy()

    def row_sums(self) -> NDArray[np.float64]:
        return self._sums

    def rows(self, dofs: NDArray[np.int64]) -> sp.csr_matrix:
        dofs = np.asarray(dofs, dtype=np.int64)
        pos = np.minimum(np.searchsorted(self._at, dofs), max(len(self._at) - 1, 0))
        if len(dofs) and (len(self._at) == 0 or np.any(self._at[pos] != dofs)):
            missing = dofs[self._at[pos] != dofs] if len(self._at) else dofs
            raise ValueError(
                f"the rows of K at dof {int(missing[0])} are kept by the MPI ranks, not on "
                "rank 0, which holds those of the contact and the constrained dofs"
            )
        return sp.csr_matrix(self._rows[pos])

    def __matmul__(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        x = np.asarray(x, dtype=np.float64)
        n = self.shape[0]
        if x.shape[0] != n:
            raise ValueError(f"K @ x: x has {x.shape[0]} rows, K {n}")
        k = 1 if x.ndim == 1 else x.shape[1]
        st = _rank()
        with st.command("multiply", self.matrix_id, None, k):
            Y = _multiply(st, self.matrix_id, x.reshape(n, k), k)
        assert Y is not None
        return Y[:, 0] if x.ndim == 1 else Y


def _stiffness(
    st: _Rank, mid: int, n: int = 0, assembly: Any = None, partition: str = "rows"
) -> tuple[NDArray[np.float64], NDArray[np.float64], dict[str, Any]] | None:
    """The collective making of the distributed matrix ``mid``, kept on every rank;
    returns on rank 0 the absolute row sums and the diagonal of K (each rank's rows,
    gathered in K's order) and the report of the assembly, None elsewhere."""
    n, partition = st.comm.bcast((n, partition) if st.rank == 0 else None, root=0)
    loc, (indptr, indices, data), report = assemble_by_cells(st, n, assembly, partition)
    sums = abs_row_sums(indptr, data, loc.rows)
    row = np.repeat(np.arange(loc.rows), np.diff(indptr))
    on = indices == row + loc.starts[st.rank]
    diag = np.zeros(loc.rows)
    diag[row[on]] = data[on]
    del row, on
    loc.A = _matrix(st, loc, (indptr, indices, data))
    del indptr, indices, data
    loc.x, loc.b = loc.A.createVecs()
    st.factors[mid] = loc
    sums_all, diag_all = loc.gather(sums), loc.gather(diag)
    if st.rank != 0 or sums_all is None or diag_all is None:
        return None
    return sums_all, diag_all, report


def _multiply(
    st: _Rank, mid: int, X: NDArray[np.float64] | None = None, k: int = 0
) -> NDArray[np.float64] | None:
    """``K X`` over the ranks, column by column (X on rank 0, (n, k)), on rank 0."""
    loc: _Local = st.factors[mid]
    return loc.columns(X, k, lambda: loc.A.mult(loc.b, loc.x))
