"""Structured meshes of a box, prisms extruded from 2D meshes, and the box's sides as parts.

The box ``[x0, x0 + lx] x [y0, y0 + ly] x [z0, z0 + lz]`` is cut into ``nx * ny * nz``
grid hexahedra (:func:`box_hexahedra`), each of which may be cut into six tetrahedra
(:func:`box_tetrahedra`, the Kuhn / Freudenthal split along the main diagonal, the same
in every hexahedron, so that neighbours share their triangles). :func:`extrude` stacks
layers of prisms on any polygonal :class:`~vemwear.mesh.Mesh`. Every generator builds
the faces of each cell and lets :meth:`Mesh3D.from_cell_faces` merge the shared ones.

The six sides of a box are the boundary parts ``xmin``, ``xmax``, ``ymin``, ``ymax``,
``zmin`` and ``zmax`` (:data:`BOX_SIDES`, :func:`tag_box`); the box generators tag
them, after the paper's three part names (which stay codes 1, 2, 3, as in 2D).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from itertools import permutations

import numpy as np
from numpy.typing import NDArray

from .geometry3d import loop_next, loop_owner, reverse_loops
from .polyhedra import Mesh3D
from .polymesh import Mesh, MeshError, part_names_with

__all__ = [
    "BOX_SIDES",
    "HEX_FACES",
    "TET_FACES",
    "box_hexahedra",
    "box_tetrahedra",
    "cell_loops",
    "extrude",
    "tag_box",
]

#: The sides of a box, as boundary part names.
BOX_SIDES: tuple[str, ...] = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")

#: Outward faces of a hexahedron in VTK order (bottom 0-3 counter-clockwise, top 4-7).
HEX_FACES = ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))
#: Outward faces of a positively oriented tetrahedron (0, 1, 2, 3).
TET_FACES = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))

Triple = tuple[float, float, float]


def cell_loops(
    cells: NDArray[np.int64], local_faces: Sequence[Sequence[int]], first_cell: int = 0
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """The face loops of cells of one type: ``(offsets, vertices, cells)`` for
    :meth:`Mesh3D.from_cell_faces`.

    Parameters
    ----------
    cells : (n, m) int array
        Vertex ids of every cell.
    local_faces : sequence of sequences of int
        The faces of the cell type as local vertex loops.
    first_cell : int
        The id of the first cell.
    """
    cells = np.asarray(cells, dtype=np.int64)
    n = len(cells)
    verts = np.concatenate([cells[:, list(f)] for f in local_faces], axis=1).ravel()
    sizes = np.tile([len(f) for f in local_faces], n)
    off = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=off[1:])
    owner = np.repeat(np.arange(first_cell, first_cell + n, dtype=np.int64), len(local_faces))
    return off, verts, owner


def _grid(
    size: Sequence[float], divisions: Sequence[int], origin: Sequence[float]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Grid points and the hexahedra (VTK order) of the box."""
    if len(size) != 3 or len(divisions) != 3 or len(origin) != 3:
        raise ValueError("size, divisions and origin need three entries each")
    nx, ny, nz = (int(d) for d in divisions)
    if min(nx, ny, nz) < 1:
        raise ValueError(f"divisions must be positive integers, got {list(divisions)}")
    lx, ly, lz = (float(s) for s in size)
    if not min(lx, ly, lz) > 0:
        raise ValueError(f"size must be positive, got {list(size)}")
    axes = [
        o + np.linspace(0.0, s, d + 1)
        for o, s, d in zip(origin, (lx, ly, lz), (nx, ny, nz), strict=True)
    ]
    Z, Y, X = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")  # x fastest
    points = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    v = (i + (nx + 1) * (j + (ny + 1) * k)).ravel()
    dx, dy, dz = 1, nx + 1, (nx + 1) * (ny + 1)
    corner = np.array([0, dx, dx + dy, dy, dz, dz + dx, dz + dx + dy, dz + dy])
    return points, v[:, None] + corner


def box_hexahedra(
    size: Triple = (2.0, 1.0, 1.0),
    divisions: tuple[int, int, int] = (8, 4, 4),
    origin: Triple = (0.0, 0.0, 0.0),
) -> Mesh3D:
    """Box split into ``nx * ny * nz`` axis-aligned hexahedra, sides tagged.

    Parameters
    ----------
    size : (float, float, float)
        Side lengths ``(lx, ly, lz)`` (default: the 3D analogue of the paper's (0, 2) x (0, 1)).
    divisions : (int, int, int)
        Cells ``(nx, ny, nz)`` along x, y and z.
    origin : (float, float, float)
        The corner with the smallest coordinates.

    Returns
    -------
    Mesh3D
        Cells numbered x fastest, then y, then z; the six sides are the parts
        :data:`BOX_SIDES`.
    """
    points, hexes = _grid(size, divisions, origin)
    return tag_box(Mesh3D.from_cell_faces(points, *cell_loops(hexes, HEX_FACES)))


