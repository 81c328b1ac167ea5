"""Quadrature on polygons and edges: the fan of triangles, triangle rules, cell means, moments.

Every cell is split into the fan of triangles ``(xbar, x_i, x_{i+1})`` from its vertex
average ``xbar`` (3.9). With *signed* triangle areas, sums over the fan integrate exactly
over any simple polygon, star-shaped with respect to ``xbar`` or not (the parts outside
the cell cancel). A triangle rule exact for degree ``d`` thus gives a polygon rule exact
for degree ``d``; the rules here are the degree-2 rule of the loads (Section 3.3) and the
degree-5 rule of the errors against exact solutions. Work is batched by vertex count
(:attr:`vemwear.mesh.Mesh.groups`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.polymesh import Mesh

__all__ = [
    "GAUSS2",
    "TRIANGLE_RULES",
    "Fan",
    "Field",
    "cell_means",
    "eval_field",
    "fan",
    "polygon_moments",
    "polygon_quadrature",
]

#: A vector field given as a constant 2-vector or a callable ``f(x, t)`` on (m, 2) points.
Field = ArrayLike | Callable[[NDArray[np.float64], float], ArrayLike]

#: Two-point Gauss rule on [0, 1] (the parameter along an edge; weights 1/2 each):
#: exact for cubics, so for a linear load times a linear test function.
GAUSS2 = np.array([0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0)])

_D5_A1, _D5_B1, _D5_W1 = 0.0597158717897698, 0.4701420641051151, 0.1323941527885062
_D5_A2, _D5_B2, _D5_W2 = 0.7974269853530873, 0.1012865073234563, 0.1259391805448271

#: Triangle rules by degree of exactness: ``(barycentric coordinates (q, 3), weights (q,))``
#: with weights summing to 1 (multiply by the area). Degree 2: the edge midpoints; degree
#: 5: Dunavant's 7-point rule.
TRIANGLE_RULES: dict[int, tuple[NDArray[np.float64], NDArray[np.float64]]] = {
    2: (np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]]), np.full(3, 1.0 / 3.0)),
    5: (
        np.array(
            [
                [1 / 3, 1 / 3, 1 / 3],
                [_D5_A1, _D5_B1, _D5_B1],
                [_D5_B1, _D5_A1, _D5_B1],
                [_D5_B1, _D5_B1, _D5_A1],
                [_D5_A2, _D5_B2, _D5_B2],
                [_D5_B2, _D5_A2, _D5_B2],
                [_D5_B2, _D5_B2, _D5_A2],
            ]
        ),
        np.array([0.225, _D5_W1, _D5_W1, _D5_W1, _D5_W2, _D5_W2, _D5_W2]),
    ),
}


class Fan(NamedTuple):
    """The fan of triangles ``(xbar, x_i, x_{i+1})`` of a batch of ``m`` cells with ``n``
    vertices each (counter-clockwise)."""

    X: NDArray[np.float64]  # (m, n, 2) vertices x_i
    X_next: NDArray[np.float64]  # (m, n, 2) vertices x_{i+1}
    xbar: NDArray[np.float64]  # (m, 2) vertex averages
    rel: NDArray[np.float64]  # (m, n, 2) x_i - xbar
    rel_next: NDArray[np.float64]  # (m, n, 2) x_{i+1} - xbar
    area: NDArray[np.float64]  # (m, n) signed areas of the triangles

    def points(self, degree: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The points and weights of the triangle rule of ``degree`` on every triangle.

        Returns
        -------
        points : (m, n * q, 2) array
        weights : (m, n * q) array, signed (they sum to the cell areas)
        """
        bary, w = _rule(degree)
        pts = (
            bary[:, 0, None, None, None] * self.xbar[None, :, None, :]
            + bary[:, 1, None, None, None] * self.X[None]
            + bary[:, 2, None, None, None] * self.X_next[None]
        )  # (q, m, n, 2)
        m = len(self.xbar)
        wt = w[:, None, None] * self.area[None]  # (q, m, n)
        return (
            pts.transpose(1, 0, 2, 3).reshape(m, -1, 2),
            wt.transpose(1, 0, 2).reshape(m, -1),
        )


