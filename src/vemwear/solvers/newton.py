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
from numpy.typing import NDArray

from .backends import SchurFactorization, schur_factorize
from .pieces import MIN_WIDTH, PiecePredictor, block_width
from .rigid import (
    anchored_schur,
    newton_rigid,
    rigid_modes,
)
from .system import (
    _TINY,
    RESIDUAL_NAMES,
    ContactSystem,
    ConvergenceError,
    StepData,
    StepSolution,
    at_rounding_floor,
    check_converged,
    kkt_residuals_block,
)
from .threads import solver_threads


@dataclass(frozen=True)
class NewtonOptions:
    """Tolerance on the scaled KKT residuals, iteration limit, sparse backend
    (:func:`.backends.resolve_backend`: ``"auto"`` takes the fastest installed)."""

    tol: float = 1e-10
    max_iter: int = 100
    backend: str = "auto"


class _ReducedMatrix:
    """The LU factors of the reduced Newton matrix for one active set and slope vector.

    With ``M = C_NN W + C_NT W Fric`` (``A_fric``) the Newton system for the new iterate
    reads ``(I + M D) y + C_NN W p_rigid = rhs`` with ``D = diag(p')`` (``M p_rigid`` at
    the nodes whose friction acts on the whole pressure, ``total``); on the active set
    ``y = g``, on the inactive set ``p_rigid = 0``. The unknowns left, ``y`` on the
    inactive and ``p_rigid`` on the active nodes, share one index per node, so the
    matrix is ``M D`` with the active columns replaced by those of ``C_NN W`` and ones
    added on the inactive diagonal. It is factorized once per (active set, slopes,
    friction where slopes are nonzero) and kept while those stay the same.
    """

    def __init__(self, A_fric, norm_active, active, dp, fric, total=None) -> None:
        self.active = active
        self.dp = dp
        # the friction enters only through the columns with a nonzero slope, and with
        # friction on the whole pressure through the active columns of those nodes
        on_rigid = total is not None and bool(np.any(active & total))
        self.fric = fric if np.any(dp[~active]) or on_rigid else None
        Mat = np.multiply(A_fric, dp[None, :], order="F")  # LAPACK's order: no copy
        Mat[:, active] = norm_active  # the active columns of C_NN W
        if on_rigid:  # d R / d p_rigid = C_NN W + C_NT W Fric at those nodes
            Mat[:, active & total] = A_fric[:, active & total]
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
        self.factor: SchurFactorization
        if system.contact_dofs is None:
            last = np.unique(np.concatenate([system.N.indices, system.Tau.indices]))
        else:
            cd = system.contact_dofs.ravel()
            last = cd[cd >= 0]
        #: the rigid motions that only contact holds (load control), or None
        self.rigid = None if system.rigid is None else rigid_modes(system, last)
        if self.rigid is not None:  # K without the anchors: the Schur block on ``last``
            self.factor = anchored_schur(system, self.rigid, last, self.options.backend)
        if system.contact_dofs is None:  # a trace operator (k = 2): C_NN = N_c C N_c^T
            cols = last
            if self.rigid is None:
                self.factor = schur_factorize(
                    system.K, cols, system.dof_points, self.options.backend, system.assembly
                )
            Nc = system.N[:, cols].toarray()
            CN = self.factor.S_inv @ Nc.T
            C_NN = Nc @ CN
            C_NT = [(system.Tau[:, cols].toarray() @ CN).T]  # N C Tau^T, (m, r m)
        else:
            free = cd >= 0  # prescribed components of contact nodes are not unknowns
            if self.rigid is None:
                self.factor = schur_factorize(
                    system.K, cd[free], system.dof_points, self.options.backend, system.assembly
                )
            k = system.contact_dofs.shape[1]  # the dimension d
            if np.all(free):
                C = self.factor.S_inv.reshape(m, k, m, k)  # block of K^{-1} on contact dofs
            else:
                full = np.zeros((k * m, k * m))
                full[np.ix_(free, free)] = self.factor.S_inv
                C = full.reshape(m, k, m, k)
            nu, tau = system.normals, system.tangents
            C_NN = np.einsum("ai,aibj,bj->ab", nu, C, nu)
            # one block per friction row, from the same block C of K^{-1}
            C_NT = [np.einsum("ai,aibj,bj->ab", nu, C, t) for t in tau.reshape(-1, m, k)]
        w = system.weights
        r = system.rows
        # H = [C_NN, C_NT], one product per iteration, holds the blocks (views of it),
        # made and copied in turn: the only (m, (1 + r) m) array kept (C_NN W and
        # C_NT W Fric are formed when a reduced matrix is, :meth:`friction_matrix`)
        self.H = np.empty((m, (1 + r) * m))
        self.C_NN, self.C_NT = self.H[:, :m], self.H[:, m:]
        self.C_NN[...] = C_NN
        del C_NN
        for j, block in enumerate(C_NT):
            width = block.shape[1]
            self.C_NT[:, j * width : (j + 1) * width] = block
        del C_NT
        self._x = np.zeros((1 + r) * m)  # work arrays of the iteration, and views of parts
        self._x_n, self._x_t = self._x[:m], self._x[m:]
        self._x_rows = self._x_t.reshape(r, m)
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
        s = self.system
        w = s.weights[:, None]
        P_soft, P_rigid = np.column_stack(p_softs), np.column_stack(p_rigids)
        P = w * (P_soft + P_rigid)
        fric = np.column_stack([st.fric for st in steps])
        Q = s.friction_weights(fric, s.friction_pressure(P_soft, P_rigid))
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

    def norm_columns(self, cols: NDArray) -> NDArray:
        """Columns ``cols`` of ``C_NN W`` (an index or boolean array over the nodes)."""
        return self.C_NN[:, cols] * self.system.weights[cols][None, :]

    def friction_matrix(self, fric: NDArray) -> NDArray:
        """``C_NN W + C_NT W Fric`` (m, m): how the pressure friction acts on moves the
        normal displacements (the friction rows of a node summed), formed in place."""
        s = self.system
        m = s.m
        TF = np.multiply(self.C_NT, s.tile_rows(s.weights)[None, :])  # C_NT W
        TF *= fric[None, :]
        if s.rows == 1:
            out = TF
            out += np.multiply(self.C_NN, s.weights[None, :])  # C_NN W
            return out
        out = np.multiply(self.C_NN, s.weights[None, :])
        for k in range(s.rows):
            out += TF[:, k * m : (k + 1) * m]
        return out

    def reduced_matrix(self, active: NDArray, dp: NDArray, fric: NDArray) -> _ReducedMatrix:
        """The LU factors of the reduced Newton matrix of this active set, slopes and
        friction: the kept ones while they stay the same."""
        red = self._reduced
        if red is None or not red.matches(active, dp, fric):
            self._reduced = red = None  # its factors are not kept while new ones are made
            red = self._reduced = _ReducedMatrix(
                self.friction_matrix(fric),
                self.norm_columns(active),
                active,
                dp,
                fric,
                self.system.friction_total,
            )
        return red

    def recover_many(
        self,
        steps: list[StepData],
        p_rigids: list[NDArray],
        p_softs: list[NDArray],
        out: NDArray | None = None,
        ys: list[NDArray] | None = None,
    ) -> NDArray:
        """Full displacements of several levels with one block solve, shape (nf, len(steps)).

        ``out``, a Fortran-ordered (nf, len(steps)) array, receives them instead of a
        new array: a caller that recovers block after block reuses its memory. Under
        load control (:mod:`.rigid`) the levels' ``ys`` (``N u``) give the amplitudes
        of the rigid motions, ``u = G (F - forces) + R a``.
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
        if self.rigid is None:
            return self.factor.solve(rhs, out=out)
        if ys is None:
            raise ValueError("recover_many: the levels' y = N u are needed under load control")
        D = np.column_stack([self.normal_displacement(st.F) for st in steps])
        A = self.rigid.amplitudes(np.column_stack(ys), D, self.H @ np.vstack([P, Q]))
        rhs[self.rigid.anchors] = 0.0  # G ignores them: no copy of the block to clear them
        X = self.factor.solve(rhs, out=out)
        X += self.rigid.R @ A
        return X

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
            X = self.recover_many([step], [p_rigid], [p_soft], ys=[y])
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
        if self.rigid is not None:
            start = None if guess is None else (np.array(guess.u_nu), np.array(guess.p_rigid))
            return newton_rigid(self, step, d, start, 0)
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
            self._wf = (fric, s.tile_rows(w) * fric)
        wf = self._wf[1]
        total = s.friction_total
        if s.rows > 1:  # friction rows (r, m) times the nodal pressure (m,)
            wf, x_t = wf.reshape(s.rows, s.m), self._x_rows
        inv_g = self.inv_g_ref
        stop = 0.1 * opt.tol
        seen: set[bytes] = set()  # the pieces left (their active sets and slopes)
        last, same = None, 0  # steps in a row on one piece: at_rounding_floor
        while True:
            r = y - wear
            p_soft = law(r)
            # R = y - d + C_NN W (p_soft + p_rigid) + C_NT W Fric q, q = p_soft (+ p_rigid
            # where friction acts on the whole pressure)
            np.multiply(w, p_soft + p_rigid, out=x_n)
            np.multiply(
                wf, p_soft if total is None else s.friction_pressure(p_soft, p_rigid), out=x_t
            )
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
                np.multiply(wf, t if total is None else s.friction_pressure(t, -dp_I), out=x_t)
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


__all__ = ["CondensedNewton", "ConvergenceError", "NewtonOptions"]