def _kuhn_tets() -> NDArray[np.int64]:
    """The six tetrahedra of the unit cube along its diagonal 0-6 (VTK corners),
    positively oriented: one per order of the three axes along the path from 0 to 6."""
    unit = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
    )
    code = {tuple(p): c for c, p in enumerate(unit.tolist())}
    tets = []
    for perm in permutations(range(3)):
        p = [0, 0, 0]
        path = [code[tuple(p)]]
        for axis in perm:
            p[axis] += 1
            path.append(code[tuple(p)])
        a, b, c, d = unit[path]
        if np.dot(np.cross(b - a, c - a), d - a) < 0:
            path[2], path[3] = path[3], path[2]
        tets.append(path)
    return np.array(tets, dtype=np.int64)


def box_tetrahedra(
    size: Triple = (2.0, 1.0, 1.0),
    divisions: tuple[int, int, int] = (8, 4, 4),
    origin: Triple = (0.0, 0.0, 0.0),
) -> Mesh3D:
    """Box split into ``6 * nx * ny * nz`` tetrahedra (Kuhn split of every hexahedron).

    Every grid hexahedron is cut into the six tetrahedra around its diagonal from the
    corner with the smallest to that with the largest coordinates; all hexahedra are cut
    the same way, so the tetrahedra are conforming. Parameters as :func:`box_hexahedra`.

    Returns
    -------
    Mesh3D
        The six tetrahedra of grid hexahedron ``h`` are cells ``6h .. 6h + 5``.
    """
    points, hexes = _grid(size, divisions, origin)
    tets = hexes[:, _kuhn_tets()].reshape(-1, 4)
    return tag_box(Mesh3D.from_cell_faces(points, *cell_loops(tets, TET_FACES)))


def extrude(
    mesh: Mesh,
    n_layers: int = 1,
    lz: float = 1.0,
    *,
    z: Sequence[float] | None = None,
    z0: float = 0.0,
    bottom: str = "zmin",
    top: str = "zmax",
) -> Mesh3D:
    """Prisms: a polygonal mesh extruded along z in layers.

    Parameters
    ----------
    mesh : Mesh
        Any polygonal mesh (convex or not, with hanging nodes).
    n_layers : int
        Number of layers of equal height ``lz / n_layers``.
    lz : float
        Total height.
    z : sequence of float, optional
        The heights of the layer interfaces instead (increasing, at least two);
        ``n_layers``, ``lz`` and ``z0`` are then ignored.
    z0 : float
        Height of the bottom.
    bottom, top : str
        Part names of the bottom and top faces.

    Returns
    -------
    Mesh3D
        Cell ``l * n + k`` is the prism of 2D cell ``k`` in layer ``l``; its side
        faces on the 2D mesh's boundary keep the 2D boundary part of their edge.
    """
    if z is None:
        if int(n_layers) < 1 or not float(lz) > 0:
            raise ValueError(f"need n_layers >= 1 and lz > 0, got {n_layers} and {lz}")
        levels = float(z0) + np.linspace(0.0, float(lz), int(n_layers) + 1)
    else:
        levels = np.asarray(z, dtype=float)
        if levels.ndim != 1 or len(levels) < 2 or np.any(np.diff(levels) <= 0):
            raise ValueError("z must be at least two increasing heights")
    L, n2, nc = len(levels) - 1, mesh.n_points, mesh.n_cells
    off2, cv2 = mesh.cell_offsets, mesh.cell_vertices
    points = np.column_stack([np.tile(mesh.points, (L + 1, 1)), np.repeat(levels, n2)]).astype(
        float
    )
    shift = n2 * np.arange(L)[:, None]
    rev = reverse_loops(off2, cv2, np.ones(nc, dtype=bool))
    a, b = cv2, cv2[loop_next(off2)]
    cells2 = loop_owner(off2)
    layer_cells = nc * np.arange(L)[:, None]
    sides = np.stack([a + shift, b + shift, b + shift + n2, a + shift + n2], axis=-1)
    verts = np.concatenate([(rev + shift).ravel(), (cv2 + shift + n2).ravel(), sides.ravel()])
    sizes = np.concatenate([np.tile(np.diff(off2), 2 * L), np.full(L * len(cv2), 4)])
    owners = np.concatenate(
        [(np.arange(nc) + layer_cells).ravel()] * 2 + [(cells2 + layer_cells).ravel()]
    )
    off = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=off[1:])
    names = part_names_with(mesh.part_names, [bottom, top])
    m3 = Mesh3D.from_cell_faces(points, off, verts, owners, L * nc, part_names=names)
    # tags: bottom / top faces by level, side faces by their 2D boundary edge
    bf = m3.boundary_faces
    first = m3.face_vertices[m3.face_offsets[bf]]
    second = m3.face_vertices[m3.face_offsets[bf] + 1]
    lvl = m3.face_vertices // n2
    lo = np.minimum.reduceat(lvl, m3.face_offsets[:-1])[bf]
    hi = np.maximum.reduceat(lvl, m3.face_offsets[:-1])[bf]
    tags = np.zeros(len(bf), dtype=np.int8)
    tags[(lo == hi) & (lo == 0)] = names.index(bottom) + 1
    tags[(lo == hi) & (lo == L)] = names.index(top) + 1
    side = lo != hi
    be = mesh.boundary_edges
    key2 = be[:, 0] * n2 + be[:, 1]
    order = np.argsort(key2)
    k = (first[side] % n2) * n2 + second[side] % n2
    pos = np.clip(np.searchsorted(key2[order], k), 0, max(len(key2) - 1, 0))
    if len(key2) and np.all(key2[order][pos] == k):
        tags[side] = np.asarray(mesh.boundary_tags)[order][pos]
    else:  # pragma: no cover - the side faces of boundary edges are the 3D boundary
        raise MeshError("the extruded side faces do not match the boundary edges")
    return m3.with_tags(tags)


