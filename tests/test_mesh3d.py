"""Polyhedral meshes: generators, geometry, checks, quality, file I/O and the 3D registry."""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np
import pytest

from vemwear.mesh import MeshError, nonconvex_mesh, rectangle_voronoi, tag_rectangle
from vemwear.mesh.checks3d import (
    check_boundary3d,
    check_cells3d,
    check_conforming3d,
    check_faces3d,
    check_mesh3d,
    check_vertices3d,
)
from vemwear.mesh.generate3d import (
    BOX_SIDES,
    box_hexahedra,
    box_tetrahedra,
    cell_loops,
    extrude,
    tag_box,
)
from vemwear.mesh.io3d import read_mesh3d, write_mesh3d
from vemwear.mesh.polyhedra import Mesh3D
from vemwear.mesh.quality3d import quality_report3d
from vemwear.mesh.registry3d import FAMILIES_3D, family3d, generate_mesh3d
from vemwear.mesh.voronoi3d import box_voronoi, halton

SIZE = (2.0, 1.0, 1.0)


def _meshes() -> dict[str, Mesh3D]:
    return {
        "hexahedra": box_hexahedra(SIZE, (4, 3, 2)),
        "tetrahedra": box_tetrahedra(SIZE, (3, 2, 2)),
        "prisms_nonconvex": tag_box(extrude(nonconvex_mesh((2.0, 1.0), (4, 3), depth=0.6), 3)),
        "prisms_voronoi": tag_box(extrude(rectangle_voronoi((2.0, 1.0), 20, seed=1), 2)),
        "voronoi3d": box_voronoi(SIZE, 97, seed=5),
    }


MESHES = _meshes()


def _signed_area_sums(m: Mesh3D) -> np.ndarray:
    s = np.zeros((m.n_cells, 3))
    np.add.at(s, m.cell_of_entry, m.cell_face_signs[:, None] * m.face_area_vectors[m.cell_faces])
    return s


# ----------------------------------------------------------------------------- generators
def test_counts() -> None:
    assert box_hexahedra(SIZE, (4, 3, 2)).n_cells == 24
    assert box_tetrahedra(SIZE, (3, 2, 2)).n_cells == 6 * 12
    for n in (2, 7, 64, 301):
        assert box_voronoi(SIZE, n, seed=n).n_cells == n
    m = box_hexahedra(SIZE, (4, 3, 2))
    assert m.n_points == 5 * 4 * 3
    assert m.n_faces == 5 * 3 * 2 + 4 * 4 * 2 + 4 * 3 * 3


@pytest.mark.parametrize("name", list(MESHES))
def test_closed_oriented_and_filling_the_box(name: str) -> None:
    m = MESHES[name]
    check_mesh3d(m, require=BOX_SIDES)
    scale = np.abs(m.face_area_vectors).max()
    assert np.abs(_signed_area_sums(m)).max() < 1e-13 * scale  # closed cells
    assert np.all(m.cell_volumes > 0)
    assert m.cell_volumes.sum() == pytest.approx(2.0, abs=1e-12)
    assert np.bincount(m.cell_faces).max() <= 2
    assert m.face_areas[m.boundary_faces].sum() == pytest.approx(10.0, abs=1e-12)
    # every boundary face on a side, outward normal = that side's normal
    outward = m.face_normals[m.boundary_faces] * m.boundary_face_signs[:, None]
    expect: dict[str, list[int]] = {"xmin": [-1, 0, 0], "xmax": [1, 0, 0], "ymin": [0, -1, 0]}
    expect |= {"ymax": [0, 1, 0], "zmin": [0, 0, -1], "zmax": [0, 0, 1]}
    total = 0.0
    for side, normal in expect.items():
        on = np.asarray(m.boundary_tags == m.part_names.index(side) + 1)
        assert on.any()
        np.testing.assert_allclose(outward[on] - np.array(normal), 0.0, atol=1e-12)
        axis = int(np.flatnonzero(normal)[0])
        plane = 0.0 if min(normal) < 0 else SIZE[axis]
        assert np.allclose(m.face_centroids[m.part_faces(side), axis], plane, atol=1e-12)
        total += m.face_areas[m.part_faces(side)].sum()
    assert total == pytest.approx(10.0, abs=1e-12)
    # centroids: the volume-weighted sum is the box's centroid
    c = (m.cell_volumes[:, None] * m.cell_centroids).sum(axis=0) / 2.0
    np.testing.assert_allclose(c, [1.0, 0.5, 0.5], atol=1e-12)


