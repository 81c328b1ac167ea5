"""MUMPS through PETSc (petsc4py), on one MPI rank or several.

Under ``mpirun -n N`` rank 0 runs the simulation (assembly, the level loop, the
outputs) and the other ranks serve its collective linear algebra (:func:`serve`,
inside :func:`session`): each command starts with a broadcast from rank 0, so that
every rank takes part in the same factorization and the same solves.

Factorization (:class:`PetscSchur`): the distributed matrix is assembled by the ranks,
each from the cells of its part of the mesh (:func:`.petsc_cells.assemble_by_cells`: rank 0
partitions the cells and sends the recipe, :class:`vemwear.simulate.cellparts.
CellAssembly`; a rank owns the rows of its cells, renumbered in contiguous blocks, and
the interface rows' entries go to their owner); for a matrix given without a recipe
(the anchored K of load control) rank 0 sends each rank its block of rows; a matrix
that the ranks keep for the run (:mod:`.petsc_operator`) is factorized as it is. PETSc
gives the distributed matrix to MUMPS (Cholesky of an SPD matrix) with the contact
dofs as MUMPS's Schur variables (``MatFactorSetSchurIS``, MUMPS's ICNTL(19)):
MUMPS factorizes the interior block over all ranks and leaves the dense Schur
complement ``S = K_cc - K_ci K_ii^{-1} K_ic`` on rank 0, valid in its lower triangle,
which :func:`.base.compliance_from_schur` inverts as for PARDISO. petsc4py 3.18 does
not wrap ``MatFactorSetSchurIS`` and ``MatFactorGetSchurComplement``; they are called
through ctypes in the PETSc library that petsc4py loaded.

Solves: PETSc 3.18 refuses MUMPS's Schur reduction and expansion on more than one
rank ("Parallel Schur complements not yet supported from PETSc"). With MUMPS's
ICNTL(26) = 0 a solve gives the interior solution ``K_ii^{-1} b_i`` (the Schur entries
set to zero) on any number of ranks, and ``K^{-1} b`` follows by block elimination on
rank 0, two interior solves per right-hand side::

    x_c = S^{-1} (b_c - K_ci K_ii^{-1} b_i),    x_i = K_ii^{-1} (b_i - K_ic x_c)
"""

from __future__ import annotations

import ctypes
import signal
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import NDArray

from ...util.arrays import unique as _unique
from .base import compliance_from_schur
from .petsc_cells import assemble_by_cells
from .petsc_operator import _multiply, _stiffness
from .petsc_ranks import (
    _STOP_SIGNALS,
    HINT,
    _check,
    _InStep,
    _library,
    _Local,
    _matrix,
    _Rank,
    _rank,
    available,
)

__all__ = ["HINT", "PetscSchur", "available", "serve", "session"]


