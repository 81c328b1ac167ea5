"""The polygonal mesh type.

A mesh is a set of vertices and of simple polygons (cells) listed
counter-clockwise by vertex index, with any number of vertices per cell.
A hanging node is simply a vertex of every cell whose boundary passes through it,
so the mesh is always conforming in the virtual element sense (paper, Remark 4.9).

Boundary edges are the directed cell edges whose reverse does not occur in another
cell; they keep the orientation of their cell, so their outward normal is the edge
direction turned clockwise. Each boundary edge carries the code of one named
boundary part: code ``i`` is ``part_names[i - 1]``, 0 is untagged. The paper's parts
``clamped`` (Gamma_D), ``traction`` (Gamma_N) and ``contact`` (Gamma_C) have codes
1, 2, 3 by default; any other names (a gmsh physical group, a config's part) follow.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..util.arrays import unique as _unique

#: The paper's boundary parts, codes 1, 2, 3 of every mesh (then any other names).
PARTS: tuple[str, ...] = ("clamped", "traction", "contact")
UNTAGGED = 0

#: The cached properties of a :class:`Mesh` that depend on its points and cells only: a
#: mesh with other tags shares them (:meth:`Mesh.with_tags`, :meth:`Mesh.with_boundary`).
_GEOMETRY = frozenset(
    (
        "cell_sizes",
        "groups",
        "directed_edges",
        "edge_cells",
        "edge_twins",
        "_boundary_rows",
        "boundary_edges",
        "boundary_edge_cells",
        "edges",
        "cell_areas",
        "cell_diameters",
    )
)


def part_code(name: str, names: Sequence[str] = PARTS) -> int:
    """Integer code of a boundary part name among ``names`` (``clamped`` -> 1, ...)."""
    try:
        return list(names).index(name) + 1
    except ValueError:
        raise ValueError(
            f"unknown boundary part {name!r}; the parts are {', '.join(names)}"
        ) from None


def part_names_with(names: Sequence[str], more: Sequence[str]) -> tuple[str, ...]:
    """``names`` followed by the names of ``more`` not among them, in order."""
    out = list(names)
    out += [n for n in dict.fromkeys(more) if n not in out]
    return tuple(out)


class BoundaryParts:
    """The named boundary parts of a mesh, from its ``boundary_tags`` (code ``i + 1``
    for ``part_names[i]``, 0 untagged): shared by :class:`Mesh` (edges) and
    :class:`~vemwear.mesh.polyhedra.Mesh3D` (faces)."""

    boundary_tags: NDArray[np.int8] | None
    part_names: tuple[str, ...]

    @property
    def parts(self) -> tuple[str, ...]:
        """Names of the parts that have boundary edges (faces in 3D), in code order."""
        present = set(_unique(np.asarray(self.boundary_tags)).tolist())
        return tuple(n for i, n in enumerate(self.part_names) if i + 1 in present)

    def part_counts(self) -> dict[str, int]:
        """Boundary edges (faces in 3D) of every named part, empty ones included."""
        tags = np.asarray(self.boundary_tags)
        return {p: int(np.sum(tags == i + 1)) for i, p in enumerate(self.part_names)}


class MeshError(ValueError):
    """A mesh that is not valid for the method; the message names cells or vertices."""


def checked_tags(
    tags: ArrayLike | None, n: int, part_names: Sequence[str]
) -> tuple[NDArray[np.int8], tuple[str, ...]]:
    """The read-only part codes of ``n`` boundary facets (all 0 if ``tags`` is None) and
    the part names, checked: one code per facet, codes ``0..len(part_names)``, at most
    127 distinct names (2D edges and 3D faces alike)."""
    t = np.zeros(n, dtype=np.int8) if tags is None else np.array(tags, dtype=np.int8)
    if t.shape != (n,):
        raise MeshError(f"boundary_tags must have shape ({n},), got {t.shape}")
    names = tuple(str(x) for x in part_names)
    if len(set(names)) != len(names) or len(names) > 127:
        raise MeshError(f"part_names must be at most 127 distinct names, got {names}")
    if np.any((t < 0) | (t > len(names))):
        raise MeshError(f"boundary_tags must be codes 0..{len(names)}")
    t.setflags(write=False)
    return t, names


@dataclass(frozen=True, eq=False)
class Mesh(BoundaryParts):
    """Polygonal mesh with tagged boundary edges.

    Parameters
    ----------
    points : (n_points, 2) float array
        Vertex coordinates.
    cell_offsets : (n_cells + 1,) int array
        Cell ``k`` has vertices ``cell_vertices[cell_offsets[k]:cell_offsets[k + 1]]``.
    cell_vertices : int array
        Concatenated counter-clockwise vertex lists of the cells.
    boundary_tags : (n_boundary_edges,) int array, optional
        Part code of every boundary edge, in the order of :attr:`boundary_edges`: code
        ``i`` is the part ``part_names[i - 1]``; 0 marks an untagged edge.
    part_names : tuple of str
        Names of the part codes 1, 2, ...; the paper's three parts first by default.
    """

    points: NDArray[np.float64]
    cell_offsets: NDArray[np.int64]
    cell_vertices: NDArray[np.int64]
    boundary_tags: NDArray[np.int8] | None = field(default=None)
    part_names: tuple[str, ...] = PARTS

    def __post_init__(self) -> None:
        pts = np.ascontiguousarray(self.points, dtype=np.float64)
        off = np.ascontiguousarray(self.cell_offsets, dtype=np.int64)
        cv = np.ascontiguousarray(self.cell_vertices, dtype=np.int64)
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise MeshError(f"points must have shape (n, 2), got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            bad = np.flatnonzero(~np.all(np.isfinite(pts), axis=1))
            raise MeshError(f"vertices {bad[:10].tolist()} have non-finite coordinates")
        if off.ndim != 1 or off.size < 2 or off[0] != 0 or off[-1] != cv.size:
            raise MeshError("cell_offsets must start at 0 and end at len(cell_vertices)")
        sizes = np.diff(off)
        if np.any(sizes < 3):
            bad = np.flatnonzero(sizes < 3)
            raise MeshError(f"cells {bad[:10].tolist()} have fewer than 3 vertices")
        if cv.size and (cv.min() < 0 or cv.max() >= len(pts)):
            bad = np.flatnonzero((cv < 0) | (cv >= len(pts)))
            cells = np.searchsorted(off, bad, side="right") - 1
            raise MeshError(
                f"cells {_unique(cells)[:10].tolist()} refer to vertex ids "
                f"outside 0..{len(pts) - 1}"
            )
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "cell_offsets", off)
        object.__setattr__(self, "cell_vertices", cv)
        for arr in (pts, off, cv):
            arr.setflags(write=False)
        tags, names = checked_tags(self.boundary_tags, len(self.boundary_edges), self.part_names)
        object.__setattr__(self, "part_names", names)
        object.__setattr__(self, "boundary_tags", tags)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_cells(
        cls,
        points: ArrayLike,
        cells: Sequence[Sequence[int]] | NDArray[np.int64],
        boundary_tags: ArrayLike | None = None,
        part_names: Sequence[str] = PARTS,
    ) -> Mesh:
        """Build a mesh from a list of vertex-index lists (or an (n_cells, n) array)."""
        if isinstance(cells, np.ndarray) and cells.ndim == 2:
            sizes = np.full(len(cells), cells.shape[1], dtype=np.int64)
            flat = cells.reshape(-1)
        else:
            sizes = np.array([len(c) for c in cells], dtype=np.int64)
            flat = (
                np.concatenate([np.asarray(c, dtype=np.int64) for c in cells])
                if len(cells)
                else np.zeros(0, np.int64)
            )
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        tags = None if boundary_tags is None else np.asarray(boundary_tags)
        return cls(np.asarray(points, dtype=float), offsets, flat, tags, tuple(part_names))

    # ------------------------------------------------------------------ sizes
    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def n_cells(self) -> int:
        return len(self.cell_offsets) - 1

    @cached_property
    def cell_sizes(self) -> NDArray[np.int64]:
        """Number of vertices of every cell."""
        return np.diff(self.cell_offsets)

    def cell(self, k: int) -> NDArray[np.int64]:
        """Vertex ids of cell ``k`` (counter-clockwise)."""
        return self.cell_vertices[self.cell_offsets[k] : self.cell_offsets[k + 1]]

    @property
    def cells(self) -> list[NDArray[np.int64]]:
        """Vertex-id lists of all cells (a Python list; for I/O, not hot paths)."""
        return np.split(self.cell_vertices, self.cell_offsets[1:-1])

    @cached_property
    def groups(self) -> dict[int, tuple[NDArray[np.int64], NDArray[np.int64]]]:
        """Cells batched by vertex count: ``{n: (cell_ids, (m, n) vertex ids)}``."""
        out: dict[int, tuple[NDArray[np.int64], NDArray[np.int64]]] = {}
        sizes = self.cell_sizes
        for n in _unique(sizes):
            ids = np.flatnonzero(sizes == n)
            idx = self.cell_offsets[ids][:, None] + np.arange(n)[None, :]
            out[int(n)] = (ids, self.cell_vertices[idx])
        return out

    # ------------------------------------------------------------------ edges
    @cached_property
    def directed_edges(self) -> NDArray[np.int64]:
        """All cell edges (a, b) in cell orientation, cell by cell; shape (sum n_K, 2)."""
        nxt = np.arange(1, self.cell_vertices.size + 1)
        last = self.cell_offsets[1:] - 1
        nxt[last] = self.cell_offsets[:-1]
        return np.column_stack([self.cell_vertices, self.cell_vertices[nxt]])

    @cached_property
    def edge_cells(self) -> NDArray[np.int64]:
        """Cell id of every row of :attr:`directed_edges`."""
        return np.repeat(np.arange(self.n_cells), self.cell_sizes)

    @cached_property
    def edge_twins(self) -> NDArray[np.int64]:
        """The row of :attr:`directed_edges` of each edge's reverse (the neighbouring
        cell's side of an interior edge), -1 on the boundary."""
        de = self.directed_edges
        n = max(self.n_points, 1)
        key = de[:, 0] * n + de[:, 1]
        order = np.argsort(key)
        key = key[order]
        rev = de[:, 1] * n + de[:, 0]
        # a sorted search, several times faster than np.isin on 10^5-10^6 edges
        pos = np.minimum(np.searchsorted(key, rev), len(key) - 1)
        return np.where(key[pos] == rev, order[pos], -1)

    @cached_property
    def _boundary_rows(self) -> NDArray[np.int64]:
        de = self.directed_edges
        # an edge is interior when its reverse is another cell's edge
        rows = np.flatnonzero(self.edge_twins < 0)
        # a canonical order (by first vertex, then second) makes tags reproducible
        order = np.lexsort((de[rows, 1], de[rows, 0]))
        return rows[order]

    @cached_property
    def boundary_edges(self) -> NDArray[np.int64]:
        """Boundary edges (a, b) oriented as in their cell (outward normal on the right)."""
        return self.directed_edges[self._boundary_rows]

    @cached_property
    def boundary_edge_cells(self) -> NDArray[np.int64]:
        """The cell owning each boundary edge."""
        return self.edge_cells[self._boundary_rows]

    @cached_property
    def edges(self) -> NDArray[np.int64]:
        """Unique undirected edges (a < b)."""
        e = np.sort(self.directed_edges, axis=1)
        return np.unique(e, axis=0)

    def edge_midpoints(self, edges: NDArray[np.int64]) -> NDArray[np.float64]:
        return 0.5 * (self.points[edges[:, 0]] + self.points[edges[:, 1]])

    def boundary_normals(self) -> NDArray[np.float64]:
        """Unit outward normals of the boundary edges."""
        d = self.points[self.boundary_edges[:, 1]] - self.points[self.boundary_edges[:, 0]]
        n = np.column_stack([d[:, 1], -d[:, 0]])
        return n / np.linalg.norm(n, axis=1)[:, None]

    # ------------------------------------------------------------------ parts
    def part_code(self, name: str) -> int:
        """The code of a part of this mesh (ValueError naming the parts if unknown)."""
        return part_code(name, self.part_names)

    def has_part(self, name: str) -> bool:
        """Whether the part exists and has boundary edges."""
        return name in self.parts

    def part_edges(self, name: str) -> NDArray[np.int64]:
        """Boundary edges of one part, oriented as in their cell (none for a part name
        this mesh does not know among the paper's three)."""
        if name not in self.part_names and name in PARTS:
            return np.zeros((0, 2), dtype=np.int64)
        return self.boundary_edges[self.boundary_tags == self.part_code(name)]

    def with_tags(self, tags: ArrayLike, part_names: Sequence[str] | None = None) -> Mesh:
        """The same cells with other boundary tags (and part names)."""
        names = self.part_names if part_names is None else tuple(part_names)
        return self._retagged(np.asarray(tags), names)

    def _retagged(self, tags: NDArray[np.int8], names: tuple[str, ...]) -> Mesh:
        """The same points and cells with other tags, sharing the cached geometry (the
        boundary edges are found once per geometry, not once per tagging)."""
        new = object.__new__(Mesh)
        new.__dict__.update({k: v for k, v in self.__dict__.items() if k in _GEOMETRY})
        Mesh.__init__(new, self.points, self.cell_offsets, self.cell_vertices, tags, names)
        return new

    def part_vertices(self, name: str) -> NDArray[np.int64]:
        """Sorted ids of the vertices on the closure of a part."""
        return _unique(self.part_edges(name))

    def with_boundary(
        self,
        parts: Mapping[str, Callable[[NDArray[np.float64]], NDArray[np.bool_]] | str],
        *,
        overwrite: bool = True,
    ) -> Mesh:
        """Tag boundary edges by predicates on edge midpoints.

        Parameters
        ----------
        parts
            ``{part_name: predicate}``; a predicate maps an (m, 2) array of edge
            midpoints to an (m,) boolean array. The string ``"rest"`` as a
            predicate tags every edge not tagged by the other entries. Entries are
            applied in the order given; a later entry wins where two match.
        overwrite
            If False, keep existing non-zero tags and only tag untagged edges.

        Returns
        -------
        Mesh
            A new mesh with the same cells and updated ``boundary_tags``.
        """
        tags = np.array(self.boundary_tags, dtype=np.int8, copy=True)
        names = part_names_with(self.part_names, list(parts))
        if overwrite:
            tags[:] = UNTAGGED
        # with overwrite=False only the edges untagged on entry may be (re)tagged, so
        # that a later entry still wins over an earlier one of the same call
        protected = tags != UNTAGGED
        mid = self.edge_midpoints(self.boundary_edges)
        rest: list[str] = []
        for name, pred in parts.items():
            code = part_code(name, names)
            if isinstance(pred, str):
                if pred != "rest":
                    raise ValueError(f"boundary part {name!r}: unknown selector {pred!r}")
                rest.append(name)
                continue
            hit = np.asarray(pred(mid), dtype=bool)
            if hit.shape != (len(mid),):
                raise ValueError(
                    f"boundary part {name!r}: predicate must return shape ({len(mid)},)"
                )
            tags[hit & ~protected] = code
        for name in rest:
            tags[tags == UNTAGGED] = part_code(name, names)
        return self._retagged(tags, names)

    # ------------------------------------------------------------------ geometry
    @cached_property
    def cell_areas(self) -> NDArray[np.float64]:
        """Signed areas (positive for counter-clockwise cells), shoelace formula."""
        a, b = self.directed_edges[:, 0], self.directed_edges[:, 1]
        # coordinates relative to the first vertex of each cell keep the sum accurate
        ref = np.repeat(
            self.points[self.cell_vertices[self.cell_offsets[:-1]]], self.cell_sizes, axis=0
        )
        pa, pb = self.points[a] - ref, self.points[b] - ref
        cross = pa[:, 0] * pb[:, 1] - pb[:, 0] * pa[:, 1]
        areas = np.bincount(self.edge_cells, weights=cross, minlength=self.n_cells)
        return np.asarray(0.5 * areas, dtype=np.float64)

    @cached_property
    def cell_diameters(self) -> NDArray[np.float64]:
        """Largest vertex-to-vertex distance of every cell."""
        diam2 = np.zeros(self.n_cells)
        for n, (ids, verts) in self.groups.items():
            X = self.points[verts]
            i, j = np.triu_indices(n, 1)  # each pair once; squared lengths, one sqrt
            d = X[:, i] - X[:, j]
            diam2[ids] = (d[..., 0] ** 2 + d[..., 1] ** 2).max(axis=1)
        return np.sqrt(diam2)

    @property
    def h(self) -> float:
        """Mesh size: the largest cell diameter (the one definition of h in vemwear; the
        paper's "h = 1/n" of squares is their side, whose diameter is sqrt(2)/n)."""
        return float(self.cell_diameters.max())

    def __repr__(self) -> str:
        counts = {n: len(ids) for n, (ids, _) in self.groups.items()}
        tagged = self.part_counts()
        return (
            f"Mesh({self.n_points} vertices, {self.n_cells} cells by vertex count {counts}, "
            f"boundary edges {tagged}, untagged {int(np.sum(self.boundary_tags == 0))})"
        )
