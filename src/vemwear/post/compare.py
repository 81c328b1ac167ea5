"""Comparison with a reference solution on a nested mesh (Example 5.5): error histories
and convergence orders.

The reference ``(u_ref, w_ref)`` is computed on a finer mesh that is *nested* (every
coarse vertex is a fine vertex, every fine cell lies inside one coarse cell) and on a
finer time grid. Both are compared at the **common time levels** (levels of the coarse
grid that are also levels of the reference grid). The variants (keys of
:attr:`ErrorHistory.displacement` and :attr:`ErrorHistory.wear`; docs/method.md, section 7):

``"H1"`` (the primary displacement error, paper Table 1)
    ``||Pi_h u_h - Pi_ref u_ref||_{H1} / ||Pi_ref u_ref||_{H1}``: each solution projected
    by its own ``Pi`` (3.8)-(3.10) on its own mesh, the difference of the two piecewise
    linear fields integrated exactly over the cells of the reference mesh
    (:func:`~vemwear.post.norms.nested_difference_norms_sq`), full H1 norm.
``"H1semi"``
    The same with the H1 seminorm.
``"H1_coarse"``
    ``||Pi_h(u_h - I_h u_ref)||_{H1} / ||Pi_h I_h u_ref||_{H1}`` on the coarse mesh, with
    ``I_h u_ref`` the reference at the coarse vertices: blind to ``u_ref - I_h u_ref``.
``"H1semi_meanvalue"``
    ``|Pi_ref(P u_h - u_ref)|_{H1} / |Pi_ref u_ref|_{H1}`` with ``P`` the mean value
    prolongation of the coarse vertex values to the reference vertices (:func:`prolongation`).
``"L2"`` (the primary wear error, paper Table 2)
    ``||w_h - w_ref||_{L2(Gamma_C)} / ||w_ref||_{L2(Gamma_C)}``, both piecewise linear along
    Gamma_C, integrated exactly over the reference's contact edges (``w_h`` is linear on
    each of them, :func:`contact_prolongation`).
``"L2_coarse"``, ``"nodal_coarse"``
    ``||w_h - I_h w_ref|| / ||I_h w_ref||`` on the coarse contact edges, exact or with the
    nodal quadrature (:func:`~vemwear.post.norms.contact_l2_norm`).

At a level where the reference norm vanishes (the wear at ``t = 0``) the relative
error is NaN and is skipped by the maxima.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.locate import NonNestedMeshError
from ..mesh.polymesh import Mesh
from ..vem.projection import LinearFields
from .nested_errors import displacement_errors, pairs, wear_errors
from .norms import ProjectedNorms
from .prolong import contact_prolongation, prolongation

if TYPE_CHECKING:
    from ..simulate import Result

__all__ = [
    "DISPLACEMENT_VARIANTS",
    "WEAR_VARIANTS",
    "Comparison",
    "ErrorHistory",
    "NonNestedMeshError",
    "Solution",
    "common_levels",
    "contact_prolongation",
    "convergence_orders",
    "prolongation",
    "solution_errors",
]

#: The displacement and wear variants of :class:`ErrorHistory` (module docstring).
DISPLACEMENT_VARIANTS: tuple[str, ...] = ("H1", "H1semi", "H1_coarse", "H1semi_meanvalue")
WEAR_VARIANTS: tuple[str, ...] = ("L2", "L2_coarse", "nodal_coarse")


@dataclass(frozen=True, eq=False)
class Solution:
    """What the error functionals need of a run.

    Parameters
    ----------
    mesh : Mesh
        The mesh, with its ``contact`` (and ``clamped``) boundary parts.
    t : (L,) array
        Time levels.
    u_levels : (S,) int array
        Levels at which the displacement is stored.
    u : (S, n_points, 2) array
        Displacement at those levels.
    contact_nodes : (m,) int array
        Vertex ids of the contact nodes.
    wear : (L, m) array
        Wear at the contact nodes at every level.
    """

    mesh: Mesh
    t: NDArray[np.float64]
    u_levels: NDArray[np.int64]
    u: NDArray[np.float64]
    contact_nodes: NDArray[np.int64]
    wear: NDArray[np.float64]

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        lv = np.asarray(self.u_levels, dtype=np.int64)
        u = np.asarray(self.u, dtype=float)
        cn = np.asarray(self.contact_nodes, dtype=np.int64)
        w = np.asarray(self.wear, dtype=float)
        if u.shape != (len(lv), self.mesh.n_points, 2):
            raise ValueError(
                f"u must have shape ({len(lv)}, {self.mesh.n_points}, 2), got {u.shape}"
            )
        if w.shape != (len(t), len(cn)):
            raise ValueError(f"wear must have shape ({len(t)}, {len(cn)}), got {w.shape}")
        for name, v in (("t", t), ("u_levels", lv), ("u", u), ("contact_nodes", cn), ("wear", w)):
            object.__setattr__(self, name, v)

    @classmethod
    def from_result(cls, result: Result) -> Solution:
        """The solution of a finished :func:`~vemwear.simulate.simulate` run."""
        return cls(
            mesh=result.problem.mesh,
            t=np.asarray(result.t),
            u_levels=np.asarray(result.u_levels),
            u=np.asarray(result.u),
            contact_nodes=np.asarray(result.contact_nodes),
            wear=np.asarray(result.wear),
        )

    def displacement(self, level: int) -> NDArray[np.float64]:
        """(n_points, 2) displacement at a level (negative counts from the end).

        Raises
        ------
        KeyError
            If the displacement of that level was not stored.
        """
        lv = int(level) % len(self.t)
        where = np.flatnonzero(self.u_levels == lv)
        if where.size == 0:
            raise KeyError(f"the displacement at level {lv} (t = {self.t[lv]:g}) was not stored")
        return self.u[where[0]]

    def arrays(self) -> dict[str, NDArray[Any]]:
        """Plain arrays (the mesh under the names of ``result.npz``), for ``numpy.savez``."""
        m = self.mesh
        return {
            "t": self.t,
            "u_levels": self.u_levels,
            "u": self.u,
            "contact_nodes": self.contact_nodes,
            "wear": self.wear,
            "points": m.points,
            "cells_offsets": m.cell_offsets,
            "cells_vertices": m.cell_vertices,
            "boundary_tags": np.asarray(m.boundary_tags, dtype=np.int8),
        }

    @classmethod
    def from_arrays(cls, data: Any) -> Solution:
        """Inverse of :meth:`arrays`; also reads the arrays of ``result.npz``
        (:func:`~vemwear.post.load_result`), whose ``u_levels`` may be missing (all levels)."""
        from .results import mesh_from_arrays

        mesh = mesh_from_arrays(data)
        if not isinstance(mesh, Mesh):
            raise ValueError("comparing saved results: 2D runs only (this one is 3D)")
        t = np.asarray(data["t"])
        u = np.asarray(data["u"])
        lv = np.asarray(data["u_levels"]) if "u_levels" in data else np.arange(len(u))
        return cls(
            mesh=mesh,
            t=t,
            u_levels=lv,
            u=u,
            contact_nodes=np.asarray(data["contact_nodes"]),
            wear=np.asarray(data["wear"]),
        )


def _solution(s: Solution | Result) -> Solution:
    return s if isinstance(s, Solution) else Solution.from_result(s)


#: Fine cells times levels of one block of :meth:`Comparison.errors`: 1 MB per array.
#: The work is bound by memory traffic, so larger blocks are slower on large reference
#: meshes (Example 5.5's 131,072 cells: blocks of 1 level beat 4, 4 beat 16); on small
#: ones a block holds many levels.
_BLOCK = 2**17


def _stored_at(s: Solution, levels: NDArray[np.int64]) -> NDArray[np.int64]:
    """For every level, the index of its displacement in ``s.u`` (the first), or -1."""
    first: dict[int, int] = {}
    for i, lv in enumerate(s.u_levels.tolist()):
        first.setdefault(int(lv), i)
    return np.array([first.get(lv, -1) for lv in levels.tolist()], dtype=np.int64)


def common_levels(
    t_coarse: ArrayLike, t_ref: ArrayLike, *, rtol: float = 1e-9
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Levels of the coarse grid that are also levels of the reference grid.

    Returns
    -------
    (i_coarse, i_ref) : int arrays of equal length
        ``t_coarse[i_coarse] == t_ref[i_ref]`` up to ``rtol * max(T, 1)``.
    """
    tc = np.asarray(t_coarse, dtype=float)
    tr = np.asarray(t_ref, dtype=float)
    scale = rtol * max(float(np.abs(tr).max(initial=0.0)), 1.0)
    j = np.clip(np.searchsorted(tr, tc), 0, len(tr) - 1)
    jm = np.clip(j - 1, 0, len(tr) - 1)
    jj = np.where(np.abs(tr[jm] - tc) < np.abs(tr[j] - tc), jm, j)
    ok = np.abs(tr[jj] - tc) <= scale
    return np.flatnonzero(ok).astype(np.int64), jj[ok].astype(np.int64)


