"""The continuous data of Problem 2.1 and their discretization (paper Sections 2-3).

The discrete choices the paper leaves open (nodal contact quadrature, normals at
corners, the stabilization weight, the load) are those of docs/method.md, sections 1-4.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, cast

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..contact import (
    ComplianceLaw,
    ContactBoundary,
    FoundationVelocity,
    LinearCompliance,
    NodalField,
    check_law,
    contact_boundary,
    nodal_values,
)
from ..mesh.checks import check_mesh
from ..mesh.polymesh import Mesh
from ..solvers.system import ContactSystem, StepData
from ..util.hashing import sha256_arrays
from ..vem import Material, body_force_vector, stiffness, traction_vector
from ..vem.assembly import Field
from .timegrid import TimeGrid


class DataError(ValueError):
    """Data that give non-finite numbers (an overflow), named with the quantity."""


@dataclass(frozen=True, eq=False)
class Problem:
    """Contact problem with wear on a tagged polygonal mesh (Problem 2.1 / 3.3).

    Parameters
    ----------
    mesh : Mesh
        With boundary parts ``clamped`` (Gamma_D, required), ``traction`` (Gamma_N)
        and ``contact`` (Gamma_C, required).
    material : Material
        Lamé coefficients lam, eta.
    time : TimeGrid
        The partition of [0, T].
    f1, f2 : Field
        Body force and traction: a 2-vector or a callable ``f(x, t)``.
    p : ComplianceLaw
        Normal compliance law of the soft layer.
    g, mu, kappa : NodalField
        Layer thickness (> 0), friction coefficient (>= 0), wear coefficient (>= 0)
        along Gamma_C.
    v_star : FoundationVelocity or 2-vector
        Velocity of the foundation, never zero.
    stabilization : str
        ``"paper"`` (weight 1, the paper's dofi-dofi), ``"eta"`` or ``"trace"``.
    """

    mesh: Mesh
    material: Material
    time: TimeGrid
    f1: Field = (0.0, 0.0)
    f2: Field = (0.0, 0.0)
    p: ComplianceLaw = field(default_factory=lambda: LinearCompliance(0.4))
    g: NodalField = 0.1
    mu: NodalField = 0.0
    kappa: NodalField = 0.0
    v_star: FoundationVelocity | ArrayLike = (1.0, 0.0)
    stabilization: str = "paper"

    def __post_init__(self) -> None:
        if not isinstance(self.v_star, FoundationVelocity):
            object.__setattr__(self, "v_star", FoundationVelocity(self.v_star))
        v_star = cast(FoundationVelocity, self.v_star)
        check_mesh(self.mesh, require=("clamped", "contact"))
        scale = float(max(np.abs(self.nodal["g"]).max(), 1e-300))  # validates g, mu, kappa
        check_law(self.p, scale=scale)
        for level, t in enumerate(self.time.t):
            if np.linalg.norm(v_star(t)) == 0.0:
                raise ValueError(
                    f"v_star vanishes at t = {t:g} (level {level}); H0(c) needs v* != 0"
                )

    @cached_property
    def contact(self) -> ContactBoundary:
        """Nodes, weights and normals of Gamma_C."""
        return contact_boundary(self.mesh)

    @cached_property
    def nodal(self) -> dict[str, NDArray[np.float64]]:
        """g, mu and kappa at the contact nodes, checked for their signs."""
        cb = self.contact
        out = {}
        for name, rel in (("g", "> 0"), ("mu", ">= 0"), ("kappa", ">= 0")):
            v = nodal_values(getattr(self, name), cb, name)
            ok = v > 0 if name == "g" else v >= 0
            if not np.all(ok):
                a = int(np.flatnonzero(~ok)[0])
                raise ValueError(
                    f"{name} must be {rel} on the contact part; it is {v[a]:g} at contact node "
                    f"{a} (vertex {cb.nodes[a]}, x = {cb.points[a].tolist()})"
                )
            out[name] = v
        return out

    @cached_property
    def discrete(self) -> Discretization:
        """The assembled discrete problem (built on first use)."""
        return Discretization(self)

    def describe(self) -> dict[str, Any]:
        """The inputs as JSON-friendly data (callables by name)."""

        def desc(x: Any) -> Any:
            if callable(x):
                return getattr(x, "__name__", "callable")
            if isinstance(x, dict):
                return {k: desc(v) for k, v in x.items()}
            return np.asarray(x).tolist()

        m = self.mesh
        return {
            "mesh": {
                "points": m.n_points,
                "cells": m.n_cells,
                "h": m.h,
                "cells_by_vertex_count": {str(n): len(i) for n, (i, _) in m.groups.items()},
            },
            "material": {"lam": self.material.lam, "eta": self.material.eta},
            "time": self.time.describe(),
            "f1": desc(self.f1),
            "f2": desc(self.f2),
            "p": self.p.describe(),
            "g": desc(self.g),
            "mu": desc(self.mu),
            "kappa": desc(self.kappa),
            "v_star": self.v_star.describe(),  # type: ignore[union-attr]
            "stabilization": self.stabilization,
        }

    def fingerprint(self) -> dict[str, Any]:
        """What determines the computed numbers: the physics and the discretization.

        Solver options are not part of it: every solver that converges gives the same
        solution to its tolerance. Data given as callables enter by their values (g,
        mu and kappa at the contact nodes, v* at up to 65 sampled levels, the load
        vector at t_0 and T) besides their names. Hash it with
        :func:`vemwear.util.hashing.sha256_json`.
        """
        from .. import __version__

        m, t = self.mesh, self.time.t
        sample = np.unique(np.linspace(0, len(t) - 1, min(len(t), 65)).astype(np.int64))

        def load(t: float) -> NDArray[np.float64]:  # without assembling the stiffness
            return body_force_vector(m, self.f1, t) + traction_vector(m, self.f2, t)

        return {
            "format": "vemwear-problem/1",
            "vemwear_version": __version__,
            "description": self.describe(),
            "mesh": sha256_arrays(m.points, m.cell_offsets, m.cell_vertices, m.boundary_tags),
            "time": sha256_arrays(t),
            "nodal": sha256_arrays(*(self.nodal[k] for k in ("g", "mu", "kappa"))),
            "v_star": sha256_arrays(np.array([self.v_star(t[i]) for i in sample])),  # type: ignore[operator]
            "load": sha256_arrays(load(float(t[0])), load(float(t[-1]))),
        }


class Discretization:
    """Everything the time loop needs: K on free dofs, contact operators, nodal data."""

    def __init__(self, problem: Problem) -> None:
        mesh = problem.mesh
        self.problem = problem
        self.contact: ContactBoundary = problem.contact
        cb = self.contact
        self.g, self.mu, self.kappa = (problem.nodal[k] for k in ("g", "mu", "kappa"))
        ndof = 2 * mesh.n_points
        fixed = np.zeros(ndof, dtype=bool)
        cl = mesh.part_vertices("clamped")
        fixed[2 * cl] = fixed[2 * cl + 1] = True
        self.free = np.flatnonzero(~fixed)
        with np.errstate(all="ignore"):
            self.K_full = stiffness(mesh, problem.material, problem.stabilization)
        if not np.all(np.isfinite(self.K_full.data)):
            mat = problem.material
            raise DataError(
                f"[material] lam = {mat.lam:g}, eta = {mat.eta:g} give a stiffness matrix with "
                "non-finite entries (an overflow); use values of a sensible scale"
            )
        K = self.K_full[self.free][:, self.free].tocsr()
        index = -np.ones(ndof, dtype=np.int64)
        index[self.free] = np.arange(len(self.free))
        cdofs = index[np.column_stack([2 * cb.nodes, 2 * cb.nodes + 1])]
        self.system = ContactSystem(
            K=K,
            contact_dofs=cdofs,
            normals=cb.normals,
            tangents=cb.tangents,
            weights=cb.weights,
            g=self.g,
            p=problem.p,
            dof_points=mesh.points[self.free // 2],
        )
        self._constant_load = not (callable(problem.f1) or callable(problem.f2))
        self._F0: NDArray | None = None

    @property
    def n_dof(self) -> int:
        return 2 * self.problem.mesh.n_points

    def load(self, t: float) -> NDArray[np.float64]:
        """``f_h(t)`` on the free dofs (body force by 3.3, traction by edge quadrature)."""
        if self._constant_load and self._F0 is not None:
            return self._F0
        pr = self.problem
        with np.errstate(all="ignore"):
            F = body_force_vector(pr.mesh, pr.f1, t) + traction_vector(pr.mesh, pr.f2, t)
        F = F[self.free]
        if not np.all(np.isfinite(F)):
            raise DataError(
                f"[loads] f1, f2 give a load vector with non-finite entries at t = {t:g} (an "
                "overflow); use loads of a sensible scale"
            )
        if self._constant_load:
            self._F0 = F
        return F

    def step_data(self, level: int, w: NDArray[np.float64]) -> StepData:
        t = float(self.problem.time.t[level])
        n_star = self.problem.v_star.n_star(t)  # type: ignore[union-attr]
        fric = self.mu * self.contact.friction_direction(n_star)
        return StepData(F=self.load(t), w=w, fric=fric, t=t, level=level)

    def alpha(self, t: float) -> NDArray[np.float64]:
        """``alpha(t) = kappa |v*(t)|`` at the contact nodes (2.2)."""
        return self.kappa * self.problem.v_star.speed(t)  # type: ignore[union-attr]

    def full_displacement(self, u_free: NDArray[np.float64]) -> NDArray[np.float64]:
        """(n_points, 2) displacement with zeros on the clamped part."""
        u = np.zeros(self.n_dof)
        u[self.free] = u_free
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
        Lp = float(self.problem.p.lipschitz)
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
