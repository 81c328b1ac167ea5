"""Load control: rigid motions that only contact holds (docs/method.md, section 1c).

When the constraints leave rigid motions free that contact can resist (a pad pressed
by a traction and held in the normal direction by the foundation alone), the stiffness
K on the free dofs is singular: ``K R = 0`` for the (n, r) matrix R of those rigid
motions. Every displacement is ``u = G b + R a`` with ``b = F - forces`` the load less
the layer forces, ``a`` the r amplitudes of the rigid motions, and G the inverse of K
with r *anchor* dofs fixed at zero: K with the anchors' rows and columns removed is
SPD (the anchors stop the rigid motions), and one factorization of it serves the whole
run as K's did. ``K G b = b`` holds exactly when the load is balanced in the rigid
directions, ``R^T b = 0``: the r equations that the contact forces must satisfy and
that determine ``a``. The condensed Newton (:mod:`.newton`) then has the unknowns
``y = N u``, ``p_rigid`` and ``a``:

    y - d + C_NN W (p_soft + p_rigid) + C_NT W Fric p_soft - (N R) a = 0,
    (N R)^T W (p_soft + p_rigid) + (Tau R)^T W Fric p_soft - R^T F = 0,

with ``d = N G F``, ``C_NN = N G N^T``, ``C_NT = N G Tau^T`` from the Schur block of
the anchored K.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import NDArray

from .backends import factorize, schur_factorize
from .system import (
    _TINY,
    ContactSystem,
    ConvergenceError,
    StepData,
    StepSolution,
    at_rounding_floor,
)

__all__ = ["AnchoredFactor", "RigidModes", "choose_anchors", "layer_x", "rigid_modes"]


def choose_anchors(R: NDArray[np.float64], exclude: NDArray[np.int64]) -> NDArray[np.int64]:
    """r dofs, none in ``exclude``, whose rows of R (n, r) are as independent as possible
    (QR with column pivoting of ``R^T``): fixing them stops the rigid motions R with the
    best-conditioned r x r block."""
    n, r = R.shape
    allowed = np.ones(n, dtype=bool)
    allowed[exclude] = False
    cand = np.flatnonzero(allowed)
    if len(cand) < r:
        cand = np.arange(n)
    _, _, piv = sla.qr(R[cand].T, mode="economic", pivoting=True)
    return np.sort(cand[piv[:r]])


class AnchoredFactor:
    """``G b``: K's inverse with the anchor dofs fixed at zero, from a factorization of
    ``K_a``, K with the anchors' rows and columns replaced by those of the identity
    (:func:`anchored_matrix`; a Schur factorization, whose block on the contact dofs it
    keeps as ``S_inv``, or a plain one). ``K_a`` is SPD and solves on the whole dof
    vector: no gather or scatter of the other dofs."""

    def __init__(self, inner: Any, anchors: NDArray[np.int64], n: int, schur: bool) -> None:
        self.inner, self.anchors, self.n, self.schur = inner, anchors, n, schur
        self.name: str = getattr(inner, "name", "")
        self.timings: dict[str, float] = getattr(inner, "timings", {})
        self.S_inv: NDArray[np.float64] = getattr(inner, "S_inv", np.zeros((0, 0)))

    def solve(self, b: NDArray[np.float64], out: NDArray[np.float64] | None = None) -> NDArray:
        """``G b`` for a vector or an (n, k) block (written to ``out`` when given)."""
        b = np.asarray(b, dtype=float)
        if np.any(b[self.anchors]):  # G ignores the load on the anchors
            b = b.copy(order="F")
            b[self.anchors] = 0.0
        if out is None or self.schur:  # a Schur factorization writes to ``out`` itself
            x = self.inner.solve(b) if out is None else self.inner.solve(b, out=out)
        else:
            x = out
            x[...] = self.inner.solve(b)
        x[self.anchors] = 0.0  # exactly, whatever a refinement step of the solver left
        return x


def anchored_matrix(K: sp.spmatrix, anchors: NDArray[np.int64]) -> sp.csr_matrix:
    """K with the rows and columns of the anchor dofs replaced by the identity's, on K's
    own sparsity pattern (its stored zeros kept: the ordering of the factorization sees
    the same graph as for K, and a product D K D, which drops them, gives a slower one)."""
    Ka = sp.csr_matrix(K, copy=True)
    Ka.sort_indices()
    rows = np.repeat(np.arange(Ka.shape[0]), np.diff(Ka.indptr))
    on = np.zeros(Ka.shape[0], dtype=bool)
    on[anchors] = True
    hit = on[rows] | on[Ka.indices]
    Ka.data[hit] = 0.0
    diag = hit & (rows == Ka.indices)
    if int(diag.sum()) != len(anchors):  # K's diagonal is stored: SPD on the free dofs
        raise ValueError("anchored_matrix: an anchor's diagonal entry is not stored")
    Ka.data[diag] = 1.0
    return Ka


@dataclass
class RigidModes:
    """The rigid motions held by contact, as a step solver uses them.

    Attributes
    ----------
    R : (n, r) the rigid motions on the free dofs
    anchors, keep : the anchor dofs and the others
    NR, TR : (m, r) ``N R`` and ``Tau R``
    H_R : (r, 2m) ``[(N R)^T, (Tau R)^T]``: the layer forces' components along R
    pinv_NR : (r, m) the pseudo-inverse of ``N R``: ``a`` from ``y`` and the forces
    names : the rigid motions in words, for messages
    """

    R: NDArray[np.float64]
    anchors: NDArray[np.int64]
    keep: NDArray[np.int64]
    NR: NDArray[np.float64]
    TR: NDArray[np.float64]
    H_R: NDArray[np.float64]
    abs_H_R: NDArray[np.float64]
    pinv_NR: NDArray[np.float64]
    names: tuple[str, ...]
    force_scale: NDArray[np.float64]
    _load: tuple[Any, NDArray[np.float64], bool] | None = None
    _bordered: tuple[bytes, Any, float] | None = None

    def load(self, F: NDArray[np.float64]) -> NDArray[np.float64]:
        """``R^T F``: the load along the rigid motions."""
        return self.R.T @ F

    def load_of(self, F: NDArray[np.float64]) -> tuple[NDArray[np.float64], bool]:
        """:meth:`load` and :meth:`negligible` of F, kept for the same array object (a
        constant load is one)."""
        if self._load is None or self._load[0] is not F:
            self._load = (F, self.load(F), self.negligible(F))
        return self._load[1], self._load[2]

    def bordered(
        self, solver: Any, active: NDArray, dp: NDArray, fric: NDArray
    ) -> tuple[Any, float]:
        """The LU factors of the bordered reduced matrix of a piece (None if singular)
        and the scale of its force rows, kept while the piece and friction stay.

        Its top-left block is the condensed Newton's reduced matrix (``A_fric D``, the
        active columns ``C_NN W``, or ``A_fric`` where friction acts on the whole
        pressure, ones on the inactive diagonal); the border is ``-N R`` and the rows of
        the force balance along R, ``(N R)^T W + (Tau R)^T W Fric`` (each node's friction
        rows summed) times the slope on the inactive columns, ``(N R)^T W`` (plus the
        friction part where it acts on the whole pressure) on the active ones."""
        key = active.tobytes() + dp.tobytes() + fric.tobytes()
        if self._bordered is not None and self._bordered[0] == key:
            return self._bordered[1], self._bordered[2]
        s = solver.system
        m, r = len(active), self.R.shape[1]
        total = s.friction_total
        on_total = active & total if total is not None else np.zeros(m, dtype=bool)
        inactive = np.flatnonzero(~active)
        A_fric = solver.friction_matrix(fric)
        B = np.zeros((m + r, m + r))
        Mat = B[:m, :m]
        Mat[...] = A_fric * dp[None, :]
        Mat[:, active] = solver.norm_columns(active)
        Mat[:, on_total] = A_fric[:, on_total]
        Mat[inactive, inactive] += 1.0
        B[:m, m:] = -self.NR
        LN, LT = self.force_rows(s, fric)
        L = (LN + LT) * dp
        L[:, active] = LN[:, active]
        L[:, on_total] += LT[:, on_total]
        # the force rows on the scale of the displacement rows, for the pivoting
        sR = 1.0 / max(float(np.abs(L).max()), _TINY)
        B[m:, :m] = sR * L
        with warnings.catch_warnings():  # a singular B is expected and handled here
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(B, check_finite=False)
        if not np.all(np.abs(np.diag(lu[0])) > 1e-14 * max(float(np.abs(B).max()), _TINY)):
            lu = None  # singular: no node holds a rigid motion
        self._bordered = (key, lu, sR)
        return lu, sR

    def force_rows(self, system: ContactSystem, fric: NDArray) -> tuple[NDArray, NDArray]:
        """``(N R)^T W`` and ``(Tau R)^T W Fric`` with each node's friction rows summed,
        (r, m) each: the force balance along R is ``LN (p_soft + p_rigid) + LT q`` (q the
        pressure friction acts on) ``= R^T F``."""
        m, r = system.m, self.R.shape[1]
        w = system.weights
        LT = (self.TR * (system.tile_rows(w) * fric)[:, None]).T.reshape(r, system.rows, m)
        return self.NR.T * w, LT.sum(axis=1)

    def negligible(self, F: NDArray[np.float64]) -> bool:
        """Whether the load has no component along the rigid motions: each within
        1e-12 of its own scale ``|R|^T |F|`` or of the force that moving the contact
        nodes by 1e-12 max g against their normal stiffness would take."""
        limit = 1e-12 * np.maximum(np.abs(self.R).T @ np.abs(F), self.force_scale)
        return bool(np.all(np.abs(self.load(F)) <= limit))

    def balance(self, x: NDArray, f_R: NDArray) -> tuple[NDArray, float]:
        """The force balance along the rigid motions, ``H_R x - R^T F``, and its scaled
        size: each component over the largest force it sums (a backward error)."""
        R2 = self.H_R @ x - f_R
        scale = np.maximum(np.maximum(np.abs(f_R), self.abs_H_R @ np.abs(x)), _TINY)
        return R2, float(np.max(np.abs(R2) / scale, initial=0.0))

    def amplitudes(self, Y: NDArray, D: NDArray, HX: NDArray) -> NDArray:
        """``a`` of levels (columns) from ``y = d - H x + (N R) a``: least squares on
        the contact nodes (exact where the condensed equation holds)."""
        return self.pinv_NR @ (Y - D + HX)


def rigid_modes(system: ContactSystem, exclude: NDArray[np.int64]) -> RigidModes:
    """:class:`RigidModes` of a system with ``system.rigid`` set; the anchors avoid the
    dofs ``exclude`` (the contact dofs, which stay in the Schur block)."""
    R = np.asarray(system.rigid, dtype=np.float64)
    anchors = choose_anchors(R, exclude)
    keep = np.setdiff1d(np.arange(system.n_free), anchors)
    NR = np.asarray(system.N @ R)
    TR = np.asarray(system.Tau @ R)
    H_R = np.hstack([NR.T, TR.T])
    return RigidModes(
        R=R,
        anchors=anchors,
        keep=keep,
        NR=NR,
        TR=TR,
        H_R=H_R,
        abs_H_R=np.abs(H_R),
        pinv_NR=np.linalg.pinv(NR),
        names=tuple(system.rigid_names) or tuple(f"rigid motion {j}" for j in range(R.shape[1])),
        # |N R|^T (omega c_ncp) max g: a normal motion of max g against the nodal stiffness
        force_scale=np.abs(NR).T @ (system.weights * system.c_ncp) * float(np.abs(system.g).max()),
    )


def anchored_schur(
    system: ContactSystem, rigid: RigidModes, last: NDArray[np.int64], backend: str
) -> AnchoredFactor:
    """The Schur factorization of the anchored K (:func:`anchored_matrix`), its Schur
    block on the free dofs ``last`` (in that order)."""
    if np.any(np.isin(last, rigid.anchors)):
        raise ValueError("anchors: a contact dof was chosen as an anchor")
    Ka = anchored_matrix(system.K, rigid.anchors)
    inner = schur_factorize(Ka, last, system.dof_points, backend)
    return AnchoredFactor(inner, rigid.anchors, system.n_free, schur=True)


def anchored_factor(system: ContactSystem, rigid: RigidModes, backend: str) -> AnchoredFactor:
    """A plain factorization of the anchored K (``G`` for any right-hand side)."""
    Ka = anchored_matrix(system.K, rigid.anchors)
    inner = factorize(Ka.tocsc(), backend)
    return AnchoredFactor(inner, rigid.anchors, system.n_free, schur=False)


def liftoff_error(
    system: ContactSystem, rigid: RigidModes, step: StepData, x: NDArray, f_R: NDArray, method: str
) -> ConvergenceError:
    """The error of a load that pulls the body off the foundation: no contact node is
    pressed, so nothing balances the load along the rigid motion named."""
    R2, _ = rigid.balance(x, f_R)
    # the load's largest component along the held motions is the one that pulls
    j = int(np.argmax(np.abs(f_R) if np.any(f_R) else np.abs(R2)))
    parts = ", ".join(repr(p) for p in system.contact_names) or "the contact part"
    return ConvergenceError(
        f"{method}: the load pulls the body off the foundation at time level {step.level} "
        f"(t = {step.t:.6g}): no node of {parts} is pressed, and contact cannot balance the "
        f"load along {rigid.names[j]} (its component {f_R[j]:.3g})"
    )


def bordered_jacobian(
    J: sp.spmatrix, rigid: RigidModes
) -> tuple[sp.csc_matrix, NDArray[np.float64]]:
    """``[J_:,keep, J R]``: the Jacobian in the unknowns (u on the kept dofs, a), for
    the full-space Newton (u = P u_keep + R a), and ``J R``."""
    JR = np.asarray(J @ rigid.R)
    return sp.hstack([J.tocsc()[:, rigid.keep], sp.csc_matrix(JR)], format="csc"), JR


def layer_x(system: ContactSystem, fric: NDArray, p_soft: NDArray, p_rigid: NDArray) -> NDArray:
    """The layer forces' weights ``[W (p_soft + p_rigid), W Fric q]`` (q the pressure
    friction acts on): the ``x`` of the condensed equation and of the force balance."""
    q = system.friction_pressure(p_soft, p_rigid)
    return np.concatenate([system.weights * (p_soft + p_rigid), system.friction_weights(fric, q)])


def cold_start(system: ContactSystem, wear: NDArray) -> tuple[NDArray, NDArray]:
    """Newton's start under load control, (y, p_rigid): every contact node halfway into
    the soft layer where the layer is stiff there; on the rigid layer, active with a
    small pressure, where it is worn through or has no stiffness (p = 0: Signorini
    contact). Either way the first step's matrix holds the body."""
    g = system.g
    y = wear + 0.5 * (g - wear)
    soft = (g > wear) & (system.p.derivative(y - wear) > 0)
    y = np.where(soft, y, g)
    p_rigid = np.where(soft, 0.0, system.c_ncp * 1e-3 * float(np.abs(g).max()))
    return y, p_rigid