def _rule(degree: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    if degree not in TRIANGLE_RULES:
        raise ValueError(
            f"no triangle rule of degree {degree}; available: {sorted(TRIANGLE_RULES)}"
        )
    return TRIANGLE_RULES[degree]


def fan(X: NDArray[np.float64]) -> Fan:
    """The fan of triangles of a batch of cells with vertex coordinates X (m, n, 2)."""
    xbar = X.mean(axis=1)
    a = X - xbar[:, None, :]
    b = np.roll(a, -1, axis=1)
    area = 0.5 * (a[..., 0] * b[..., 1] - b[..., 0] * a[..., 1])
    return Fan(X, np.roll(X, -1, axis=1), xbar, a, b, area)


def eval_field(f: Field, x: NDArray[np.float64], t: float, name: str) -> NDArray[np.float64]:
    """The values (len(x), 2) of a :data:`Field` at the points ``x`` and time ``t``.

    Raises
    ------
    ValueError
        If the field does not give one 2-vector per point; the message names ``name``.
    """
    if callable(f):
        v = np.asarray(f(x, t), dtype=float)
        v = np.broadcast_to(v, (len(x), 2)) if v.shape == (2,) else v
    else:
        v = np.broadcast_to(np.asarray(f, dtype=float), (len(x), 2))
    if v.shape != (len(x), 2):
        raise ValueError(f"{name} must give a 2-vector per point, got shape {v.shape}")
    return v


def cell_means(mesh: Mesh, f: Field, t: float = 0.0, name: str = "f") -> NDArray[np.float64]:
    """``P_0^K f`` for every cell (Section 3.3): the cell mean, by the degree-2 rule on the
    fan (exact for quadratic f on any simple cell).

    Returns
    -------
    (n_cells, 2) array
    """
    out = np.zeros((mesh.n_cells, 2))
    if not callable(f):
        out[:] = eval_field(f, np.zeros((1, 2)), t, name)[0]
        return out
    for _n, (ids, verts) in mesh.groups.items():
        fn = fan(mesh.points[verts])
        pts, w = fn.points(2)
        val = eval_field(f, pts.reshape(-1, 2), t, name).reshape(pts.shape)
        out[ids] = np.einsum("mq,mqc->mc", w, val) / fn.area.sum(axis=1)[:, None]
    return out


def polygon_quadrature(
    mesh: Mesh, degree: int = 5
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """A quadrature on every cell, exact for polynomials of ``degree``: the triangle rule
    on every triangle of the fan, with signed weights (valid for any simple polygon).

    Returns
    -------
    points : (Q, 2) ; weights : (Q,) ; cell : (Q,) int (the cell of each point)
    """
    P, W, C = [], [], []
    for _n, (ids, verts) in mesh.groups.items():
        pts, w = fan(mesh.points[verts]).points(degree)
        P.append(pts.reshape(-1, 2))
        W.append(w.ravel())
        C.append(np.repeat(ids, w.shape[1]))
    return np.concatenate(P), np.concatenate(W), np.concatenate(C).astype(np.int64)


def polygon_moments(
    mesh: Mesh,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Area, vertex average and first and second moments of every cell about it.

    With ``d = x - xbar``: ``M1 = int_K d dx`` and ``M2 = int_K d d^T dx``, exact, from the
    fan with signed areas (on a triangle with vertices ``0, a, b`` relative to ``xbar``:
    ``int d = A (a + b) / 3`` and ``int d d^T = A (a a^T + b b^T + (a + b)(a + b)^T) / 12``).
    So ``int_K |c + D d|^2 = |K| |c|^2 + 2 c . D M1 + tr(D M2 D^T)`` exactly.

    Returns
    -------
    area : (n_cells,) ; xbar : (n_cells, 2) ; M1 : (n_cells, 2) ; M2 : (n_cells, 2, 2)
    """
    nc = mesh.n_cells
    area, xbar = np.zeros(nc), np.zeros((nc, 2))
    M1, M2 = np.zeros((nc, 2)), np.zeros((nc, 2, 2))
    for _n, (ids, verts) in mesh.groups.items():
        f = fan(mesh.points[verts])
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
