"""Sparse direct factorizations behind one interface, with an optional faster backend.

``factorize(A)`` returns an object with ``solve(b)`` for a vector or a block of
right-hand sides. SciPy's SuperLU is always available. PARDISO (``pypardiso``, the
``fast`` extra) factorizes large matrices several times faster but back-substitutes
more slowly on this project's matrices (``benchmarks/bench_backends.py``), so
``"auto"`` picks it only where factorizations dominate: ``factorize(A, "auto",
many_factorizations=True)`` for matrices above :data:`PARDISO_MIN_SIZE` unknowns
(the full-space Newton path). The condensed Newton path always uses SuperLU, whose
factors give the Schur complement (:class:`SchurFactor`).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from .ordering import nested_dissection

BACKENDS = ("auto", "scipy", "pardiso")

#: Below this many unknowns SuperLU factorizes about as fast as PARDISO.
PARDISO_MIN_SIZE = 20_000


def _have_pardiso() -> bool:
    try:
        import pypardiso  # noqa: F401
    except Exception:
        return False
    return True


class SuperLUFactor:
    """SuperLU with a symmetric fill-reducing ordering (symmetric mode for SPD matrices)."""

    name = "scipy"

    def __init__(self, A: sp.spmatrix, symmetric: bool = True) -> None:
        opts = {"SymmetricMode": True} if symmetric else {}
        self.lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", options=opts)

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.lu.solve(np.asarray(b, dtype=float))


class PardisoFactor:
    """Intel MKL PARDISO through pypardiso (factorization kept between solves)."""

    name = "pardiso"

    def __init__(self, A: sp.spmatrix) -> None:
        import pypardiso

        self.solver = pypardiso.PyPardisoSolver()
        self.solver.set_matrix_type(11)  # real nonsymmetric: robust, uses the full pattern
        self.A = sp.csr_matrix(A)
        self.A.sort_indices()
        self.solver.factorize(self.A)
        self.solver.set_phase(33)  # solve only, with the factorization above

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        # pypardiso's public solve() compares the whole matrix with the factorized one
        # on every call; the matrix is fixed here, so call the solve phase directly
        b = np.asfortranarray(b, dtype=float)
        return np.asarray(self.solver._call_pardiso(self.A, b))


def resolve_backend(backend: str = "auto", size: int = 0, many_factorizations: bool = False) -> str:
    """The backend that ``factorize`` uses for a matrix of ``size`` unknowns."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown linear-algebra backend {backend!r}; expected one of {BACKENDS}")
    if backend == "auto":
        fast = many_factorizations and size >= PARDISO_MIN_SIZE and _have_pardiso()
        return "pardiso" if fast else "scipy"
    if backend == "pardiso" and not _have_pardiso():
        raise ValueError(
            "backend 'pardiso' asked for but pypardiso is not installed "
            "(pip install 'vemwear[fast]')"
        )
    return backend


def factorize(
    A: sp.spmatrix,
    backend: str = "auto",
    *,
    symmetric: bool = True,
    many_factorizations: bool = False,
):
    """Factorize a sparse matrix once; the result solves for any number of right-hand sides.

    ``symmetric`` lets SuperLU use its symmetric mode (SPD matrices); PARDISO always
    factorizes as a general matrix. ``many_factorizations`` tells ``"auto"`` that the
    caller factorizes again and again (see :func:`resolve_backend`).
    """
    chosen = resolve_backend(backend, A.shape[0], many_factorizations)
    return PardisoFactor(A) if chosen == "pardiso" else SuperLUFactor(A, symmetric=symmetric)


class SchurFactor:
    """SuperLU factorization of an SPD matrix with the dofs ``last`` eliminated last.

    The rest is ordered by geometric nested dissection (:mod:`.ordering`). With the
    diagonal pivots SuperLU takes on SPD matrices, ``P K P^T = L U`` and the trailing
    block gives the Schur complement onto ``last`` for free:
    ``S = K_cc - K_ci K_ii^{-1} K_ic = L_cc U_cc``. Its inverse is the block of
    ``K^{-1}`` on ``last``, so condensing onto the contact dofs costs no extra solves.

    Parameters
    ----------
    K : (n, n) sparse SPD matrix
    last : (c,) dof ids to eliminate last (in this order)
    points : (n, 2) coordinates of each dof's vertex, for the ordering
    """

    name = "scipy"

    def __init__(
        self, K: sp.spmatrix, last: NDArray[np.int64], points: NDArray[np.float64]
    ) -> None:
        tick = time.perf_counter()
        self.timings: dict[str, float] = {}
        n = K.shape[0]
        last = np.asarray(last, dtype=np.int64).ravel()
        K = sp.csr_matrix(K)
        paired = (
            n % 2 == 0
            and np.array_equal(points[0::2], points[1::2])
            and len(last) % 2 == 0
            and np.all(last[0::2] % 2 == 0)
            and np.array_equal(last[1::2], last[0::2] + 1)
        )
        if paired:  # order vertices (pairs of dofs), which halves the graph
            pair = sp.csr_matrix((np.ones(n), (np.arange(n), np.arange(n) // 2)), shape=(n, n // 2))
            adj = (pair.T @ abs(K) @ pair).tocsr()
            vorder = nested_dissection(adj, points[0::2], last[0::2] // 2)
            perm = np.column_stack([2 * vorder, 2 * vorder + 1]).ravel()
        else:
            perm = nested_dissection(abs(K).tocsr(), points, last)
        self.perm = perm
        Kp = K[perm][:, perm].tocsc()
        self.timings["ordering"] = time.perf_counter() - tick
        tick = time.perf_counter()
        self.lu = spla.splu(
            Kp, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True}
        )
        self.timings["factorization"] = time.perf_counter() - tick
        tick = time.perf_counter()
        c = len(last)
        tail = np.arange(n - c, n)
        if not (
            np.array_equal(self.lu.perm_c[n - c :], tail)
            and np.array_equal(self.lu.perm_r[n - c :], tail)
        ):
            # SuperLU moved the trailing dofs: fall back to solves for the block of K^{-1}
            E = np.zeros((n, c))
            E[tail, np.arange(c)] = 1.0
            self.S_inv = self.lu.solve(E)[tail]
        else:
            # SPD without pivoting: U = D L^T, so S = L22 U22 = U22^T D22^{-1} U22
            U22 = self.lu.U[:, n - c :][n - c :].toarray()
            S = U22.T @ (U22 / np.diag(U22)[:, None])
            S = 0.5 * (S + S.T)
            self.S_inv = sla.cho_solve(sla.cho_factor(S), np.eye(c))
        self.timings["schur"] = time.perf_counter() - tick
        self.n = n

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        b = np.asarray(b, dtype=float)
        xp = self.lu.solve(np.ascontiguousarray(b[self.perm]))
        x = np.empty_like(xp)
        x[self.perm] = xp
        return x
