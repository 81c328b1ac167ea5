"""Errors against a reference solution on a nested mesh (design note section 5, Example 5.5).

The reference ``(u_ref, w_ref)`` is computed on a finer mesh whose vertices include
every vertex of the coarse mesh (*nested* meshes) and on a finer time grid. Both are
compared at the **common time levels** (levels of the coarse grid that are also levels
of the reference grid), on the coarse mesh, through the nodal interpolation ``I_h`` of
the reference on the coarse vertices (the coarse vertices are matched to fine vertices
by coordinates with a KD-tree; a coarse vertex without a fine twin is an error,
:class:`NonNestedMeshError`).

Which norm is which
-------------------
``"H1"`` (the default, the paper's Table 1)
    ``||Pi(u_h - I_h u_ref)||_{H1} / ||Pi I_h u_ref||_{H1}``, the full H1 norm (L2 part
    plus gradient part) of the piecewise linear field ``Pi v``, summed over the coarse
    cells. ``Pi`` is the coarse VEM projection (3.8)-(3.10), ``Pi v = vbar + G (x - xbar)``
    on each cell, so on a cell ``||Pi v||^2_{H1(K)} = |K| |G|_F^2 + int_K |Pi v|^2`` and the
    L2 part is integrated exactly with the polygon's moments (fan triangulation from the
    vertex average, signed areas, a rule exact for quadratics).
``"H1semi"``
    The same with the H1 seminorm ``|K| |G|_F^2`` only (no L2 part): the energy-like
    error, insensitive to the constant part of ``Pi`` (the vertex average, 3.9).

The wear error is ``||w_h - I_h w_ref||_{L2(Gamma_C)} / ||I_h w_ref||_{L2(Gamma_C)}`` with
``w`` piecewise linear along Gamma_C, integrated exactly edge by edge over the
contact edges of the coarse mesh (``mesh.part_edges("contact")``); a vertex of a
contact edge that is not a contact node (the end of Gamma_C on the clamped part)
carries ``w = 0``. ``quadrature="nodal"`` gives the nodal-quadrature variant
``sum_a omega_a w_a^2`` (the quadrature of the contact terms, design note section 3).

At a level where the reference norm vanishes (the wear at ``t = 0``) the relative
error is NaN and is skipped by the maxima.

Where the errors are measured
-----------------------------
``on="coarse"`` (the default, design note section 5) is the above. ``on="fine"``
(:meth:`Comparison.errors`) prolongates the coarse solution to the reference mesh
instead (:func:`prolongation`: exact on coarse edges, mean value interpolation of the
vertex values inside coarse cells; :func:`contact_prolongation` for the wear) and
uses ``Pi`` and Gamma_C of the reference mesh: ``||Pi_ref(P u_h - u_ref)|| /
||Pi_ref u_ref||``. This error also contains the interpolation error
``u_ref - I_h u_ref`` of the reference; for Example 5.5 it is 3-4 times the coarse one
and close to the paper's Table 1 (with ``"H1semi"``).

The module also computes errors against a known exact solution
(:func:`exact_errors`, used by :mod:`vemwear.paper.manufactured`) with a degree-5 rule
on the fan triangulation of every cell.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from ..mesh.polymesh import Mesh
from ..vem.assembly import projection_coefficients
from ..vem.local import Fan, fan

if TYPE_CHECKING:
    from ..simulate import Result

__all__ = [
    "DISPLACEMENT_NORMS",
    "Comparison",
    "ErrorHistory",
    "NonNestedMeshError",
    "ProjectedNorms",
    "RelativeError",
    "Solution",
    "common_levels",
    "contact_l2_norm",
    "contact_prolongation",
    "convergence_orders",
    "displacement_error",
    "exact_errors",
    "fan_quadrature",
    "linear_field_norms",
    "locate_cells",
    "match_vertices",
    "polygon_moments",
    "projected_norm",
    "prolongation",
    "solution_errors",
    "wear_error",
]

#: Displacement norms understood by :func:`displacement_error` (see the module docstring).
DISPLACEMENT_NORMS: tuple[str, ...] = ("H1", "H1semi")
WEAR_QUADRATURES: tuple[str, ...] = ("exact", "nodal")


class NonNestedMeshError(ValueError):
    """The coarse mesh has vertices that are not vertices of the fine (reference) mesh."""


class RelativeError(NamedTuple):
    """An error, the norm of the reference and their ratio (NaN if the reference is 0)."""

    error: float
    reference: float
    relative: float


def _ratio(err: float, ref: float) -> RelativeError:
    rel = err / ref if ref > 0 else float("nan")
    return RelativeError(float(err), float(ref), float(rel))


# ----------------------------------------------------------------------------- solutions
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


# ----------------------------------------------------------------------------- matching
def match_vertices(
    coarse_points: ArrayLike, fine_points: ArrayLike, *, tol: float | None = None
) -> NDArray[np.int64]:
    """For every coarse vertex, the index of the fine vertex at the same place.

    Parameters
    ----------
    coarse_points, fine_points : (n, 2) array_like
        Vertex coordinates.
    tol : float, optional
        Largest accepted distance; default ``1e-9`` times the diameter of the bounding
        box of the fine points.

    Returns
    -------
    (n_coarse,) int array

    Raises
    ------
    NonNestedMeshError
        If a coarse vertex has no fine vertex within ``tol``; the message gives the
        number of such vertices and the first of them.
    """
    C = np.asarray(coarse_points, dtype=float)
    F = np.asarray(fine_points, dtype=float)
    if tol is None:
        span = float(np.linalg.norm(F.max(axis=0) - F.min(axis=0))) if len(F) else 1.0
        tol = 1e-9 * max(span, 1e-300)
    dist, idx = cKDTree(F).query(C, k=1)
    bad = np.flatnonzero(~(dist <= tol))
    if bad.size:
        b = int(bad[0])
        raise NonNestedMeshError(
            f"the meshes are not nested: {bad.size} of {len(C)} coarse vertices are not "
            f"vertices of the fine mesh (first: vertex {b} at {C[b].tolist()}, nearest fine "
            f"vertex at distance {float(dist[b]):.3g} > tol {tol:.3g})"
        )
    return np.asarray(idx, dtype=np.int64)


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


# ----------------------------------------------------------------------------- geometry
def _fans(mesh: Mesh) -> Iterator[tuple[NDArray[np.int64], Fan]]:
    """``(cell ids, fan)`` for every group of cells of equal vertex count."""
    for _n, (ids, verts) in mesh.groups.items():
        yield ids, fan(mesh.points[verts])


def polygon_moments(
    mesh: Mesh,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Area, vertex average and first and second moments of every cell about it.

    With ``d = x - xbar``: ``M1 = int_K d dx`` and ``M2 = int_K d d^T dx``, exact, from
    the fan of triangles ``(xbar, x_i, x_{i+1})`` with signed areas (exact for every
    simple polygon, star-shaped with respect to ``xbar`` or not).

    Returns
    -------
    area : (n_cells,) ; xbar : (n_cells, 2) ; M1 : (n_cells, 2) ; M2 : (n_cells, 2, 2)
    """
    nc = mesh.n_cells
    area, xbar = np.zeros(nc), np.zeros((nc, 2))
    M1, M2 = np.zeros((nc, 2)), np.zeros((nc, 2, 2))
    for ids, f in _fans(mesh):
        a, b, A = f.rel, f.rel_next, f.area
        s = a + b
        area[ids] = A.sum(axis=1)
        xbar[ids] = f.xbar
        M1[ids] = np.einsum("mi,mic->mc", A, s) / 3.0
        outer = (
            np.einsum("mic,mid->micd", a, a)
            + np.einsum("mic,mid->micd", b, b)
            + np.einsum("mic,mid->micd", s, s)
        )
        M2[ids] = np.einsum("mi,micd->mcd", A, outer) / 12.0
    return area, xbar, M1, M2


