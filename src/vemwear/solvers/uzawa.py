"""The paper's reference solver: an Uzawa iteration with two multipliers (Glowinski).

The two multipliers are the pressure ``p_rigid`` of the rigid layer (for the unilateral
constraint ``N u <= g``) and the pressure ``q`` of the soft layer (for the normal
compliance term, which the iteration freezes). One iteration is one
back-substitution with the factorization of K, then an update of both multipliers:

    K u = F - N^T(weights (q + p_rigid)) - Tau^T(weights fric q)
    p_rigid <- max(0, p_rigid + rho_1 (N u - g))              (projected gradient ascent)
    q   <- q + rho_2 (p(N u - w) - q)                  (relaxed fixed point)

``rho_1 = 1 / ||weights C_NN||`` and ``rho_2 = 1 / (1 + L_p ||weights C_NN||)`` with
``||weights C_NN||`` estimated once by power iteration. The iteration stops when the
KKT residuals of ``(u, p_rigid)`` are below the tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .backends import factorize
from .system import (
    ContactSystem,
    StepData,
    StepSolution,
    check_converged,
    kkt_residuals,
)


@dataclass(frozen=True)
class UzawaOptions:
    tol: float = 1e-10
    max_iter: int = 200_000
    backend: str = "auto"
    check_every: int = 10


class Uzawa:
    """Uzawa iteration for the step problem; K factorized once per simulation."""

    method = "uzawa"
    #: No block recovery, no prediction (:class:`.protocol.StepSolver`).
    batch = False
    predicts = False

    def __init__(self, system: ContactSystem, options: UzawaOptions | None = None) -> None:
        self.system = system
        self.options = options or UzawaOptions()
        self.factor = factorize(system.K, self.options.backend)
        self.norm_C = self._compliance_norm()
        L = system.p.lipschitz if np.isfinite(system.p.lipschitz) else 1.0
        self.rho1 = 1.0 / self.norm_C
        self.rho2 = 1.0 / (1.0 + L * self.norm_C)

    @property
    def setup_timings(self) -> dict[str, float]:
        """Wall times of the factorization's parts."""
        return dict(getattr(self.factor, "timings", {}))

    def _compliance_norm(self, iterations: int = 50) -> float:
        """Largest eigenvalue of ``W^(1/2) C_NN W^(1/2)``, by power iteration."""
        s = self.system
        sq = np.sqrt(s.weights)
        x = np.ones(s.m) / np.sqrt(s.m)
        val = 0.0
        for _ in range(iterations):
            y = sq * (s.N @ self.factor.solve(s.N.T @ (sq * x)))
            val_new = float(np.linalg.norm(y))
            x = y / val_new
            if abs(val_new - val) <= 1e-6 * val_new:
                val = val_new
                break
            val = val_new
        return 1.05 * val  # a margin: the estimate approaches from below

    def stiffness_note(self) -> str:
        """A note for the error message when the soft layer's fixed point contracts
        slowly: by ``1 - rho_2`` per iteration, ``1 / rho_2 = 1 + L_p ||weights C_NN||``
        above 1000 (a soft layer that much stiffer than the body). Empty otherwise."""
        ratio = 1.0 / self.rho2
        if not ratio > 1000.0:
            return ""
        return (
            f"; the soft layer's fixed point contracts by 1 - 1/{ratio:.3g} per iteration "
            "(1 + L_p |omega C_NN|: a layer much stiffer than the body), which the "
            "condensed Newton (solver newton) does not depend on"
        )

    def solve(
        self, step: StepData, guess: StepSolution | None = None, recover: bool = True
    ) -> StepSolution:
        s, opt = self.system, self.options
        if guess is not None:
            p_rigid, q = np.array(guess.p_rigid, copy=True), np.array(guess.p_soft, copy=True)
        else:
            p_rigid, q = np.zeros(s.m), np.zeros(s.m)
        u: NDArray = np.zeros(s.n_free)
        res: dict[str, float] = {}
        it = 0
        for it in range(1, opt.max_iter + 1):
            u = self.factor.solve(step.F - s.layer_forces(p_rigid, q, step.fric))
            y = s.N @ u
            if it % opt.check_every == 0:
                res = kkt_residuals(s, step, u, p_rigid)
                if max(res.values()) <= opt.tol:
                    break
            p_rigid = np.maximum(0.0, p_rigid + self.rho1 * (y - s.g))
            q = q + self.rho2 * (s.p(y - step.w) - q)
        res = kkt_residuals(s, step, u, p_rigid)
        check_converged(res, opt.tol, step, "Uzawa", it, self.stiffness_note)
        y = s.N @ u
        return StepSolution(
            u=u, u_nu=y, p_rigid=p_rigid, p_soft=s.p(y - step.w), iterations=it, residuals=res
        )
