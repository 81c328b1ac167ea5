"""Small polyhedral meshes for the 3D element tests, built here (not by vemwear.mesh).

Cells are given as lists of vertex loops oriented outward (right-hand normal out of the
cell); :func:`mesh_from_cells` stores every face once (keyed by its vertex set) and gives
the second cell of a face the sign -1. Every generator keeps the faces planar: boxes of
hexahedra under a projective map (which maps planes to planes), tetrahedra (always
planar), prisms of a 2D mesh between horizontal layers.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vemwear.mesh.polyhedra import Mesh3D
from vemwear.mesh.registry import FAMILIES

SIDES = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")


def mesh_from_cells(
    points, cells: Sequence[Sequence[Sequence[int]]], tag_box: bool = True
) -> Mesh3D:
    """A :class:`Mesh3D` from outward vertex loops per cell; boundary faces tagged by the
    side of the bounding box they lie on (``SIDES``), when ``tag_box``."""
    points = np.asarray(points, dtype=float)
    loops: list[Sequence[int]] = []
    where: dict[frozenset[int], int] = {}
    cell_faces, signs, offsets = [], [], [0]
    for cell in cells:
        for loop in cell:
            key = frozenset(int(v) for v in loop)
            if key in where:
                cell_faces.append(where[key])
                signs.append(-1)
            else:
                where[key] = len(loops)
                loops.append([int(v) for v in loop])
                cell_faces.append(where[key])
                signs.append(1)
        offsets.append(len(cell_faces))
    fo = np.concatenate([[0], np.cumsum([len(lp) for lp in loops])])
    fv = np.concatenate([np.asarray(lp) for lp in loops])
    mesh = Mesh3D(points, fo, fv, np.asarray(offsets), np.asarray(cell_faces), np.asarray(signs))
    if not tag_box:
        return mesh
    lo, hi = points.min(axis=0), points.max(axis=0)
    tags = np.zeros(len(mesh.boundary_faces), dtype=np.int8)
    for j, f in enumerate(mesh.boundary_faces):
        X = points[fv[fo[f] : fo[f + 1]]]
        for axis in range(3):
            for side, val in ((0, lo[axis]), (1, hi[axis])):
                if np.allclose(X[:, axis], val, atol=1e-12 * (1 + abs(val))):
                    tags[j] = 2 * axis + side + 1
    return mesh.with_tags(tags, SIDES)


def _grid(n: tuple[int, int, int], size=(1.0, 1.0, 1.0)):
    nx, ny, nz = n
    x, y, z = (np.linspace(0.0, s, k + 1) for s, k in zip(size, n, strict=True))
    P = np.stack(np.meshgrid(x, y, z, indexing="ij"), axis=-1).reshape(-1, 3)
    idx = np.arange(len(P)).reshape(nx + 1, ny + 1, nz + 1)
    return P, idx


#: Outward loops of the unit cube's faces, corners as (i, j, k) offsets.
CUBE_FACES = (
    ((0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)),
    ((1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)),
    ((0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)),
    ((0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)),
    ((0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)),
    ((0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)),
)


def hexahedra(n: tuple[int, int, int], size=(1.0, 1.0, 1.0)) -> Mesh3D:
    """A box of nx * ny * nz hexahedra."""
    P, idx = _grid(n, size)
    cells = []
    for i in range(n[0]):
        for j in range(n[1]):
            for k in range(n[2]):
                cells.append([[idx[i + a, j + b, k + c] for a, b, c in f] for f in CUBE_FACES])
    return mesh_from_cells(P, cells)


def _tet_loops(P, t):
    """The four outward loops of the tetrahedron t."""
    a, b, c, d = t
    if np.dot(np.cross(P[b] - P[a], P[c] - P[a]), P[d] - P[a]) < 0:
        b, c = c, b
    return [[a, c, b], [a, b, d], [b, c, d], [a, d, c]]


def kuhn_tetrahedra(n: tuple[int, int, int], size=(1.0, 1.0, 1.0)) -> Mesh3D:
    """Every hexahedron of the box split into the 6 Kuhn tetrahedra along its diagonal."""
    P, idx = _grid(n, size)
    perms = ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))
    cells = []
    for i in range(n[0]):
        for j in range(n[1]):
            for k in range(n[2]):
                for p in perms:
                    c = np.array([i, j, k])
                    t = [idx[tuple(c)]]
                    for ax in p:
                        c = c.copy()
                        c[ax] += 1
                        t.append(idx[tuple(c)])
                    cells.append(_tet_loops(P, t))
    return mesh_from_cells(P, cells)


def prisms(kind: str, divisions, heights: Sequence[float], **options) -> Mesh3D:
    """Prisms of a 2D mesh of ``FAMILIES[kind]`` (``divisions``: its divisions, or its
    cell count for "voronoi") on the unit square between the planes z = heights."""
    key = "n_cells" if kind == "voronoi" else "divisions"
    m2 = FAMILIES[kind].generate(**{key: divisions}, size=(1.0, 1.0), **options)
    P2, npl = m2.points, m2.n_points
    z = np.asarray(heights, dtype=float)
    P = np.concatenate([np.column_stack([P2, np.full(npl, h)]) for h in z])
    cells = []
    for layer in range(len(z) - 1):
        lo, hi = layer * npl, (layer + 1) * npl
        for k in range(m2.n_cells):
            v = m2.cell_vertices[m2.cell_offsets[k] : m2.cell_offsets[k + 1]]
            faces = [[lo + a for a in v[::-1]], [hi + a for a in v]]
            faces += [
                [lo + a, lo + b, hi + b, hi + a] for a, b in zip(v, np.roll(v, -1), strict=True)
            ]
            cells.append(faces)
    return mesh_from_cells(P, cells)


def projective(mesh: Mesh3D, rng: np.random.Generator, strength: float = 0.15) -> Mesh3D:
    """The mesh under a random projective map x -> (A x + b) / (1 + c . x) (planes stay
    planes), A near the identity; the box's side tags are kept."""
    A = np.eye(3) + strength * rng.uniform(-1, 1, (3, 3))
    c = strength * rng.uniform(-1, 1, 3)
    X = mesh.points
    Y = (X @ A.T) / (1.0 + X @ c)[:, None]
    return Mesh3D(
        Y,
        mesh.face_offsets,
        mesh.face_vertices,
        mesh.cell_offsets,
        mesh.cell_faces,
        mesh.cell_face_signs,
        mesh.boundary_tags,
        mesh.part_names,
    )


def perturb_interior(mesh: Mesh3D, rng: np.random.Generator, amount: float) -> Mesh3D:
    """Interior vertices moved by up to ``amount`` in every coordinate (for tetrahedra
    only: other faces would stop being planar)."""
    on_boundary = np.zeros(mesh.n_points, bool)
    fo, fv = mesh.face_offsets, mesh.face_vertices
    for f in mesh.boundary_faces:
        on_boundary[fv[fo[f] : fo[f + 1]]] = True
    X = mesh.points.copy()
    X[~on_boundary] += rng.uniform(-amount, amount, (int((~on_boundary).sum()), 3))
    return Mesh3D(
        X,
        fo,
        fv,
        mesh.cell_offsets,
        mesh.cell_faces,
        mesh.cell_face_signs,
        mesh.boundary_tags,
        mesh.part_names,
    )
