"""What every sparse backend provides, and the dense step they share.

A *Schur factorization* factorizes an SPD matrix ``K`` once and gives

* ``S_inv``: the block of ``K^{-1}`` on a set of dofs (the contact dofs), the inverse
  of the Schur complement ``S = K_cc - K_ci K_ii^{-1} K_ic`` that a partial
  factorization leaves, and
* ``solve(b, out=None)``: ``K^{-1} b`` for a vector or an (n, k) block of right-hand
  sides, with the same factorization (the recovery of the displacement), written to
  ``out`` when given (a Fortran-ordered array of b's shape, reused block after block).

A *factorization* (any square matrix) gives ``solve(b)`` only.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from ..threads import solver_threads


class Factorization(Protocol):
    """A sparse factorization of a square matrix."""

    name: str

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]: ...


class SchurFactorization(Protocol):
    """A factorization of an SPD matrix with the Schur complement on chosen dofs.

    Attributes
    ----------
    name : the backend's name
    n : size of K
    S_inv : (c, c) block of ``K^{-1}`` on the chosen dofs (the inverse of S)
    timings : seconds spent per stage ("ordering", "factorization", "schur")
    """

    name: str
    n: int
    S_inv: NDArray[np.float64]
    timings: dict[str, float]

    def solve(
        self, b: NDArray[np.float64], out: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]: ...


#: Columns per block of the in-place passes over a dense Schur block (bounds their
#: temporaries to ``c x _BLOCK`` entries instead of ``c x c``).
_BLOCK = 512


def _lower_finite(A: NDArray[np.float64]) -> bool:
    """Whether the lower triangle of the square ``A`` is finite, column block by block."""
    c = A.shape[0]
    for j0 in range(0, c, _BLOCK):
        if not np.isfinite(np.tril(A[j0:, j0 : j0 + _BLOCK])).all():
            return False
    return True


def _mirror_lower(A: NDArray[np.float64]) -> None:
    """Overwrite the strict upper triangle of the square ``A`` with the lower one's
    transpose, in place; entries become ``x + 0.0``, as ``tril(A) + tril(A, -1).T``
    gives them (bitwise the same array, without its three ``c x c`` temporaries)."""
    c = A.shape[0]
    for j0 in range(0, c, _BLOCK):
        j1 = min(j0 + _BLOCK, c)
        D = A[j0:j1, j0:j1]
        D[...] = np.tril(D) + np.tril(D, -1).T
        A[:j0, j0:j1] = A[j0:j1, :j0].T
    np.add(A, 0.0, out=A)


def compliance_from_schur(S: NDArray[np.float64], overwrite_s: bool = False) -> NDArray[np.float64]:
    """``S^{-1}`` of an SPD Schur complement by Cholesky (LAPACK potrf and potri).

    Only the lower triangle of ``S`` is read (MUMPS, for one, returns only that
    triangle); the result is symmetric. With ``overwrite_s`` a Fortran-ordered float64
    ``S`` is overwritten by the result instead of copied (a 6336 x 6336 block, 3D
    contact on 64 x 32 x 32 hexahedra, is 320 MB); the passes after LAPACK work in
    place, so the memory needed is that of ``S`` and one copy at most.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``S`` is not positive definite (K was not SPD) or not finite.
    """
    reuse = (
        overwrite_s
        and isinstance(S, np.ndarray)
        and S.dtype == np.float64
        and S.flags.f_contiguous
        and S.flags.writeable
    )
    S = S if reuse else np.array(S, dtype=float, order="F", copy=True)
    if not _lower_finite(S):  # LAPACK would not notice NaN pivots
        raise np.linalg.LinAlgError(
            "the Schur complement on the contact dofs has non-finite entries: the "
            "stiffness overflows (material data out of range)"
        )
    potrf, potri = sla.get_lapack_funcs(("potrf", "potri"), (S,))
    with solver_threads():
        L, info = potrf(S, lower=True, overwrite_a=True, clean=False)
        if info == 0:
            inv, info2 = potri(L, lower=True, overwrite_c=True)
    if info != 0:
        raise np.linalg.LinAlgError(
            f"the Schur complement on the contact dofs is not positive definite "
            f"(leading minor {info}): the stiffness is not SPD"
        )
    if info2 != 0:  # pragma: no cover - potrf succeeded, so the factor is regular
        raise np.linalg.LinAlgError(f"inverting the Schur complement failed (info {info2})")
    _mirror_lower(inv)
    if not np.isfinite(inv).all():
        raise np.linalg.LinAlgError(
            "the inverse of the Schur complement on the contact dofs overflows: the "
            "stiffness is singular to working precision"
        )
    return inv.T  # C-ordered (as the products downstream always had it), the same values
