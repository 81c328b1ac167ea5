"""The element terms of the residual a posteriori estimator, k = 2 (docs/method.md, section 11).

The terms of :mod:`vemwear.vem.estimator` with the quadratic projection ``Pi u`` of
:func:`~vemwear.vem.dofs2.project2` (3.8, with the k >= 2 rigid-motion conditions):
its stress ``sigma_K = sigma(Pi u)`` is linear on every cell, so

* the element term is the oscillation of the load, ``h_K^2 ||f1 - Pi_0^K f1||_K^2``: the
  residual ``f1 + div sigma_K`` is tested with ``v - I v``, the interpolation error of a
  function of H^1; the dofs of k = 2 contain the cell means, so an interpolant that keeps
  them gives ``int_K (v - I v) = 0``, and the constant part of the residual, where the
  constant ``div sigma_K`` lies, drops out (for k = 1 the vertex values keep no mean and
  the term stays ``h_K^2 ||f1||_K^2``);
* the jumps ``1/2 sum_e h_e ||[sigma n]||_e^2`` and the boundary residuals ``sum_e h_e ||t -
  sigma n||_e^2`` are integrated by three-point Gauss on every edge piece (exact for the
  jumps, which are linear along a piece);
* the stabilization term is ``S^K((I - Pi) u, (I - Pi) u) = a_h^K(u, u) - a^K(Pi u, Pi
  u)`` (3.11) with the local stiffness itself, so it carries the stiffness's own weight
  ``s_K`` whatever the stabilization.

The constants and the energy scaling are those of k = 1 (:func:`elasticity_terms2` returns
the same keys as :func:`~vemwear.vem.estimator.elasticity_terms`); the contact terms are
added by :func:`vemwear.simulate.estimate.estimate`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh
from .dofs2 import GAUSS3, P2Fields, cell_dofs2, project2
from .estimator import (
    EDGE_CONSTANT,
    ELEMENT_CONSTANT,
    cell_sums,
    edge_gauss_points,
    load_residuals,
)
from .local import Material
from .local2 import element_matrices2
from .quadrature import Field, eval_field, polygon_quadrature

__all__ = [
    "edge_stresses",
    "elasticity_terms2",
    "jump_terms2",
    "stabilization_terms2",
    "stress_at",
    "traction_terms2",
    "volume_terms2",
]

FloatArray = NDArray[np.float64]


def stress_at(fields: P2Fields, material: Material, x: ArrayLike, cells: ArrayLike) -> FloatArray:
    """``sigma(Pi u)`` of ``cells[j]`` at the points ``x[j]``: (q, 2, 2)."""
    _, grad = fields.at(x, cells)
    eps = 0.5 * (grad + grad.transpose(0, 2, 1))
    sig = 2.0 * material.eta * eps
    tr = material.lam * (eps[:, 0, 0] + eps[:, 1, 1])
    sig[:, 0, 0] += tr
    sig[:, 1, 1] += tr
    return sig


def volume_terms2(mesh: Mesh, f1: Field, t: float = 0.0) -> FloatArray:
    """``h_K^2 ||f1 - Pi_0^K f1||_{L2(K)}^2`` per cell (degree-5 rule on the fan): the
    element residual ``f1 + div sigma(Pi u)`` less its mean, which is orthogonal to the
    interpolation error of a cell-mean-preserving interpolant (module docstring);
    ``div sigma(Pi u)`` is constant on K and drops out with the mean."""
    x, w, cell = polygon_quadrature(mesh, degree=5)
    f = eval_field(f1, x, t, "body force f1")
    area = cell_sums(cell, w, minlength=mesh.n_cells)
    mean = np.column_stack(
        [cell_sums(cell, w * f[:, c], minlength=mesh.n_cells) / area for c in range(2)]
    )
    r = f - mean[cell]
    sq = cell_sums(cell, w * np.sum(r * r, axis=1), minlength=mesh.n_cells)
    return mesh.cell_diameters**2 * sq


def edge_stresses(
    mesh: Mesh,
    fields: P2Fields,
    material: Material,
    edges: NDArray[np.int64],
    cells: NDArray[np.int64],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``sigma(Pi u)`` of ``cells`` at the three Gauss points of their ``edges`` (m, 3, 2,
    2), the lengths (m,) and the unit normals (m, 2) of the edges (outward for a
    counter-clockwise cell)."""
    d = mesh.points[edges[:, 1]] - mesh.points[edges[:, 0]]
    L = np.hypot(d[:, 0], d[:, 1])
    n = np.column_stack([d[:, 1], -d[:, 0]]) / L[:, None]
    x = edge_gauss_points(mesh, edges).reshape(-1, 2)
    sig = stress_at(fields, material, x, np.repeat(cells, 3)).reshape(-1, 3, 2, 2)
    return sig, L, n


