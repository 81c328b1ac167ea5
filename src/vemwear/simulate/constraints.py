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

from ..mesh.polyhedra import Mesh3D
from ..mesh.polymesh import Mesh
from ..vem.space import P1Space, Space, has_part, make_space, part_facets
from .rigidparts import RigidPart, Ties

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
    uz : float, callable or None
        The prescribed ``u_z`` on a 3D mesh (callables get (n, 3) points).
    """

    part: str
    ux: Component = None
    uy: Component = None
    uz: Component = None

    def __post_init__(self) -> None:
        if self.ux is None and self.uy is None and self.uz is None:
            raise ValueError(f"displacement on {self.part!r}: give ux, uy or both")

    @property
    def components(self) -> tuple[Component, Component, Component]:
        """``(ux, uy, uz)``."""
        return (self.ux, self.uy, self.uz)

    def describe(self) -> dict[str, object]:
        def desc(c: Component) -> object:
            return getattr(c, "__name__", "callable") if callable(c) else c

        out = {"part": self.part, "ux": desc(self.ux), "uy": desc(self.uy)}
        if self.uz is not None:  # 2D descriptions (and fingerprints) stay as they were
            out["uz"] = desc(self.uz)
        return out


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
        mesh: Mesh | Mesh3D,
        clamped: Sequence[str],
        prescribed: Sequence[Prescribed],
        space: Space | None = None,
        rigid: Sequence[RigidPart] = (),
    ) -> None:
        if space is None:
            space = make_space(mesh) if isinstance(mesh, Mesh3D) else P1Space(mesh)
        self.space: Space = space
        sp_ = self.space
        n = sp_.n_dofs
        #: the dimension d: dof i is component i % d (of a vertex, an edge or a cell)
        self.dim = d = int(sp_.dim)
        comps = [(p.ux, p.uy, p.uz)[:d] for p in prescribed]
        for p in prescribed:
            if d == 2 and p.uz is not None:
                raise ValueError(f"displacement on {p.part!r}: uz is for 3D meshes only")
        clamped = tuple(c for c in clamped if has_part(mesh, c))
        #: the constraining parts: the clamped ones, the prescribed ones, the rigid ones
        self.parts = (*clamped, *(p.part for p in prescribed), *(r.part for r in rigid))
        self.n_clamped = len(clamped)
        owner = -np.ones(n, dtype=np.int64)  # -1 free, else the index in self.parts
        for i, name in enumerate(clamped):
            for dd in sp_.component_dofs(part_facets(mesh, name)):
                owner[dd[owner[dd] < 0]] = i
        # rigid parts (section 1d): their dofs are tied to one master per component; they
        # win over prescribed parts at shared vertices, and may not touch a clamped one
        rigid_dofs = [sp_.component_dofs(part_facets(mesh, r.part)) for r in rigid]
        for r, comp in zip(rigid, rigid_dofs, strict=True):
            hit = np.concatenate(comp)[owner[np.concatenate(comp)] >= 0]
            if len(hit):
                raise ValueError(
                    f"the rigid part {r.part!r} touches the clamped part "
                    f"{self.parts[owner[hit[0]]]!r} (dof {int(hit[0])}, at "
                    f"{sp_.dof_points[hit[0]].tolist()}): a clamped vertex cannot move with "
                    "the rigid part"
                )
        tied = np.zeros(n, dtype=bool)
        for comp in rigid_dofs:
            for dd in comp:
                tied[dd] = True
        for i, pr in enumerate(prescribed):
            comp = sp_.component_dofs(part_facets(mesh, pr.part))
            for dd, spec in zip(comp, comps[i], strict=True):
                if spec is not None:
                    dd = dd[~tied[dd]]
                    owner[dd[owner[dd] < 0]] = self.n_clamped + i
        #: the ties of the rigid parts (None without rigid parts)
        self.ties = (
            Ties(
                tuple(rigid),
                [list(c[:d]) for c in rigid_dofs],
                n,
                sp_.dof_points,
                d * mesh.n_points,
            )
            if rigid
            else None
        )
        self.rigid = tuple(rigid)
        if self.ties is not None:
            first = self.n_clamped + len(prescribed)
            for j, r in enumerate(rigid):
                for c in range(d):
                    if r.component(c)[1] is not None:
                        owner[self.ties.masters[j, c]] = first + j
            tied[self.ties.masters.ravel()] = False  # masters are dofs; slaves are not
            rot = self.ties.rotation_dofs
            tied[rot[rot >= 0]] = False  # nor are the dofs that hold a part's rotation
        #: dofs tied to a rigid part's master (neither free nor constrained)
        self.slaves = np.flatnonzero(tied)
        self.mesh = mesh
        self.prescribed = tuple(prescribed)
        self.dofs = np.flatnonzero(owner >= 0)
        self.owner = owner[self.dofs]
        self.free = np.flatnonzero((owner < 0) & ~tied)
        self.mask = owner >= 0
        self._tied = tied
        self._components = comps
        self.time_dependent = any(callable(c) for cs in comps for c in cs) or bool(
            self.ties is not None and self.ties.time_dependent
        )
        self.zero = all(
            not callable(c) and (c is None or float(c) == 0.0) for cs in comps for c in cs
        ) and all(
            not callable(u) and (u is None or float(u) == 0.0) for r in rigid for u in r.translation
        )

    @property
    def fully_fixed_vertices(self) -> NDArray[np.bool_]:
        """Vertices with all components constrained (they are no contact nodes)."""
        d = self.dim
        fixed = self.mask | self._tied
        if self.ties is not None:  # the masters move with their rigid part
            fixed[self.ties.masters.ravel()] = True
            rot = self.ties.rotation_dofs
            fixed[rot[rot >= 0]] = True
        return np.asarray(fixed[: d * self.mesh.n_points].reshape(-1, d).all(axis=1))

    def values(self, t: float) -> NDArray[np.float64]:
        """The prescribed values at the constrained dofs (``self.dofs``) at time ``t``."""
        out = np.zeros(len(self.dofs))
        if self.zero:
            return out
        for i, pr in enumerate(self.prescribed):
            for c, spec in enumerate(self._components[i]):
                sel = (self.owner == self.n_clamped + i) & (self.dofs % self.dim == c)
                if spec is None or not np.any(sel):
                    continue
                if callable(spec):
                    val = self.space.component_values(self.dofs[sel], spec, t)
                    if not np.all(np.isfinite(val)):
                        name = ("ux", "uy", "uz")[c]
                        raise ValueError(
                            f"displacement on {pr.part!r}: {name} is not finite at t = {t:g}"
                        )
                    out[sel] = val
                else:
                    out[sel] = float(spec)
        first = self.n_clamped + len(self.prescribed)
        for j, r in enumerate(self.rigid):
            for c in range(self.dim):
                u = r.component(c)[1]
                sel = (self.owner == first + j) & (self.dofs % self.dim == c)
                if u is not None and np.any(sel):
                    out[sel] = float(u(t)) if callable(u) else float(u)
        return out

    def rigid_motion_matrix(self, X: NDArray[np.float64], c: NDArray[np.int64]) -> NDArray:
        """The rigid motions at points ``X`` (n, d) in components ``c`` (n,): an (n, 3)
        matrix in 2D (translations in x and y, the rotation about the vertex mean, scaled
        by the mesh size) and (n, 6) in 3D (three translations, three rotations). Its
        columns are the coordinates of :meth:`free_rigid_basis`."""
        P = self.mesh.points
        centre = P.mean(axis=0)
        L = float(np.ptp(P, axis=0).max()) or 1.0
        if self.dim == 3:
            Y = (X - centre) / L
            A = np.zeros((len(c), 6))
            A[np.arange(len(c)), c] = 1.0
            for k in range(3):  # rotation about axis k: e_k x (x - centre)
                rot = np.cross(np.eye(3)[k], Y)
                A[:, 3 + k] = rot[np.arange(len(c)), c]
            return A
        A = np.zeros((len(c), 3))
        A[c == 0, 0] = 1.0
        A[c == 1, 1] = 1.0
        A[:, 2] = np.where(c == 0, -(X[:, 1] - centre[1]), X[:, 0] - centre[0]) / L
        return A

    def free_rigid_basis(self) -> NDArray[np.float64]:
        """An orthonormal basis (r, 3) in 2D or (r, 6) in 3D of the rigid motions the
        constraints leave free, in the coordinates of :meth:`rigid_motion_matrix`: the
        null space of the rigid motions at the constrained dofs (a rigid motion is
        linear, so its dof, a vertex value or a mean over an edge or a cell, is its value
        at the dof's point)."""
        n_rigid = 6 if self.dim == 3 else 3
        if len(self.dofs) == 0 and len(self.slaves) == 0:
            return np.eye(n_rigid)
        pts, d = self.space.dof_points, self.dim
        A = self._motion_rows(self.dofs)
        if self.ties is not None:  # a tie u_s = u_master holds what moves s and its master apart
            s = self.slaves[~self._turning_slaves]
            m = self.ties.master[s]
            # a part that turns about some axes holds the global rotations about the others
            rot = self.ties.rotation_dofs
            held = [
                np.eye(n_rigid)[n_rigid - rot.shape[1] + k]
                for i, pc in enumerate(self.ties.parts)
                if pc.turns
                for k in np.flatnonzero(rot[i] < 0)
            ]
            A = np.vstack(
                [
                    A,
                    self.rigid_motion_matrix(pts[s], s % d)
                    - self.rigid_motion_matrix(pts[m], m % d),
                    *held,
                ]
            )
        return null_space_rows(A)

    def rigid_modes(self, basis: NDArray[np.float64]) -> NDArray[np.float64]:
        """The rigid motions ``basis`` (r, 3 or 6) as dof vectors, (n_dofs, r), in the
        unknowns of the tied system (a part that turns: its translation of its centre
        on its masters, its rotation on its rotation dofs)."""
        return self._motion_rows(np.arange(self.space.n_dofs)) @ basis.T

    @property
    def _turning_slaves(self) -> NDArray[np.bool_]:
        """Which of :attr:`slaves` belong to a rigid part that turns."""
        ties = self.ties
        if ties is None or not ties.turning:
            return np.zeros(len(self.slaves), dtype=bool)
        part_masters = [ties.masters[i] for i, pc in enumerate(ties.parts) if pc.turns]
        return np.isin(ties.master[self.slaves], np.concatenate(part_masters))

    def _motion_rows(self, dofs: NDArray[np.int64]) -> NDArray[np.float64]:
        """:meth:`rigid_motion_matrix` at ``dofs`` in the tied system's unknowns: a
        turning part's masters hold the motion at its centre, its rotation dofs the
        rotation (coordinates 2 in 2D, 3 + k in 3D, over the length scale)."""
        pts, d, ties = self.space.dof_points, self.dim, self.ties
        if ties is None or not ties.turning:
            return self.rigid_motion_matrix(pts[dofs], dofs % d)
        pts = pts.copy()
        for i, pc in enumerate(ties.parts):
            if pc.turns:
                pts[ties.masters[i]] = ties.centres[i]
        A = self.rigid_motion_matrix(pts[dofs], dofs % d)
        L = float(np.ptp(self.mesh.points, axis=0).max()) or 1.0
        first = 2 if d == 2 else 3
        for k, col in enumerate(ties.rotation_dofs.T):
            hit = np.isin(dofs, col[col >= 0])
            if not np.any(hit):
                continue
            A[hit] = 0.0
            A[hit, first + k] = 1.0 / L
        return A

    def free_rigid_motions(self) -> list[str]:
        """The rigid motions the constraints leave free, described in words (empty if
        none): translations in x and y and rotations about a point (3D: the six rigid
        motions, translations along and rotations about axes)."""
        return describe_motions(self.mesh, self.free_rigid_basis())


def describe_motions(mesh: Mesh | Mesh3D, null: NDArray[np.float64]) -> list[str]:
    """Words for the rigid motions spanned by the rows of ``null`` (coordinates of
    :meth:`Constraints.rigid_motion_matrix`)."""
    P = mesh.points
    centre = P.mean(axis=0)
    L = float(np.ptp(P, axis=0).max()) or 1.0
    if len(null) == 0:
        return []
    if P.shape[1] == 3:
        if len(null) == 6:
            return ["the three translations and the three rotations"]
        return [_motion3d(n, centre, L) for n in null]
    if len(null) == 3:
        return ["translations in x and y and the rotation"]
    return [_motion(n, centre, L) for n in null]


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


def _motion3d(n: NDArray[np.float64], centre: NDArray[np.float64], L: float) -> str:
    t, r = n[:3], n[3:]
    if np.linalg.norm(r) < 1e-9 * np.linalg.norm(n):
        a, b, c = (float(x) + 0.0 for x in t / t[np.argmax(np.abs(t))])
        return f"the translation along ({a:.3g}, {b:.3g}, {c:.3g})"
    # u = t + r x (x - centre) / L: the axis r through the point where u is along r
    p = centre + L * np.cross(r, t) / float(r @ r)
    a, b, c = (float(x) + 0.0 for x in r / r[np.argmax(np.abs(r))])
    return (
        f"the rotation about the axis ({a:.3g}, {b:.3g}, {c:.3g}) through "
        f"({p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g})"
    )


def null_space_rows(A: NDArray[np.float64]) -> NDArray[np.float64]:
    """An orthonormal basis of the null space of ``A`` (m, r), as rows (r - rank, r).

    The SVD leaves out the left singular vectors of a tall ``A`` (m rows for the
    constrained dofs or contact nodes, r = 3 or 6): the full (m, m) factor cost
    O(m^2) memory and O(m^3) time (0.5 s of a 2D adaptive run's 4.5 s), and LAPACK's
    ``Vt`` is the same, bit for bit, without it.
    """
    m, r = A.shape
    _, sv, Vt = np.linalg.svd(A, full_matrices=m < r)
    rank = int(np.sum(sv > 1e-10 * max(float(sv.max(initial=0)), 1e-300)))
    return np.asarray(Vt[rank:])
