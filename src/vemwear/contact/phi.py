"""The contact functional phi_h with nodal quadrature (paper 2.21; docs/method.md, section 3)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .boundary import ContactBoundary
from .law import ComplianceLaw


def phi_h(
    cb: ContactBoundary,
    p: ComplianceLaw,
    mu: NDArray[np.float64],
    n_star: NDArray[np.float64],
    w: NDArray[np.float64],
    u: NDArray[np.float64],
    v: NDArray[np.float64],
) -> float:
    """``phi_h(t, w, u, v) = sum_a omega_a p(u_nu(a) - w_a) (v_nu(a) + mu_a n* . v_tau(a))``."""
    pa = p(cb.N @ u - w)
    return float(
        np.sum(cb.weights * pa * (cb.N @ v + mu * cb.friction_direction(n_star) * (cb.Tau @ v)))
    )
