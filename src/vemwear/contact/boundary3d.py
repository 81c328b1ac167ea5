"""The contact part Gamma_C of a polyhedral mesh (docs/method.md, section 10, "Contact").

The contact nodes are the vertices of the contact faces that are not fixed (all three
components prescribed). Node ``a`` has the weight ``omega_a = sum_F w_a^F`` (each contact
face's area shared among its vertices by the face vertex weights of the space, exact for
constants and for linear fields on triangles and parallelograms), the unit normal
``nu_a`` (the weight-averaged outward normal of its contact faces, across edges and
corners) and the tangent plane ``nu_a^perp``.

Friction is folded into one tangential row per node as in 2D: the foundation velocity
of a part keeps one line, ``v*(t) = s(t) e`` (its length and sign may change in time),
so its tangential part at a node is ``v*_tau(a, t) = s(t) e_tau(a)`` with
``e_tau = e - (e . nu_a) nu_a``. The node's tangent ``tau_a = e_tau / |e_tau|`` is that
line; then ``v* . tau_a = +-|v*_tau|``, the friction direction is
``n* = -sign(v* . tau_a) tau_a`` and the wear rate ``alpha = kappa |v* . tau_a|``,
exactly the 2D formulas of :class:`~vemwear.simulate.discrete.Discretization`. Where
``e`` is normal to the face (``e_tau = 0``) the tangent is any unit tangent and
``v* . tau_a = 0``: no friction and no wear there. A foundation velocity that turns in
3D (two directions that are not parallel) would need the tangential row to change in
time; it is refused (:func:`velocity_line`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..mesh.polyhedra import Mesh3D
from ..mesh.polymesh import MeshError
from ..vem.space3d import P1Space3D, tangent_basis
from .boundary import ContactBoundary

__all__ = ["contact_boundary3d", "velocity_line"]


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
    e = np.asarray(directions, dtype=float).reshape(len(parts), 3)[part]
    e_tau = e - np.sum(e * nu, axis=1)[:, None] * nu
    length = np.linalg.norm(e_tau, axis=1)
    slides = length > 1e-12 * np.maximum(np.linalg.norm(e, axis=1), 1e-300)
    tau, _ = tangent_basis(nu)
    tau[slides] = e_tau[slides] / length[slides, None]
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
