"""What the step problem reads of the stiffness K, whether held or distributed.

A serial run holds K on the free dofs as a SciPy CSR matrix. An MPI run (the petsc
backend, docs/mpi.md) does not: the ranks hold its rows, and rank 0 holds a
:class:`Stiffness` operator, which gives what the level loop reads of K: its shape, its
diagonal, its absolute row sums (the scales of the KKT residuals), its rows at the
dofs rank 0 holds (the contact dofs: the block elimination of every solve) and the
products ``K x`` of vectors and blocks (the equilibrium residuals).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

__all__ = ["ROW_CHUNK", "Stiffness", "abs_row_sums"]

#: rows of K whose absolute values are taken at once (:func:`abs_row_sums`)
ROW_CHUNK = 1 << 16


@runtime_checkable
class Stiffness(Protocol):
    """K on the free dofs as an operator (not a SciPy matrix)."""

    @property
    def shape(self) -> tuple[int, int]: ...

    def diagonal(self) -> NDArray[np.float64]:
        """The diagonal of K, (n,)."""
        ...

    def row_sums(self) -> NDArray[np.float64]:
        """The absolute row sums of K, (n,)."""
        ...

    def rows(self, dofs: NDArray[np.int64]) -> sp.csr_matrix:
        """The rows ``dofs`` of K, (len(dofs), n)."""
        ...

    def __matmul__(self, x: NDArray[np.float64]) -> Any:
        """``K x`` of a vector (n,) or a block (n, k)."""
        ...


def abs_row_sums(
    indptr: NDArray[np.integer], data: NDArray[np.float64], n: int
) -> NDArray[np.float64]:
    """The absolute row sums of the CSR rows ``(indptr, data)``, (n,): row by row from
    the left, as a product of ``|K|`` with ones sums them, without a copy of K (as large
    as the factors' tenth in 3D) and in chunks of rows."""
    out = np.zeros(n)
    for start in range(0, n, ROW_CHUNK):
        stop = min(start + ROW_CHUNK, n)
        lo, hi = indptr[start], indptr[stop]
        rows = slice(start, stop)
        filled = indptr[start + 1 : stop + 1] > indptr[rows]  # reduceat: no empty rows
        if lo < hi:
            sums = np.add.reduceat(np.abs(data[lo:hi]), indptr[rows][filled] - lo)
            out[rows][filled] = sums
    return out
