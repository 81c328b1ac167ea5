"""The full-space semismooth Newton method for the step problem (the plain path).

Newton on all free dofs with a fresh sparse factorization of the Jacobian at every
iteration; the complementarity conditions as in :mod:`.newton`. Under load control
(:mod:`.rigid`) its unknowns are u on the kept dofs and the rigid amplitudes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .backends import factorize
from .newton import NewtonOptions
from .rigid import (
    anchored_factor,
    bordered_jacobian,
    cold_start,
    layer_x,
    liftoff_error,
    pressed,
    rigid_modes,
    touching_solution,
)
from .system import (
    ContactSystem,
    ConvergenceError,
    StepData,
    StepSolution,
    at_rounding_floor,
    check_converged,
    kkt_residuals,
)


class FullNewton:
    """Semismooth Newton on all free dofs (the plain path): a new sparse LU per iteration."""

    method = "newton-full"
    #: No block recovery, no prediction, no set-up (a new LU per iteration).
    batch = False
    predicts = False
    setup_timings: dict[str, float] = {}  # noqa: RUF012 - read only

    def __init__(self, system: ContactSystem, options: NewtonOptions | None = None) -> None:
        self.system = system
        self.options = options or NewtonOptions()
        #: the rigid motions that only contact holds (load control), or None
        self.rigid = None if system.rigid is None else rigid_modes(system, system.contact_cols)
        self._G: Any = None  # K without the anchors, factorized at the first use

    def solve(
        self, step: StepData, guess: StepSolution | None = None, recover: bool = True
    ) -> StepSolution:
        s, opt, rig = self.system, self.options, self.rigid
        if rig is not None and rig.negligible(step.F):
            return self._touching(step)
        # a previous level that touched without force is no warm start under load control
        if (
            guess is not None
            and guess.u is not None
            and (rig is None or pressed(s, s.N @ guess.u, guess.p_rigid, step.w))
        ):
            u, p_rigid = np.array(guess.u, copy=True), np.array(guess.p_rigid, copy=True)
        elif rig is not None:  # the rigid motion to the condensed Newton's cold start
            y0, p_rigid = cold_start(s, step.w)
            u = rig.R @ (rig.pinv_NR @ y0)
        else:
            u, p_rigid = np.zeros(s.n_free), np.zeros(s.m)
        N, Tau, weights = s.N, s.Tau, s.weights
        it = 0
        last: tuple[NDArray, NDArray] | None = None
        same = 0  # Newton steps in a row on one piece (active set, slopes)
        while it < opt.max_iter:
            y = N @ u
            p_soft, dp = s.p(y - step.w), s.p.derivative(y - step.w)
            active = p_rigid + s.c_ncp * (y - s.g) > 0
            if last is not None and np.array_equal(active, last[0]) and np.array_equal(dp, last[1]):
                same += 1
                if same >= 2:  # the residual of the iterate, only where it may stop
                    res = kkt_residuals(s, step, u, np.maximum(p_rigid, 0.0))
                    if at_rounding_floor(same, max(res.values()) <= opt.tol):
                        break
            else:
                same = 0
            last = (active, dp)
            it += 1
            if s.rows == 1:
                J = (
                    s.K
                    + N.T @ sp.diags(weights * dp) @ N
                    + Tau.T @ sp.diags(weights * step.fric * dp) @ N
                )
            else:  # each friction row of a node moves with the node's normal displacement
                J = (
                    s.K
                    + N.T @ sp.diags(weights * dp) @ N
                    + Tau.T @ sp.diags(s.friction_weights(step.fric, dp)) @ sp.vstack([N] * s.rows)
                )
            # residual without the rigid-layer term: p_rigid_new enters the system directly
            r0 = s.K @ u - step.F + s.layer_forces(0.0, p_soft, step.fric)
            # under load control the unknowns are u on the kept dofs and the rigid
            # amplitudes a (u = P u_keep + R a, :mod:`.rigid`)
            Jb = J if rig is None else bordered_jacobian(J, rig)[0]
            if np.any(active):  # saddle point with the active constraints N_A u = g_A
                A = np.flatnonzero(active)
                NA = N[A]
                G = NA.T @ sp.diags(weights[active])
                if s.friction_total is not None:  # the friction of p_rigid at those nodes
                    on = np.where(s.friction_total, 1.0, 0.0)
                    rows = s.friction_weights(step.fric, on)
                    E = sp.csr_matrix(
                        (
                            np.ones(s.rows * len(A)),
                            (
                                np.concatenate([A + k * s.m for k in range(s.rows)]),
                                np.tile(np.arange(len(A)), s.rows),
                            ),
                        ),
                        shape=(s.rows * s.m, len(A)),
                    )
                    G = G + Tau.T @ sp.diags(rows) @ E
                NAb = NA if rig is None else bordered_jacobian(NA, rig)[0]
                M = sp.bmat([[Jb, G], [NAb, None]], format="csc")
                rhs = np.concatenate([-r0, s.g[active] - NA @ u])
            else:
                M, rhs = sp.csc_matrix(Jb), -r0
            try:
                lu = factorize(M, opt.backend, symmetric=False, many_factorizations=True)
            except ConvergenceError:
                if rig is None or np.any(active) or np.any(dp):
                    raise
                x = layer_x(s, step.fric, p_soft, p_rigid)
                raise liftoff_error(
                    s, rig, step, x, rig.load(step.F), "semismooth Newton (full)"
                ) from None
            sol = lu.solve(rhs)
            if rig is None:
                du = sol[: s.n_free]
            else:
                nk = len(rig.keep)
                du = rig.R @ sol[nk : s.n_free]
                du[rig.keep] += sol[:nk]
            p_rigid_new = np.zeros(s.m)
            p_rigid_new[active] = sol[s.n_free :]
            u, p_rigid = u + du, p_rigid_new
            if np.abs(du).max() <= 1e-14 * max(
                np.abs(u).max(), float(np.abs(s.g).max())
            ) and np.array_equal(active, p_rigid + s.c_ncp * (N @ u - s.g) > 0):
                break
        p_rigid = np.maximum(p_rigid, 0.0)
        res = kkt_residuals(s, step, u, p_rigid)
        if rig is not None and max(res.values()) > opt.tol:
            p_soft = s.p(N @ u - step.w)
            if not (np.any(p_soft) or np.any(p_rigid)):
                x = layer_x(s, step.fric, p_soft, p_rigid)
                raise liftoff_error(s, rig, step, x, rig.load(step.F), "semismooth Newton (full)")
        check_converged(res, opt.tol, step, "semismooth Newton (full)", it)
        y = N @ u
        return StepSolution(
            u=u, u_nu=y, p_rigid=p_rigid, p_soft=s.p(y - step.w), iterations=it, residuals=res
        )

    def _touching(self, step: StepData) -> StepSolution:
        """Under a load with no component along the held rigid motions: no contact
        force, the body touching the worn layer (:func:`.rigid.touching_solution`)."""
        assert self.rigid is not None
        if self._G is None:
            self._G = anchored_factor(self.system, self.rigid, self.options.backend)
        sol = touching_solution(self.system, self.rigid, step, self._G)
        check_converged(sol.residuals, self.options.tol, step, "semismooth Newton (full)", 0)
        return sol


__all__ = ["FullNewton"]
