"""The contact part Gamma_C of a polyhedral mesh (docs/method.md, section 10, "Contact").

The contact nodes are the vertices of the contact faces that are not fixed (all three
components prescribed). Node ``a`` has the weight ``omega_a = sum_F w_a^F`` (each contact
face's area shared among its vertices by the face vertex weights of the space, exact for
constants and for linear fields on triangles and parallelograms), the unit normal
``nu_a`` (the weight-averaged outward normal of its contact faces, across edges and
corners) and the tangent plane ``nu_a^perp``.

Friction is folded into one tangential row per node as in 2D where the foundation
velocity of a part keeps one line, ``v*(t) = s(t) e`` (its length and sign may change in time),
so its tangential part at a node is ``v*_tau(a, t) = s(t) e_tau(a)`` with
``e_tau = e - (e . nu_a) nu_a``. The node's tangent ``tau_a = e_tau / |e_tau|`` is that
line; then ``v* . tau_a = +-|v*_tau|``, the friction direction is
``n* = -sign(v* . tau_a) tau_a`` and the wear rate ``alpha = kappa |v* . tau_a|``,
exactly the 2D formulas of :class:`~vemwear.simulate.discrete.Discretization`. Where
``e`` is normal to the face (``e_tau = 0``) the tangent is any unit tangent and
``v* . tau_a = 0``: no friction and no wear there. A field ``v*(x, t)`` whose direction
keeps one line at every node (a disc turning at a constant rate) has one row per node
too, along its own line; a v* that turns in time at some node gets two fixed tangential
rows per node, ``tau_1, tau_2``, whose coefficients follow ``v*_tau`` level by level
(:func:`sliding_lines`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..mesh.polyhedra import Mesh3D
from ..mesh.polymesh import MeshError
from ..vem.space3d import P1Space3D, tangent_basis
from .boundary import ContactBoundary
from .parts import ContactPart, velocity_levels

__all__ = ["contact_boundary3d", "foundation_rows", "sliding_lines", "velocity_line"]


def _line_tangents(e: NDArray[np.float64], nu: NDArray[np.float64]) -> NDArray[np.float64]:
    """The unit tangents ``e_tau / |e_tau|`` of the lines ``e`` (m, 3) at nodes with
    normals ``nu``; the first tangent of :func:`tangent_basis` where ``e`` is normal
    (or zero)."""
    e_tau = e - np.sum(e * nu, axis=1)[:, None] * nu
    length = np.linalg.norm(e_tau, axis=1)
    slides = length > 1e-12 * np.maximum(np.linalg.norm(e, axis=1), 1e-300)
    tau, _ = tangent_basis(nu)
    tau[slides] = e_tau[slides] / length[slides, None]
    return tau


def sliding_lines(cb: ContactBoundary, lines: NDArray[np.float64] | None) -> ContactBoundary:
    """The contact boundary with the friction rows of a v* that is a field or turns.

    Parameters
    ----------
    cb : ContactBoundary
    lines : (m, 3) array or None
        The line ``e_a`` of v* at every node (its direction at node a keeps one line in
        time): one friction row per node, ``tau_a = e_tau / |e_tau|``, as for a v* of
        one line. None: v* turns at some node, and friction gets two rows per node, the
        fixed tangents ``tau_1, tau_2`` of :func:`tangent_basis` (``tangents`` and
        ``tangents2``), whose coefficients ``mu n* . tau_k`` follow v*_tau level by
        level (docs/method.md, section 10).
    """
    if lines is not None:
        return dataclasses.replace(cb, tangents=_line_tangents(lines, cb.normals))
    t1, t2 = tangent_basis(cb.normals)
    return dataclasses.replace(cb, tangents=t1, tangents2=t2)


def foundation_rows(
    cb: ContactBoundary, parts: Sequence[ContactPart], t: NDArray[np.float64]
) -> ContactBoundary:
    """The contact boundary (built with each part's line of v*) with the friction rows
    its foundation velocities need on the time grid ``t``: unchanged where every part's
    v* is of the time alone and keeps one line; one row per node along the node's own
    line where v* is a field whose direction keeps one line at every node; two rows per
    node where v* turns at some node (:func:`sliding_lines`)."""
    lines = np.zeros((cb.m, 3))
    spatial = False
    for i, pc in enumerate(parts):
        sel = cb.part == i
        if not pc.velocity.spatial:
            try:
                lines[sel] = velocity_line(velocity_levels(pc.velocity, t))
            except ValueError:
                return sliding_lines(cb, None)
            continue
        spatial = True
        E, keeps = _field_lines(pc, cb.points[sel], t)
        if not keeps:
            return sliding_lines(cb, None)
        lines[sel] = E
    return sliding_lines(cb, lines) if spatial else cb


def _field_lines(
    pc: ContactPart, points: NDArray[np.float64], t: NDArray[np.float64]
) -> tuple[NDArray[np.float64], bool]:
    """The line of a v* field at each of the points (the direction of its longest sample
    over the levels) and whether every sample keeps it: two passes over the levels in
    blocks of about a million numbers."""
    m = len(points)
    block = max(1, 2**20 // max(3 * m, 1))
    top, E = np.zeros(m), np.zeros((m, 3))
    for a in range(0, len(t), block):
        with np.errstate(all="ignore"):
            V = np.array([pc.velocity.at(points, float(x)) for x in t[a : a + block]])
        speed = np.linalg.norm(V, axis=2)
        j = np.argmax(speed, axis=0)
        longer = speed[j, np.arange(m)] > top
        top[longer] = speed[j, np.arange(m)][longer]
        E[longer] = V[j, np.arange(m)][longer]
    E /= np.where(top > 0, top, 1.0)[:, None]
    for a in range(0, len(t), block):
        with np.errstate(all="ignore"):
            V = np.array([pc.velocity.at(points, float(x)) for x in t[a : a + block]])
        if np.any(np.linalg.norm(np.cross(V, E[None]), axis=2) > 1e-12 * top[None]):
            return E, False
    return E, True


def velocity_line(V: NDArray[np.float64], name: str = "v_star") -> NDArray[np.float64]:
    """The unit direction ``e`` of a foundation velocity sampled at many times.

    Parameters
    ----------
    V : (L, 3) array
        ``v*(t_n)`` at the levels.
    name : str
        For messages.

    Returns
    -------
    (3,) array
        The direction of the longest sample (zeros if v* vanishes at every level).

    Raises
    ------
    ValueError
        If two samples are not parallel (v* turns): the one-row friction of the step
        problem needs a fixed line.
    """
    V = np.asarray(V, dtype=float).reshape(-1, 3)
    speed = np.linalg.norm(V, axis=1)
    top = float(speed.max(initial=0.0))
    if top == 0.0:
        return np.zeros(3)
    e = V[int(np.argmax(speed))] / top
    off = np.linalg.norm(np.cross(V, e), axis=1)
    bad = np.flatnonzero(off > 1e-12 * top)
    if bad.size:
        raise ValueError(
            f"{name} must keep one line in 3D (its length and sign may change): it is "
            f"{V[bad[0]].tolist()} at level {int(bad[0])}, not parallel to {e.tolist()}; "
            "a turning foundation velocity is not supported yet"
        )
    return np.asarray(e, dtype=np.float64)


def contact_boundary3d(
    mesh: Mesh3D,
    parts: Sequence[str] = ("contact",),
    fixed: NDArray[np.bool_] | None = None,
    space: P1Space3D | None = None,
    directions: NDArray[np.float64] | None = None,
) -> ContactBoundary:
    """Build the contact data of the parts ``parts`` of a tagged polyhedral mesh.

    Parameters
    ----------
    mesh : Mesh3D
    parts : sequence of str
        The contact parts, in order; a vertex shared by two parts belongs to the first
        (its weight and normal take the faces of both).
    fixed : (n_points,) bool array, optional
        Vertices that are no contact nodes (all three components prescribed); by
        default the vertices of the ``clamped`` part.
    space : P1Space3D, optional
        The space whose face vertex weights give the nodal weights and normals.
    directions : (len(parts), 3) array, optional
        The line ``e`` of each part's foundation velocity (:func:`velocity_line`); the
        node's tangent is its normalized tangential part. By default the x axis.

    Returns
    -------
    ContactBoundary
        With ``s`` the x coordinate of the nodes (3D has no arc length).
    """
    sp3 = P1Space3D(mesh) if space is None else space
    parts = tuple(parts)
    per_part = [mesh.part_faces(name) for name in parts]
    for name, faces in zip(parts, per_part, strict=True):
        if len(faces) == 0:
            raise MeshError(f"the mesh has no {name!r} boundary faces")
    faces = np.concatenate(per_part)
    weight, _ = sp3.trace_weights(faces)
    normal = sp3.trace_normals(faces)
    if fixed is None:
        fixed = np.zeros(mesh.n_points, dtype=bool)
        if "clamped" in mesh.part_names:
            fixed[sp3.facet_vertices(mesh.part_faces("clamped"))] = True
    taken = np.array(fixed, dtype=bool, copy=True)
    nodes_l, part_l = [], []
    for i, pf in enumerate(per_part):
        v = sp3.facet_vertices(pf)
        v = v[~taken[v]]
        taken[v] = True
        nodes_l.append(v)
        part_l.append(np.full(len(v), i, dtype=np.int64))
    nodes, part = np.concatenate(nodes_l), np.concatenate(part_l)
    if nodes.size == 0:
        raise MeshError("every contact vertex is also clamped: no contact node is left")
    nu = normal[nodes]
    if directions is None:
        directions = np.tile([1.0, 0.0, 0.0], (len(parts), 1))
    tau = _line_tangents(np.asarray(directions, dtype=float).reshape(len(parts), 3)[part], nu)
    points = mesh.points[nodes]
    return ContactBoundary(
        nodes=nodes,
        points=points,
        s=points[:, 0].copy(),
        weights=weight[nodes],
        normals=nu,
        tangents=tau,
        n_dof=sp3.n_dofs,
        part=part,
        part_names=parts,
    )
