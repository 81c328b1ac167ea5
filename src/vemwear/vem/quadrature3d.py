"""Geometry and quadrature on polyhedral meshes (3D, :class:`~vemwear.mesh.polyhedra.Mesh3D`).

Faces (docs/method.md, "3D (k = 1)"). Every face F with the vertex loop
``x_1, ..., x_n`` is split into the fan of triangles ``(xbar_F, x_i, x_{i+1})`` through its
vertex average ``xbar_F``. Their vector areas sum to the face's vector area
``|F| nu_F`` (``nu_F`` its right-hand unit normal), their centroids weighted by their signed
areas give the face centroid ``c_F``. The *face vertex weights* ``w_i^F`` are the weights of
the rule ``int_F v ds = sum_i w_i^F v(x_i)``:

* ``"enhanced"`` (the default): ``w_i^F = |F| / n + (c_F - xbar_F) . q_i^F`` with the
  in-plane vertex normal weights ``q_i^F = (|e_{i-1}| m_{i-1} + |e_i| m_i) / 2`` (``m`` the
  outward unit normal of an edge in the plane of F). This is ``int_F Pi_F v`` with
  ``Pi_F v = vbar_F + grad_F v . (x - xbar_F)`` the face's k = 1 projection, its gradient
  ``|F|^-1 int_dF v m`` exact from the edges: the integral of v itself over the enhanced
  face space (Ahmad et al. 2013; Beirão da Veiga, Dassi, Russo 2017, lowest order).
* ``"fan"``: the integral of the piecewise linear interpolant on the fan, with the
  vertex average of the values at ``xbar_F``:
  ``w_i^F = (a_{i-1} + a_i) / 3 + |F| / (3 n)``, ``a_i`` the signed area of triangle i.

Both are exact for every linear field on a planar face (a linear v has its value at
``xbar_F`` equal to the vertex average, and ``Pi_F v = v``), and both give ``|F| / n`` on
triangles and parallelograms (there ``c_F = xbar_F`` and the fan triangles are equal).

Cells. Every cell K is split into the signed tetrahedra ``(xbar_K, xbar_F, x_i, x_{i+1})``
over the fan triangles of its faces (``xbar_K`` the vertex average of K, the orientation
from the face's sign in K). With signed volumes, a tetrahedron rule exact for degree d
gives a rule exact for degree d on any polyhedron with planar faces, convex or not.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..mesh.polyhedra import Mesh3D

__all__ = [
    "FACE_RULES",
    "TET_RULES",
    "FaceGeometry",
    "Field3",
    "TetSplit",
    "cell_face_entries",
    "cell_means3d",
    "cell_vertex_averages",
    "eval_field3",
    "face_geometry",
    "face_means",
    "polyhedron_quadrature",
    "segment_sum",
    "tet_split",
]

#: A vector field: a constant 3-vector or a callable ``f(x, t)`` on (m, 3) points.
Field3 = ArrayLike | Callable[[NDArray[np.float64], float], ArrayLike]

#: The face vertex weight rules (module docstring).
FACE_RULES = ("enhanced", "fan")

_T5 = (0.3108859192633006, 0.0927352503108912, 0.0455037041256496)
_W5 = (0.1126879257180159, 0.0734930431163619, 0.0425460207770812)


def _tet_rule5() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    bary, w = [], []
    for a, wt in zip(_T5[:2], _W5[:2], strict=True):
        for j in range(4):
            b = np.full(4, a)
            b[j] = 1.0 - 3.0 * a
            bary.append(b)
            w.append(wt)
    for i in range(4):
        for j in range(i + 1, 4):
            p = np.full(4, 0.5 - _T5[2])
            p[[i, j]] = _T5[2]
            bary.append(p)
            w.append(_W5[2])
    return np.array(bary), np.array(w)


_A2, _B2 = 0.5854101966249685, 0.1381966011250105

#: Tetrahedron rules by degree of exactness: (barycentric coordinates (q, 4), weights (q,)
#: summing to 1). Degree 2: the 4-point rule; degree 5: the 14-point rule with positive
#: weights (Walkington 2000).
TET_RULES: dict[int, tuple[NDArray[np.float64], NDArray[np.float64]]] = {
    2: (np.full((4, 4), _B2) + (_A2 - _B2) * np.eye(4), np.full(4, 0.25)),
    5: _tet_rule5(),
}


def eval_field3(f: Field3, x: NDArray[np.float64], t: float, name: str) -> NDArray[np.float64]:
    """The values (len(x), 3) of a :data:`Field3` at the points ``x`` (len(x), 3).

    Raises
    ------
    ValueError
        If the field does not give one 3-vector per point; the message names ``name``.
    """
    v = np.asarray(f(x, t) if callable(f) else f, dtype=float)
    if v.shape == (3,):
        v = np.broadcast_to(v, (len(x), 3))
    if v.shape != (len(x), 3):
        raise ValueError(f"{name} must give a 3-vector per point, got shape {v.shape}")
    return v


def segment_sum(index: NDArray[np.int64], values: NDArray[np.float64], n: int) -> NDArray:
    """``out[k] = sum of values[j] with index[j] == k`` for (E,) or (E, c) values."""
    if values.ndim == 1:
        return np.bincount(index, values, minlength=n)
    return np.stack(
        [np.bincount(index, values[:, c], minlength=n) for c in range(values.shape[1])], 1
    )


class FaceGeometry(NamedTuple):
    """Geometry of every face of a mesh (:func:`face_geometry`); ``E`` = len(face_vertices)."""

    xbar: NDArray[np.float64]  # (n_faces, 3) vertex averages
    normal: NDArray[np.float64]  # (n_faces, 3) right-hand unit normals
    area: NDArray[np.float64]  # (n_faces,)
    centroid: NDArray[np.float64]  # (n_faces, 3)
    face: NDArray[np.int64]  # (E,) the face of every entry of face_vertices
    next: NDArray[np.int64]  # (E,) the entry of the next vertex of the loop
    fan_area: NDArray[np.float64]  # (E,) signed area of the fan triangle (xbar, x_i, x_i+1)
    q: NDArray[np.float64]  # (E, 3) in-plane vertex normal weights q_i^F
    weights: NDArray[np.float64]  # (E,) face vertex weights w_i^F of the chosen rule


def face_geometry(mesh: Mesh3D, rule: str = "enhanced") -> FaceGeometry:
    """Vertex averages, normals, areas, centroids and vertex weights of every face.

    Parameters
    ----------
    mesh : Mesh3D
    rule : {"enhanced", "fan"}
        The face vertex weights (module docstring); both are exact for linear fields.
    """
    if rule not in FACE_RULES:
        raise ValueError(f"unknown face rule {rule!r}; expected one of {', '.join(FACE_RULES)}")
    off, fv, P = mesh.face_offsets, mesh.face_vertices, mesh.points
    nf, sizes = mesh.n_faces, mesh.face_sizes
    face = np.repeat(np.arange(nf), sizes)
    E = len(fv)
    nxt = np.arange(1, E + 1)
    nxt[off[1:] - 1] = off[:-1]
    prv = np.arange(-1, E - 1)
    prv[off[:-1]] = off[1:] - 1
    X = P[fv]
    xbar = segment_sum(face, X, nf) / sizes[:, None]
    a = X - xbar[face]
    b = a[nxt]
    vec = 0.5 * np.cross(a, b)  # vector areas of the fan triangles
    A = segment_sum(face, vec, nf)
    area = np.linalg.norm(A, axis=1)
    normal = A / area[:, None]
    fan_area = np.einsum("ec,ec->e", vec, normal[face])
    centroid = xbar + segment_sum(face, fan_area[:, None] * (a + b) / 3.0, nf) / area[:, None]
    em = np.cross(b - a, normal[face])  # |e_i| m_i of the edge (x_i, x_i+1)
    q = 0.5 * (em + em[prv])
    if rule == "enhanced":
        w = (area / sizes)[face] + np.einsum("ec,ec->e", centroid[face] - xbar[face], q)
    else:
        w = (fan_area + fan_area[prv]) / 3.0 + (area / (3.0 * sizes))[face]
    return FaceGeometry(xbar, normal, area, centroid, face, nxt, fan_area, q, w)


class TetSplit(NamedTuple):
    """The signed tetrahedra ``(xbar_K, xbar_F, x_i, x_{i+1})`` of every cell
    (:func:`tet_split`)."""

    cell: NDArray[np.int64]  # (T,) the cell of every tetrahedron
    vertices: NDArray[np.float64]  # (T, 4, 3)
    volume: NDArray[np.float64]  # (T,) signed volumes

    def points(self, degree: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Points (T * q, 3) and signed weights (T * q,) of the tetrahedron rule of
        ``degree`` on every tetrahedron (tetrahedron by tetrahedron)."""
        if degree not in TET_RULES:
            raise ValueError(f"no tetrahedron rule of degree {degree}; have {sorted(TET_RULES)}")
        bary, w = TET_RULES[degree]
        pts = np.einsum("qj,tjc->tqc", bary, self.vertices)
        return pts.reshape(-1, 3), (self.volume[:, None] * w[None]).ravel()