def newton_rigid(solver: Any, step: StepData, d: NDArray, start: tuple | None, it: int):
    """The condensed semismooth Newton iteration with the rigid amplitudes ``a``
    (:class:`~vemwear.solvers.newton.CondensedNewton` under load control): the reduced
    matrix of each piece bordered by ``-N R`` and the force balance along R.

    Returns y, p_rigid, p_soft, the iteration count and the three residuals (the
    equilibrium one the larger of the condensed equation's, over max g, and the force
    balance's, :meth:`RigidModes.balance`). The stopping rule is the condensed
    Newton's (docs/method.md section 5); the start, :func:`cold_start` without a guess.
    """
    s, opt, rig = solver.system, solver.options, solver.rigid
    g, c_ncp, wear, fric, law, w = s.g, s.c_ncp, step.w, step.fric, s.p, s.weights
    H = solver.H
    f_R, negligible = rig.load_of(step.F)
    if negligible:
        return touching(s, rig, step, d)
    if start is not None and not pressed(s, start[0], start[1], wear):
        start = None  # the previous level touched without force (a load ramped from 0)
    y, p_rigid = cold_start(s, wear) if start is None else start
    inv_g = solver.inv_g_ref

    def layer(y: NDArray, p_rigid: NDArray) -> tuple[NDArray, NDArray]:
        p_soft = law(y - wear)
        return p_soft, layer_x(s, fric, p_soft, p_rigid)

    p_soft, x = layer(y, p_rigid)
    a = rig.amplitudes(y[:, None], d[:, None], (H @ x)[:, None])[:, 0]
    stop = 0.1 * opt.tol
    last, same = b"", 0
    method = "semismooth Newton (condensed)"
    while True:
        p_soft, x = layer(y, p_rigid)
        R1 = H @ x + y - d - rig.NR @ a
        R2, eq2 = rig.balance(x, f_R)
        errors = _errors(y, p_rigid, R1, g, inv_g, eq2)
        done = max(errors) <= stop or it == opt.max_iter
        if not done:
            it += 1
            active = p_rigid + c_ncp * (y - g) > 0.0
            dp = law.derivative(y - wear)
            piece = active.tobytes() + dp.tobytes()
            same = same + 1 if piece == last else 0
            last = piece
            if at_rounding_floor(same, max(errors) <= opt.tol):
                done, it = True, it - 1
        if done:
            if max(errors) > opt.tol and not (np.any(p_soft) or np.any(p_rigid)):
                raise liftoff_error(s, rig, step, x, f_R, method)
            return y, p_rigid, p_soft, it, errors
        lu, sR = rig.bordered(solver, active, dp, fric)
        if lu is None:
            # too few nodes pressed to hold the body (a start touching at one node, an
            # iterate that overshot): the step of the piece whose lifted nodes keep a
            # small slope; a load that truly pulls the body off never converges, and
            # the test above names it
            lu, sR = rig.bordered(solver, active, _with_floor(dp, active, s.c_ncp), fric)
        dy_A = np.where(active, g - y, 0.0)
        dp_I = np.where(active, 0.0, p_rigid)
        t = dp * dy_A
        xp = np.concatenate(
            [w * (t - dp_I), s.friction_weights(fric, s.friction_pressure(t, -dp_I))]
        )
        rhs = np.concatenate([-R1 - dy_A - H @ xp, -sR * (R2 + rig.H_R @ xp)])
        sol = sla.lu_solve(lu, rhs, check_finite=False)
        m = s.m
        y = np.where(active, g, y + sol[:m])
        p_rigid = np.where(active, p_rigid + sol[:m], 0.0)
        a = a + sol[m:]


