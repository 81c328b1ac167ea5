"""The stiffness on the free dofs as a sum over cells, for assembly rank by rank.

An MPI run (the petsc backend, docs/mpi.md) sends one :class:`CellAssembly` to every
rank; each rank assembles the part of ``K`` of its own cells (:meth:`CellAssembly.part`)
in the global numbering of the free dofs, with the same constraint mapping as
:class:`~vemwear.simulate.discrete.Discretization` (the rigid parts' ties ``Q^T K Q``,
then the free rows and columns): both are linear in the cells' matrices, so the parts
add up to ``K``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..mesh.partition import partition_cells
from ..vem.local import Material

__all__ = ["CellAssembly"]


@dataclasses.dataclass(frozen=True, eq=False)
class CellAssembly:
    """What a rank needs to assemble its cells' part of ``K`` (picklable).

    Attributes
    ----------
    space : the virtual element space (with its mesh)
    material, stabilization : as in :meth:`~vemwear.vem.space.Space.stiffness`
    free : (n,) the free dofs, in the order of K's rows
    ties : the rigid parts' ties (``tie(K) = Q^T K Q``), or None
    """

    space: Any
    material: Material
    stabilization: str
    free: NDArray[np.int64]
    ties: Any = None

    @property
    def n_cells(self) -> int:
        return int(self.space.mesh.n_cells)

    def partition(self, parts: int, method: str = "auto") -> tuple[NDArray[np.int64], str]:
        """The part of every cell and the partitioner used.

        ``method = "rows"``: the cells in the order of the first row of K (the first
        free dof) of their vertices, cut in parts of equal count: the parts follow K's
        own numbering (on the generators' meshes, numbered lexicographically, slabs), so
        that the contiguous blocks of K's rows that PETSc gives the ranks are mostly
        those of their own cells (for k = 2, whose edge and cell dofs come after all
        vertex dofs, only the vertex rows). Other methods: :func:`~vemwear.mesh.
        partition.partition_cells` (``"auto"``: METIS when pymetis imports, else slabs).
        """
        mesh = self.space.mesh
        if hasattr(mesh, "cell_vertex_ids"):  # 3D: the distinct vertices of each cell
            offsets, vertices = mesh.cell_vertex_offsets, mesh.cell_vertex_ids
        else:
            offsets, vertices = mesh.cell_offsets, mesh.cell_vertices
        if method != "rows":
            return partition_cells(offsets, vertices, mesh.points, parts, method)
        n, d = len(self.free), int(self.space.dim)
        # the first free row at or after each vertex's first dof (a vertex whose dofs are
        # all constrained takes the next free one: a place in the numbering all the same)
        first = np.minimum(np.searchsorted(self.free, d * np.arange(len(mesh.points))), n - 1)
        cell_first = np.minimum.reduceat(first[vertices], offsets[:-1])
        order = np.argsort(cell_first, kind="stable")
        part = np.empty(len(order), dtype=np.int64)
        part[order] = np.arange(len(order)) * parts // max(len(order), 1)
        return part, "rows"

    def part(self, cells: NDArray[np.int64]) -> sp.csr_matrix:
        """The sum of the ``cells``' matrices on the free dofs, (n, n)."""
        with np.errstate(all="ignore"):
            K = self.space.stiffness(self.material, self.stabilization, cells)
            if self.ties is not None:
                K = self.ties.tie(K)
        return sp.csr_matrix(K[self.free][:, self.free])