class ProjectedNorms:
    """Fast norms of ``Pi u`` on one mesh, for many fields ``u``.

    ``Pi u`` is linear in ``u``; its coefficients ``(vbar, G)`` on every cell are
    gathered once into a sparse matrix (built by applying
    :func:`~vemwear.vem.projection_coefficients` to unit vectors on a copy of the mesh
    whose cells share no vertex), and the cells' moments are computed once
    (:func:`polygon_moments`). Then every field costs one sparse product.

    Parameters
    ----------
    mesh : Mesh
    """

    def __init__(self, mesh: Mesh) -> None:
        self.mesh = mesh
        self.area, self.xbar, self.M1, self.M2 = polygon_moments(mesh)
        nc = mesh.n_cells
        off = mesh.cell_offsets
        sizes = mesh.cell_sizes
        loose = Mesh(mesh.points[mesh.cell_vertices], off, np.arange(len(mesh.cell_vertices)))
        rows, cols, vals = [], [], []
        out_rows = 6 * np.arange(nc)[:, None] + np.arange(6)[None, :]  # (nc, 6)
        for j in range(int(sizes.max())):
            cells = np.flatnonzero(sizes > j)
            pos = off[cells] + j
            for c in range(2):
                U = np.zeros((len(mesh.cell_vertices), 2))
                U[pos, c] = 1.0
                _xb, vb, G = projection_coefficients(loose, U)
                coef = np.concatenate([vb, G.reshape(nc, 4)], axis=1)[cells]  # (k, 6)
                rows.append(out_rows[cells].ravel())
                cols.append(np.repeat(2 * mesh.cell_vertices[pos] + c, 6))
                vals.append(coef.ravel())
        self.operator = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(6 * nc, 2 * mesh.n_points),
        )
        self.operator.eliminate_zeros()

    def coefficients(self, u: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``vbar`` (n_cells, 2) and ``G`` (n_cells, 2, 2) of ``Pi u``."""
        c = (self.operator @ np.asarray(u, dtype=float).reshape(-1)).reshape(-1, 6)
        return c[:, :2], c[:, 2:].reshape(-1, 2, 2)

    def norms_sq(self, u: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Squared L2 norm and squared H1 seminorm of ``Pi u`` on every cell.

        ``int_K |Pi u|^2 = |K| |vbar|^2 + 2 vbar . G M1 + tr(G M2 G^T)`` (exact) and
        ``|Pi u|^2_{H1(K)} = |K| |G|_F^2``.
        """
        vbar, G = self.coefficients(u)
        return _linear_norms_sq(self.area, self.M1, self.M2, vbar, G)

    def norm(self, u: ArrayLike, norm: str = "H1") -> float:
        """``||Pi u||`` in the norm ``"H1"`` or ``"H1semi"`` (module docstring)."""
        _check_norm(norm)
        return _total(*self.norms_sq(u), norm)


def _check_norm(norm: str) -> None:
    if norm not in DISPLACEMENT_NORMS:
        raise ValueError(f"norm must be one of {DISPLACEMENT_NORMS}, got {norm!r}")


def _total(l2: NDArray[np.float64], semi: NDArray[np.float64], norm: str) -> float:
    """The norm ``"H1"`` or ``"H1semi"`` over the mesh from the squared cell norms."""
    return math.sqrt(float(semi.sum() + (l2.sum() if norm == "H1" else 0.0)))


def _linear_norms_sq(
    area: NDArray[np.float64],
    M1: NDArray[np.float64],
    M2: NDArray[np.float64],
    vbar: NDArray[np.float64],
    G: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Squared L2 norm and H1 seminorm per cell of ``vbar + G (x - xbar)``, from the
    moments about ``xbar`` (:func:`polygon_moments`)."""
    GM1 = np.einsum("kij,kj->ki", G, M1)
    l2 = (
        area * np.sum(vbar**2, axis=1)
        + 2.0 * np.sum(vbar * GM1, axis=1)
        + np.einsum("kij,kjl,kil->k", G, M2, G)
    )
    return np.maximum(l2, 0.0), area * np.sum(G**2, axis=(1, 2))


def linear_field_norms(mesh: Mesh, u: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Squared L2 norm and squared H1 seminorm of ``Pi u`` on every cell.

    ``Pi u = vbar + G (x - xbar)`` (:func:`~vemwear.vem.projection_coefficients`);
    ``int_K |Pi u|^2 = |K| |vbar|^2 + 2 vbar . G M1 + tr(G M2 G^T)`` (exact, with the
    moments of :func:`polygon_moments`) and ``|Pi u|^2_{H1(K)} = |K| |G|_F^2``. For many
    fields on one mesh, :class:`ProjectedNorms` is faster.

    Parameters
    ----------
    mesh : Mesh
    u : (n_points, 2) or (2 n_points,) array_like
        Vertex values (the VEM degrees of freedom).

    Returns
    -------
    l2_sq, semi_sq : (n_cells,) arrays
    """
    # projection_coefficients and polygon_moments both expand about the vertex average
    _xbar, vbar, G = projection_coefficients(mesh, np.asarray(u, dtype=float))
    area, _xbar, M1, M2 = polygon_moments(mesh)
    return _linear_norms_sq(area, M1, M2, vbar, G)


def projected_norm(mesh: Mesh, u: ArrayLike, norm: str = "H1") -> float:
    """``||Pi u||`` over the mesh in the norm ``"H1"`` or ``"H1semi"`` (module docstring)."""
    _check_norm(norm)
    return _total(*linear_field_norms(mesh, u), norm)


def displacement_error(
    mesh: Mesh, u_h: ArrayLike, u_ref: ArrayLike, norm: str = "H1"
) -> RelativeError:
    """``||Pi(u_h - u_ref)|| / ||Pi u_ref||`` on ``mesh`` (``u_ref`` already on its vertices).

    Parameters
    ----------
    mesh : Mesh
        The (coarse) mesh whose projection ``Pi`` is used.
    u_h, u_ref : (n_points, 2) array_like
        Vertex values; ``u_ref`` is typically ``I_h u_ref``, the reference at the
        coarse vertices.
    norm : {"H1", "H1semi"}

    Returns
    -------
    RelativeError
    """
    _check_norm(norm)
    uh = np.asarray(u_h, dtype=float).reshape(mesh.n_points, 2)
    ur = np.asarray(u_ref, dtype=float).reshape(mesh.n_points, 2)
    area, _xbar, M1, M2 = polygon_moments(mesh)  # once for both fields

    def total(v: NDArray[np.float64]) -> float:
        _xb, vbar, G = projection_coefficients(mesh, v)
        return _total(*_linear_norms_sq(area, M1, M2, vbar, G), norm)

    return _ratio(total(uh - ur), total(ur))


def contact_l2_norm(
    mesh: Mesh, contact_nodes: ArrayLike, w: ArrayLike, quadrature: str = "exact"
) -> float:
    """``||w||_{L2(Gamma_C)}`` of the piecewise linear function with nodal values ``w``.

    Parameters
    ----------
    mesh : Mesh
        With its ``contact`` edges.
    contact_nodes : (m,) int array_like
        Vertex ids carrying the values ``w``; other vertices of contact edges (the
        clamped end of Gamma_C) carry 0.
    w : (m,) array_like
    quadrature : {"exact", "nodal"}
        Exact integral of the square of a linear function on every edge,
        ``L (a^2 + a b + b^2) / 3``, or the nodal (trapezoidal) rule ``L (a^2 + b^2) / 2``.
    """
    if quadrature not in WEAR_QUADRATURES:
        raise ValueError(f"quadrature must be one of {WEAR_QUADRATURES}, got {quadrature!r}")
    nodes = np.asarray(contact_nodes, dtype=np.int64)
    wv = np.asarray(w, dtype=float)
    if wv.shape != nodes.shape:
        raise ValueError(f"w has shape {wv.shape}, expected {nodes.shape}")
    full = np.zeros(mesh.n_points)
    full[nodes] = wv
    e = mesh.part_edges("contact")
    L = np.linalg.norm(mesh.points[e[:, 1]] - mesh.points[e[:, 0]], axis=1)
    a, b = full[e[:, 0]], full[e[:, 1]]
    if quadrature == "exact":
        s = L * (a * a + a * b + b * b) / 3.0
    else:
        s = L * (a * a + b * b) / 2.0
    return math.sqrt(float(s.sum()))


def wear_error(
    mesh: Mesh,
    contact_nodes: ArrayLike,
    w_h: ArrayLike,
    w_ref: ArrayLike,
    quadrature: str = "exact",
) -> RelativeError:
    """``||w_h - w_ref||_{L2(Gamma_C)} / ||w_ref||_{L2(Gamma_C)}`` (see :func:`contact_l2_norm`)."""
    wh = np.asarray(w_h, dtype=float)
    wr = np.asarray(w_ref, dtype=float)
    return _ratio(
        contact_l2_norm(mesh, contact_nodes, wh - wr, quadrature),
        contact_l2_norm(mesh, contact_nodes, wr, quadrature),
    )


# ----------------------------------------------------------------------------- histories
@dataclass
class ErrorHistory:
    """Relative errors of a coarse solution against a reference at the common levels.

    Attributes
    ----------
    t : (J,) common times
    levels, ref_levels : (J,) their indices in the coarse and the reference grids
    displacement : dict of str to (J,) arrays
        Relative displacement errors by norm (``"H1"``, ``"H1semi"``); NaN where the
        coarse or the reference displacement was not stored.
    wear : dict of str to (J,) arrays
        Relative wear errors by quadrature (``"exact"``, ``"nodal"``); NaN where the
        reference wear vanishes (``t = 0``).
    absolute : dict of str to (J,) arrays
        The absolute errors, keyed ``"u_H1"``, ``"u_H1semi"``, ``"w_exact"``, ``"w_nodal"``.
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
            return self.wear[variant or "exact"]
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


def _point_segment(
    P: NDArray[np.float64], A: NDArray[np.float64], B: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Distance of points P to segments AB (broadcast) and the parameter s of the foot."""
    d = B - A
    dd = np.maximum(np.sum(d * d, axis=-1), 1e-300)
    s = np.clip(np.sum((P - A) * d, axis=-1) / dd, 0.0, 1.0)
    foot = A + s[..., None] * d
    return np.linalg.norm(P - foot, axis=-1), s


def _vertex_averages(mesh: Mesh) -> NDArray[np.float64]:
    """(n_cells, 2) vertex average of every cell."""
    xbar = np.zeros((mesh.n_cells, 2))
    np.add.at(xbar, mesh.edge_cells, mesh.points[mesh.cell_vertices])
    return xbar / mesh.cell_sizes[:, None]


def _padded_edges(mesh: Mesh) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """(n_cells, n_max) vertex ids ``V`` and ``Vn``: edge ``i`` of a cell runs from
    ``V[:, i]`` to ``Vn[:, i]`` (closing edge last); the lanes past a cell's vertex count
    are degenerate edges ``v_0 -> v_0``, which no point test sees."""
    sizes = mesh.cell_sizes
    lane = np.arange(int(sizes.max()))[None, :]
    pad = np.minimum(lane, sizes[:, None] - 1)
    V = mesh.cell_vertices[mesh.cell_offsets[:-1, None] + pad]
    nxt = np.where(lane < sizes[:, None] - 1, pad + 1, 0)  # edge i: v_i -> v_{i+1 mod n}
    Vn = mesh.cell_vertices[mesh.cell_offsets[:-1, None] + nxt]
    return np.where(lane < sizes[:, None], V, Vn), Vn


def _inside(
    P: NDArray[np.float64], A: NDArray[np.float64], B: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Crossing-number test of the points P (t, 1, 2) in the polygons of edges A -> B
    (t, n, 2)."""
    y = P[..., 1]
    cross = (A[..., 1] > y) != (B[..., 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = A[..., 0] + (y - A[..., 1]) * (B[..., 0] - A[..., 0]) / (B[..., 1] - A[..., 1])
    return np.sum(cross & (P[..., 0] < xint), axis=1) % 2 == 1


def locate_cells(mesh: Mesh, points: ArrayLike, k: int = 12) -> NDArray[np.int64]:
    """The cell containing each point (-1 for points outside the mesh).

    Candidates are the ``k`` cells with the nearest vertex averages (a KD-tree); the
    first candidate that contains the point by the crossing-number test wins. A point
    on cell boundaries (or the domain boundary) that no test claims goes to the
    candidate whose boundary is nearest, within ``1e-9`` of the mesh extent.

    Parameters
    ----------
    mesh : Mesh
    points : (n, 2) array_like
    k : int
        Number of candidate cells per point.

    Returns
    -------
    (n,) int array
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    k = min(int(k), mesh.n_cells)
    _d, cand = cKDTree(_vertex_averages(mesh)).query(pts, k=k)
    cand = np.asarray(cand).reshape(len(pts), k)
    V, Vn = _padded_edges(mesh)
    C = mesh.points
    cell = -np.ones(len(pts), dtype=np.int64)
    for j in range(k):
        todo = np.flatnonzero(cell < 0)
        if todo.size == 0:
            break
        c = cand[todo, j]
        hit = _inside(pts[todo][:, None, :], C[V[c]], C[Vn[c]])
        cell[todo[hit]] = c[hit]
    todo = np.flatnonzero(cell < 0)
    if todo.size:
        P = pts[todo][:, None, :]
        dist = np.stack(
            [
                _point_segment(P, C[V[cand[todo, j]]], C[Vn[cand[todo, j]]])[0].min(axis=1)
                for j in range(k)
            ],
            axis=1,
        )
        best = np.argmin(dist, axis=1)
        tol = 1e-9 * float(np.ptp(mesh.points, axis=0).max())
        ok = dist[np.arange(len(todo)), best] <= tol
        cell[todo[ok]] = cand[todo[ok], best[ok]]
    return cell


def prolongation(
    coarse: Mesh,
    fine_points: ArrayLike,
    *,
    tol: float | None = None,
    candidates: int = 12,
) -> sp.csr_matrix:
    """The linear map from coarse vertex values to values at fine points (nested meshes).

    A VEM function ``v`` of the coarse mesh is known on the cell boundaries (linear on
    every edge) but not inside the cells. The prolongation takes, at a fine point,
    ``v`` itself if the point is a coarse vertex or lies on a coarse edge (linear
    interpolation along the edge, exact), and the mean value interpolant (Floater's
    generalized barycentric coordinates: linear on the edges, exact for linear fields,
    defined on any simple polygon) of the vertex values of the coarse cell containing
    it otherwise. The result is a continuous function of the fine mesh.

    Parameters
    ----------
    coarse : Mesh
    fine_points : (q, 2) array_like
        Points inside the coarse mesh (typically the vertices of a nested fine mesh).
    tol : float, optional
        Distance under which a point is on an edge; default ``1e-9`` times the diameter
        of the bounding box of the coarse mesh.
    candidates : int
        Number of nearest cells (by vertex average) tried for every point.

    Returns
    -------
    (2 q, 2 n_coarse) sparse matrix
        Acting on the interleaved vertex values ``(v_x, v_y)``.

    Raises
    ------
    NonNestedMeshError
        If a point lies in no coarse cell.
    """
    X = np.asarray(fine_points, dtype=float)
    q = len(X)
    C = coarse.points
    if tol is None:
        tol = 1e-9 * max(float(np.linalg.norm(C.max(axis=0) - C.min(axis=0))), 1e-300)
    rows: list[NDArray[np.int64]] = []
    cols: list[NDArray[np.int64]] = []
    vals: list[NDArray[np.float64]] = []

    def add(pts: NDArray[np.int64], verts: NDArray[np.int64], w: NDArray[np.float64]) -> None:
        for c in range(2):
            rows.append(2 * pts + c)
            cols.append(2 * verts + c)
            vals.append(w)

    # 1. coarse vertices
    dist, near = cKDTree(C).query(X, k=1)
    hit = np.flatnonzero(dist <= tol)
    add(hit, near[hit], np.ones(len(hit)))
    # 2. points on a coarse edge or inside a coarse cell
    V, Vn = _padded_edges(coarse)  # (nc, nmax), padded with degenerate edges
    nmax = V.shape[1]
    k = min(int(candidates), coarse.n_cells)
    todo = np.flatnonzero(dist > tol)
    _d, cand = cKDTree(_vertex_averages(coarse)).query(X[todo], k=k)
    cand = np.asarray(cand).reshape(len(todo), k)
    for r in range(k):
        if todo.size == 0:
            break
        cells = cand[:, r]
        P = X[todo][:, None, :]
        A, B = C[V[cells]], C[Vn[cells]]  # (t, nmax, 2): edges A -> B, closing edge last
        de, s = _point_segment(P, A, B)
        j = np.argmin(de, axis=1)
        t_all = np.arange(len(todo))
        on_edge = de[t_all, j] <= tol
        if np.any(on_edge):
            t_ = np.flatnonzero(on_edge)
            sj = s[t_, j[t_]]
            add(todo[t_], V[cells[t_], j[t_]], 1.0 - sj)
            add(todo[t_], Vn[cells[t_], j[t_]], sj)
        inside = _inside(P, A, B) & ~on_edge
        if np.any(inside):
            # mean value coordinates: w_i = (tan(a_{i-1}/2) + tan(a_i/2)) / r_i, with a_i the
            # angle at x of the edge (A_i, B_i); tan(a/2) = cross / (r_A r_B + dot)
            t_ = np.flatnonzero(inside)
            dA, dB = A[t_] - P[t_], B[t_] - P[t_]
            rA, rB = np.linalg.norm(dA, axis=-1), np.linalg.norm(dB, axis=-1)
            cr = dA[..., 0] * dB[..., 1] - dA[..., 1] * dB[..., 0]
            dot = np.sum(dA * dB, axis=-1)
            tan = cr / (rA * rB + dot)  # 0 on degenerate (padded) edges
            w_edge = tan / rA + tan / rB  # contributions to the edge's two ends
            pts = np.repeat(todo[t_], nmax)
            w = np.concatenate([(tan / rA).ravel(), (tan / rB).ravel()])
            tot = np.sum(w_edge, axis=1)
            w = w / np.concatenate([np.repeat(tot, nmax), np.repeat(tot, nmax)])
            add(
                np.concatenate([pts, pts]),
                np.concatenate([V[cells[t_]].ravel(), Vn[cells[t_]].ravel()]),
                w,
            )
        keep = ~(on_edge | inside)
        todo, cand = todo[keep], cand[keep]
    if todo.size:
        b = int(todo[0])
        raise NonNestedMeshError(
            f"{todo.size} fine points lie in none of the {k} nearest coarse cells (first: "
            f"{X[b].tolist()}); are the meshes nested and covering the same domain?"
        )
    M = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * q, 2 * coarse.n_points),
    )
    M.sum_duplicates()
    return M


def contact_prolongation(
    coarse: Mesh, coarse_nodes: ArrayLike, fine_points: ArrayLike, *, tol: float | None = None
) -> sp.csr_matrix:
    """The linear map from wear values at the coarse contact nodes to values at fine points
    on Gamma_C (piecewise linear interpolation along the coarse contact edges; the
    clamped end of Gamma_C carries 0).

    Returns
    -------
    (q, m_coarse) sparse matrix

    Raises
    ------
    NonNestedMeshError
        If a point is on no coarse contact edge.
    """
    X = np.asarray(fine_points, dtype=float)
    nodes = np.asarray(coarse_nodes, dtype=np.int64)
    C = coarse.points
    if tol is None:
        tol = 1e-9 * max(float(np.linalg.norm(C.max(axis=0) - C.min(axis=0))), 1e-300)
    index = -np.ones(coarse.n_points, dtype=np.int64)
    index[nodes] = np.arange(len(nodes))
    e = coarse.part_edges("contact")
    k = min(4, len(e))
    _d, cand = cKDTree(0.5 * (C[e[:, 0]] + C[e[:, 1]])).query(X, k=k)
    cand = np.asarray(cand).reshape(len(X), k)
    de, s = _point_segment(X[:, None, :], C[e[cand, 0]], C[e[cand, 1]])
    j = np.argmin(de, axis=1)
    r = np.arange(len(X))
    if np.any(de[r, j] > tol):
        b = int(np.flatnonzero(de[r, j] > tol)[0])
        raise NonNestedMeshError(f"point {X[b].tolist()} is on no coarse contact edge")
    edge = cand[r, j]
    sj = s[r, j]
    rows, cols, vals = [], [], []
    for end, w in ((0, 1.0 - sj), (1, sj)):
        col = index[e[edge, end]]
        ok = col >= 0  # the clamped end of Gamma_C: w = 0
        rows.append(r[ok])
        cols.append(col[ok])
        vals.append(w[ok])
    M = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(len(X), len(nodes)),
    )
    M.sum_duplicates()
    return M