# ----------------------------------------------------------------------------- histories
@dataclass
class ErrorHistory:
    """Relative errors of a coarse solution against a reference at the common levels.

    Attributes
    ----------
    t : (J,) common times
    levels, ref_levels : (J,) their indices in the coarse and the reference grids
    displacement : dict of str to (J,) arrays
        Relative displacement errors by variant (:data:`DISPLACEMENT_VARIANTS`, module
        docstring); NaN where the coarse or the reference displacement was not stored.
    wear : dict of str to (J,) arrays
        Relative wear errors by variant (:data:`WEAR_VARIANTS`); NaN where the reference
        wear vanishes (``t = 0``).
    absolute : dict of str to (J,) arrays
        The absolute errors, keyed ``"u_<variant>"`` and ``"w_<variant>"``.
    h, k : float
        Coarse mesh size (largest cell diameter) and largest coarse time step.
    """

    t: NDArray[np.float64]
    levels: NDArray[np.int64]
    ref_levels: NDArray[np.int64]
    displacement: dict[str, NDArray[np.float64]]
    wear: dict[str, NDArray[np.float64]]
    absolute: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    h: float = float("nan")
    k: float = float("nan")

    def _series(self, quantity: str, variant: str | None) -> NDArray[np.float64]:
        if quantity in ("u", "displacement"):
            return self.displacement[variant or "H1"]
        if quantity in ("w", "wear"):
            return self.wear[variant or "L2"]
        raise ValueError(f"quantity must be 'displacement' or 'wear', got {quantity!r}")

    def at_T(self, quantity: str, variant: str | None = None) -> float:
        """The relative error at the last common level (``t = T``)."""
        return float(self._series(quantity, variant)[-1])

    def max(self, quantity: str, variant: str | None = None) -> float:
        """The largest relative error over the common levels (NaN entries skipped)."""
        s = self._series(quantity, variant)
        return float(np.nanmax(s)) if np.any(np.isfinite(s)) else float("nan")

    def argmax_time(self, quantity: str, variant: str | None = None) -> float:
        """The time of :meth:`max`."""
        s = self._series(quantity, variant)
        if not np.any(np.isfinite(s)):
            return float("nan")
        return float(self.t[int(np.nanargmax(s))])


