"""The contact part Gamma_C: nodes, nodal quadrature weights, normals (docs/method.md, section 3).

Contact nodes are the mesh vertices on the closure of Gamma_C that are not fixed (on
the closure of Gamma_D, or with both components prescribed). Node ``a`` has the weight
``omega_a`` (half the lengths of its contact edges), the unit outward normal ``nu_a``
(the edge normal; at a corner between two contact edges, their normalized average) and
the unit tangent ``tau_a = (-nu_y, nu_x)``. Gamma_C may have several parts: the nodes
are ordered part by part, along the chains of each part's edges; a vertex shared by two
contact parts belongs to the first (its weight and normal take the edges of both).

For k = 2 (:func:`contact_boundary` with a :class:`~vemwear.vem.space.P2Space`) the edge
midpoints of Gamma_C are contact nodes too, between the vertices along each chain, with
the edge normal and Simpson's weights (``sum |e| / 6`` at a vertex, ``4 |e| / 6`` at a
midpoint), and :attr:`ContactBoundary.trace` gives the displacement at every node from
the dofs (docs/method.md, section 9, "Contact for k = 2").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..mesh.polymesh import Mesh, MeshError
from ..vem.dofs2 import edge_ids
from ..vem.space import Space


@dataclass(frozen=True, eq=False)
class ContactBoundary:
    """Nodal quadrature data on Gamma_C.

    Attributes
    ----------
    nodes : (m,) vertex ids, ordered along each chain of contact edges; for k = 2 an
        edge midpoint is ``n_points + e``, ``e`` the row of :attr:`Mesh.edges`; in 3D
        sorted by vertex id within each part (:mod:`vemwear.contact.boundary3d`)
    points : (m, d) their coordinates
    s : (m,) arc length from the start of the node's chain (3D: the x coordinate)
    weights : (m,) omega_a
    normals, tangents : (m, d) unit nu_a and tau_a; in 3D tau_a is the tangential
        direction of the foundation velocity's line at the node (the friction row)
    n_dof : number of global dofs (d * n_points)
    part : (m,) index of the node's contact part in ``part_names``
    part_names : the contact parts, in order
    trace : (2 m, n_dof) sparse, optional
        Rows ``2 a + c``: component c of the displacement at node a from the dofs; None
        for k = 1, where node a is vertex ``nodes[a]`` and the rows pick its two dofs.
    tangents2 : (m, 3), optional
        3D with a foundation velocity that turns: the second tangent of every node; the
        friction then has two rows per node, ``tangents`` and ``tangents2``
        (:func:`~vemwear.contact.boundary3d.sliding_lines`).
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
    trace: sp.csr_matrix | None = None
    tangents2: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        if len(self.part) != len(self.nodes):
            object.__setattr__(self, "part", np.zeros(len(self.nodes), dtype=np.int64))

    @property
    def m(self) -> int:
        return len(self.nodes)

    @property
    def friction_tangents(self) -> NDArray[np.float64]:
        """The directions of the friction rows, (r m, d): ``tangents`` (r = 1), then
        ``tangents2`` when v* turns in 3D (r = 2)."""
        if self.tangents2 is None:
            return self.tangents
        return np.vstack([self.tangents, self.tangents2])

    @property
    def dim(self) -> int:
        """The dimension d (2 or 3) of the points and directions."""
        return int(self.normals.shape[1])

    def _component_operator(self, direction: NDArray[np.float64]) -> sp.csr_matrix:
        d = self.dim
        if self.trace is not None:
            T = self.trace
            op = sp.diags(direction[:, 0]) @ T[0::d] + sp.diags(direction[:, 1]) @ T[1::d]
            for c in range(2, d):
                op = op + sp.diags(direction[:, c]) @ T[c::d]
            return sp.csr_matrix(op)
        rows = np.repeat(np.arange(self.m), d)
        cols = (d * self.nodes[:, None] + np.arange(d)).ravel()
        return sp.csr_matrix((direction.ravel(), (rows, cols)), shape=(self.m, self.n_dof))

    @property
    def N(self) -> sp.csr_matrix:
        """``N @ u = (u . nu_a)_a``, the normal displacements at contact nodes."""
        return self._component_operator(self.normals)

    @property
    def Tau(self) -> sp.csr_matrix:
        """``Tau @ u = (u . tau_a)_a``, the tangential displacements at contact nodes
        (with two friction rows, ``tangents2``: those along ``tau_1``, then ``tau_2``)."""
        if self.tangents2 is None:
            return self._component_operator(self.tangents)
        return sp.csr_matrix(
            sp.vstack(
                [self._component_operator(self.tangents), self._component_operator(self.tangents2)]
            )
        )

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
    space: Space | None = None,
    constrained: NDArray[np.bool_] | None = None,
) -> ContactBoundary:
    """Build the contact data of the parts ``parts`` of a tagged mesh.

    Parameters
    ----------
    mesh : Mesh
    parts : tuple of str
        The contact parts, in order.
    fixed : (n_points,) bool array, optional
        Vertices that are no contact nodes (both components prescribed); by default
        the vertices of the ``clamped`` part (k = 1).
    space : Space, optional
        The virtual element space; k = 1 (the vertices only) when None or of order 1.
    constrained : (space.n_dofs,) bool array, optional
        For k >= 2: the constrained dofs; a node whose displacement depends on
        constrained dofs only is no contact node (by default the dofs of ``clamped``).
    """
    if space is not None and space.order >= 2:
        return _contact_boundary_k2(mesh, parts, space, constrained)
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


