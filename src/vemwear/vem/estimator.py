"""The element terms of the residual a posteriori estimator, k = 1 (docs/method.md, section 11).

For a displacement ``u`` (vertex values) on a polygonal mesh, with ``sigma_K`` the
(constant) stress of ``Pi u`` on cell K (3.8)-(3.10) and ``h_e`` the length of an edge
piece (the part of a cell side between two consecutive vertices, so a side with a
hanging node is two pieces, each with its own neighbour):

* :func:`volume_terms`: ``h_K^2 ||f1 + div sigma(Pi u)||_K^2 = h_K^2 ||f1||_K^2`` (the
  projection is linear, its stress constant);
* :func:`jump_terms`: ``1/2 sum_e h_e ||[sigma(Pi u) n]||_e^2`` over the interior pieces
  of ``dK``, half to each side (the neighbour across a piece is the cell of the reversed
  directed edge: every hanging node is a vertex of both cells);
* :func:`traction_terms`: ``sum_e h_e ||t - sigma(Pi u) n||_e^2`` over given boundary
  pieces with a target traction ``t`` (the load f2 on Gamma_N; the contact traction on
  Gamma_C), by three-point Gauss on every piece;
* :func:`stabilization_terms`: ``S^K((I - Pi) u, (I - Pi) u)``, with the weight of the
  stiffness (3.11).

Each returns one number per cell; the work is batched by vertex count or by edge, with
no loop over cells. :func:`elasticity_terms` weighs them into energies,

    ``C_R^2 R_K / m_C``, ``C_E^2 J_K / m_C``, ``C_E^2 N_K / m_C``, ``S_K``,

with ``m_C = 2 eta`` (the coercivity of C) and the constants :data:`ELEMENT_CONSTANT`
and :data:`EDGE_CONSTANT`; the contact terms are added above, by
:func:`vemwear.simulate.estimate.estimate`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh
from .dofs2 import GAUSS3
from .local import STABILIZATIONS, Material
from .projection import Projection, local_projection, projection_matrix
from .quadrature import Field, eval_field, polygon_quadrature

#: ``C_R``: the element term's constant, Payne and Weinberger's 1/pi of the Poincaré
#: inequality ``||v - v_K||_K <= h_K / pi ||grad v||_K`` on convex cells.
ELEMENT_CONSTANT = 1.0 / np.pi
#: ``C_E``: the edge terms' constant, from the trace inequality ``||v - v_K||_e^2 <= C_E^2
#: h_e ||grad v||_K^2`` on the unit square (1/4 for the linear mode ``x - 1/2``).
EDGE_CONSTANT = 0.5


__all__ = [
    "EDGE_CONSTANT",
    "ELEMENT_CONSTANT",
    "GAUSS3",
    "cell_stresses",
    "cell_sums",
    "edge_gauss_points",
    "elasticity_terms",
    "jump_terms",
    "load_residuals",
    "stabilization_terms",
    "traction_terms",
    "volume_terms",
]

FloatArray = NDArray[np.float64]


def cell_sums(index: NDArray[np.int64], weights: FloatArray, minlength: int) -> FloatArray:
    """Sums of ``weights`` per cell ``index`` (``minlength`` cells), as floats."""
    return np.asarray(np.bincount(index, weights, minlength=minlength), dtype=np.float64)


def cell_stresses(mesh: Mesh, material: Material, u: ArrayLike) -> FloatArray:
    """``sigma(Pi u)`` on every cell, (n_cells, 2, 2): ``2 eta eps + lam tr(eps) I``."""
    eps = Projection(mesh)(np.asarray(u, dtype=float).reshape(-1)).strain
    sig = 2.0 * material.eta * eps
    tr = material.lam * (eps[:, 0, 0] + eps[:, 1, 1])
    sig[:, 0, 0] += tr
    sig[:, 1, 1] += tr
    return sig


def _normals(mesh: Mesh, edges: NDArray[np.int64]) -> tuple[FloatArray, FloatArray]:
    """Lengths and ``|e| n`` (outward for the edge's cell) of directed edges (m, 2)."""
    d = mesh.points[edges[:, 1]] - mesh.points[edges[:, 0]]
    return np.hypot(d[:, 0], d[:, 1]), np.column_stack([d[:, 1], -d[:, 0]])


def volume_terms(mesh: Mesh, f1: Field, t: float = 0.0) -> FloatArray:
    """``h_K^2 ||f1||_{L2(K)}^2`` per cell (degree-5 rule on the fan of every cell)."""
    x, w, cell = polygon_quadrature(mesh, degree=5)
    f = eval_field(f1, x, t, "body force f1")
    sq = cell_sums(cell, w * np.sum(f * f, axis=1), minlength=mesh.n_cells)
    return mesh.cell_diameters**2 * sq


def jump_terms(mesh: Mesh, stress: FloatArray) -> FloatArray:
    """``1/2 sum_e h_e ||[sigma n]||_e^2`` per cell over its interior edge pieces.

    The stress is constant on each cell, so on a piece of length ``L`` with unit normal
    ``n`` the term is ``L^2 |(sigma_K - sigma_K') n|^2``; each directed piece of K gives
    half of it to K (its twin gives the other half to K').
    """
    twin = mesh.edge_twins
    rows = np.flatnonzero(twin >= 0)
    de = mesh.directed_edges[rows]
    _, Ln = _normals(mesh, de)
    jump = np.einsum(
        "mij,mj->mi", stress[mesh.edge_cells[rows]] - stress[mesh.edge_cells[twin[rows]]], Ln
    )
    # |jump|^2 with the unnormalized Ln is L^2 |(.) n|^2 = h_e ||.||_e^2
    return 0.5 * cell_sums(
        mesh.edge_cells[rows], np.sum(jump * jump, axis=1), minlength=mesh.n_cells
    )


def edge_gauss_points(mesh: Mesh, edges: NDArray[np.int64]) -> FloatArray:
    """The three Gauss points of every edge (m, 2): shape (m, 3, 2)."""
    s = GAUSS3[0]
    a, b = mesh.points[edges[:, 0]], mesh.points[edges[:, 1]]
    return a[:, None, :] + s[None, :, None] * (b - a)[:, None, :]


def traction_terms(
    mesh: Mesh,
    stress: FloatArray,
    edges: NDArray[np.int64],
    cells: NDArray[np.int64],
    target: FloatArray,
) -> FloatArray:
    """``sum_e h_e ||t - sigma(Pi u) n||_e^2`` per cell over boundary pieces.

    Parameters
    ----------
    mesh : Mesh
    stress : (n_cells, 2, 2) array
        :func:`cell_stresses`.
    edges : (m, 2) int array
        Boundary pieces, oriented as in their cell (:attr:`Mesh.boundary_edges`).
    cells : (m,) int array
        Their cells.
    target : (m, 3, 2) array
        The traction ``t`` at the Gauss points of every piece (:func:`edge_gauss_points`).
    """
    if len(edges) == 0:
        return np.zeros(mesh.n_cells)
    L, Ln = _normals(mesh, edges)
    sn = np.einsum("mij,mj->mi", stress[cells], Ln / L[:, None])
    r = target - sn[:, None, :]
    sq = L * L * np.einsum("g,mg->m", GAUSS3[1], np.sum(r * r, axis=2))
    return cell_sums(cells, sq, minlength=mesh.n_cells)


def stabilization_terms(
    mesh: Mesh, material: Material, u: ArrayLike, stabilization: str = "paper"
) -> FloatArray:
    """``S^K((I - Pi) u, (I - Pi) u)`` per cell, with the weight ``s_K`` of the stiffness
    (:func:`~vemwear.vem.local.element_matrices`): zero on triangles."""
    if stabilization not in STABILIZATIONS:
        raise ValueError(
            f"unknown stabilization {stabilization!r}; expected one of {', '.join(STABILIZATIONS)}"
        )
    U = np.asarray(u, dtype=float).reshape(-1, 2)
    out = np.zeros(mesh.n_cells)
    for n, (ids, verts) in mesh.groups.items():
        if n == 3:
            continue
        lp = local_projection(mesh.points[verts])
        P = projection_matrix(lp)
        v = U[verts].reshape(len(ids), 2 * n)
        r = v - np.einsum("mij,mj->mi", P, v)
        s = np.sum(r * r, axis=1)
        if stabilization == "eta":
            s *= 2.0 * material.eta
        elif stabilization == "trace":
            # tr(|K| B^T D B) = sum_i (D00 qx_i^2 + D11 qy_i^2 + D22 (qx_i^2 + qy_i^2)) / |K|
            D = material.D
            qx, qy = lp.q[..., 0], lp.q[..., 1]
            tr = np.sum((D[0, 0] + D[2, 2]) * qx * qx + (D[1, 1] + D[2, 2]) * qy * qy, axis=1)
            s *= tr / lp.area / (2 * n)
        out[ids] = s
    return out


def load_residuals(
    mesh: Mesh,
    tractions: Mapping[str, Field],
    t: float,
    residual: Callable[[NDArray[np.int64], NDArray[np.int64], FloatArray], FloatArray],
) -> FloatArray:
    """``N_K`` per cell: ``residual(edges, cells, target)`` (the traction terms of a
    projection, :func:`traction_terms` for k = 1) summed over the parts with a load, the
    target the part's f2 at the three Gauss points of every piece."""
    be, bc = mesh.boundary_edges, mesh.boundary_edge_cells
    out = np.zeros(mesh.n_cells)
    for name, f2 in tractions.items():
        rows = np.flatnonzero(mesh.boundary_tags == mesh.part_code(name))
        if rows.size:
            x = edge_gauss_points(mesh, be[rows]).reshape(-1, 2)
            tgt = eval_field(f2, x, t, f"traction of {name!r}").reshape(-1, 3, 2)
            out += residual(be[rows], bc[rows], tgt)
    return out


def elasticity_terms(
    mesh: Mesh,
    material: Material,
    u: ArrayLike,
    f1: Field,
    tractions: Mapping[str, Field],
    stabilization: str = "paper",
    t: float = 0.0,
) -> tuple[dict[str, FloatArray], FloatArray]:
    """The element, jump, traction and stabilization terms in energy units (module
    docstring), and the stresses of ``Pi u``.

    Parameters
    ----------
    mesh : Mesh
    material : Material
    u : (n_points, 2) array_like
    f1 : Field
        The body force.
    tractions : mapping of part name to Field
        The parts with a traction term and their f2 (a free part: ``(0, 0)``).
    stabilization : str
        The stiffness's (:func:`~vemwear.vem.local.element_matrices`).
    t : float
        The time of the loads.

    Returns
    -------
    terms : dict with keys ``element``, ``jump``, ``traction``, ``stabilization``
    stress : (n_cells, 2, 2) array
    """
    U = np.asarray(u, dtype=float).reshape(mesh.n_points, 2)
    sig = cell_stresses(mesh, material, U)

    def residual(edges: NDArray[np.int64], cells: NDArray[np.int64], tgt: FloatArray) -> FloatArray:
        return traction_terms(mesh, sig, edges, cells, tgt)

    traction = load_residuals(mesh, tractions, t, residual)
    ce = EDGE_CONSTANT**2 / material.coercivity
    terms = {
        "element": ELEMENT_CONSTANT**2 / material.coercivity * volume_terms(mesh, f1, t),
        "jump": ce * jump_terms(mesh, sig),
        "traction": ce * traction,
        "stabilization": stabilization_terms(mesh, material, U, stabilization),
    }
    return terms, sig
