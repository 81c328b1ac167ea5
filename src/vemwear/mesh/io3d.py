"""Reading and writing polyhedral meshes through meshio.

Reading (:func:`read_mesh3d`, :func:`from_meshio3d`): the volume cells ``tetra``,
``hexahedron``, ``wedge``, ``pyramid`` and ``polyhedron`` (VTU) become cells of a
:class:`~vemwear.mesh.polyhedra.Mesh3D` through their standard local faces, shared faces
merged; a cell listed inside out (all its faces inward, e.g. a wedge in the other
ordering convention) is turned the right way. Boundary parts come from surface cells
(``triangle``, ``quad``, ``polygon``) with the cell data ``gmsh:physical`` (named by the
physical groups of dimension 2, an unnamed group is ``physical_<number>``) or ``part``
(named by the field data ``{name: [code, 2]}``), matched to the boundary faces by their
vertices; or, in the VTU files :func:`write_mesh3d` writes, from the field data
``vemwear:boundary_offsets``, ``vemwear:boundary_vertices`` and ``vemwear:boundary_tags``
(the boundary faces' loops and part codes: a VTU file of polyhedra holds no other cells).
Points no cell uses (gmsh geometry points) are dropped.

Writing (:func:`write_mesh3d`, NumPy only, not through meshio: its VTU writer loops over
cells in Python and drops field data): VTU with VTK polyhedron cells (faces listed
outward, so ParaView shows any cell), the cell data ``cell_id`` (meshio groups polyhedra
by vertex count when reading) and the boundary parts as above.
"""

from __future__ import annotations

import base64
import contextlib
import io
import os
from collections.abc import Mapping
from itertools import chain
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..util.arrays import unique as _unique
from .generate3d import HEX_FACES, TET_FACES, cell_loops
from .geometry3d import reverse_loops, take_loops
from .polyhedra import Mesh3D
from .polymesh import PARTS, MeshError


def _quoteattr(text: str) -> str:
    """``xml.sax.saxutils.quoteattr`` (imported here: its module pulls in urllib, http
    and ssl, 40 ms of every run's start that writes no 3D file)."""
    from xml.sax.saxutils import quoteattr

    return quoteattr(text)


if TYPE_CHECKING:
    import meshio

__all__ = ["VTUWriter3D", "from_meshio3d", "mesh_file_dim", "read_mesh3d", "write_mesh3d"]

#: Outward local faces of the linear volume cells (VTK / meshio vertex order).
LOCAL_FACES: dict[str, tuple[tuple[int, ...], ...]] = {
    "tetra": TET_FACES,
    "hexahedron": HEX_FACES,
    "wedge": ((0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)),
    "pyramid": ((0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)),
}
_SURFACE = ("triangle", "quad", "polygon")
_KEYS = ("vemwear:boundary_offsets", "vemwear:boundary_vertices", "vemwear:boundary_tags")


def _vtk_faces(mesh: Mesh3D, cells: NDArray[np.int64]) -> tuple[NDArray, NDArray]:
    """VTK polyhedron ``faces`` and ``faceoffsets`` of the cells in the given order:
    per cell its face count, then per face its size and outward vertex loop."""
    nf = np.diff(mesh.cell_offsets)[cells]
    ent_off, ent = take_loops(mesh.cell_offsets, np.arange(len(mesh.cell_faces)), cells)
    f, sign = mesh.cell_faces[ent], mesh.cell_face_signs[ent]
    size = mesh.face_sizes[f]
    cell_len = 1 + np.add.reduceat(1 + size, ent_off[:-1]) if len(ent) else np.ones(0, int)
    cell_start = np.concatenate([[0], np.cumsum(cell_len)[:-1]]).astype(np.int64)
    g = np.concatenate([[0], np.cumsum(1 + size)[:-1]])
    cell_of = np.repeat(np.arange(len(cells)), nf)
    estart = cell_start[cell_of] + 1 + g - g[ent_off[:-1]][cell_of]
    out = np.empty(int(cell_len.sum()), dtype=np.int64)
    out[cell_start] = nf
    out[estart] = size
    loff, lv = take_loops(mesh.face_offsets, mesh.face_vertices, f)
    lv = reverse_loops(loff, lv, sign < 0)
    out[np.repeat(estart + 1 - loff[:-1], size) + np.arange(len(lv))] = lv
    return out, cell_start + cell_len


