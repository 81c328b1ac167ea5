"""Rigid parts: boundary parts that move as one rigid body (the holder of a pin or ball).

All dofs of a rigid part's component c are tied to one *master* dof, the part's
translation t_c: u_s = t_c for every dof s of the part's component c (vertex values
and, for k = 2, edge and cell means of a translation). Each component of t is either
prescribed (a number or a function of t) or loaded by a force resultant F_c(t) (zero
when omitted: the part is free to move in c). With the matrix Q of the ties
(Q[s, master(s)] = 1, identity elsewhere), the stiffness becomes Q^T K Q, the load
Q^T f_h plus the resultants on the masters, and the displacement Q u (docs/method.md
section 1d). The force the holder exerts on the body is F_c on a loaded component and
the reaction on a prescribed one.

A part whose rotation is free moves as ``u(x) = t + theta x (x - x_0)`` (small
rotations, as the elasticity is linear), x_0 the mean of its vertices: t is the
translation of x_0, and theta (one angle in 2D, three in 3D) is kept in dofs of the
part that the ties free otherwise (the *rotation dofs*, no new unknowns): Q gains the
entries ``(e_k x (x_s - x_0))_c`` in their columns, and the moment resultant about x_0,
M_k(t), is their load (zero when omitted).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

__all__ = ["RigidPart", "Ties"]

#: A component of a rigid part's force or translation: a number, a function of t, or
#: None (omitted).
TimeComponent = float | Callable[[float], float] | None


@dataclass(frozen=True, eq=False)
class RigidPart:
    """A boundary part that moves as one rigid body.

    Parameters
    ----------
    part : str
        The boundary part.
    force : tuple of (float, callable of t, or None)
        The resultant on the part, per component (None: 0, unless the translation is
        prescribed in that component).
    translation : tuple of (float, callable of t, or None)
        Prescribed components of the part's translation (None: free).
    rotation : {"fixed", "free"} or tuple of them
        "fixed": the part translates only; "free": it also turns, about the mean of its
        vertices, loaded by ``moment``; in 3D also one per axis (``("free", "free",
        "fixed")``: it tilts but does not turn about z).
    moment : tuple of (float, callable of t, or None)
        The moment resultant about the mean of the part's vertices (2D: ``(M_z,)``; 3D:
        ``(M_x, M_y, M_z)``; None: 0), with ``rotation = "free"`` only.
    """

    part: str
    force: tuple[TimeComponent, ...] = (None, None)
    translation: tuple[TimeComponent, ...] = (None, None)
    rotation: Literal["fixed", "free"] | tuple[Literal["fixed", "free"], ...] = "fixed"
    moment: tuple[TimeComponent, ...] = ()

    def __post_init__(self) -> None:
        for c, (f, u) in enumerate(zip(self.force, self.translation, strict=False)):
            if f is not None and u is not None:
                raise ValueError(
                    f"rigid part {self.part!r}: component {'xyz'[c]} has both a force and a "
                    "prescribed translation; give one"
                )
        axes = (self.rotation,) if isinstance(self.rotation, str) else self.rotation
        if any(a not in ("fixed", "free") for a in axes) or len(axes) not in (1, 3):
            raise ValueError(
                f"rigid part {self.part!r}: rotation is 'fixed', 'free' or, in 3D, one of "
                "them per axis"
            )
        fixed = [k for k, m in enumerate(self.moment) if callable(m) or (m or 0.0) != 0.0]
        if any(not self.free_axis(k) for k in fixed):
            raise ValueError(
                f"rigid part {self.part!r}: a moment about a fixed axis; give the moment about "
                "the axes whose rotation is 'free' (a fixed rotation takes it as a reaction)"
            )

    def free_axis(self, k: int) -> bool:
        """Whether the rotation about axis k (2D: k = 0, about z) is free."""
        if isinstance(self.rotation, str):
            return self.rotation == "free"
        return k < len(self.rotation) and self.rotation[k] == "free"

    @property
    def turns(self) -> bool:
        """Whether the part turns about some axis."""
        return any(self.free_axis(k) for k in range(3))

    def component(self, c: int) -> tuple[TimeComponent, TimeComponent]:
        """(force, translation) of component c."""
        f = self.force[c] if c < len(self.force) else None
        u = self.translation[c] if c < len(self.translation) else None
        return f, u

    def moment_component(self, k: int) -> TimeComponent:
        """Component k of the moment (None: 0)."""
        return self.moment[k] if k < len(self.moment) else None

    def describe(self) -> dict[str, object]:
        def desc(v: TimeComponent) -> object:
            return getattr(v, "__name__", "callable") if callable(v) else v

        out: dict[str, object] = {
            "part": self.part,
            "force": [desc(f) for f in self.force],
            "translation": [desc(u) for u in self.translation],
            "rotation": self.rotation if isinstance(self.rotation, str) else list(self.rotation),
        }
        if self.turns:  # (parts that translate only keep their earlier fingerprint)
            out["moment"] = [desc(m) for m in self.moment]
        return out


def _at(v: TimeComponent, t: float) -> float:
    value = float(v(t)) if callable(v) else float(v or 0.0)
    if not np.isfinite(value):
        raise ValueError(f"a rigid part's force or translation is not finite at t = {t:g}")
    return value


def _rotation_columns(D: NDArray[np.float64], c: NDArray[np.int64]) -> NDArray[np.float64]:
    """``(e_k x D)_c``, (n, 1) in 2D and (n, 3) in 3D: the displacement in component c
    at offsets D (n, d) from the centre of a unit rotation about axis k."""
    rows = np.arange(len(c))
    if D.shape[1] == 2:  # e_z x (dx, dy) = (-dy, dx)
        return np.where(c == 0, -D[:, 1], D[:, 0])[:, None]
    return np.column_stack([np.cross(np.eye(3)[k], D)[rows, c] for k in range(3)])


class Ties:
    """The ties of the rigid parts on a space's dofs.

    Attributes
    ----------
    master : (n,) the dof each dof is tied to (itself when not tied)
    slaves : dofs tied to another one
    masters : (P, d) the master dof of each part and component
    rotation_dofs : (P, 1) in 2D, (P, 3) in 3D: the dofs holding a part's rotation
        (-1 where its rotation is fixed)
    centres : (P, d) the mean of each part's vertices (x_0)
    Q : (n, n) sparse, ``u = Q u_hat``
    moved : the dofs whose row of Q is not the identity's
    """

    def __init__(
        self,
        parts: tuple[RigidPart, ...],
        comp_dofs: list[list[NDArray[np.int64]]],
        n: int,
        dof_points: NDArray[np.float64],
        n_vertex_dofs: int,
    ) -> None:
        self.parts = parts
        d = dof_points.shape[1]
        nrot = 1 if d == 2 else 3
        for pc in parts:
            if pc.turns and len(pc.moment) not in (0, nrot):
                raise ValueError(
                    f"rigid part {pc.part!r}: the moment is "
                    + ("one number (M_z) in 2D" if d == 2 else "[M_x, M_y, M_z] in 3D")
                )
            if d == 2 and not isinstance(pc.rotation, str):
                raise ValueError(
                    f"rigid part {pc.part!r}: in 2D the rotation is 'fixed' or 'free' (about z)"
                )
        master = np.arange(n)  # the translation master of each dof
        masters, rot = [], -np.ones((len(parts), nrot), dtype=np.int64)
        rows, cols, vals = [], [], []  # Q's rotation entries
        self.centres = np.zeros((len(parts), d))
        turning = []
        for i, (pc, dofs_c) in enumerate(zip(parts, comp_dofs, strict=True)):
            row = []
            sorted_c = [np.sort(np.asarray(dd, dtype=np.int64)) for dd in dofs_c]
            for dd in sorted_c:
                master[dd] = dd[0]
                row.append(int(dd[0]))
            masters.append(row)
            vert = sorted_c[0][sorted_c[0] < n_vertex_dofs]
            self.centres[i] = dof_points[vert].mean(axis=0)
            if not pc.turns:
                continue
            if min(len(dd) for dd in sorted_c) < 2:
                raise ValueError(f"rigid part {pc.part!r}: a part of one vertex cannot turn")
            rot[i] = [int(sorted_c[k % d][1]) if pc.free_axis(k) else -1 for k in range(nrot)]
            part = np.concatenate(sorted_c)
            turning.append(part)
            E = _rotation_columns(dof_points[part] - self.centres[i], part % d)
            for k in np.flatnonzero(rot[i] >= 0):
                rows.append(part)
                cols.append(np.full(len(part), rot[i, k]))
                vals.append(E[:, k])
        # u_s = t_master(s) (+ the rotation's displacement at s): Q's entries
        r = np.concatenate([np.arange(n), *rows])
        c = np.concatenate([master, *cols])
        v = np.concatenate([np.ones(n), *vals])
        self.Q = sp.csr_matrix((v, (r, c)), shape=(n, n))
        self.Q.eliminate_zeros()
        master[rot[rot >= 0]] = rot[rot >= 0]  # a rotation dof is no slave: it holds theta
        self.master = master
        self.masters = np.array(masters, dtype=np.int64).reshape(len(parts), -1)
        self.rotation_dofs = rot
        self.slaves = np.flatnonzero(master != np.arange(n))
        self.turning = bool(turning)
        self.moved = np.union1d(self.slaves, np.concatenate(turning)) if turning else self.slaves

    def tie(self, K: sp.spmatrix) -> sp.csr_matrix:
        """``Q^T K Q``: the stiffness on the untied dofs, the masters and rotation dofs."""
        return sp.csr_matrix(self.Q.T @ K @ self.Q)

    def load(self, F: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        """``Q^T F`` plus each loaded component's force on its master and each moment
        on its rotation dof."""
        out = np.asarray(self.Q.T @ F, dtype=np.float64)
        for i, pc in enumerate(self.parts):
            for c, dof in enumerate(self.masters[i]):
                f, u = pc.component(c)
                if u is None and f is not None:
                    out[dof] += _at(f, t)
            for k, dof in enumerate(self.rotation_dofs[i]):
                m = pc.moment_component(k)
                if dof >= 0 and m is not None:
                    out[dof] += _at(m, t)
        return out

    def expand(self, U: NDArray[np.float64]) -> None:
        """``u = Q u_hat`` in place on the rows of U (k, n): the tied dofs from their
        masters (and the rotation dofs)."""
        if not self.turning:  # ties u_s = u_master: copies, bitwise
            U[:, self.slaves] = U[:, self.master[self.slaves]]
            return
        U[:, self.moved] = (self.Q[self.moved] @ U.T).T

    def motions(self, u: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
        """Each part's translation of its centre (P, d) and rotation (P, 1 in 2D, 3 in
        3D; zero where fixed) in a displacement u (n_points, d) of the vertices."""
        u = np.asarray(u, dtype=np.float64).ravel()
        P, d = self.masters.shape
        t = np.zeros((P, d))
        theta = np.zeros((P, self.rotation_dofs.shape[1]))
        for i, pc in enumerate(self.parts):
            if not pc.turns:
                t[i] = u[self.masters[i]]
                continue
            free = self.rotation_dofs[i] >= 0
            cols = np.concatenate([self.masters[i], self.rotation_dofs[i][free]])
            rows = np.flatnonzero(np.isin(self.master[: len(u)], cols))  # its vertex dofs
            B = self.Q[rows][:, cols].toarray()
            x = np.linalg.lstsq(B, u[rows], rcond=None)[0]
            t[i], theta[i, free] = x[:d], x[d:]
        return t, theta

    def forces(self, t: float, d: int) -> NDArray[np.float64]:
        """(P, d) the applied resultants of the loaded components (0 where prescribed)."""
        out = np.zeros((len(self.parts), d))
        for i, pc in enumerate(self.parts):
            for c in range(d):
                f, u = pc.component(c)
                if u is None and f is not None:
                    out[i, c] = _at(f, t)
        return out

    @property
    def time_dependent(self) -> bool:
        return any(
            callable(v) for pc in self.parts for v in (*pc.force, *pc.translation, *pc.moment)
        )