class Comparison:
    """Errors of coarse solutions against one reference (nested meshes), with the
    reference's norms cached, for the error definitions of the module docstring.

    Parameters
    ----------
    reference : Solution or Result
        The reference run; its displacement must be stored at the common levels.
    tol : float, optional
        Vertex matching tolerance (:func:`match_vertices`).
    """

    def __init__(self, reference: Solution | Result, *, tol: float | None = None) -> None:
        self.reference = _solution(reference)
        self.tol = tol
        self._fine_norms: ProjectedNorms | None = None
        self._fine_ref: dict[int, tuple[float, float]] = {}  # level -> (L2^2, H1semi^2)
        r = self.reference
        self._ref_contact = -np.ones(r.mesh.n_points, dtype=np.int64)
        self._ref_contact[r.contact_nodes] = np.arange(len(r.contact_nodes))

    @property
    def fine_norms(self) -> ProjectedNorms:
        """:class:`ProjectedNorms` of the reference mesh (built on first use)."""
        if self._fine_norms is None:
            self._fine_norms = ProjectedNorms(self.reference.mesh)
        return self._fine_norms

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

    def errors(
        self, coarse: Solution | Result, *, on: str = "coarse", levels: str = "common"
    ) -> ErrorHistory:
        """The relative errors of ``coarse`` at the common levels.

        Parameters
        ----------
        coarse : Solution or Result
            Its displacement stored at the common levels (e.g. ``store="all"``).
        on : {"coarse", "fine"}
            ``"coarse"`` (design note section 5, the default): ``I_h`` of the reference
            on the coarse mesh, ``Pi`` of the coarse mesh. ``"fine"``: the coarse solution
            prolongated to the reference mesh (:func:`prolongation`: exact on coarse
            edges, mean value interpolation of the vertex values inside coarse cells;
            wear linear along the coarse contact edges), ``Pi`` of the reference mesh;
            this includes the interpolation error of the reference, ``u_ref - I_h u_ref``.
        levels : {"common", "final"}
            Every common level, or only ``t = T``.

        Raises
        ------
        NonNestedMeshError
            If the meshes are not nested.
        """
        c, r = _solution(coarse), self.reference
        if on not in ("coarse", "fine"):
            raise ValueError(f"on must be 'coarse' or 'fine', got {on!r}")
        idx = match_vertices(c.mesh.points, r.mesh.points, tol=self.tol)
        cmap = self._ref_contact[idx[c.contact_nodes]]
        if np.any(cmap < 0):
            a = int(np.flatnonzero(cmap < 0)[0])
            raise NonNestedMeshError(
                f"coarse contact node {a} (vertex {int(c.contact_nodes[a])} at "
                f"{c.mesh.points[c.contact_nodes[a]].tolist()}) is not a contact node of the "
                "reference"
            )
        ic, ir = self._levels(c, levels)
        if on == "coarse":
            norms = ProjectedNorms(c.mesh)
        else:
            norms = self.fine_norms
            Pu = prolongation(c.mesh, r.mesh.points, tol=self.tol)
            Pw = contact_prolongation(
                c.mesh, c.contact_nodes, r.mesh.points[r.contact_nodes], tol=self.tol
            )
        J = len(ic)
        disp = {n: np.full(J, np.nan) for n in DISPLACEMENT_NORMS}
        wear = {q: np.full(J, np.nan) for q in WEAR_QUADRATURES}
        absolute = {f"u_{n}": np.full(J, np.nan) for n in DISPLACEMENT_NORMS}
        absolute.update({f"w_{q}": np.full(J, np.nan) for q in WEAR_QUADRATURES})
        c_stored = set(c.u_levels.tolist())
        r_stored = set(r.u_levels.tolist())
        for j, (a, b) in enumerate(zip(ic.tolist(), ir.tolist(), strict=True)):
            if a in c_stored and b in r_stored:
                if on == "coarse":
                    uh, ur = c.displacement(a), r.displacement(b)[idx]
                else:
                    uh = (Pu @ c.displacement(a).ravel()).reshape(-1, 2)
                    ur = r.displacement(b)
                e_l2, e_semi = (float(x.sum()) for x in norms.norms_sq(uh - ur))
                if on == "fine" and b in self._fine_ref:
                    r_l2, r_semi = self._fine_ref[b]
                else:
                    r_l2, r_semi = (float(x.sum()) for x in norms.norms_sq(ur))
                    if on == "fine":
                        self._fine_ref[b] = (r_l2, r_semi)
                for n, e2, r2 in (("H1", e_l2 + e_semi, r_l2 + r_semi), ("H1semi", e_semi, r_semi)):
                    rel = _ratio(math.sqrt(float(e2)), math.sqrt(float(r2)))
                    disp[n][j], absolute[f"u_{n}"][j] = rel.relative, rel.error
            for q in WEAR_QUADRATURES:
                if on == "coarse":
                    e = wear_error(c.mesh, c.contact_nodes, c.wear[a], r.wear[b][cmap], q)
                else:
                    e = wear_error(r.mesh, r.contact_nodes, Pw @ c.wear[a], r.wear[b], q)
                wear[q][j], absolute[f"w_{q}"][j] = e.relative, e.error
        k = float(np.diff(c.t).max()) if len(c.t) > 1 else float("nan")
        return ErrorHistory(
            t=c.t[ic].copy(),
            levels=ic,
            ref_levels=ir,
            displacement=disp,
            wear=wear,
            absolute=absolute,
            h=c.mesh.h,
            k=k,
        )