def _b64(a: NDArray) -> str:
    """VTK inline binary: base64 of a UInt32 byte count and the little-endian data."""
    data = np.ascontiguousarray(a).astype(a.dtype.newbyteorder("<"), copy=False).tobytes()
    return base64.b64encode(np.array(len(data), dtype="<u4").tobytes() + data).decode()


def _array(name: str, a: NDArray, extra: str = "") -> str:
    a = np.asarray(a)
    kind = {"f": "Float", "i": "Int", "u": "UInt"}[a.dtype.kind]
    if a.dtype.kind == "f":
        a = a.astype(np.float64)
    elif a.dtype != np.uint8:
        a = a.astype(np.int64)
    ncomp = "" if a.ndim == 1 else f' NumberOfComponents="{a.shape[1]}"'
    return (
        f'<DataArray type="{kind}{8 * a.dtype.itemsize}" Name={_quoteattr(name)}{ncomp}'
        f'{extra} format="binary">{_b64(a.ravel())}</DataArray>\n'
    )


def write_mesh3d(
    mesh: Mesh3D,
    path: str | os.PathLike[str],
    point_data: Mapping[str, ArrayLike] | None = None,
    cell_data: Mapping[str, ArrayLike] | None = None,
) -> None:
    """Write a polyhedral mesh to a ``.vtu`` file: VTK polyhedron cells, boundary parts.

    Every cell is a VTK polyhedron with its faces listed outward (ParaView shows any
    cell, convex or not). Cells are written grouped by their number of vertices (the
    way meshio reads polyhedra back) with their ids as the cell data ``cell_id``; the
    boundary parts as field data (see the module docstring).

    Parameters
    ----------
    mesh : Mesh3D
    path : str or Path
        A ``.vtu`` file.
    point_data, cell_data : mapping, optional
        Arrays to show: ``(n_points, ...)`` and ``(n_cells, ...)`` in the mesh's order.

    Raises
    ------
    MeshError
        For another suffix than ``.vtu`` or data of the wrong length.
    """
    VTUWriter3D(mesh)(path, point_data, cell_data)


