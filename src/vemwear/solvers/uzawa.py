"""The paper's reference solver: an Uzawa iteration with two multipliers (Glowinski).

The two multipliers are the pressure ``p_rigid`` of the rigid layer (for the unilateral
constraint ``N u <= g``) and the pressure ``q`` of the soft layer (for the normal
compliance term, which the iteration freezes). One iteration is one
back-substitution with the factorization of K, then an update of both multipliers:

    K u = F - N^T(weights (q + p_rigid)) - Tau^T(weights fric q)   (q + p_rigid in the
                                          friction term where it acts on the whole pressure)
    p_rigid <- max(0, p_rigid + rho_1 (N u - g))              (projected gradient ascent)
    q   <- q + rho_2 (p(N u - w) - q)                  (relaxed fixed point)

``rho_1 = 1 / ||weights C_NN||`` and ``rho_2 = 1 / (1 + L_p ||weights C_NN||)`` with
``||weights C_NN||`` estimated once by power iteration. The iteration stops when the
KKT residuals of ``(u, p_rigid)`` are below the tolerance.

Under load control (rigid motions that only contact holds, :mod:`.rigid`) K is
factorized without the anchor dofs and u = G (F - forces) + R a: for given amplitudes
a the iteration above solves the problem whose anchors are held at R a, and an outer
Newton iteration (its Jacobian by finite differences, r + 1 inner solves) finds the a
whose contact forces balance the load along R (docs/method.md section 1c).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .backends import factorize
from .rigid import (
    anchored_factor,
    cold_start,
    layer_x,
    liftoff_error,
    rigid_modes,
    touching_solution,
)
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
        #: the rigid motions that only contact holds (load control), or None
        self.rigid = None if system.rigid is None else rigid_modes(system, system.contact_cols)
        if self.rigid is None:
            self.factor: Any = factorize(system.K, self.options.backend)
        else:
            self.factor = anchored_factor(system, self.rigid, self.options.backend)
        self.norm_C = self._compliance_norm()
        L = system.p.lipschitz if np.isfinite(system.p.lipschitz) else 1.0
        self.rho1 = 1.0 / self.norm_C
        self.rho2 = 1.0 / (1.0 + L * self.norm_C)
        self._q = np.zeros(system.m)  # the soft layer's multiplier of the last iteration

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
        if self.rigid is None:
            u, p_rigid, it = self._iterate(step, p_rigid, q, None)
        elif self.rigid.negligible(step.F):  # no load along R: touching without force
            sol = touching_solution(s, self.rigid, step, self.factor)
            check_converged(sol.residuals, opt.tol, step, "Uzawa", 0)
            return sol
        else:
            u, p_rigid, it = self._balance(step, guess, p_rigid, q)
        res = kkt_residuals(s, step, u, p_rigid)
        check_converged(res, opt.tol, step, "Uzawa", it, self.stiffness_note)
        y = s.N @ u
        return StepSolution(
            u=u, u_nu=y, p_rigid=p_rigid, p_soft=s.p(y - step.w), iterations=it, residuals=res
        )

    def _iterate(
        self, step: StepData, p_rigid: NDArray, q: NDArray, a: NDArray | None, tol: float = 0.0
    ) -> tuple[NDArray, NDArray, int]:
        """The Uzawa iteration from (p_rigid, q); with rigid amplitudes ``a`` it solves the
        problem whose anchors are held at R a (its residual measured off the anchors).
        Returns u, p_rigid and the iteration count."""
        s, opt = self.system, self.options
        rig = self.rigid
        tol = tol or opt.tol
        u: NDArray = np.zeros(s.n_free)
        it = 0
        for it in range(1, opt.max_iter + 1):
            u = self.factor.solve(step.F - s.layer_forces(p_rigid, q, step.fric))
            if rig is not None and a is not None:
                u = u + rig.R @ a
            y = s.N @ u
            if it % opt.check_every == 0:
                if rig is None:
                    res = kkt_residuals(s, step, u, p_rigid)
                else:  # the anchors' reactions are the outer iteration's business
                    res = _off_anchors(s, step, u, p_rigid, rig.keep)
                if max(res.values()) <= tol:
                    break
            p_rigid = np.maximum(0.0, p_rigid + self.rho1 * (y - s.g))
            q = q + self.rho2 * (s.p(y - step.w) - q)
        self._q = q
        return u, p_rigid, it

    def _balance(
        self, step: StepData, guess: StepSolution | None, p_rigid: NDArray, q: NDArray
    ) -> tuple[NDArray, NDArray, int]:
        """Load control: Newton on the amplitudes a until the contact forces balance the
        load along R, each residual an inner Uzawa solve; from the condensed Newton's
        cold start (or the previous level's a)."""
        s, opt, rig = self.system, self.options, self.rigid
        assert rig is not None
        d = s.N @ self.factor.solve(step.F)
        if guess is not None and guess.u is not None:
            a = rig.pinv_NR @ (s.N @ guess.u - d)
        else:
            y0, p_rigid = cold_start(s, step.w)
            a = rig.pinv_NR @ (y0 - d)
        f_R = rig.load(step.F)
        total, h = 0, 1e-3 * float(np.abs(s.g).max())

        def phi(
            a: NDArray, p_rigid: NDArray, q: NDArray
        ) -> tuple[NDArray, NDArray, NDArray, float]:
            nonlocal total
            u, p_rigid, it = self._iterate(step, p_rigid, q, a, 0.01 * opt.tol)
            total += it
            p_soft = s.p(s.N @ u - step.w)
            R2, size = rig.balance(layer_x(s, step.fric, p_soft, p_rigid), f_R)
            return R2, u, p_rigid, size

        R2, u, p_rigid, size = phi(a, p_rigid, q)
        for _ in range(50):
            if size <= 0.01 * opt.tol:
                break
            q0 = self._q
            J = np.column_stack([(phi(a + h * e, p_rigid, q0)[0] - R2) / h for e in np.eye(len(a))])
            try:
                a = a - np.linalg.solve(J, R2)
            except np.linalg.LinAlgError:
                x = layer_x(s, step.fric, s.p(s.N @ u - step.w), p_rigid)
                raise liftoff_error(s, rig, step, x, f_R, "Uzawa") from None
            R2, u, p_rigid, size = phi(a, p_rigid, self._q)
        return u, p_rigid, total


def _off_anchors(
    s: ContactSystem, step: StepData, u: NDArray, p_rigid: NDArray, keep: NDArray
) -> dict[str, float]:
    """:func:`kkt_residuals` with the equilibrium measured on the kept dofs only."""
    res = kkt_residuals(s, step, u, p_rigid)
    force, _ = s.contact_force(u, p_rigid, step.fric, step.w)
    Ku = s.K @ u
    r = (Ku - step.F + force)[keep]
    scale = max(float(np.abs(step.F).max()), float(np.abs(Ku).max()), float(np.abs(force).max()))
    res["equilibrium"] = float(np.abs(r).max()) / max(scale, 1e-300)
    return res