def _contact_boundary_k2(
    mesh: Mesh,
    parts: tuple[str, ...],
    space: Space,
    constrained: NDArray[np.bool_] | None,
) -> ContactBoundary:
    """The contact nodes of k = 2: along each chain, every vertex followed by the
    midpoint of its outgoing edge; Simpson's weights; the trace operator of ``space``."""
    P, nv = mesh.points, mesh.n_points
    per_part = [mesh.part_edges(name) for name in parts]
    for name, pe in zip(parts, per_part, strict=True):
        if len(pe) == 0:
            raise MeshError(f"the mesh has no {name!r} boundary edges")
    edges = np.concatenate(per_part)
    first = np.cumsum([0, *(len(pe) for pe in per_part)])
    d = P[edges[:, 1]] - P[edges[:, 0]]
    length = np.linalg.norm(d, axis=1)
    nrm = np.column_stack([d[:, 1], -d[:, 0]]) / length[:, None]
    w_vertex, w_mid = space.trace_weights(edges)
    nsum = np.zeros((nv, 2))
    np.add.at(nsum, edges[:, 0], nrm)
    np.add.at(nsum, edges[:, 1], nrm)
    taken = np.zeros(nv, dtype=bool)
    ids_l, arc_l, part_l, mid_l = [], [], [], []
    for i, pe in enumerate(per_part):
        order, arc = _chains(pe, P, nv)
        out_edge = -np.ones(nv, dtype=np.int64)
        out_edge[pe[:, 0]] = np.arange(len(pe))
        se = out_edge[order]  # the edge leaving each vertex of the chain (-1 at its end)
        keep_v = ~taken[order]
        taken[order] = True
        n = len(order)
        # positions 2 j (vertex j) and 2 j + 1 (midpoint of its outgoing edge)
        ids = np.empty(2 * n, dtype=np.int64)
        ids[0::2] = order
        ids[1::2] = first[i] + np.maximum(se, 0)  # a row of `edges` (a midpoint)
        s = np.empty(2 * n)
        s[0::2] = arc
        s[1::2] = arc + 0.5 * length[ids[1::2]]
        is_mid = np.zeros(2 * n, dtype=bool)
        is_mid[1::2] = True
        keep = np.empty(2 * n, dtype=bool)
        keep[0::2], keep[1::2] = keep_v, se >= 0
        ids_l.append(ids[keep])
        arc_l.append(s[keep])
        mid_l.append(is_mid[keep])
        part_l.append(np.full(int(keep.sum()), i, dtype=np.int64))
    ids, s, is_mid = np.concatenate(ids_l), np.concatenate(arc_l), np.concatenate(mid_l)
    part = np.concatenate(part_l)
    verts, mids = ids[~is_mid], ids[is_mid]
    T = space.trace_operator(verts, edges[mids])  # rows: the vertices, then the midpoints
    pos = np.empty(len(ids), dtype=np.int64)
    pos[~is_mid] = np.arange(len(verts))
    pos[is_mid] = len(verts) + np.arange(len(mids))
    T = sp.csr_matrix(T[np.column_stack([2 * pos, 2 * pos + 1]).ravel()])
    if constrained is None:
        constrained = np.zeros(space.n_dofs, dtype=bool)
        if "clamped" in mesh.part_names:
            for dofs in space.component_dofs(mesh.part_edges("clamped")):
                constrained[dofs] = True
    # a node whose displacement is prescribed in both components is no contact node
    loose = abs(T) @ (~np.asarray(constrained, dtype=bool)).astype(float) > 0
    keep = loose.reshape(-1, 2).any(axis=1)
    if not np.any(keep):
        raise MeshError("every contact vertex is also clamped: no contact node is left")
    ids, s, is_mid, part = ids[keep], s[keep], is_mid[keep], part[keep]
    T = sp.csr_matrix(T[np.column_stack([keep, keep]).ravel()])
    mid_edges = edges[ids[is_mid]]
    nodes = ids.copy()
    nodes[is_mid] = nv + edge_ids(mesh, mid_edges[:, 0], mid_edges[:, 1])
    points = np.empty((len(ids), 2))
    points[~is_mid] = P[ids[~is_mid]]
    points[is_mid] = 0.5 * (P[mid_edges[:, 0]] + P[mid_edges[:, 1]])
    weights = np.empty(len(ids))
    weights[~is_mid] = w_vertex[ids[~is_mid]]
    weights[is_mid] = w_mid[ids[is_mid]]
    normals = np.empty((len(ids), 2))
    nv_sum = nsum[ids[~is_mid]]
    normals[~is_mid] = nv_sum / np.linalg.norm(nv_sum, axis=1)[:, None]
    normals[is_mid] = nrm[ids[is_mid]]
    tangents = np.column_stack([-normals[:, 1], normals[:, 0]])
    return ContactBoundary(
        nodes=nodes,
        points=points,
        s=s,
        weights=weights,
        normals=normals,
        tangents=tangents,
        n_dof=space.n_dofs,
        part=part,
        part_names=tuple(parts),
        trace=T,
    )
