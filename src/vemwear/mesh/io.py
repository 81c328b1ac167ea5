"""Reading and writing meshes through meshio.

Cells of any vertex count are stored as meshio blocks (``triangle``, ``quad``,
``polygon``); boundary parts as ``line`` cells with an integer cell-data field
``part`` (1 clamped, 2 traction, 3 contact, then the mesh's other part names, which the
field data ``{name: [code, 1]}`` records). Gmsh files name their boundary lines by
physical groups of any name; a group without a name is ``physical_<number>``.
:func:`read_mesh` is the one reader of mesh files: it checks what it reads.
"""

from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..util.arrays import unique as _unique
from .checks import check_cells, check_conforming, check_vertices
from .polymesh import PARTS, Mesh, MeshError

if TYPE_CHECKING:
    import meshio

_BLOCK = {3: "triangle", 4: "quad"}
_POLY_TYPES = ("triangle", "quad", "polygon")


def to_meshio(mesh: Mesh, with_boundary: bool = True) -> meshio.Mesh:
    """Convert to a :class:`meshio.Mesh` (points padded to 3D), cells grouped by size."""
    import meshio  # loaded with the first mesh file: start-up time

    blocks = []
    for n, (_ids, verts) in sorted(mesh.groups.items()):
        blocks.append(meshio.CellBlock(_BLOCK.get(n, "polygon"), verts))
    cell_data: dict[str, list[np.ndarray]] = {
        "part": [np.zeros(len(b.data), np.int32) for b in blocks]
    }
    cell_ids = [ids.astype(np.int64) for _, (ids, _v) in sorted(mesh.groups.items())]
    cell_data["cell_id"] = cell_ids
    if with_boundary and len(mesh.boundary_edges):
        blocks.append(meshio.CellBlock("line", mesh.boundary_edges))
        cell_data["part"].append(np.asarray(mesh.boundary_tags, dtype=np.int32))
        cell_data["cell_id"].append(-np.ones(len(mesh.boundary_edges), np.int64))
    pts = np.column_stack([mesh.points, np.zeros(mesh.n_points)])
    field_data = {name: np.array([i + 1, 1]) for i, name in enumerate(mesh.part_names)}
    return meshio.Mesh(pts, blocks, cell_data=cell_data, field_data=field_data)


def from_meshio(m: meshio.Mesh) -> Mesh:
    """Build a :class:`Mesh` from a meshio mesh; 2D cells are reordered by cell id if present.

    Boundary parts come from ``line`` cells (see the module docstring); a line tagged
    with two different parts is a :class:`MeshError`.
    """

    pts = np.asarray(m.points, dtype=float)
    if pts.ndim != 2 or len(pts) == 0:
        raise MeshError("no points found")
    if pts.shape[1] > 2:
        if np.any(np.abs(pts[:, 2:]) > 1e-12 * max(1.0, np.abs(pts).max())):
            raise MeshError("points are not in the plane z = 0")
        pts = pts[:, :2]
    cells: list[np.ndarray] = []
    order: list[np.ndarray] = []
    line_blocks: list[tuple[np.ndarray, np.ndarray | None]] = []
    part_names = list(PARTS)  # grown by the physical groups of the file, in their order
    names = {int(v[0]): k for k, v in (m.field_data or {}).items() if len(v) and len(v) >= 1}
    for bi, block in enumerate(m.cells):
        data = np.asarray(block.data, dtype=np.int64)
        if block.type in _POLY_TYPES or block.type.startswith("polygon"):
            cells.extend(list(data))
            ids = m.cell_data.get("cell_id", [None] * len(m.cells))[bi]
            order.append(np.asarray(ids) if ids is not None else np.full(len(data), -1))
        elif block.type == "line":
            tag = None
            if "part" in m.cell_data:
                code = np.asarray(m.cell_data["part"][bi], dtype=np.int64)
                tag = np.array(
                    [
                        _gmsh_part(names.get(int(c), ""), int(c), part_names) if c > 0 else 0
                        for c in code
                    ]
                    if names
                    else code,
                    dtype=np.int64,
                )
            elif "gmsh:physical" in m.cell_data:
                phys = np.asarray(m.cell_data["gmsh:physical"][bi], dtype=np.int64)
                tag = np.array(
                    [_gmsh_part(names.get(int(p), ""), int(p), part_names) for p in phys]
                )
            line_blocks.append((data, tag))
        elif block.type in ("vertex",):
            continue
        else:
            raise MeshError(f"cell type {block.type!r} is not a polygon")
    if not cells:
        raise MeshError("no polygonal cells found")
    ids = np.concatenate(order)
    if np.all(ids >= 0) and len(_unique(ids)) == len(ids):
        cells = [cells[i] for i in np.argsort(ids)]
    # drop points not used by any 2D cell (gmsh keeps geometry points)
    used = np.zeros(len(pts), bool)
    for c in cells:
        used[c] = True
    remap = -np.ones(len(pts), np.int64)
    remap[used] = np.arange(int(used.sum()))
    mesh = Mesh.from_cells(pts[used], [remap[c] for c in cells], part_names=part_names)
    if line_blocks:
        mesh = _apply_line_tags(mesh, line_blocks, remap)
    return mesh


