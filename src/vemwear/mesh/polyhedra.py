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
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from .polymesh import PARTS, MeshError

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
class Mesh3D:
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
                f"cells {np.unique(cells)[:10].tolist()} refer to face ids outside 0..{nf - 1}"
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
        tags = self.boundary_tags
        tags = np.zeros(nb, dtype=np.int8) if tags is None else np.asarray(tags, np.int8)
        if tags.shape != (nb,):
            raise MeshError(f"boundary_tags must have shape ({nb},), got {tags.shape}")
        names = tuple(str(n) for n in self.part_names)
        if len(set(names)) != len(names) or len(names) > 127:
            raise MeshError(f"part_names must be at most 127 distinct names, got {names}")
        if np.any((tags < 0) | (tags > len(names))):
            raise MeshError(f"boundary_tags must be codes 0..{len(names)}")
        tags = np.ascontiguousarray(tags)
        tags.setflags(write=False)
        object.__setattr__(self, "boundary_tags", tags)
        object.__setattr__(self, "part_names", names)

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
        key = np.unique(cell * self.n_points + verts)
        cells, verts = np.divmod(key, self.n_points)
        off = np.zeros(self.n_cells + 1, dtype=np.int64)
        np.cumsum(np.bincount(cells, minlength=self.n_cells), out=off[1:])
        return off, verts
