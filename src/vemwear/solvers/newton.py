"""Semismooth (primal-dual active-set) Newton methods for the step problem.

The complementarity conditions ``p_rigid >= 0, N u <= g, p_rigid (N u - g) = 0`` are written
as ``p_rigid = max(0, p_rigid + c (N u - g))``; its generalized derivative splits the contact
nodes into an active set (``N u = g``) and an inactive set (``p_rigid = 0``), and
``p`` contributes its generalized derivative ``p'``.

* :class:`CondensedNewton` works on the contact unknowns only. The stiffness never
  changes, so ``K`` is factorized once per simulation and condensed onto the contact
  nodes: ``u = K^{-1} F - K^{-1} (N^T f_N + Tau^T f_T)`` gives
  ``N u = d - C_NN f_N - C_NT f_T`` with the dense compliance blocks
  ``C_NN = N K^{-1} N^T`` and ``C_NT = N K^{-1} Tau^T``.
* :class:`FullNewton` is the plain path: Newton on all free dofs, with a fresh sparse
  factorization of the Jacobian at every iteration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import NDArray

from .linalg import SchurFactor, factorize
from .system import (
    ContactSystem,
    ConvergenceError,
    StepData,
    StepSolution,
    check_converged,
    condensed_residuals,
    kkt_residuals,
)


@dataclass(frozen=True)
class NewtonOptions:
    """Tolerance on the scaled KKT residuals, iteration limit, linear-algebra backend
    (the condensed solver always uses SuperLU, whose factors give the Schur complement)."""

    tol: float = 1e-10
    max_iter: int = 100
    backend: str = "auto"


def _reduced_matrix(J11, J12, active):
    """Columns of the Newton system for the unknowns dy_I (inactive) and dlam_A (active)."""
    return np.hstack([J11[:, ~active], J12[:, active]])


def _active_set_step(lu, J11, J12, y, p_rigid, R, active, g):
    """Solve the Newton system for (dy, dp_rigid) with dy_A = g_A - y_A and dlam_I = -lam_I.

    ``J11 dy + J12 dp_rigid = -R`` (m equations); the unknowns are dy_I and dlam_A, and
    ``lu`` factorizes their columns (:func:`_reduced_matrix`).
    """
    inactive = ~active
    dy = np.zeros_like(y)
    dp_rigid = np.zeros_like(p_rigid)
    dy[active] = g[active] - y[active]
    dp_rigid[inactive] = -p_rigid[inactive]
    rhs = -R - J11[:, active] @ dy[active] - J12[:, inactive] @ dp_rigid[inactive]
    sol = sla.lu_solve(lu, rhs)
    ni = int(inactive.sum())
    dy[inactive] = sol[:ni]
    dp_rigid[active] = sol[ni:]
    return dy, dp_rigid


class CondensedNewton:
    """Semismooth Newton on the condensed system; one factorization of K per simulation.

    Parameters
    ----------
    system : ContactSystem
    options : NewtonOptions
    """

    method = "newton"

    def __init__(self, system: ContactSystem, options: NewtonOptions | None = None) -> None:
        self.system = system
        self.options = options or NewtonOptions()
        m = system.m
        # one factorization whose trailing block is the Schur complement on Gamma_C
        self.factor = SchurFactor(system.K, system.contact_dofs.ravel(), system.dof_points)
        C = self.factor.S_inv.reshape(m, 2, m, 2)  # block of K^{-1} on the contact dofs
        nu, tau = system.normals, system.tangents
        self.C_NN = np.einsum("ai,aibj,bj->ab", nu, C, nu)
        self.C_NT = np.einsum("ai,aibj,bj->ab", nu, C, tau)
        self.A_norm = self.C_NN * system.weights[None, :]
        self._eye = np.eye(m)
        self._lu_cache: dict[bytes, tuple] = {}
        self._fric_key: bytes | None = None
        self._F: NDArray | None = None
        self._d: NDArray | None = None

    def _normal_displacement_of_load(self, F: NDArray) -> NDArray:
        """``d = N K^{-1} F``, recomputed only when the load changes."""
        if self._F is None or not np.array_equal(F, self._F):
            self._F = np.array(F, copy=True)
            self._d = self.system.N @ self.factor.solve(self._F)
        return self._d  # type: ignore[return-value]

    def recover_many(
        self, steps: list[StepData], p_rigids: list[NDArray], p_softs: list[NDArray]
    ) -> NDArray:
        """Full displacements of several levels with one block solve, shape (nf, len(steps))."""
        s = self.system
        rhs = np.column_stack(
            [
                st.F - s.layer_forces(p_rigid, p_soft, st.fric)
                for st, p_rigid, p_soft in zip(steps, p_rigids, p_softs, strict=True)
            ]
        )
        return self.factor.solve(rhs)

    def solve(
        self, step: StepData, guess: StepSolution | None = None, recover: bool = True
    ) -> StepSolution:
        """Solve one step problem on the contact unknowns (y = N u, p_rigid).

        With ``recover=False`` the full displacement is not computed (``u`` is None);
        :meth:`recover_many` computes it later for several levels at once.
        """
        s, opt = self.system, self.options
        d = self._normal_displacement_of_load(step.F)
        if guess is not None:
            y, p_rigid = np.array(guess.u_nu, copy=True), np.array(guess.p_rigid, copy=True)
        else:
            y, p_rigid = np.minimum(d, s.g), np.zeros(s.m)
        A_norm = self.A_norm
        A_fric = self.C_NT * (s.weights * step.fric)[None, :]
        fric_key = step.fric.tobytes()
        if fric_key != self._fric_key:  # the Newton matrices depend on the friction direction
            self._lu_cache.clear()
            self._fric_key = fric_key
        it = 0
        while True:
            r = y - step.w
            p_soft, dp = s.p(r), s.p.derivative(r)
            R = y - d + A_norm @ (p_soft + p_rigid) + A_fric @ p_soft
            res = condensed_residuals(s, y, p_rigid, R)
            if max(res.values()) <= 0.1 * opt.tol or it == opt.max_iter:
                break
            it += 1
            active = p_rigid + s.c_ncp * (y - s.g) > 0
            J11 = self._eye + (A_norm + A_fric) * dp[None, :]
            key = active.tobytes() + dp.tobytes()
            lu = self._lu_cache.get(key)
            if lu is None:  # same active set and slopes as before: reuse the factorization
                lu = sla.lu_factor(_reduced_matrix(J11, A_norm, active), check_finite=False)
                if len(self._lu_cache) >= 8:
                    self._lu_cache.pop(next(iter(self._lu_cache)))
                self._lu_cache[key] = lu
            dy, dp_rigid = _active_set_step(lu, J11, A_norm, y, p_rigid, R, active, s.g)
            y, p_rigid = y + dy, p_rigid + dp_rigid
        p_rigid = np.maximum(p_rigid, 0.0)
        p_soft = s.p(y - step.w)
        u = None
        if recover:
            u = self.recover_many([step], [p_rigid], [p_soft])[:, 0]
            res = kkt_residuals(s, step, u, p_rigid)
            y = s.N @ u
        check_converged(res, opt.tol, step, "semismooth Newton (condensed)", it)
        return StepSolution(
            u=u, u_nu=y, p_rigid=p_rigid, p_soft=p_soft, iterations=it, residuals=res
        )


class FullNewton:
    """Semismooth Newton on all free dofs (the plain path): a new sparse LU per iteration."""

    method = "newton-full"

    def __init__(self, system: ContactSystem, options: NewtonOptions | None = None) -> None:
        self.system = system
        self.options = options or NewtonOptions()

    def solve(
        self, step: StepData, guess: StepSolution | None = None, recover: bool = True
    ) -> StepSolution:
        s, opt = self.system, self.options
        if guess is not None and guess.u is not None:
            u, p_rigid = np.array(guess.u, copy=True), np.array(guess.p_rigid, copy=True)
        else:
            u, p_rigid = np.zeros(s.n_free), np.zeros(s.m)
        N, Tau, weights = s.N, s.Tau, s.weights
        it = 0
        while it < opt.max_iter:
            it += 1
            y = N @ u
            p_soft, dp = s.p(y - step.w), s.p.derivative(y - step.w)
            active = p_rigid + s.c_ncp * (y - s.g) > 0
            J = (
                s.K
                + N.T @ sp.diags(weights * dp) @ N
                + Tau.T @ sp.diags(weights * step.fric * dp) @ N
            )
            # residual without the rigid-layer term: p_rigid_new enters the system directly
            r0 = s.K @ u - step.F + s.layer_forces(0.0, p_soft, step.fric)
            if np.any(active):  # saddle point with the active constraints N_A u = g_A
                NA = N[np.flatnonzero(active)]
                M = sp.bmat([[J, NA.T @ sp.diags(weights[active])], [NA, None]], format="csc")
                rhs = np.concatenate([-r0, s.g[active] - NA @ u])
            else:
                M, rhs = sp.csc_matrix(J), -r0
            sol = factorize(M, opt.backend, symmetric=False, many_factorizations=True).solve(rhs)
            du = sol[: s.n_free]
            p_rigid_new = np.zeros(s.m)
            p_rigid_new[active] = sol[s.n_free :]
            u, p_rigid = u + du, p_rigid_new
            if np.abs(du).max() <= 1e-14 * max(
                np.abs(u).max(), float(np.abs(s.g).max())
            ) and np.array_equal(active, p_rigid + s.c_ncp * (N @ u - s.g) > 0):
                break
        p_rigid = np.maximum(p_rigid, 0.0)
        res = kkt_residuals(s, step, u, p_rigid)
        check_converged(res, opt.tol, step, "semismooth Newton (full)", it)
        y = N @ u
        return StepSolution(
            u=u, u_nu=y, p_rigid=p_rigid, p_soft=s.p(y - step.w), iterations=it, residuals=res
        )


__all__ = ["CondensedNewton", "ConvergenceError", "FullNewton", "NewtonOptions"]
