"""The lowest-order 3D space (k = 1 on polyhedra) behind the interface of :mod:`vemwear.vem.space`.

:class:`P1Space3D` offers the members of :class:`~vemwear.vem.space.Space` with the
boundary *facets* being faces (ids into :class:`~vemwear.mesh.polyhedra.Mesh3D`'s faces, a
1D int array) instead of 2D edges (an (m, 2) array), and three components: global dof
``3 v + c`` is component c of the displacement at vertex v (docs/method.md, "3D (k = 1)").

Contact on boundary faces (docs/method.md, "3D (k = 1)", "Trace"): the nodes are the
vertices of the contact faces; the nodal weights are the face vertex weights ``w_a^F``
summed over the node's contact faces (the rule of the consistency term,
:mod:`vemwear.vem.quadrature3d`: each face's area shared among its vertices, exactly
``|F| / n`` on triangles and parallelograms, exact for linear fields on every planar
face); the nodal normal is the weight-averaged outward normal of those faces,
``nu_a = sum_F w_a^F nu_F / |sum_F w_a^F nu_F|``, with an orthonormal tangent basis.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..mesh.polyhedra import Mesh3D
from ..util.arrays import unique as _unique
from .local import Material
from .local3d import (
    CellGeometry,
    LinearFields3D,
    Projection3D,
    body_force_vector3d,
    cell_geometry,
    face_load_vector3d,
    stiffness3d,
)
from .quadrature3d import FaceGeometry, Field3, face_geometry

__all__ = ["P1Space3D", "tangent_basis"]

#: A scalar component of a prescribed displacement: a number or ``f(x, t)`` of (n, 3)
#: points giving (n,) values.
Scalar3 = float | Callable[[NDArray[np.float64], float], ArrayLike]


def tangent_basis(
    normals: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """An orthonormal tangent pair ``(tau_1, tau_2)`` for unit normals (m, 3), with
    ``(tau_1, tau_2, nu)`` right-handed: ``tau_1`` is the normalized ``e x nu`` for the
    coordinate axis e least aligned with nu, ``tau_2 = nu x tau_1``."""
    nu = np.asarray(normals, dtype=float).reshape(-1, 3)
    e = np.zeros_like(nu)
    e[np.arange(len(nu)), np.argmin(np.abs(nu), axis=1)] = 1.0
    t1 = np.cross(e, nu)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1, np.cross(nu, t1)


class P1Space3D:
    """The lowest-order space on polyhedra (k = 1, d = 3): the vertex values, ``3 n_points``
    dofs.

    Parameters
    ----------
    mesh : Mesh3D
    rule : {"enhanced", "fan"}
        The face vertex weights of the consistency term, the tractions and the contact
        weights (:mod:`vemwear.vem.quadrature3d`).
    """

    dim = 3
    order = 1

    def __init__(self, mesh: Mesh3D, rule: str = "enhanced") -> None:
        self.mesh = mesh
        self.rule = rule

    @cached_property
    def faces(self) -> FaceGeometry:
        """Geometry and vertex weights of every face."""
        return face_geometry(self.mesh, self.rule)

    @cached_property
    def cells(self) -> CellGeometry:
        """Vertex normal weights, volumes and vertex averages of every cell."""
        return cell_geometry(self.mesh, self.rule)

    @property
    def n_dofs(self) -> int:
        return 3 * self.mesh.n_points

    @cached_property
    def dof_points(self) -> NDArray[np.float64]:
        """(n_dofs, 3) the vertex of each dof."""
        return np.repeat(self.mesh.points, 3, axis=0)

    def stiffness(
        self,
        material: Material,
        stabilization: str = "paper",
        cells: NDArray[np.int64] | None = None,
    ) -> sp.csr_matrix:
        """``a_h`` (3.11) on all dofs (:func:`~vemwear.vem.local3d.stiffness3d`), summed
        over ``cells`` only when given."""
        return stiffness3d(
            self.mesh, material, stabilization, self.rule, geometry=self.cells, cells=cells
        )

    def body_force(self, f1: Field3, t: float = 0.0) -> NDArray[np.float64]:
        """The load of Section 3.3 for k = 1 (vertex averages)."""
        return body_force_vector3d(self.mesh, f1, t, geometry=self.cells)

    def boundary_load(
        self, faces: NDArray[np.int64], f2: Field3, t: float = 0.0
    ) -> NDArray[np.float64]:
        """``int P_0^F f2 . v ds`` over the faces, by the face vertex weights."""
        return face_load_vector3d(self.mesh, faces, f2, t, self.rule)

    def facet_vertices(self, faces: ArrayLike) -> NDArray[np.int64]:
        """The vertices of the faces (sorted, distinct)."""
        f = np.asarray(faces, dtype=np.int64).reshape(-1)
        m = self.mesh
        sizes = m.face_sizes[f]
        starts = m.face_offsets[f]
        idx = np.repeat(starts - np.cumsum(sizes) + sizes, sizes) + np.arange(int(sizes.sum()))
        return _unique(m.face_vertices[idx])

    def component_dofs(self, faces: NDArray[np.int64]) -> tuple[NDArray[np.int64], ...]:
        """For each component, the dofs at the vertices of the faces (sorted)."""
        v = self.facet_vertices(faces)
        return (3 * v, 3 * v + 1, 3 * v + 2)

    def component_values(
        self, dofs: NDArray[np.int64], spec: Scalar3, t: float = 0.0
    ) -> NDArray[np.float64]:
        """The prescribed component at the vertices of ``dofs``."""
        x = self.mesh.points[np.asarray(dofs, dtype=np.int64) // 3]
        if callable(spec):
            return np.broadcast_to(np.asarray(spec(x, t), dtype=float), (len(x),)).copy()
        return np.full(len(x), float(spec))

    def vertex_values(self, u: ArrayLike) -> NDArray[np.float64]:
        """(n_points, 3): the dofs themselves."""
        return np.asarray(u, dtype=float).reshape(-1, 3)

    def projection(self, material: Material, u: ArrayLike) -> LinearFields3D:
        """``Pi u`` of (3.8)-(3.10), linear on every cell (``material`` is not used)."""
        return self._projection(u)

    @cached_property
    def _projection(self) -> Projection3D:
        return Projection3D(self.mesh, self.rule, geometry=self.cells)

    # ------------------------------------------------------------------ trace (contact)
    def _outward(self, faces: NDArray[np.int64]) -> NDArray[np.float64]:
        """Outward unit normals of boundary faces."""
        m = self.mesh
        pos = np.searchsorted(m.boundary_faces, faces)
        ok = pos < len(m.boundary_faces)
        ok[ok] = m.boundary_faces[pos[ok]] == faces[ok]
        if not np.all(ok):
            raise ValueError(f"faces {faces[~ok][:10].tolist()} are not boundary faces")
        return m.boundary_face_signs[pos][:, None] * self.faces.normal[faces]

    def _face_entries(self, faces: NDArray[np.int64]) -> tuple[NDArray, NDArray]:
        pick = np.full(self.mesh.n_faces, -1)
        pick[faces] = np.arange(len(faces))
        e = np.flatnonzero(pick[self.faces.face] >= 0)
        return e, pick[self.faces.face[e]]

    def trace_weights(
        self, faces: NDArray[np.int64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The nodal weights ``omega_a = sum_F w_a^F`` over the faces at every vertex
        (zero off the faces); no nodes besides the vertices.

        Raises
        ------
        ValueError
            If a vertex of the faces gets a weight <= 0 (a face far from star-shaped about
            its vertex average with the enhanced rule); the nodal law needs positive weights.
        """
        faces = np.asarray(faces, dtype=np.int64).reshape(-1)
        e, _ = self._face_entries(faces)
        fv = self.mesh.face_vertices[e]
        w = np.bincount(fv, self.faces.weights[e], minlength=self.mesh.n_points).astype(float)
        bad = _unique(fv[w[fv] <= 0])
        if bad.size:
            raise ValueError(
                f"contact weights <= 0 at vertices {bad[:10].tolist()}: faces too distorted "
                f"for the {self.rule!r} face rule"
            )
        return w, np.zeros(0)

    def trace_normals(self, faces: NDArray[np.int64]) -> NDArray[np.float64]:
        """(n_points, 3): the weight-averaged outward unit normal of the faces at each of
        their vertices, ``sum_F w_a^F nu_F`` normalized (zero off the faces)."""
        faces = np.asarray(faces, dtype=np.int64).reshape(-1)
        e, local = self._face_entries(faces)
        fv = self.mesh.face_vertices[e]
        contrib = self.faces.weights[e][:, None] * self._outward(faces)[local]
        n = np.stack(
            [np.bincount(fv, contrib[:, c], minlength=self.mesh.n_points) for c in range(3)], 1
        ).astype(float)
        norm = np.linalg.norm(n, axis=1)
        on = norm > 0
        n[on] /= norm[on, None]
        return n

    def trace_operator(
        self, vertices: NDArray[np.int64], edges: NDArray[np.int64] | None = None
    ) -> sp.csr_matrix:
        """Rows ``3 a + c``: component c of v at node a (the vertices; k = 1 has no other
        nodes, so ``edges`` must be empty)."""
        if edges is not None and len(edges):
            raise ValueError("k = 1 has no contact nodes besides the vertices")
        v = np.asarray(vertices, dtype=np.int64)
        m = len(v)
        cols = (3 * v[:, None] + np.arange(3)).ravel()
        return sp.csr_matrix((np.ones(3 * m), (np.arange(3 * m), cols)), shape=(3 * m, self.n_dofs))
