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

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import NDArray

from .backends import factorize, schur_factorize
from .system import _TINY, ContactSystem, ConvergenceError, StepData

__all__ = ["AnchoredFactor", "RigidModes", "choose_anchors", "rigid_modes"]


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
    """``G b``: K's inverse with the anchor dofs fixed at zero, from a factorization of K
    on the other dofs ``keep`` (a Schur factorization, whose block on the contact dofs it
    keeps as ``S_inv``, or a plain one)."""

    def __init__(self, inner: Any, keep: NDArray[np.int64], n: int) -> None:
        self.inner, self.keep, self.n = inner, keep, n
        self.name: str = getattr(inner, "name", "")
        self.timings: dict[str, float] = getattr(inner, "timings", {})
        self.S_inv: NDArray[np.float64] = getattr(inner, "S_inv", np.zeros((0, 0)))

    def solve(self, b: NDArray[np.float64], out: NDArray[np.float64] | None = None) -> NDArray:
        """``G b`` for a vector or an (n, k) block (written to ``out`` when given)."""
        b = np.asarray(b, dtype=float)
        x = np.zeros(b.shape) if out is None else out
        if out is not None:
            x[...] = 0.0
        x[self.keep] = self.inner.solve(np.asfortranarray(b[self.keep]))
        return x


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

    def load(self, F: NDArray[np.float64]) -> NDArray[np.float64]:
        """``R^T F``: the load along the rigid motions."""
        return self.R.T @ F

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
    """The Schur factorization of K without the anchors, its Schur block on the free
    dofs ``last`` (in that order)."""
    keep = rigid.keep
    pos = -np.ones(system.n_free, dtype=np.int64)
    pos[keep] = np.arange(len(keep))
    Kk = system.K[keep][:, keep].tocsr()
    inner = schur_factorize(Kk, pos[last], system.dof_points[keep], backend)
    if np.any(pos[last] < 0):
        raise ValueError("anchors: a contact dof was chosen as an anchor")
    return AnchoredFactor(inner, keep, system.n_free)


def anchored_factor(system: ContactSystem, rigid: RigidModes, backend: str) -> AnchoredFactor:
    """A plain factorization of K without the anchors (``G`` for any right-hand side)."""
    keep = rigid.keep
    inner = factorize(system.K[keep][:, keep].tocsc(), backend)
    return AnchoredFactor(inner, keep, system.n_free)


def liftoff_error(
    system: ContactSystem, rigid: RigidModes, step: StepData, x: NDArray, f_R: NDArray, method: str
) -> ConvergenceError:
    """The error of a load that pulls the body off the foundation: no contact node is
    pressed, so nothing balances the load along the rigid motion named."""
    R2, _ = rigid.balance(x, f_R)
    j = int(np.argmax(np.abs(R2)))
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


def newton_rigid(solver: Any, step: StepData, d: NDArray, start: tuple | None, it: int):
    """The condensed semismooth Newton iteration with the rigid amplitudes ``a``
    (:class:`~vemwear.solvers.newton.CondensedNewton` under load control): the reduced
    matrix of each piece bordered by ``-N R`` and the force balance along R.

    Returns y, p_rigid, p_soft, the iteration count and the three residuals (the
    equilibrium one the larger of the condensed equation's, over max g, and the force
    balance's, :meth:`RigidModes.balance`). From the cold start the nodes start halfway
    into the soft layer (where it is thinner than the wear, on the rigid layer), so
    that the layer's stiffness holds the body in the first step.
    """
    from .system import condensed_residuals

    s, opt, rig = solver.system, solver.options, solver.rigid
    g, c_ncp, wear, fric, law, w = s.g, s.c_ncp, step.w, step.fric, s.p, s.weights
    m, r = s.m, rig.R.shape[1]
    wf = w * fric
    H, A_norm, T_fric = solver.H, solver.A_norm, solver.T_fric
    f_R = rig.load(step.F)
    if rig.negligible(step.F):
        return touching(s, rig, step, d)
    if start is None:
        room = g > wear
        y = np.where(room, wear + 0.5 * (g - wear), g)
        p_rigid = np.where(room, 0.0, c_ncp * 1e-3 * float(np.abs(g).max()))
    else:
        y, p_rigid = start

    def layer(y: NDArray, p_rigid: NDArray) -> tuple[NDArray, NDArray]:
        p_soft = law(y - wear)
        return p_soft, np.concatenate([w * (p_soft + p_rigid), wf * p_soft])

    p_soft, x = layer(y, p_rigid)
    a = rig.amplitudes(y[:, None], d[:, None], (H @ x)[:, None])[:, 0]
    stop = 0.1 * opt.tol
    last, same = b"", 0
    method = "semismooth Newton (condensed)"
    while True:
        p_soft, x = layer(y, p_rigid)
        R1 = H @ x + y - d - rig.NR @ a
        res = condensed_residuals(s, y, p_rigid, R1)
        R2, eq2 = rig.balance(x, f_R)
        errors = (max(res["equilibrium"], eq2), res["feasibility"], res["complementarity"])
        if max(errors) <= stop or it == opt.max_iter:
            if max(errors) > opt.tol and not (np.any(p_soft) or np.any(p_rigid)):
                raise liftoff_error(s, rig, step, x, f_R, method)
            return y, p_rigid, p_soft, it, errors
        it += 1
        active = p_rigid + c_ncp * (y - g) > 0.0
        dp = law.derivative(y - wear)
        piece = active.tobytes() + dp.tobytes()
        if piece == last:
            same += 1
            if (same >= 2 and max(errors) <= opt.tol) or same >= 4:
                if max(errors) > opt.tol and not (np.any(p_soft) or np.any(p_rigid)):
                    raise liftoff_error(s, rig, step, x, f_R, method)
                return y, p_rigid, p_soft, it - 1, errors
        else:
            same = 0
        last = piece
        if not np.any(active) and not np.any(dp):
            raise liftoff_error(s, rig, step, x, f_R, method)
        inactive = np.flatnonzero(~active)
        B = np.zeros((m + r, m + r))
        Mat = B[:m, :m]
        Mat[...] = (A_norm + T_fric * fric[None, :]) * dp[None, :]
        Mat[:, active] = A_norm[:, active]
        Mat[inactive, inactive] += 1.0
        B[:m, m:] = -rig.NR
        L = (rig.NR.T * w + rig.TR.T * wf) * dp
        L[:, active] = rig.NR.T[:, active] * w[active]
        # the force rows on the scale of the displacement rows, for the pivoting
        sR = 1.0 / max(float(np.abs(L).max()), _TINY)
        B[m:, :m] = sR * L
        dy_A = np.where(active, g - y, 0.0)
        dp_I = np.where(active, 0.0, p_rigid)
        t = dp * dy_A
        xp = np.concatenate([w * (t - dp_I), wf * t])
        rhs = np.concatenate([-R1 - dy_A - H @ xp, -sR * (R2 + rig.H_R @ xp)])
        try:
            sol = sla.solve(B, rhs, check_finite=False)
        except np.linalg.LinAlgError:
            raise liftoff_error(s, rig, step, x, f_R, method) from None
        z, da = sol[:m], sol[m:]
        y = np.where(active, g, y + z)
        p_rigid = np.where(active, p_rigid + z, 0.0)
        a = a + da


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
