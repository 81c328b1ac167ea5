"""The contact part Gamma_C: nodes, nodal quadrature weights, normals (docs/method.md, section 3).

Contact nodes are the mesh vertices on the closure of Gamma_C that are not on the
closure of Gamma_D. Node ``a`` has the weight ``omega_a`` (half the lengths of its
contact edges), the unit outward normal ``nu_a`` (the edge normal; at a corner
between two contact edges, their normalized average) and the unit tangent
``tau_a = (-nu_y, nu_x)``. Nodes are ordered along the contact part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..mesh.polymesh import Mesh, MeshError


@dataclass(frozen=True, eq=False)
class ContactBoundary:
    """Nodal quadrature data on Gamma_C.

    Attributes
    ----------
    nodes : (m,) vertex ids, ordered along each chain of contact edges
    points : (m, 2) their coordinates
    s : (m,) arc length from the start of the node's chain
    weights : (m,) omega_a
    normals, tangents : (m, 2) unit nu_a and tau_a
    n_dof : number of global dofs (2 * n_points)
    """

    nodes: NDArray[np.int64]
    points: NDArray[np.float64]
    s: NDArray[np.float64]
    weights: NDArray[np.float64]
    normals: NDArray[np.float64]
    tangents: NDArray[np.float64]
    n_dof: int

    @property
    def m(self) -> int:
        return len(self.nodes)

    def _component_operator(self, direction: NDArray[np.float64]) -> sp.csr_matrix:
        rows = np.repeat(np.arange(self.m), 2)
        cols = np.column_stack([2 * self.nodes, 2 * self.nodes + 1]).ravel()
        return sp.csr_matrix((direction.ravel(), (rows, cols)), shape=(self.m, self.n_dof))

    @property
    def N(self) -> sp.csr_matrix:
        """``N @ u = (u . nu_a)_a``, the normal displacements at contact nodes."""
        return self._component_operator(self.normals)

    @property
    def Tau(self) -> sp.csr_matrix:
        """``Tau @ u = (u . tau_a)_a``, the tangential displacements at contact nodes."""
        return self._component_operator(self.tangents)

    def friction_direction(self, n_star: NDArray[np.float64]) -> NDArray[np.float64]:
        """``n* . tau_a`` at every node, so that ``n* . v_tau(a) = (n* . tau_a)(v . tau_a)``."""
        return self.tangents @ np.asarray(n_star, dtype=float)


def contact_boundary(mesh: Mesh) -> ContactBoundary:
    """Build the contact data of a mesh whose contact part is tagged."""
    edges = mesh.part_edges("contact")
    if len(edges) == 0:
        raise MeshError("the mesh has no 'contact' boundary edges")
    P = mesh.points
    d = P[edges[:, 1]] - P[edges[:, 0]]
    length = np.linalg.norm(d, axis=1)
    nrm = np.column_stack([d[:, 1], -d[:, 0]]) / length[:, None]
    nv = mesh.n_points
    weight = np.zeros(nv)
    np.add.at(weight, edges[:, 0], 0.5 * length)
    np.add.at(weight, edges[:, 1], 0.5 * length)
    nsum = np.zeros((nv, 2))
    np.add.at(nsum, edges[:, 0], nrm)
    np.add.at(nsum, edges[:, 1], nrm)

    # order the nodes along the chains of contact edges (boundary edges run counter-clockwise)
    succ = -np.ones(nv, dtype=np.int64)
    succ[edges[:, 0]] = edges[:, 1]
    has_pred = np.zeros(nv, dtype=bool)
    has_pred[edges[:, 1]] = True
    starts = [int(v) for v in np.unique(edges[:, 0]) if not has_pred[v]]
    if not starts:  # a closed loop
        starts = [int(edges[0, 0])]
    chain: list[int] = []
    chain_s: list[float] = []
    seen = np.zeros(nv, dtype=bool)
    for v0 in starts:
        v, s = v0, 0.0
        while v >= 0 and not seen[v]:
            seen[v] = True
            chain.append(v)
            chain_s.append(s)
            nxt = int(succ[v])
            if nxt >= 0:
                s += float(np.linalg.norm(P[nxt] - P[v]))
            v = nxt
    order = np.asarray(chain, dtype=np.int64)
    clamped = np.zeros(nv, dtype=bool)
    clamped[mesh.part_vertices("clamped")] = True
    keep = ~clamped[order]
    nodes, arc = order[keep], np.asarray(chain_s, dtype=float)[keep]
    if nodes.size == 0:
        raise MeshError("every contact vertex is also clamped: no contact node is left")
    normals = nsum[nodes] / np.linalg.norm(nsum[nodes], axis=1)[:, None]
    tangents = np.column_stack([-normals[:, 1], normals[:, 0]])
    return ContactBoundary(
        nodes=nodes,
        points=P[nodes],
        s=arc,
        weights=weight[nodes],
        normals=normals,
        tangents=tangents,
        n_dof=2 * nv,
    )