def _with_floor(dp: NDArray, active: NDArray, c_ncp: NDArray) -> NDArray:
    """The slopes with a floor, 1e-3 of the largest (or of c_ncp), at the inactive nodes
    where the law is flat."""
    floor = 1e-3 * (float(dp.max()) if np.any(dp > 0) else float(np.max(c_ncp)))
    return np.where(~active & (dp <= 0.0), floor, dp)


def pressed(system: ContactSystem, y: NDArray, p_rigid: NDArray, wear: NDArray) -> bool:
    """Whether some contact node holds the body at (y, p_rigid): on the rigid layer, or
    in the soft layer where it is stiff (else Newton's first matrix is singular)."""
    active = p_rigid + system.c_ncp * (y - system.g) > 0.0
    return bool(np.any(active) or np.any(system.p.derivative(y - wear)))


def _errors(
    y: NDArray, p_rigid: NDArray, R1: NDArray, g: NDArray, inv_g: float, eq2: float
) -> tuple[float, float, float]:
    """The three condensed residuals (:func:`~vemwear.solvers.system.condensed_residuals`)
    with the force balance's ``eq2`` in the equilibrium one."""
    equilibrium = max(float(np.abs(R1).max()) * inv_g, eq2)
    gap = (g - y) * inv_g
    feasibility = max(0.0, -float(gap.min()))
    p_ref = float(np.abs(p_rigid).max())
    if p_ref == 0.0:
        return equilibrium, feasibility, feasibility
    return equilibrium, feasibility, float(np.abs(np.minimum(p_rigid / p_ref, gap)).max())


