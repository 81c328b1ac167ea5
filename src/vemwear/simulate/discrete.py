"""The assembled discrete problem: what the time loop needs at every level.

:class:`Discretization` holds the stiffness on the free dofs, the lifting of prescribed
displacements, the contact operators of all contact parts, and gives at each level the
data of the step problem (3.21): the load, the friction direction and the wear rate
from the tangential foundation velocity, and the shift of the contact unknowns by the
initial gap (docs/method.md, sections 3b and 4).
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..contact import ContactBoundary, tangential_velocity
from ..solvers.system import ContactSystem, StepData, StepSolution
from ..vem import stiffness

if TYPE_CHECKING:
    from .problem import Problem

__all__ = ["DataError", "Discretization"]


class DataError(ValueError):
    """Data that give non-finite numbers (an overflow), named with the quantity."""


class Discretization:
    """Everything the time loop needs: K on free dofs, contact operators, nodal data.

    The contact unknowns of the solvers are ``y = N_f u_f``, the normal displacement
    from the free dofs. The normal displacement is ``u_nu = y + offset``, where
    ``offset`` comes from prescribed components at contact nodes, and the step problem
    is solved with ``w + shift`` in place of ``w`` and the bound ``g + shift``, where
    ``shift = gap - offset``: so the penetration is ``u_nu - gap - w`` and the
    constraint ``u_nu - gap <= g`` (with no gap and no prescribed contact component,
    ``shift`` is zero and the data are the paper's, bitwise).
    """

    def __init__(self, problem: Problem) -> None:
        mesh = problem.mesh
        self.problem = problem
        self.contact: ContactBoundary = problem.contact
        cb = self.contact
        self.g, self.mu, self.kappa = (problem.nodal[k] for k in ("g", "mu", "kappa"))
        self.gap = problem.nodal["gap"]
        self.constraints = con = problem.constraints
        self.free = con.free
        with np.errstate(all="ignore"):
            self.K_full = stiffness(mesh, problem.material, problem.stabilization)
        if not np.all(np.isfinite(self.K_full.data)):
            mat = problem.material
            raise DataError(
                f"[material] lam = {mat.lam:g}, eta = {mat.eta:g} give a stiffness matrix with "
                "non-finite entries (an overflow); use values of a sensible scale"
            )
        K = self.K_full[self.free][:, self.free].tocsr()
        # the lifting of prescribed values, K_fc u_c(t) (none if all are zero)
        self.K_fc = None if con.zero else self.K_full[self.free][:, con.dofs].tocsr()
        index = -np.ones(self.n_dof, dtype=np.int64)
        index[self.free] = np.arange(len(self.free))
        cdofs = index[np.column_stack([2 * cb.nodes, 2 * cb.nodes + 1])]
        self.offset = self._contact_offset(cdofs)
        shift = self.gap - self.offset
        self.shift = shift if np.any(shift != 0.0) else None
        self.system = ContactSystem(
            K=K,
            contact_dofs=cdofs,
            normals=cb.normals,
            tangents=cb.tangents,
            weights=cb.weights,
            g=self.g if self.shift is None else self.g + self.shift,
            p=problem.law,
            dof_points=mesh.points[self.free // 2],
        )
        self._constant_load = not (
            callable(problem.f1)
            or any(callable(f) for f in problem.tractions.values())
            or con.time_dependent
        )
        self._F0: NDArray | None = None

    def _contact_offset(self, cdofs: NDArray[np.int64]) -> NDArray[np.float64]:
        """``nu_a . u_c`` at the contact nodes from their prescribed components, which
        must not change in time (a contact node's normal displacement is the unknown)."""
        con, cb = self.constraints, self.contact
        off = np.zeros(cb.m)
        if con.zero or np.all(cdofs >= 0):
            return off
        t = self.problem.time.t
        pos = -np.ones(self.n_dof, dtype=np.int64)
        pos[con.dofs] = np.arange(len(con.dofs))

        def at(time: float) -> NDArray[np.float64]:
            u = con.values(time)
            o = np.zeros(cb.m)
            for c in (0, 1):
                fixed = cdofs[:, c] < 0
                o[fixed] += cb.normals[fixed, c] * u[pos[2 * cb.nodes[fixed] + c]]
            return o

        off = at(float(t[0]))
        if con.time_dependent:
            for time in np.linspace(float(t[0]), float(t[-1]), 17)[1:]:
                if not np.allclose(at(float(time)), off, rtol=0, atol=1e-14):
                    raise ValueError(
                        "a prescribed displacement that changes in time moves contact nodes "
                        "along their normal; the normal displacement of a contact node is an "
                        "unknown of the contact problem: prescribe it on other parts"
                    )
        return off

    @property
    def n_dof(self) -> int:
        return 2 * self.problem.mesh.n_points

    def load(self, t: float) -> NDArray[np.float64]:
        """``f_h(t) - K_fc u_c(t)`` on the free dofs (body force by 3.3, tractions by
        edge quadrature, the lifting of prescribed displacements)."""
        if self._constant_load and self._F0 is not None:
            return self._F0
        pr = self.problem
        with np.errstate(all="ignore"):
            F = pr.external_load(t)
        F = F[self.free]
        if self.K_fc is not None:
            F = F - self.K_fc @ self.constraints.values(t)
        if not np.all(np.isfinite(F)):
            raise DataError(
                f"[loads] f1, f2 give a load vector with non-finite entries at t = {t:g} (an "
                "overflow); use loads of a sensible scale"
            )
        if self._constant_load:
            self._F0 = F
        return F

    def tangential_velocity(self, t: float) -> NDArray[np.float64]:
        """``v*(t) . tau_a`` at every contact node (each part's own v*)."""
        cb = self.contact
        return tangential_velocity(self.problem.parts, cb.part, cb.tangents, t)

    def step_data(self, level: int, w: NDArray[np.float64]) -> StepData:
        """The step problem of a level with the wear ``w`` (= w^n)."""
        t = float(self.problem.time.t[level])
        # n* . tau_a = -sign(v*_tau . tau_a): friction opposes the tangential sliding,
        # and vanishes where the foundation does not slide along the boundary
        fric = self.mu * -np.sign(self.tangential_velocity(t))
        w_step = w if self.shift is None else w + self.shift
        return StepData(F=self.load(t), w=w_step, fric=fric, t=t, level=level)

    def alpha(self, t: float) -> NDArray[np.float64]:
        """``alpha(t) = kappa |v*_tau(t)|`` at the contact nodes (2.2 for any Gamma_C)."""
        return self.kappa * np.abs(self.tangential_velocity(t))

    def physical(self, solution: StepSolution) -> StepSolution:
        """The solution with its true normal displacement ``u_nu = y + offset``."""
        if not np.any(self.offset):
            return solution
        return dataclasses.replace(solution, u_nu=solution.u_nu + self.offset)

    def full_displacement(
        self, u_free: NDArray[np.float64], t: float | None = None
    ) -> NDArray[np.float64]:
        """(n_points, 2) displacement: ``u_free`` on the free dofs, the prescribed values
        at time ``t`` on the others (zero on clamped parts)."""
        u = np.zeros(self.n_dof)
        u[self.free] = u_free
        if not self.constraints.zero:
            if t is None:
                raise ValueError("full_displacement: the time is needed for prescribed values")
            u[self.constraints.dofs] = self.constraints.values(t)
        return u.reshape(-1, 2)

    def smallness_estimate(self) -> dict[str, float]:
        """Estimate of the smallness condition of Theorem 3.4, ``c_0^2 L_p ||mu|| < C_1``.

        ``C_1 / c_0^2`` is the smallest generalized eigenvalue of ``a_h(v, v)`` against
        ``||v||^2_{L^2(Gamma_C)}`` (nodal quadrature) on the free dofs; the condition
        reads ``L_p ||mu||_inf * (c_0^2 / C_1) < 1``.
        """
        import scipy.sparse.linalg as spla

        s = self.system
        Mc = (s.N.T @ sp.diags(s.weights) @ s.N + s.Tau.T @ sp.diags(s.weights) @ s.Tau).tocsc()
        try:
            vals = spla.eigsh(Mc, k=1, M=s.K.tocsc(), which="LA", return_eigenvectors=False)
            ratio = float(vals[0])  # max of ||v||^2_Gc / a_h(v, v) = c_0^2 / C_1
        except Exception:
            return {"ratio": float("nan")}
        Lp = float(self.problem.law.lipschitz)
        value = Lp * float(np.abs(self.mu).max(initial=0)) * ratio
        if np.isfinite(value) and value >= 1.0:
            warnings.warn(
                f"the smallness condition of Theorem 3.4 may fail: L_p ||mu|| c_0^2 / C_1 "
                f"~= {value:.3g} >= 1; the step problem may have no unique solution",
                stacklevel=2,
            )
        return {
            "c0_sq_over_C1": ratio,
            "L_p": Lp,
            "mu_max": float(np.abs(self.mu).max(initial=0)),
            "ratio": value,
        }