class _CellEntries(NamedTuple):
    cell: NDArray[np.int64]  # (S,) the cell of every (cell, face, vertex) entry
    entry: NDArray[np.int64]  # (S,) the entry of face_vertices
    sign: NDArray[np.int8]  # (S,) the face's sign in the cell


def cell_face_entries(mesh: Mesh3D) -> _CellEntries:
    """Every (cell, face, face vertex) triple, flattened in the order of ``cell_faces``."""
    per_face = mesh.face_sizes[mesh.cell_faces]
    total = int(per_face.sum())
    starts = mesh.face_offsets[mesh.cell_faces]
    idx = np.repeat(starts - np.cumsum(per_face) + per_face, per_face) + np.arange(total)
    return _CellEntries(
        np.repeat(mesh.cell_of_entry, per_face), idx, np.repeat(mesh.cell_face_signs, per_face)
    )


def cell_vertex_averages(mesh: Mesh3D) -> NDArray[np.float64]:
    """(n_cells, 3) the vertex average of every cell (the point of (3.9))."""
    sizes = np.diff(mesh.cell_vertex_offsets)
    cell = np.repeat(np.arange(mesh.n_cells), sizes)
    return segment_sum(cell, mesh.points[mesh.cell_vertex_ids], mesh.n_cells) / sizes[:, None]


