"""Sparse direct factorizations behind one interface, with an optional faster backend.

``factorize(A)`` returns an object with ``solve(b)`` for a vector or a block of
right-hand sides. SciPy's SuperLU is the default; PARDISO (``pypardiso``) is used
when installed and ``backend="auto"`` or ``"pardiso"`` is asked for.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

BACKENDS = ("auto", "scipy", "pardiso")


def _have_pardiso() -> bool:
    try:
        import pypardiso  # noqa: F401
    except Exception:
        return False
    return True


class SuperLUFactor:
    """SuperLU with a symmetric fill-reducing ordering (the matrices here are SPD)."""

    name = "scipy"

    def __init__(self, A: sp.spmatrix) -> None:
        self.lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A",
                            options={"SymmetricMode": True})

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

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        b = np.ascontiguousarray(b, dtype=float)
        return np.asarray(self.solver.solve(self.A, b))


def resolve_backend(backend: str = "auto") -> str:
    if backend not in BACKENDS:
        raise ValueError(f"unknown linear-algebra backend {backend!r}; expected one of {BACKENDS}")
    if backend == "auto":
        return "pardiso" if _have_pardiso() else "scipy"
    if backend == "pardiso" and not _have_pardiso():
        raise ValueError("backend 'pardiso' asked for but pypardiso is not installed "
                         "(pip install 'vemwear[fast]')")
    return backend


def factorize(A: sp.spmatrix, backend: str = "auto"):
    """Factorize a sparse matrix once; the result solves for any number of right-hand sides."""
    return PardisoFactor(A) if resolve_backend(backend) == "pardiso" else SuperLUFactor(A)
