"""The distributed matrix of the petsc backend, assembled by the ranks from their cells.

Rank 0 sends every rank the recipe of the stiffness (:class:`vemwear.simulate.
cellparts.CellAssembly`) and the split of the cells; each rank adds its own cells'
matrices and keeps the rows it owns, and the entries of another rank's rows (the
interface with its cells) are sent to that rank (:func:`assemble_by_cells`).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .petsc_ranks import _InStep, _Local, _Rank

__all__ = ["assemble_by_cells"]


def assemble_by_cells(
    st: _Rank, n: int, assembly: Any, partition: str
) -> tuple[_Local, tuple[NDArray, NDArray, NDArray], dict[str, Any]]:
    """This rank's rows of K, assembled from the cells of its part of the mesh.

    Rank 0 partitions the cells (:meth:`~vemwear.simulate.cellparts.CellAssembly.
    partition`, by ``partition``) and sends the recipe and the partition to every rank;
    each rank sums its cells' matrices on the free dofs (:meth:`~vemwear.simulate.
    cellparts.CellAssembly.part`).

    The rows: with ``partition = "rows"`` (the cells split by the contiguous row blocks
    of K's own numbering) the distributed matrix is K in that numbering, the one the
    serial backends factorize. With ``"metis"`` or ``"slabs"`` a row belongs to a rank
    whose cells touch it (the lowest or the highest such rank, for even and odd rows)
    and the rows are renumbered so that each rank owns a contiguous block of them. Either
    way, the entries of rows owned by another rank (the interface with its cells) are
    sent to it and added there. Returns the row split, this rank's rows (CSR over all
    columns, in the distributed numbering) and, on rank 0, the report: the partitioner
    and, per rank, the cells, the rows and the seconds of the cells' assembly.
    """
    comm, MPI = st.comm, st.MPI
    assembly = comm.bcast(assembly, root=0)
    part, method = comm.bcast(
        assembly.partition(st.size, partition) if st.rank == 0 else None, root=0
    )
    tick = time.perf_counter()
    mine = np.flatnonzero(part == st.rank)
    A = sp.csr_matrix(assembly.part(mine))
    seconds = time.perf_counter() - tick
    if A.shape != (n, n):
        raise RuntimeError(f"the cells' matrix is {A.shape}, the stiffness ({n}, {n})")
    if method == "rows":  # K's own numbering: the part as it is
        loc = _Local(st, n)
    else:
        P = A.tocoo()
        del A
        low = np.full(n, st.size, dtype=np.int64)
        low[P.row] = st.rank
        comm.Allreduce(MPI.IN_PLACE, low, op=MPI.MIN)
        if n and int(low.max()) >= st.size:
            raise _InStep("a row of the stiffness that no cell touches (a singular matrix)")
        high = np.full(n, -1, dtype=np.int64)
        high[P.row] = st.rank
        comm.Allreduce(MPI.IN_PLACE, high, op=MPI.MAX)
        # an interface row goes to the lowest or the highest rank whose cells touch it,
        # in turn: the interfaces' rows are shared, not all given to the lower rank
        owner = np.where(np.arange(n) % 2 == 0, low, high)
        del low, high
        order = np.argsort(owner, kind="stable")
        at = np.empty(n, dtype=np.int64)
        at[order] = np.arange(n)
        loc = _Local(st, n, np.bincount(owner, minlength=st.size), order)
        del owner
        A = sp.csr_matrix((P.data, (at[P.row], at[P.col])), shape=(n, n))
        del P, at
    starts = loc.starts
    out: list[Any] = []
    for r in range(st.size):
        blk = A[starts[r] : starts[r + 1]]
        out.append((blk.data, blk.indices, blk.indptr) if blk.nnz and r != st.rank else None)
    own = sp.csr_matrix(A[starts[st.rank] : starts[st.rank + 1]])
    del A
    received = comm.alltoall(out)
    del out
    # added as triplets, this rank's first, then in rank order: the same sums in every
    # run, and the entries that cancel stay in the pattern (a sparse sum would drop
    # them, and MUMPS orders the pattern that is left much worse: the dofs of a vertex
    # no longer share their columns; 3D: several times the factor's memory)
    parts = [sp.csr_matrix(got, shape=own.shape).tocoo() for got in received if got is not None]
    del received
    if parts:
        parts.insert(0, own.tocoo())
        own = sp.csr_matrix(
            (
                np.concatenate([q.data for q in parts]),
                (np.concatenate([q.row for q in parts]), np.concatenate([q.col for q in parts])),
            ),
            shape=own.shape,
        )
    del parts
    own.sum_duplicates()
    own.sort_indices()
    seconds_all = time.perf_counter() - tick
    rows = comm.gather((len(mine), loc.rows, seconds, seconds_all), root=0)
    report: dict[str, Any] = {}
    if rows is not None:
        report = {
            "partitioner": method,
            "cells": [r[0] for r in rows],
            "rows": [r[1] for r in rows],
            "cell_seconds": [r[2] for r in rows],
            "seconds": [r[3] for r in rows],
        }
    return loc, (own.indptr, own.indices, own.data), report
