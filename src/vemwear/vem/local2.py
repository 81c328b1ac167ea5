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


def _pairs(n: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """The vertex pairs ``i < j`` of an n-gon (for the diameters)."""
    if n not in _PAIRS:
        _PAIRS[n] = np.triu_indices(n, 1)
    return _PAIRS[n]


_PAIRS: dict[int, tuple[NDArray[np.intp], NDArray[np.intp]]] = {}

#: ``D = rows @ _BT``: the dofs ``chi(q_a)`` from the monomials (or their means) at the
#: local nodes; ``_BT[j, 12 c + a] = BASIS[a, j, c]``.
_BT = np.ascontiguousarray(BASIS.transpose(1, 2, 0).reshape(6, 2 * N_BASIS))
_BT.setflags(write=False)


@functools.lru_cache(maxsize=32)
def _constants(material: Material) -> tuple[Array, Array, Array]:
    """Tables of a material: ``WJ`` (6, 144) with ``G = h^-2 sum_j (int_K m_j) WJ[j]``;
    ``S`` (6, 24) with ``h sigma(q_a) N . e_c = sum_(p, t) m_p N_t S[(p, t), 12 c + a]``
    (``p`` over 1, xi, eta and ``t`` over the components of N); ``DIV`` (2, 12) with
    ``h^2 div sigma(q_a) . e_c = DIV[c, a]``."""
    Dm = material.D
    W = np.einsum("apk,kl,brl->prab", STRAIN, Dm, STRAIN)  # (3, 3, 12, 12)
    WJ = np.zeros((6, N_BASIS, N_BASIS))
    for p in range(3):
        for r in range(3):
            WJ[_PAIR[p, r]] += W[p, r]
    SIG = np.einsum("kl,apl->apk", Dm, STRAIN)  # h sigma(q_a) = sum_p SIG[a, p] m_p (Voigt)
    S = np.zeros((3, 2, 2, N_BASIS))  # [p, t, c, a]: (sxx nx + sxy ny, sxy nx + syy ny)
    S[:, 0, 0], S[:, 1, 0] = SIG[:, :, 0].T, SIG[:, :, 2].T
    S[:, 0, 1], S[:, 1, 1] = SIG[:, :, 2].T, SIG[:, :, 1].T
    DIV = np.stack([SIG[:, 1, 0] + SIG[:, 2, 2], SIG[:, 1, 2] + SIG[:, 2, 1]])
    out = (WJ.reshape(6, -1), S.reshape(6, 2 * N_BASIS), DIV)
    for a in out:
        a.setflags(write=False)
    return out


class ElementWork:
    """Buffers for the element work on up to ``m`` cells with ``n`` vertices, reused from
    batch to batch by :func:`element_stiffness_into` (fresh arrays of a few MB per batch
    cost more in page faults than the arithmetic).

    ``L[:, :, :12]`` holds ``Pi^T`` (N, 12) and ``L[:, :, 12:]`` the dofs of the basis ``D``
    (N, 12) after :func:`_project`.
    """

    def __init__(self, m: int, n: int) -> None:
        nd = local_dof_count(n)
        self.m, self.n = m, n
        self.L = np.empty((m, nd, 2 * N_BASIS))
        self.R = np.empty((m, nd, 2 * N_BASIS))
        self.Z = np.empty((m, nd, nd))
        self.B = np.empty((m, nd, N_BASIS))  # a^K(v, q_a) of the dofs, transposed
        self.D = np.empty((m, nd, N_BASIS))
        self.U = np.empty((m, 2, n, 3, 2))
        self.mono = np.empty((m, 2 * n, 6))
        self.rows = np.empty((m, 2 * n + 1, 6))


def _project(X: Array, material: Material, w: ElementWork) -> tuple[Array, ...]:
    """``Pi`` (3.8) of a batch into ``w`` (module docstring); returns the matrices G, the
    scaled moments ``h^-2 int_K m_j`` (m, 6), the vertex averages and the diameters.

    With ``G[3:, 3:] pi_2 = B[3:]`` for the nine non-rigid ``q_a`` (``G`` vanishes on the
    rigid motions) and the three rigid-motion rows upper triangular in ``pi_1`` (the
    cell means of e_x, e_y are exact unit vectors, the rotation of the translations is
    zero), ``Pi`` costs one 9 x 9 inverse and a back substitution.
    """
    m, n, _ = X.shape
    WJ, S, DIV = _constants(material)
    L, B, D, U = w.L[:m], w.B[:m], w.D[:m], w.U[:m]
    center = X.mean(axis=1)
    i, j = _pairs(n)
    d = X[:, i] - X[:, j]
    h = np.sqrt((d[..., 0] ** 2 + d[..., 1] ** 2).max(axis=1))
    a = (X - center[:, None, :]) / h[:, None, None]  # scaled vertices
    b = np.roll(a, -1, axis=1)
    ax, ay, bx, by = a[..., 0], a[..., 1], b[..., 0], b[..., 1]
    A = 0.5 * (ax * by - bx * ay)  # the fan from the vertex average, signed
    mom = np.empty((m, 6))  # h^-2 int_K m_j, exact on the fan
    mom[:, 0] = A.sum(axis=1)
    mom[:, 1] = (A * (ax + bx)).sum(axis=1) / 3.0
    mom[:, 2] = (A * (ay + by)).sum(axis=1) / 3.0
    mom[:, 3] = (A * (ax * ax + ax * bx + bx * bx)).sum(axis=1) / 6.0
    mom[:, 4] = (A * (2.0 * (ax * ay + bx * by) + ax * by + bx * ay)).sum(axis=1) / 12.0
    mom[:, 5] = (A * (ay * ay + ay * by + by * by)).sum(axis=1) / 6.0
    area = mom[:, 0]

    # monomials at the vertices and the edge midpoints; D from them
    mono = w.mono[:m]
    x = mono[:, :, 1].reshape(m, 2, n)
    y = mono[:, :, 2].reshape(m, 2, n)
    x[:, 0], y[:, 0] = ax, ay
    np.multiply(ax + bx, 0.5, out=x[:, 1])
    np.multiply(ay + by, 0.5, out=y[:, 1])
    mono[:, :, 0] = 1.0
    mono[:, :, 3] = mono[:, :, 1] ** 2
    np.multiply(mono[:, :, 1], mono[:, :, 2], out=mono[:, :, 4])
    mono[:, :, 5] = mono[:, :, 2] ** 2
    mv, mm = mono[:, :n], mono[:, n:]
    rows = w.rows[:m]
    rows[:, :n] = mv
    rows[:, n : 2 * n] = (mv + 4.0 * mm + np.roll(mv, -1, axis=1)) / 6.0  # Simpson
    rows[:, 2 * n] = mom / area[:, None]
    np.matmul(rows, _BT, out=D.reshape(m, 2 * n + 1, 2 * N_BASIS))
    L[:, :, N_BASIS:] = D
    G = np.matmul(mom, WJ).reshape(m, N_BASIS, N_BASIS)

    # a^K(v, q_a) by parts (3.8): B[:, i, a] for the local dof i
    Nx, Ny = by - ay, ax - bx  # |e_i| n_i / h
    um, uv = U[:, 1], U[:, 0]
    np.multiply(mm[..., :3], Nx[..., None], out=um[..., 0])
    np.multiply(mm[..., :3], Ny[..., None], out=um[..., 1])
    np.multiply(mv[..., :3], (Nx + np.roll(Nx, 1, axis=1))[..., None], out=uv[..., 0])
    np.multiply(mv[..., :3], (Ny + np.roll(Ny, 1, axis=1))[..., None], out=uv[..., 1])
    uv -= um
    uv -= np.roll(um, 1, axis=1)
    uv /= 6.0
    # Simpson on edge i with v(mid) = (6 mean_i - v_i - v_(i+1)) / 4: vertex i gets
    # (t_i(x_i) + t_(i-1)(x_i) - t_i(mid_i) - t_(i-1)(mid_(i-1))) / 6, mean_i gets t_i(mid_i)
    Bv = B.reshape(m, 2 * n + 1, 2 * N_BASIS)
    np.matmul(U.reshape(m, 2 * n, 6), S, out=Bv[:, : 2 * n])
    np.multiply(-area[:, None, None], DIV, out=B[:, 4 * n :])

    # pi_2 = G22^-1 B[3:], then the rigid rows (cell mean; h / |K| int_K rot)
    Gi = np.linalg.inv(G[:, 3:, 3:])
    pi = L[:, :, :N_BASIS]  # Pi^T
    np.matmul(B[:, :, 3:], Gi.transpose(0, 2, 1), out=pi[:, :, 3:])
    R = np.empty((m, 3, N_BASIS))
    R[:, :2] = D[:, 4 * n :]
    np.divide(np.matmul(mom[:, :3], ROT[:, :3].T), area[:, None], out=R[:, 2])
    W1 = -np.matmul(pi[:, :, 3:], R[:, :, 3:].transpose(0, 2, 1))  # (m, N, 3)
    W1[:, 4 * n, 0] += 1.0
    W1[:, 4 * n + 1, 1] += 1.0
    W1[:, 2 * n : 4 * n, 2] += ((b - a) / area[:, None, None]).reshape(m, 2 * n)  # |e| t
    # R[:, :, :3] is upper triangular (the rest vanishes identically)
    pi[:, :, 2] = W1[:, :, 2] / R[:, 2, 2, None]
    pi[:, :, 1] = (W1[:, :, 1] - R[:, 1, 2, None] * pi[:, :, 2]) / R[:, 1, 1, None]
    pi[:, :, 0] = (
        W1[:, :, 0] - R[:, 0, 1, None] * pi[:, :, 1] - R[:, 0, 2, None] * pi[:, :, 2]
    ) / R[:, 0, 0, None]
    return G, mom, center, h


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
    w = ElementWork(m, n)
    G, mom, center, h = _project(np.asarray(X, dtype=float), material, w)
    pi = np.ascontiguousarray(w.L[:, :, :N_BASIS].transpose(0, 2, 1))
    return LocalProjection2(pi, w.D, G, mom[:, 0] * h * h, center, h)


def _check_stabilization(stabilization: str) -> None:
    if stabilization not in STABILIZATIONS:
        raise ValueError(
            f"unknown stabilization {stabilization!r}; expected one of {', '.join(STABILIZATIONS)}"
        )


def element_stiffness_into(
    X: Array, material: Material, stabilization: str, out: Array, w: ElementWork
) -> tuple[Array, ...]:
    """Write ``a_h^K`` (3.11) of a batch of cells into ``out`` (m, N, N), using the buffers
    ``w`` (:class:`ElementWork` for at least ``m`` cells with ``n`` vertices).

    With ``P = D Pi`` (the dofs of ``Pi v``), ``s`` the weight of the dofi-dofi term and
    ``B`` the right-hand sides of (3.8): ``a_h^K = Pi^T G Pi + s (I - P)^T (I - P)
    = Z + Z^T + s I`` with ``Z = Pi^T (s/2 D^T D Pi + B/2) - s D Pi``, one product
    ``[Pi^T | D] [s/2 D^T D Pi + B/2 ; -s Pi]`` of inner size 24, symmetric by construction
    (``Pi^T G Pi = Pi^T B`` as ``G Pi = B`` on the non-rigid rows and ``G`` vanishes on
    the rigid motions).

    Returns
    -------
    The matrices ``G``, the scaled moments, the vertex averages and the diameters.
    """
    m, n, _ = X.shape
    nd = local_dof_count(n)
    geometry = _project(X, material, w)
    L, R, D, B, Z = w.L[:m], w.R[:m], w.D[:m], w.B[:m], w.Z[:m]
    pi = L[:, :, :N_BASIS]
    s = np.ones(m)  # the weight of the dofi-dofi term, per cell
    if stabilization == "eta":
        s *= 2.0 * material.eta
    elif stabilization == "trace":  # tr(Pi^T G Pi) / N
        s = np.einsum("mia,mia->m", pi[:, :, 3:], B[:, :, 3:]) / nd
    sc = s[:, None, None]
    M = np.matmul(D.transpose(0, 2, 1), D)
    M *= 0.5 * sc
    np.matmul(pi, M, out=R[:, :, :N_BASIS])
    R[:, :, 3:N_BASIS] += 0.5 * B[:, :, 3:]
    np.multiply(pi, -sc, out=R[:, :, N_BASIS:])
    np.matmul(L, R.transpose(0, 2, 1), out=Z)
    np.add(Z, Z.transpose(0, 2, 1), out=out)
    out.reshape(m, nd * nd)[:, :: nd + 1] += s[:, None]
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
    w = ElementWork(m, n)
    K = np.empty((m, nd, nd))
    G, mom, center, h = element_stiffness_into(X, material, stabilization, K, w)
    pi = np.ascontiguousarray(w.L[:, :, :N_BASIS].transpose(0, 2, 1))
    return Local2(K, LocalProjection2(pi, w.D, G, mom[:, 0] * h * h, center, h))
