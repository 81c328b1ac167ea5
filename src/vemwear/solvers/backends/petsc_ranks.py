"""The ranks of an MPI job and their shares of the petsc backend's linear algebra.

petsc4py and mpi4py, found and initialized once (:func:`available`); this rank's side
of the collective commands that rank 0 broadcasts (:class:`_Rank`); one distributed
matrix or factorization's part on this rank, with the scatter of rank 0's columns to
the ranks' rows and their gathering back (:class:`_Local`). Used by
:mod:`.petsc` (the factorization and the solves), :mod:`.petsc_cells` (the matrix
assembled from the ranks' cells) and :mod:`.petsc_operator` (K kept by the ranks).
"""

from __future__ import annotations

import ctypes
import glob
import os
import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["HINT", "available"]

#: How to get petsc4py, said when it cannot be imported.
HINT = (
    "petsc4py and mpi4py are not importable: on Debian or Ubuntu, `apt-get install "
    "python3-petsc4py python3-mpi4py openmpi-bin` and run vemwear with Debian's python3 "
    "(a venv made with --system-site-packages, NumPy < 2); with conda, `conda install -c "
    "conda-forge petsc4py mpi4py`; see docs/mpi.md"
)

#: Where Debian's python3-petsc4py-real* puts petsc4py (its .pth file only finds it
#: through PETSC_DIR or a `petsc` alternative that the package does not set)
_DEBIAN = "/usr/lib/petscdir/petsc*/*-real/lib/python3/dist-packages"


@cache
def _modules() -> tuple[Any, Any]:
    """petsc4py's ``PETSc`` and mpi4py's ``MPI``, initialized once."""
    import importlib.util

    if importlib.util.find_spec("mpi4py") is None:  # before petsc4py is looked for
        raise ImportError(f"{HINT} (no module named 'mpi4py')")
    try:
        import petsc4py
    except ImportError:
        found = sorted(glob.glob(_DEBIAN))
        if not found:
            raise ImportError(HINT) from None
        sys.path.append(found[-1])
        try:
            import petsc4py
        except ImportError as exc:
            raise ImportError(f"{HINT} ({exc})") from None
    try:
        from mpi4py import MPI
    except ImportError as exc:
        raise ImportError(f"{HINT} ({exc})") from None
    if "petsc4py.PETSc" not in sys.modules:
        petsc4py.init([])  # PETSc reads PETSC_OPTIONS, not vemwear's command line
    from petsc4py import PETSc

    if np.dtype(PETSc.ScalarType) != np.float64:
        raise ImportError(f"PETSc is built with {PETSc.ScalarType} scalars; vemwear needs real")
    return PETSc, MPI


def available() -> bool:
    """True when petsc4py and mpi4py import (a real-number PETSc with MUMPS)."""
    try:
        _modules()
    except Exception:
        return False
    return True


@cache
def _library() -> Any:
    """The PETSc shared library that petsc4py loaded, with the Schur routines typed."""
    PETSc, _ = _modules()
    paths: list[str] = []
    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths += [line.split()[-1] for line in maps if "/libpetsc" in line]
    except OSError:  # not Linux: look where petsc4py says PETSc is
        import petsc4py

        conf = petsc4py.get_config()
        where = os.path.join(conf["PETSC_DIR"], conf.get("PETSC_ARCH", ""), "lib")
        paths += sorted(glob.glob(os.path.join(where, "libpetsc*")))
    lib: Any = None
    for path in dict.fromkeys(paths):
        try:
            lib = ctypes.CDLL(path)
            lib.MatFactorSetSchurIS  # noqa: B018 - raises AttributeError if absent
        except (OSError, AttributeError):
            continue
        break
    else:
        raise ImportError("the PETSc library of petsc4py was not found (needs PETSc >= 3.8)")
    vp, ip = ctypes.c_void_p, ctypes.c_int
    index = ctypes.c_int64 if np.dtype(PETSc.IntType).itemsize == 8 else ctypes.c_int32
    dp = ctypes.POINTER(ctypes.POINTER(ctypes.c_double))
    lib.MatFactorSetSchurIS.argtypes = [vp, vp]
    lib.MatFactorGetSchurComplement.argtypes = [vp, ctypes.POINTER(vp), ctypes.POINTER(ip)]
    lib.MatFactorRestoreSchurComplement.argtypes = [vp, ctypes.POINTER(vp), ip]
    lib.MatGetSize.argtypes = [vp, ctypes.POINTER(index), ctypes.POINTER(index)]
    lib.MatDenseGetLDA.argtypes = [vp, ctypes.POINTER(index)]
    lib.MatDenseGetArrayRead.argtypes = [vp, dp]
    lib.MatDenseRestoreArrayRead.argtypes = [vp, dp]
    lib.index_type = index
    return lib


class _InStep(RuntimeError):
    """A failure that every rank meets at the same point of a command (the ranks stay
    in step: the workers go on serving, rank 0 reports it)."""


def _check(code: int, what: str) -> None:
    if code != 0:
        raise _InStep(f"PETSc's {what} failed with error code {code}")


