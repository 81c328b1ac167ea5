"""The assembled discrete problem: what the time loop needs at every level.

:class:`Discretization` holds the stiffness on the free dofs, the lifting of prescribed
displacements, the contact operators of all contact parts, and gives at each level the
data of the step problem (3.21): the load, the friction direction and the wear rate
from the tangential foundation velocity, and the shift of the contact unknowns by the
initial gap (docs/method.md, sections 3b and 4). The element level comes in through the
problem's space (:mod:`vemwear.vem.space`), so nothing here depends on the order k.
"""

from __future__ import annotations

import dataclasses
import functools
import time
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..contact import (
    ContactBoundary,
    ContactPart,
    nodal_velocity,
    tangential_components,
    tangential_velocity,
    velocity_levels,
)
from ..solvers.protocol import StepSolver
from ..solvers.system import ContactSystem, StepData, StepSolution
from .blocks import DataError, cell_assembly, stiffness_blocks, whole_stiffness
from .constraints import describe_motions
from .wear import wear_rate, wear_update

if TYPE_CHECKING:
    from .problem import Problem

__all__ = ["DataError", "Discretization"]


#: Tangential foundation velocities within this multiple of the largest ``|v*|`` of the
#: time grid are zero (64 units in the last place: round-off of the data's expressions).
VELOCITY_ROUNDOFF = 64 * float(np.finfo(np.float64).eps)


@dataclasses.dataclass(frozen=True)
class _Sliding:
    """The tangential foundation velocity at one time and what the step data take from
    it: the friction coefficients ``mu n* . tau_a`` and the wear rate ``alpha``."""

    t: float
    v: NDArray[np.float64]
    fric: NDArray[np.float64]
    alpha: NDArray[np.float64]


@dataclasses.dataclass
class _Resultants:
    """The force resultants as an affine map of the layer forces (:meth:`Discretization.
    resultants`): ``A @ [W (p_soft + p_rigid); W fric p_soft] + b``, flattened rows
    (part, component); ``b`` holds the reactions to the load and the prescribed values,
    ``b_F`` the load vector it was computed for."""

    A: NDArray[np.float64]
    ZT: NDArray[np.float64] | None = None
    ET: NDArray[np.float64] | None = None
    b: NDArray[np.float64] | None = None
    b_F: Any = None


