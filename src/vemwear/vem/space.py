"""The virtual element space behind one interface, for k = 1 and k = 2 (docs/architecture.md,
"The discrete problem, for any space").

The layers above the element level (contact, simulate, solvers, post) talk to a
:class:`Space` and need not know the order k: the number of dofs and a point for each,
the stiffness ``a_h`` (3.11), the loads of Section 3.3 and of the tractions, the dofs of
a boundary part and their values for a prescribed displacement, the displacement at the
vertices, ``Pi u``, and the trace of the displacement at the contact nodes.

* :class:`P1Space` (k = 1) wraps :mod:`vemwear.vem.assembly` and
  :mod:`vemwear.vem.projection`: dof ``2 v + c`` is component c at vertex v.
* :class:`P2Space` (k = 2) wraps :mod:`vemwear.vem.dofs2`: vertex values, one mean per
  component per edge, one per cell (:class:`~vemwear.vem.dofs2.Numbering2`).

Contact nodes (docs/method.md, section 9, "Contact for k = 2"): for k = 1 the vertices of
Gamma_C with the trapezoidal weights ``sum |e| / 2``; for k = 2 also the edge midpoints,
with Simpson's weights (``sum |e| / 6`` at a vertex, ``4 |e| / 6`` at a midpoint). The
trace of v at a midpoint is the value of the edge's quadratic there,
``(6 m_e - v_a - v_b) / 4`` with ``m_e`` the edge mean: a row over three dofs.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property
from typing import Any, Protocol

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..mesh.polyhedra import Mesh3D
from ..mesh.polymesh import Mesh
from ..util.arrays import unique as _unique
from .assembly import body_force_vector, edge_load_vector, stiffness
from .dofs2 import (
    GAUSS3,
    body_force_vector2,
    edge_ids,
    edge_load_vector2,
    facet_dofs2,
    numbering2,
    project2,
    stiffness2,
)
from .local import Material
from .projection import Projection
from .quadrature import Field
from .space3d import P1Space3D

__all__ = [
    "ORDERS",
    "P1Space",
    "P1Space3D",
    "P2Space",
    "Space",
    "has_part",
    "make_space",
    "part_facets",
]

#: The orders k of the implemented spaces.
ORDERS = (1, 2)

#: A scalar component of a prescribed displacement: a number or ``f(x, t)`` of (n, 2)
#: points giving (n,) values (as :data:`vemwear.simulate.constraints.Component`).
Scalar = float | Callable[[NDArray[np.float64], float], ArrayLike]


class Space(Protocol):
    """What the layers above the element level ask of a virtual element space.

    The boundary *facets* are edges ((m, 2) vertex pairs) on a 2D :class:`Mesh` and
    face ids ((m,) ints) on a :class:`Mesh3D` (:func:`part_facets`); global dof ``i`` of
    the vertex values is component ``i % dim`` at vertex ``i // dim``.
    """

    @property
    def mesh(self) -> Mesh | Mesh3D: ...

    dim: int
    order: int

    @property
    def n_dofs(self) -> int: ...

    @property
    def dof_points(self) -> NDArray[np.float64]: ...

    def stiffness(
        self,
        material: Material,
        stabilization: str = "paper",
        cells: NDArray[np.int64] | None = None,
    ) -> sp.csr_matrix: ...

    def body_force(self, f1: Field, t: float = 0.0) -> NDArray[np.float64]: ...

    def boundary_load(
        self, edges: NDArray[np.int64], f2: Field, t: float = 0.0
    ) -> NDArray[np.float64]: ...

    def component_dofs(self, edges: NDArray[np.int64]) -> tuple[NDArray[np.int64], ...]: ...

    def component_values(
        self, dofs: NDArray[np.int64], spec: Scalar, t: float = 0.0
    ) -> NDArray[np.float64]: ...

    def vertex_values(self, u: ArrayLike) -> NDArray[np.float64]: ...

    def projection(self, material: Material, u: ArrayLike) -> Any: ...

    def trace_weights(
        self, edges: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...

    def trace_operator(
        self, vertices: NDArray[np.int64], edges: NDArray[np.int64]
    ) -> sp.csr_matrix: ...


def part_facets(mesh: Mesh | Mesh3D, name: str) -> NDArray[np.int64]:
    """The boundary facets of a part: its edges ((m, 2)) in 2D, its face ids ((m,)) in
    3D (none for a part the mesh does not have)."""
    if isinstance(mesh, Mesh3D):
        return mesh.part_faces(name)
    return mesh.part_edges(name)


def has_part(mesh: Mesh | Mesh3D, name: str) -> bool:
    """Whether the part exists and has boundary facets."""
    if isinstance(mesh, Mesh3D):
        return len(mesh.part_faces(name)) > 0
    return mesh.has_part(name)


def _lengths(mesh: Mesh, edges: NDArray[np.int64]) -> NDArray[np.float64]:
    P = mesh.points
    return np.asarray(np.linalg.norm(P[edges[:, 1]] - P[edges[:, 0]], axis=1), dtype=np.float64)


def _scalar_at(spec: Scalar, x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
    """A scalar component at points ``x`` (n, 2), broadcast to (n,)."""
    if callable(spec):
        return np.broadcast_to(np.asarray(spec(x, t), dtype=float), (len(x),)).copy()
    return np.full(len(x), float(spec))


class P1Space:
    """The lowest-order space (k = 1): the vertex values, ``2 n_points`` dofs.

    Parameters
    ----------
    mesh : Mesh
    """

    dim = 2
    order = 1

    def __init__(self, mesh: Mesh) -> None:
        self.mesh = mesh

    @property
    def n_dofs(self) -> int:
        return 2 * self.mesh.n_points

    @cached_property
    def dof_points(self) -> NDArray[np.float64]:
        """(n_dofs, 2) the vertex of each dof."""
        return np.repeat(self.mesh.points, 2, axis=0)

    def stiffness(
        self,
        material: Material,
        stabilization: str = "paper",
        cells: NDArray[np.int64] | None = None,
    ) -> sp.csr_matrix:
        """``a_h`` (3.11) on all dofs (:func:`~vemwear.vem.assembly.stiffness`), summed
        over ``cells`` only when given."""
        return stiffness(self.mesh, material, stabilization, cells)

    def body_force(self, f1: Field, t: float = 0.0) -> NDArray[np.float64]:
        """The load of Section 3.3 for k = 1 (vertex averages)."""
        return body_force_vector(self.mesh, f1, t)

    def boundary_load(
        self, edges: NDArray[np.int64], f2: Field, t: float = 0.0
    ) -> NDArray[np.float64]:
        """``int f2 . v ds`` over the edges, two-point Gauss (exact for the space)."""
        return edge_load_vector(self.mesh, edges, f2, t)

    def component_dofs(self, edges: NDArray[np.int64]) -> tuple[NDArray[np.int64], ...]:
        """For each component, the dofs at the vertices of the edges (sorted)."""
        v = _unique(np.asarray(edges, dtype=np.int64))
        return (2 * v, 2 * v + 1)

    def component_values(
        self, dofs: NDArray[np.int64], spec: Scalar, t: float = 0.0
    ) -> NDArray[np.float64]:
        """The prescribed component at the vertices of ``dofs``."""
        return _scalar_at(spec, self.mesh.points[np.asarray(dofs) // 2], t)

    def vertex_values(self, u: ArrayLike) -> NDArray[np.float64]:
        """(n_points, 2): the dofs themselves."""
        return np.asarray(u, dtype=float).reshape(-1, 2)

    def projection(self, material: Material, u: ArrayLike) -> Any:
        """``Pi u`` of (3.8)-(3.10), linear on every cell (``material`` is not used)."""
        return self._projection(u)

    @cached_property
    def _projection(self) -> Projection:
        return Projection(self.mesh)

    def trace_weights(
        self, edges: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Trapezoidal weights: ``sum |e| / 2`` at each vertex; no midpoints."""
        L = _lengths(self.mesh, edges)
        w = np.zeros(self.mesh.n_points)
        np.add.at(w, edges[:, 0], 0.5 * L)
        np.add.at(w, edges[:, 1], 0.5 * L)
        return w, np.zeros(0)

    def trace_operator(
        self, vertices: NDArray[np.int64], edges: NDArray[np.int64]
    ) -> sp.csr_matrix:
        """Rows ``2 a + c``: component c of v at node a (the vertices; no midpoints)."""
        if len(edges):
            raise ValueError("k = 1 has no contact nodes at edge midpoints")
        v = np.asarray(vertices, dtype=np.int64)
        m = len(v)
        cols = np.column_stack([2 * v, 2 * v + 1]).ravel()
        return sp.csr_matrix((np.ones(2 * m), (np.arange(2 * m), cols)), shape=(2 * m, self.n_dofs))


