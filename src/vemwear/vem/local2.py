"""Second-order virtual elements (k = 2) for 2D elasticity: local dofs, Pi, element matrices.

The local space is the paper's ``V_h^K`` of Section 3.1 with k = 2: ``v`` quadratic on
every edge, ``div sigma(v)`` constant in K. Its degrees of freedom on a cell with ``n``
vertices ``x_1, ..., x_n`` (counter-clockwise; edge ``e_i = [x_i, x_{i+1}]``) are, in the
local order used everywhere below (``N = 4 n + 2`` of them):

* ``2 i + c`` (``i < n``): the vertex value ``v_c(x_i)``;
* ``2 n + 2 i + c``: the edge moment ``(1/|e_i|) int_{e_i} v_c ds`` (moment against P0);
* ``4 n + c``: the cell moment ``(1/|K|) int_K v_c dx``.

All of them are displacements (the moments are means), so the dofi-dofi stabilization
weighs them alike. Polynomials are written in the scaled monomials
``m_j = 1, xi, eta, xi^2, xi eta, eta^2`` with ``(xi, eta) = (x - x_K) / h_K`` (``x_K`` the
vertex average, ``h_K`` the diameter), and ``[P2(K)]^2`` in the basis ``q_0..q_11`` of
:data:`BASIS`: the three rigid motions first (``e_x``, ``e_y``, the rotation
``(-eta, xi)``), then the three linear strains ``(xi, 0)``, ``(0, eta)``, ``(eta, xi)``, then
``m_j e_c`` for the quadratic ``m_j``.

**The projection Pi (3.8).** ``a^K(Pi v, q) = a^K(v, q)`` for the nine ``q`` that are not rigid
motions. The right-hand side is computable from the dofs by parts:
``a^K(v, q) = -int_K v . div sigma(q) dx + int_dK v . sigma(q) n ds``. ``div sigma(q)`` is
constant, so the cell term is ``-|K| div sigma(q) . (cell moment)``; on an edge ``v`` is
quadratic (vertex values and the edge mean fix it: the midpoint value is
``(6 mean - v_a - v_b) / 4``) and ``sigma(q) n`` linear, so Simpson's rule is exact.
**Rigid motions**, the standard k >= 2 choice (replacing (3.9)-(3.10)):

* ``(1/|K|) int_K Pi v dx = (1/|K|) int_K v dx``: the cell moment, a dof (2 conditions);
* ``int_K rot Pi v dx = int_K rot v dx = int_dK v . t ds = sum_i |e_i| mean_i . t_i``
  (Green's formula, ``rot v = d_x v_y - d_y v_x``, ``t`` the counter-clockwise tangent):
  the edge moments only.

Both right-hand sides are exact functionals of ``v`` and exact for ``v`` in ``[P2]^2``, so
``Pi q = q`` on ``[P2]^2``; the vertex averages (3.9)-(3.10) of the paper are a k = 1 device
(for k = 1 there is no cell moment), see docs/method.md, "Second order (k = 2)".

**Bilinear form (3.11).** ``a_h^K = a^K(Pi u, Pi v) + s_K sum_i chi_i((I - Pi) u) chi_i((I -
Pi) v)``, the dofi-dofi stabilization with the k = 1 weights (:mod:`vemwear.vem.local`).

Everything is batched by vertex count: arrays of shape ``(m, n, 2)`` for ``m`` cells.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .local import STABILIZATIONS, Material
from .quadrature import fan

__all__ = [
    "BASIS",
    "N_BASIS",
    "Local2",
    "LocalProjection2",
    "basis_gradients",
    "basis_values",
    "cell_geometry",
    "element_matrices2",
    "local_dof_count",
    "local_projection2",
    "monomials",
]

Array = NDArray[np.float64]

#: Number of basis functions of ``[P2(K)]^2``.
N_BASIS = 12


def _basis() -> NDArray[np.float64]:
    """``T[a, j, c]``: ``q_a = sum_{j, c} T[a, j, c] m_j e_c``."""
    T = np.zeros((N_BASIS, 6, 2))
    T[0, 0, 0] = T[1, 0, 1] = 1.0  # translations
    T[2, 2, 0], T[2, 1, 1] = -1.0, 1.0  # rotation (-eta, xi)
    T[3, 1, 0] = T[4, 2, 1] = 1.0  # (xi, 0), (0, eta)
    T[5, 2, 0] = T[5, 1, 1] = 1.0  # (eta, xi)
    for k, j in enumerate((3, 4, 5)):
        T[6 + 2 * k, j, 0] = T[7 + 2 * k, j, 1] = 1.0
    return T


#: The basis of ``[P2(K)]^2`` in the scaled monomials: ``BASIS[a, j, c]``.
BASIS = _basis()
BASIS.setflags(write=False)

# d m_j / d xi and d m_j / d eta in the linear monomials (1, xi, eta): [j, p]
_DXI = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0], [0, 2, 0], [0, 0, 1], [0, 0, 0]], float)
_DETA = np.array([[0, 0, 0], [0, 0, 0], [1, 0, 0], [0, 0, 0], [0, 1, 0], [0, 0, 2]], float)

#: ``h_K d_d (q_a)_c = sum_p GRAD[a, c, d, p] m_p`` (p over 1, xi, eta).
GRAD = np.stack(
    [np.einsum("ajc,jp->acp", BASIS, _DXI), np.einsum("ajc,jp->acp", BASIS, _DETA)], axis=2
)
#: Voigt strains ``h_K (eps_xx, eps_yy, 2 eps_xy)(q_a) = sum_p STRAIN[a, p, :] m_p``.
STRAIN = np.stack([GRAD[:, 0, 0], GRAD[:, 1, 1], GRAD[:, 0, 1] + GRAD[:, 1, 0]], axis=-1)
#: ``h_K rot q_a = sum_p ROT[a, p] m_p``.
ROT = GRAD[:, 1, 0] - GRAD[:, 0, 1]
# index of the monomial m_p m_r (p, r over 1, xi, eta) among the six
_PAIR = np.array([[0, 1, 2], [1, 3, 4], [2, 4, 5]])


def local_dof_count(n: int) -> int:
    """Local dofs of a cell with ``n`` vertices: ``2 n + 2 n + 2``."""
    return 4 * n + 2


def monomials(xi: Array) -> Array:
    """The six scaled monomials at scaled points ``xi`` (..., 2); shape (..., 6)."""
    x, y = xi[..., 0], xi[..., 1]
    return np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], axis=-1)


def basis_values(xi: Array) -> Array:
    """``q_a`` at scaled points (..., 2); shape (..., 12, 2)."""
    return np.einsum("...j,ajc->...ac", monomials(xi), BASIS)


def basis_gradients(xi: Array, h: Array) -> Array:
    """``d_d (q_a)_c`` at scaled points (..., 2) with the diameters ``h`` broadcast against
    ``xi[..., 0]``; shape (..., 12, 2, 2) indexed ``[a, c, d]``."""
    lin = monomials(xi)[..., :3]
    return np.einsum("...p,acdp->...acd", lin, GRAD) / np.asarray(h)[..., None, None, None]


def cell_geometry(X: Array) -> tuple[Array, Array, Array]:
    """Vertex averages ``x_K``, diameters ``h_K`` and the integrals of the six scaled
    monomials over every cell (the degree-2 rule on the fan: exact on any simple cell).

    Returns
    -------
    center : (m, 2) ; h : (m,) ; moments : (m, 6), ``moments[:, 0] = |K|``
    """
    f = fan(X)
    i, j = np.triu_indices(X.shape[1], 1)
    d = X[:, i] - X[:, j]
    h = np.sqrt((d[..., 0] ** 2 + d[..., 1] ** 2).max(axis=1))
    pts, w = f.points(2)
    xi = (pts - f.xbar[:, None, :]) / h[:, None, None]
    return f.xbar, h, np.einsum("mq,mqj->mj", w, monomials(xi))


def _traction(sig: Array, N: Array) -> Array:
    """``sigma N`` from Voigt stresses (..., 12, 3) and normals (..., 2) -> (..., 12, 2)."""
    nx, ny = N[..., None, 0], N[..., None, 1]
    sxx, syy, sxy = sig[..., 0], sig[..., 1], sig[..., 2]
    return np.stack([sxx * nx + sxy * ny, sxy * nx + syy * ny], axis=-1)


class LocalProjection2(NamedTuple):
    """``Pi`` of k = 2 on a batch of ``m`` cells with ``n`` vertices (:func:`local_projection2`)."""

    pi: Array  # (m, 12, N) coefficients of Pi v in BASIS from the local dofs, N = 4 n + 2
    dofs: Array  # (m, N, 12) the local dofs of the basis functions, chi_i(q_a)
    energy: Array  # (m, 12, 12) a^K(q_a, q_b)
    area: Array  # (m,)
    center: Array  # (m, 2) the vertex averages x_K
    h: Array  # (m,) the diameters h_K


class Local2(NamedTuple):
    """The k = 2 element quantities of a batch of cells (:func:`element_matrices2`)."""

    K: Array  # (m, N, N) local stiffness a_h^K (3.11)
    projection: LocalProjection2


def local_projection2(X: Array, material: Material) -> LocalProjection2:
    """The projection ``Pi`` (3.8) of k = 2 with the k >= 2 rigid-motion conditions (module
    docstring), as coefficients in :data:`BASIS` of the local dofs.

    Parameters
    ----------
    X : (m, n, 2) array
        Vertex coordinates, counter-clockwise.
    material : Material
        (3.8) is the energy projection: for k = 2 it depends on the Lamé coefficients.
    """
    m, n, _ = X.shape
    nd = local_dof_count(n)
    center, h, mom = cell_geometry(X)
    area = mom[:, 0]
    hh = h[:, None, None]
    Xn = np.roll(X, -1, axis=1)
    mid = 0.5 * (X + Xn)
    mv = monomials((X - center[:, None, :]) / hh)  # (m, n, 6) at the vertices
    mm = monomials((mid - center[:, None, :]) / hh)  # at the edge midpoints

    # chi_i(q_a): vertex values, edge means (Simpson, exact for quadratics), cell means
    D = np.empty((m, nd, N_BASIS))
    D[:, : 2 * n] = np.einsum("mij,ajc->mica", mv, BASIS).reshape(m, 2 * n, N_BASIS)
    edge_mean = (mv + 4.0 * mm + np.roll(mv, -1, axis=1)) / 6.0
    D[:, 2 * n : 4 * n] = np.einsum("mij,ajc->mica", edge_mean, BASIS).reshape(m, 2 * n, -1)
    D[:, 4 * n :] = np.einsum("mj,ajc->mca", mom / area[:, None], BASIS)

    # G[a, b] = a^K(q_a, q_b): C eps(q_a) : eps(q_b) is quadratic, from the moments
    Dm = material.D
    W = np.einsum("apk,kl,brl->prab", STRAIN, Dm, STRAIN)  # (3, 3, 12, 12)
    G = np.einsum("mpr,prab->mab", mom[:, _PAIR], W) / (h * h)[:, None, None]

    # a^K(v, q_a) from the dofs by parts (3.8); Voigt stresses h sigma(q_a) = sum_p SIG m_p
    SIG = np.einsum("kl,apl->apk", Dm, STRAIN)  # (12, 3, 3) [a, p, k]
    sv = np.einsum("mip,apk->miak", mv[..., :3], SIG) / hh[..., None]  # (m, n, 12, 3)
    sm = np.einsum("mip,apk->miak", mm[..., :3], SIG) / hh[..., None]
    d = Xn - X
    Nrm = np.stack([d[..., 1], -d[..., 0]], axis=-1)  # |e_i| n_i
    # Simpson on edge i with v(mid) = (6 mean_i - v_i - v_{i+1}) / 4:
    # int_e v . t ds = [v_i . (t_i - t_mid) + v_{i+1} . (t_{i+1} - t_mid)] / 6 + mean_i . t_mid
    t_mid = _traction(sm, Nrm)  # (m, n, 12, 2), tractions times |e_i|
    t_start = _traction(sv, Nrm) - t_mid  # vertex i on edge i
    t_end = _traction(np.roll(sv, -1, axis=1), Nrm) - t_mid  # vertex i + 1 on edge i
    wv = (t_start + np.roll(t_end, 1, axis=1)) / 6.0
    # div sigma(q_a), constant: d_k sigma = SIG[:, k + 1] / h^2
    div = np.stack([SIG[:, 1, 0] + SIG[:, 2, 2], SIG[:, 1, 2] + SIG[:, 2, 1]], axis=-1)
    B = np.empty((m, N_BASIS, nd))
    B[:, :, : 2 * n] = wv.transpose(0, 2, 1, 3).reshape(m, N_BASIS, 2 * n)
    B[:, :, 2 * n : 4 * n] = t_mid.transpose(0, 2, 1, 3).reshape(m, N_BASIS, 2 * n)
    B[:, :, 4 * n :] = -(area / (h * h))[:, None, None] * div[None]

    # rigid motions: the cell mean (rows 0, 1) and h_K / |K| times int_K rot (row 2)
    Gt = G.copy()
    Gt[:, :2] = D[:, 4 * n :]
    Gt[:, 2] = np.einsum("mp,ap->ma", mom[:, :3], ROT) / area[:, None]
    B[:, :3] = 0.0
    B[:, 0, 4 * n] = B[:, 1, 4 * n + 1] = 1.0
    B[:, 2, 2 * n : 4 * n] = (h / area)[:, None] * d.reshape(m, 2 * n)  # |e_i| t_i
    pi = np.linalg.solve(Gt, B)  # (m, 12, N)
    return LocalProjection2(pi, D, G, area, center, h)


def element_matrices2(X: Array, material: Material, stabilization: str = "paper") -> Local2:
    """Local stiffness matrices ``a_h^K`` (3.11) of k = 2 for a batch of cells.

    Parameters
    ----------
    X : (m, n, 2) array
        Vertex coordinates, counter-clockwise.
    material : Material
    stabilization : {"paper", "eta", "trace"}
        Weight ``s_K`` of the dofi-dofi term, as for k = 1: 1, ``2 eta``, or
        ``tr(K_c) / N`` with ``K_c`` the consistency matrix and ``N = 4 n + 2``.

    Returns
    -------
    Local2
        The stiffness ``K`` (m, N, N) and the projection (:func:`local_projection2`).
    """
    if stabilization not in STABILIZATIONS:
        raise ValueError(
            f"unknown stabilization {stabilization!r}; expected one of {', '.join(STABILIZATIONS)}"
        )
    lp = local_projection2(X, material)
    nd = lp.dofs.shape[1]
    K = np.matmul(lp.pi.transpose(0, 2, 1), np.matmul(lp.energy, lp.pi))  # a^K(Pi u, Pi v)
    IP = -np.matmul(lp.dofs, lp.pi)  # I - P, P the dofs of Pi v
    diag = np.arange(nd)
    IP[:, diag, diag] += 1.0
    S = np.matmul(IP.transpose(0, 2, 1), IP)  # the dofi-dofi term
    if stabilization == "eta":
        S *= 2.0 * material.eta
    elif stabilization == "trace":
        S *= (np.trace(K, axis1=1, axis2=2) / nd)[:, None, None]
    K += S
    K = 0.5 * (K + K.transpose(0, 2, 1))  # symmetric to round-off
    return Local2(K, lp)
