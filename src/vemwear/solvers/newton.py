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

import contextlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import NDArray

from .backends import factorize, schur_factorize
from .pieces import MIN_WIDTH, PiecePredictor, block_width
from .system import (
    _TINY,
    RESIDUAL_NAMES,
    ContactSystem,
    ConvergenceError,
    StepData,
    StepSolution,
    check_converged,
    kkt_residuals,
    kkt_residuals_block,
)
from .threads import solver_threads

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


@dataclass(frozen=True)
class NewtonOptions:
    """Tolerance on the scaled KKT residuals, iteration limit, sparse backend
    (:func:`.backends.resolve_backend`: ``"auto"`` takes the fastest installed)."""

    tol: float = 1e-10
    max_iter: int = 100
    backend: str = "auto"


class _ReducedMatrix:
    """The LU factors of the reduced Newton matrix for one active set and slope vector.

    With ``M = C_NN W + C_NT W Fric`` the Newton system for the new iterate reads
    ``(I + M D) y + C_NN W p_rigid = rhs`` with ``D = diag(p')``; on the active set
    ``y = g``, on the inactive set ``p_rigid = 0``. The unknowns left, ``y`` on the
    inactive and ``p_rigid`` on the active nodes, share one index per node, so the
    matrix is ``M D`` with the active columns replaced by those of ``C_NN W`` and ones
    added on the inactive diagonal. It is factorized once per (active set, slopes,
    friction where slopes are nonzero) and kept while those stay the same.
    """

    def __init__(self, A_norm, T_fric, active, dp, fric) -> None:
        self.active = active
        self.dp = dp
        # the friction enters only through the columns with a nonzero slope
        self.fric = fric if np.any(dp[~active]) else None
        Mat = (A_norm + T_fric * fric[None, :]) * dp[None, :]
        Mat[:, active] = A_norm[:, active]
        inactive = np.flatnonzero(~active)
        Mat[inactive, inactive] += 1.0
        self.lu, self.piv, info = _getrf(Mat, overwrite_a=True)
        if info != 0:
            raise np.linalg.LinAlgError(f"singular reduced Newton matrix (pivot {info})")

    def matches(self, active, dp, fric) -> bool:
        """Same active set, slopes and (where it matters) friction: O(m) comparisons."""
        return bool(
            active.tobytes() == self.active.tobytes()  # booleans: bytes compare as values
            and (dp == self.dp).all()
            and (self.fric is None or fric is self.fric or (fric == self.fric).all())
        )

    def solve(self, rhs: NDArray) -> NDArray:
        return _getrs(self.lu, self.piv, rhs)[0]


_getrf, _getrs = sla.get_lapack_funcs(("getrf", "getrs"), (np.zeros(1),))


