"""A partition of a mesh's cells into parts of about equal size, one per MPI rank.

METIS (``pymetis``, the ``mpi`` extra) cuts the dual graph of the cells (two cells are
neighbours when they share a facet: at least ``d`` vertices), which keeps the
interface between the parts, and so the rows that two ranks both assemble, small.
Without pymetis the cells are cut into slabs of equal count along the longest extent of
their vertex averages: a geometric split whose interface is about as small on the
block-shaped domains of the examples, and larger on elongated or curved ones.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

__all__ = ["METHODS", "partition_cells"]

#: The partitioners, as :func:`partition_cells` reports them.
METHODS = ("metis", "slabs")


def partition_cells(
    offsets: NDArray[np.int64],
    vertices: NDArray[np.int64],
    points: NDArray[np.float64],
    parts: int,
    method: str = "auto",
) -> tuple[NDArray[np.int64], str]:
    """The part (0 to ``parts - 1``) of every cell, and the method used.

    Parameters
    ----------
    offsets, vertices : the cells' vertices in CSR form (cell ``k`` has
        ``vertices[offsets[k]:offsets[k + 1]]``)
    points : (n_points, d) vertex coordinates
    parts : the number of parts (>= 1)
    method : {"auto", "metis", "slabs"}
        ``"auto"``: METIS when pymetis imports, else slabs.
    """
    if method not in ("auto", *METHODS):
        raise ValueError(f"unknown partitioner {method!r}; expected 'auto' or one of {METHODS}")
    n_cells = len(offsets) - 1
    if parts <= 1 or n_cells <= parts:
        return np.minimum(np.arange(n_cells), max(parts - 1, 0)).astype(np.int64), "slabs"
    if method == "slabs":
        return _slabs(offsets, vertices, points, parts), "slabs"
    try:
        import pymetis
    except ImportError:
        if method == "metis":
            raise ImportError("partitioner 'metis' needs pymetis: pip install pymetis") from None
        return _slabs(offsets, vertices, points, parts), "slabs"
    sizes = np.diff(offsets)
    incidence = sp.csr_matrix(
        (np.ones(len(vertices)), vertices, offsets), shape=(n_cells, len(points))
    )
    shared = sp.csr_matrix(incidence @ incidence.T)
    # neighbours through a facet: d shared vertices (an edge in 2D, a face in 3D)
    shared.data[shared.data < points.shape[1]] = 0.0
    shared.setdiag(0.0)
    shared.eliminate_zeros()
    xadj, adjncy = shared.indptr.astype(np.int64), shared.indices.astype(np.int64)
    # the work of a cell: its local matrix's entries
    weights = (sizes * sizes).astype(np.int64)
    if hasattr(pymetis, "CSRAdjacency"):  # pymetis >= 2025
        graph = pymetis.CSRAdjacency(xadj, adjncy)
        membership = pymetis.part_graph(parts, graph, vweights=weights)[1]
    else:
        membership = pymetis.part_graph(parts, xadj=xadj, adjncy=adjncy, vweights=weights)[1]
    part = np.asarray(membership, dtype=np.int64)
    if len(np.unique(part)) < parts and method == "auto":  # an empty part (tiny graphs)
        return _slabs(offsets, vertices, points, parts), "slabs"
    return part, "metis"


def _slabs(
    offsets: NDArray[np.int64],
    vertices: NDArray[np.int64],
    points: NDArray[np.float64],
    parts: int,
) -> NDArray[np.int64]:
    """Slabs of equal cell count along the longest extent of the cells' vertex averages."""
    sizes = np.diff(offsets)
    cell = np.repeat(np.arange(len(sizes)), sizes)
    centre = (
        np.stack(
            [
                np.bincount(cell, points[vertices, c], minlength=len(sizes))
                for c in range(points.shape[1])
            ],
            axis=1,
        )
        / sizes[:, None]
    )
    axis = int(np.argmax(np.ptp(centre, axis=0)))
    order = np.argsort(centre[:, axis], kind="stable")
    part = np.empty(len(sizes), dtype=np.int64)
    part[order] = np.arange(len(sizes)) * parts // len(sizes)
    return part