def tet_split(mesh: Mesh3D, faces: FaceGeometry | None = None) -> TetSplit:
    """The signed tetrahedra of every cell through its vertex average and the vertex
    averages of its faces (module docstring)."""
    fg = face_geometry(mesh) if faces is None else faces
    ce = cell_face_entries(mesh)
    P, fv = mesh.points, mesh.face_vertices
    xk = cell_vertex_averages(mesh)[ce.cell]
    xf = fg.xbar[fg.face[ce.entry]]
    xi, xj = P[fv[ce.entry]], P[fv[fg.next[ce.entry]]]
    vol = ce.sign * np.einsum("tc,tc->t", xf - xk, np.cross(xi - xf, xj - xf)) / 6.0
    return TetSplit(ce.cell, np.stack([xk, xf, xi, xj], axis=1), vol)


def polyhedron_quadrature(
    mesh: Mesh3D, degree: int = 5
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """A rule on every cell exact for polynomials of ``degree`` (2 or 5), signed weights.

    Returns
    -------
    points : (Q, 3) ; weights : (Q,) ; cell : (Q,) int (the cell of each point)
    """
    ts = tet_split(mesh)
    pts, w = ts.points(degree)
    return pts, w, np.repeat(ts.cell, len(TET_RULES[degree][1]))


def cell_means3d(mesh: Mesh3D, f: Field3, t: float = 0.0, name: str = "f") -> NDArray:
    """``P_0^K f`` of every cell (Section 3.3): the cell mean by the degree-2 rule on the
    signed tetrahedra (exact for quadratic f on any polyhedron with planar faces).

    Returns
    -------
    (n_cells, 3) array
    """
    nc = mesh.n_cells
    if not callable(f):
        return np.tile(eval_field3(f, np.zeros((1, 3)), t, name)[0], (nc, 1))
    pts, w, cell = polyhedron_quadrature(mesh, 2)
    val = eval_field3(f, pts, t, name)
    vol = np.bincount(cell, w, minlength=nc)
    return segment_sum(cell, w[:, None] * val, nc) / vol[:, None]


def face_means(
    mesh: Mesh3D,
    faces: NDArray[np.int64],
    f: Field3,
    t: float = 0.0,
    name: str = "f2",
    geometry: FaceGeometry | None = None,
) -> NDArray[np.float64]:
    """``P_0^F f`` on the given faces: the face mean by the degree-2 rule (edge midpoints)
    on the fan triangles (exact for quadratic f on planar faces). (len(faces), 3)."""
    faces = np.asarray(faces, dtype=np.int64)
    if not callable(f):
        return np.tile(eval_field3(f, np.zeros((1, 3)), t, name)[0], (len(faces), 1))
    fg = face_geometry(mesh) if geometry is None else geometry
    pick = np.full(mesh.n_faces, -1)
    pick[faces] = np.arange(len(faces))
    e = np.flatnonzero(pick[fg.face] >= 0)
    P, fv = mesh.points, mesh.face_vertices
    xf, xi, xj = fg.xbar[fg.face[e]], P[fv[e]], P[fv[fg.next[e]]]
    total = np.zeros((len(e), 3))
    for p in (0.5 * (xf + xi), 0.5 * (xi + xj), 0.5 * (xj + xf)):
        total += eval_field3(f, p, t, name)
    local = pick[fg.face[e]]
    s = segment_sum(local, (fg.fan_area[e] / 3.0)[:, None] * total, len(faces))
    return s / fg.area[faces][:, None]
