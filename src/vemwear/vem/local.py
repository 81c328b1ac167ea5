"""Local virtual element matrices of lowest order (k = 1), batched by vertex count.

For a batch of ``m`` cells with ``n`` vertices each (coordinates ``X``, shape
``(m, n, 2)``, counter-clockwise) and local dofs ordered ``(u_x1, u_y1, u_x2, ...)``:

* the strain of the projection is computable from boundary values,
  ``eps(Pi v) = 1/|K| int_dK sym(v (x) n) ds`` (paper 3.8), since v is linear on edges;
* the rigid part of ``Pi v`` is fixed by the vertex averages (3.9) and (3.10);
* ``a_h^K(u, v) = |K| eps(Pi u) : C eps(Pi v) + S^K((I - Pi) u, (I - Pi) v)`` (3.11),
  with the dofi-dofi stabilization ``S^K = s_K * sum_i chi_i chi_i``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

STABILIZATIONS = ("paper", "eta", "trace")


@dataclass(frozen=True)
class Material:
    """Isotropic linear elasticity, ``sigma = 2 eta eps + lam tr(eps) I`` (paper Section 5).

    Parameters
    ----------
    lam, eta : float
        Lamé coefficients lambda and eta (the paper's names; eta is the shear modulus).
    """

    lam: float
    eta: float

    def __post_init__(self) -> None:
        for name in ("lam", "eta"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise ValueError(f"material: Lamé coefficient {name} must be positive, got {v}")

    @property
    def D(self) -> NDArray[np.float64]:
        """Elasticity matrix in Voigt notation (eps_xx, eps_yy, 2 eps_xy)."""
        lam, eta = self.lam, self.eta
        return np.array([[lam + 2 * eta, lam, 0.0], [lam, lam + 2 * eta, 0.0], [0.0, 0.0, eta]])

    @property
    def coercivity(self) -> float:
        """Smallest eigenvalue of C on symmetric tensors: m_C = 2 eta (for lam > 0)."""
        return 2.0 * self.eta


def geometry(X: NDArray[np.float64]):
    """Areas, vertex averages and the vertex normal weights of a batch of polygons.

    Returns
    -------
    area : (m,) array
    xbar : (m, 2) array, the vertex average (3.9)
    q : (m, n, 2) array, ``q_i = (|e_{i-1}| n_{i-1} + |e_i| n_i) / 2`` so that
        ``int_dK v (x) n ds = sum_i v_i (x) q_i`` for v linear on edges.
    """
    xbar = X.mean(axis=1)
    Y = X - xbar[:, None, :]  # relative coordinates keep the shoelace sum accurate
    Yn = np.roll(Y, -1, axis=1)
    area = 0.5 * np.sum(Y[..., 0] * Yn[..., 1] - Yn[..., 0] * Y[..., 1], axis=1)
    d = Yn - Y
    N = np.stack([d[..., 1], -d[..., 0]], axis=-1)  # |e| n for counter-clockwise cells
    q = 0.5 * (N + np.roll(N, 1, axis=1))
    return area, xbar, q


class Fan(NamedTuple):
    """The fan of triangles ``(xbar, x_i, x_{i+1})`` of a batch of ``m`` cells with ``n``
    vertices each. With signed areas, sums over the fan integrate exactly over any
    simple cell, star-shaped with respect to ``xbar`` or not."""

    X: NDArray[np.float64]  # (m, n, 2) vertices x_i
    X_next: NDArray[np.float64]  # (m, n, 2) vertices x_{i+1}
    xbar: NDArray[np.float64]  # (m, 2) vertex averages
    rel: NDArray[np.float64]  # (m, n, 2) x_i - xbar
    rel_next: NDArray[np.float64]  # (m, n, 2) x_{i+1} - xbar
    area: NDArray[np.float64]  # (m, n) signed areas of the triangles


def fan(X: NDArray[np.float64]) -> Fan:
    """The fan of triangles of a batch of cells with vertex coordinates X (m, n, 2)."""
    xbar = X.mean(axis=1)
    a = X - xbar[:, None, :]
    b = np.roll(a, -1, axis=1)
    area = 0.5 * (a[..., 0] * b[..., 1] - b[..., 0] * a[..., 1])
    return Fan(X, np.roll(X, -1, axis=1), xbar, a, b, area)


def strain_operator(area: NDArray, q: NDArray) -> NDArray[np.float64]:
    """``B`` with ``(eps_xx, eps_yy, 2 eps_xy)(Pi v) = B @ v``; shape (m, 3, 2n)."""
    m, n, _ = q.shape
    B = np.zeros((m, 3, 2 * n))
    qa = q / area[:, None, None]
    B[:, 0, 0::2] = qa[..., 0]
    B[:, 1, 1::2] = qa[..., 1]
    B[:, 2, 0::2] = qa[..., 1]
    B[:, 2, 1::2] = qa[..., 0]
    return B


def _interleave(xx, xy, yx, yy):
    """Assemble (m, 2n, 2n) from four (m, n, n) blocks: [2j + a, 2i + c] = block_ac[j, i]."""
    m, n, _ = xx.shape
    out = np.empty((m, 2 * n, 2 * n))
    out[:, 0::2, 0::2], out[:, 0::2, 1::2] = xx, xy
    out[:, 1::2, 0::2], out[:, 1::2, 1::2] = yx, yy
    return out


def projection_matrix(X: NDArray, xbar: NDArray, area: NDArray, q: NDArray) -> NDArray[np.float64]:
    """Matrix of the dofs of ``Pi v`` (its vertex values) in terms of the dofs of v.

    ``Pi v(x) = vbar + E (x - xbar) + omega J (x - xbar)`` where vbar is the vertex
    average of v (3.9), ``E = eps(Pi v)`` and omega solves (3.10):
    ``omega = (sum_i d_i x v_i - sum_i d_i x E d_i) / sum_i |d_i|^2``, ``d_i = x_i - xbar``.
    For a symmetric E, ``sum_i d_i x E d_i = e_xy (S_xx - S_yy) + (e_yy - e_xx) S_xy`` with
    the second moments ``S_ab = sum_i d_ia d_ib``. Shape (m, 2n, 2n), built from outer
    products per component pair.
    """
    _m, n, _ = X.shape
    d = X - xbar[:, None, :]
    dx, dy = d[..., 0], d[..., 1]  # (m, n)
    qx, qy = q[..., 0] / area[:, None], q[..., 1] / area[:, None]
    Sxx, Syy, Sxy = (np.sum(a * b, axis=1)[:, None] for a, b in ((dx, dx), (dy, dy), (dx, dy)))
    Sdd = Sxx + Syy
    # strain of the unit dofs: (i, x) -> exx = qx_i, exy = qy_i / 2;
    #                          (i, y) -> eyy = qy_i, exy = qx_i / 2
    # rotation of the unit dofs from (3.10)
    om_x = (-dy - (0.5 * qy * (Sxx - Syy) - qx * Sxy)) / Sdd  # (m, n) over i
    om_y = (dx - (0.5 * qx * (Sxx - Syy) + qy * Sxy)) / Sdd
    o = lambda a, b: a[:, :, None] * b[:, None, :]  # noqa: E731  (m, n_j, n_i)
    inv_n = 1.0 / n
    xx = inv_n + o(dx, qx) + 0.5 * o(dy, qy) - o(dy, om_x)
    xy = 0.5 * o(dy, qx) - o(dy, om_y)
    yx = 0.5 * o(dx, qy) + o(dx, om_x)
    yy = inv_n + 0.5 * o(dx, qx) + o(dy, qy) + o(dx, om_y)
    return _interleave(xx, xy, yx, yy)


def consistency_matrix(area: NDArray, q: NDArray, material: Material) -> NDArray[np.float64]:
    """``|K| B^T D B``: the term ``a^K(Pi u, Pi v)`` of (3.11), from outer products of q."""
    lam, eta = material.lam, material.eta
    qx, qy = q[..., 0], q[..., 1]
    sx, sy = qx / area[:, None], qy / area[:, None]  # 1/|K| once, not per entry
    o = lambda a, b: a[:, :, None] * b[:, None, :]  # noqa: E731
    XX, YY, XY = o(sx, qx), o(sy, qy), o(sx, qy)
    YX = XY.transpose(0, 2, 1)
    return _interleave(
        (lam + 2 * eta) * XX + eta * YY,
        lam * XY + eta * YX,
        lam * YX + eta * XY,
        (lam + 2 * eta) * YY + eta * XX,
    )


def element_matrices(
    X: NDArray[np.float64], material: Material, stabilization: str = "paper"
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Local stiffness matrices ``a_h^K`` (3.11) of a batch of cells with equal vertex count.

    Parameters
    ----------
    X : (m, n, 2) array
        Vertex coordinates, counter-clockwise.
    material : Material
    stabilization : {"paper", "eta", "trace"}
        Weight ``s_K`` of the dofi-dofi term: ``"paper"`` uses 1 (the paper's choice),
        ``"eta"`` uses ``2 eta``, ``"trace"`` uses ``tr(K_c) / (2n)`` with ``K_c`` the
        consistency matrix.

    Returns
    -------
    K : (m, 2n, 2n) local stiffness
    B : (m, 3, 2n) strain operator of ``Pi``
    P : (m, 2n, 2n) projection on vertex values
    area : (m,) cell areas
    """
    if stabilization not in STABILIZATIONS:
        raise ValueError(
            f"unknown stabilization {stabilization!r}; expected one of {', '.join(STABILIZATIONS)}"
        )
    area, xbar, q = geometry(X)
    B = strain_operator(area, q)
    Kc = consistency_matrix(area, q, material)
    P = projection_matrix(X, xbar, area, q)
    m, n2, _ = P.shape
    IP = np.eye(n2)[None] - P
    if stabilization == "paper":
        s = np.ones(m)
    elif stabilization == "eta":
        s = np.full(m, 2.0 * material.eta)
    else:
        s = np.trace(Kc, axis1=1, axis2=2) / n2
    IPt = np.ascontiguousarray(IP.transpose(0, 2, 1))  # a batched matmul is 3x an einsum here
    K = Kc + s[:, None, None] * (IPt @ IP)
    return K, B, P, area
