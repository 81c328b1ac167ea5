"""The step problem (paper 3.21) as a complementarity problem on the free dofs.

With ``w`` fixed, find ``u`` and ``p_rigid`` such that (docs/method.md, step problem)

    K u - F + N^T(weights (p(N u - w) + p_rigid)) + Tau^T(weights fric q) = 0,
    p_rigid >= 0,  N u <= g,  p_rigid (N u - g) = 0,

where ``fric_a = mu_a (n*(t) . tau_a)``, ``p`` is the compliance law and ``weights``
are the nodal weights omega_a. ``p_rigid`` and ``p_soft = p(N u - w)`` are the pressures
(forces per unit length) of the rigid and the soft layer; the weights turn them into
nodal forces (docs/method.md). Friction acts on ``q = p_soft`` (the paper's law 2.8)
or, at the nodes of ``friction_total``, on the whole pressure ``q = p_soft + p_rigid``
(section 4b). ``Tau`` has one row per node, or two (``tau_1``, then ``tau_2``) where
the foundation velocity turns in 3D; ``fric`` has one coefficient per row.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..contact.law import ComplianceLaw
from .stiffness import Stiffness, abs_row_sums

#: The scaled KKT residuals every step reports, in this order.
RESIDUAL_NAMES = ("equilibrium", "feasibility", "complementarity")

_TINY = float(np.finfo(float).tiny)


class ConvergenceError(RuntimeError):
    """A step problem whose solver did not reach its tolerance."""


class FactorizationError(ConvergenceError):
    """A sparse factorization failed (a singular or indefinite matrix)."""


@dataclass(frozen=True, eq=False)
class ContactSystem:
    """Data of the step problem that do not change in time.

    Attributes
    ----------
    K : (nf, nf) sparse stiffness on the free dofs, or, in an MPI run, an operator
        (:class:`.stiffness.Stiffness`) whose rows the ranks hold
    contact_dofs : (m, d) free-dof ids of the d components at each contact node
        (-1 for a prescribed component); None when ``trace`` is given
    normals : (m, d) unit nu_a
    tangents : (r m, d) the unit directions of the friction rows: tau_a (r = 1; in 3D
        the line of the friction force, :mod:`vemwear.contact.boundary3d`), or tau_1,a
        then tau_2,a (r = 2, a foundation velocity that turns in 3D)
    weights : (m,) nodal weights
    g : (m,) thickness of the soft layer (bound on ``N u``)
    p : the compliance law
    dof_points : (nf, d) coordinates of the vertex of each free dof (for the ordering
        of the factorization)
    trace : (d m, nf) sparse, optional
        Rows ``d a + c``: component c of the displacement at node a from the free dofs,
        for spaces whose contact nodes are not dofs (k = 2: edge midpoints); then
        ``N = diag(nu_x) T_x + diag(nu_y) T_y`` and the same for ``Tau``.
    rigid : (nf, r), optional
        The rigid motions that only contact holds (load control, :mod:`.rigid`): K is
        singular along them; None when the constraints hold the body.
    rigid_names, contact_names : the rigid motions in words and the contact parts, for
        messages
    friction_total : (m,) bool, optional
        The nodes where friction acts on the whole contact pressure ``p_soft +
        p_rigid`` (``friction_on = "total"``); None: on ``p_soft`` everywhere.
    assembly : optional
        K as a sum over the mesh's cells, for a backend that assembles it rank by rank
        over an MPI job (the petsc backend): an object with ``n_cells``,
        ``partition(parts)`` and ``part(cells)``
        (:class:`vemwear.simulate.cellparts.CellAssembly`); the serial backends use K.
    """

    K: sp.csr_matrix | Stiffness
    contact_dofs: NDArray[np.int64] | None
    normals: NDArray[np.float64]
    tangents: NDArray[np.float64]
    weights: NDArray[np.float64]
    g: NDArray[np.float64]
    p: ComplianceLaw
    dof_points: NDArray[np.float64]
    trace: sp.csr_matrix | None = None
    rigid: NDArray[np.float64] | None = None
    rigid_names: tuple[str, ...] = ()
    contact_names: tuple[str, ...] = ()
    friction_total: NDArray[np.bool_] | None = None
    assembly: Any = None
    N: sp.csr_matrix = field(init=False, repr=False)
    Tau: sp.csr_matrix = field(init=False, repr=False)
    c_ncp: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.contact_dofs is None:
            self._init_from_trace()
            return
        m, nf = len(self.weights), self.K.shape[0]
        for name, direction in (("N", self.normals), ("Tau", self.tangents)):
            r = len(direction) // m  # friction rows per node
            rows = np.repeat(np.arange(r * m), np.shape(self.contact_dofs)[1])
            cols = np.tile(np.asarray(self.contact_dofs).ravel(), r)
            free = cols >= 0  # prescribed components do not enter N and Tau
            vals = np.asarray(direction).ravel()
            op = sp.csr_matrix((vals[free], (rows[free], cols[free])), shape=(r * m, nf))
            object.__setattr__(self, name, op)
        # scale of the complementarity function p_rigid + c (N u - g): the normal stiffness
        # per unit length at each node, so both terms are pressures of comparable size
        diagK = self.K.diagonal()
        dK = np.where(self.contact_dofs >= 0, diagK[np.maximum(self.contact_dofs, 0)], 0.0)
        kn = np.sum(dK * np.asarray(self.normals) ** 2, axis=1)
        object.__setattr__(self, "c_ncp", kn / self.weights)

    def _init_from_trace(self) -> None:
        """N, Tau and the complementarity scale from the trace operator."""
        if self.trace is None:
            raise ValueError("ContactSystem: give contact_dofs or trace")
        T = sp.csr_matrix(self.trace)
        k, m = np.shape(self.normals)[1], len(self.weights)
        for name, dirs in (("N", self.normals), ("Tau", self.tangents)):
            ops = []
            for d in np.asarray(dirs).reshape(-1, m, k):  # each friction row
                op = sp.diags(d[:, 0]) @ T[0::k] + sp.diags(d[:, 1]) @ T[1::k]
                for c in range(2, k):
                    op = op + sp.diags(d[:, c]) @ T[c::k]
                ops.append(op)
            op = sp.csr_matrix(ops[0] if len(ops) == 1 else sp.vstack(ops))
            op.eliminate_zeros()
            object.__setattr__(self, name, op)
        # as for nodal dofs: sum_j N_aj^2 K_jj, the normal stiffness at the node
        kn = self.N.multiply(self.N) @ self.K.diagonal()
        object.__setattr__(self, "c_ncp", np.asarray(kn) / self.weights)

    @property
    def m(self) -> int:
        return len(self.weights)

    @property
    def rows(self) -> int:
        """The friction rows per node r: 1, or 2 where v* turns in 3D."""
        return len(self.tangents) // len(self.weights)

    def friction_pressure(self, p_soft: NDArray, p_rigid: NDArray | float) -> NDArray:
        """The pressure friction acts on, (m,) or (m, k): ``p_soft``, plus ``p_rigid`` at
        the nodes of :attr:`friction_total` (``p_soft`` itself when there are none)."""
        if self.friction_total is None:
            return p_soft
        total = self.friction_total if np.ndim(p_soft) == 1 else self.friction_total[:, None]
        return p_soft + np.where(total, p_rigid, 0.0)

    def friction_weights(self, fric: NDArray, q: NDArray) -> NDArray:
        """``W Fric q``, the weights of ``Tau^T`` in the friction force: ``fric`` (r m,)
        or (r m, k), ``q`` (m,) or (m, k) the pressure friction acts on."""
        w = self.weights if np.ndim(fric) == 1 else self.weights[:, None]
        if len(fric) == len(w):  # one row per node
            return w * fric * q
        F = np.reshape(fric, (-1, *np.shape(q)))
        return np.reshape((w * F) * q, np.shape(fric))

    def tile_rows(self, x: NDArray) -> NDArray:
        """A nodal array (m,) or (m, k) repeated for the r friction rows."""
        r = self.rows
        return x if r == 1 else np.concatenate([x] * r)

    @cached_property
    def contact_cols(self) -> NDArray[np.int64]:
        """The free dofs that ``N`` and ``Tau`` act on, increasing: the contact forces
        live there."""
        return np.unique(np.concatenate([self.N.indices, self.Tau.indices]))

    @cached_property
    def N_contact(self) -> sp.csr_matrix:
        """``N`` restricted to the columns :attr:`contact_cols`: ``N u = N_contact
        u[contact_cols]``, the same sums in the same order without reading all of u."""
        return self.N[:, self.contact_cols].tocsr()

    @cached_property
    def force_operators(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """``N^T`` and ``Tau^T`` restricted to the rows :attr:`contact_cols`, so that
        products with several levels' pressures are (2m, k), not (n, k)."""
        cols = self.contact_cols
        return self.N[:, cols].T.tocsr(), self.Tau[:, cols].T.tocsr()

    @cached_property
    def transposes(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """``N^T`` and ``Tau^T`` (CSR), kept: an iteration that applies them at every
        step would otherwise rebuild them each time (the same sums in the same order)."""
        return self.N.T.tocsr(), self.Tau.T.tocsr()

    @cached_property
    def K_row_sums(self) -> NDArray[np.float64]:
        """The absolute row sums of K, for backward errors (:func:`.stiffness.
        abs_row_sums`); of a distributed K, summed by the ranks on their rows and
        gathered (:meth:`.stiffness.Stiffness.row_sums`)."""
        if isinstance(self.K, Stiffness):
            return self.K.row_sums()
        K = self.K if isinstance(self.K, sp.csr_matrix) else sp.csr_matrix(self.K)
        return abs_row_sums(K.indptr, K.data, K.shape[0])

    @cached_property
    def K_norm(self) -> float:
        """``|K|``, the largest absolute row sum of K (max norm), for backward errors."""
        return float(self.K_row_sums.max())

    @cached_property
    def abs_force_operators(
        self,
    ) -> tuple[sp.csr_matrix, sp.csr_matrix, NDArray[np.float64], NDArray[np.float64]]:
        """What :meth:`operator_norms` needs: ``|N^T|`` and ``|Tau^T|`` on the rows
        :attr:`contact_cols`, the absolute row sums of ``N``, and those of K on the rows
        :attr:`contact_cols`. The absolute row sums of the soft layer's tangent
        ``N^T W P' N + Tau^T W Fric P' N`` are at most
        ``|N^T| (w p' |N| 1) + |Tau^T| (w |fric| p' |N| 1)``."""
        NT, TT = self.force_operators
        nu_sum = np.asarray(abs(self.N_contact).sum(axis=1)).ravel()
        return abs(NT).tocsr(), abs(TT).tocsr(), nu_sum, self.K_row_sums[self.contact_cols]

    def operator_norms(self, dP: NDArray, fric: NDArray) -> NDArray[np.float64]:
        """``| |K| + |J_soft| |`` (max norm) at each of k levels: the norm of the
        operator ``u -> K u + force(u)`` linearized where the law's slopes are ``dP``
        (m, k), with friction coefficients ``fric`` (m, k), J_soft the soft layer's
        tangent ``N^T W P' N + Tau^T W Fric P' N``. It is ``|K|`` where no node
        penetrates."""
        if not np.any(dP):
            return np.full(dP.shape[1], self.K_norm)
        aNT, aTT, nu_sum, K_rows = self.abs_force_operators
        t = (self.weights * nu_sum)[:, None] * dP
        rows = aNT @ t + aTT @ (np.abs(fric) * self.tile_rows(t))
        rows += K_rows[:, None]
        return np.maximum(rows.max(axis=0), self.K_norm)

    @property
    def n_free(self) -> int:
        return self.K.shape[0]

    def layer_forces(self, p_rigid: NDArray | float, p_soft: NDArray, fric: NDArray) -> NDArray:
        """Nodal forces of the rigid and the soft layer,
        ``N^T(weights (p_soft + p_rigid)) + Tau^T(weights fric q)``, q the pressure
        friction acts on (:meth:`friction_pressure`)."""
        q = self.friction_pressure(p_soft, p_rigid)
        NT, TT = self.transposes
        return NT @ (self.weights * (p_soft + p_rigid)) + TT @ self.friction_weights(fric, q)

    def contact_force(self, u: NDArray, p_rigid: NDArray, fric: NDArray, w: NDArray):
        """The contact term of the residual and the soft-layer pressure at ``u``."""
        p_soft = self.p(self.N @ u - w)
        return self.layer_forces(p_rigid, p_soft, fric), p_soft


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
    p_rigid: NDArray[np.float64]
    p_soft: NDArray[np.float64]
    iterations: int
    residuals: dict[str, float]
    forces: NDArray[np.float64] | None = None


def _residuals(
    system: ContactSystem, y: NDArray, p_rigid: NDArray, equilibrium: float, p_ref: float
) -> dict[str, float]:
    """The three residuals, given the scaled equilibrium residual and the pressure scale
    (:func:`_residuals_block` of one column)."""
    return _residuals_block(
        system, y[:, None], p_rigid[:, None], np.array([equilibrium]), np.array([p_ref])
    )[0]


def kkt_residuals(
    system: ContactSystem, step: StepData, u: NDArray, p_rigid: NDArray
) -> dict[str, float]:
    """Scaled KKT residuals of a candidate solution (all dimensionless, max norms).

    ``equilibrium``: residual of the equation over the largest force in it;
    ``feasibility``: largest violation of ``N u <= g`` over max g;
    ``complementarity``: ``max |min(p_rigid / p_ref, (g - N u) / g_ref)|`` (it is zero
    exactly when p_rigid >= 0, N u <= g and p_rigid (N u - g) = 0).
    """
    force, p_soft = system.contact_force(u, p_rigid, step.fric, step.w)
    Ku = system.K @ u
    r = Ku - step.F + force
    tiny = _TINY
    fscale = max(
        np.abs(step.F).max(initial=0), np.abs(Ku).max(initial=0), np.abs(force).max(initial=0), tiny
    )
    p_ref = max(float(np.abs(p_rigid).max(initial=0)), float(np.abs(p_soft).max(initial=0)), tiny)
    return _residuals(system, system.N @ u, p_rigid, np.abs(r).max(initial=0) / fscale, p_ref)


def _by_load(steps: list[StepData], Z: NDArray) -> list[tuple[NDArray, NDArray]]:
    """``sum_j F_j Z[j]`` as pairs (F, summed rows of Z): levels that share one load
    vector (constant loads share the object) cost one outer product. The rows of a
    group are summed in level order (a sum over the first axis adds row after row)."""
    groups: dict[int, list[int]] = {}
    for j, st in enumerate(steps):
        groups.setdefault(id(st.F), []).append(j)
    return [(steps[rows[0]].F, Z[rows].sum(axis=0)) for rows in groups.values()]


def _by_level(f: Callable[[NDArray], NDArray], R: NDArray, elementwise: bool) -> NDArray:
    """``f`` (the law or its slope) of the penetrations ``R`` (k, m) of k levels, as
    (m, k): on all rows at once when the law is elementwise, else row by row, as
    :func:`kkt_residuals` applies it to one level."""
    return f(R).T if elementwise else np.column_stack([f(r) for r in R])


#: Random combinations of a block's levels in :func:`kkt_residuals_block`.
PROBES = 3


def kkt_residuals_block(
    system: ContactSystem,
    steps: list[StepData],
    X: NDArray,
    p_rigids: list[NDArray],
    y_refs: NDArray | None = None,
    tol: float | None = None,
) -> list[dict[str, float]]:
    """:func:`kkt_residuals` of several levels at once, ``X`` (n_free, k) their
    displacements; feasibility and complementarity over ``y_refs`` (k,), the scales of
    their normal displacements, instead of max g when given (the condensed solver gives
    ``max(max g, max |d|)``, d the normal displacement of the load alone:
    :meth:`~vemwear.solvers.newton.CondensedNewton.displacement_scales`).

    Feasibility and complementarity are exact, level by level (they need only ``N X``).
    The recovery is a direct solve with the contact forces known, so its equilibrium
    residual is measured as a normwise backward error: ``|r|`` over
    ``max(|F|, |force|, |J| x_ref)`` (max norms), which does not grow with the
    condition number of K as the force-scaled residual of :func:`kkt_residuals` does (at
    h = 1/512 that one reaches 1e-10 on a backward-stable solve). ``|J|`` is the norm of
    the operator ``u -> K u + force(u)`` at the level
    (:meth:`ContactSystem.operator_norms`: ``|K|`` plus the soft layer's tangent, the
    larger part for a stiff layer, whose slope turns the rounding of y into forces) and
    ``x_ref = max(max |x|, y_ref)``: the displacement a residual stands for is measured
    on the scale of the normal displacements, as feasibility is (the recovery's forces
    come from Newton's y, which carries rounding on that scale). The residuals
    ``E = K X - F + force`` are not formed column by column
    (k products with K): for k > :data:`PROBES` they are checked on ``PROBES`` random
    combinations of the columns (Freivalds' check), ``E Z`` with Gaussian ``Z`` (k,
    PROBES), whose columns are scaled by each level's force scale. Every entry of ``E Z``
    is a Gaussian of standard deviation ``|E_i,:|_2 >= max_j |E_ij|``, so the estimate
    ``max |E Z|`` is below 1/100 of the largest scaled residual of the block with
    probability below ``0.008^PROBES = 5e-7``, and above it by at most ``|Z_:,i|_1``. The
    estimate is the equilibrium residual of every level of the block; where it is above
    ``tol`` (when given), the residuals are computed level by level instead (k products
    with K), so that no level fails on an estimate. ``Z`` is seeded by the first level,
    so that a resumed run gives the same numbers.
    """
    k = len(steps)
    m = system.m
    dofs = system.contact_cols
    NX = system.N_contact @ X[dofs]
    P_rigid = np.column_stack(p_rigids)
    # the penetrations level by level, (k, m): the law acts on each contiguous row as
    # kkt_residuals applies it (or on all at once when it is elementwise)
    R = np.empty((k, m))
    np.subtract(NX.T, np.array([st.w for st in steps]), out=R)
    P_soft = _by_level(system.p, R, system.p.elementwise)
    fric = np.column_stack([st.fric for st in steps])
    w = system.weights[:, None]
    # the contact forces live on the contact dofs: N^T a + Tau^T b restricted to them
    NT, TT = system.force_operators
    Q = system.friction_pressure(P_soft, P_rigid)
    force = NT @ (w * (P_soft + P_rigid)) + TT @ system.friction_weights(fric, Q)
    # column maxima: the same numbers as level by level (max is exact); the load's
    # once per load vector (a constant load: one object)
    F_max: dict[int, float] = {}
    for st in steps:
        if id(st.F) not in F_max:
            F_max[id(st.F)] = float(np.abs(st.F).max(initial=0))
    x_ref = np.maximum(X.max(axis=0), -X.min(axis=0))  # max |X|, no temporary
    if y_refs is not None:
        x_ref = np.maximum(x_ref, y_refs)
    scale = np.maximum(
        np.maximum([F_max[id(st.F)] for st in steps], np.abs(force).max(axis=0, initial=0)),
        system.operator_norms(_by_level(system.p.derivative, R, system.p.elementwise), fric)
        * x_ref,
    )
    scale = np.maximum(scale, _TINY)

    def combined(Z: NDArray) -> NDArray:
        """``max |E Z|`` of each column of ``Z`` (k, j)."""
        E = system.K @ (X @ Z)
        for F, coef in _by_load(steps, Z):
            E -= np.multiply.outer(F, coef)
        E[dofs] += force @ Z
        return np.abs(E.T, order="C").max(axis=1)  # contiguous rows: a fast reduction

    if k <= PROBES:
        equilibrium = combined(np.diag(1.0 / scale))  # level by level
    else:
        Z = np.random.default_rng(steps[0].level).standard_normal((k, PROBES))
        equilibrium = np.full(k, combined(Z / scale[:, None]).max())
        if tol is not None and equilibrium[0] > tol:  # an estimate can be |Z_:,i|_1 too
            equilibrium = combined(np.diag(1.0 / scale))  # large: level by level
    p_ref = np.maximum(
        np.maximum(np.abs(P_rigid).max(axis=0, initial=0), np.abs(P_soft).max(axis=0, initial=0)),
        _TINY,
    )
    return _residuals_block(system, NX, P_rigid, equilibrium, p_ref, y_refs)


def _residuals_block(
    system: ContactSystem,
    Y: NDArray,
    P_rigid: NDArray,
    equilibrium: NDArray,
    p_ref: NDArray,
    y_ref: NDArray | None = None,
) -> list[dict[str, float]]:
    """:func:`_residuals` of the columns of ``Y = N X`` and ``P_rigid``, bitwise the same
    (elementwise operations and maxima over each column); ``y_ref`` (k,), the scales of
    the normal displacements, max g unless given."""
    g = system.g[:, None]
    g_ref: Any = max(float(np.abs(system.g).max()), _TINY) if y_ref is None else y_ref
    ncp = np.minimum(P_rigid / p_ref, (g - Y) / g_ref)
    feasibility = np.fmax(0.0, (Y - g).max(axis=0, initial=0)) / g_ref  # fmax: as max(0.0, x)
    complementarity = np.abs(ncp).max(axis=0, initial=0)
    return [
        dict(zip(RESIDUAL_NAMES, values, strict=True))
        for values in zip(
            equilibrium.tolist(), feasibility.tolist(), complementarity.tolist(), strict=True
        )
    ]


#: Newton steps in a row on one piece after which an iteration stops
#: (:func:`at_rounding_floor`).
_STALL = 4


def at_rounding_floor(same: int, within_tol: bool) -> bool:
    """Whether a semismooth Newton iteration stops at the rounding floor of its residual.

    ``same`` counts the steps in a row taken on one piece (active set and slopes): the
    iterate after the first such step solves the piece's linear system and a second one
    refines it; past that only rounding changes. So an iterate within tol after two such
    steps is final, and one above it after :data:`_STALL` steps will not get there (a
    residual floor above the stopping threshold: a load that moves the body 1e5 times g,
    or a very stiff layer). Both Newton solvers stop by this rule (docs/method.md).
    """
    return (same >= 2 and within_tol) or same >= _STALL


def condensed_residuals(
    system: ContactSystem, y: NDArray, p_rigid: NDArray, R: NDArray
) -> dict[str, float]:
    """The residuals of the condensed equations ``R(y, p_rigid) = 0`` (R in displacement
    units, scaled by max g) with the complementarity conditions on y = N u."""
    tiny = _TINY
    g_ref = max(float(np.abs(system.g).max()), tiny)
    p_ref = max(float(np.abs(p_rigid).max(initial=0)), tiny)
    return _residuals(system, y, p_rigid, np.abs(R).max(initial=0) / g_ref, p_ref)


def check_converged(
    residuals: dict[str, float],
    tol: float,
    step: StepData,
    method: str,
    iterations: int,
    why: Callable[[], str] | None = None,
) -> None:
    """Raise :class:`ConvergenceError` naming the time level when a residual is above tol;
    ``why()``, called only then, adds what the solver knows of the cause (or "")."""
    if all(0.0 <= v <= tol for v in residuals.values()):  # the usual case, at once
        return
    bad = [k for k, v in residuals.items() if not np.isfinite(v)]
    if bad:
        raise ConvergenceError(
            f"{method}: non-finite values at time level {step.level} (t = {step.t:.6g}): the "
            f"{bad[0]} residual is {residuals[bad[0]]}; the data overflow (check the scale of "
            "the loads, the material and the contact data)"
        )
    worst = max(residuals, key=lambda k: residuals[k])
    if not residuals[worst] <= tol:
        raise ConvergenceError(
            f"{method} did not converge at time level {step.level} (t = {step.t:.6g}) after "
            f"{iterations} iterations: {worst} residual {residuals[worst]:.3e} > tol {tol:.1e}"
            + (why() if why is not None else "")
        )
