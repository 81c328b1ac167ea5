"""The stiffness on the free dofs as a sum over cells, for assembly rank by rank.

An MPI run (the petsc backend, docs/mpi.md) sends one :class:`CellAssembly` to every
rank; each rank assembles the part of ``K`` of its own cells (:meth:`CellAssembly.part`)
in the global numbering of the free dofs, with the same constraint mapping as
:class:`~vemwear.simulate.discrete.Discretization` (the rigid parts' ties ``Q^T K Q``,
then the free rows and columns): both are linear in the cells' matrices, so the parts
add up to ``K``.

Rank 0 of such a run holds only the rows of K at the contact and the constrained dofs
(:meth:`CellAssembly.around`): the sum of the matrices of the cells that touch them,
whose rows there are complete and summed in the same order as those of the whole K.
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
        offsets, vertices = self._cell_vertices()
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

    def _cell_vertices(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """The cells' vertices in CSR form (3D: the distinct vertices of each cell)."""
        mesh = self.space.mesh
        if hasattr(mesh, "cell_vertex_ids"):
            return mesh.cell_vertex_offsets, mesh.cell_vertex_ids
        return mesh.cell_offsets, mesh.cell_vertices

    def touching(self, dofs: NDArray[np.int64]) -> NDArray[np.int64]:
        """The cells (increasing ids) whose matrices may have entries in the rows of
        ``dofs`` (all dofs, before the ties): those with a vertex of the dofs' nodes
        (k = 2: a vertex of an edge node's edge; a cell node's own cell), a superset of
        the cells that touch them, which is all a complete row needs."""
        space, mesh = self.space, self.space.mesh
        d, n_points = int(space.dim), len(mesh.points)
        dofs = np.asarray(dofs, dtype=np.int64)
        marked = np.zeros(n_points, dtype=bool)
        hit = np.zeros(self.n_cells, dtype=bool)
        if int(space.order) == 1:
            marked[dofs // d] = True
        else:  # k = 2 (:func:`vemwear.vem.dofs2.numbering2`): vertex, edge, cell nodes
            node = dofs // 2
            edges = np.asarray(mesh.edges)
            marked[node[node < n_points]] = True
            on_edge = node[(node >= n_points) & (node < n_points + len(edges))] - n_points
            marked[edges[on_edge].ravel()] = True
            hit[node[node >= n_points + len(edges)] - n_points - len(edges)] = True
        offsets, vertices = self._cell_vertices()
        if len(vertices):
            hit |= np.logical_or.reduceat(marked[vertices], offsets[:-1])
        return np.flatnonzero(hit)

    def around(self, dofs: NDArray[np.int64]) -> sp.csr_matrix:
        """The stiffness on all dofs, tied (``Q^T K Q``), of the cells that touch
        ``dofs`` (all dofs, after the ties) and the dofs tied to them.

        Its rows and columns at ``dofs`` are those of the whole matrix bitwise: every
        cell that adds to them is in, and each assembly sums a row's entries in cell
        order (which a subset of the cells keeps), the ties' products row by row.
        """
        dofs = np.asarray(dofs, dtype=np.int64)
        if self.ties is not None:  # the dofs that the ties map onto ``dofs``
            tied = self.ties.Q[:, dofs].tocoo().row
            dofs = np.union1d(dofs, tied)
        with np.errstate(all="ignore"):
            K = self.space.stiffness(self.material, self.stabilization, self.touching(dofs))
            return K if self.ties is None else self.ties.tie(K)

    def part(self, cells: NDArray[np.int64]) -> sp.csr_matrix:
        """The sum of the ``cells``' matrices on the free dofs, (n, n)."""
        with np.errstate(all="ignore"):
            K = self.space.stiffness(self.material, self.stabilization, cells)
            if self.ties is not None:
                K = self.ties.tie(K)
        return sp.csr_matrix(K[self.free][:, self.free])