class Discretization:
    """Everything the time loop needs: K on free dofs, contact operators, nodal data.

    The contact unknowns of the solvers are ``y = N_f u_f``, the normal displacement
    from the free dofs. The normal displacement is ``u_nu = y + offset``, where
    ``offset`` comes from prescribed components at contact nodes, and the step problem
    is solved with ``w + shift`` in place of ``w`` and the bound ``g + shift``, where
    ``shift = gap - offset``: so the penetration is ``u_nu - gap - w`` and the
    constraint ``u_nu - gap <= g`` (with no gap and no prescribed contact component,
    ``shift`` is zero and the data are the paper's, bitwise).

    With ``distributed`` (an MPI run of the petsc backend, docs/mpi.md) K is kept by the
    ranks and ``system.K`` is rank 0's operator of it; this process assembles only the
    cells along the contact and the constrained dofs.
    """

    def __init__(self, problem: Problem, distributed: bool = False) -> None:
        tick = time.perf_counter()
        mesh = problem.mesh
        self.problem = problem
        self.contact: ContactBoundary = problem.contact
        cb = self.contact
        self.g, self.mu, self.kappa = (problem.nodal[k] for k in ("g", "mu", "kappa"))
        self.gap = problem.nodal["gap"]
        self.constraints = con = problem.constraints
        self.free = con.free
        self.space = space = problem.space
        assembly = cell_assembly(problem)
        #: whether K is kept by the ranks of the MPI job (docs/mpi.md): asked for, and
        #: not under load control, whose anchored K is made from the whole matrix
        self.distributed = distributed and not len(problem.rigid_basis)
        blocks = stiffness_blocks(problem, assembly if self.distributed else None)
        K = blocks.K
        # the coupling of the free and the constrained dofs: the lifting of prescribed
        # values, K_fc u_c(t) (none if all are zero), and the reactions, K_cc u_c(t)
        self._K_fc, self._K_cc = blocks.K_fc, blocks.K_cc
        self.K_fc = None if con.zero else self._K_fc
        del blocks
        trace = None
        #: the dimension d: dof i of the vertex values is component i % d
        self.dim = dim = int(space.dim)
        if cb.trace is None:  # k = 1: the d dofs of each contact vertex
            index = -np.ones(self.n_dof, dtype=np.int64)
            index[self.free] = np.arange(len(self.free))
            cdofs = index[dim * cb.nodes[:, None] + np.arange(dim)]
            self.offset = self._contact_offset(cdofs)
            dof_points = mesh.points[self.free // dim]
        else:  # the trace operator on the free dofs; prescribed dofs give the offset
            cdofs = None
            trace = sp.csr_matrix(cb.trace[:, self.free])
            self.offset = self._contact_offset_trace()
            dof_points = space.dof_points[self.free]
        shift = self.gap - self.offset
        self.shift = shift if np.any(shift != 0.0) else None
        # load control: the rigid motions that only contact holds (docs/method.md 1c)
        basis = problem.rigid_basis
        rigid = con.rigid_modes(basis)[self.free] if len(basis) else None
        parts = problem.parts
        on = [pc.friction_on == "total" for pc in parts]
        self.system = ContactSystem(
            K=K,
            contact_dofs=cdofs,
            normals=cb.normals,
            tangents=cb.friction_tangents,
            weights=cb.weights,
            g=self.g if self.shift is None else self.g + self.shift,
            p=problem.law,
            dof_points=dof_points,
            trace=trace,
            rigid=rigid,
            rigid_names=tuple(describe_motions(mesh, basis)) if rigid is not None else (),
            contact_names=tuple(cb.part_names),
            friction_total=np.array(on)[cb.part] if any(on) else None,
            assembly=assembly,
        )
        wear = [pc.wear_on == "total" for pc in parts]
        #: the nodes whose wear rate takes the whole contact pressure (``wear_on =
        #: "total"``), None if there are none: the soft layer wears, the rigid one not
        self.wear_total = np.array(wear)[cb.part] if any(wear) else None
        #: whether the load F of the step problems is the same at all times (then
        #: :meth:`load` gives one array object)
        self.constant_load = not (
            callable(problem.f1)
            or any(callable(f) for f in problem.tractions.values())
            or con.time_dependent
        )
        self._F0: NDArray | None = None
        self._F_all: NDArray | None = None
        self._solvers: dict[Any, Any] = {}
        self._resultants: _Resultants | None = None
        self._sliding_at: _Sliding | None = None
        self._sliding_prev: _Sliding | None = None
        #: wall seconds of the phases done on this discretization and not yet reported
        #: by a run: ``assembly`` (this constructor), ``setup`` (a step solver's
        #: factorization), ``smallness`` (:meth:`smallness_estimate`); the first run
        #: reports them (:meth:`take_timings`), also when a diagnostic asked for them
        #: before it, and a later run that reuses them spends none
        self.timings: dict[str, float] = {"assembly": time.perf_counter() - tick}

    @functools.cached_property
    def K_full(self) -> sp.csr_matrix:
        """The stiffness on all dofs (free and constrained), assembled again when asked:
        a run keeps only the blocks it uses (``system.K``, ``K_fc``, ``K_cc``)."""
        return whole_stiffness(self.problem)

    def take_timings(self) -> dict[str, float]:
        """The phases of :attr:`timings` spent since the last call (then forgotten)."""
        out, self.timings = self.timings, {}
        return out

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
            d = self.dim
            for c in range(d):
                fixed = cdofs[:, c] < 0
                o[fixed] += cb.normals[fixed, c] * u[pos[d * cb.nodes[fixed] + c]]
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

    def _contact_offset_trace(self) -> NDArray[np.float64]:
        """As :meth:`_contact_offset`, with the trace operator: ``N_c u_c``."""
        con, cb = self.constraints, self.contact
        if con.zero:
            return np.zeros(cb.m)
        Nc = cb.N[:, con.dofs].tocsr()
        if Nc.nnz == 0:
            return np.zeros(cb.m)
        t = self.problem.time.t
        off = np.asarray(Nc @ con.values(float(t[0])), dtype=np.float64)
        if con.time_dependent:
            for time in np.linspace(float(t[0]), float(t[-1]), 17)[1:]:
                if not np.allclose(Nc @ con.values(float(time)), off, rtol=0, atol=1e-14):
                    raise ValueError(
                        "a prescribed displacement that changes in time moves contact nodes "
                        "along their normal; the normal displacement of a contact node is an "
                        "unknown of the contact problem: prescribe it on other parts"
                    )
        return off

    def step_solver(self, opts: Any) -> StepSolver:
        """The step solver of ``opts`` on this system, built once (one factorization of
        K however many runs use it, e.g. the cycles of a cycle jump)."""
        if opts not in self._solvers:
            tick = time.perf_counter()
            self._solvers[opts] = opts.build(self.system)
            self.timings["setup"] = self.timings.get("setup", 0.0) + time.perf_counter() - tick
        return self._solvers[opts]

    def release_solvers(self) -> None:
        """Drop the step solvers built so far, with their factorizations (at 1/512 the
        factors take more memory than the rest of the run); a later run builds them
        again."""
        self._solvers.clear()

    @property
    def n_dof(self) -> int:
        return int(self.space.n_dofs)

    def load(self, t: float) -> NDArray[np.float64]:
        """``f_h(t) - K_fc u_c(t)`` on the free dofs (body force by 3.3, tractions by
        edge quadrature, the lifting of prescribed displacements)."""
        if self.constant_load and self._F0 is not None:
            return self._F0
        F = self._external_load(t)[self.free]
        if self.K_fc is not None:
            F = F - self.K_fc @ self.constraints.values(t)
        if not np.all(np.isfinite(F)):
            raise DataError(
                f"[loads] f1, f2 give a load vector with non-finite entries at t = {t:g} (an "
                "overflow); use loads of a sensible scale"
            )
        if self.constant_load:
            self._F0 = F
        return F

    def tangential_velocity(self, t: float) -> NDArray[np.float64]:
        """``v*(t) . tau_a`` at every contact node (each part's own v*); the last time's
        values are kept (step data and wear rate ask for the same t), and the first
        ones for good when every v* is a constant vector.

        Values within round-off of zero are zero: a v* that vanishes at a level (the
        zeros of ``cos(2 pi t)`` evaluate to about 1e-16) gives no friction and no wear
        there (docs/method.md, section 3b), not the full friction of a round-off sign.
        Round-off is :data:`VELOCITY_ROUNDOFF` times the largest ``|v*|`` of the time
        grid.
        """
        return self._sliding(t).v

    def _sliding(self, t: float) -> _Sliding:
        """:meth:`tangential_velocity` with the friction coefficients and wear rate."""
        s = self._sliding_at
        if s is not None and s.t != t and not self.steady_sliding:
            # the loop asks for alpha(t_n) and the friction of t_{n+1} in turn: the two
            # last times are kept
            prev = self._sliding_prev
            self._sliding_prev = s
            if prev is not None and prev.t == t:
                self._sliding_at = prev
                return prev
        if s is None or (s.t != t and not self.steady_sliding):
            cb = self.contact
            if cb.tangents2 is not None:
                s = self._turning(t)
            else:
                v = tangential_velocity(self.problem.parts, cb.part, cb.tangents, t, cb.points)
                v[np.abs(v) <= self._velocity_roundoff] = 0.0
                # n* . tau_a = -sign(v*_tau . tau_a): friction opposes the tangential
                # sliding, and vanishes where the foundation does not slide along the
                # boundary
                s = _Sliding(t, v, self.mu * -np.sign(v), wear_rate(self.kappa, np.abs(v)))
            self._sliding_at = s
        return s

    def _turning(self, t: float) -> _Sliding:
        """The sliding data with two friction rows (3D, v* turns): ``v`` holds ``v* .
        tau_1`` then ``v* . tau_2`` (2m,), ``fric`` the coefficients ``mu n* . tau_k =
        -mu (v* . tau_k) / |v*_tau|`` of the rows, ``alpha = kappa |v*_tau|``."""
        cb = self.contact
        V = nodal_velocity(self.problem.parts, cb.part, cb.points, t)
        v1 = tangential_components(V, cb.tangents)
        v2 = tangential_components(V, cast(NDArray[np.float64], cb.tangents2))
        speed = np.hypot(v1, v2)
        still = speed <= self._velocity_roundoff
        v = np.concatenate([np.where(still, 0.0, v1), np.where(still, 0.0, v2)])
        unit = np.where(still, 0.0, 1.0 / np.where(still, 1.0, speed))
        fric = np.concatenate([self.mu * -v1 * unit, self.mu * -v2 * unit])
        return _Sliding(t, v, fric, wear_rate(self.kappa, np.where(still, 0.0, speed)))

    @functools.cached_property
    def steady_sliding(self) -> bool:
        """Whether every part's v* is a constant vector: then v*_tau and what follows
        from it are the same at every time."""
        return all(pc.velocity.steady for pc in self.problem.parts)

    @functools.cached_property
    def _velocity_roundoff(self) -> float:
        t = np.asarray(self.problem.time.t, dtype=np.float64)
        cb = self.contact
        scale = max(
            (
                float(np.abs(velocity_levels(pc.velocity, t)).max(initial=0.0))
                if not pc.velocity.spatial
                else _field_scale(pc, cb.points[cb.part == i], t)
                for i, pc in enumerate(self.problem.parts)
            ),
            default=0.0,
        )
        return VELOCITY_ROUNDOFF * scale

    def step_data(self, level: int, w: NDArray[np.float64]) -> StepData:
        """The step problem of a level with the wear ``w`` (= w^n)."""
        t = float(self.problem.time.t[level])
        return StepData(
            F=self.load(t), w=self.step_wear(w), fric=self.friction(t), t=t, level=level
        )

    def step_wear(self, w: NDArray[np.float64]) -> NDArray[np.float64]:
        """The wear of the step problem, ``w + shift`` (``w`` itself without a shift)."""
        return w if self.shift is None else w + self.shift

    def friction(self, t: float) -> NDArray[np.float64]:
        """``mu n*.tau`` at the contact nodes at time t (the step data's ``fric``)."""
        return self._sliding(t).fric

    def alpha(self, t: float) -> NDArray[np.float64]:
        """``alpha(t) = kappa |v*_tau(t)|`` at the contact nodes (2.2 for any Gamma_C)."""
        return self._sliding(t).alpha

    def wear_pressure(
        self, p_soft: NDArray[np.float64], p_rigid: NDArray[np.float64] | None
    ) -> Any:
        """The pressure of the wear rate (3.22): ``p_soft`` (the paper's; the rigid layer
        does not wear), plus ``p_rigid`` at the nodes of ``wear_on = "total"`` (then
        ``p_rigid`` must be given)."""
        if self.wear_total is None:
            return p_soft
        if p_rigid is None:
            raise ValueError("the wear of wear_on = 'total' needs the rigid-layer pressure")
        return p_soft + np.where(self.wear_total, p_rigid, 0.0)

    def next_wear(
        self,
        level: int,
        w: NDArray[np.float64],
        p_soft: NDArray[np.float64],
        p_rigid: NDArray[np.float64] | None,
    ) -> Any:
        """``w^{n+1}`` from the wear and the pressures of level ``n = level`` (3.22):
        :func:`~vemwear.simulate.wear.wear_update` with ``alpha(t_n)`` and
        :meth:`wear_pressure`."""
        t = self._times
        return wear_update(
            w, t[level + 1] - t[level], self.alpha(t[level]), self.wear_pressure(p_soft, p_rigid)
        )

    @functools.cached_property
    def _times(self) -> list[float]:
        """The time levels as Python floats (read at every level; the same doubles)."""
        return cast(list[float], self.problem.time.t.tolist())

    @property
    def force_parts(self) -> tuple[tuple[str, str], ...]:
        """``(part, kind)`` of the rows of :meth:`resultants`: every contact part
        (``"contact"``), then every clamped and prescribed part (``"reaction"``)."""
        cb, con = self.contact, self.constraints
        kinds = ["reaction"] * (len(con.parts) - len(con.rigid)) + ["rigid"] * len(con.rigid)
        return (
            *((n, "contact") for n in cb.part_names),
            *zip(con.parts, kinds, strict=True),
        )

    def resultants(self, step: StepData, solution: StepSolution, solver: Any) -> NDArray:
        """(P, d) force resultants on the body at a level (rows :attr:`force_parts`):
        the force of each contact part's layer, ``-sum_a omega_a [(p_soft + p_rigid)
        nu_a + fric_a p_soft tau_a]``, and the reaction of each clamped or prescribed
        part, ``(K u - f_h)`` summed over its constrained dofs (the contact forces on
        prescribed components of contact nodes included). The reactions come from the
        condensed data, without recovering u: ``K_cf u_f = Z^T (F - forces_f)`` with
        ``Z = K_ff^{-1} K_fc E`` computed once. All rows are one affine map of the layer
        forces, built once (:meth:`_resultant_map`): a level costs one (d P, 2m) product."""
        return self.resultants_run([step], [solution], solver)[0]

    def resultants_run(
        self, steps: Sequence[StepData], solutions: Sequence[StepSolution], solver: Any
    ) -> list[NDArray]:
        """:meth:`resultants` of several levels: their layer forces in one pass, then
        the product of each level (the same numbers as level by level)."""
        op = self._resultant_map(solver)
        m, w, r = self.contact.m, self.contact.weights, self.system.rows
        P_soft = np.array([sol.p_soft for sol in solutions])
        P_rigid = np.array([sol.p_rigid for sol in solutions])
        X = np.empty((len(steps), (1 + r) * m))
        np.add(P_soft, P_rigid, out=X[:, :m])
        X[:, :m] *= w
        # the friction of the step problem: on p_soft, or on the whole pressure
        Q = self.system.friction_pressure(P_soft.T, P_rigid.T).T
        fric = np.array([st.fric for st in steps])
        for k in range(r):
            rows = slice((1 + k) * m, (2 + k) * m)
            np.multiply(fric[:, k * m : (k + 1) * m], Q, out=X[:, rows])
            X[:, rows] *= w
        out = []
        for j, step in enumerate(steps):
            # one product a level: its forces do not depend on the run it came in
            f = op.A @ X[j]
            if op.ZT is not None and op.ET is not None:
                f += self._static_reactions(op, op.ZT, op.ET, step)
            f = f.reshape(-1, self.dim)
            if self.constraints.ties is not None:  # the force on a loaded component
                f[len(f) - len(self.constraints.rigid) :] += self.constraints.ties.forces(
                    step.t, self.dim
                )
            out.append(f)
        return out

    def _static_reactions(
        self, op: _Resultants, ZT: NDArray, ET: NDArray, step: StepData
    ) -> NDArray:
        """The reactions' part that the layer forces leave, computed once per load."""
        if op.b is None or step.F is not op.b_F or not self.constant_load:
            con = self.constraints
            static = -self._external_load(step.t)[con.dofs]
            if not con.zero:  # K_cc u_c of the prescribed values
                static = static + np.asarray(self._K_cc @ con.values(step.t))
            b = np.zeros(len(op.A))
            b[len(op.A) - len(ZT) :] = ZT @ step.F + ET @ static
            op.b, op.b_F = b, step.F
        return op.b

    def _resultant_map(self, solver: Any) -> _Resultants:
        """The affine map of :meth:`resultants`, built once. Its rows: each contact
        part's ``-sum_a`` over its nodes of ``nu_a`` and ``tau_a`` times the two layer
        forces; each constrained part's ``-Z^T (N^T, Tau^T)`` plus ``E^T`` of the layer
        forces on constrained components (``E``: the 0/1 matrix of (part, component)
        of each constrained dof)."""
        if self._resultants is not None:
            return self._resultants
        cb, con, d = self.contact, self.constraints, self.dim
        m, P, r = cb.m, len(cb.part_names), self.system.rows
        tangents = cb.friction_tangents.reshape(r, m, d)
        # contact parts: rows (part, component), columns (normal force, friction rows)
        A_c = np.zeros((P, d, 1 + r, m))
        for c in range(d):
            A_c[cb.part, c, 0, np.arange(m)] = -cb.normals[:, c]
            for k in range(r):
                A_c[cb.part, c, 1 + k, np.arange(m)] = -tangents[k, :, c]
        A = A_c.reshape(P * d, (1 + r) * m)
        op = _Resultants(A=A)
        if con.parts:
            s = self.system
            cols = con.owner * d + con.dofs % d  # (part, component) of each constrained dof
            ET = np.zeros((d * len(con.parts), len(con.dofs)))
            ET[cols, np.arange(len(con.dofs))] = 1.0
            B = self._K_fc @ ET.T  # K_fc E: sparse times a thin dense block
            factor = getattr(solver, "factor", None)
            if factor is not None:
                Z = factor.solve(B)
            elif s.rigid is not None:  # G of the anchored K (docs/method.md 1c)
                from ..solvers.rigid import anchored_factor, rigid_modes

                Z = anchored_factor(s, rigid_modes(s, s.contact_cols), "auto").solve(B)
            elif not self.distributed:
                import scipy.sparse.linalg as spla

                Z = spla.splu(cast(sp.csr_matrix, s.K).tocsc()).solve(B)
            else:
                raise ValueError(
                    "resultants: K is kept by the MPI ranks; give the step solver whose "
                    "factorization solves with it (the condensed Newton's)"
                )
            ZT = np.ascontiguousarray(np.asarray(Z).reshape(len(self.free), -1).T)
            A_r = -np.hstack([np.asarray(s.N @ ZT.T).T, np.asarray(s.Tau @ ZT.T).T])
            # the layer forces on constrained components (usually none: told by the
            # operators' column indices without slicing)
            on = np.zeros(self.n_dof, dtype=bool)
            on[con.dofs] = True
            N, Tau = cb.N, cb.Tau
            if on[N.indices].any() or on[Tau.indices].any():
                A_r[:, :m] += (N[:, con.dofs] @ ET.T).T
                A_r[:, m:] += (Tau[:, con.dofs] @ ET.T).T
            op.A, op.ZT, op.ET = np.vstack([A, A_r]), ZT, ET
        self._resultants = op
        return op

    def _external_load(self, t: float) -> NDArray[np.float64]:
        """``f_h(t)`` on all dofs (body force and tractions), assembled once for a
        constant load (the free and the constrained dofs share it)."""
        if self._F_all is not None:
            return self._F_all
        with np.errstate(all="ignore"):
            F = self.problem.external_load(t)
        ties = self.constraints.ties
        if ties is not None:  # Q^T f_h and the rigid parts' resultants on their masters
            F = ties.load(F, t)
        if self.constant_load:
            self._F_all = F
        return F

    def physical(
        self, solution: StepSolution, step: StepData | None = None, solver: Any = None
    ) -> StepSolution:
        """The solution with its true normal displacement ``u_nu = y + offset`` and, with
        ``step`` and ``solver``, its force resultants (:meth:`resultants`). The forces
        are set on ``solution`` itself; a new solution carries the shifted ``u_nu``, so
        that ``solution`` stays the solver's warm start (y, not u_nu)."""
        if step is not None:
            solution.forces = self.resultants(step, solution, solver)
        if self._offset_nonzero:
            return dataclasses.replace(solution, u_nu=solution.u_nu + self.offset)
        return solution

    @functools.cached_property
    def _offset_nonzero(self) -> bool:
        return bool(np.any(self.offset))

    def full_dofs(self, u_free: NDArray[np.float64], t: float | None = None) -> NDArray:
        """All dofs of the displacement: ``u_free`` on the free dofs, the prescribed
        values at time ``t`` on the others (zero on clamped parts)."""
        if t is None and not self.constraints.zero:
            raise ValueError("full_displacement: the time is needed for prescribed values")
        return self.full_dofs_block(np.asarray(u_free)[:, None], [t])[0]

    def full_dofs_block(
        self,
        X: NDArray[np.float64],
        times: Sequence[float | None],
        out: NDArray[np.float64] | None = None,
    ) -> NDArray:
        """:meth:`full_dofs` of the columns of ``X`` (n_free, k) at their ``times``, as
        the rows of a (k, n_dofs) array (``out`` when given): one pass for a block."""
        con = self.constraints
        U = np.empty((X.shape[1], self.n_dof)) if out is None else out
        U[:, self.free] = X.T
        if con.zero:
            U[:, con.dofs] = 0.0
        else:
            for j, t in enumerate(times):
                U[j, con.dofs] = con.values(cast(float, t))
        if con.ties is not None:  # u = Q u_hat: the tied dofs move with their masters
            con.ties.expand(U)
        return U

    def full_displacement(
        self, u_free: NDArray[np.float64], t: float | None = None
    ) -> NDArray[np.float64]:
        """(n_points, d) displacement at the vertices (the vertex dofs of
        :meth:`full_dofs`; all dofs for k = 1)."""
        return self.space.vertex_values(self.full_dofs(u_free, t))

    def smallness_estimate(self, solver: Any = None) -> dict[str, float]:
        """Estimate of the smallness condition of Theorem 3.4, ``c_0^2 L_p ||mu|| < C_1``.

        ``c_0^2 / C_1`` is the largest generalized eigenvalue of
        ``||v||^2_{L^2(Gamma_C)}`` (nodal quadrature, normal and tangential) against
        ``a_h(v, v)`` on the free dofs; the condition reads ``L_p ||mu||_inf (c_0^2 /
        C_1) < 1``. With ``B = [N; Tau]`` and the weights ``W`` that eigenvalue is the
        largest one of ``W^(1/2) B K^{-1} B^T W^(1/2)``, in which ``B K^{-1} B^T`` needs
        only the block of ``K^{-1}`` on the contact dofs: the step solver's own Schur
        factorization gives it, so the estimate costs a few dense products instead of a
        second factorization of K.

        Parameters
        ----------
        solver : step solver, optional
            A step solver of this discretization (:meth:`step_solver`) whose
            ``factor.S_inv`` is that block (the condensed Newton's); otherwise a Schur
            factorization is made here with the fastest backend.
        """
        import scipy.sparse.linalg as spla

        from ..solvers.backends import schur_factorize

        tick = time.perf_counter()
        s = self.system
        if s.rigid is not None:  # load control: a_h is not coercive (docs/method.md 1c)
            return {"ratio": float("nan")}
        if s.contact_dofs is None:  # the order of the condensed solver's Schur block
            cols = s.contact_cols
        else:
            cd = np.asarray(s.contact_dofs).ravel()
            cols = cd[cd >= 0]
        S_inv = getattr(getattr(solver, "factor", None), "S_inv", None)
        if S_inv is None or S_inv.shape != (len(cols), len(cols)):
            if self.distributed:
                raise ValueError(
                    "smallness_estimate: K is kept by the MPI ranks; give the run's step "
                    "solver (solver=), whose factorization has the block of K^-1 it needs"
                )
            S_inv = schur_factorize(s.K, cols, s.dof_points).S_inv
        sw = np.sqrt(np.concatenate([s.weights, s.tile_rows(s.weights)]))
        B = sp.vstack([s.N[:, cols], s.Tau[:, cols]]).tocsr()
        Bt = B.T.tocsr()

        def mv(x: NDArray[np.float64]) -> NDArray[np.float64]:
            x = np.ravel(x)
            return cast("NDArray[np.float64]", sw * (B @ (S_inv @ (Bt @ (sw * x)))))

        op = spla.LinearOperator((len(sw), len(sw)), matvec=mv, dtype=np.float64)
        try:
            vals = spla.eigsh(op, k=1, which="LA", return_eigenvectors=False)
            ratio = float(vals[0])  # max of ||v||^2_Gc / a_h(v, v) = c_0^2 / C_1
        except Exception:
            return {"ratio": float("nan")}
        finally:
            self.timings["smallness"] = (
                self.timings.get("smallness", 0.0) + time.perf_counter() - tick
            )
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


def _field_scale(pc: ContactPart, points: NDArray[np.float64], t: NDArray[np.float64]) -> float:
    """The largest ``|v*|`` of a field at the points over the levels (in blocks of about a
    million numbers)."""
    block = max(1, 2**20 // max(3 * len(points), 1))
    top = 0.0
    with np.errstate(all="ignore"):
        for a in range(0, len(t), block):
            V = np.array([pc.velocity.at(points, float(x)) for x in t[a : a + block]])
            top = max(top, float(np.abs(V).max(initial=0.0)))
    return top
