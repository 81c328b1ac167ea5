"""The contact part Gamma_C: nodes, nodal quadrature weights, normals (docs/method.md, section 3).

Contact nodes are the mesh vertices on the closure of Gamma_C that are not fixed (on
the closure of Gamma_D, or with both components prescribed). Node ``a`` has the weight
``omega_a`` (half the lengths of its contact edges), the unit outward normal ``nu_a``
(the edge normal; at a corner between two contact edges, their normalized average) and
the unit tangent ``tau_a = (-nu_y, nu_x)``. Gamma_C may have several parts: the nodes
are ordered part by part, along the chains of each part's edges; a vertex shared by two
contact parts belongs to the first (its weight and normal take the edges of both).
"""

from __future__ import annotations

from dataclasses import dataclass, field

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
    part : (m,) index of the node's contact part in ``part_names``
    part_names : the contact parts, in order
    """

    nodes: NDArray[np.int64]
    points: NDArray[np.float64]
    s: NDArray[np.float64]
    weights: NDArray[np.float64]
    normals: NDArray[np.float64]
    tangents: NDArray[np.float64]
    n_dof: int
    part: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    part_names: tuple[str, ...] = ("contact",)

    def __post_init__(self) -> None:
        if len(self.part) != len(self.nodes):
            object.__setattr__(self, "part", np.zeros(len(self.nodes), dtype=np.int64))

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


def _chains(
    edges: NDArray[np.int64], P: NDArray[np.float64], nv: int
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """Vertices of directed edges ordered along their chains, and the arc length from
    the start of each chain (boundary edges run counter-clockwise)."""
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
    return np.asarray(chain, dtype=np.int64), np.asarray(chain_s, dtype=float)


def arc_length(mesh: Mesh, part: str, x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Arc length of points on a boundary part from the start of their chain of edges
    (as :attr:`ContactBoundary.s` at the vertices); each point is taken on its nearest
    edge of the part.

    Parameters
    ----------
    mesh : Mesh
    part : str
        The boundary part.
    x : (n, 2) array
        Points on the part (e.g. quadrature points of its edges).
    """
    P = mesh.points
    edges = mesh.part_edges(part)
    if len(edges) == 0:
        raise MeshError(f"the mesh has no {part!r} boundary edges")
    order, arc = _chains(edges, P, mesh.n_points)
    s_vertex = np.zeros(mesh.n_points)
    s_vertex[order] = arc
    a, d = P[edges[:, 0]], P[edges[:, 1]] - P[edges[:, 0]]
    length = np.linalg.norm(d, axis=1)
    x = np.asarray(x, dtype=float).reshape(-1, 2)
    out = np.empty(len(x))
    for i in range(0, len(x), 512):  # (512, edges) at a time
        rel = x[i : i + 512, None, :] - a[None]
        t = np.clip(np.einsum("qek,ek->qe", rel, d) / length**2, 0.0, 1.0)
        e = np.linalg.norm(rel - t[..., None] * d, axis=2).argmin(axis=1)
        out[i : i + 512] = s_vertex[edges[e, 0]] + t[np.arange(len(e)), e] * length[e]
    return out


def contact_boundary(
    mesh: Mesh,
    parts: tuple[str, ...] = ("contact",),
    fixed: NDArray[np.bool_] | None = None,
) -> ContactBoundary:
    """Build the contact data of the parts ``parts`` of a tagged mesh.

    Parameters
    ----------
    mesh : Mesh
    parts : tuple of str
        The contact parts, in order.
    fixed : (n_points,) bool array, optional
        Vertices that are no contact nodes (both components prescribed); by default
        the vertices of the ``clamped`` part.
    """
    P = mesh.points
    nv = mesh.n_points
    per_part = [mesh.part_edges(name) for name in parts]
    for name, edges in zip(parts, per_part, strict=True):
        if len(edges) == 0:
            raise MeshError(f"the mesh has no {name!r} boundary edges")
    edges = np.concatenate(per_part)
    d = P[edges[:, 1]] - P[edges[:, 0]]
    length = np.linalg.norm(d, axis=1)
    nrm = np.column_stack([d[:, 1], -d[:, 0]]) / length[:, None]
    weight = np.zeros(nv)
    np.add.at(weight, edges[:, 0], 0.5 * length)
    np.add.at(weight, edges[:, 1], 0.5 * length)
    nsum = np.zeros((nv, 2))
    np.add.at(nsum, edges[:, 0], nrm)
    np.add.at(nsum, edges[:, 1], nrm)
    if fixed is None:
        fixed = np.zeros(nv, dtype=bool)
        if "clamped" in mesh.part_names:
            fixed[mesh.part_vertices("clamped")] = True
    taken = np.array(fixed, dtype=bool, copy=True)
    nodes_l, arc_l, part_l = [], [], []
    for i, pe in enumerate(per_part):
        order, arc = _chains(pe, P, nv)
        keep = ~taken[order]
        taken[order] = True
        nodes_l.append(order[keep])
        arc_l.append(arc[keep])
        part_l.append(np.full(int(keep.sum()), i, dtype=np.int64))
    nodes, s = np.concatenate(nodes_l), np.concatenate(arc_l)
    if nodes.size == 0:
        raise MeshError("every contact vertex is also clamped: no contact node is left")
    normals = nsum[nodes] / np.linalg.norm(nsum[nodes], axis=1)[:, None]
    tangents = np.column_stack([-normals[:, 1], normals[:, 0]])
    return ContactBoundary(
        nodes=nodes,
        points=P[nodes],
        s=s,
        weights=weight[nodes],
        normals=normals,
        tangents=tangents,
        n_dof=2 * nv,
        part=np.concatenate(part_l),
        part_names=tuple(parts),
    )
