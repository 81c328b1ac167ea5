"""Intel MKL PARDISO through its C routine ``pardiso`` in MKL's single dynamic library.

``mkl_rt`` is looked up where the ``mkl`` wheel (a dependency of ``pypardiso``) puts
it, ``$PYPARDISO_MKL_RT`` first; pypardiso's own search (which walks the whole
installation) is only the last resort.

:class:`PardisoSchur` factorizes the SPD stiffness (``mtype = 2``, Cholesky) with the
Schur option ``iparm[35] = 2``: the rows marked in ``perm`` (the contact dofs) are
left out of the factorization, which returns their Schur complement
``S = K_cc - K_ci K_ii^{-1} K_ic`` as a dense matrix and keeps the factors of
``K_ii``. Block solves with ``K`` use the same factorization (phase 33, which
completes the elimination with the Schur block; the partial phases 331/333 with the
dense ``S_inv`` in between give the same result but were 1.3-1.8 times slower in
``benchmarks/bench_backends.py``). No factor of the whole matrix is formed in the
factorization phase.

In 3D the Schur factorization costs about twice the flops of a plain Cholesky of the
same ``K`` (``benchmarks/bench_schur3d.py``): with the contact dofs last, every front
above the contact face carries the face's dofs. PARDISO offers no cheaper way to the
same block: its partial solve with sparse right-hand sides (``iparm[30]``) orders the
marked dofs last as well (the same fill, and its solves for the block are slower than
the Schur output), a user ordering (``iparm[4] = 1``) of PARDISO's own nested
dissection with the contact dofs moved last has 5 times the fill (hexahedra
32 x 16 x 16), and ``iparm[35] = 1``, ``iparm[23] = 0`` or ``10`` and serial METIS
were not faster than the settings below.

:class:`PardisoFactor` factorizes any square matrix (real nonsymmetric, ``mtype =
11``, or SPD, ``mtype = 2``) for the full-space Newton path and Uzawa.

The handle ``pt`` of a factorization is released (phase -1) when its object is
garbage collected.
"""

from __future__ import annotations

import ctypes
import glob
import os
import site
import sys
import time
import weakref
from functools import cache
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ...util.arrays import unique as _unique
from ..threads import solver_threads
from .base import compliance_from_schur

_ERRORS = {
    -1: "input inconsistent",
    -2: "not enough memory",
    -3: "reordering problem",
    -4: "zero pivot: the matrix is not positive definite (or is singular)",
    -5: "unclassified internal error",
    -6: "reordering failed",
    -7: "diagonal matrix is singular",
    -8: "32-bit integer overflow",
    -9: "not enough memory for out-of-core",
    -10: "error opening out-of-core files",
    -11: "read/write error with out-of-core files",
    -12: "wrong PARDISO version for the 64-bit interface",
    -13: "interrupted",
    -15: "Schur complement error",
}


def available() -> bool:
    """True when MKL's PARDISO can be loaded (``pypardiso`` installed with MKL)."""
    try:
        _routine()
    except Exception:
        return False
    return True


def _mkl_rt() -> Any:
    """MKL's runtime library, loaded with ctypes.

    Idle OpenMP threads of MKL spin for 1 ms after each parallel region, not for
    OpenMP's default 200 ms (``KMP_BLOCKTIME=1`` unless set already): spinning that
    long takes the cores of a machine with few or busy cores from the work that
    follows (the factorization time varied by more than a factor two), while sleeping
    at once (0) makes every phase of a small problem wake its threads again (with 0,
    the floor of the 32 x 16 run in ``benchmarks/bench_getfem.py`` is about 10 % higher;
    ``benchmarks/bench_speed.py --reference`` shows no difference at 1/256).
    """
    os.environ.setdefault("KMP_BLOCKTIME", "1")
    env = os.environ.get("PYPARDISO_MKL_RT")
    candidates = [env] if env else []
    for root in dict.fromkeys((sys.prefix, sys.base_prefix, site.USER_BASE or "")):
        if root:
            candidates += sorted(glob.glob(os.path.join(root, "lib", "libmkl_rt.so*")))
            candidates += sorted(glob.glob(os.path.join(root, "Library", "bin", "mkl_rt*.dll")))
    for path in candidates:
        try:
            return ctypes.CDLL(path)
        except OSError:
            continue
    import pypardiso  # searches everywhere; raises when MKL is missing

    return pypardiso.ps.libmkl


@cache
def _thread_functions() -> tuple[Any, Any]:
    """MKL's ``mkl_get_max_threads`` and ``mkl_set_num_threads_local``."""
    lib = _mkl_rt()
    get, local = lib.MKL_Get_Max_Threads, lib.MKL_Set_Num_Threads_Local
    get.argtypes, get.restype = [], ctypes.c_int
    local.argtypes, local.restype = [ctypes.c_int], ctypes.c_int
    return get, local