class _Rank:
    """This rank's side of the collective work: the communicators, its factorizations."""

    def __init__(self) -> None:
        PETSc, MPI = _modules()
        self.PETSc, self.MPI = PETSc, MPI
        self.comm = MPI.COMM_WORLD
        self.rank, self.size = self.comm.Get_rank(), self.comm.Get_size()
        self.factors: dict[int, _Local] = {}
        self.next_id = 0
        #: rank 0 is between the broadcast of a command and its end
        self.busy = False

    @contextmanager
    def command(self, op: str, *args: Any) -> Iterator[None]:
        """Rank 0: broadcast the command ``op`` to the workers, then do its part; a stop
        signal (Ctrl-C, SIGTERM, SIGHUP) waits for the end of the command."""
        if self.busy:
            raise RuntimeError("the MPI ranks are out of step: a collective solve was interrupted")
        with _signals_held():
            if self.size > 1:
                self.comm.bcast((op, args), root=0)
            self.busy = True
            try:
                yield
            except _InStep:
                self.busy = False
                raise
            self.busy = False


_STOP_SIGNALS = {getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)}


@contextmanager
def _signals_held() -> Iterator[None]:
    """Hold the stop signals (delivered when the section ends): a rank must not leave a
    collective operation half done, or the ranks go out of step."""
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - not POSIX
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@cache
def _rank() -> _Rank:
    return _Rank()


class _Local:
    """One factorization, this rank's part: the solver, its vectors, the row split.

    The rows of the distributed matrix are in contiguous blocks, ``counts[r]`` on rank
    ``r``; ``order`` (when the matrix was assembled from the ranks' cells) lists the rows
    of K in the distributed matrix's order, so that each rank owns the rows of its own
    cells; rank 0 permutes the vectors it scatters and gathers by it.
    """

    def __init__(
        self,
        st: _Rank,
        n: int,
        counts: NDArray[np.int64] | None = None,
        order: NDArray[np.int64] | None = None,
    ) -> None:
        self.st = st
        self.n = n
        size = st.size
        if counts is None:
            counts = np.array([n // size + (r < n % size) for r in range(size)])
        self.counts = counts
        self.starts = np.concatenate([[0], np.cumsum(self.counts)])
        self.rows = int(self.counts[st.rank])
        self.order = order
        self.ksp: Any = None
        self.A: Any = None  # a matrix kept for products (:mod:`.petsc_operator`)
        self.F: Any = None
        self.b: Any = None
        self.x: Any = None
        self.buf = np.zeros(self.rows)

    def position(self, dofs: NDArray[np.int64]) -> NDArray[np.int64]:
        """The rows of the distributed matrix of K's rows ``dofs``."""
        if self.order is None:
            return dofs
        at = np.empty(self.n, dtype=np.int64)
        at[self.order] = np.arange(self.n)
        return at[dofs]

    def interior(self, R: NDArray[np.float64] | None, k: int) -> NDArray[np.float64] | None:
        """``K_ii^{-1} R_i`` column by column (R on rank 0, (n, k)), gathered on rank 0."""
        return self.columns(R, k, lambda: self.F.solve(self.b, self.x))

    def columns(
        self, R: NDArray[np.float64] | None, k: int, apply: Callable[[], None]
    ) -> NDArray[np.float64] | None:
        """``apply`` (``b -> x``: a solve, a product) to the columns of R (on rank 0,
        (n, k)), each scattered to the ranks' rows, the results gathered on rank 0."""
        st, MPI = self.st, self.st.MPI
        X = np.empty((self.n, k), order="F") if st.rank == 0 else None
        col = np.empty(self.n)
        split = [self.counts, self.starts[:-1], MPI.DOUBLE]
        for j in range(k):
            if st.rank == 0:
                assert R is not None
                col[:] = R[:, j] if self.order is None else R[self.order, j]
            st.comm.Scatterv([col, *split] if st.rank == 0 else None, self.buf, root=0)
            self.b.setArray(self.buf)
            apply()
            out = self.x.getArray(readonly=True)
            st.comm.Gatherv(out, [col, *split] if st.rank == 0 else None, root=0)
            if X is not None:
                if self.order is None:
                    X[:, j] = col
                else:
                    X[self.order, j] = col
        return X

    def gather(self, mine: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """One number per row of this rank, gathered on rank 0 in K's order, (n,)."""
        st = self.st
        out = np.empty(self.n) if st.rank == 0 else None
        split = [self.counts, self.starts[:-1], st.MPI.DOUBLE]
        st.comm.Gatherv(
            np.ascontiguousarray(mine), [out, *split] if out is not None else None, root=0
        )
        if out is None or self.order is None:
            return out
        back = np.empty(self.n)
        back[self.order] = out
        return back

    def release(self) -> None:
        for obj in (self.ksp, self.A, self.b, self.x):
            if obj is not None:
                obj.destroy()


def _matrix(st: _Rank, loc: _Local, rows: tuple[NDArray, NDArray, NDArray]) -> Any:
    """The distributed SPD matrix of this rank's CSR ``rows`` (all columns)."""
    PETSc, it = st.PETSc, st.PETSc.IntType
    indptr, indices, data = rows
    shape = ((loc.rows, loc.n), (loc.rows, loc.n))
    csr = (indptr.astype(it), indices.astype(it), np.asarray(data, dtype=np.float64))
    A = PETSc.Mat().createAIJ(size=shape, csr=csr, comm=PETSc.COMM_WORLD)
    A.setOption(PETSc.Mat.Option.SPD, True)
    return A
