"""Essential boundary conditions: clamped parts and prescribed displacement components.

The paper's Gamma_D (u = 0) is a ``clamped`` part. Besides, a part may prescribe one or
both displacement components, constant or as functions of x and t
(:class:`Prescribed`): rollers (``ux = 0``), a displacement-controlled face
(``uy = -delta t``). A component not prescribed on such a part is traction-free. At a
vertex shared by several parts that prescribe the same component, the first one wins:
the clamped parts, then the prescribed parts in their order. The prescribed values
enter the discrete problem by lifting: ``K_ff u_f = F_f - K_fc u_c(t)``
(docs/method.md, section 1b).

:meth:`Constraints.free_rigid_motions` finds the rigid motions the constraints leave
free, so that a problem without a clamped part is accepted exactly when its stiffness
on the free dofs is regular.

The dofs of a part come from the virtual element space (:mod:`vemwear.vem.space`): for
k = 1 the two dofs of every vertex of the part; for k = 2 also the edge means of its
edges, whose prescribed values are the means of the prescribed component over the edge.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh
from ..vem.space import P1Space, Space

__all__ = ["Component", "Constraints", "Prescribed"]

#: A prescribed component: a number or a callable ``f(x, t)`` of the (n, 2) vertex
#: coordinates and the time, giving (n,) values.
Component = float | Callable[[NDArray[np.float64], float], ArrayLike] | None


@dataclass(frozen=True, eq=False)
class Prescribed:
    """Prescribed displacement components on a boundary part.

    Parameters
    ----------
    part : str
        The boundary part.
    ux, uy : float, callable or None
        The prescribed ``u_x`` and ``u_y`` (None: that component is traction-free).
    """

    part: str
    ux: Component = None
    uy: Component = None

    def __post_init__(self) -> None:
        if self.ux is None and self.uy is None:
            raise ValueError(f"displacement on {self.part!r}: give ux, uy or both")

    def describe(self) -> dict[str, object]:
        def desc(c: Component) -> object:
            return getattr(c, "__name__", "callable") if callable(c) else c

        return {"part": self.part, "ux": desc(self.ux), "uy": desc(self.uy)}


class Constraints:
    """The constrained dofs of a mesh and their values at any time.

    Parameters
    ----------
    mesh : Mesh
    clamped : sequence of str
        Parts with u = 0 (those the mesh does not have are skipped).
    prescribed : sequence of Prescribed
        Parts with prescribed components.
    space : Space, optional
        The virtual element space whose dofs are constrained (k = 1 by default).
    """

    def __init__(
        self,
        mesh: Mesh,
        clamped: Sequence[str],
        prescribed: Sequence[Prescribed],
        space: Space | None = None,
    ) -> None:
        self.space: Space = P1Space(mesh) if space is None else space
        sp_ = self.space
        n = sp_.n_dofs
        clamped = tuple(c for c in clamped if mesh.has_part(c))
        #: the constraining parts: the clamped ones, then the prescribed ones
        self.parts = (*clamped, *(p.part for p in prescribed))
        self.n_clamped = len(clamped)
        owner = -np.ones(n, dtype=np.int64)  # -1 free, else the index in self.parts
        for i, name in enumerate(clamped):
            for d in sp_.component_dofs(mesh.part_edges(name)):
                owner[d[owner[d] < 0]] = i
        for i, pr in enumerate(prescribed):
            comp = sp_.component_dofs(mesh.part_edges(pr.part))
            for d, spec in zip(comp, (pr.ux, pr.uy), strict=True):
                if spec is not None:
                    owner[d[owner[d] < 0]] = self.n_clamped + i
        self.mesh = mesh
        self.prescribed = tuple(prescribed)
        self.dofs = np.flatnonzero(owner >= 0)
        self.owner = owner[self.dofs]
        self.free = np.flatnonzero(owner < 0)
        self.mask = owner >= 0
        self.time_dependent = any(callable(c) for p in prescribed for c in (p.ux, p.uy))
        self.zero = all(
            not callable(c) and (c is None or float(c) == 0.0)
            for p in prescribed
            for c in (p.ux, p.uy)
        )

    @property
    def fully_fixed_vertices(self) -> NDArray[np.bool_]:
        """Vertices with both components constrained (they are no contact nodes)."""
        return np.asarray(self.mask[: 2 * self.mesh.n_points].reshape(-1, 2).all(axis=1))

    def values(self, t: float) -> NDArray[np.float64]:
        """The prescribed values at the constrained dofs (``self.dofs``) at time ``t``."""
        out = np.zeros(len(self.dofs))
        if self.zero:
            return out
        for i, pr in enumerate(self.prescribed):
            for c, spec in enumerate((pr.ux, pr.uy)):
                sel = (self.owner == self.n_clamped + i) & (self.dofs % 2 == c)
                if spec is None or not np.any(sel):
                    continue
                if callable(spec):
                    val = self.space.component_values(self.dofs[sel], spec, t)
                    if not np.all(np.isfinite(val)):
                        name = "ux" if c == 0 else "uy"
                        raise ValueError(
                            f"displacement on {pr.part!r}: {name} is not finite at t = {t:g}"
                        )
                    out[sel] = val
                else:
                    out[sel] = float(spec)
        return out

    def free_rigid_motions(self) -> list[str]:
        """The rigid motions the constraints leave free, described in words (empty if
        none): translations in x and y and rotations about a point."""
        P = self.mesh.points
        centre = P.mean(axis=0)
        L = float(np.ptp(P, axis=0).max()) or 1.0
        # a rigid motion is linear: its dof (a vertex value or a mean over an edge or a
        # cell) is its value at the dof's point
        X, c = self.space.dof_points[self.dofs], self.dofs % 2
        A = np.zeros((len(self.dofs), 3))
        A[c == 0, 0] = 1.0
        A[c == 1, 1] = 1.0
        A[:, 2] = np.where(c == 0, -(X[:, 1] - centre[1]), X[:, 0] - centre[0]) / L
        if len(A) == 0:
            return ["translations in x and y and the rotation"]
        _, sv, Vt = np.linalg.svd(A, full_matrices=True)
        rank = int(np.sum(sv > 1e-10 * max(float(sv.max(initial=0)), 1e-300)))
        if rank == 3:
            return []
        null = Vt[rank:]
        if len(null) >= 2:
            return (
                ["translations in x and y and the rotation"]
                if len(null) == 3
                else [_motion(n, centre, L) for n in null]
            )
        return [_motion(null[0], centre, L)]


def _motion(n: NDArray[np.float64], centre: NDArray[np.float64], L: float) -> str:
    a, b, c = (float(x) for x in n / np.abs(n).max())
    if abs(c) < 1e-9:
        if abs(b) < 1e-9:
            return "the translation in x"
        if abs(a) < 1e-9:
            return "the translation in y"
        return f"the translation along ({a:.3g}, {b:.3g})"
    x0, y0 = centre[0] - b * L / c, centre[1] + a * L / c
    return f"the rotation about ({x0:.4g}, {y0:.4g})"