def test_hexahedra_geometry_exact() -> None:
    m = box_hexahedra((1.0, 1.0, 1.0), (2, 2, 2), origin=(1.0, 2.0, 3.0))
    np.testing.assert_allclose(m.cell_volumes, 0.125)
    np.testing.assert_allclose(m.cell_diameters, np.sqrt(3) / 2)
    np.testing.assert_allclose(m.cell_centroids[0], [1.25, 2.25, 3.25])
    np.testing.assert_allclose(m.face_areas, 0.25)
    assert len(m.edges) == 3 * (2 * 3 * 3)  # edges of a 2 x 2 x 2 grid
    assert m.points.min(axis=0).tolist() == [1.0, 2.0, 3.0]


def test_tetrahedra_conforming_kuhn_split() -> None:
    m = box_tetrahedra((1.0, 1.0, 1.0), (2, 2, 2))
    np.testing.assert_allclose(m.cell_volumes, 1 / 48)
    assert np.all(m.face_sizes == 3)
    # interior faces are shared by two tetrahedra: faces = (4 * cells + boundary) / 2
    assert m.n_faces == (4 * m.n_cells + len(m.boundary_faces)) // 2
    assert len(m.boundary_faces) == 6 * 4 * 2
    assert m.n_points == 27  # no new vertices


def test_extrude_nonconvex_prisms_keep_the_2d_parts() -> None:
    m2 = tag_rectangle(nonconvex_mesh((2.0, 1.0), (4, 3), depth=0.6))
    m = extrude(m2, z=[0.0, 0.2, 0.7, 1.0])
    assert m.n_cells == 3 * m2.n_cells
    np.testing.assert_allclose(m.cell_volumes[: m2.n_cells], 0.2 * m2.cell_areas)
    assert m.part_names[:3] == m2.part_names[:3] and m.part_names[-2:] == ("zmin", "zmax")
    lengths = np.linalg.norm(
        m2.points[m2.part_edges("contact")[:, 1]] - m2.points[m2.part_edges("contact")[:, 0]],
        axis=1,
    )
    assert m.face_areas[m.part_faces("contact")].sum() == pytest.approx(lengths.sum() * 1.0)
    assert np.allclose(m.face_centroids[m.part_faces("contact"), 1], 0.0)
    assert np.allclose(m.face_centroids[m.part_faces("zmax"), 2], 1.0)
    check_mesh3d(m, require=("clamped", "contact", "traction", "zmin", "zmax"))
    rep = quality_report3d(m)
    assert np.array_equal(rep.n_faces, 2 + np.tile(m2.cell_sizes, 3))


def test_tag_box_parts_and_sides() -> None:
    m = box_hexahedra(SIZE, (2, 2, 2))
    a = tag_box(m, {"clamped": "xmin", "contact": "zmin", "traction": ["xmax", "ymin"]})
    b = tag_box(m, sides={"xmin": "clamped", "zmin": "contact", "xmax": "traction"})
    assert len(a.part_faces("clamped")) == len(b.part_faces("clamped")) == 4
    assert len(a.part_faces("traction")) == 8 and len(b.part_faces("traction")) == 4
    assert np.sum(a.boundary_tags == 0) == 2 * 4  # ymax and zmax
    with pytest.raises(ValueError, match="unknown side 'left'"):
        tag_box(m, {"clamped": "left"})


def test_voronoi_deterministic_and_from_seeds() -> None:
    a, b = box_voronoi(SIZE, 50, seed=2), box_voronoi(SIZE, 50, seed=2)
    np.testing.assert_array_equal(a.points, b.points)
    c = box_voronoi(SIZE, 50, seed=3)
    assert c.n_points != a.n_points or not np.array_equal(a.points, c.points)
    seeds = np.array([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5]])
    m = box_voronoi(SIZE, seeds=seeds, lloyd_iterations=0)
    np.testing.assert_allclose(m.cell_volumes, [1.0, 1.0])
    assert m.n_faces == 11  # 2 x 5 sides and the middle face
    with pytest.raises(ValueError, match="strictly inside"):
        box_voronoi(SIZE, seeds=[[0.0, 0.5, 0.5], [1.0, 0.5, 0.5]])