def solution_errors(
    coarse: Solution | Result,
    reference: Solution | Result,
    *,
    on: str = "coarse",
    levels: str = "common",
    tol: float | None = None,
) -> ErrorHistory:
    """Relative errors of ``coarse`` against ``reference`` (nested meshes, design note 5).

    A shortcut for ``Comparison(reference, tol=tol).errors(coarse, on=on, levels=levels)``;
    use :class:`Comparison` to compare several coarse runs with one reference.

    Parameters
    ----------
    coarse, reference : Solution or Result
        The coarse run (its displacement stored at the common levels, e.g.
        ``store="all"``) and the reference run (its displacement stored at least at
        the common levels).
    on : {"coarse", "fine"}
        Where the errors are measured (:meth:`Comparison.errors`).
    levels : {"common", "final"}
        Every common level, or only ``t = T``.
    tol : float, optional
        Vertex matching tolerance (:func:`match_vertices`).

    Returns
    -------
    ErrorHistory

    Raises
    ------
    NonNestedMeshError
        If a coarse vertex is not a reference vertex, or a coarse contact node is
        not a reference contact node.
    ValueError
        If the grids have no common level, or do not share ``T``.
    """
    return Comparison(reference, tol=tol).errors(coarse, on=on, levels=levels)


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


# ----------------------------------------------------------------------------- exact solutions
# Degree-5 rule on a triangle (7 points, Dunavant), barycentric coordinates and weights.
_D5_A1, _D5_B1, _D5_W1 = 0.0597158717897698, 0.4701420641051151, 0.1323941527885062
_D5_A2, _D5_B2, _D5_W2 = 0.7974269853530873, 0.1012865073234563, 0.1259391805448271
_D5_BARY = np.array(
    [
        [1 / 3, 1 / 3, 1 / 3],
        [_D5_A1, _D5_B1, _D5_B1],
        [_D5_B1, _D5_A1, _D5_B1],
        [_D5_B1, _D5_B1, _D5_A1],
        [_D5_A2, _D5_B2, _D5_B2],
        [_D5_B2, _D5_A2, _D5_B2],
        [_D5_B2, _D5_B2, _D5_A2],
    ]
)
_D5_W = np.array([0.225, _D5_W1, _D5_W1, _D5_W1, _D5_W2, _D5_W2, _D5_W2])