def _on_sides(mesh: Mesh3D, faces: NDArray[np.int64], rtol: float) -> NDArray[np.bool_]:
    """(len(faces), 6): which sides of the mesh's bounding box every face lies on."""
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    tol = rtol * float(np.max(hi - lo))
    starts = mesh.face_offsets[:-1]
    X = mesh.points[mesh.face_vertices]
    fmin = np.minimum.reduceat(X, starts, axis=0)[faces]
    fmax = np.maximum.reduceat(X, starts, axis=0)[faces]
    cols = []
    for d in range(3):
        cols += [fmax[:, d] <= lo[d] + tol, fmin[:, d] >= hi[d] - tol]
    return np.column_stack(cols)


def tag_box(
    mesh: Mesh3D,
    parts: Mapping[str, str | Sequence[str]] | None = None,
    *,
    sides: Mapping[str, str] | None = None,
    rtol: float = 1e-9,
) -> Mesh3D:
    """Tag the boundary faces on the sides of the mesh's bounding box.

    Parameters
    ----------
    mesh : Mesh3D
        A mesh of a box (or any mesh: only faces on the box's sides are tagged).
    parts : mapping, optional
        Part name to a side (``xmin``, ``xmax``, ``ymin``, ``ymax``, ``zmin``,
        ``zmax``) or a list of sides, as :func:`~vemwear.mesh.tag_rectangle`.
    sides : mapping, optional
        Side to part name instead (``{"xmin": "clamped", "zmin": "contact"}``).
        Without ``parts`` and ``sides`` every side is the part of its own name.
    rtol : float
        A face lies on a side when all its vertices are within ``rtol`` times the
        box's largest side length of it.

    Returns
    -------
    Mesh3D
        With these parts tagged (faces on no selected side untagged); the part names
        are the mesh's followed by the new ones.
    """
    if parts is not None and sides is not None:
        raise ValueError("give either parts or sides, not both")
    if sides is not None:
        grouped: dict[str, list[str]] = {}
        for side, part in sides.items():
            grouped.setdefault(part, []).append(side)
        parts = grouped
    if parts is None:
        parts = {s: s for s in BOX_SIDES}
    names = part_names_with(mesh.part_names, list(parts))
    on = _on_sides(mesh, mesh.boundary_faces, rtol)
    tags = np.zeros(len(mesh.boundary_faces), dtype=np.int8)
    for name, which in parts.items():
        which = [which] if isinstance(which, str) else list(which)
        for side in which:
            if side not in BOX_SIDES:
                raise ValueError(
                    f"{name}: unknown side {side!r}; expected one of {', '.join(BOX_SIDES)}"
                )
            tags[on[:, BOX_SIDES.index(side)]] = names.index(name) + 1
    return mesh.with_tags(tags, names)