def jump_terms2(mesh: Mesh, fields: P2Fields, material: Material) -> FloatArray:
    """``1/2 sum_e h_e ||[sigma n]||_e^2`` per cell over its interior edge pieces (half to
    each side, as for k = 1), by three-point Gauss along every piece."""
    twin = mesh.edge_twins
    rows = np.flatnonzero(twin >= 0)
    de = mesh.directed_edges[rows]
    mine, L, n = edge_stresses(mesh, fields, material, de, mesh.edge_cells[rows])
    other, _, _ = edge_stresses(mesh, fields, material, de, mesh.edge_cells[twin[rows]])
    jump = np.einsum("mgij,mj->mgi", mine - other, n)
    sq = L * L * np.einsum("g,mg->m", GAUSS3[1], np.sum(jump * jump, axis=2))
    return 0.5 * cell_sums(mesh.edge_cells[rows], sq, minlength=mesh.n_cells)


def traction_terms2(
    mesh: Mesh,
    fields: P2Fields,
    material: Material,
    edges: NDArray[np.int64],
    cells: NDArray[np.int64],
    target: FloatArray,
) -> FloatArray:
    """``sum_e h_e ||t - sigma(Pi u) n||_e^2`` per cell over boundary pieces, with the
    traction ``t`` (m, 3, 2) at the Gauss points of every piece (as
    :func:`~vemwear.vem.estimator.traction_terms`)."""
    if len(edges) == 0:
        return np.zeros(mesh.n_cells)
    sig, L, n = edge_stresses(mesh, fields, material, edges, cells)
    r = target - np.einsum("mgij,mj->mgi", sig, n)
    sq = L * L * np.einsum("g,mg->m", GAUSS3[1], np.sum(r * r, axis=2))
    return cell_sums(cells, sq, minlength=mesh.n_cells)


def stabilization_terms2(
    mesh: Mesh, material: Material, u: ArrayLike, stabilization: str = "paper"
) -> FloatArray:
    """``S^K((I - Pi) u, (I - Pi) u) = a_h^K(u, u) - a^K(Pi u, Pi u)`` per cell (3.11), from
    all the dofs ``u`` of the k = 2 space; rounding below zero is cut to zero."""
    v = np.asarray(u, dtype=float).reshape(-1)
    out = np.zeros(mesh.n_cells)
    for _n, (ids, verts) in mesh.groups.items():
        loc = element_matrices2(mesh.points[verts], material, stabilization)
        x = v[cell_dofs2(mesh, ids, verts)]
        c = np.einsum("mal,ml->ma", loc.projection.pi, x)
        full = np.einsum("ml,mlk,mk->m", x, loc.K, x)
        consistent = np.einsum("ma,mab,mb->m", c, loc.projection.energy, c)
        out[ids] = np.maximum(full - consistent, 0.0)
    return out


def elasticity_terms2(
    mesh: Mesh,
    material: Material,
    u: ArrayLike,
    f1: Field,
    tractions: Mapping[str, Field],
    stabilization: str = "paper",
    t: float = 0.0,
) -> tuple[dict[str, FloatArray], P2Fields]:
    """The element, jump, traction and stabilization terms of k = 2 in energy units, and
    ``Pi u`` (the k = 1 :func:`~vemwear.vem.estimator.elasticity_terms` with ``u`` all the
    dofs of the second-order space)."""
    fields = project2(mesh, material, u)

    def residual(edges: NDArray[np.int64], cells: NDArray[np.int64], tgt: FloatArray) -> FloatArray:
        return traction_terms2(mesh, fields, material, edges, cells, tgt)

    traction = load_residuals(mesh, tractions, t, residual)
    ce = EDGE_CONSTANT**2 / material.coercivity
    terms = {
        "element": ELEMENT_CONSTANT**2 / material.coercivity * volume_terms2(mesh, f1, t),
        "jump": ce * jump_terms2(mesh, fields, material),
        "traction": ce * traction,
        "stabilization": stabilization_terms2(mesh, material, u, stabilization),
    }
    return terms, fields