def _factorize(
    st: _Rank,
    fid: int,
    n: int = 0,
    last: NDArray[np.int64] | None = None,
    K: sp.csr_matrix | None = None,
    K_c: sp.csr_matrix | None = None,
    assembly: Any = None,
    partition: str = "rows",
    matrix: int | None = None,
) -> tuple[NDArray[np.float64], list[int], dict[str, Any]] | None:
    """The collective factorization; returns on rank 0 the Schur complement (Fortran
    order, lower triangle valid), the megabytes of MUMPS's factorization on each rank
    and the report of the distributed matrix's making (:func:`.petsc_cells.assemble_by_cells`;
    without ``assembly``, the seconds of the rows' sending and receiving on each rank),
    None elsewhere.

    Rank 0 gives the size ``n``, the Schur dofs ``last`` and the rows ``K_c`` of K at
    them, and the matrix: the id of a distributed matrix made before (``matrix``,
    :class:`.petsc_operator.PetscStiffness`), or ``assembly`` (made here from the
    ranks' cells), or ``K`` (its rows sent from rank 0)."""
    PETSc, comm = st.PETSc, st.comm
    head = None
    if last is not None:
        head = (n, len(last), assembly is not None, partition, matrix)
    n, c, by_cells, partition, matrix = comm.bcast(head, root=0)
    report: dict[str, Any] = {}
    A: Any = None
    if matrix is not None:  # the matrix of the operator: made, kept by its owner
        made = st.factors[matrix]
        loc = _Local(st, n, made.counts, made.order)
        A = made.A
    elif by_cells:
        loc, (indptr, indices, data), report = assemble_by_cells(st, n, assembly, partition)
    else:
        tick = time.perf_counter()
        loc = _Local(st, n)
        if st.rank == 0:
            assert K is not None
            for r in range(1, st.size):
                blk = K[loc.starts[r] : loc.starts[r + 1]]
                comm.send((blk.indptr, blk.indices, blk.data), dest=r, tag=fid)
            mine = K[: loc.starts[1]]
            indptr, indices, data = mine.indptr, mine.indices, mine.data
        else:
            indptr, indices, data = comm.recv(source=0, tag=fid)
        seconds = comm.gather(time.perf_counter() - tick, root=0)
        report = {"partitioner": "rows", "seconds": seconds} if seconds is not None else {}
    owned = A is None
    if owned:
        A = _matrix(st, loc, (indptr, indices, data))
        del indptr, indices, data
    it = PETSc.IntType
    ksp = PETSc.KSP().create(PETSc.COMM_WORLD)
    ksp.setOperators(A)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    pc.setFactorSetUpSolverType()
    F = pc.getFactorMatrix()
    ids = np.asarray(loc.position(last), dtype=it) if last is not None else np.zeros(0, dtype=it)
    schur = PETSc.IS().createGeneral(ids, comm=PETSc.COMM_WORLD)
    lib = _library()
    _check(lib.MatFactorSetSchurIS(F.handle, schur.handle), "MatFactorSetSchurIS")
    try:
        pc.setUp()
    except PETSc.Error as exc:
        raise _InStep(f"MUMPS: {exc}") from None
    info = F.getMumpsInfog(1)
    if info < 0:
        raise _InStep(f"MUMPS failed: INFOG(1) = {info}, INFOG(2) = {F.getMumpsInfog(2)}")
    F.setMumpsIcntl(26, 0)  # solves: the interior system only (module docstring)
    # MUMPS's INFO(22): the memory (MB) the factorization used on each rank
    megabytes = comm.gather(int(F.getMumpsInfo(22)), root=0)
    loc.x, loc.b = A.createVecs()
    if owned:
        A.destroy()  # the solver keeps its own reference
    schur.destroy()
    loc.ksp, loc.F = ksp, F
    st.factors[fid] = loc
    # one product S z by an interior solve tells which triangle of MUMPS's block holds S
    z = np.cos(np.arange(c) + 0.5) if st.rank == 0 else np.zeros(0)
    Y = loc.interior(None if K_c is None else (K_c.T @ z)[:, None], 1)
    if st.rank != 0 or K_c is None or Y is None or last is None:
        return None
    Sz = K_c[:, last] @ z - K_c @ Y[:, 0]  # K_cc z - K_ci K_ii^{-1} K_ic z
    return _schur_block(lib, F, c, z, Sz), megabytes, report


def _schur_block(
    lib: Any, F: Any, c: int, z: NDArray[np.float64], Sz: NDArray[np.float64]
) -> NDArray[np.float64]:
    """A copy of the dense Schur complement MUMPS left on rank 0, valid in its lower
    triangle.

    With ICNTL(19) = 2 (PETSc's choice for a Cholesky factor) MUMPS fills one triangle
    of the block: the lower one (column-major) on one rank, the upper one on several
    (PETSc 3.18 with MUMPS 5.5), the other holding what was left there. The triangle
    whose symmetric matrix gives the product ``Sz = S z``, computed by a solve, is
    taken, transposed to the lower one.
    """
    S, status = ctypes.c_void_p(), ctypes.c_int()
    _check(
        lib.MatFactorGetSchurComplement(F.handle, ctypes.byref(S), ctypes.byref(status)),
        "MatFactorGetSchurComplement",
    )
    rows, cols, lda = lib.index_type(), lib.index_type(), lib.index_type()
    lib.MatGetSize(S, ctypes.byref(rows), ctypes.byref(cols))
    lib.MatDenseGetLDA(S, ctypes.byref(lda))
    if (rows.value, cols.value) != (c, c):
        raise RuntimeError(
            f"MUMPS returned a {rows.value} x {cols.value} Schur block, not {c} x {c}"
        )
    ptr = ctypes.POINTER(ctypes.c_double)()
    _check(lib.MatDenseGetArrayRead(S, ctypes.byref(ptr)), "MatDenseGetArrayRead")
    try:
        full = np.ctypeslib.as_array(ptr, shape=(lda.value * c,)) if c else np.zeros(0)
        M = full.reshape(c, lda.value)[:, :c].T  # the block, a Fortran-ordered view
        errors = [_symmetric_error(M, z, Sz, lower) for lower in (True, False)]
        lower = errors[0] <= errors[1]
        if min(errors) > 1e-8:
            raise RuntimeError(
                f"neither triangle of MUMPS's Schur block is the Schur complement "
                f"(relative errors {errors[0]:.1e}, {errors[1]:.1e} of S z)"
            )
        return np.array(M if lower else M.T, order="F")
    finally:
        lib.MatDenseRestoreArrayRead(S, ctypes.byref(ptr))
        lib.MatFactorRestoreSchurComplement(F.handle, ctypes.byref(S), status.value)


