"""Runs of levels on one piece of the condensed step problem, certified together.

For a compliance law that is linear on segments (``law.piecewise_linear``), a
constant load and the same friction direction, the condensed step problem of
:class:`~vemwear.solvers.newton.CondensedNewton` (paper 3.21 after eliminating u) is
linear on each *piece*: a fixed active set A of the rigid layer and a fixed segment
``p = D r + q`` of the law at every node. On a piece its solution is an affine
function of the wear,

    J z = M w + c0,    y = g on A and z elsewhere,    p_rigid = z on A and 0 elsewhere,

with ``M = (C_NN W + C_NT W Fric) D``, ``J`` the reduced Newton matrix of the piece
(``M`` with the columns of A replaced by those of ``C_NN W``, ones added on the
diagonal off A) and ``c0 = d - (C_NN W + C_NT W Fric) q - (I + M)[:, A] g_A``. This
is the iterate that one Newton step from any point of the piece gives. Where friction
acts on the whole pressure (``friction_total``), the columns of A in J are those of
``C_NN W + C_NT W Fric`` at such nodes (Newton's reduced matrix), and the map is the
same; with two friction rows per node (a v* that turns in 3D) ``C_NT W Fric`` sums them.

Wear grows slowly, so a level mostly lies on the piece that Newton sees from the level
before (the active set of the previous solution and the segments of ``y^{n-1} - w^n``).
:class:`PiecePredictor` computes a run of levels on the piece of its first level from
the wear recurrence alone (one product and one solve with the kept LU factors per
level), then checks the whole run at once: that each level's piece is the one Newton
would see from the level before, and Newton's own exit test, the three condensed
residuals with the true law at most ``tol / 10`` (one matrix product for the run).
The accepted levels are the leading ones that pass both; the first level that fails
is left to Newton.

Each accepted level is therefore a function of the previous solution and its wear
alone, whatever run it was computed in: the residual products are taken in a block of
fixed width with level n in column ``n % width``, so that a column's numbers do not
depend on the others. A run resumed at any level gives bitwise the same numbers.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from .system import _TINY, RESIDUAL_NAMES, StepData, StepSolution

if TYPE_CHECKING:
    from .newton import CondensedNewton

__all__ = ["FIRST_RUN", "MIN_WIDTH", "Piece", "PiecePredictor", "block_width"]

_getrs = sla.get_lapack_funcs("getrs", (np.zeros(1),))

_NO_AMPLITUDES = np.zeros(0)

#: Levels of a first run, and of a run after one cut short by a change of piece.
FIRST_RUN = 8


#: The fewest columns of a residual block with which runs pay: below, with more than
#: 362 contact nodes, Newton's levels are bound by BLAS products and cost no more than
#: a run's (6 % less at 512 contact nodes, 16 % less at 1024; README, Performance).
MIN_WIDTH = 4


def block_width(m: int) -> int:
    """Columns of the residual block for m contact nodes: up to 64 levels in one
    product, fewer for large m so that the product (2 m^2 flops a column, whatever
    the run's length) stays below 2^20 flops."""
    return int(min(64, max(1, 2**19 // max(m * m, 1))))


class Piece:
    """The affine map of one piece, wear -> (y, p_rigid): the LU factors of J (Newton's
    reduced matrix of the piece), ``M`` and ``c0``.

    Under load control (:mod:`.rigid`) the unknowns gain the amplitudes ``a`` of the
    rigid motions and the map is ``B [z; a] = [M w + c0; L w + e0]``, with B the
    bordered reduced matrix (:meth:`.rigid.RigidModes.bordered`) and the force rows
    ``L = s_R (LN + LT) D``, ``e0 = s_R (R^T F - (LN + LT) (q + D g_A))``: the force
    balance along R on the piece. ``usable`` is False where B is singular.
    """

    def __init__(self, newton: CondensedNewton, d, active, slope, offset, fric, F) -> None:
        self.key = (active.tobytes(), slope.tobytes(), offset.tobytes(), fric.tobytes())
        self.d = d
        self.active, self.slope, self.offset = active, slope, offset
        self.any_active = bool(active.any())
        AT = newton.friction_matrix(fric)  # C_NN W + C_NT W Fric
        self.M = AT * slope[None, :]
        c0 = d - AT @ offset
        g_A = np.where(active, newton.system.g, 0.0)
        if self.any_active:
            c0 -= self.M @ g_A
            c0 -= g_A
        self.c0 = c0
        rig = newton.rigid
        self.usable = True
        self.red: Any = None
        self.bordered: Any = None
        if rig is None:
            self.red = newton.reduced_matrix(active, slope, fric)
            return
        self.bordered, sR = rig.bordered(newton, active, slope, fric)
        self.usable = self.bordered is not None
        self.f_R = rig.load_of(F)[0]
        LN, LT = rig.force_rows(newton.system, fric)
        L = (LN + LT) * sR
        self.L = L * slope[None, :]
        self.e0 = sR * self.f_R - L @ offset - self.L @ g_A

    def solve(self, w: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``z`` (y off the active set, p_rigid on it) and the amplitudes ``a`` (none
        without load control) of the piece's solution at wear ``w``."""
        b = self.M @ w
        b += self.c0
        if self.red is not None:
            return self.red.solve(b), _NO_AMPLITUDES
        lu, piv = self.bordered  # LAPACK directly: a level costs microseconds
        za = _getrs(lu, piv, np.concatenate([b, self.L @ w + self.e0]))[0]
        m = len(b)
        return za[:m], za[m:]

    def matches(self, active, slope, offset, fric, d) -> bool:
        # a constant load keeps its array d
        return d is self.d and self.key == (
            active.tobytes(),
            slope.tobytes(),
            offset.tobytes(),
            fric.tobytes(),
        )


class PiecePredictor:
    """Runs of levels on one piece for a :class:`~vemwear.solvers.newton.CondensedNewton`
    (its condensed operators, its LU factors of the reduced matrices), keeping the
    last piece."""

    def __init__(self, newton: CondensedNewton) -> None:
        self.newton = newton
        self.width = block_width(newton.system.m)
        #: the piece of the last run
        self.piece: Piece | None = None
        # levels the next run tries: doubled after a whole run is accepted, back to
        # FIRST_RUN after a run cut short (a piece change costs the levels tried past it)
        self._run = FIRST_RUN
        s = newton.system  # work block: the x of Newton's products, (1 + r) m rows
        self._X = np.zeros(((1 + s.rows) * s.m, self.width), order="F")

    def __call__(
        self,
        guess: StepSolution,
        step: StepData,
        advance: Callable[[NDArray[np.float64]], NDArray[np.float64] | None],
        limit: int,
        times: Sequence[float] | NDArray[np.float64],
    ) -> list[tuple[StepData, StepSolution]]:
        """The leading levels of a run from ``step`` on that lie on the piece Newton
        sees at ``step`` and pass its exit test.

        Parameters
        ----------
        guess : StepSolution
            The solution of the level before ``step``.
        step : StepData
            The first level; its load and friction stay for the whole run (the caller
            asks only for a constant load).
        advance : callable
            ``advance(p_soft)``, the wear ``w`` of the next level's step data from
            this level's soft pressure (the scheme's wear update), or None where the
            next level's friction is not that of ``step`` (the run ends there);
            called for all but the last level of the run.
        limit : int
            Levels to predict at most. A run also stops before the next multiple of
            :attr:`width`; it tries :data:`FIRST_RUN` levels after a run cut short,
            twice the levels of a whole run after one.
        times : sequence of float
            The time of every level (that of the step data).

        Returns
        -------
        list of (StepData, StepSolution)
            The accepted levels with their step data (u not recovered, one iteration
            each), possibly none.
        """
        newton = self.newton
        s = newton.system
        m, law, g, c_ncp = s.m, s.p, s.g, s.c_ncp
        first = step.level % self.width
        count = min(self._run, limit, self.width - first)
        d = newton.normal_displacement(step.F)
        fric = step.fric
        y0, w = guess.u_nu, step.w
        active = guess.p_rigid + c_ncp * (y0 - g) > 0.0  # Newton's first iteration
        slope, offset = law.segments(y0 - w)
        piece = self.piece
        if piece is None or not piece.matches(active, slope, offset, fric, d):
            piece = self.piece = Piece(newton, d, active, slope, offset, fric, step.F)
        rig = newton.rigid
        if rig is not None and (not piece.usable or rig.load_of(step.F)[1]):
            return []  # nothing holds the body on this piece, or no load: Newton says
        Y, P, S, Wr = (np.empty((count, m)) for _ in range(4))
        A = np.empty((count, 0 if rig is None else rig.R.shape[1]))
        inv_g, limit_tol = newton.inv_g_ref, 0.1 * newton.options.tol
        cut = False  # whether a level failed the exit test's feasibility
        for j in range(count):
            if j:
                w_next = advance(S[j - 1])
                if w_next is None:  # the step data change beyond the wear
                    count = j
                    break
                w = w_next
            Wr[j] = w
            z, A[j] = piece.solve(w)
            if piece.any_active:
                Y[j] = np.where(active, g, z)
                P[j] = np.where(active, z, 0.0)
            else:
                Y[j] = z
                P[j] = 0.0
            S[j] = law(Y[j] - w)
            # the feasibility of Newton's exit test at this level (the number of
            # _errors, bitwise): a level beyond the bound fails the test, so the run ends
            # before it without the levels after it (a piece change at the run's start
            # cost a whole run of levels)
            if not -(float((g - Y[j]).min()) * inv_g) <= limit_tol:
                count, cut = j, True
                break
        Y, P, S, Wr, A = Y[:count], P[:count], S[:count], Wr[:count], A[:count]
        P_plus = np.maximum(P, 0.0)  # Newton's solution clamps p_rigid after its test
        if count:
            ok = self._same_piece(Y, P_plus, Wr, piece)
            errors = self._errors(d, fric, Y, P, S, first, A, piece)
            ok &= np.all(errors <= limit_tol, axis=1)
        else:
            ok, errors = np.ones(0, dtype=bool), np.empty((0, 3))
        k = count if ok.all() else int(np.argmin(ok))
        self._run = min(2 * count, self.width) if k == count and not cut else FIRST_RUN
        F, n = step.F, step.level
        res = errors[:k].tolist()
        return [
            (
                StepData(F=F, w=Wr[j], fric=fric, t=float(times[n + j]), level=n + j),
                StepSolution(
                    u=None,
                    u_nu=Y[j],
                    p_rigid=P_plus[j],
                    p_soft=S[j],
                    iterations=1,
                    residuals=dict(zip(RESIDUAL_NAMES, res[j], strict=True)),
                ),
            )
            for j in range(k)
        ]

    def _same_piece(self, Y, P_plus, Wr, piece: Piece) -> NDArray[np.bool_]:
        """Whether Newton, started from level j - 1's solution with level j's wear,
        sees the piece of the run (true for the first level by construction)."""
        s = self.newton.system
        ok = np.ones(len(Y), dtype=bool)
        if len(Y) > 1:
            active = P_plus[:-1] + s.c_ncp * (Y[:-1] - s.g) > 0.0
            slope, offset = s.p.segments(Y[:-1] - Wr[1:])
            ok[1:] = (
                (active == piece.active).all(axis=1)
                & (slope == piece.slope).all(axis=1)
                & (offset == piece.offset).all(axis=1)
            )
        return ok

    def _errors(self, d, fric, Y, P, S, first: int, A, piece: Piece) -> NDArray[np.float64]:
        """The three condensed residuals of Newton's exit test, (k, 3), of the rows of
        Y, P (p_rigid before clamping) and S (p_soft), by the formulas of Newton's
        (equilibrium max |R| / g_ref; feasibility and complementarity of p_rigid and
        g - y): the products with H in a block of :attr:`width` columns, row j in
        column ``first + j``. Under load control, with the amplitudes A (k, r): the
        condensed equation's ``- (N R) a`` and the force balance along R
        (:meth:`.rigid.RigidModes.balance`) in the equilibrium residual."""
        newton = self.newton
        s = newton.system
        k, m = Y.shape
        X = self._X  # the other columns' values do not enter these columns' products
        cols = slice(first, first + k)
        X[:m, cols] = (s.weights * (S + P)).T  # Newton's x: W (p_soft + p_rigid)
        Q = s.friction_pressure(S.T, P.T)  # and W Fric q, q = p_soft (+ p_rigid: total)
        X[m:, cols] = s.friction_weights(np.broadcast_to(fric[:, None], (len(fric), k)), Q)
        R = (newton.H @ X)[:, cols].T
        R += Y
        R -= d
        inv_g = newton.inv_g_ref
        rig = newton.rigid
        if rig is not None:
            for j in range(A.shape[1]):  # elementwise: a row's numbers are its own
                R -= A[:, j : j + 1] * rig.NR[:, j]
        equilibrium = np.abs(R).max(axis=1) * inv_g
        if rig is not None:
            R2 = (rig.H_R @ X)[:, cols].T - piece.f_R
            scale = np.maximum((rig.abs_H_R @ np.abs(X))[:, cols].T, np.abs(piece.f_R))
            eq2 = (np.abs(R2) / np.maximum(scale, _TINY)).max(axis=1, initial=0.0)
            equilibrium = np.maximum(equilibrium, eq2)
        g_minus_y = s.g - Y
        gap = g_minus_y * inv_g
        p_ref = np.abs(P).max(axis=1)
        has_p = p_ref != 0.0
        # without rigid-layer pressure: the largest violation of the bound (or 0)
        low = -(g_minus_y.min(axis=1) * inv_g)
        feasibility = np.maximum(0.0, -gap.min(axis=1))
        ncp = np.abs(np.minimum(P / np.where(has_p, p_ref, 1.0)[:, None], gap)).max(axis=1)
        out: Any = np.column_stack(
            [
                equilibrium,
                np.where(has_p, feasibility, np.where(low > 0.0, low, 0.0)),
                np.where(has_p, ncp, np.where(low <= 0.0, 0.0, low)),  # a NaN stays
            ]
        )
        return out