@pytest.mark.parametrize("n, seed", [(60, 4), (400, 0)])
def test_voronoi_cells_are_the_voronoi_cells_of_their_seeds(n: int, seed: int) -> None:
    """Without Lloyd iterations, every vertex of cell k is as close to seed k as to any
    other seed (its nearest seeds, by a k-d tree); every interior face lies on the
    bisector of its two cells' seeds; the cells fill the box."""
    from scipy.spatial import cKDTree

    seeds = np.clip(np.asarray(SIZE) * halton(n, 3, seed), 1e-6, np.asarray(SIZE) - 1e-6)
    m = box_voronoi(SIZE, seeds=seeds, lloyd_iterations=0)
    check_mesh3d(m)
    h = (np.prod(SIZE) / n) ** (1 / 3)
    nearest, _ = cKDTree(seeds).query(m.points)
    cell = np.repeat(np.arange(n), np.diff(m.cell_vertex_offsets))
    own = np.linalg.norm(m.points[m.cell_vertex_ids] - seeds[cell], axis=1)
    np.testing.assert_allclose(own, nearest[m.cell_vertex_ids], atol=1e-12 * h)
    uses = np.bincount(m.cell_faces, minlength=m.n_faces)
    inner = np.flatnonzero(uses == 2)
    a = np.full(m.n_faces, -1)
    b = np.full(m.n_faces, -1)
    pos = m.cell_face_signs > 0
    a[m.cell_faces[pos]] = m.cell_of_entry[pos]
    b[m.cell_faces[~pos]] = m.cell_of_entry[~pos]
    owner = np.repeat(np.arange(m.n_faces), m.face_sizes)
    x = m.points[m.face_vertices]
    da = np.linalg.norm(x - seeds[a[owner]], axis=1)
    db = np.linalg.norm(x - seeds[b[owner]], axis=1)
    on = np.isin(owner, inner)
    np.testing.assert_allclose(da[on], db[on], atol=1e-12 * h)
    assert m.cell_volumes.sum() == pytest.approx(np.prod(SIZE), rel=1e-12)


# ----------------------------------------------------------------------------- checks
def _cube_loops(m: Mesh3D) -> tuple[np.ndarray, np.ndarray]:
    return m.face_offsets.copy(), m.face_vertices.copy()


def _with(m: Mesh3D, **changes: object) -> Mesh3D:
    args = {
        "points": m.points,
        "face_offsets": m.face_offsets,
        "face_vertices": m.face_vertices,
        "cell_offsets": m.cell_offsets,
        "cell_faces": m.cell_faces,
        "cell_face_signs": m.cell_face_signs,
    }
    args.update(changes)  # type: ignore[arg-type]
    return Mesh3D(**args)  # type: ignore[arg-type]


def test_checks_catch_their_defects() -> None:
    m = box_hexahedra((1.0, 1.0, 1.0), (2, 1, 1))
    # a face with the wrong sign: edges used twice in one direction
    s = m.cell_face_signs.copy()
    s[0] = -s[0]
    with pytest.raises(MeshError, match=r"cells \[0\] are not closed or their faces are misori"):
        check_cells3d(_with(m, cell_face_signs=s))
    # all signs of a cell reversed: closed but inverted
    s = m.cell_face_signs.copy()
    s[m.cell_offsets[1] :] *= -1
    with pytest.raises(MeshError, match=r"cells \[1\] are inverted \(negative volume\)"):
        check_cells3d(_with(m, cell_face_signs=s))
    # a face dropped from a cell: not closed
    keep = np.ones(len(m.cell_faces), dtype=bool)
    keep[0] = False
    off = m.cell_offsets - np.array([0, 1, 1])
    with pytest.raises(MeshError, match=r"cells \[0\] are not closed: edge"):
        check_cells3d(_with(m, cell_faces=m.cell_faces[keep], cell_offsets=off,
                            cell_face_signs=m.cell_face_signs[keep]))  # fmt: skip
    # a vertex moved off its face's plane
    p = m.points.copy()
    p[-1, 2] += 0.01
    with pytest.raises(MeshError, match=r"are not planar: a vertex lies up to"):
        check_faces3d(_with(m, points=p))
    # a degenerate cell: the top of the box squashed onto the bottom
    p = m.points.copy()
    p[:, 2] = 0.0
    with pytest.raises(MeshError, match=r"faces .* are degenerate \(zero area\)"):
        check_faces3d(_with(m, points=p))
    with pytest.raises(MeshError, match=r"cells \[0, 1\] are degenerate \(zero volume\)"):
        check_cells3d(_with(m, points=p))
    # duplicate vertices: a copy of vertex 0 used by nothing
    with pytest.raises(MeshError, match=r"vertices \[12\] belong to no cell"):
        check_vertices3d(_with(m, points=np.vstack([m.points, m.points[:1]])))
    p = m.points.copy()
    p[1] = p[0]
    with pytest.raises(MeshError, match=r"duplicate vertices \(same coordinates\): pairs \[\[0, 1"):
        check_vertices3d(_with(m, points=p))
    # a face listing a vertex twice
    fv = m.face_vertices.copy()
    fv[1] = fv[0]
    with pytest.raises(MeshError, match=r"faces \[0\] list a vertex twice"):
        check_faces3d(_with(m, face_vertices=fv))


