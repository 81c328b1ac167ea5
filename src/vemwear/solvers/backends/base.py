"""What every sparse backend provides, and the dense step they share.

A *Schur factorization* factorizes an SPD matrix ``K`` once and gives

* ``S_inv``: the block of ``K^{-1}`` on a set of dofs (the contact dofs), the inverse
  of the Schur complement ``S = K_cc - K_ci K_ii^{-1} K_ic`` that a partial
  factorization leaves, and
* ``solve(b)``: ``K^{-1} b`` for a vector or an (n, k) block of right-hand sides, with
  the same factorization (the recovery of the displacement).

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

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]: ...


def compliance_from_schur(S: NDArray[np.float64]) -> NDArray[np.float64]:
    """``S^{-1}`` of an SPD Schur complement by Cholesky (LAPACK potrf and potri).

    Only the lower triangle of ``S`` is read (MUMPS, for one, returns only that
    triangle); the result is symmetric.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``S`` is not positive definite (K was not SPD) or not finite.
    """
    S = np.array(S, dtype=float, order="F", copy=True)
    if not np.isfinite(np.tril(S)).all():  # LAPACK would not notice NaN pivots
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
    inv = np.tril(inv)
    if not np.isfinite(inv).all():
        raise np.linalg.LinAlgError(
            "the inverse of the Schur complement on the contact dofs overflows: the "
            "stiffness is singular to working precision"
        )
    return inv + np.tril(inv, -1).T
