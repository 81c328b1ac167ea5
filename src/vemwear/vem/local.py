"""Local virtual element matrices of lowest order (k = 1), batched by vertex count.

For a batch of ``m`` cells with ``n`` vertices each (coordinates ``X``, shape
``(m, n, 2)``, counter-clockwise) and local dofs ordered ``(u_x1, u_y1, u_x2, ...)``:

* the projection ``Pi v`` (its strain from boundary values (3.8), its value at the vertex
  average (3.9) and its rotation (3.10)) comes from :mod:`vemwear.vem.projection`;
* ``a_h^K(u, v) = |K| eps(Pi u) : C eps(Pi v) + S^K((I - Pi) u, (I - Pi) v)`` (3.11),
  with the dofi-dofi stabilization ``S^K = s_K * sum_i chi_i chi_i``; the weight
  ``s_K`` is the paper's 1 by default (docs/method.md, section 2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .projection import local_projection, projection_matrix, strain_operator

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


def strain_stress(
    E: NDArray[np.float64], material: Material
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The 3x3 strain, stress ``sigma = 2 eta eps + lam tr(eps) I`` and von Mises stress
    of strains ``E``: (q, 2, 2) in 2D (plane strain: eps_zz = 0, sigma_zz = lam tr) or
    (q, 3, 3) in 3D."""
    d = E.shape[1]
    tr = np.trace(E, axis1=1, axis2=2)
    lam, eta = float(material.lam), float(material.eta)
    strain = np.zeros((len(E), 3, 3))
    strain[:, :d, :d] = E
    stress = 2.0 * eta * strain
    for i in range(3):
        stress[:, i, i] += lam * tr
    sxx, syy, szz, sxy = stress[:, 0, 0], stress[:, 1, 1], stress[:, 2, 2], stress[:, 0, 1]
    shear = 3.0 * (stress[:, 1, 2] ** 2 + stress[:, 0, 2] ** 2)  # 0 in plane strain
    vm = np.sqrt(
        0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2) + 3.0 * sxy**2 + shear
    )
    return strain, stress, vm


def _interleave(xx, xy, yx, yy, out=None):
    """Assemble (m, 2n, 2n) from four (m, n, n) blocks: [2j + a, 2i + c] = block_ac[j, i]
    (into ``out`` when given)."""
    m, n, _ = xx.shape
    out = np.empty((m, 2 * n, 2 * n)) if out is None else out
    out[:, 0::2, 0::2], out[:, 0::2, 1::2] = xx, xy
    out[:, 1::2, 0::2], out[:, 1::2, 1::2] = yx, yy
    return out


def consistency_matrix(
    area: NDArray, q: NDArray, material: Material, out: NDArray | None = None
) -> NDArray[np.float64]:
    """``|K| B^T D B``: the term ``a^K(Pi u, Pi v)`` of (3.11), from outer products of
    ``q = |K| grad`` (written to ``out``, shape (m, 2n, 2n), when given)."""
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
        out,
    )


def triangle_matrices(
    X: NDArray[np.float64], material: Material, out: NDArray | None = None
) -> NDArray[np.float64]:
    """Local stiffness matrices ``a_h^K`` (3.11) of a batch of triangles, shape (m, 6, 6)
    (written to ``out`` when given).

    On a triangle the lowest-order virtual element space is P1 and ``Pi`` is the
    identity on it, so ``I - Pi = 0`` and the stabilization of (3.11) vanishes for
    every weight: ``a_h^K = |K| B^T D B`` with the P1 strain operator. The boundary
    integrals ``q_i = |K| grad phi_i = (y_{i+1} - y_{i+2}, x_{i+2} - x_{i+1}) / 2``
    give it directly, without the projection matrices of :func:`element_matrices`
    (which computes the stabilization as round-off, 1e-31 relative, 8 times slower).
    """
    x, y = X[..., 0], X[..., 1]
    nxt, prv = [1, 2, 0], [2, 0, 1]
    q = np.empty(X.shape)
    q[..., 0] = 0.5 * (y[:, nxt] - y[:, prv])
    q[..., 1] = 0.5 * (x[:, prv] - x[:, nxt])
    area = np.einsum("mi,mi->m", x, q[..., 0])
    return consistency_matrix(area, q, material, out)


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
    lp = local_projection(X)
    area = lp.area
    B = strain_operator(area, lp.q)
    # |K| B^T D B as one batched product (3-4 times faster than consistency_matrix's
    # outer products, the same numbers)
    Kc = np.matmul(B.transpose(0, 2, 1), np.einsum("ij,mjk->mik", material.D, B))
    Kc *= area[:, None, None]
    P = projection_matrix(lp)
    n2 = P.shape[1]
    IP = np.negative(P)
    diag = np.arange(n2)
    IP[:, diag, diag] += 1.0  # I - P, without another temporary of the batch's size
    S = np.matmul(IP.transpose(0, 2, 1), IP)  # the dofi-dofi term (I - P)^T (I - P)
    del IP
    if stabilization == "eta":
        S *= 2.0 * material.eta
    elif stabilization == "trace":
        S *= (np.trace(Kc, axis1=1, axis2=2) / n2)[:, None, None]
    Kc += S  # weight 1 for "paper": no product at all
    return Kc, B, P, area