def test_non_conforming_faces_are_found() -> None:
    # two cubes side by side, the shared face stored twice (once per cube)
    pts = box_hexahedra((1.0, 1.0, 1.0), (2, 1, 1)).points
    hexes = np.array([[0, 1, 4, 3, 6, 7, 10, 9], [1, 2, 5, 4, 7, 8, 11, 10]])
    loops = cell_loops(hexes, ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5),
                               (2, 3, 7, 6), (3, 0, 4, 7)))  # fmt: skip
    ok = Mesh3D.from_cell_faces(pts, *loops)
    check_mesh3d(ok)
    off, fv, _cells = loops
    # the second cube's copy of the shared face gets a new face id (a duplicate loop)
    sep = Mesh3D(pts, off, fv, np.array([0, 6, 12]), np.arange(12), np.ones(12, np.int8))
    with pytest.raises(MeshError, match=r"faces 3 and 11 have the same vertices \[1, 4, 7, 10\]"):
        check_conforming3d(sep)
    # a big face against four small ones without the hanging nodes: edges unmatched
    fine = box_hexahedra((1.0, 1.0, 1.0), (1, 2, 2), origin=(1.0, 0.0, 0.0))
    coarse = box_hexahedra((1.0, 1.0, 1.0), (1, 1, 1))
    P = np.vstack([coarse.points, fine.points])
    n = coarse.n_points
    fo = np.concatenate([coarse.face_offsets, fine.face_offsets[1:] + coarse.face_offsets[-1]])
    fv2 = np.concatenate([coarse.face_vertices, fine.face_vertices + n])
    co = np.concatenate([coarse.cell_offsets, fine.cell_offsets[1:] + 6])
    cf = np.concatenate([coarse.cell_faces, fine.cell_faces + coarse.n_faces])
    cs = np.concatenate([coarse.cell_face_signs, fine.cell_face_signs])
    glued = Mesh3D(P, fo, fv2, co, cf, cs)
    from scipy.spatial import cKDTree

    pairs = cKDTree(P).query_pairs(1e-12, output_type="ndarray")  # merge the shared corners
    remap = np.arange(len(P))
    remap[pairs[:, 1]] = pairs[:, 0]
    glued = Mesh3D(P, fo, remap[fv2], co, cf, cs)
    with pytest.raises(MeshError, match=r"non-conforming faces: vertex \d+ lies on edge"):
        check_conforming3d(glued)
    # a face missing from the boundary: its edges are matched by no other face
    hole = Mesh3D(ok.points, ok.face_offsets, ok.face_vertices, np.array([0, 6, 11]),
                  ok.cell_faces[:11], ok.cell_face_signs[:11])  # fmt: skip
    with pytest.raises(MeshError, match=r"non-conforming faces .* is not matched by exactly one"):
        check_conforming3d(hole)
    # the same sign in both cells
    s = ok.cell_face_signs.copy()
    shared = np.flatnonzero(np.bincount(ok.cell_faces) == 2)[0]
    s[ok.cell_faces == shared] = 1
    with pytest.raises(MeshError, match=rf"faces \[{shared}\] have the same sign in both"):
        check_conforming3d(_with(ok, cell_face_signs=s))


def test_boundary_check_and_constructor_errors() -> None:
    m = box_hexahedra(SIZE, (2, 1, 1))
    with pytest.raises(MeshError, match=r"the mesh has no 'contact' boundary faces"):
        check_boundary3d(m, ("contact",))
    bare = m.with_tags(np.zeros(len(m.boundary_faces), np.int8))
    with pytest.raises(MeshError, match=r"10 boundary faces have no boundary part"):
        check_boundary3d(bare)
    with pytest.raises(MeshError, match="belong to more than two cells"):
        _with(m, cell_faces=np.zeros_like(m.cell_faces))


