"""Validity checks of a polyhedral mesh, each raising :class:`MeshError` naming faces,
cells or vertices.

* :func:`check_vertices3d`: no two vertices coincide, every vertex is used by a cell.
* :func:`check_faces3d`: no face lists a vertex twice, no face has zero area, every face
  is planar within a tolerance (largest distance of a vertex to the face's plane over the
  face's diameter).
* :func:`check_cells3d`: no cell lists a face twice; every cell is closed (each edge of
  its faces is used by exactly two of them, in opposite directions once the signs are
  applied), correctly oriented (positive volume) and not degenerate.
* :func:`check_conforming3d`: an interior face has opposite signs in its two cells; the
  boundary faces form a closed surface (each of their edges is used by two of them in
  opposite directions), and no two boundary faces have the same vertices (a face between
  two cells stored twice).
* :func:`check_boundary3d`: every boundary face is in a part, the required parts exist.
"""

from __future__ import annotations

from itertools import chain

import numpy as np
from numpy.typing import NDArray

from ..util.arrays import isin as _isin
from ..util.arrays import unique as _unique
from .checks import _ids
from .geometry3d import face_planarity, loop_next, loop_owner
from .polyhedra import Mesh3D
from .polymesh import MeshError

__all__ = [
    "check_boundary3d",
    "check_cells3d",
    "check_conforming3d",
    "check_faces3d",
    "check_mesh3d",
    "check_vertices3d",
]


def _scale(mesh: Mesh3D) -> float:
    ext = mesh.points.max(axis=0) - mesh.points.min(axis=0)
    return float(max(np.max(ext), np.finfo(float).tiny))


def check_vertices3d(mesh: Mesh3D, rtol: float = 1e-10) -> None:
    """No two vertices within ``rtol`` times the mesh size of each other; none unused."""
    from scipy.spatial import cKDTree

    used = np.zeros(mesh.n_points, dtype=bool)
    used[mesh.face_vertices[_isin(loop_owner(mesh.face_offsets), mesh.cell_faces)]] = True
    if not np.all(used):
        raise MeshError(f"vertices {_ids(np.flatnonzero(~used))} belong to no cell (dangling)")
    pairs = cKDTree(mesh.points).query_pairs(rtol * _scale(mesh), output_type="ndarray")
    if len(pairs):
        raise MeshError(f"duplicate vertices (same coordinates): pairs {_ids(pairs[:, :2])}")


