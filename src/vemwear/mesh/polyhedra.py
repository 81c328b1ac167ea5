"""The polyhedral mesh type (3D).

A 3D mesh is a set of vertices, of planar polygonal faces given as vertex loops, and of
cells given as the faces that bound them. Each face is stored once; a cell lists its
faces with a sign: +1 when the face's loop, read counter-clockwise seen from outside
the cell (its right-hand normal), points out of the cell, -1 when it points in. A face
shared by two cells therefore has sign +1 in one and -1 in the other. Hanging nodes are
vertices of every face whose boundary passes through them, as in 2D, so the mesh is
conforming in the virtual element sense.

Boundary faces are the faces of exactly one cell; their outward normal is their
right-hand normal times their sign in that cell. Each boundary face carries the code of
one named boundary part, as the boundary edges of a 2D :class:`~vemwear.mesh.Mesh`: code
``i`` is ``part_names[i - 1]``, 0 is untagged.

:meth:`Mesh3D.from_cell_faces` builds a mesh from every cell's own face loops (shared faces
found and stored once); the geometry (face areas, normals and centroids, cell volumes,
centroids and diameters, :mod:`vemwear.mesh.geometry3d`) is computed once on demand.
Generators: :mod:`.generate3d` (hexahedra, tetrahedra, prisms, the box's sides as parts),
:mod:`.voronoi3d`; checks :mod:`.checks3d`, quality :mod:`.quality3d`, files :mod:`.io3d`,
registry :mod:`.registry3d`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..util.arrays import unique as _unique
from .polymesh import PARTS, BoundaryParts, MeshError, checked_tags

__all__ = ["Mesh3D"]


def _csr(offsets: NDArray, values: NDArray, name: str) -> tuple[NDArray, NDArray]:
    off = np.ascontiguousarray(offsets, dtype=np.int64)
    val = np.ascontiguousarray(values, dtype=np.int64)
    if off.ndim != 1 or off.size < 2 or off[0] != 0 or off[-1] != val.size:
        raise MeshError(f"{name}_offsets must start at 0 and end at len({name}_...)")
    if np.any(np.diff(off) < 0):
        raise MeshError(f"{name}_offsets must not decrease")
    return off, val


@dataclass(frozen=True, eq=False)
class Mesh3D(BoundaryParts):
    """Polyhedral mesh with tagged boundary faces.

    Parameters
    ----------
    points : (n_points, 3) float array
        Vertex coordinates.
    face_offsets : (n_faces + 1,) int array
        Face ``f`` has the vertex loop ``face_vertices[face_offsets[f]:face_offsets[f+1]]``.
    face_vertices : int array
        Concatenated vertex loops of the faces (each face once).
    cell_offsets : (n_cells + 1,) int array
        Cell ``k`` has the faces ``cell_faces[cell_offsets[k]:cell_offsets[k + 1]]``.
    cell_faces : int array
        Concatenated face ids of the cells.
    cell_face_signs : int array
        For each entry of ``cell_faces``: +1 if the face's right-hand normal points out
        of the cell, -1 if it points in.
    boundary_tags : (n_boundary_faces,) int array, optional
        Part code of every boundary face, in the order of :attr:`boundary_faces`.
    part_names : tuple of str
        Names of the part codes 1, 2, ...
    """

    points: NDArray[np.float64]
    face_offsets: NDArray[np.int64]
    face_vertices: NDArray[np.int64]
    cell_offsets: NDArray[np.int64]
    cell_faces: NDArray[np.int64]
    cell_face_signs: NDArray[np.int8]
    boundary_tags: NDArray[np.int8] | None = field(default=None)
    part_names: tuple[str, ...] = PARTS

    #: The dimension of the space, for the layers shared with 2D meshes.
    dim = 3

    def __post_init__(self) -> None:
        pts = np.ascontiguousarray(self.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise MeshError(f"points must have shape (n, 3), got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            bad = np.flatnonzero(~np.all(np.isfinite(pts), axis=1))
            raise MeshError(f"vertices {bad[:10].tolist()} have non-finite coordinates")
        foff, fv = _csr(self.face_offsets, self.face_vertices, "face")
        coff, cf = _csr(self.cell_offsets, self.cell_faces, "cell")
        signs = np.ascontiguousarray(self.cell_face_signs, dtype=np.int8)
        if signs.shape != cf.shape or not np.all(np.abs(signs) == 1):
            raise MeshError("cell_face_signs must hold +1 or -1 for every entry of cell_faces")
        small = np.flatnonzero(np.diff(foff) < 3)
        if small.size:
            raise MeshError(f"faces {small[:10].tolist()} have fewer than 3 vertices")
        small = np.flatnonzero(np.diff(coff) < 4)
        if small.size:
            raise MeshError(f"cells {small[:10].tolist()} have fewer than 4 faces")
        if fv.size and (fv.min() < 0 or fv.max() >= len(pts)):
            raise MeshError(f"faces refer to vertex ids outside 0..{len(pts) - 1}")
        nf = foff.size - 1
        if cf.size and (cf.min() < 0 or cf.max() >= nf):
            bad = np.flatnonzero((cf < 0) | (cf >= nf))
            cells = np.searchsorted(coff, bad, side="right") - 1
            raise MeshError(
                f"cells {_unique(cells)[:10].tolist()} refer to face ids outside 0..{nf - 1}"
            )
        uses = np.bincount(cf, minlength=nf)
        if np.any(uses > 2):
            bad = np.flatnonzero(uses > 2)
            raise MeshError(f"faces {bad[:10].tolist()} belong to more than two cells")
        for name, arr in (
            ("points", pts),
            ("face_offsets", foff),
            ("face_vertices", fv),
            ("cell_offsets", coff),
            ("cell_faces", cf),
            ("cell_face_signs", signs),
        ):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        nb = len(self.boundary_faces)
        tags, names = checked_tags(self.boundary_tags, nb, self.part_names)
        object.__setattr__(self, "boundary_tags", tags)
        object.__setattr__(self, "part_names", names)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_cell_faces(
        cls,
        points: ArrayLike,
        loop_offsets: ArrayLike,
        loop_vertices: ArrayLike,
        loop_cells: ArrayLike,
        n_cells: int | None = None,
        *,
        orient: bool = False,
        part_names: Sequence[str] = PARTS,
    ) -> Mesh3D:
        """A mesh from the faces of every cell, each cell listing all its faces.

        Faces met in two cells (the same set of vertices) are stored once, with the
        loop of their first occurrence (so boundary faces keep the loop given, and
        interior faces that of the cell met first); the sign of an occurrence is +1 if
        its loop runs the same way as the stored one, -1 otherwise. Faces are numbered
        in the order of their first occurrence.

        Parameters
        ----------
        points : (n_points, 3) float array
        loop_offsets, loop_vertices : int arrays
            The face loops of all cells (CSR), each running counter-clockwise seen from
            outside its cell (or all inward in a cell, with ``orient``).
        loop_cells : (n_loops,) int array
            The cell of every loop.
        n_cells : int, optional
            Number of cells (default: the largest cell id + 1).
        orient : bool
            Reverse every loop of the cells whose volume comes out negative (cells
            listed with inward loops, e.g. inverted elements of a file).
        part_names : sequence of str
            Names of the part codes (the boundary is untagged).

        Returns
        -------
        Mesh3D
        """
        from .geometry3d import cell_geometry, reverse_loops, take_loops

        pts = np.asarray(points, dtype=np.float64)
        off = np.asarray(loop_offsets, dtype=np.int64)
        lv = np.asarray(loop_vertices, dtype=np.int64)
        lc = np.asarray(loop_cells, dtype=np.int64)
        nl = len(off) - 1
        if lc.shape != (nl,):
            raise MeshError(f"loop_cells must have one cell per loop ({nl}), got {lc.shape}")
        nc = int(lc.max()) + 1 if n_cells is None else int(n_cells)
        if orient and nl:
            vol, _ = cell_geometry(pts, off, lv, lc, np.arange(nl), np.ones(nl), nc)
            lv = reverse_loops(off, lv, (vol < 0)[lc])
        sizes = np.diff(off)
        rep = np.empty(nl, dtype=np.int64)  # the first loop with the same vertex set
        forward = np.empty(nl, dtype=bool)  # the loop's direction, read from its least vertex
        for s in _unique(sizes):  # loops of one size at a time
            g = np.flatnonzero(sizes == s)
            R = lv[off[g][:, None] + np.arange(s)]
            S = np.sort(R, axis=1)
            order = np.lexsort(S.T[::-1])  # stable: equal rows keep increasing loop ids
            Ss = S[order]
            new = np.ones(len(g), dtype=bool)
            new[1:] = np.any(Ss[1:] != Ss[:-1], axis=1)
            rep[g[order]] = g[order[new]][np.cumsum(new) - 1]
            rows = np.arange(len(g))
            lo = np.argmin(R, axis=1)
            forward[g] = R[rows, (lo + 1) % s] < R[rows, (lo - 1) % s]
        reps, face_of_loop = np.unique(rep, return_inverse=True)
        signs = np.where(forward == forward[rep], 1, -1).astype(np.int8)
        foff, fv = take_loops(off, lv, reps)
        order = np.argsort(lc, kind="stable")
        coff = np.zeros(nc + 1, dtype=np.int64)
        np.cumsum(np.bincount(lc, minlength=nc), out=coff[1:])
        return cls(
            pts, foff, fv, coff, face_of_loop[order], signs[order], part_names=tuple(part_names)
        )

    # ------------------------------------------------------------------ sizes
    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_faces(self) -> int:
        return len(self.face_offsets) - 1

    @property
    def n_cells(self) -> int:
        return len(self.cell_offsets) - 1

    @cached_property
    def face_sizes(self) -> NDArray[np.int64]:
        """Vertices of every face."""
        return np.diff(self.face_offsets)

    @cached_property
    def cell_of_entry(self) -> NDArray[np.int64]:
        """The cell of every entry of :attr:`cell_faces`."""
        return np.repeat(np.arange(self.n_cells), np.diff(self.cell_offsets))

    # ------------------------------------------------------------------ boundary
    @cached_property
    def boundary_faces(self) -> NDArray[np.int64]:
        """Ids of the faces of exactly one cell, increasing."""
        uses = np.bincount(self.cell_faces, minlength=self.n_faces)
        return np.flatnonzero(uses == 1)

    @cached_property
    def boundary_face_signs(self) -> NDArray[np.int8]:
        """Sign of each boundary face in its cell: its outward normal is the sign times
        its right-hand normal."""
        sign = np.zeros(self.n_faces, dtype=np.int8)
        sign[self.cell_faces] = self.cell_face_signs  # boundary faces occur once
        return sign[self.boundary_faces]

    def part_faces(self, name: str) -> NDArray[np.int64]:
        """Face ids of the boundary part ``name`` (an unknown name has none)."""
        if name not in self.part_names:
            return np.zeros(0, dtype=np.int64)
        code = self.part_names.index(name) + 1
        return self.boundary_faces[self.boundary_tags == code]

    def with_tags(
        self, boundary_tags: NDArray[np.int8], part_names: tuple[str, ...] | None = None
    ) -> Mesh3D:
        """The same mesh with other boundary tags (and part names)."""
        return Mesh3D(
            self.points,
            self.face_offsets,
            self.face_vertices,
            self.cell_offsets,
            self.cell_faces,
            self.cell_face_signs,
            boundary_tags,
            self.part_names if part_names is None else part_names,
        )

    # ------------------------------------------------------------------ geometry
    @cached_property
    def _face_geometry(self) -> tuple[NDArray, NDArray, NDArray]:
        from .geometry3d import face_geometry

        return face_geometry(self.points, self.face_offsets, self.face_vertices)

    @cached_property
    def face_area_vectors(self) -> NDArray[np.float64]:
        """Area times unit right-hand normal of every face (n_faces, 3)."""
        return self._face_geometry[0]

    @cached_property
    def face_areas(self) -> NDArray[np.float64]:
        """Area of every face."""
        return np.asarray(np.linalg.norm(self.face_area_vectors, axis=1))

    @cached_property
    def face_normals(self) -> NDArray[np.float64]:
        """Unit right-hand normal of every face (n_faces, 3); 0 for a face of no area."""
        a = self.face_areas[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(a > 0, self.face_area_vectors / a, 0.0)

    @cached_property
    def face_centroids(self) -> NDArray[np.float64]:
        """Area centroid of every face (n_faces, 3)."""
        return self._face_geometry[1]

    @cached_property
    def face_diameters(self) -> NDArray[np.float64]:
        """Largest distance between two vertices of every face."""
        from .geometry3d import group_max_distance

        return group_max_distance(self.points, self.face_offsets, self.face_vertices)

    @cached_property
    def _cell_geometry(self) -> tuple[NDArray, NDArray]:
        from .geometry3d import cell_geometry

        return cell_geometry(
            self.points,
            self.face_offsets,
            self.face_vertices,
            self.cell_of_entry,
            self.cell_faces,
            self.cell_face_signs,
            self.n_cells,
            self._face_geometry,
        )

    @cached_property
    def cell_volumes(self) -> NDArray[np.float64]:
        """Signed volume of every cell (positive for a correctly oriented cell)."""
        return self._cell_geometry[0]

    @cached_property
    def cell_centroids(self) -> NDArray[np.float64]:
        """Centroid of every cell (n_cells, 3)."""
        return self._cell_geometry[1]

    @cached_property
    def cell_diameters(self) -> NDArray[np.float64]:
        """Largest distance between two vertices of every cell."""
        from .geometry3d import group_max_distance

        return group_max_distance(self.points, self.cell_vertex_offsets, self.cell_vertex_ids)

    @cached_property
    def edges(self) -> NDArray[np.int64]:
        """The distinct edges of the faces, as sorted vertex pairs (n_edges, 2)."""
        from .geometry3d import loop_next

        a = self.face_vertices
        b = a[loop_next(self.face_offsets)]
        key = _unique(np.minimum(a, b) * self.n_points + np.maximum(a, b))
        return np.column_stack(np.divmod(key, self.n_points))

    # ------------------------------------------------------------------ cells
    @cached_property
    def cell_vertex_offsets(self) -> NDArray[np.int64]:
        """CSR offsets of :attr:`cell_vertex_ids`."""
        return self._cell_vertices[0]

    @cached_property
    def cell_vertex_ids(self) -> NDArray[np.int64]:
        """The distinct vertices of every cell, increasing within a cell (CSR with
        :attr:`cell_vertex_offsets`)."""
        return self._cell_vertices[1]

    @cached_property
    def _cell_vertices(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        per_face = self.face_sizes[self.cell_faces]
        cell = np.repeat(self.cell_of_entry, per_face)
        starts = self.face_offsets[self.cell_faces]
        idx = np.repeat(starts - np.cumsum(per_face) + per_face, per_face) + np.arange(
            per_face.sum()
        )
        verts = self.face_vertices[idx]
        key = _unique(cell * self.n_points + verts)
        cells, verts = np.divmod(key, self.n_points)
        off = np.zeros(self.n_cells + 1, dtype=np.int64)
        np.cumsum(np.bincount(cells, minlength=self.n_cells), out=off[1:])
        return off, verts