class CondensedNewton:
    """Semismooth Newton on the condensed system; one factorization of K per simulation.

    The factorization (:func:`.backends.schur_factorize`) gives the block ``C`` of
    ``K^{-1}`` on the contact dofs, hence the dense compliance blocks
    ``C_NN = N K^{-1} N^T`` and ``C_NT = N K^{-1} Tau^T``. The unknowns are ``y = N u``
    and ``p_rigid``; the condensed equations (paper 3.21 after eliminating u) are

        R(y, p_rigid) = y - d + C_NN W (p(y - w) + p_rigid) + C_NT W Fric p(y - w) = 0

    with ``d = N K^{-1} F`` and complementarity between ``p_rigid`` and ``g - y``. Every
    step is certified by the residuals of these equations (:func:`condensed_residuals`);
    the full displacement, when asked for, by those of the full system
    (:func:`kkt_residuals_block`: the solve's backward error, and the constraint over
    the scale of the normal displacements, :meth:`displacement_scales`).

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
        if system.contact_dofs is None:  # a trace operator (k = 2): C_NN = N_c C N_c^T
            cols = np.unique(np.concatenate([system.N.indices, system.Tau.indices]))
            self.factor = schur_factorize(system.K, cols, system.dof_points, self.options.backend)
            Nc = system.N[:, cols].toarray()
            CN = self.factor.S_inv @ Nc.T
            self.C_NN = Nc @ CN
            self.C_NT = system.Tau[:, cols].toarray() @ CN
            self.C_NT = np.ascontiguousarray(self.C_NT.T)  # N C Tau^T
        else:
            cd = system.contact_dofs.ravel()
            free = cd >= 0  # prescribed components of contact nodes are not unknowns
            self.factor = schur_factorize(
                system.K, cd[free], system.dof_points, self.options.backend
            )
            k = system.contact_dofs.shape[1]  # the dimension d
            if np.all(free):
                C = self.factor.S_inv.reshape(m, k, m, k)  # block of K^{-1} on contact dofs
            else:
                full = np.zeros((k * m, k * m))
                full[np.ix_(free, free)] = self.factor.S_inv
                C = full.reshape(m, k, m, k)
            nu, tau = system.normals, system.tangents
            self.C_NN = np.einsum("ai,aibj,bj->ab", nu, C, nu)
            self.C_NT = np.einsum("ai,aibj,bj->ab", nu, C, tau)
        w = system.weights
        self.A_norm = self.C_NN * w[None, :]
        self.T_fric = self.C_NT * w[None, :]  # C_NT W: the friction term is T_fric Fric
        self.H = np.hstack([self.C_NN, self.C_NT])  # one product per iteration
        self._x = np.zeros(2 * m)  # work arrays of the iteration, and views of their halves
        self._x_n, self._x_t = self._x[:m], self._x[m:]
        self._buf = np.zeros(2 * m)
        self._zeros = np.zeros(m)
        self._zeros.setflags(write=False)
        self._wf: tuple[NDArray | None, NDArray] = (None, w)  # (fric, weights * fric)
        self.inv_g_ref = 1.0 / max(float(np.abs(system.g).max()), _TINY)
        self._reduced: _ReducedMatrix | None = None
        self._predictor: PiecePredictor | None = None
        self._F: NDArray | None = None
        self._d: NDArray | None = None
        self._rhs = np.empty((system.n_free, 0), order="F")  # work array of recover_many
        # large dense products and LU factorizations run with one BLAS pool
        self._threads = solver_threads if m >= 128 else contextlib.nullcontext

    def normal_displacement(self, F: NDArray) -> NDArray:
        """``d = N K^{-1} F``, solved again only for a new load (the same array object,
        as a constant load gives, is recognised without looking at its entries)."""
        if F is not self._F:
            if self._F is None or not np.array_equal(F, self._F):
                self._d = self.system.N @ self.factor.solve(F)
            self._F = F
        return self._d  # type: ignore[return-value]

    def displacement_scales(
        self,
        steps: list[StepData],
        ys: list[NDArray],
        p_rigids: list[NDArray],
        p_softs: list[NDArray],
    ) -> NDArray:
        """``max(max g, max |d|)`` of each level, from its step solution (``y = N u``,
        the pressures): the scale of the normal displacements of the KKT residuals of
        its recovered u (:func:`~vemwear.solvers.system.kkt_residuals_block`).

        ``y`` is ``d = N K^{-1} F`` less the normal displacement of the contact forces,
        ``y = d - C_NN W (p_soft + p_rigid) - C_NT W Fric p_soft``. Where the load alone
        would push the body far beyond the rigid layer (a slender body: ``|d|`` a
        hundred times g), ``y`` is a small difference of large terms and its error is
        that of ``d``, up to cond(K) times the machine epsilon times ``|d|``: measured
        over g alone it can exceed any tolerance near 1e-10 however the solution is
        computed. ``d`` is taken from the condensed equation at the step solution (one
        product with the m x 2m block ``H``, no solve), so the scale does not depend on
        the displacement it certifies.
        """
        D = self.H @ np.vstack(self._layer_forces(steps, p_rigids, p_softs))
        D += np.column_stack(ys)
        return np.maximum(np.abs(D).max(axis=0), 1.0 / self.inv_g_ref)

    def _layer_forces(
        self, steps: list[StepData], p_rigids: list[NDArray], p_softs: list[NDArray]
    ) -> tuple[NDArray, NDArray]:
        """``W (p_soft + p_rigid)`` and ``W Fric p_soft`` of several levels, (m, k) each:
        the weights of ``N^T`` and ``Tau^T`` in the layer forces (the ``x`` of the
        condensed equation, level by level)."""
        w = self.system.weights[:, None]
        P_soft = np.column_stack(p_softs)
        P = w * (P_soft + np.column_stack(p_rigids))
        Q = w * np.column_stack([st.fric for st in steps]) * P_soft
        return P, Q

    def stiffness_note(self, y: NDArray, step: StepData) -> str:
        """A note for Newton's error message when the soft layer is much stiffer than the
        body at the contact nodes, ``max_a p'(y_a - w_a) omega_a (C_NN)_aa`` above 100
        (the compliance slope times the body's own compliance there): Newton's steps
        can then cycle between pieces even from the cold start, and the slope turns the
        rounding of y into a condensed residual that grows with the ratio (Example
        5.2's data with p = 1e8 r: above tol, tests/test_solvers.py). Empty
        otherwise."""
        s = self.system
        ratio = float(np.max(s.p.derivative(y - step.w) * s.weights * np.diag(self.C_NN)))
        if not ratio > 100.0:
            return ""
        return (
            f"; the soft layer is {ratio:.3g} times as stiff as the body at the contact "
            "nodes (p' omega C_NN), where Newton's steps can cycle and the slope turns "
            "the rounding of N u into residuals"
        )

    def reduced_matrix(self, active: NDArray, dp: NDArray, fric: NDArray) -> _ReducedMatrix:
        """The LU factors of the reduced Newton matrix of this active set, slopes and
        friction: the kept ones while they stay the same."""
        red = self._reduced
        if red is None or not red.matches(active, dp, fric):
            red = self._reduced = _ReducedMatrix(self.A_norm, self.T_fric, active, dp, fric)
        return red

    def recover_many(
        self,
        steps: list[StepData],
        p_rigids: list[NDArray],
        p_softs: list[NDArray],
        out: NDArray | None = None,
    ) -> NDArray:
        """Full displacements of several levels with one block solve, shape (nf, len(steps)).

        ``out``, a Fortran-ordered (nf, len(steps)) array, receives them instead of a
        new array: a caller that recovers block after block reuses its memory.
        """
        s = self.system
        k = len(steps)
        if len(p_rigids) != k or len(p_softs) != k:
            raise ValueError("recover_many: one p_rigid and one p_soft per step")
        # the right-hand sides F - N^T W (p_soft + p_rigid) - Tau^T W fric p_soft, built
        # in one Fortran-ordered block (the layout the solvers take, no copies) of a work
        # array kept from call to call (fresh memory of that size costs page faults)
        P, Q = self._layer_forces(steps, p_rigids, p_softs)
        if self._rhs.shape[1] < k:
            self._rhs = np.empty((s.n_free, k), order="F")
        rhs = self._rhs[:, :k]
        if all(st.F is steps[0].F for st in steps):  # a constant load: one broadcast
            rhs[...] = steps[0].F[:, None]
        else:
            for j, st in enumerate(steps):
                rhs[:, j] = st.F
        # N and Tau act on the contact dofs only: (2m, k) products, not (n, k) ones
        NT, TT = s.force_operators
        rhs[s.contact_cols] -= NT @ P + TT @ Q
        return self.factor.solve(rhs, out=out)

    def predict(
        self,
        guess: StepSolution,
        step: StepData,
        advance: Callable[[NDArray], NDArray | None],
        limit: int,
        times: Sequence[float] | NDArray,
    ) -> list[tuple[StepData, StepSolution]]:
        """Levels from ``step`` on, on the piece Newton sees from ``guess``, certified
        by Newton's exit test (:class:`.pieces.PiecePredictor`; for piecewise-linear
        laws and a constant load, while the friction stays the same)."""
        with self._threads():
            return self.predictor(guess, step, advance, limit, times)

    @property
    def predicts(self) -> bool:
        """Whether :meth:`predict` pays: a piecewise-linear law and at most 362 contact
        nodes (:data:`.pieces.MIN_WIDTH`)."""
        return self.system.p.piecewise_linear and block_width(self.system.m) >= MIN_WIDTH

    #: Recovers many levels in one block solve (:class:`.protocol.BatchStepSolver`).
    batch = True

    @property
    def setup_timings(self) -> dict[str, float]:
        """Wall times of the factorization's parts."""
        return dict(getattr(self.factor, "timings", {}))

    @property
    def predictor(self) -> PiecePredictor:
        """The runs of levels on one piece (made at the first use)."""
        if self._predictor is None:
            self._predictor = PiecePredictor(self)
        return self._predictor

    def solve(
        self, step: StepData, guess: StepSolution | None = None, recover: bool = True
    ) -> StepSolution:
        """Solve one step problem on the contact unknowns (y = N u, p_rigid).

        With ``recover=False`` the full displacement is not computed (``u`` is None);
        :meth:`recover_many` computes it later for several levels at once.
        """
        with self._threads():
            y, p_rigid, p_soft, it, errors = self._iterate(step, guess)
        s, tol = self.system, self.options.tol
        res = dict(zip(RESIDUAL_NAMES, errors, strict=True))
        why = lambda: self.stiffness_note(y, step)  # noqa: E731 (called on failure only)
        check_converged(res, tol, step, "semismooth Newton (condensed)", it, why)
        p_rigid = np.maximum(p_rigid, 0.0)
        u = None
        if recover:
            # certified as a recovered block is (run_levels): the solve's backward error
            X = self.recover_many([step], [p_rigid], [p_soft])
            scales = self.displacement_scales([step], [y], [p_rigid], [p_soft])
            res = kkt_residuals_block(s, [step], X, [p_rigid], scales)[0]
            u = X[:, 0]
            y = s.N @ u
            check_converged(res, tol, step, "recovery of the displacement", it)
        return StepSolution(
            u=u, u_nu=y, p_rigid=p_rigid, p_soft=p_soft, iterations=it, residuals=res
        )

    def _iterate(self, step: StepData, guess: StepSolution | None):
        """The Newton iterations; returns y, p_rigid, p_soft = p(y - w), the iteration
        count and the three condensed residuals of the last iterate.

        Each iteration solves ``J11 dy + C_NN W dp_rigid = -R`` with ``dy = g - y`` on
        the active and ``dp_rigid = -p_rigid`` on the inactive set (the linearization of
        R, ``J11 = I + M D``); when the active set is the same as at the previous
        iterate, these prescribed parts are zero and the right-hand side is ``-R``.

        Started from ``guess`` (the previous level), the iteration can cycle between
        pieces when the solution moved far from it (a soft layer much stiffer than the
        body with wear steps that overshoot): when a piece comes back that is not the
        last one, it starts again from the cold start ``y = min(d, g)``,
        ``p_rigid = 0``, within the same ``max_iter``.
        """
        d = self.normal_displacement(step.F)
        if guess is None:
            return self._newton(step, d, None, 0)[:5]
        start = (np.array(guess.u_nu, copy=True), np.array(guess.p_rigid, copy=True))
        out = self._newton(step, d, start, 0)
        if out[5]:  # a cycle: once more from the cold start
            out = self._newton(step, d, None, out[3])
        return out[:5]

    def _newton(self, step: StepData, d: NDArray, start: tuple | None, it: int):
        """:meth:`_iterate` from ``start`` (y, p_rigid), or from the cold start if None,
        counting iterations from ``it``; returns also whether it stopped at a cycle (a
        piece seen before, not the last one: only from a given start)."""
        s, opt = self.system, self.options
        g, c_ncp, wear, fric, law = s.g, s.c_ncp, step.w, step.fric, s.p
        if start is not None:
            y, p_rigid = start
        else:
            y, p_rigid = np.minimum(d, g), np.zeros(s.m)
        w, H, x, x_n, x_t, buf = s.weights, self.H, self._x, self._x_n, self._x_t, self._buf
        if self._wf[0] is not fric:  # the steps of a steady v* share one fric array
            self._wf = (fric, w * fric)
        wf = self._wf[1]
        inv_g = self.inv_g_ref
        stop = 0.1 * opt.tol
        seen: set[bytes] = set()  # the pieces left (their active sets and slopes)
        last, same = None, 0  # steps in a row on one piece: at_rounding_floor
        while True:
            r = y - wear
            p_soft = law(r)
            # R = y - d + C_NN W (p_soft + p_rigid) + C_NT W Fric p_soft
            np.multiply(w, p_soft + p_rigid, out=x_n)
            np.multiply(wf, p_soft, out=x_t)
            R = H @ x
            R += y
            R -= d
            errors = _condensed_errors(y, p_rigid, R, g, inv_g, buf)
            if max(errors) <= stop or it == opt.max_iter:
                return y, p_rigid, p_soft, it, errors, False
            it += 1
            active = p_rigid + c_ncp * (y - g) > 0.0
            dp = law.derivative(r)
            red = self.reduced_matrix(active, dp, fric)
            if red is last:
                same += 1
                if at_rounding_floor(same, max(errors) <= opt.tol):
                    return y, p_rigid, p_soft, it - 1, errors, False
            else:
                same = 0
                if start is not None and it > 2:  # (the usual level takes one or two)
                    piece = active.tobytes() + dp.tobytes()
                    if piece in seen:
                        return y, p_rigid, p_soft, it - 1, errors, True
                    seen.add(piece)
            last = red
            # no active node (the body off the rigid layer, the usual case): the masks
            # give dy_A = 0 and dp_I = p_rigid, without the array passes
            any_active = np.count_nonzero(active) > 0
            dy_A = np.where(active, g - y, 0.0) if any_active else self._zeros
            dp_I = np.where(active, 0.0, p_rigid) if any_active else p_rigid
            rhs = -R
            if np.count_nonzero(dy_A) or np.count_nonzero(dp_I):
                # rhs -= J11 dy_A + C_NN W (-p_rigid_I)
                t = dp * dy_A
                np.multiply(w, t - dp_I, out=x_n)
                np.multiply(wf, t, out=x_t)
                rhs -= dy_A
                rhs -= H @ x
            sol = red.solve(rhs)
            if any_active:
                y = np.where(active, g, y + sol)
                p_rigid = np.where(active, p_rigid + sol, 0.0)
            else:
                y = y + sol
                p_rigid = np.zeros(s.m)


def _condensed_errors(y, p_rigid, R, g, inv_g, buf) -> tuple[float, float, float]:
    """The three condensed residuals of :func:`condensed_residuals`, as a tuple
    (``buf``: a work array of 2m entries).

    ``inv_g = 1 / g_ref > 0``: scaling by it commutes with abs, min and max (rounding
    is monotone), so ``max |R| inv_g`` is the largest of the scaled entries, bitwise.
    Without rigid-layer pressure (``p_rigid = 0``, the usual case) the complementarity
    function is ``min(0, (g - y) / g_ref)``, whose largest absolute value is the largest
    violation ``-min (g - y) / g_ref`` of the bound (or 0): no array pass for it.
    """
    m = len(y)
    equilibrium = float(np.abs(R, out=buf[:m]).max()) * inv_g
    if not np.count_nonzero(p_rigid):
        low = -(float((g - y).min()) * inv_g)
        # max(0.0, low) is 0 for a NaN low; the complementarity keeps the NaN
        return equilibrium, max(0.0, low), 0.0 if low <= 0.0 else low
    p_ref = float(np.abs(p_rigid).max()) or _TINY  # = max(max p_rigid, -min p_rigid)
    gap = np.subtract(g, y, out=buf[:m])
    gap *= inv_g
    ncp = np.minimum(p_rigid / p_ref, gap, out=buf[m:])
    return equilibrium, max(0.0, -float(gap.min())), float(np.abs(ncp, out=ncp).max())


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