# ----------------------------------------------------------------------------- quality
@pytest.mark.parametrize("name", list(MESHES))
def test_quality_report_on_every_family(name: str) -> None:
    m = MESHES[name]
    rep = quality_report3d(m)
    text = str(rep)
    assert f"{m.n_cells} cells, {m.n_faces} faces, {m.n_points} vertices" in text
    summary = rep.summary()
    assert 0 < summary["|K|^(1/3) / h_K"][0] <= summary["|K|^(1/3) / h_K"][2] < 0.7
    assert summary["face planarity"][2] < 1e-10
    assert np.all(rep.n_faces >= 4) and np.all(rep.n_vertices >= 4)
    if name == "hexahedra":
        lo, _mean, hi = summary["|K|^(1/3) / h_K"]
        assert lo == pytest.approx(hi) and rep.ok


def test_quality_report_cube_and_kuhn_values() -> None:
    cube = quality_report3d(box_hexahedra((1.0, 1.0, 1.0), (1, 1, 1)))
    assert cube.volume_ratio[0] == pytest.approx(1 / np.sqrt(3))
    assert cube.rho_ratio[0] == pytest.approx(0.5 / np.sqrt(3))
    assert cube.edge_ratio[0] == pytest.approx(1 / np.sqrt(3))
    tet = quality_report3d(box_tetrahedra((1.0, 1.0, 1.0), (1, 1, 1)))
    np.testing.assert_allclose(tet.volume_ratio, (1 / 6) ** (1 / 3) / np.sqrt(3))


# ----------------------------------------------------------------------------- files
@pytest.mark.parametrize("name", ["hexahedra", "prisms_nonconvex", "voronoi3d"])
def test_vtu_round_trip(name: str, tmp_path: Path) -> None:
    m = MESHES[name]
    path = tmp_path / "m.vtu"
    write_mesh3d(m, path, cell_data={"volume": m.cell_volumes}, point_data={"x": m.points})
    back = read_mesh3d(path)
    np.testing.assert_allclose(back.points, m.points)
    np.testing.assert_allclose(back.cell_volumes, m.cell_volumes, rtol=1e-13)
    np.testing.assert_allclose(back.cell_centroids, m.cell_centroids, atol=1e-13)
    assert back.part_names == m.part_names
    for part in m.part_names:
        np.testing.assert_allclose(
            np.sort(back.face_areas[back.part_faces(part)]),
            np.sort(m.face_areas[m.part_faces(part)]),
        )
    raw = meshio.read(path)
    assert all(b.type.startswith("polyhedron") for b in raw.cells)
    ids = np.concatenate(raw.cell_data["cell_id"])
    vol = np.concatenate(raw.cell_data["volume"])
    np.testing.assert_allclose(vol, m.cell_volumes[ids])


def _gmsh_file(path: Path, cells: list[tuple[str, np.ndarray]], points: np.ndarray, tri) -> None:
    """A gmsh 2.2 file: volume cells in group 7 'body', the boundary triangles tagged."""
    tri_cells, tri_phys = tri
    phys = [np.full(len(c), 7) for _, c in cells] + [tri_phys]
    meshio.write(
        path,
        meshio.Mesh(
            points,
            [*cells, ("triangle", tri_cells)],
            cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
            field_data={
                "bottom": np.array([1, 2]),
                "top": np.array([2, 2]),
                "body": np.array([7, 3]),
            },
        ),
        file_format="gmsh22",
        binary=False,
    )


def test_gmsh_tetrahedra_with_physical_groups(tmp_path: Path) -> None:
    t = box_tetrahedra((1.0, 1.0, 1.0), (2, 2, 2))
    tets = t.cell_vertex_ids.reshape(-1, 4)[:, [0, 1, 2, 3]]
    bottom, top = t.part_faces("zmin"), t.part_faces("zmax")
    faces = np.concatenate([bottom, top])
    tri = t.face_vertices[t.face_offsets[faces][:, None] + np.arange(3)]
    phys = np.r_[np.ones(len(bottom), int), np.full(len(top), 2)]
    pts = np.vstack([t.points, [[5.0, 5.0, 5.0]]])  # a geometry point of no cell
    _gmsh_file(tmp_path / "t.msh", [("tetra", tets)], pts, (tri, phys))
    m = read_mesh3d(tmp_path / "t.msh")  # sorted vertex lists: half of them inside out
    assert m.n_cells == t.n_cells and m.n_points == t.n_points
    np.testing.assert_allclose(m.cell_volumes, 1 / 48)
    assert m.part_names[-2:] == ("bottom", "top")
    assert len(m.part_faces("bottom")) == len(m.part_faces("top")) == 8
    assert np.allclose(m.face_centroids[m.part_faces("top"), 2], 1.0)
    assert np.sum(m.boundary_tags == 0) == len(m.boundary_faces) - 16