class Comparison:
    """Errors of coarse solutions against one reference (nested meshes), for the variants
    of the module docstring; ``Pi`` of the reference mesh and the reference's norms are
    computed once.

    Parameters
    ----------
    reference : Solution or Result
        The reference run; its displacement must be stored at the common levels.
    tol : float, optional
        Tolerance of the nesting checks (:func:`~vemwear.mesh.locate.match_vertices`).
    """

    def __init__(self, reference: Solution | Result, *, tol: float | None = None) -> None:
        self.reference = _solution(reference)
        self.tol = tol
        r = self.reference
        self.fine = ProjectedNorms(r.mesh)
        self._moments = (self.fine.area, self.fine.M1, self.fine.M2)
        self._ref_sq: dict[int, tuple[float, float]] = {}  # level -> (L2^2, H1semi^2)
        self._ref_contact = -np.ones(r.mesh.n_points, dtype=np.int64)
        self._ref_contact[r.contact_nodes] = np.arange(len(r.contact_nodes))

    def _levels(self, c: Solution, levels: str) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        r = self.reference
        ic, ir = common_levels(c.t, r.t)
        if ic.size == 0:
            raise ValueError("the coarse and the reference time grids have no common level")
        if not math.isclose(float(c.t[-1]), float(r.t[-1]), rel_tol=1e-9):
            raise ValueError(
                f"the grids end at different times: T = {c.t[-1]:g} (coarse) and "
                f"{r.t[-1]:g} (reference)"
            )
        if levels == "final":
            if ic[-1] != len(c.t) - 1:
                raise ValueError("t = T is not a common level")
            return ic[-1:], ir[-1:]
        if levels != "common":
            raise ValueError(f"levels must be 'common' or 'final', got {levels!r}")
        return ic, ir

    def _reference_sq(
        self, levels: NDArray[np.int64], fields: LinearFields
    ) -> list[tuple[float, float]]:
        """``(L2^2, H1semi^2)`` of ``Pi_ref u_ref`` at reference levels whose fields (a block
        of :meth:`Projection.many <vemwear.vem.projection.Projection.many>`) are given,
        computed once per level."""
        todo = [i for i, b in enumerate(levels.tolist()) if b not in self._ref_sq]
        if todo:
            f = LinearFields(fields.xbar, fields.value[todo], fields.gradient[todo])
            l2, semi = (x.sum(axis=-1) for x in self.fine.norms_sq(f))
            for i, a, s in zip(todo, l2.tolist(), semi.tolist(), strict=True):
                self._ref_sq[int(levels[i])] = (a, s)
        return [self._ref_sq[b] for b in levels.tolist()]

    def errors(self, coarse: Solution | Result, *, levels: str = "common") -> ErrorHistory:
        """The relative errors of ``coarse`` at the common levels, every variant.

        Parameters
        ----------
        coarse : Solution or Result
            Its displacement stored at the common levels (e.g. ``store="all"``); where it
            is not, the displacement errors are NaN.
        levels : {"common", "final"}
            Every common level, or only ``t = T``.

        Raises
        ------
        NonNestedMeshError
            If the meshes are not nested, or a coarse contact node is not a reference one.
        ValueError
            If the grids have no common level, or do not share ``T``.
        """
        return self.errors_many([coarse], levels=levels)[0]

    def errors_many(
        self,
        runs: Sequence[Solution | Result],
        *,
        levels: str = "common",
        secondary: str = "common",
    ) -> list[ErrorHistory]:
        """:meth:`errors` of several coarse runs, the same numbers, in less time: the
        reference's projection at a level is computed once for all the runs that have
        it, and a mesh nested in a finer run's mesh is located through that mesh
        (:mod:`vemwear.post.nested_errors`).

        Parameters
        ----------
        runs : sequence of Solution or Result
        levels : {"common", "final"}
        secondary : {"common", "final"}
            The secondary displacement variants (``H1_coarse``, ``H1semi_meanvalue``)
            at the levels of ``levels``, or only at ``t = T`` (NaN at the others; the
            mean value variant costs a projection on the reference mesh per level).

        Returns
        -------
        list of ErrorHistory
            In the order of ``runs``.

        Raises
        ------
        NonNestedMeshError, ValueError
            As :meth:`errors`, for the first run concerned.
        """
        r = self.reference
        sols = [_solution(c) for c in runs]
        found = pairs([c.mesh for c in sols], r.mesh, self.tol)
        cmaps = []
        for c, p in zip(sols, found, strict=True):
            cmap = self._ref_contact[p.idx[c.contact_nodes]]
            if np.any(cmap < 0):
                a = int(np.flatnonzero(cmap < 0)[0])
                raise NonNestedMeshError(
                    f"coarse contact node {a} (vertex {int(c.contact_nodes[a])} at "
                    f"{c.mesh.points[c.contact_nodes[a]].tolist()}) is not a contact node "
                    "of the reference"
                )
            cmaps.append(cmap)
            p.ic, p.ir = self._levels(c, levels)
            J = len(p.ic)
            p.disp = {v: np.full(J, np.nan) for v in DISPLACEMENT_VARIANTS}
            p.wear = {v: np.full(J, np.nan) for v in WEAR_VARIANTS}
            p.absolute = {f"u_{v}": np.full(J, np.nan) for v in DISPLACEMENT_VARIANTS}
            p.absolute.update({f"w_{v}": np.full(J, np.nan) for v in WEAR_VARIANTS})
        ref_at = _stored_at(r, np.arange(len(r.t), dtype=np.int64))
        items = [
            (p, ProjectedNorms(c.mesh), c.u, _stored_at(c, p.ic))
            for c, p in zip(sols, found, strict=True)
        ]
        block = max(1, _BLOCK // r.mesh.n_cells)
        displacement_errors(
            items, r.u, ref_at, self.fine, self._reference_sq, block, self.tol, secondary
        )
        out = []
        for c, p, cmap in zip(sols, found, cmaps, strict=True):
            wear_errors(p, c.contact_nodes, c.wear, r.mesh, r.contact_nodes, r.wear, cmap, self.tol)
            k = float(np.diff(c.t).max()) if len(c.t) > 1 else float("nan")
            out.append(
                ErrorHistory(
                    t=c.t[p.ic].copy(),
                    levels=p.ic,
                    ref_levels=p.ir,
                    displacement=p.disp,
                    wear=p.wear,
                    absolute=p.absolute,
                    h=c.mesh.h,
                    k=k,
                )
            )
        return out


def solution_errors(
    coarse: Solution | Result,
    reference: Solution | Result,
    *,
    levels: str = "common",
    tol: float | None = None,
) -> ErrorHistory:
    """Relative errors of ``coarse`` against ``reference`` (nested meshes), every variant.

    A shortcut for ``Comparison(reference, tol=tol).errors(coarse, levels=levels)``; use
    :class:`Comparison` to compare several coarse runs with one reference.
    """
    return Comparison(reference, tol=tol).errors(coarse, levels=levels)


def convergence_orders(
    errors: Sequence[float] | ArrayLike, h: Sequence[float] | ArrayLike | None = None
) -> NDArray[np.float64]:
    """Orders ``log(e_{i-1} / e_i) / log(h_{i-1} / h_i)``; ``log2`` of the ratios if ``h`` is
    omitted (halved mesh sizes). One entry fewer than ``errors``."""
    e = np.asarray(errors, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        num = np.log(e[:-1] / e[1:])
        den = (
            np.log(2.0)
            if h is None
            else np.log(np.asarray(h, float)[:-1] / np.asarray(h, float)[1:])
        )
        return np.asarray(num / den, dtype=float)