class VTUWriter3D:
    """:func:`write_mesh3d` for one mesh and many fields (the levels of a series): the
    mesh's part of the file (points, polyhedra, boundary parts) is encoded once.

    Parameters
    ----------
    mesh : Mesh3D
    """

    def __init__(self, mesh: Mesh3D) -> None:
        self.mesh = mesh
        nv = np.diff(mesh.cell_vertex_offsets)
        self.order = order = np.argsort(nv, kind="stable")
        faces, faceoffsets = _vtk_faces(mesh, order)
        conn_off, conn = take_loops(mesh.cell_vertex_offsets, mesh.cell_vertex_ids, order)
        bf = mesh.boundary_faces
        boff, bv = take_loops(mesh.face_offsets, mesh.face_vertices, bf)
        field = {name: np.array([i + 1, 2]) for i, name in enumerate(mesh.part_names)}
        tags = np.asarray(mesh.boundary_tags, np.int64)
        field.update(zip(_KEYS, (boff, bv, tags), strict=True))
        self.head = "".join(
            [
                '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" '
                'byte_order="LittleEndian">\n<UnstructuredGrid>\n<FieldData>\n',
                *(_array(k, v, f' NumberOfTuples="{len(v)}"') for k, v in field.items()),
                f'</FieldData>\n<Piece NumberOfPoints="{mesh.n_points}" '
                f'NumberOfCells="{mesh.n_cells}">\n<Points>\n',
                _array("Points", mesh.points),
                "</Points>\n<Cells>\n",
                _array("connectivity", conn),
                _array("offsets", conn_off[1:]),
                _array("types", np.full(mesh.n_cells, 42, dtype=np.uint8)),
                _array("faces", faces),
                _array("faceoffsets", faceoffsets),
                "</Cells>\n",
            ]
        )
        self.cell_id = _array("cell_id", order.astype(np.int64))

    def __call__(
        self,
        path: str | os.PathLike[str],
        point_data: Mapping[str, ArrayLike] | None = None,
        cell_data: Mapping[str, ArrayLike] | None = None,
    ) -> None:
        """Write the mesh with these fields to the ``.vtu`` file ``path``."""
        mesh, path = self.mesh, Path(path)
        if path.suffix.lower() != ".vtu":
            raise MeshError(f"{path}: polyhedral meshes are written as .vtu files only")
        pd = {k: np.asarray(v) for k, v in (point_data or {}).items()}
        cd = {k: np.asarray(v) for k, v in (cell_data or {}).items()}
        for what, data, n in (("point", pd, mesh.n_points), ("cell", cd, mesh.n_cells)):
            for k, v in data.items():
                if len(v) != n:
                    raise MeshError(f"{path}: {what} data {k!r} has {len(v)} rows, expected {n}")
        own = cd.pop("cell_id", None)  # by default the cells' ids in the file's order
        parts = [
            self.head,
            "<PointData>\n",
            *(_array(k, v) for k, v in pd.items()),
            "</PointData>\n<CellData>\n",
            self.cell_id if own is None else _array("cell_id", own[self.order]),
            *(_array(k, v[self.order]) for k, v in cd.items()),
            "</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n",
        ]
        path.write_text("".join(parts))


def _polyhedra(data: list[list[NDArray]], first: int) -> tuple[NDArray, NDArray, NDArray]:
    """Face loops of meshio polyhedron cells (a list of cells, each a list of faces)."""
    faces = list(chain.from_iterable(data))
    sizes = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
    off = np.zeros(len(faces) + 1, dtype=np.int64)
    np.cumsum(sizes, out=off[1:])
    verts = np.concatenate(faces).astype(np.int64) if faces else np.zeros(0, np.int64)
    per = np.fromiter(map(len, data), dtype=np.int64, count=len(data))
    return off, verts, first + np.repeat(np.arange(len(data)), per)


def _names(m: meshio.Mesh) -> dict[int, str]:
    """Names of the surface physical groups (dimension 2) by number."""
    out = {}
    for name, v in (m.field_data or {}).items():
        v = np.asarray(v).ravel()
        if not name.startswith("vemwear:") and len(v) == 2 and int(v[1]) == 2:
            out[int(v[0])] = name
    return out