def _gmsh_part(name: str, number: int, part_names: list[str]) -> int:
    """The part code of a gmsh physical group (by its name; unnamed groups by number)."""
    name = name or f"physical_{number}"
    if name not in part_names:
        part_names.append(name)
    return part_names.index(name) + 1


def _apply_line_tags(mesh: Mesh, blocks, remap: np.ndarray) -> Mesh:
    n = mesh.n_points
    be = mesh.boundary_edges
    key = np.minimum(be[:, 0], be[:, 1]) * n + np.maximum(be[:, 0], be[:, 1])
    srt = np.argsort(key)
    lines = [(d, t) for d, t in blocks if t is not None]
    if not lines:
        return mesh
    data = np.concatenate([d for d, _ in lines])  # vertex ids of the file
    tag = np.concatenate([t for _, t in lines])
    e = remap[data]
    ok = np.all(e >= 0, axis=1) & (tag > 0)
    data, tag, e = data[ok], tag[ok], e[ok]
    k = np.minimum(e[:, 0], e[:, 1]) * n + np.maximum(e[:, 0], e[:, 1])
    pos = np.clip(np.searchsorted(key[srt], k), 0, len(key) - 1)
    found = key[srt[pos]] == k
    if not np.all(found):
        bad = data[~found][:3].tolist()
        raise MeshError(f"tagged lines {bad} are not boundary edges of the cells")
    _, first, inv = np.unique(k, return_index=True, return_inverse=True)
    clash = np.flatnonzero(tag != tag[first][inv])
    if clash.size:
        i = clash[0]
        a, b = data[i].tolist()
        old, new = (mesh.part_names[int(c) - 1] for c in (tag[first][inv][i], tag[i]))
        raise MeshError(
            f"boundary edge ({a}, {b}) is tagged both {old!r} and {new!r}; every boundary "
            "edge must belong to exactly one part"
        )
    tags = np.array(mesh.boundary_tags, copy=True)
    tags[srt[pos]] = tag
    return mesh.with_tags(tags)


def _check_dangling(m: meshio.Mesh) -> None:
    """Vertices that no polygonal cell uses (the reader would drop them)."""
    n = len(m.points)
    used = np.zeros(n, dtype=bool)
    for block in m.cells:
        if block.type in _POLY_TYPES or block.type.startswith("polygon"):
            ids = np.asarray(block.data, dtype=np.int64).ravel()
            if ids.size and (ids.min() < 0 or ids.max() >= n):
                raise MeshError(f"cells refer to vertex ids outside 0..{n - 1}")
            used[ids] = True
    if used.any() and not used.all():
        bad = np.flatnonzero(~used)
        more = f" and {bad.size - 10} more" if bad.size > 10 else ""
        raise MeshError(
            f"vertices {bad[:10].tolist()}{more} belong to no cell (dangling); remove them "
            "from the file"
        )


