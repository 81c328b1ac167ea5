"""Rigid parts: boundary parts that move as one rigid body (the holder of a pin or ball).

All dofs of a rigid part's component c are tied to one *master* dof, the part's
translation t_c (its rotation is fixed): u_s = t_c for every dof s of the part's
component c (vertex values and, for k = 2, edge and cell means of a translation). Each
component of t is either prescribed (a number or a function of t) or loaded by a force
resultant F_c(t) (zero when omitted: the part is free to move in c). With the 0/1
matrix Q of the ties (Q[s, master(s)] = 1, identity elsewhere), the stiffness becomes
Q^T K Q, the load Q^T f_h plus the resultants on the masters, and the displacement
Q u (docs/method.md section 1d). The force the holder exerts on the body is F_c on a
loaded component and the reaction on a prescribed one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

__all__ = ["RigidPart", "Ties"]

#: A component of a rigid part's force or translation: a number, a function of t, or
#: None (omitted).
TimeComponent = float | Callable[[float], float] | None


@dataclass(frozen=True, eq=False)
class RigidPart:
    """A boundary part that moves as one rigid body with a fixed rotation.

    Parameters
    ----------
    part : str
        The boundary part.
    force : tuple of (float, callable of t, or None)
        The resultant on the part, per component (None: 0, unless the translation is
        prescribed in that component).
    translation : tuple of (float, callable of t, or None)
        Prescribed components of the part's translation (None: free).
    """

    part: str
    force: tuple[TimeComponent, ...] = (None, None)
    translation: tuple[TimeComponent, ...] = (None, None)

    def __post_init__(self) -> None:
        for c, (f, u) in enumerate(zip(self.force, self.translation, strict=False)):
            if f is not None and u is not None:
                raise ValueError(
                    f"rigid part {self.part!r}: component {'xyz'[c]} has both a force and a "
                    "prescribed translation; give one"
                )

    def component(self, c: int) -> tuple[TimeComponent, TimeComponent]:
        """(force, translation) of component c."""
        f = self.force[c] if c < len(self.force) else None
        u = self.translation[c] if c < len(self.translation) else None
        return f, u

    def describe(self) -> dict[str, object]:
        def desc(v: TimeComponent) -> object:
            return getattr(v, "__name__", "callable") if callable(v) else v

        return {
            "part": self.part,
            "force": [desc(f) for f in self.force],
            "translation": [desc(u) for u in self.translation],
            "rotation": "fixed",
        }


def _at(v: TimeComponent, t: float) -> float:
    value = float(v(t)) if callable(v) else float(v or 0.0)
    if not np.isfinite(value):
        raise ValueError(f"a rigid part's force or translation is not finite at t = {t:g}")
    return value


class Ties:
    """The ties of the rigid parts on a space's dofs.

    Attributes
    ----------
    master : (n,) the dof each dof is tied to (itself when not tied)
    slaves : dofs tied to another one
    masters : (P, d) the master dof of each part and component
    Q : (n, n) sparse, ``u = Q u_hat``
    """

    def __init__(
        self, parts: tuple[RigidPart, ...], comp_dofs: list[list[NDArray[np.int64]]], n: int
    ) -> None:
        self.parts = parts
        master = np.arange(n)
        masters = []
        for dofs_c in comp_dofs:
            row = []
            for dd in dofs_c:
                dd = np.sort(np.asarray(dd, dtype=np.int64))
                master[dd] = dd[0]
                row.append(int(dd[0]))
            masters.append(row)
        self.master = master
        self.masters = np.array(masters, dtype=np.int64).reshape(len(parts), -1)
        self.slaves = np.flatnonzero(master != np.arange(n))
        self.Q = sp.csr_matrix((np.ones(n), (np.arange(n), master)), shape=(n, n))

    def tie(self, K: sp.spmatrix) -> sp.csr_matrix:
        """``Q^T K Q``: the stiffness on the untied dofs and the masters."""
        return sp.csr_matrix(self.Q.T @ K @ self.Q)

    def load(self, F: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        """``Q^T F`` plus each loaded component's force on its master."""
        out = np.asarray(self.Q.T @ F, dtype=np.float64)
        for i, pc in enumerate(self.parts):
            for c, dof in enumerate(self.masters[i]):
                f, u = pc.component(c)
                if u is None and f is not None:
                    out[dof] += _at(f, t)
        return out

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
        return any(callable(v) for pc in self.parts for v in (*pc.force, *pc.translation))