def fan_quadrature(
    mesh: Mesh,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """A degree-5 quadrature on every cell: 7 points on each triangle of the fan
    ``(xbar, x_i, x_{i+1})`` from the vertex average, with signed weights (valid for
    any simple polygon).

    Returns
    -------
    points : (Q, 2) ; weights : (Q,) ; cell : (Q,) int (the cell of each point)
    """
    P, W, C = [], [], []
    for ids, f in _fans(mesh):
        c = f.xbar[None, :, None, :]
        pts = (
            _D5_BARY[:, 0, None, None, None] * c
            + _D5_BARY[:, 1, None, None, None] * f.X[None]
            + _D5_BARY[:, 2, None, None, None] * f.X_next[None]
        )  # (7, m, n, 2)
        w = _D5_W[:, None, None] * f.area[None]  # (7, m, n)
        P.append(pts.reshape(-1, 2))
        W.append(w.ravel())
        C.append(np.broadcast_to(ids[None, :, None], w.shape).ravel())
    return np.concatenate(P), np.concatenate(W), np.concatenate(C).astype(np.int64)


def exact_errors(
    mesh: Mesh,
    u_h: ArrayLike,
    u: Callable[[NDArray[np.float64]], NDArray[np.float64]],
    grad_u: Callable[[NDArray[np.float64]], NDArray[np.float64]],
) -> dict[str, float]:
    """Errors of a discrete displacement against an exact one.

    Parameters
    ----------
    mesh : Mesh
    u_h : (n_points, 2) array_like
        Vertex values of the discrete solution.
    u : callable
        ``u(x)`` for ``x`` of shape (q, 2), returning (q, 2).
    grad_u : callable
        ``grad_u(x)`` returning (q, 2, 2) with ``[:, i, j] = d_j u_i``.

    Returns
    -------
    dict
        ``L2``: ``||Pi u_h - u||_{L2}``; ``H1semi``: ``||grad(Pi u_h) - grad u||_{L2}``
        (cell by cell); ``nodal``: the discrete L2 norm ``(sum_K |K| mean_{x_i in K}
        |u_h(x_i) - u(x_i)|^2)^{1/2}`` of the nodal errors; and the norms ``L2_u``,
        ``H1semi_u`` of ``u`` (same quadrature) for relative errors. All with the
        degree-5 rule of :func:`fan_quadrature`.
    """
    U = np.asarray(u_h, dtype=float).reshape(mesh.n_points, 2)
    xbar, vbar, G = projection_coefficients(mesh, U)
    x, w, cell = fan_quadrature(mesh)
    pi = vbar[cell] + np.einsum("qij,qj->qi", G[cell], x - xbar[cell])
    ue = np.asarray(u(x), dtype=float)
    ge = np.asarray(grad_u(x), dtype=float)
    l2 = float(np.sum(w * np.sum((pi - ue) ** 2, axis=1)))
    h1 = float(np.sum(w * np.sum((G[cell] - ge) ** 2, axis=(1, 2))))
    l2u = float(np.sum(w * np.sum(ue**2, axis=1)))
    h1u = float(np.sum(w * np.sum(ge**2, axis=(1, 2))))
    nod_err = np.sum((U - np.asarray(u(mesh.points), dtype=float)) ** 2, axis=1)
    per_cell = (
        np.bincount(mesh.edge_cells, weights=nod_err[mesh.cell_vertices], minlength=mesh.n_cells)
        / mesh.cell_sizes
    )
    nodal = float(np.sum(mesh.cell_areas * per_cell))
    return {
        "L2": math.sqrt(max(l2, 0.0)),
        "H1semi": math.sqrt(max(h1, 0.0)),
        "nodal": math.sqrt(nodal),
        "L2_u": math.sqrt(l2u),
        "H1semi_u": math.sqrt(h1u),
    }