def _symmetric_error(
    M: NDArray[np.float64], z: NDArray[np.float64], Sz: NDArray[np.float64], lower: bool
) -> float:
    """``|A z - Sz| / |Sz|`` for the symmetric ``A`` of one triangle of ``M``
    (triangular products: no c x c temporary)."""
    if len(z) == 0:
        return 0.0
    (trmv,) = sla.get_blas_funcs(("trmv",), (M,))
    Az = trmv(M, z, lower=lower) + trmv(M, z, lower=lower, trans=1) - np.diag(M) * z
    return float(np.linalg.norm(Az - Sz)) / max(float(np.linalg.norm(Sz)), 1e-300)


def _solve(st: _Rank, fid: int, B: NDArray[np.float64] | None = None, k: int = 0) -> Any:
    """The collective solve ``K^{-1} B`` by block elimination (module docstring); the
    workers take part in the ``2 k`` interior solves, rank 0 does the rest."""
    loc = st.factors[fid]
    if st.rank != 0:
        loc.interior(None, k)
        loc.interior(None, k)
        return None
    return B


def serve() -> None:
    """The loop of the ranks other than 0: take part in each command of rank 0 until it
    sends ``stop`` (:func:`session` does when rank 0's work ends). The stop signals
    that a launcher forwards to every rank are ignored here: rank 0 handles them (it
    saves the finished levels) and then lets the workers go."""
    old = {sig: signal.signal(sig, signal.SIG_IGN) for sig in _STOP_SIGNALS}
    try:
        _serve(_rank())
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)


def _serve(st: _Rank) -> None:
    while True:
        op, args = st.comm.bcast(None, root=0)
        if op == "stop":
            break
        try:
            if op == "factorize":
                _factorize(st, *args)
            elif op == "solve":
                _solve(st, *args)
            elif op == "stiffness":
                _stiffness(st, *args)
            elif op == "multiply":
                _multiply(st, *args)
        except _InStep:  # rank 0 meets it too and reports it
            continue
        except BaseException:  # a rank out of step: end the whole job, not only this rank
            import traceback

            traceback.print_exc()
            st.comm.Abort(1)
    _release(st)


def _release(st: _Rank) -> None:
    for loc in st.factors.values():
        loc.release()
    st.factors.clear()


@contextmanager
def session() -> Iterator[bool]:
    """The MPI job's frame: yields True on rank 0, which does the work, and False on the
    other ranks, which then call :func:`serve`; when rank 0 leaves, the workers are
    told to stop (a job whose rank 0 stopped within a collective solve is aborted)."""
    st = _rank()
    if st.rank != 0:
        yield False
        return
    try:
        yield True
    finally:
        if st.busy:
            print(
                "vemwear: rank 0 stopped within a collective solve; aborting the MPI job "
                "(the saved levels are kept: resume with --resume)",
                file=sys.stderr,
                flush=True,
            )
            st.comm.Abort(1)
        if st.size > 1:
            st.comm.bcast(("stop", ()), root=0)
        _release(st)