@cache
def _routine() -> Any:
    """MKL's ``pardiso`` C routine with its argument types."""
    f = _mkl_rt().pardiso
    i32p = ctypes.POINTER(ctypes.c_int32)
    f.argtypes = [
        ctypes.POINTER(ctypes.c_int64),  # pt
        i32p,  # maxfct
        i32p,  # mnum
        i32p,  # mtype
        i32p,  # phase
        i32p,  # n
        ctypes.c_void_p,  # a
        i32p,  # ia
        i32p,  # ja
        i32p,  # perm
        i32p,  # nrhs
        i32p,  # iparm
        i32p,  # msglvl
        ctypes.c_void_p,  # b
        ctypes.c_void_p,  # x
        i32p,  # error
    ]
    f.restype = None
    return f


class _Handle:
    """One PARDISO factorization: the matrix in 0-based CSR, ``pt``, ``iparm``, ``perm``."""

    def __init__(self, A: sp.csr_matrix, mtype: int, iparm: dict[int, int], perm=None) -> None:
        self.f = _routine()
        self.n = A.shape[0]
        self.mtype = mtype
        self.a = np.ascontiguousarray(A.data, dtype=np.float64)
        self.ia = np.ascontiguousarray(A.indptr, dtype=np.int32)
        self.ja = np.ascontiguousarray(A.indices, dtype=np.int32)
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        self.iparm[0] = 1  # the values below, zero (default) elsewhere
        self.iparm[34] = 1  # 0-based indexing
        for k, v in iparm.items():
            self.iparm[k] = v
        self.perm = np.zeros(self.n, dtype=np.int32) if perm is None else perm
        self.live = False
        #: MKL threads of the analysis and factorization, pinned for every later phase
        self.threads = 0

    def __call__(self, phase: int, b: NDArray, x: NDArray, nrhs: int = 1) -> None:
        # A solve must run with the thread count of the factorization: MKL 2026's
        # one-column solve after a Schur factorization returns garbage otherwise (a
        # backward error of 1e2-1e8 when a caller changes MKL's threads in between,
        # e.g. with threadpoolctl; tests/test_backends.py)
        get_threads, set_local = _thread_functions()
        if self.threads == 0:
            self.threads = int(get_threads())
        previous = set_local(self.threads)
        try:
            self._call(phase, b, x, nrhs)
        finally:
            set_local(previous)

    def _call(self, phase: int, b: NDArray, x: NDArray, nrhs: int) -> None:
        i32 = ctypes.c_int32
        i32p = ctypes.POINTER(i32)
        err = i32(0)
        self.f(
            self.pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
            ctypes.byref(i32(1)),
            ctypes.byref(i32(1)),
            ctypes.byref(i32(self.mtype)),
            ctypes.byref(i32(phase)),
            ctypes.byref(i32(self.n)),
            self.a.ctypes.data,
            self.ia.ctypes.data_as(i32p),
            self.ja.ctypes.data_as(i32p),
            self.perm.ctypes.data_as(i32p),
            ctypes.byref(i32(nrhs)),
            self.iparm.ctypes.data_as(i32p),
            ctypes.byref(i32(0)),
            b.ctypes.data,
            x.ctypes.data,
            ctypes.byref(err),
        )
        if phase > 0:
            self.live = True
        if err.value != 0:
            why = _ERRORS.get(err.value, "unknown error")
            raise RuntimeError(f"PARDISO phase {phase} failed with error {err.value}: {why}")

    def release(self) -> None:
        """Free PARDISO's internal memory (phase -1)."""
        if self.live:
            self.live = False
            dummy = np.zeros(1)
            self(-1, dummy, dummy)


def _block(b: NDArray, n: int) -> tuple[NDArray, int]:
    """Right-hand sides as a Fortran-ordered (n, k) float array, and k."""
    b = np.asarray(b, dtype=np.float64)
    if b.shape[0] != n:
        raise ValueError(f"right-hand side has {b.shape[0]} rows, the matrix {n}")
    k = 1 if b.ndim == 1 else b.shape[1]
    return np.asfortranarray(b.reshape(n, k)), k


def _upper(A: sp.csr_matrix) -> sp.csr_matrix:
    """The upper triangle (with the diagonal) of a square CSR matrix, the entries of
    ``sp.triu`` in the same order (sorted indices), without its round trip through COO."""
    if not A.has_canonical_format:  # sorted indices, no repeated entries, as from COO
        A = A.copy()
        A.sum_duplicates()
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    keep = A.indices >= rows
    indptr = np.zeros(A.shape[0] + 1, dtype=A.indptr.dtype)
    np.cumsum(np.bincount(rows[keep], minlength=A.shape[0]), out=indptr[1:])
    return sp.csr_matrix((A.data[keep], A.indices[keep], indptr), shape=A.shape)


def _transpose_in_place(A: NDArray[np.float64], block: int = 512) -> None:
    """Overwrite the square C-ordered ``A`` with its transpose, tile by tile (a copy
    of one ``block x block`` tile at a time instead of one of ``A``)."""
    c = A.shape[0]
    for i0 in range(0, c, block):
        i1 = min(i0 + block, c)
        D = A[i0:i1, i0:i1]
        D[...] = D.T.copy()
        for j0 in range(i1, c, block):
            j1 = min(j0 + block, c)
            upper = A[i0:i1, j0:j1].copy()
            A[i0:i1, j0:j1] = A[j0:j1, i0:i1].T
            A[j0:j1, i0:i1] = upper.T


