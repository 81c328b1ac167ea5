"""Reading and writing meshes through meshio.

Cells of any vertex count are stored as meshio blocks (``triangle``, ``quad``,
``polygon``); boundary parts as ``line`` cells with an integer cell-data field
``part`` (1 clamped, 2 traction, 3 contact). Gmsh files may instead name their
boundary lines by physical groups called ``clamped``, ``traction`` and ``contact``.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import meshio
import numpy as np

from .polymesh import PARTS, Mesh, MeshError

_BLOCK = {3: "triangle", 4: "quad"}
_POLY_TYPES = ("triangle", "quad", "polygon")


def to_meshio(mesh: Mesh, with_boundary: bool = True) -> meshio.Mesh:
    """Convert to a :class:`meshio.Mesh` (points padded to 3D), cells grouped by size."""
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
        cell_data["part"].append(mesh.boundary_tags.astype(np.int32))
        cell_data["cell_id"].append(-np.ones(len(mesh.boundary_edges), np.int64))
    pts = np.column_stack([mesh.points, np.zeros(mesh.n_points)])
    return meshio.Mesh(pts, blocks, cell_data=cell_data)


def from_meshio(m: meshio.Mesh, source: str = "mesh") -> Mesh:
    """Build a :class:`Mesh` from a meshio mesh; 2D cells are reordered by cell id if present."""
    pts = np.asarray(m.points, dtype=float)
    if pts.ndim != 2 or len(pts) == 0:
        raise MeshError(f"{source}: no points found")
    if pts.shape[1] > 2:
        if np.any(np.abs(pts[:, 2:]) > 1e-12 * max(1.0, np.abs(pts).max())):
            raise MeshError(f"{source}: points are not in the plane z = 0")
        pts = pts[:, :2]
    cells: list[np.ndarray] = []
    order: list[np.ndarray] = []
    line_blocks: list[tuple[np.ndarray, np.ndarray | None]] = []
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
                tag = np.asarray(m.cell_data["part"][bi], dtype=np.int64)
            elif "gmsh:physical" in m.cell_data:
                phys = np.asarray(m.cell_data["gmsh:physical"][bi], dtype=np.int64)
                tag = np.array([_gmsh_part(names.get(int(p), ""), source) for p in phys])
            line_blocks.append((data, tag))
        elif block.type in ("vertex",):
            continue
        else:
            raise MeshError(f"{source}: cell type {block.type!r} is not a polygon")
    if not cells:
        raise MeshError(f"{source}: no polygonal cells found")
    ids = np.concatenate(order)
    if np.all(ids >= 0) and len(np.unique(ids)) == len(ids):
        cells = [cells[i] for i in np.argsort(ids)]
    # drop points not used by any 2D cell (gmsh keeps geometry points)
    used = np.zeros(len(pts), bool)
    for c in cells:
        used[c] = True
    remap = -np.ones(len(pts), np.int64)
    remap[used] = np.arange(int(used.sum()))
    mesh = Mesh.from_cells(pts[used], [remap[c] for c in cells])
    if line_blocks:
        mesh = _apply_line_tags(mesh, line_blocks, remap, source)
    return mesh


def _gmsh_part(name: str, source: str) -> int:
    if name not in PARTS:
        raise MeshError(
            f"{source}: physical group {name!r} on boundary lines is not one of {', '.join(PARTS)}"
        )
    return PARTS.index(name) + 1


def _apply_line_tags(mesh: Mesh, blocks, remap: np.ndarray, source: str) -> Mesh:
    n = mesh.n_points
    be = mesh.boundary_edges
    key = np.minimum(be[:, 0], be[:, 1]) * n + np.maximum(be[:, 0], be[:, 1])
    tags = np.array(mesh.boundary_tags, copy=True)
    for data, tag in blocks:
        if tag is None:
            continue
        e = remap[data]
        ok = np.all(e >= 0, axis=1)
        e, t = e[ok], tag[ok]
        k = np.minimum(e[:, 0], e[:, 1]) * n + np.maximum(e[:, 0], e[:, 1])
        srt = np.argsort(key)
        pos = np.clip(np.searchsorted(key[srt], k), 0, len(key) - 1)
        found = key[srt[pos]] == k
        if not np.all(found):
            bad = e[~found][:3].tolist()
            raise MeshError(f"{source}: tagged lines {bad} are not boundary edges of the cells")
        tags[srt[pos]] = t
    return Mesh(mesh.points, mesh.cell_offsets, mesh.cell_vertices, tags)


def read_mesh(path: str | Path) -> Mesh:
    """Read a mesh file (any format meshio reads, e.g. ``.vtu``, ``.msh``)."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"mesh file not found: {path}")
    try:
        # some meshio readers print to stdout, and some call sys.exit on bad files
        with contextlib.redirect_stdout(io.StringIO()):
            m = meshio.read(path)
    except SystemExit:  # some meshio readers exit on files they cannot parse
        raise MeshError(f"{path}: cannot read mesh (meshio could not parse it)") from None
    except Exception as exc:  # meshio raises many kinds; report them as one
        raise MeshError(f"{path}: cannot read mesh ({exc or type(exc).__name__})") from None
    return from_meshio(m, source=str(path))


def write_mesh(mesh: Mesh, path: str | Path, file_format: str | None = None) -> None:
    """Write a mesh (cells and tagged boundary lines) with meshio.

    Gmsh ``.msh`` holds triangles and quadrilaterals only; other polygons need ``.vtu``.
    """
    path = Path(path)
    fmt = file_format or ("gmsh22" if path.suffix == ".msh" else None)
    m = to_meshio(mesh)
    if fmt and fmt.startswith("gmsh"):
        if any(n > 4 for n in mesh.groups):
            raise MeshError(f"{path}: gmsh files hold triangles and quads only; use .vtu")
        phys = [np.where(d > 0, d, 0).astype(np.int32) for d in m.cell_data["part"]]
        m.cell_data = {"gmsh:physical": phys, "gmsh:geometrical": phys}
        m.field_data = {name: np.array([i + 1, 1]) for i, name in enumerate(PARTS)}
        m.points = m.points.copy()
    meshio.write(path, m, file_format=fmt)