def check_faces3d(mesh: Mesh3D, rtol: float = 1e-12, planarity: float = 1e-8) -> None:
    """Faces list distinct vertices, have positive area and are planar.

    Parameters
    ----------
    rtol : float
        A face is degenerate if its area is at most ``rtol`` times its diameter squared.
    planarity : float
        Largest distance of a vertex to the face's plane, over the face's diameter.
    """
    off, fv = mesh.face_offsets, mesh.face_vertices
    owner = loop_owner(off)
    key = np.sort(owner * mesh.n_points + fv)
    rep = _unique(key[1:][key[1:] == key[:-1]] // mesh.n_points)
    if rep.size:
        raise MeshError(f"faces {_ids(rep)} list a vertex twice")
    diam = mesh.face_diameters
    bad = np.flatnonzero(mesh.face_areas <= rtol * diam**2)
    if bad.size:
        raise MeshError(f"faces {_ids(bad)} are degenerate (zero area)")
    flat = face_planarity(mesh.points, off, fv, mesh._face_geometry)
    bad = np.flatnonzero(flat > planarity)
    if bad.size:
        worst = bad[np.argmax(flat[bad])]
        raise MeshError(
            f"faces {_ids(bad)} are not planar: a vertex lies up to {flat[worst]:.3g} face "
            f"diameters off the face's plane (face {worst}; tolerance {planarity:g})"
        )


def _cell_edges(mesh: Mesh3D) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Directed edges (a, b) of every cell's faces, signs applied, and their cells."""
    sizes = mesh.face_sizes[mesh.cell_faces]
    e = np.repeat(np.arange(len(mesh.cell_faces)), sizes)
    start = np.repeat(mesh.face_offsets[mesh.cell_faces] - np.cumsum(sizes) + sizes, sizes)
    k = start + np.arange(int(sizes.sum()))
    a = mesh.face_vertices[k]
    b = mesh.face_vertices[loop_next(mesh.face_offsets)[k]]
    flip = mesh.cell_face_signs[e] < 0
    a, b = np.where(flip, b, a), np.where(flip, a, b)
    return a, b, mesh.cell_of_entry[e]


def check_cells3d(mesh: Mesh3D, rtol: float = 1e-12) -> None:
    """Cells are closed, correctly oriented and not degenerate.

    A cell is closed when every edge of its faces is used by exactly two of its faces,
    once in each direction after the signs are applied (a face with sign -1 runs
    backwards); this also catches a face with the wrong sign. A cell is degenerate if
    its volume is at most ``rtol`` times its diameter cubed.
    """
    n = mesh.n_points
    pair = mesh.cell_of_entry * mesh.n_faces + mesh.cell_faces
    s = np.sort(pair)
    twice = _unique(s[1:][s[1:] == s[:-1]] // mesh.n_faces)
    if twice.size:
        raise MeshError(f"cells {_ids(twice)} list a face twice")
    a, b, cell = _cell_edges(mesh)
    key = (cell * n + a) * n + b
    uniq, counts = np.unique(key, return_counts=True)
    if np.any(counts > 1):
        k = uniq[counts > 1][0]
        c, rest = divmod(int(k), n * n)
        bad = _unique(uniq[counts > 1] // (n * n))
        raise MeshError(
            f"cells {_ids(bad)} are not closed or their faces are misoriented: edge "
            f"({rest // n}, {rest % n}) of cell {c} is used twice in the same direction "
            "(check the signs of the cell's faces)"
        )
    rev = (cell * n + b) * n + a
    alone = ~_isin(key, rev)
    if np.any(alone):
        i = np.flatnonzero(alone)[0]
        raise MeshError(
            f"cells {_ids(_unique(cell[alone]))} are not closed: edge ({a[i]}, {b[i]}) of "
            f"cell {cell[i]} belongs to one of its faces only"
        )
    vol = mesh.cell_volumes
    tiny = rtol * mesh.cell_diameters**3
    bad = np.flatnonzero(np.abs(vol) <= tiny)
    if bad.size:
        raise MeshError(f"cells {_ids(bad)} are degenerate (zero volume)")
    bad = np.flatnonzero(vol < 0)
    if bad.size:
        raise MeshError(
            f"cells {_ids(bad)} are inverted (negative volume): their faces' signs point "
            "inwards; a sign is +1 when the face's right-hand normal points out of the cell"
        )


def check_conforming3d(mesh: Mesh3D) -> None:
    """Interior faces have opposite signs in their cells; the boundary is a closed surface
    and no face between two cells is stored twice."""
    nf, n = mesh.n_faces, mesh.n_points
    total = np.zeros(nf, dtype=np.int64)
    np.add.at(total, mesh.cell_faces, mesh.cell_face_signs)
    uses = np.bincount(mesh.cell_faces, minlength=nf)
    bad = np.flatnonzero((uses == 2) & (total != 0))
    if bad.size:
        f = bad[0]
        cells = mesh.cell_of_entry[mesh.cell_faces == f]
        raise MeshError(
            f"faces {_ids(bad)} have the same sign in both their cells (face {f} in cells "
            f"{cells.tolist()}): the cells overlap or one of them is inverted"
        )
    bf = mesh.boundary_faces
    if bf.size == 0:
        raise MeshError("the mesh has no boundary faces")
    off, fv, sizes = mesh.face_offsets, mesh.face_vertices, mesh.face_sizes
    for m in _unique(sizes[bf]):  # boundary faces with the same vertex set, by size
        g = bf[sizes[bf] == m]
        S = np.sort(fv[off[g][:, None] + np.arange(m)], axis=1)
        order = np.lexsort(S.T[::-1])
        same = np.flatnonzero(np.all(S[order][1:] == S[order][:-1], axis=1))
        if same.size:
            fa, fb = np.sort(g[order[[same[0], same[0] + 1]]])
            raise MeshError(
                f"faces {fa} and {fb} have the same vertices {S[order[same[0]]].tolist()}: a "
                "face between two cells is stored twice (store it once, with opposite signs)"
            )
    sizes = sizes[bf]
    start = np.repeat(off[bf] - np.cumsum(sizes) + sizes, sizes)
    k = start + np.arange(int(sizes.sum()))
    face = np.repeat(bf, sizes)
    sign = np.repeat(mesh.boundary_face_signs, sizes)
    a, b = fv[k], fv[loop_next(off)[k]]
    a, b = np.where(sign < 0, b, a), np.where(sign < 0, a, b)
    key, rev = a * n + b, b * n + a
    uniq, counts = np.unique(key, return_counts=True)
    lone = ~_isin(key, rev) | _isin(key, uniq[counts > 1])
    if np.any(lone):
        i = np.flatnonzero(lone)
        f = face[i[0]]
        cell = mesh.cell_of_entry[np.flatnonzero(mesh.cell_faces == f)[0]]
        raise MeshError(
            f"non-conforming faces {_ids(_unique(face[i]))}: edge ({a[i[0]]}, {b[i[0]]}) of "
            f"boundary face {f} (cell {cell}) is not matched by exactly one other boundary "
            "face; neighbouring cells must share whole faces (put hanging nodes in the "
            "loops of the larger faces)"
        )
    _check_hanging(mesh, _unique(np.minimum(a, b) * n + np.maximum(a, b)), face, a, b)


def _check_hanging(
    mesh: Mesh3D, keys: NDArray[np.int64], face: NDArray, a: NDArray, b: NDArray, rtol=1e-9
) -> None:
    """No boundary vertex lies inside an edge of the boundary faces (a hanging node that
    the faces on the other side do not list: two closed surfaces touching)."""
    from scipy.spatial import cKDTree

    n = mesh.n_points
    ea, eb = np.divmod(keys, n)
    P = mesh.points
    verts = _unique(np.concatenate([ea, eb]))
    A, B = P[ea], P[eb]
    half = 0.5 * np.linalg.norm(B - A, axis=1)
    hits = cKDTree(P[verts]).query_ball_point(0.5 * (A + B), half * (1 - 1e-9))
    counts = np.fromiter(map(len, hits), dtype=np.int64, count=len(hits))
    e = np.repeat(np.arange(len(keys)), counts)
    c = verts[np.fromiter(chain.from_iterable(hits), dtype=np.int64, count=int(counts.sum()))]
    keep = (c != ea[e]) & (c != eb[e])
    e, c = e[keep], c[keep]
    d = B[e] - A[e]
    dist = np.linalg.norm(np.cross(P[c] - A[e], d), axis=1) / (2 * half[e])
    on = np.flatnonzero(dist <= rtol * _scale(mesh))
    if on.size:
        k = on[0]
        x, y = ea[e[k]], eb[e[k]]
        f = face[np.flatnonzero(((a == x) & (b == y)) | ((a == y) & (b == x)))[0]]
        raise MeshError(
            f"non-conforming faces: vertex {c[k]} lies on edge ({x}, {y}) of boundary face "
            f"{f} but is not a vertex of it: faces on both sides of a surface must match "
            "(put hanging nodes in the loops of the larger faces)"
        )


def check_boundary3d(mesh: Mesh3D, require: tuple[str, ...] = ()) -> None:
    """Every boundary face is tagged and the required parts are present."""
    untagged = np.flatnonzero(mesh.boundary_tags == 0)
    if untagged.size:
        f = mesh.boundary_faces[untagged]
        c = mesh.face_centroids[f[0]]
        raise MeshError(
            f"{untagged.size} boundary faces have no boundary part, e.g. faces {_ids(f[:3])} "
            f"(face {f[0]} centred at ({c[0]:.6g}, {c[1]:.6g}, {c[2]:.6g})); put them in a part"
        )
    for name in require:
        if mesh.part_faces(name).size == 0:
            raise MeshError(f"the mesh has no {name!r} boundary faces")


def check_mesh3d(
    mesh: Mesh3D, require: tuple[str, ...] | None = None, planarity: float = 1e-8
) -> None:
    """Run every check: vertices, faces, cells, conformity, and (if ``require`` is given)
    boundary parts."""
    check_vertices3d(mesh)
    check_faces3d(mesh, planarity=planarity)
    check_cells3d(mesh)
    check_conforming3d(mesh)
    if require is not None:
        check_boundary3d(mesh, require)
