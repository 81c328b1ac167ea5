"""Nodal values on Gamma_C carried to the contact nodes of another mesh (docs/method.md,
section 11): the wear when an adaptive mesh changes.

A value of the old mesh lives at its contact nodes and is piecewise linear along its
contact edges (docs/method.md section 3), or for k = 2 piecewise quadratic through the
vertices and the edge midpoints. A new node that is an old node takes the old value
there, exactly (bitwise): a kept vertex, or for k = 2 an old midpoint that refinement
made a vertex; a new node inside an old contact edge takes the interpolant along that
edge. An end of an old edge that is
not a contact node (a clamped end of Gamma_C) carries 0, the convention of the nodal
quadrature (its weight there is 0): refinement then keeps the integral of the values by
the nodal quadrature, and the worn volume with it.
Refining and coarsening keep Gamma_C as a set, so every new node lies on an old contact
edge; a point that does not is refused, naming it. On a curved Gamma_C, refinement puts
the new nodes onto the curve (:mod:`vemwear.mesh.curves`), off the old edge by about its
sagitta: ``off_chord`` then accepts a node within that fraction of the old edge's length
from it, and gives it the value at its projection onto the edge.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.locate import extent_tol, point_segment_distance
from ..mesh.polymesh import Mesh, MeshError
from ..vem.dofs2 import edge_ids

__all__ = ["transfer_along_contact", "vertex_slopes"]


def transfer_along_contact(
    mesh: Mesh,
    nodes: ArrayLike,
    values: ArrayLike,
    points: ArrayLike,
    parts: Sequence[str] = ("contact",),
    off_chord: float = 0.0,
    cubic: bool = False,
) -> NDArray[np.float64]:
    """The piecewise linear function of ``values`` along the contact edges of ``mesh``,
    at ``points`` (module docstring).

    Parameters
    ----------
    mesh : Mesh
        The old mesh.
    nodes : (m,) int array_like
        Its contact nodes: vertex ids (k = 1), and for k = 2 edge midpoints as
        ``n_points + e``, ``e`` the row of :attr:`Mesh.edges`.
    values : (m,) array_like
        The values there.
    points : (q, 2) array_like
        The new contact nodes.
    parts : sequence of str
        The contact parts whose edges carry the function.
    off_chord : float
        Accept a node up to this fraction of an old edge's length away from the edge
        (0: only nodes on the edges, within round-off; see
        :data:`~vemwear.mesh.curves.OFF_CHORD`).
    cubic : bool
        k = 1: the monotone piecewise cubic through the values (:func:`_node_slopes`)
        instead of the piecewise linear function; kept nodes keep their values as well.

    Returns
    -------
    (q,) array
    """
    nodes = np.asarray(nodes, dtype=np.int64)
    v = np.asarray(values, dtype=float)
    if v.shape != nodes.shape:
        raise ValueError(
            f"values must have one entry per contact node ({len(nodes)}), got {v.shape}"
        )
    X = np.asarray(points, dtype=float).reshape(-1, 2)
    E = np.concatenate([mesh.part_edges(p) for p in parts])
    if len(E) == 0:
        raise MeshError(f"the mesh has no edges on the contact parts {list(parts)}")
    quadratic = bool(np.any(nodes >= mesh.n_points))  # k = 2: midpoint nodes
    node_of = np.full(mesh.n_points + (len(mesh.edges) if quadratic else 0), -1, dtype=np.int64)
    node_of[nodes] = np.arange(len(nodes))
    ia, ib = node_of[E[:, 0]], node_of[E[:, 1]]
    va = np.where(ia >= 0, v[np.maximum(ia, 0)], 0.0) if len(v) else np.zeros(len(E))
    vb = np.where(ib >= 0, v[np.maximum(ib, 0)], 0.0) if len(v) else np.zeros(len(E))
    if quadratic:
        im = node_of[mesh.n_points + edge_ids(mesh, E[:, 0], E[:, 1])]
        vm = np.where(im >= 0, v[np.maximum(im, 0)], 0.0)
    A, B = mesh.points[E[:, 0]], mesh.points[E[:, 1]]
    from scipy.spatial import cKDTree  # imported when used: a run without adaptivity never is

    tol = extent_tol(mesh.points, None)
    k = min(8, len(E))
    _, cand = cKDTree(0.5 * (A + B)).query(X, k=k)
    cand = np.asarray(cand).reshape(len(X), k)
    dist, s = point_segment_distance(X[:, None, :], A[cand], B[cand])
    best = np.argmin(dist, axis=1)
    rows = np.arange(len(X))
    e = cand[rows, best]
    far = dist[rows, best] > tol
    if off_chord > 0:
        far &= dist[rows, best] > tol + off_chord * np.linalg.norm(B[e] - A[e], axis=1)
    if np.any(far):
        q = int(np.flatnonzero(far)[0])
        raise MeshError(
            f"new contact node {q} at {X[q].tolist()} lies on no contact edge of the old mesh"
        )
    t = s[rows, best]
    L = np.linalg.norm(B[e] - A[e], axis=1)
    if quadratic:  # the quadratic through the start, the midpoint and the end
        if cubic:
            raise ValueError("the cubic transfer is for k = 1 (vertex nodes only)")
        out = (1 - t) * (1 - 2 * t) * va[e] + 4 * t * (1 - t) * vm[e] + t * (2 * t - 1) * vb[e]
        at_m = np.abs(t - 0.5) * L <= tol  # an old midpoint, now a vertex: its value
        out[at_m] = vm[e[at_m]]
    elif cubic:  # cubic Hermite on the edge with the nodes' monotone slopes
        d = _node_slopes(mesh, E, va, vb)
        da, db = d[E[e, 0]] * L, d[E[e, 1]] * L
        t2, t3 = t * t, t * t * t
        out = (
            (2 * t3 - 3 * t2 + 1) * va[e]
            + (t3 - 2 * t2 + t) * da
            + (3 * t2 - 2 * t3) * vb[e]
            + (t3 - t2) * db
        )
    else:
        out = (1.0 - t) * va[e] + t * vb[e]
    # kept vertices: the old value itself, not a rounded interpolant
    at_a = t * L <= tol
    at_b = (1.0 - t) * L <= tol
    out[at_a] = va[e[at_a]]
    out[at_b] = vb[e[at_b]]
    return out


def _node_slopes(
    mesh: Mesh, E: NDArray[np.int64], va: NDArray[np.float64], vb: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The slope along Gamma_C at every vertex of the contact edges ``E`` (oriented along
    the boundary, values ``va`` at their starts and ``vb`` at their ends) for a monotone
    piecewise cubic (Fritsch and Carlson, as SciPy's PCHIP): zero where the slopes of the
    two edges at a vertex differ in sign (a local extremum stays one, no overshoot), their
    weighted harmonic mean otherwise; at an end of a chain of edges, the slope of its
    edge."""
    L = np.linalg.norm(mesh.points[E[:, 1]] - mesh.points[E[:, 0]], axis=1)
    d_in, d_out, h_in, h_out = vertex_slopes(mesh.n_points, E, (vb - va) / L, L)
    w1, w2 = 2 * h_out + h_in, h_out + 2 * h_in
    same = d_in * d_out > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = (w1 + w2) / (w1 / d_in + w2 / d_out)
    both = (h_in > 0) & (h_out > 0)
    return np.where(both, np.where(same, mean, 0.0), d_in + d_out)


def vertex_slopes(
    n: int, E: NDArray[np.int64], slope: NDArray[np.float64], L: NDArray[np.float64]
) -> tuple[NDArray[np.float64], ...]:
    """At each of ``n`` vertices, the slope and length of the edge of ``E`` (oriented along
    the boundary) that ends there and of the one that starts there: ``(s_in, s_out, L_in,
    L_out)``, zero where there is none (the ends of a chain of edges)."""
    s_in, s_out, l_in, l_out = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    s_in[E[:, 1]], l_in[E[:, 1]] = slope, L
    s_out[E[:, 0]], l_out[E[:, 0]] = slope, L
    return s_in, s_out, l_in, l_out
