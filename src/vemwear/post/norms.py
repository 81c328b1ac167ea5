"""Norms of projected displacements and of the wear, and errors against exact solutions.

Which norm is which (docs/method.md, section 7; paper Example 5.5)
------------------------------------------------------------------
``"H1"``
    The full H1 norm (L2 part plus gradient part) of the piecewise linear field
    ``Pi v`` (:class:`~vemwear.vem.projection.Projection`, (3.8)-(3.10)): on a cell,
    ``Pi v = value + G (x - xbar)`` and ``||Pi v||^2_{H1(K)} = int_K |Pi v|^2 + |K| |G|_F^2``,
    the L2 part integrated exactly with the cell's moments
    (:func:`~vemwear.vem.quadrature.polygon_moments`).
``"H1semi"``
    The gradient part only, ``|K| |G|_F^2``: insensitive to the value at the vertex
    average (3.9).

:func:`nested_difference_norms_sq` gives these norms for the difference of two such
fields on two nested meshes, cell by cell of the fine one (exact: on a fine cell both
fields are linear).

The wear norm is ``||w||_{L2(Gamma_C)}`` of the function that is linear on every contact
edge with the nodal values ``w`` (:func:`contact_l2_norm`); a vertex of a contact edge that
is not a contact node (the end of Gamma_C on the clamped part) carries ``w = 0``.
``quadrature="nodal"`` gives the nodal-quadrature variant ``sum_a weights_a w_a^2`` (the
quadrature of the contact terms).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh
from ..vem.dofs2 import edge_ids
from ..vem.projection import LinearFields, Projection
from ..vem.quadrature import polygon_moments, polygon_quadrature

__all__ = [
    "DISPLACEMENT_NORMS",
    "WEAR_QUADRATURES",
    "ProjectedNorms",
    "RelativeError",
    "contact_l2_norm",
    "displacement_error",
    "exact_errors",
    "linear_norms_sq",
    "linear_seminorms_sq",
    "nested_difference_norms_sq",
    "nested_offsets",
    "projected_norm",
    "relative_error",
    "wear_error",
]

#: Displacement norms (module docstring).
DISPLACEMENT_NORMS: tuple[str, ...] = ("H1", "H1semi")
#: Quadratures of :func:`contact_l2_norm`.
WEAR_QUADRATURES: tuple[str, ...] = ("exact", "nodal")


class RelativeError(NamedTuple):
    """An error, the norm of the reference and their ratio (NaN if the reference is 0)."""

    error: float
    reference: float
    relative: float


def relative_error(err: float, ref: float) -> RelativeError:
    """``RelativeError(err, ref, err / ref)``, the ratio NaN if ``ref`` is not positive."""
    rel = err / ref if ref > 0 else float("nan")
    return RelativeError(float(err), float(ref), float(rel))


def check_norm(norm: str) -> None:
    """Raise ``ValueError`` unless ``norm`` is one of :data:`DISPLACEMENT_NORMS`."""
    if norm not in DISPLACEMENT_NORMS:
        raise ValueError(f"norm must be one of {DISPLACEMENT_NORMS}, got {norm!r}")


def total_norm(l2_sq: NDArray[np.float64], semi_sq: NDArray[np.float64], norm: str) -> float:
    """The norm ``"H1"`` or ``"H1semi"`` over a mesh from the squared cell norms."""
    check_norm(norm)
    return math.sqrt(float(semi_sq.sum() + (l2_sq.sum() if norm == "H1" else 0.0)))


def linear_norms_sq(
    area: NDArray[np.float64],
    M1: NDArray[np.float64],
    M2: NDArray[np.float64],
    c: NDArray[np.float64],
    D: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Squared L2 norm and H1 seminorm per cell of ``c + D (x - xbar)``.

    ``int_K |c + D d|^2 = |K| |c|^2 + 2 c . D M1 + tr(D M2 D^T)`` with the moments about
    ``xbar`` (:func:`~vemwear.vem.quadrature.polygon_moments`), and ``|K| |D|_F^2``.
    ``c`` (cells, 2) and ``D`` (cells, 2, 2) may carry a leading axis of fields (then the
    results are (fields, cells)).
    """
    return _norms_sq(area, M1, M2, c[..., 0], c[..., 1], *_entries(D))