class PetscSchur:
    """MUMPS's Cholesky factorization of SPD ``K`` through PETSc, over the ranks of the
    MPI job, with the Schur complement on ``last`` (the module docstring).

    Made on rank 0 (the other ranks take part through :func:`serve`).

    ``megabytes[r]`` is the memory MUMPS's factorization used on rank ``r`` (its
    INFO(22)). With ``assembly`` every rank assembles the rows of the distributed
    matrix from its own cells (:func:`.petsc_cells.assemble_by_cells`) and ``assembly_report`` says
    how: the partitioner, and per rank the cells, the rows and the seconds (of the
    cells' matrices, and with the exchange of the interface rows). Without it, rank 0
    sends each rank its block of K's rows (``assembly_report``: partitioner ``"rows"``
    and the seconds of each rank).

    Parameters
    ----------
    K : (n, n) sparse SPD matrix, or the operator of one kept by the ranks
        (:class:`.petsc_operator.PetscStiffness`: its matrix is factorized as it is)
    last : (c,) dof ids of the Schur block, in this order
    points : unused (MUMPS orders the matrix itself); accepted for a common signature
    assembly : optional
        K as a sum over cells (:class:`vemwear.simulate.cellparts.CellAssembly`), whose
        parts add up to ``K``.
    partition : {"rows", "metis", "slabs"}
        How the cells are split over the ranks with ``assembly``: ``"rows"`` (the
        default) by the contiguous row blocks of K's own numbering, so that MUMPS
        orders the matrix of the serial run (its ordering with a Schur block is AMD,
        which depends on the numbering: renumbered to METIS's parts, the 3D factor took
        1.3 times the memory, docs/mpi.md); ``"metis"``/``"slabs"``: the cells by
        :func:`vemwear.mesh.partition.partition_cells` and the rows renumbered to them.
    """

    name = "petsc"

    def __init__(
        self,
        K: Any,
        last: NDArray[np.int64],
        points: Any = None,
        assembly: Any = None,
        partition: str = "rows",
    ) -> None:
        st = _rank()
        if st.rank != 0:
            raise RuntimeError("PetscSchur is made on rank 0; the other ranks run serve()")
        self.timings: dict[str, float] = {}
        last = np.asarray(last, dtype=np.int64).ravel()
        if len(_unique(last)) != len(last):
            raise ValueError("Schur dofs: the list of contact dofs has repeated entries")
        tick = time.perf_counter()
        matrix = getattr(K, "matrix_id", None)
        if matrix is not None:  # K kept by the ranks (.petsc_operator): rank 0 has K_c
            self.n = K.shape[0]
            self.K_c = K.rows(last)
            K = None
        else:
            K = sp.csr_matrix(K, dtype=np.float64)
            K.sum_duplicates()
            self.n = K.shape[0]
            self.K_c = K[last]  # (c, n): the rows of the contact dofs
        self.last = last
        self.K_ic = sp.csr_matrix(self.K_c.T)  # K is symmetric: the columns of them
        self.fid = st.next_id
        st.next_id += 1
        self.timings["ordering"] = time.perf_counter() - tick
        tick = time.perf_counter()
        with st.command("factorize", self.fid):
            made = _factorize(st, self.fid, self.n, last, K, self.K_c, assembly, partition, matrix)
        self.timings["factorization"] = time.perf_counter() - tick
        tick = time.perf_counter()
        assert made is not None
        S, megabytes, report = made
        self.megabytes: list[int] = megabytes
        self.assembly_report: dict[str, Any] = report
        self.S_inv = compliance_from_schur(S, overwrite_s=True)
        del S
        self.timings["schur"] = time.perf_counter() - tick

    def solve(
        self, b: NDArray[np.float64], out: NDArray[np.float64] | None = None
    ) -> NDArray[np.float64]:
        """``K^{-1} b`` for a vector or an (n, k) block of right-hand sides, written to
        ``out`` when given (an array of b's shape, Fortran-ordered)."""
        b = np.asarray(b, dtype=np.float64)
        if b.shape[0] != self.n:
            raise ValueError(f"right-hand side has {b.shape[0]} rows, the matrix {self.n}")
        k = 1 if b.ndim == 1 else b.shape[1]
        B = b.reshape(self.n, k)
        st = _rank()
        loc = st.factors[self.fid]
        with st.command("solve", self.fid, None, k):
            Y = loc.interior(B, k)
            assert Y is not None
            # x_c = S^{-1} (b_c - K_ci y_i): y is zero on the contact dofs
            Xc = self.S_inv @ (B[self.last] - self.K_c @ Y)
            R = B - self.K_ic @ Xc  # its contact rows are not read by MUMPS
            X = loc.interior(R, k)
        assert X is not None
        X[self.last] = Xc
        if out is not None:
            if out.shape != b.shape or out.dtype != np.float64:
                raise ValueError("solve: out must be a float64 array of b's shape")
            out.reshape(self.n, k, order="A")[...] = X
            return out
        return X[:, 0] if b.ndim == 1 else X