def read_mesh(path: str | os.PathLike[str], *, check: bool = True) -> Mesh:
    """Read a mesh file (any format meshio reads, e.g. ``.vtu``, ``.msh``) and check it.

    Parameters
    ----------
    path : str or Path
        The mesh file.
    check : bool
        Check the mesh: no dangling vertices (used by no cell; ``.msh`` files may keep
        geometry points, which are dropped), no duplicate vertices, no cell listing a
        vertex twice, no degenerate, clockwise or self-intersecting cells, no
        overlapping cells, conforming edges (:mod:`vemwear.mesh.checks`). Without it
        the mesh is only read (to inspect an invalid mesh).

    Returns
    -------
    Mesh
        With the boundary parts tagged in the file.

    Raises
    ------
    MeshError
        ``"{path}: ..."``: no such file, a file meshio cannot read, content that is
        not a polygonal mesh, an edge tagged with two parts, or a failed check (the
        message names the cells, vertices or edges by their ids in the file).
    """
    import meshio  # loaded with the first mesh file: start-up time

    path = Path(path)
    if not path.is_file():
        raise MeshError(f"{path}: {'not a file' if path.exists() else 'no such file'}")
    chatter = io.StringIO()  # meshio prints its reasons (and some readers call sys.exit)
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            m = meshio.read(path)
    except SystemExit:
        why = " ".join(chatter.getvalue().split())
        raise MeshError(
            f"{path}: cannot read mesh (meshio could not parse it{f': {why}' if why else ''})"
        ) from None
    except Exception as exc:  # meshio raises many kinds; report them as one
        raise MeshError(f"{path}: cannot read mesh ({exc or type(exc).__name__})") from None
    try:
        if check and path.suffix.lower() != ".msh":
            _check_dangling(m)
        mesh = from_meshio(m)
        if check:
            check_vertices(mesh)
            check_cells(mesh)
            check_conforming(mesh)
    except MeshError as exc:
        raise MeshError(f"{path}: {exc}") from None
    except (ValueError, IndexError, KeyError, TypeError) as exc:  # malformed content
        raise MeshError(
            f"{path}: cannot read mesh (malformed file: {type(exc).__name__}: {exc})"
        ) from None
    return mesh


def write_mesh(mesh: Mesh, path: str | Path, file_format: str | None = None) -> None:
    """Write a mesh (cells and tagged boundary lines) with meshio.

    Gmsh ``.msh`` holds triangles and quadrilaterals only; other polygons need ``.vtu``.

    Parameters
    ----------
    mesh : Mesh
        The mesh; its boundary parts are written as line cells with cell data ``part``.
    path : str or Path
        The file; its suffix chooses the format unless ``file_format`` is given.
    file_format : str, optional
        A meshio format name (``.msh`` files are written as ``gmsh22``).

    Raises
    ------
    MeshError
        If a Gmsh file would need cells other than triangles and quadrilaterals.
    """
    import meshio  # loaded with the first mesh file: start-up time

    path = Path(path)
    fmt = file_format or ("gmsh22" if path.suffix == ".msh" else None)
    m = to_meshio(mesh)
    if fmt and fmt.startswith("gmsh"):
        if any(n > 4 for n in mesh.groups):
            raise MeshError(f"{path}: gmsh files hold triangles and quads only; use .vtu")
        phys = [np.where(d > 0, d, 0).astype(np.int32) for d in m.cell_data["part"]]
        m.cell_data = {"gmsh:physical": phys, "gmsh:geometrical": phys}
        m.field_data = {name: np.array([i + 1, 1]) for i, name in enumerate(mesh.part_names)}
        m.points = m.points.copy()
    if fmt and fmt.startswith("gmsh"):  # ASCII: readable and portable
        meshio.write(path, m, file_format=fmt, binary=False)
    else:
        meshio.write(path, m, file_format=fmt)