def touching(system: ContactSystem, rig: RigidModes, step: StepData, d: NDArray):
    """The step solution under a load with no component along the held rigid motions
    (``d`` the normal displacement of the load in the anchored gauge): no contact
    force, and the body touching the worn layer: the rigid motion that fits the contact
    nodes best to it (least squares), lowered along the motion that moves every node by
    one along its normal until no node penetrates. Returns y, p_rigid, p_soft, the
    iteration count (0) and the three residuals."""
    from .system import condensed_residuals

    s = system
    a = rig.pinv_NR @ (step.w - d)
    c = rig.pinv_NR @ np.ones(s.m)
    v = rig.NR @ c
    y = d + rig.NR @ a
    if np.all(v > 0):
        a = a - float(np.max((y - step.w) / v)) * c
        y = d + rig.NR @ a
    y = np.minimum(y, s.g)
    zero = np.zeros(s.m)
    res = condensed_residuals(s, y, zero, zero)
    return y, zero, s.p(y - step.w), 0, (0.0, res["feasibility"], res["complementarity"])


def touching_solution(
    system: ContactSystem, rig: RigidModes, step: StepData, G: AnchoredFactor
) -> StepSolution:
    """:func:`touching` as a full step solution (u = G F + R a) for the solvers that
    work with u, with its residuals. The load is zero along R only to rounding: its
    residual, R (R^T F) / |R|^2, is measured as a backward error on the scale of the
    displacements (as the condensed solver's recovered u is, ``kkt_residuals_block``),
    not over |F|, which may itself be that small."""
    from .system import kkt_residuals

    s = system
    u = G.solve(step.F)
    y, *_ = touching(s, rig, step, s.N @ u)
    u = u + rig.R @ (rig.pinv_NR @ (y - s.N @ u))
    p_rigid = np.zeros(s.m)
    res = kkt_residuals(s, step, u, p_rigid)
    x_ref = max(float(np.abs(u).max(initial=0)), float(np.abs(s.g).max()))
    r = s.K @ u - step.F
    res["equilibrium"] = float(np.abs(r).max()) / max(
        float(np.abs(step.F).max()), s.K_norm * x_ref, _TINY
    )
    y = s.N @ u
    return StepSolution(
        u=u, u_nu=y, p_rigid=p_rigid, p_soft=s.p(y - step.w), iterations=0, residuals=res
    )
