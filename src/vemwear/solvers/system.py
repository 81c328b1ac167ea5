"""The step problem (paper 3.21) as a complementarity problem on the free dofs.

With ``w`` fixed, find ``u`` and ``lam`` such that (design.md section 4)

    K u - F + N^T(omega (p(N u - w) + lam)) + Tau^T(omega fric p(N u - w)) = 0,
    lam >= 0,  N u <= g,  lam (N u - g) = 0,

where ``fric_a = mu_a (n*(t) . tau_a)``. Here ``lam`` and ``p`` are pressures
(forces per unit length) of the rigid and the soft layer; ``omega`` turns them
into nodal forces.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..contact.law import ComplianceLaw


class ConvergenceError(RuntimeError):
    """A step problem whose solver did not reach its tolerance."""


@dataclass(frozen=True, eq=False)
class ContactSystem:
    """Data of the step problem that do not change in time.

    Attributes
    ----------
    K : (nf, nf) sparse stiffness on the free dofs
    contact_dofs : (m, 2) free-dof ids of the x and y components at each contact node
    normals, tangents : (m, 2) unit nu_a and tau_a
    omega : (m,) nodal weights
    g : (m,) thickness of the soft layer (bound on ``N u``)
    p : the compliance law
    dof_points : (nf, 2) coordinates of the vertex of each free dof (for the ordering
        of the factorization)
    """

    K: sp.csr_matrix
    contact_dofs: NDArray[np.int64]
    normals: NDArray[np.float64]
    tangents: NDArray[np.float64]
    omega: NDArray[np.float64]
    g: NDArray[np.float64]
    p: ComplianceLaw
    dof_points: NDArray[np.float64]
    N: sp.csr_matrix = field(init=False, repr=False)
    Tau: sp.csr_matrix = field(init=False, repr=False)
    c_ncp: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        m, nf = len(self.omega), self.K.shape[0]
        rows = np.repeat(np.arange(m), 2)
        cols = np.asarray(self.contact_dofs).ravel()
        for name, direction in (("N", self.normals), ("Tau", self.tangents)):
            op = sp.csr_matrix((np.asarray(direction).ravel(), (rows, cols)), shape=(m, nf))
            object.__setattr__(self, name, op)
        # scale of the complementarity function lam + c (N u - g): the normal stiffness
        # per unit length at each node, so both terms are pressures of comparable size
        diagK = self.K.diagonal()
        kn = np.sum(diagK[self.contact_dofs] * np.asarray(self.normals) ** 2, axis=1)
        object.__setattr__(self, "c_ncp", kn / self.omega)

    @property
    def m(self) -> int:
        return len(self.omega)

    @property
    def n_free(self) -> int:
        return self.K.shape[0]

    def layer_forces(self, lam: NDArray, pa: NDArray, fric: NDArray) -> NDArray:
        """Nodal forces of the rigid and the soft layer,
        ``N^T(omega (p + lam)) + Tau^T(omega fric p)``, for the pressures lam and p."""
        return self.N.T @ (self.omega * (pa + lam)) + self.Tau.T @ (self.omega * fric * pa)

    def contact_force(self, u: NDArray, lam: NDArray, fric: NDArray, w: NDArray):
        """The contact term of the residual and the soft-layer pressure at ``u``."""
        pa = self.p(self.N @ u - w)
        return self.layer_forces(lam, pa, fric), pa


@dataclass(frozen=True)
class StepData:
    """What changes from step to step: load, wear, friction direction, and where we are."""

    F: NDArray[np.float64]
    w: NDArray[np.float64]
    fric: NDArray[np.float64]
    t: float = 0.0
    level: int = 0


@dataclass
class StepSolution:
    """Solution of one step problem with its solver statistics."""

    u: NDArray[np.float64] | None
    u_nu: NDArray[np.float64]
    lam: NDArray[np.float64]
    p: NDArray[np.float64]
    iterations: int
    residuals: dict[str, float]


def _residuals(
    system: ContactSystem, y: NDArray, lam: NDArray, equilibrium: float, lam_ref: float
) -> dict[str, float]:
    """The three residuals, given the scaled equilibrium residual and the pressure scale."""
    g_ref = max(float(np.abs(system.g).max()), np.finfo(float).tiny)
    ncp = np.minimum(lam / lam_ref, (system.g - y) / g_ref)
    return {
        "equilibrium": float(equilibrium),
        "feasibility": float(max(0.0, (y - system.g).max(initial=0)) / g_ref),
        "complementarity": float(np.abs(ncp).max(initial=0)),
    }


def kkt_residuals(
    system: ContactSystem, step: StepData, u: NDArray, lam: NDArray
) -> dict[str, float]:
    """Scaled KKT residuals of a candidate solution (all dimensionless, max norms).

    ``equilibrium``: residual of the equation over the largest force in it;
    ``feasibility``: largest violation of ``N u <= g`` over max g;
    ``complementarity``: ``max |min(lam / lam_ref, (g - N u) / g_ref)|`` (it is zero
    exactly when lam >= 0, N u <= g and lam (N u - g) = 0).
    """
    force, pa = system.contact_force(u, lam, step.fric, step.w)
    Ku = system.K @ u
    r = Ku - step.F + force
    tiny = np.finfo(float).tiny
    fscale = max(
        np.abs(step.F).max(initial=0), np.abs(Ku).max(initial=0), np.abs(force).max(initial=0), tiny
    )
    lam_ref = max(float(np.abs(lam).max(initial=0)), float(np.abs(pa).max(initial=0)), tiny)
    return _residuals(system, system.N @ u, lam, np.abs(r).max(initial=0) / fscale, lam_ref)


def condensed_residuals(
    system: ContactSystem, y: NDArray, lam: NDArray, R: NDArray
) -> dict[str, float]:
    """The residuals of the condensed equations ``R(y, lam) = 0`` (R in displacement
    units, scaled by max g) with the complementarity conditions on y = N u."""
    tiny = np.finfo(float).tiny
    g_ref = max(float(np.abs(system.g).max()), tiny)
    lam_ref = max(float(np.abs(lam).max(initial=0)), tiny)
    return _residuals(system, y, lam, np.abs(R).max(initial=0) / g_ref, lam_ref)


def check_converged(
    residuals: dict[str, float], tol: float, step: StepData, method: str, iterations: int
) -> None:
    """Raise :class:`ConvergenceError` naming the time level when a residual is above tol."""
    worst = max(residuals, key=lambda k: residuals[k])
    if not residuals[worst] <= tol:  # also catches NaN
        raise ConvergenceError(
            f"{method} did not converge at time level {step.level} (t = {step.t:.6g}) after "
            f"{iterations} iterations: {worst} residual {residuals[worst]:.3e} > tol {tol:.1e}"
        )