class P2Space:
    """The second-order space (k = 2) of :mod:`vemwear.vem.dofs2`.

    Parameters
    ----------
    mesh : Mesh
    load_rule : {"paper", "projection"}
        The body-force load (:func:`~vemwear.vem.dofs2.body_force_vector2`); the
        ``"projection"`` rule needs the material, given to :meth:`stiffness` first.
    """

    dim = 2
    order = 2

    def __init__(self, mesh: Mesh, load_rule: str = "paper") -> None:
        self.mesh = mesh
        self.numbering = numbering2(mesh)
        self.load_rule = load_rule
        self._material: Material | None = None

    @property
    def n_dofs(self) -> int:
        return self.numbering.n_dofs

    @cached_property
    def dof_points(self) -> NDArray[np.float64]:
        """(n_dofs, 2): the vertex, the edge midpoint or the cell's vertex average."""
        m = self.mesh
        E = m.edges
        mid = 0.5 * (m.points[E[:, 0]] + m.points[E[:, 1]])
        centre = np.zeros((m.n_cells, 2))
        for c in (0, 1):
            s = np.bincount(
                np.repeat(np.arange(m.n_cells), m.cell_sizes),
                m.points[m.cell_vertices, c],
                minlength=m.n_cells,
            )
            centre[:, c] = s / m.cell_sizes
        return np.repeat(np.concatenate([m.points, mid, centre]), 2, axis=0)

    def stiffness(
        self,
        material: Material,
        stabilization: str = "paper",
        cells: NDArray[np.int64] | None = None,
    ) -> sp.csr_matrix:
        """``a_h`` (3.11) of k = 2 on all dofs (:func:`~vemwear.vem.dofs2.stiffness2`),
        summed over ``cells`` only when given."""
        self._material = material
        return stiffness2(self.mesh, material, stabilization, cells)

    def body_force(self, f1: Field, t: float = 0.0) -> NDArray[np.float64]:
        """The load of Section 3.3 for k >= 2 (cell moments against P_0)."""
        return body_force_vector2(self.mesh, f1, t, rule=self.load_rule, material=self._material)

    def boundary_load(
        self, edges: NDArray[np.int64], f2: Field, t: float = 0.0
    ) -> NDArray[np.float64]:
        """``int f2 . v ds`` over the edges, three-point Gauss (exact for the space)."""
        return edge_load_vector2(self.mesh, np.asarray(edges, dtype=np.int64), f2, t)

    def component_dofs(self, edges: NDArray[np.int64]) -> tuple[NDArray[np.int64], ...]:
        """For each component, the vertex dofs and edge-mean dofs on the closure of the
        edges."""
        return facet_dofs2(self.mesh, edges)

    def component_values(
        self, dofs: NDArray[np.int64], spec: Scalar, t: float = 0.0
    ) -> NDArray[np.float64]:
        """The prescribed component's dofs: its value at a vertex, its mean over an edge
        (three-point Gauss). Cell dofs are never prescribed."""
        dofs = np.asarray(dofs, dtype=np.int64)
        num, P = self.numbering, self.mesh.points
        out = np.empty(len(dofs))
        vert = dofs < num.edge_offset
        if np.any(dofs >= num.cell_offset):
            raise ValueError("component_values: cell dofs are not prescribed")
        out[vert] = _scalar_at(spec, P[dofs[vert] // 2], t)
        if not np.all(vert):
            if not callable(spec):
                out[~vert] = float(spec)
            else:
                E = self.mesh.edges[(dofs[~vert] - num.edge_offset) // 2]
                a, b = P[E[:, 0]], P[E[:, 1]]
                s, w = GAUSS3
                out[~vert] = sum(
                    w[q] * _scalar_at(spec, (1 - s[q]) * a + s[q] * b, t) for q in range(len(s))
                )
        return out

    def vertex_values(self, u: ArrayLike) -> NDArray[np.float64]:
        """(n_points, 2): the vertex dofs."""
        v = np.asarray(u, dtype=float).reshape(-1)
        return v[: self.numbering.edge_offset].reshape(-1, 2)

    def projection(self, material: Material, u: ArrayLike) -> Any:
        """``Pi u`` (3.8) on every cell, quadratic (:func:`~vemwear.vem.dofs2.project2`)."""
        return project2(self.mesh, material, u)

    def trace_weights(
        self, edges: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Simpson's weights: ``sum |e| / 6`` at each vertex, ``4 |e| / 6`` at the
        midpoint of each edge (in the order of ``edges``)."""
        L = _lengths(self.mesh, edges)
        w = np.zeros(self.mesh.n_points)
        np.add.at(w, edges[:, 0], L / 6.0)
        np.add.at(w, edges[:, 1], L / 6.0)
        return w, 4.0 * L / 6.0

    def trace_operator(
        self, vertices: NDArray[np.int64], edges: NDArray[np.int64]
    ) -> sp.csr_matrix:
        """Rows ``2 a + c``: component c of v at node a, the vertices first, then the
        midpoints of ``edges``, where ``v = (6 m_e - v_a - v_b) / 4``."""
        v = np.asarray(vertices, dtype=np.int64)
        E = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        nv, ne = len(v), len(E)
        e = self.numbering.edge_offset + 2 * edge_ids(self.mesh, E[:, 0], E[:, 1])
        rows, cols, vals = [], [], []
        for c in (0, 1):
            rows.append(2 * np.arange(nv) + c)
            cols.append(2 * v + c)
            vals.append(np.ones(nv))
            r = 2 * (nv + np.arange(ne)) + c
            for col, val in ((e + c, 1.5), (2 * E[:, 0] + c, -0.25), (2 * E[:, 1] + c, -0.25)):
                rows.append(r)
                cols.append(col)
                vals.append(np.full(ne, val))
        return sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(2 * (nv + ne), self.n_dofs),
        )


def make_space(mesh: Mesh | Mesh3D, order: int = 1) -> P1Space | P2Space | P1Space3D:
    """The space of order ``order`` (1 or 2) on ``mesh`` (order 1 on a :class:`Mesh3D`)."""
    if isinstance(mesh, Mesh3D):
        if order != 1:
            raise ValueError(f"3D meshes have the space of order 1 only, got order {order!r}")
        return P1Space3D(mesh)
    if order == 1:
        return P1Space(mesh)
    if order == 2:
        return P2Space(mesh)
    raise ValueError(f"order must be one of {ORDERS}, got {order!r}")
