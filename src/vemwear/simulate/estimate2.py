"""The contact terms of the residual estimator for k = 2 (docs/method.md, section 11).

For k = 2 the contact nodes of Gamma_C are its vertices and its edge midpoints
(:func:`~vemwear.contact.boundary.contact_boundary`, Simpson's weights), and a
displacement is quadratic along every edge piece: its vertex values and its edge mean
fix it, the midpoint value being ``(6 mean - u_a - u_b) / 4``. The terms of k = 1
(:func:`vemwear.simulate.estimate.estimate`) carry over with quadratic interpolation
between the three nodes of a piece in place of the linear one:

* ``C_K = sum h_e ||t_C - sigma(Pi u) n||_e^2``, the traction of the layers against that of
  the quadratic ``Pi u``, at the three Gauss points of every piece, with ``u_nu``, the
  gap, the wear, ``p_rigid`` and ``mu n*.tau`` quadratic along the piece and the
  compliance law evaluated at the Gauss points;
* ``Q_K = |int_e p_rigid (g + gap - u_nu) ds|`` with both factors quadratic along the
  piece, integrated exactly (zero at the nodes, where the step problem holds it; not zero
  on a piece whose nodes are partly in contact with the rigid layer).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..vem.dofs2 import GAUSS3, P2Fields, edge_ids, numbering2
from ..vem.estimator import cell_sums
from ..vem.estimator2 import traction_terms2

if TYPE_CHECKING:
    from .problem import Problem

__all__ = ["contact_data", "contact_terms2", "layer_traction"]

FloatArray = NDArray[np.float64]

_S = GAUSS3[0]
#: The quadratic Lagrange basis of the nodes (start, midpoint, end) at the Gauss points.
_PHI = np.stack([(1 - _S) * (1 - 2 * _S), 4 * _S * (1 - _S), _S * (2 * _S - 1)])


def contact_data(
    problem: Problem, p_rigid: FloatArray, wear: ArrayLike | None, t: float
) -> tuple[Any, int, FloatArray, dict[str, FloatArray], FloatArray, NDArray[np.bool_]]:
    """What the contact terms of either order read: the contact boundary, its number of
    nodes, the wear (zero when None), the nodal data, ``mu n*.tau`` at ``t`` and which
    nodes take the friction on the total pressure; ``p_rigid`` checked."""
    cb = problem.contact
    m = len(cb.nodes)
    if p_rigid.shape != (m,):
        raise ValueError(f"p_rigid must have one value per contact node ({m}), got {p_rigid.shape}")
    w = np.zeros(m) if wear is None else np.asarray(wear, dtype=float)
    total = np.array([pc.friction_on == "total" for pc in problem.parts])[cb.part]
    return cb, m, w, problem.nodal, problem.discrete.friction(t), total


def layer_traction(
    problem: Problem,
    part: NDArray[np.int64],
    total: NDArray[np.bool_],
    r: FloatArray,
    p_rigid: FloatArray,
    fric: FloatArray,
    n: FloatArray,
    tau: FloatArray,
) -> FloatArray:
    """The layers' traction ``t_C`` at the Gauss points (pieces, 3, 2) of pieces of the
    contact ``part`` (index into ``problem.parts``) with unit normals ``n`` and tangents
    ``tau``: the compliance law of the part at the penetration ``r``, the rigid pressure and
    ``mu n*.tau`` at the points, friction on the total pressure where ``total``."""
    ps = np.empty_like(r)
    for i, pc in enumerate(problem.parts):  # a few parts, each law on its points at once
        sel = part == i
        ps[sel] = np.asarray(pc.p(r[sel]), dtype=float)
    ft = np.where(total[:, None], ps + p_rigid, ps) * fric
    return np.asarray(-(ps + p_rigid)[..., None] * n[:, None, :] - ft[..., None] * tau[:, None, :])


def contact_terms2(
    problem: Problem,
    u: FloatArray,
    fields: P2Fields,
    p_rigid: FloatArray,
    wear: ArrayLike | None,
    t: float,
    contact: set[str],
) -> tuple[FloatArray, FloatArray]:
    """``C_K`` and ``Q_K`` (module docstring) per cell, from all the dofs ``u`` of the k = 2
    space and its projection ``fields``."""
    mesh = problem.mesh
    nc = mesh.n_cells
    con, comp = np.zeros(nc), np.zeros(nc)
    rows = np.concatenate(
        [np.flatnonzero(mesh.boundary_tags == mesh.part_code(name)) for name in sorted(contact)]
    )
    if not contact or rows.size == 0:
        return con, comp
    cb, m, w, nodal, fric, total = contact_data(problem, p_rigid, wear, t)
    E, C = mesh.boundary_edges[rows], mesh.boundary_edge_cells[rows]
    eid = edge_ids(mesh, E[:, 0], E[:, 1])
    node_of = np.full(mesh.n_points + len(mesh.edges), -1, dtype=np.int64)
    node_of[cb.nodes] = np.arange(m)
    # the nodes (start, midpoint, end) of every piece; a node that is not a contact node
    # (both components prescribed) takes the data of the midpoint, or of the other end,
    # and no rigid pressure or friction (as for k = 1)
    idx = np.stack([node_of[E[:, 0]], node_of[mesh.n_points + eid], node_of[E[:, 1]]])
    on = idx >= 0
    fill = np.where(on[1], idx[1], np.where(on[0], idx[0], idx[2]))
    data = np.where(on, idx, fill[None, :])

    def at_gauss(v: FloatArray, zero_off: bool = False) -> FloatArray:
        """Nodal values, quadratic along every piece, at its Gauss points: (pieces, 3)."""
        vals = v[data]
        if zero_off:
            vals = np.where(on, vals, 0.0)
        return np.einsum("kg,ke->eg", _PHI, vals)

    # the displacement at the three nodes of every piece, from the dofs
    num = numbering2(mesh)
    uv = u[: 2 * mesh.n_points].reshape(-1, 2)
    mean = u[num.edge_offset : num.cell_offset].reshape(-1, 2)[eid]
    ua, ub = uv[E[:, 0]], uv[E[:, 1]]
    um = (6.0 * mean - ua - ub) / 4.0
    d = mesh.points[E[:, 1]] - mesh.points[E[:, 0]]
    L = np.hypot(d[:, 0], d[:, 1])
    n = np.column_stack([d[:, 1], -d[:, 0]]) / L[:, None]
    tau = np.column_stack([-n[:, 1], n[:, 0]])
    un_nodes = np.stack([np.sum(x * n, axis=1) for x in (ua, um, ub)])
    un = np.einsum("kg,ke->eg", _PHI, un_nodes)
    r = un - at_gauss(nodal["gap"]) - at_gauss(w)
    pr = at_gauss(p_rigid, zero_off=True)
    fg = at_gauss(fric, zero_off=True)
    tgt = layer_traction(problem, cb.part[fill], total[fill], r, pr, fg, n, tau)
    con += traction_terms2(mesh, fields, problem.material, E, C, tgt)
    # p_rigid times the slack, both quadratic along the piece (the slack at the nodes'
    # normals), integrated exactly by the three Gauss points
    assert cb.trace is not None  # k = 2 contact nodes always carry their trace operator
    U_nodes = np.asarray(cb.trace @ u).reshape(-1, 2)
    slack = nodal["g"] + nodal["gap"] - np.sum(U_nodes * cb.normals, axis=1)
    q = L * np.einsum("g,eg->e", GAUSS3[1], pr * at_gauss(slack))
    comp += cell_sums(C, np.abs(q), minlength=nc)
    return con, comp