def _output(out: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``out`` as the (n, k) Fortran-ordered block PARDISO writes (a view), checked."""
    if out.shape != np.shape(b) or out.dtype != np.float64 or not out.flags.f_contiguous:
        raise ValueError("solve: out must be a Fortran-ordered float64 array of b's shape")
    return out.reshape(len(out), -1, order="F")


class PardisoFactor:
    """PARDISO factorization of a square sparse matrix; SPD (Cholesky) when ``spd``."""

    name = "pardiso"

    def __init__(self, A: sp.spmatrix, spd: bool = False) -> None:
        A = sp.csr_matrix(A, dtype=np.float64)
        if spd:
            A = sp.triu(A, format="csr")
            settings = {1: 2}  # METIS ordering
        else:  # METIS, pivot perturbation 1e-13, scaling and matching
            settings = {1: 2, 9: 13, 10: 1, 12: 1}
        A.sort_indices()
        self._h = _Handle(A, 2 if spd else 11, settings)
        weakref.finalize(self, self._h.release)
        dummy = np.zeros(1)
        with solver_threads():
            self._h(12, dummy, dummy)

    def solve(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        B, k = _block(b, self._h.n)
        X = np.zeros_like(B)
        with solver_threads():
            self._h(33, B, X, k)
        return X[:, 0] if np.ndim(b) == 1 else X


class PardisoSchur:
    """PARDISO Cholesky factorization of an SPD matrix with the Schur complement on ``last``.

    Parameters
    ----------
    K : (n, n) sparse SPD matrix
    last : (c,) dof ids of the Schur block, in this order
    points : unused (PARDISO orders by METIS); accepted for a common signature
    """

    name = "pardiso"

    def __init__(self, K: sp.spmatrix, last: NDArray[np.int64], points: Any = None) -> None:
        self.timings: dict[str, float] = {}
        tick = time.perf_counter()
        n = K.shape[0]
        last = np.asarray(last, dtype=np.int64).ravel()
        c = len(last)
        if len(_unique(last)) != c:
            raise ValueError("Schur dofs: the list of contact dofs has repeated entries")
        U = _upper(sp.csr_matrix(K, dtype=np.float64))
        perm = np.zeros(n, dtype=np.int32)
        perm[last] = 1
        # parallel nested dissection (iparm[1] = 3) and the two-level factorization
        # (iparm[23] = 1): 15-25 % faster than serial METIS on 2 cores
        # (benchmarks/bench_speed.py), the same result for the same number of threads
        self._h = _Handle(U, 2, {1: 3, 23: 1, 35: 2}, perm)
        weakref.finalize(self, self._h.release)
        self.last = last
        self.n = n
        self.timings["ordering"] = time.perf_counter() - tick
        dummy = np.zeros(1)
        out = np.zeros(max(n, c * c))
        with solver_threads():
            tick = time.perf_counter()
            self._h(11, dummy, out)
            self.timings["ordering"] += time.perf_counter() - tick
            tick = time.perf_counter()
            self._h(22, dummy, out)
            self.timings["factorization"] = time.perf_counter() - tick
            tick = time.perf_counter()
            # PARDISO numbers the Schur rows in increasing dof order
            order = np.argsort(last)
            rank = np.empty(c, dtype=np.int64)
            rank[order] = np.arange(c)
            # the block in the order of ``last``, Fortran-ordered (the transpose of the
            # C-ordered block of S^T: the same entries), inverted in place; the output
            # buffer is freed first (each is c^2 doubles: 320 MB for c = 6336). When
            # ``last`` is increasing (the contact dofs of a 3D run), the same array is
            # PARDISO's own buffer transposed in place: no second c^2 block at the peak
            block = out[: c * c].reshape(c, c)
            if np.array_equal(rank, np.arange(c)):
                _transpose_in_place(block)
                S = block.T
            else:
                S = block.T[np.ix_(rank, rank)].T
            del out, block
            self.S_inv = compliance_from_schur(S, overwrite_s=True)
            del S
            self.timings["schur"] = time.perf_counter() - tick

    def solve(
        self, b: NDArray[np.float64], out: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """``K^{-1} b`` for a vector or an (n, k) block of right-hand sides, written to
        ``out`` when given (an array of b's shape, Fortran-ordered)."""
        B, k = _block(b, self.n)
        X = np.empty_like(B, order="F") if out is None else _output(out, b)
        with solver_threads():
            self._h(33, B, X, k)  # PARDISO writes every entry
        return X[:, 0] if np.ndim(b) == 1 else X

    def solve_partial(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        """The same solve by the partial phases: forward substitution (331), whose
        contact rows hold ``b_c - K_ci K_ii^{-1} b_i``, ``x_c = S_inv (...)``, backward
        substitution (333)."""
        B, k = _block(b, self.n)
        Y = np.zeros_like(B)
        X = np.zeros_like(B)
        with solver_threads():
            self._h(331, B, Y, k)
            Y[self.last] = self.S_inv @ Y[self.last]
            self._h(333, Y, X, k)
        return X[:, 0] if np.ndim(b) == 1 else X