def _entries(D: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """``D[..., 0, 0], D[..., 0, 1], D[..., 1, 0], D[..., 1, 1]``."""
    return D[..., 0, 0], D[..., 0, 1], D[..., 1, 0], D[..., 1, 1]


def _norms_sq(
    area: NDArray[np.float64],
    M1: NDArray[np.float64],
    M2: NDArray[np.float64],
    *cD: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`linear_norms_sq` of the components ``c0, c1, D00, D01, D10, D11``."""
    # written out component by component: much faster than einsum or sums over axes of
    # length 2 on many small matrices
    c0, c1, a00, a01, a10, a11 = cD
    m0, m1 = M1[:, 0], M1[:, 1]
    s00, s01, s11 = M2[:, 0, 0], M2[:, 0, 1], M2[:, 1, 1]
    cDM1 = c0 * (a00 * m0 + a01 * m1) + c1 * (a10 * m0 + a11 * m1)
    col0, col1, semi = _gradient_squares(area, a00, a01, a10, a11)
    quad = s00 * col0 + s11 * col1 + 2.0 * s01 * (a00 * a01 + a10 * a11)  # tr(D M2 D^T)
    l2 = area * (c0 * c0 + c1 * c1) + 2.0 * cDM1 + quad
    return np.maximum(l2, 0.0), semi


def linear_seminorms_sq(area: NDArray[np.float64], D: NDArray[np.float64]) -> NDArray[np.float64]:
    """The squared H1 seminorm per cell of ``c + D (x - xbar)``, ``|K| |D|_F^2``: the
    second part of :func:`linear_norms_sq` without the L2 part."""
    return _gradient_squares(area, *_entries(D))[2]


def _gradient_squares(
    area: NDArray[np.float64], *D: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The squared lengths of the columns of every ``D`` (its entries ``D00, D01, D10,
    D11``) and ``|K| |D|_F^2``."""
    a00, a01, a10, a11 = D
    col0, col1 = a00 * a00 + a10 * a10, a01 * a01 + a11 * a11
    return col0, col1, area * (col0 + col1)


class ProjectedNorms:
    """Norms of ``Pi u`` on one mesh, for many fields ``u``.

    The projection (:class:`~vemwear.vem.projection.Projection`) and the cells' moments
    are computed once; every field then costs one sparse product.

    Parameters
    ----------
    mesh : Mesh
    projection : Projection, optional
        ``Pi`` of ``mesh``, if already built.
    """

    def __init__(self, mesh: Mesh, projection: Projection | None = None) -> None:
        self.mesh = mesh
        self.projection = Projection(mesh) if projection is None else projection
        self.area, self.xbar, self.M1, self.M2 = polygon_moments(mesh)

    def fields(self, u: ArrayLike) -> LinearFields:
        """``Pi u`` on every cell."""
        return self.projection(u)

    def norms_sq(
        self, u: ArrayLike | LinearFields
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Squared L2 norm and squared H1 seminorm of ``Pi u`` on every cell (``u`` the dofs
        or ``Pi u`` itself; for a block of fields of :meth:`Projection.many
        <vemwear.vem.projection.Projection.many>`, (fields, cells) arrays)."""
        f = u if isinstance(u, LinearFields) else self.projection(u)
        return linear_norms_sq(self.area, self.M1, self.M2, f.value, f.gradient)

    def seminorms_sq(self, u: ArrayLike | LinearFields) -> NDArray[np.float64]:
        """The second part of :meth:`norms_sq` alone: the squared H1 seminorm of ``Pi u``
        on every cell."""
        f = u if isinstance(u, LinearFields) else self.projection(u)
        return linear_seminorms_sq(self.area, f.gradient)

    def norm(self, u: ArrayLike | LinearFields, norm: str = "H1") -> float:
        """``||Pi u||`` in the norm ``"H1"`` or ``"H1semi"`` (module docstring)."""
        return total_norm(*self.norms_sq(u), norm)


def projected_norm(mesh: Mesh, u: ArrayLike, norm: str = "H1") -> float:
    """``||Pi u||`` over the mesh in the norm ``"H1"`` or ``"H1semi"`` (module docstring)."""
    return ProjectedNorms(mesh).norm(u, norm)


def displacement_error(
    mesh: Mesh, u_h: ArrayLike, u_ref: ArrayLike, norm: str = "H1"
) -> RelativeError:
    """``||Pi(u_h - u_ref)|| / ||Pi u_ref||`` on ``mesh`` (both given by their vertex values).

    Parameters
    ----------
    mesh : Mesh
        The mesh whose projection ``Pi`` is used.
    u_h, u_ref : (n_points, 2) array_like
        Vertex values.
    norm : {"H1", "H1semi"}
    """
    check_norm(norm)
    pn = ProjectedNorms(mesh)
    uh = np.asarray(u_h, dtype=float).reshape(-1)
    ur = np.asarray(u_ref, dtype=float).reshape(-1)
    return relative_error(pn.norm(uh - ur, norm), pn.norm(ur, norm))


def nested_difference_norms_sq(
    coarse: LinearFields,
    fine: LinearFields,
    cells: NDArray[np.int64],
    moments: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
    offsets: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Squared L2 norm and H1 seminorm, per fine cell, of ``coarse - fine``.

    On fine cell k, inside coarse cell ``K = cells[k]``, both fields are linear:
    ``coarse - fine = c + D (x - xbar_k)`` with ``c = value_K + G_K (xbar_k - xbar_K) -
    value_k`` and ``D = G_K - G_k``, integrated exactly with the fine cell's moments.

    Parameters
    ----------
    coarse, fine : LinearFields
        Linear fields per cell of the two meshes (e.g. ``Pi_h u_h`` and ``Pi_ref u_ref``),
        one each, or blocks of as many fields each (:meth:`Projection.many
        <vemwear.vem.projection.Projection.many>`; then the results are (fields, cells)).
    cells : (n_fine_cells,) int array
        The coarse cell of every fine cell (:func:`vemwear.mesh.nested_cells`).
    moments : (area, M1, M2)
        Of the fine cells about their vertex averages (``fine.xbar``),
        :func:`~vemwear.vem.quadrature.polygon_moments`.
    offsets : (dx0, dx1), optional
        The components of ``fine.xbar - coarse.xbar[cells]``, contiguous (computed if
        not given; the same for every field of the two meshes).
    """
    area, M1, M2 = moments
    dx0, dx1 = nested_offsets(coarse.xbar, fine.xbar, cells) if offsets is None else offsets

    def at(x: NDArray[np.float64]) -> NDArray[np.float64]:  # coarse cell values -> fine cells
        return np.take(x, cells, axis=-1)

    # entry by entry (contiguous for the blocks of Projection.many): c_i = value_i +
    # G_i0 dx_0 + G_i1 dx_1 - value_k,i and D_ij = G_ij - G_k,ij
    G = [at(g) for g in _entries(coarse.gradient)]
    c = [
        at(coarse.value[..., i]) + G[2 * i] * dx0 + G[2 * i + 1] * dx1 - fine.value[..., i]
        for i in range(2)
    ]
    D = [g - f for g, f in zip(G, _entries(fine.gradient), strict=True)]
    return _norms_sq(area, M1, M2, *c, *D)


def nested_offsets(
    coarse_xbar: NDArray[np.float64], fine_xbar: NDArray[np.float64], cells: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The components of ``fine_xbar - coarse_xbar[cells]`` (contiguous): the offsets of
    :func:`nested_difference_norms_sq`."""
    dx = fine_xbar - coarse_xbar[cells]
    return np.ascontiguousarray(dx[:, 0]), np.ascontiguousarray(dx[:, 1])


def contact_l2_norm(
    mesh: Mesh, contact_nodes: ArrayLike, w: ArrayLike, quadrature: str = "exact"
) -> float:
    """``||w||_{L2(Gamma_C)}`` of the piecewise linear function with nodal values ``w``
    (piecewise quadratic for the contact nodes of k = 2, vertices and edge midpoints).

    Parameters
    ----------
    mesh : Mesh
        With its ``contact`` edges.
    contact_nodes : (m,) int array_like
        Vertex ids carrying the values ``w`` (k = 2: ``n_points + e`` the midpoint of
        the edge ``mesh.edges[e]``); other nodes of contact edges (the clamped end of
        Gamma_C) carry 0.
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
    n = mesh.n_points
    full = np.zeros(n + (len(mesh.edges) if np.any(nodes >= n) else 0))
    full[nodes] = wv
    e = mesh.part_edges("contact")
    L = np.linalg.norm(mesh.points[e[:, 1]] - mesh.points[e[:, 0]], axis=1)
    a, b = full[e[:, 0]], full[e[:, 1]]
    if len(full) > n:  # k = 2: nodes n + i are the midpoints of mesh.edges[i]; quadratic w
        c = full[n + edge_ids(mesh, e[:, 0], e[:, 1])]
        if quadrature == "exact":  # the P2 mass matrix L / 30 [[4, 2, -1], [2, 16, 2], ...]
            s = L * (4 * a * a + 16 * c * c + 4 * b * b + 4 * a * c + 4 * c * b - 2 * a * b) / 30
        else:  # Simpson's rule, the contact quadrature of k = 2
            s = L * (a * a + 4 * c * c + b * b) / 6.0
        return math.sqrt(float(s.sum()))
    s = L * (a * a + a * b + b * b) / 3.0 if quadrature == "exact" else L * (a * a + b * b) / 2.0
    return math.sqrt(float(s.sum()))


def wear_error(
    mesh: Mesh,
    contact_nodes: ArrayLike,
    w_h: ArrayLike,
    w_ref: ArrayLike,
    quadrature: str = "exact",
) -> RelativeError:
    """``||w_h - w_ref||_{L2(Gamma_C)} / ||w_ref||_{L2(Gamma_C)}`` (:func:`contact_l2_norm`),
    both given at the contact nodes of ``mesh``."""
    wh = np.asarray(w_h, dtype=float)
    wr = np.asarray(w_ref, dtype=float)
    return relative_error(
        contact_l2_norm(mesh, contact_nodes, wh - wr, quadrature),
        contact_l2_norm(mesh, contact_nodes, wr, quadrature),
    )


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
        degree-5 rule of :func:`~vemwear.vem.quadrature.polygon_quadrature`.
    """
    U = np.asarray(u_h, dtype=float).reshape(mesh.n_points, 2)
    pi = Projection(mesh)(U)
    x, w, cell = polygon_quadrature(mesh, 5)
    pix = pi.at(x, cell)
    G = pi.gradient[cell]
    ue = np.asarray(u(x), dtype=float)
    ge = np.asarray(grad_u(x), dtype=float)
    l2 = float(np.sum(w * np.sum((pix - ue) ** 2, axis=1)))
    h1 = float(np.sum(w * np.sum((G - ge) ** 2, axis=(1, 2))))
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
