"""The residual a posteriori estimator of the step problem in 2D (docs/method.md, section
11); below for k = 1, :mod:`.estimate2` for the contact terms of k = 2.

For a solved step (displacement ``u``, pressures ``p_soft`` and ``p_rigid`` at the
contact nodes, wear ``w``), the squared indicator of cell K is

    eta_K^2 = (C_R^2 R_K + C_E^2 (J_K + N_K + C_K)) / m_C + S_K + Q_K

with ``m_C = 2 eta`` (the coercivity of C, turning squared tractions into energies) and
the constants ``C_R = 1/pi`` and ``C_E = 1/2`` (:data:`ELEMENT_CONSTANT`,
:data:`EDGE_CONSTANT`):

* ``R_K = h_K^2 ||f1||_K^2``, the element residual (``div sigma(Pi u) = 0`` for k = 1);
* ``J_K``, the jumps of ``sigma(Pi u) n`` across the interior edge pieces of K (hanging
  nodes included), half to each side;
* ``N_K = sum h_e ||f2 - sigma(Pi u) n||_e^2`` over the pieces of K on the traction and
  free parts (f2 = 0 on free parts);
* ``C_K = sum h_e ||t_C - sigma(Pi u) n||_e^2`` over the pieces of K on Gamma_C, with the
  traction of the layers ``t_C = -(p(u_nu - gap - w) + p_rigid) nu - mu (n*.tau)
  p(u_nu - gap - w) tau`` (``p_soft + p_rigid`` in the friction term with
  ``friction_on = "total"``): ``u_nu``, the gap, the wear, ``p_rigid`` and ``mu n*.tau``
  linear along the piece between their nodal values, the compliance law ``p`` evaluated
  at the Gauss points (so the residual also measures ``p(u_nu) - I_h p(u_nu)``);
* ``S_K = S^K((I - Pi) u, (I - Pi) u)``, the stabilization of (3.11);
* ``Q_K = |int_e p_rigid (g + gap - u_nu) ds|`` over the pieces of K on Gamma_C, the
  complementarity of the rigid layer with both factors linear along the piece (zero at
  the nodes, where the step problem holds it; not zero on a piece whose one end is in
  contact with the rigid layer and the other is not).

Clamped and prescribed parts and the parts of rigid holders carry no boundary term (their
traction is a reaction, not data).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh
from ..vem.estimator import EDGE_CONSTANT, GAUSS3, elasticity_terms, traction_terms
from ..vem.estimator2 import elasticity_terms2
from ..vem.quadrature import Field
from .estimate2 import contact_data, contact_terms2, layer_traction
from .problem import Problem

if TYPE_CHECKING:
    from .loop import Result

__all__ = ["TERMS", "Estimate", "estimate", "estimate_last"]

FloatArray = NDArray[np.float64]

#: The terms of the estimator, in the order of docs/method.md section 11.
TERMS = ("element", "jump", "traction", "contact", "stabilization", "complementarity")


@dataclass(frozen=True)
class Estimate:
    """The estimator of one solved step problem.

    Attributes
    ----------
    terms : dict of str to (n_cells,) arrays
        The terms of :data:`TERMS` per cell, in energy units (the traction terms divided
        by ``m_C``).
    """

    terms: dict[str, FloatArray]

    @property
    def indicators(self) -> FloatArray:
        """``eta_K^2`` per cell: the sum of the terms."""
        return np.sum([self.terms[k] for k in TERMS], axis=0)

    @property
    def total(self) -> float:
        """``eta = sqrt(sum_K eta_K^2)``."""
        return float(np.sqrt(self.indicators.sum()))

    def share(self) -> dict[str, float]:
        """The fraction of ``eta^2`` of every term."""
        tot = float(self.indicators.sum())
        return {k: float(v.sum()) / tot if tot > 0 else 0.0 for k, v in self.terms.items()}


def _boundary_roles(problem: Problem) -> tuple[dict[str, Field], set[str]]:
    """``{part: f2}`` of the parts with a traction term (traction parts, and free parts
    with f2 = 0) and the names of the contact parts."""
    mesh = problem.mesh
    held = set(problem.clamped)
    held |= {d.part for d in problem.displacement} | {r.part for r in problem.rigid}
    contact = {pc.part for pc in problem.parts}
    loads: dict[str, Field] = dict(problem.tractions)
    for name in mesh.parts:
        if name not in held and name not in contact and name not in loads:
            loads[name] = (0.0, 0.0)
    return loads, contact


def _part_rows(mesh: Mesh, name: str) -> NDArray[np.int64]:
    return np.flatnonzero(mesh.boundary_tags == mesh.part_code(name))


def estimate(
    problem: Problem,
    u: ArrayLike,
    p_rigid: ArrayLike,
    wear: ArrayLike | None = None,
    level: int = -1,
) -> Estimate:
    """The residual estimator of the step problem at a time level (module docstring; for
    k = 2 the terms of :mod:`vemwear.vem.estimator2` and :mod:`.estimate2`).

    Parameters
    ----------
    problem : Problem
        A 2D problem of order 1 or 2.
    u : array_like
        The displacement of the step: the vertex values (n_points, 2) for k = 1; all the
        dofs (``problem.space.n_dofs``,) for k = 2 (``Result.dofs``).
    p_rigid : (m,) array_like
        The rigid-layer pressure at the contact nodes.
    wear : (m,) array_like, optional
        The wear of the step problem (w^n); zero by default.
    level : int
        The time level (its time gives the loads and the friction).

    Returns
    -------
    Estimate
    """
    mesh = problem.mesh
    if not isinstance(mesh, Mesh) or problem.order not in (1, 2):
        raise ValueError("the a posteriori estimator is implemented for k = 1 and 2 in 2D")
    t = float(problem.time.t[level])
    mat = problem.material
    loads, contact = _boundary_roles(problem)
    pr = np.asarray(p_rigid, float)
    # the terms of the order: k = 2 reads every dof, k = 1 the vertex values
    elastic: Any
    contact_terms: Any
    U: FloatArray = np.asarray(u, dtype=float)
    if problem.order == 2:
        U = U.reshape(-1)
        if U.size != problem.space.n_dofs:
            raise ValueError(
                f"k = 2: u must hold all {problem.space.n_dofs} dofs of the space (Result.dofs), "
                f"got {U.size} values"
            )
        elastic, contact_terms = elasticity_terms2, contact_terms2
    else:
        U = U.reshape(mesh.n_points, 2)
        elastic, contact_terms = elasticity_terms, _contact_terms
    terms, fields = elastic(mesh, mat, U, problem.f1, loads, problem.stabilization, t)
    con, comp = contact_terms(problem, U, fields, pr, wear, t, contact)
    terms["contact"] = EDGE_CONSTANT**2 / mat.coercivity * con
    terms["complementarity"] = comp
    return Estimate(terms)


def _contact_terms(
    problem: Problem,
    U: FloatArray,
    sig: FloatArray,
    p_rigid: FloatArray,
    wear: ArrayLike | None,
    t: float,
    contact: set[str],
) -> tuple[FloatArray, FloatArray]:
    """``C_K`` and ``Q_K`` (module docstring) per cell."""
    mesh = problem.mesh
    nc = mesh.n_cells
    con, comp = np.zeros(nc), np.zeros(nc)
    if not contact:
        return con, comp
    cb, m, w, nodal, fric, total = contact_data(problem, p_rigid, wear, t)
    node_of = np.full(mesh.n_points, -1, dtype=np.int64)
    node_of[cb.nodes] = np.arange(m)
    be, bc = mesh.boundary_edges, mesh.boundary_edge_cells
    rows = np.concatenate([_part_rows(mesh, name) for name in sorted(contact)])
    if rows.size == 0:
        return con, comp
    E, C = be[rows], bc[rows]
    ia, ib = node_of[E[:, 0]], node_of[E[:, 1]]
    # an end that is not a contact node (clamped) takes the data of the other end, and
    # no rigid pressure or friction
    ia_, ib_ = np.where(ia >= 0, ia, ib), np.where(ib >= 0, ib, ia)
    d = mesh.points[E[:, 1]] - mesh.points[E[:, 0]]
    L = np.hypot(d[:, 0], d[:, 1])
    n = np.column_stack([d[:, 1], -d[:, 0]]) / L[:, None]
    tau = np.column_stack([-n[:, 1], n[:, 0]])
    s = GAUSS3[0][None, :]

    def lin(va: FloatArray, vb: FloatArray) -> FloatArray:
        return (1 - s) * va[:, None] + s * vb[:, None]

    def nodal_at(v: FloatArray, zero_off: bool = False) -> FloatArray:
        va, vb = v[ia_], v[ib_]
        if zero_off:
            va, vb = np.where(ia >= 0, va, 0.0), np.where(ib >= 0, vb, 0.0)
        return lin(va, vb)

    un = lin(np.sum(U[E[:, 0]] * n, axis=1), np.sum(U[E[:, 1]] * n, axis=1))
    r = un - nodal_at(nodal["gap"]) - nodal_at(w)
    pr, fg = nodal_at(p_rigid, zero_off=True), nodal_at(fric, zero_off=True)
    tgt = layer_traction(problem, cb.part[ia_], total[ia_], r, pr, fg, n, tau)
    con += traction_terms(mesh, sig, E, C, tgt)
    # int_e p_rigid * slack for both linear: L/6 (2 a A + a B + b A + 2 b B)
    pa, pb = np.where(ia >= 0, p_rigid[ia_], 0.0), np.where(ib >= 0, p_rigid[ib_], 0.0)
    slack = nodal["g"] + nodal["gap"]
    u_nu = np.sum(U[cb.nodes] * cb.normals, axis=1)  # with the nodes' normals (3.4)
    sa, sb = slack[ia_] - u_nu[ia_], slack[ib_] - u_nu[ib_]
    q = L / 6.0 * (2 * pa * sa + pa * sb + pb * sa + 2 * pb * sb)
    comp += np.bincount(C, np.abs(q), minlength=nc)
    return con, comp


def estimate_last(problem: Problem, result: Result, level: int = -1) -> Estimate:
    """:func:`estimate` of the last stored level of ``result``, the time level ``level``
    of ``problem`` (for k = 2 with every dof, ``Result.dofs``)."""
    u = result.u[-1] if result.dofs is None else result.dofs[-1]
    return estimate(problem, u, result.p_rigid[-1], result.wear[-1], level=level)