def test_gmsh_hexahedra_and_wedges(tmp_path: Path) -> None:
    h = box_hexahedra((2.0, 1.0, 1.0), (2, 1, 1))
    hexes = np.array([[0, 1, 4, 3, 6, 7, 10, 9]])
    # the second cube as two wedges (triangles 1-2-5 and 1-5-4 extruded)
    wedges = np.array([[1, 2, 5, 7, 8, 11], [1, 5, 4, 7, 11, 10]])
    wedges[1] = wedges[1][[0, 2, 1, 3, 5, 4]]  # the other orientation convention
    tri = (np.array([[1, 2, 5]]), np.array([1]))
    _gmsh_file(tmp_path / "hw.msh", [("hexahedron", hexes), ("wedge", wedges)], h.points, tri)
    m = read_mesh3d(tmp_path / "hw.msh")
    np.testing.assert_allclose(m.cell_volumes, [1.0, 0.5, 0.5])
    assert len(m.boundary_faces) == 5 + 4 + 3  # the cube's, two triangles below and above
    with pytest.raises(MeshError, match="is not a boundary face"):
        tri = (np.array([[1, 4, 7]]), np.array([1]))  # inside the box
        _gmsh_file(tmp_path / "bad.msh", [("hexahedron", hexes), ("wedge", wedges)], h.points, tri)
        read_mesh3d(tmp_path / "bad.msh")


def test_read_errors(tmp_path: Path) -> None:
    with pytest.raises(MeshError, match="no such file"):
        read_mesh3d(tmp_path / "nothing.vtu")
    with pytest.raises(MeshError, match=r"\.vtu files only"):
        write_mesh3d(MESHES["hexahedra"], tmp_path / "m.msh")
    flat = meshio.Mesh(np.zeros((3, 3)), [("triangle", np.array([[0, 1, 2]]))])
    meshio.write(tmp_path / "flat.vtu", flat)
    with pytest.raises(MeshError, match="no volume cells found"):
        read_mesh3d(tmp_path / "flat.vtu")


# ----------------------------------------------------------------------------- registry
def test_registry_3d_families() -> None:
    assert set(FAMILIES_3D) == {"hexahedra", "tetrahedra", "prisms", "voronoi3d"}
    assert family3d("box_voronoi").name == "voronoi3d"
    with pytest.raises(ValueError, match="did you mean 'hexahedra'"):
        family3d("hexahedron")
    hexa = generate_mesh3d("hexahedra", cells=32)
    assert hexa.n_cells == 32 and quality_report3d(hexa).edge_ratio.min() > 0.3
    tets = generate_mesh3d("tetrahedra", divisions=(2, 1, 1))
    assert tets.n_cells == 12
    vor = generate_mesh3d("voronoi3d", cells=40, seed=1)
    assert vor.n_cells == 40
    pr = generate_mesh3d("prisms", cells=16, seed=2, params={"layers": 3})
    assert pr.n_cells == 48 and FAMILIES_3D["prisms"].estimate_cells({"n_cells": 16}) == 64
    sq = generate_mesh3d("prisms", cells=8, params={"layers": 2, "base": "squares"})
    np.testing.assert_allclose(sq.cell_volumes, 2.0 / 16)
    for m in (hexa, tets, vor, pr, sq):
        check_mesh3d(m, require=BOX_SIDES)
        assert m.part_names[:3] == ("clamped", "traction", "contact")
        assert m.part_names[3:] == BOX_SIDES
    with pytest.raises(MeshError, match="does not take --divisions"):
        generate_mesh3d("voronoi3d", divisions=(2, 2, 2))
    with pytest.raises(MeshError, match="multiple of 6"):
        generate_mesh3d("tetrahedra", cells=10)
    with pytest.raises(MeshError, match="is deterministic"):
        generate_mesh3d("hexahedra", cells=8, seed=1)
