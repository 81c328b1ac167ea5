"""SciPy's SuperLU: the backend that is always available.

:class:`SuperLUFactor` factorizes any square sparse matrix (the full-space Newton
path and Uzawa). :class:`SuperLUSchur` factorizes the SPD stiffness with the contact
dofs eliminated last and reads the Schur complement onto them from the trailing block
of the factors; SuperLU has no partial factorization, so this builds all of ``U``.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from ..threads import solver_threads
from .base import compliance_from_schur
from .ordering import nested_dissection


class SuperLUFactor:
    """SuperLU with a symmetric fill-reducing ordering (symmetric mode for SPD matrices)."""

    name = "scipy"

    def __init__(self, A: sp.spmatrix, symmetric: bool = True) -> None:
        opts = {"SymmetricMode": True} if symmetric else {}
        with solver_threads():
            self.lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", options=opts)

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        with solver_threads():
            return self.lu.solve(np.asarray(b, dtype=float))


def _schur_ordering(
    K: sp.csr_matrix, last: NDArray[np.int64], points: NDArray[np.float64]
) -> NDArray[np.int64]:
    """Nested dissection of the dofs with ``last`` at the end (by vertex pairs when the
    dofs come in (x, y) pairs at the same point, which halves the graph)."""
    n = K.shape[0]
    paired = (
        n % 2 == 0
        and np.array_equal(points[0::2], points[1::2])
        and len(last) % 2 == 0
        and np.all(last[0::2] % 2 == 0)
        and np.array_equal(last[1::2], last[0::2] + 1)
    )
    if not paired:
        return nested_dissection(abs(K).tocsr(), points, last)
    pair = sp.csr_matrix((np.ones(n), (np.arange(n), np.arange(n) // 2)), shape=(n, n // 2))
    adj = (pair.T @ abs(K) @ pair).tocsr()
    vorder = nested_dissection(adj, points[0::2], last[0::2] // 2)
    return np.column_stack([2 * vorder, 2 * vorder + 1]).ravel()


class SuperLUSchur:
    """SuperLU factorization of an SPD matrix with the dofs ``last`` eliminated last.

    The rest is ordered by geometric nested dissection (:mod:`.ordering`). With the
    diagonal pivots SuperLU takes on SPD matrices, ``P K P^T = L U`` and the trailing
    block gives the Schur complement onto ``last``:
    ``S = K_cc - K_ci K_ii^{-1} K_ic = L_cc U_cc``. Its inverse ``S_inv`` is the block of
    ``K^{-1}`` on ``last``.

    Parameters
    ----------
    K : (n, n) sparse SPD matrix
    last : (c,) dof ids of the Schur block, in this order
    points : (n, 2) coordinates of each dof's vertex, for the ordering
    """

    name = "scipy"

    def __init__(
        self, K: sp.spmatrix, last: NDArray[np.int64], points: NDArray[np.float64]
    ) -> None:
        self.timings: dict[str, float] = {}
        tick = time.perf_counter()
        n = K.shape[0]
        last = np.asarray(last, dtype=np.int64).ravel()
        K = sp.csr_matrix(K)
        self.perm = _schur_ordering(K, last, np.asarray(points, dtype=float))
        Kp = K[self.perm][:, self.perm].tocsc()
        self.timings["ordering"] = time.perf_counter() - tick
        with solver_threads():
            tick = time.perf_counter()
            self.lu = spla.splu(
                Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True}
            )
            self.timings["factorization"] = time.perf_counter() - tick
            tick = time.perf_counter()
            self.S_inv = self._trailing_inverse(n, len(last))
            self.timings["schur"] = time.perf_counter() - tick
        self.n = n

    def _trailing_inverse(self, n: int, c: int) -> NDArray[np.float64]:
        """The block of ``K^{-1}`` on the trailing ``c`` dofs of the permuted matrix."""
        tail = np.arange(n - c, n)
        if not (
            np.array_equal(self.lu.perm_c[n - c :], tail)
            and np.array_equal(self.lu.perm_r[n - c :], tail)
        ):  # SuperLU moved the trailing dofs: solves for the block of K^{-1}
            E = np.zeros((n, c))
            E[tail, np.arange(c)] = 1.0
            C = self.lu.solve(E)[tail]
            return 0.5 * (C + C.T)
        # SPD without pivoting: U = D L^T, so S = L22 U22 = U22^T D22^{-1} U22
        U22 = self.lu.U[:, n - c :][n - c :].toarray()
        return compliance_from_schur(U22.T @ (U22 / np.diag(U22)[:, None]))

    def solve(
        self, b: NDArray[np.float64], out: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """``K^{-1} b`` for a vector or an (n, k) block of right-hand sides, written to
        ``out`` when given (an array of b's shape)."""
        b = np.asarray(b, dtype=float)
        with solver_threads():
            xp = self.lu.solve(np.ascontiguousarray(b[self.perm]))
        x = np.empty_like(xp) if out is None else out
        if x.shape != xp.shape:
            raise ValueError("solve: out must have b's shape")
        x[self.perm] = xp
        return x
