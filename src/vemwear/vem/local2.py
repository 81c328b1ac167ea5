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
centroid, ``h_K`` the diameter), and ``[P2(K)]^2`` in the basis ``q_0..q_11`` of
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

**Solving (3.8).** About the centroid ``int_K xi = int_K eta = 0``, so the energy does not
couple the linear strains to the quadratics: in the working basis of :func:`_constants` it is
diagonal but for the 2 x 2 matrix of second moments, and ``Pi`` has a closed form (no
inverse per cell, :func:`_project`).

**Bilinear form (3.11).** ``a_h^K = a^K(Pi u, Pi v) + s_K sum_i chi_i((I - Pi) u) chi_i((I -
Pi) v)``, the dofi-dofi stabilization with the k = 1 weights (:mod:`vemwear.vem.local`).

Everything is batched by vertex count: arrays of shape ``(m, n, 2)`` for ``m`` cells.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .local import STABILIZATIONS, Material
from .quadrature import fan

__all__ = [
    "BASIS",
    "N_BASIS",
    "ElementWork",
    "Local2",
    "LocalProjection2",
    "basis_gradients",
    "basis_values",
    "cell_geometry",
    "element_matrices2",
    "element_stiffness_into",
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
    """Vertex averages ``xbar``, diameters ``h_K`` and the integrals of the six monomials
    scaled about ``xbar`` over every cell (the degree-2 rule on the fan: exact on any simple cell).

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
    center: Array  # (m, 2) the centroids x_K
    h: Array  # (m,) the diameters h_K


class Local2(NamedTuple):
    """The k = 2 element quantities of a batch of cells (:func:`element_matrices2`)."""

    K: Array  # (m, N, N) local stiffness a_h^K (3.11)
    projection: LocalProjection2


#: ``D = rows @ _BT``: the dofs ``chi(q_a)`` from the monomials (or their means) at the
#: local nodes; ``_BT[j, 12 c + a] = BASIS[a, j, c]``.
_BT = np.ascontiguousarray(BASIS.transpose(1, 2, 0).reshape(6, 2 * N_BASIS))
_BT.setflags(write=False)


class _Tables(NamedTuple):
    """Constant tables of a material (:func:`_constants`)."""

    WJ: Array  # (6, 144): G = sum_j (h^-2 int_K m_j) WJ[j] in BASIS
    W: Array  # (12, 12): the working basis p_a = sum_b W[b, a] q_b
    SHT: Array  # (12, 12): B'/2 = SHT @ U, rows a, columns 6 c + (p, t)
    BTT: Array  # (12, 12): D' = BTT @ Dm, rows a, columns 6 c + j


@functools.lru_cache(maxsize=32)
def _constants(material: Material) -> _Tables:
    """The tables of a material.

    ``S`` (6, 24) with ``h sigma(q_a) N . e_c = sum_(p, t) m_p N_t S[(p, t), 12 c + a]``
    (``p`` over 1, xi, eta and ``t`` over the components of N; ``h^2 div sigma(q_a) . e_c
    = S[(1, 0), 12 c + a] + S[(2, 1), 12 c + a]``). The working basis ``W`` keeps the rigid
    motions and makes the energy diagonal about the centroid (:func:`_project`): the
    linear strains by ``L^-T`` with ``L L^T`` their energy per unit scaled area, the
    quadratics by ``T^-1 (I_2 (x) L_D^-T)`` with ``T`` the map from their coefficients to
    the strain gradient ``h^2 (d_x eps, d_y eps)`` (Voigt) and ``L_D L_D^T = D``.
    """
    Dm = material.D
    W4 = np.einsum("apk,kl,brl->prab", STRAIN, Dm, STRAIN)  # (3, 3, 12, 12)
    WJ = np.zeros((6, N_BASIS, N_BASIS))
    for p in range(3):
        for r in range(3):
            WJ[_PAIR[p, r]] += W4[p, r]
    SIG = np.einsum("kl,apl->apk", Dm, STRAIN)  # h sigma(q_a) = sum_p SIG[a, p] m_p (Voigt)
    S = np.zeros((3, 2, 2, N_BASIS))  # [p, t, c, a]: (sxx nx + sxy ny, sxy nx + syy ny)
    S[:, 0, 0], S[:, 1, 0] = SIG[:, :, 0].T, SIG[:, :, 2].T
    S[:, 0, 1], S[:, 1, 1] = SIG[:, :, 2].T, SIG[:, :, 1].T
    W = np.eye(N_BASIS)
    W[3:6, 3:6] = np.linalg.inv(np.linalg.cholesky(WJ[0, 3:6, 3:6])).T
    T = STRAIN[6:, 1:, :].reshape(6, 6).T  # [(p, k), a]
    LD = np.linalg.inv(np.linalg.cholesky(Dm)).T
    W[6:, 6:] = np.linalg.solve(T, np.kron(np.eye(2), LD))
    S2 = np.einsum("ptca,ab->ptcb", S, W).reshape(6, 2, N_BASIS)  # [(p, t), c, a]
    SHT = 0.5 * S2.transpose(2, 1, 0).reshape(N_BASIS, N_BASIS)
    BT = np.einsum("ajc,ab->jcb", BASIS, W)  # [j, c, a]
    BTT = BT.transpose(2, 1, 0).reshape(N_BASIS, N_BASIS)
    out = _Tables(WJ.reshape(6, -1), W, SHT, BTT)
    for a in out:
        a.setflags(write=False)
    return out


class ElementWork:
    """Buffers for the element work on up to ``m`` cells with ``n`` vertices, reused from
    batch to batch by :func:`element_stiffness_into` (fresh arrays of a few MB per batch
    cost more in page faults than the arithmetic).

    Component-major: ``X[a, k, l]`` is row ``a`` (of the working basis, or of the inputs
    ``6 c + j``) of cell ``k`` at local dof ``l``, so that the constant maps are single
    matrix products and every update is a contiguous block. The entries that do not depend
    on the cell (the translations' rows, the cell node of ``Dm``, the zero component
    halves) are written once here.
    """

    def __init__(self, m: int, n: int) -> None:
        nd = local_dof_count(n)
        self.m, self.n = m, n
        # monomial dofs and by-parts data, rows 6 c + j, at local dof 2 node + c only
        self.Dm = np.zeros((N_BASIS, m, 2 * n + 1, 2))
        self.Dm[0, :, :, 0] = self.Dm[6, :, :, 1] = 1.0
        self.U = np.zeros((N_BASIS, m, 2 * n + 1, 2))
        self.B = np.empty((N_BASIS, m, nd))  # B'/2: a^K(v, p_a) / 2 of the local dofs
        self.D = np.empty((N_BASIS, m, nd))  # the local dofs of p_a
        self.Pi = np.zeros((N_BASIS, m, nd))  # Pi in the working basis
        self.Pi[0, :, 4 * n] = self.Pi[1, :, 4 * n + 1] = 1.0
        self.Y = np.empty((N_BASIS, m, nd))
        self.M = np.empty((m, N_BASIS, N_BASIS))
        self.Z = np.empty((m, nd, nd))


#: Columns per call in :func:`_constant_product`.
_COLUMNS = 1024


def _constant_product(C: Array, X: Array, out: Array) -> None:
    """``out = C @ X`` for a small constant ``C`` (12, 12), in blocks of :data:`_COLUMNS`
    columns: a larger product would be threaded by OpenBLAS (above about 2.6e5
    multiply-adds), and waking its threads between the small products of a batch costs
    far more than the product on a busy machine."""
    for a in range(0, X.shape[1], _COLUMNS):
        np.matmul(C, X[:, a : a + _COLUMNS], out=out[:, a : a + _COLUMNS])


def _project(X: Array, material: Material, w: ElementWork) -> tuple[Array, Array, Array]:
    """``Pi`` (3.8) of a batch into ``w`` (``w.Pi`` in the working basis, ``w.B`` = B'/2,
    ``w.D`` the dofs of the working basis); returns the scaled moments about the centroid
    ``h^-2 int_K m_j`` (m, 6) (``[:, 1:3]`` zero), the centroids and the diameters.

    About the centroid the energy of the working basis ``p_a`` (:func:`_constants`) is
    ``G' = diag(0_3, |K|_h I_3, M_2 (x) I_3)`` (``|K|_h = h^-2 |K|``, ``M_2`` the scaled
    second moments): no linear-quadratic coupling, as ``int_K xi = int_K eta = 0``. So the
    non-rigid part is ``B'_lin / |K|_h`` and ``(M_2^-1 (x) I_3) B'_quad`` in closed form.
    The quadratics are taken with their cell mean removed (``m_j - mean_K m_j``, which
    does not change their strains), so every non-translation ``p_a`` has cell mean zero and
    rotation zero (the rotation of a quadratic is linear with mean zero): the cell-mean
    conditions give the translations as the cell moments, the rotation condition the
    rotation from the edge moments alone.
    """
    m, n, _ = X.shape
    tab = _constants(material)
    xy = X.transpose(2, 0, 1)  # (2, m, n)
    c0 = X.mean(axis=1).T
    P = np.empty((2, m, 2 * n))  # vertices about the vertex average, twice over
    np.subtract(xy, c0[:, :, None], out=P[:, :, :n])
    P[:, :, n:] = P[:, :, :n]
    d = P[:, :, :n, None] - P[:, :, None, :n]
    d *= d
    h = np.sqrt((d[0] + d[1]).reshape(m, n * n).max(axis=1))
    P /= h[:, None]
    ax, ay, bx, by = P[0, :, :n], P[1, :, :n], P[0, :, 1 : n + 1], P[1, :, 1 : n + 1]
    A = 0.5 * (ax * by - bx * ay)  # the fan from the vertex average, signed
    area = A.sum(axis=1)  # |K|_h
    gx = (A * (ax + bx)).sum(axis=1) / (3.0 * area)
    gy = (A * (ay + by)).sum(axis=1) / (3.0 * area)
    mom = np.zeros((m, 6))  # h^-2 int_K m_j about the centroid (parallel axes)
    mom[:, 0] = area
    sxy = (A * (2.0 * (ax * ay + bx * by) + ax * by + bx * ay)).sum(axis=1)
    mom[:, 3] = (A * (ax * ax + ax * bx + bx * bx)).sum(axis=1) / 6.0 - area * gx * gx
    mom[:, 4] = sxy / 12.0 - area * gx * gy
    mom[:, 5] = (A * (ay * ay + ay * by + by * by)).sum(axis=1) / 6.0 - area * gy * gy
    P[0] -= gx[:, None]
    P[1] -= gy[:, None]
    center = (c0 + h * np.stack([gx, gy])).T
    mx, my = 0.5 * (ax + bx), 0.5 * (ay + by)  # edge midpoints

    # the scalar monomial dofs j = 1..5 (vertex values, then edge means; cell means zero),
    # the quadratics mean-free
    V = np.empty((5, m, 2, n))
    V[0, :, 0], V[0, :, 1], V[1, :, 0], V[1, :, 1] = ax, mx, ay, my
    np.multiply(ax, ax, out=V[2, :, 0])
    V[2, :, 1] = (ax * ax + ax * bx + bx * bx) / 3.0
    np.multiply(ax, ay, out=V[3, :, 0])
    V[3, :, 1] = (2.0 * (ax * ay + bx * by) + ax * by + bx * ay) / 6.0
    np.multiply(ay, ay, out=V[4, :, 0])
    V[4, :, 1] = (ay * ay + ay * by + by * by) / 3.0
    V[2:] -= (mom[:, 3:] / area[:, None]).T[:, :, None, None]
    Dm = w.Dm[:, :m]
    Dm[1:6, :, : 2 * n, 0] = Dm[7:, :, : 2 * n, 1] = V.reshape(5, m, 2 * n)

    # a^K(v, q) by parts (3.8), U[(p, t)]: Simpson on edge i with v(mid) = (6 mean_i - v_i -
    # v_(i+1)) / 4: vertex i gets (t_i(x_i) + t_(i-1)(x_i) - t_i(mid_i) - t_(i-1)(mid_(i-1)))
    # / 6 (zero for p = 0), mean_i gets t_i(mid_i); the cell mean gets -|K| div sigma
    Nx, Ny = by - ay, ax - bx  # |e_i| n_i / h
    Nxs, Nys = Nx + np.roll(Nx, 1, axis=1), Ny + np.roll(Ny, 1, axis=1)
    Q = np.empty((6, m, 2, n))
    Uv, Ue = Q[:, :, 0], Q[:, :, 1]
    Ue[0], Ue[1], Uv[0], Uv[1] = Nx, Ny, 0.0, 0.0
    for p, vp, mp in ((1, ax, mx), (2, ay, my)):
        np.multiply(mp, Nx, out=Ue[2 * p])
        np.multiply(mp, Ny, out=Ue[2 * p + 1])
        np.multiply(vp, Nxs, out=Uv[2 * p])
        np.multiply(vp, Nys, out=Uv[2 * p + 1])
    Uv[2:] -= Ue[2:]
    Uv[2:] -= np.roll(Ue[2:], 1, axis=2)
    Uv[2:] /= 6.0
    U = w.U[:, :m]
    U[:6, :, : 2 * n, 0] = U[6:, :, : 2 * n, 1] = Q.reshape(6, m, 2 * n)
    U[2, :, 2 * n, 0] = U[5, :, 2 * n, 0] = U[8, :, 2 * n, 1] = U[11, :, 2 * n, 1] = -area

    B, D, Pi = w.B[:, :m], w.D[:, :m], w.Pi[:, :m]
    _constant_product(tab.SHT, U.reshape(N_BASIS, -1), B.reshape(N_BASIS, -1))
    _constant_product(tab.BTT, Dm.reshape(N_BASIS, -1), D.reshape(N_BASIS, -1))
    # rotation: h / |K| int_K rot Pi v = 2 pi_2 = sum_i |e_i| mean_i . t_i h / |K|
    r = 0.5 / area[:, None]
    np.multiply(bx - ax, r, out=Pi[2, :, 2 * n : 4 * n : 2])
    np.multiply(by - ay, r, out=Pi[2, :, 2 * n + 1 : 4 * n : 2])
    np.multiply(B[3:6], 2.0 / area[:, None], out=Pi[3:6])
    det = 2.0 / (mom[:, 3] * mom[:, 5] - mom[:, 4] ** 2)  # 2 M_2^-1 = [i11 i12; i12 i22]
    i11, i12, i22 = (mom[:, 5] * det)[:, None], (-mom[:, 4] * det)[:, None], (mom[:, 3] * det)
    B1, B2 = B[6:9], B[9:]
    np.multiply(B1, i11, out=Pi[6:9])
    Pi[6:9] += B2 * i12
    np.multiply(B2, i22[:, None], out=Pi[9:])
    Pi[9:] += B1 * i12
    return mom, center, h


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
    X = np.asarray(X, dtype=float)
    m, n, _ = X.shape
    nd = local_dof_count(n)
    w = ElementWork(m, n)
    mom, center, h = _project(X, material, w)
    tab = _constants(material)
    pi = np.matmul(tab.W, w.Pi.reshape(N_BASIS, -1)).reshape(N_BASIS, m, nd)
    # the quadratics of the working basis are mean-free: q_(6 + 2 k + c) = m_(3 + k) e_c
    # minus its mean (mom[3 + k] / |K|_h) e_c
    mu = mom[:, 3:] / mom[:, :1]
    for c in range(2):
        pi[c] -= np.einsum("kml,mk->ml", pi[6 + c :: 2], mu)
    Dm = np.ascontiguousarray(w.Dm[:6, :, :, 0].transpose(1, 2, 0))  # (m, 2 n + 1, 6)
    Dm[:, :, 3:] += mu[:, None, :]  # the quadratics with their means (cell rows: the means)
    dofs = np.matmul(Dm, _BT).reshape(m, nd, N_BASIS)
    G = np.matmul(mom, tab.WJ).reshape(m, N_BASIS, N_BASIS)
    return LocalProjection2(
        np.ascontiguousarray(pi.transpose(1, 0, 2)), dofs, G, mom[:, 0] * h * h, center, h
    )


def _check_stabilization(stabilization: str) -> None:
    if stabilization not in STABILIZATIONS:
        raise ValueError(
            f"unknown stabilization {stabilization!r}; expected one of {', '.join(STABILIZATIONS)}"
        )


def element_stiffness_into(
    X: Array, material: Material, stabilization: str, out: Array, w: ElementWork
) -> tuple[Array, Array, Array]:
    """Write ``a_h^K`` (3.11) of a batch of cells into ``out`` (m, N, N), using the buffers
    ``w`` (:class:`ElementWork` for at least ``m`` cells with ``n`` vertices).

    With ``D`` the dofs of the working basis, ``Pi`` the projection in it, ``P = D Pi``
    (the dofs of ``Pi v``), ``s`` the weight of the dofi-dofi term and ``B`` the
    right-hand sides of (3.8): ``a_h^K = Pi^T G Pi + s (I - P)^T (I - P) = Z + Z^T + s I``
    with ``Z = Pi^T Y``, ``Y = s/2 (D^T D) Pi + B/2 - s D^T``: three small products per
    cell (inner sizes N, 12, 12), symmetric by construction (``Pi^T G Pi = Pi^T B`` as
    ``G Pi = B`` on the non-rigid rows and ``G`` vanishes on the rigid motions).

    Returns
    -------
    The scaled moments about the centroids (m, 6), the centroids and the diameters.
    """
    m, n, _ = X.shape
    nd = local_dof_count(n)
    geometry = _project(X, material, w)
    B, D, Pi, Y, M, Z = w.B[:, :m], w.D[:, :m], w.Pi[:, :m], w.Y[:, :m], w.M[:m], w.Z[:m]
    s = np.ones((m, 1))  # the weight of the dofi-dofi term, per cell
    if stabilization == "eta":
        s *= 2.0 * material.eta
    elif stabilization == "trace":  # tr(Pi^T G Pi) / N, G Pi = B on the non-rigid rows
        s[:, 0] = np.einsum("aml,aml->m", Pi[3:], B[3:]) * (2.0 / nd)
    Dc, Pc, Yc = D.transpose(1, 0, 2), Pi.transpose(1, 0, 2), Y.transpose(1, 0, 2)
    np.matmul(Dc, Dc.transpose(0, 2, 1), out=M)
    M *= 0.5 * s[:, :, None]
    np.matmul(M, Pc, out=Yc)
    Y += B
    Y -= D if stabilization == "paper" else D * s
    np.matmul(Pc.transpose(0, 2, 1), Yc, out=Z)
    np.add(Z, Z.transpose(0, 2, 1), out=out)
    out.reshape(m, nd * nd)[:, :: nd + 1] += s
    return geometry


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
    _check_stabilization(stabilization)
    X = np.asarray(X, dtype=float)
    m, n, _ = X.shape
    nd = local_dof_count(n)
    K = np.empty((m, nd, nd))
    element_stiffness_into(X, material, stabilization, K, ElementWork(m, n))
    return Local2(K, local_projection2(X, material))