def from_meshio3d(m: meshio.Mesh) -> Mesh3D:
    """Build a :class:`Mesh3D` from a meshio mesh (see the module docstring)."""
    pts = np.asarray(m.points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
        raise MeshError("no 3D points found")
    parts: list[tuple[NDArray, NDArray, NDArray]] = []
    order: list[NDArray] = []
    surfaces: list[tuple[NDArray, NDArray, NDArray]] = []  # offsets, vertices, codes
    names = _names(m)
    part_names = list(PARTS)
    ncell = 0
    for bi, block in enumerate(m.cells):
        t = block.type
        data: Any = block.data
        if t in LOCAL_FACES or t.startswith("polyhedron"):
            if t in LOCAL_FACES:
                loops = cell_loops(np.asarray(data, np.int64), LOCAL_FACES[t], ncell)
                count = len(data)
            else:
                loops = _polyhedra(data, ncell)
                count = len(data)
            parts.append(loops)
            ids = m.cell_data.get("cell_id", [None] * len(m.cells))[bi]
            order.append(np.asarray(ids) if ids is not None else np.full(count, -1))
            ncell += count
        elif t in _SURFACE or t.startswith("polygon"):
            codes = None
            for key in ("gmsh:physical", "part"):
                if key in m.cell_data:
                    codes = np.asarray(m.cell_data[key][bi], dtype=np.int64)
                    break
            if codes is None:
                continue
            faces = [np.asarray(f, np.int64) for f in data]
            sizes = np.fromiter(map(len, faces), np.int64, len(faces))
            off = np.zeros(len(faces) + 1, dtype=np.int64)
            np.cumsum(sizes, out=off[1:])
            tags = np.zeros(len(codes), dtype=np.int64)
            for c in _unique(codes[codes > 0]):
                name = names.get(int(c), f"physical_{int(c)}")
                if name not in part_names:
                    part_names.append(name)
                tags[codes == c] = part_names.index(name) + 1
            surfaces.append((off, np.concatenate(faces) if faces else sizes, tags))
        elif t in ("vertex", "line"):
            continue
        else:
            raise MeshError(f"cell type {t!r} is not a volume cell this reader knows")
    if not parts:
        raise MeshError("no volume cells found (tetra, hexahedron, wedge, pyramid, polyhedron)")
    off = np.concatenate([[0], *[p[0][1:] + s for p, s in zip(parts, _starts(parts), strict=True)]])
    verts = np.concatenate([p[1] for p in parts])
    cells = np.concatenate([p[2] for p in parts])
    ids = np.concatenate(order)
    if np.all(ids >= 0) and len(_unique(ids)) == len(ids) and ids.max() == len(ids) - 1:
        cells = ids[cells]
    if verts.min() < 0 or verts.max() >= len(pts):
        raise MeshError(f"cells refer to vertex ids outside 0..{len(pts) - 1}")
    used = np.zeros(len(pts), dtype=bool)
    used[verts] = True
    remap = np.full(len(pts), -1, dtype=np.int64)
    remap[used] = np.arange(int(used.sum()))
    mesh = Mesh3D.from_cell_faces(
        pts[used], off, remap[verts], cells, ncell, orient=True, part_names=part_names
    )
    fd = m.field_data or {}
    if all(k in fd for k in _KEYS):
        surfaces.append(tuple(np.asarray(fd[k], np.int64).ravel() for k in _KEYS))  # type: ignore[arg-type]
        mesh = mesh.with_tags(np.asarray(mesh.boundary_tags), _stored_names(fd))
    for soff, sverts, tags in surfaces:
        if np.any(remap[sverts] < 0):
            raise MeshError("tagged surface cells use vertices of no volume cell")
        mesh = _apply_face_tags(mesh, soff, remap[sverts], tags)
    return mesh


def _starts(parts: list[tuple[NDArray, NDArray, NDArray]]) -> list[int]:
    """Offset of every block's entries in the concatenated loops."""
    return np.concatenate([[0], np.cumsum([len(p[1]) for p in parts])[:-1]]).tolist()


def _stored_names(fd: dict[str, Any]) -> tuple[str, ...]:
    """The part names of a file this module wrote (``{name: [code, 2]}``)."""
    codes = {int(np.ravel(v)[0]): k for k, v in fd.items() if not k.startswith("vemwear:")}
    return tuple(codes[i] for i in sorted(codes))


def _match_loops(a_off: NDArray, a_v: NDArray, b_off: NDArray, b_v: NDArray) -> NDArray:
    """For every loop of ``b``, the loop of ``a`` with the same vertex set (-1 if none)."""
    out = np.full(len(b_off) - 1, -1, dtype=np.int64)
    a_size, b_size = np.diff(a_off), np.diff(b_off)
    for s in np.intersect1d(a_size, b_size):
        ia, ib = np.flatnonzero(a_size == s), np.flatnonzero(b_size == s)
        rows = np.vstack(
            [
                np.sort(a_v[a_off[ia][:, None] + np.arange(s)], axis=1),
                np.sort(b_v[b_off[ib][:, None] + np.arange(s)], axis=1),
            ]
        )
        order = np.lexsort(rows.T[::-1])  # stable: a loop of a comes first in its group
        R = rows[order]
        new = np.ones(len(R), dtype=bool)
        new[1:] = np.any(R[1:] != R[:-1], axis=1)
        group = np.cumsum(new) - 1
        first = order[new][group]  # first row of every row's group
        pos = np.empty(len(R), dtype=np.int64)
        pos[order] = first
        head = pos[len(ia) :]
        out[ib] = np.where(head < len(ia), ia[np.minimum(head, len(ia) - 1)], -1)
    return out


def _apply_face_tags(mesh: Mesh3D, off: NDArray, verts: NDArray, tags: NDArray) -> Mesh3D:
    """Tag the boundary faces that the loops ``(off, verts)`` match (by vertex sets)."""
    bf = mesh.boundary_faces
    boff, bv = take_loops(mesh.face_offsets, mesh.face_vertices, bf)
    hit = _match_loops(boff, bv, off, verts)
    if np.any(hit < 0):
        i = int(np.flatnonzero(hit < 0)[0])
        raise MeshError(
            f"tagged surface face {verts[off[i] : off[i + 1]].tolist()} is not a boundary "
            "face of the volume cells"
        )
    new = np.array(mesh.boundary_tags, copy=True)
    clash = (new[hit] != 0) & (new[hit] != tags) & (tags != 0)
    if np.any(clash):
        i = int(np.flatnonzero(clash)[0])
        old, now = (mesh.part_names[int(c) - 1] for c in (new[hit[i]], tags[i]))
        raise MeshError(
            f"boundary face {int(bf[hit[i]])} is tagged both {old!r} and {now!r}; every "
            "boundary face must belong to exactly one part"
        )
    new[hit[tags > 0]] = tags[tags > 0]
    return mesh.with_tags(new)


def read_mesh3d(path: str | os.PathLike[str], *, check: bool = True) -> Mesh3D:
    """Read a polyhedral mesh file (``.msh``, ``.vtu``, any volume format meshio reads).

    Parameters
    ----------
    path : str or Path
    check : bool
        Run :func:`~vemwear.mesh.checks3d.check_mesh3d` (without boundary requirements).

    Raises
    ------
    MeshError
        ``"{path}: ..."``: no such file, a file meshio cannot read, no volume cells, a
        tagged face that is not a boundary face, or a failed check.
    """
    import meshio

    from .checks3d import check_mesh3d

    path = Path(path)
    if not path.is_file():
        raise MeshError(f"{path}: {'not a file' if path.exists() else 'no such file'}")
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            m = meshio.read(path)
    except SystemExit:
        why = " ".join(chatter.getvalue().split())
        raise MeshError(f"{path}: cannot read mesh ({why})") from None
    except Exception as exc:  # meshio raises many kinds; report them as one
        raise MeshError(f"{path}: cannot read mesh ({exc or type(exc).__name__})") from None
    try:
        mesh = from_meshio3d(m)
        if check:
            check_mesh3d(mesh)
    except MeshError as exc:
        raise MeshError(f"{path}: {exc}") from None
    except (ValueError, IndexError, KeyError, TypeError) as exc:
        raise MeshError(f"{path}: cannot read mesh ({type(exc).__name__}: {exc})") from None
    return mesh


#: meshio cell types of volume cells (and the prefix of meshio's polyhedra).
VOLUME_TYPES = (*LOCAL_FACES, "polyhedron")


def mesh_file_dim(path: str | os.PathLike[str]) -> int:
    """3 if the mesh file holds volume cells (tetrahedra, hexahedra, wedges, pyramids,
    polyhedra), else 2 (also for a file meshio cannot read: the 2D reader reports it)."""
    import meshio

    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            m = meshio.read(Path(path))
    except (Exception, SystemExit):  # the reader that follows says why
        return 2
    return 3 if any(b.type.startswith(VOLUME_TYPES) for b in m.cells) else 2
