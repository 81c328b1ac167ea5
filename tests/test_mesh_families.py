"""Voronoi meshes, mesh families, local refinement with hanging nodes, and A1 quality."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.mesh import (
    Mesh,
    MeshError,
    check_mesh,
    distorted_quads,
    hexagons,
    l_shape_domain,
    nonconvex_mesh,
    quality_report,
    rectangle_domain,
    rectangle_squares,
    rectangle_triangles,
    rectangle_voronoi,
    refine_along,
    refine_cells,
    refine_where,
    segment_predicate,
    squares_with_hanging_nodes,
    tag_rectangle,
    voronoi_from_seeds,
    voronoi_mesh,
)
from vemwear.mesh.polymesh import part_code

RECT = rectangle_domain((2.0, 1.0))
LSHAPE = l_shape_domain((2.0, 2.0), (1.0, 1.0))


def _sides(domain: np.ndarray) -> list:
    return [segment_predicate(domain[i], domain[(i + 1) % len(domain)]) for i in range(len(domain))]


def _tag_l(mesh: Mesh) -> Mesh:
    return mesh.with_boundary(
        {
            "clamped": lambda m: np.abs(m[:, 0]) < 1e-12,
            "contact": lambda m: np.abs(m[:, 1]) < 1e-12,
            "traction": "rest",
        }
    )


def _assert_on_domain_boundary(mesh: Mesh, domain: np.ndarray) -> None:
    """Every boundary edge lies on one domain side; every corner is a vertex."""
    a = mesh.points[mesh.boundary_edges[:, 0]]
    b = mesh.points[mesh.boundary_edges[:, 1]]
    for p in (a, b, 0.5 * (a + b)):
        on = np.any([f(p) for f in _sides(domain)], axis=0)
        assert np.all(on)
    for c in domain:
        assert np.min(np.linalg.norm(mesh.points - c, axis=1)) == 0.0


def _area(domain: np.ndarray) -> float:
    x, y = domain[:, 0], domain[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


# ----------------------------------------------------------------------------- Voronoi
@pytest.mark.parametrize("n", [1, 10, 100, 2048])
def test_voronoi_rectangle_exact_count_and_valid(n):
    mesh = voronoi_mesh(RECT, n, seed=1)
    assert mesh.n_cells == n
    assert np.all(mesh.cell_areas > 0)
    assert mesh.cell_areas.sum() == pytest.approx(2.0, rel=1e-12)
    check_mesh(tag_rectangle(mesh))
    _assert_on_domain_boundary(mesh, RECT)


@pytest.mark.parametrize("n", [3, 10, 100, 700])
def test_voronoi_l_shape_exact_count_and_valid(n):
    mesh = voronoi_mesh(LSHAPE, n, seed=0)
    assert mesh.n_cells == n
    assert mesh.cell_areas.sum() == pytest.approx(3.0, rel=1e-12)
    tagged = _tag_l(mesh)
    check_mesh(tagged)
    assert np.all(tagged.boundary_tags > 0)
    _assert_on_domain_boundary(mesh, LSHAPE)


@pytest.mark.parametrize("iterations", [0, 2])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_voronoi_few_lloyd_iterations_still_valid(seed, iterations):
    for domain in (RECT, LSHAPE):
        mesh = voronoi_mesh(domain, 300, seed=seed, lloyd_iterations=iterations)
        assert mesh.n_cells == 300
        check_mesh(_tag_l(mesh))


def test_voronoi_non_convex_domains():
    u_shape = np.array([[0, 0], [3, 0], [3, 2], [2, 2], [2, 0.5], [1, 0.5], [1, 2], [0, 2.0]])
    t = np.linspace(0, 2 * np.pi, 11)[:-1]
    r = np.where(np.arange(10) % 2 == 0, 1.0, 0.45)
    star = np.column_stack([r * np.cos(t), r * np.sin(t)])
    for domain in (u_shape, star):
        mesh = voronoi_mesh(domain, 150, seed=3, lloyd_iterations=5)
        assert mesh.n_cells == 150
        assert mesh.cell_areas.sum() == pytest.approx(_area(domain), rel=1e-12)
        check_mesh(mesh.with_boundary({"clamped": "rest"}))
        _assert_on_domain_boundary(mesh, domain)


def test_voronoi_deterministic():
    a = voronoi_mesh(RECT, 200, seed=7)
    b = voronoi_mesh(RECT, 200, seed=7)
    c = voronoi_mesh(RECT, 200, seed=8)
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.cell_offsets, b.cell_offsets)
    np.testing.assert_array_equal(a.cell_vertices, b.cell_vertices)
    assert a.n_points != c.n_points or not np.array_equal(a.points, c.points)


def test_voronoi_no_tiny_edges_and_shared_vertices():
    n, tol = 2048, 0.05
    mesh = voronoi_mesh(RECT, n, seed=0, collapse_tol=tol)
    e = mesh.edges
    length = np.linalg.norm(mesh.points[e[:, 0]] - mesh.points[e[:, 1]], axis=1)
    assert length.min() > tol * np.sqrt(2.0 / n)
    # conforming: every interior edge is used once in each direction
    de = mesh.directed_edges
    assert len(de) == 2 * len(e) - len(mesh.boundary_edges)


def test_voronoi_return_seeds_and_from_seeds():
    _mesh, seeds = voronoi_mesh(RECT, 50, seed=2, return_seeds=True)
    assert seeds.shape == (50, 2)
    again = voronoi_from_seeds(RECT, seeds)
    assert again.n_cells == 50
    check_mesh(tag_rectangle(again))
    # cell i is the region of seed i: its seed lies inside it (cells are convex here)
    for i in (0, 17, 49):
        X = again.points[again.cell(i)]
        e = np.roll(X, -1, axis=0) - X
        r = seeds[i] - X
        assert np.all(e[:, 0] * r[:, 1] - e[:, 1] * r[:, 0] >= -1e-12)


def test_voronoi_interior_centroids_from_triangles_match_the_polygons():
    """The fan-free centroids of the Lloyd iterations equal those of the ordered regions."""
    from vemwear.mesh import voronoi_diagram as vor

    rng = np.random.default_rng(4)
    seeds = rng.random((400, 2)) * [2.0, 1.0]
    lo, hi = RECT.min(axis=0), RECT.max(axis=0)
    tr = vor._triangulate(seeds, 0.5 * (lo + hi), 4.0 * float(np.linalg.norm(hi - lo)))
    fans = vor._fans(tr)
    ref = vor._area_centroid(fans.offsets, fans.centres[fans.tri])[1]
    fast = vor._interior_centroids(tr)
    assert np.abs(fast - ref).max() <= 1e-9 * np.abs(ref).max()


@pytest.mark.parametrize("domain", [RECT, LSHAPE], ids=["rectangle", "l-shape"])
def test_voronoi_initial_lattice_has_the_exact_count(domain):
    from vemwear.mesh import voronoi as vor

    for n in (1, 7, 100, 1234):
        pts = vor._initial_seeds(domain, n, np.random.default_rng(n))
        assert len(pts) == n and np.all(vor.point_in_domain(pts, domain))
        assert len(np.unique(pts, axis=0)) == n


def test_voronoi_default_iterations_keep_quality_on_many_cells():
    """The automatic iteration count (fewer Lloyd iterations for many cells)."""
    rep = quality_report(voronoi_mesh(RECT, 20_000, seed=3))
    assert rep.ok and rep.gamma1 > 0.2 and rep.gamma2 > 0.02


def test_importing_the_mesh_package_does_not_load_scipy_stats():
    import subprocess
    import sys

    code = "import sys, vemwear.mesh; print('scipy.stats' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_voronoi_input_errors():
    with pytest.raises(ValueError, match="counter-clockwise"):
        voronoi_mesh(RECT[::-1], 10)
    with pytest.raises(ValueError, match="positive"):
        voronoi_mesh(RECT, 0)
    with pytest.raises(ValueError, match="outside"):
        voronoi_from_seeds(RECT, [[0.5, 0.5], [3.0, 0.5]])
    with pytest.raises(ValueError, match="cross"):
        voronoi_mesh([[0, 0], [1, 1], [1, 0], [0, 1]], 10)


# ----------------------------------------------------------------------------- families
def _counts(mesh: Mesh) -> dict[int, int]:
    return {n: len(ids) for n, (ids, _v) in mesh.groups.items()}


def test_families_pass_check_mesh():
    meshes = {
        "distorted": distorted_quads((2.0, 1.0), (12, 6), 0.24, seed=3, slide_boundary=True),
        "hexagons": hexagons((2.0, 1.0), 10),
        "nonconvex": nonconvex_mesh((2.0, 1.0), (6, 4), depth=0.6),
        "checkerboard": squares_with_hanging_nodes((2.0, 1.0), (8, 4), "checkerboard"),
        "random": squares_with_hanging_nodes((2.0, 1.0), (8, 4), "random", seed=1),
        "voronoi": rectangle_voronoi((2.0, 1.0), 64, seed=4),
    }
    for name, mesh in meshes.items():
        check_mesh(tag_rectangle(mesh))
        assert mesh.cell_areas.sum() == pytest.approx(2.0, rel=1e-12), name
        assert np.all(mesh.cell_areas > 0), name


def test_family_cell_counts():
    assert distorted_quads((2.0, 1.0), (7, 3), 0.1).n_cells == 21
    nx, ny = 9, 5
    assert hexagons((2.0, 1.0), (nx, ny)).n_cells == nx * 3 + (nx + 1) * 2
    hx = hexagons((2.0, 1.0), 10)
    assert _counts(hx)[6] > hx.n_cells // 2  # hexagon dominant
    nc = nonconvex_mesh((2.0, 1.0), (6, 4))
    assert nc.n_cells == 24
    assert _counts(nc) == {5: 12, 6: 12}
    rep = quality_report(nc)
    assert np.sum(~rep.convex) == 18  # all but the bottom row
    assert np.all(rep.star_shaped)


def test_distorted_quads_convex_and_deterministic():
    a = distorted_quads((2.0, 1.0), (10, 5), 0.24, seed=5)
    b = distorted_quads((2.0, 1.0), (10, 5), 0.24, seed=5)
    np.testing.assert_array_equal(a.points, b.points)
    assert np.all(quality_report(a).convex)
    with pytest.raises(ValueError):
        distorted_quads(amplitude=0.3)


def test_checkerboard_hanging_nodes_counts():
    nx, ny = 8, 4
    mesh = squares_with_hanging_nodes((2.0, 1.0), (nx, ny), "checkerboard")
    refined = nx * ny // 2
    # refined cells share no edge: 4 midpoints and a centre each
    assert mesh.n_points == (nx + 1) * (ny + 1) + 5 * refined
    assert mesh.n_cells == nx * ny + 3 * refined
    # an interior unrefined square has 4 hanging nodes
    assert 8 in _counts(mesh)


# ----------------------------------------------------------------------------- refinement
def test_refine_along_contact_vertex_counts_and_tags():
    nx, ny = 8, 4
    base = tag_rectangle(rectangle_squares((2.0, 1.0), (nx, ny)))
    one = refine_along(base, "contact", 1)
    two = refine_along(base, "contact", 2)
    check_mesh(one)
    check_mesh(two)
    assert one.n_points - base.n_points == 4 * nx + 1
    assert two.n_points - one.n_points == 8 * nx + 1
    assert one.n_cells == nx * ny + 3 * nx
    assert two.n_cells == one.n_cells + 3 * 2 * nx
    for lev, mesh in ((1, one), (2, two)):
        contact = mesh.part_edges("contact")
        assert len(contact) == nx * 2**lev
        length = np.linalg.norm(mesh.points[contact[:, 1]] - mesh.points[contact[:, 0]], axis=1)
        assert length.sum() == pytest.approx(2.0)
        assert np.allclose(mesh.points[contact].reshape(-1, 2)[:, 1], 0.0)
        # the clamped side (left) now has hanging nodes and keeps its part code
        clamped = mesh.part_edges("clamped")
        assert len(clamped) == ny + lev
        assert np.allclose(mesh.points[clamped].reshape(-1, 2)[:, 0], 0.0)
    assert np.all(two.boundary_tags > 0)


def test_refine_cells_parent_map_and_in_place_order():
    base = tag_rectangle(rectangle_squares((2.0, 1.0), (4, 2)))
    mesh, parent = refine_cells(base, [1, 6], return_parent=True)
    assert mesh.n_cells == 8 + 6
    np.testing.assert_array_equal(np.bincount(parent), [1, 4, 1, 1, 1, 1, 4, 1])
    np.testing.assert_allclose(np.bincount(parent, weights=mesh.cell_areas), base.cell_areas)
    check_mesh(mesh)


@pytest.mark.parametrize(
    "make",
    [
        lambda: rectangle_triangles((2.0, 1.0), (4, 2), diagonal="alternate"),
        lambda: nonconvex_mesh((2.0, 1.0), (4, 3), depth=0.7),
        lambda: hexagons((2.0, 1.0), 6),
        lambda: rectangle_voronoi((2.0, 1.0), 40, seed=1),
        lambda: squares_with_hanging_nodes((2.0, 1.0), (4, 2), "random"),
    ],
)
def test_refine_general_polygons(make):
    base = tag_rectangle(make())
    mesh = refine_along(base, "contact", 3)
    check_mesh(mesh)
    assert mesh.cell_areas.sum() == pytest.approx(2.0, rel=1e-12)
    assert np.all(mesh.cell_areas > 0)
    # children are star-shaped: refining all again still works
    check_mesh(refine_cells(mesh, np.arange(mesh.n_cells)))


def test_refine_where_and_vertex_touching():
    base = tag_rectangle(rectangle_squares((2.0, 1.0), (8, 4)))
    disk = refine_where(base, lambda c: np.hypot(c[:, 0] - 1.0, c[:, 1] - 0.5) < 0.3, levels=3)
    check_mesh(disk)
    assert disk.n_cells > base.n_cells
    # contact on the left half of the bottom only: (1, 0) ends the part
    half = base.with_boundary(
        {"contact": segment_predicate((0.0, 0.0), (1.0, 0.0)), "traction": "rest"}
    )
    by_edge = refine_along(half, "contact", 1)
    by_vertex = refine_along(half, "contact", 1, touching="vertex")
    check_mesh(by_edge, require=("contact",))
    check_mesh(by_vertex, require=("contact",))
    assert by_edge.n_cells == base.n_cells + 3 * 4
    assert by_vertex.n_cells == base.n_cells + 3 * 5  # also the cell right of (1, 0)
    with pytest.raises(MeshError):
        refine_along(rectangle_squares(), "contact")  # untagged mesh


def test_refine_l_shape_voronoi_along_contact():
    mesh = _tag_l(voronoi_mesh(LSHAPE, 120, seed=2))
    fine = refine_along(mesh, "contact", 2)
    check_mesh(fine)
    assert np.sum(fine.boundary_tags == part_code("contact")) > np.sum(
        mesh.boundary_tags == part_code("contact")
    )
    assert fine.cell_areas.sum() == pytest.approx(3.0, rel=1e-12)


# ----------------------------------------------------------------------------- quality
def test_quality_squares_exact():
    rep = quality_report(rectangle_squares((2.0, 1.0), (8, 4)))
    np.testing.assert_allclose(rep.rho_ratio, 0.5 / np.sqrt(2.0), rtol=1e-12)
    np.testing.assert_allclose(rep.vertex_ratio, 1.0 / np.sqrt(2.0), rtol=1e-12)
    np.testing.assert_allclose(rep.area_ratio, 0.5, rtol=1e-12)
    np.testing.assert_allclose(rep.centre[0], [0.125, 0.125], atol=1e-12)
    assert rep.ok and rep.warnings == []
    text = str(rep)
    assert "rho_K / h_K" in text and "no warnings" in text


def test_quality_known_shapes():
    # right isosceles triangles with legs 1: inradius (2 - sqrt 2) / 2, h = sqrt 2
    rep = quality_report(rectangle_triangles((1.0, 1.0), (1, 1)))
    np.testing.assert_allclose(rep.rho, (2 - np.sqrt(2)) / 2, rtol=1e-12)
    # regular hexagon of circumradius 1: rho = sqrt(3)/2, h = 2
    t = np.arange(6) * np.pi / 3
    hexagon = Mesh.from_cells(np.column_stack([np.cos(t), np.sin(t)]), [list(range(6))])
    np.testing.assert_allclose(quality_report(hexagon).rho_ratio, np.sqrt(3) / 4, rtol=1e-12)
    # L-shaped cell: the kernel is the unit square [0, 1]^2
    ell = Mesh.from_cells(LSHAPE, [list(range(6))])
    rep = quality_report(ell)
    np.testing.assert_allclose(rep.rho, 0.5, rtol=1e-12)
    np.testing.assert_allclose(rep.centre[0], [0.5, 0.5], atol=1e-12)
    assert not rep.convex[0]
    # hanging nodes halve the vertex distance
    rep = quality_report(squares_with_hanging_nodes((1.0, 1.0), (2, 2), "checkerboard"))
    assert rep.gamma2 == pytest.approx(0.5 / np.sqrt(2.0))
    assert rep.gamma1 == pytest.approx(0.5 / np.sqrt(2.0))


def test_quality_warns_on_bad_meshes():
    # a column of very thin cells
    x = np.array([0.0, 0.5, 0.5005, 1.0])
    y = np.array([0.0, 0.5, 1.0])
    X, Y = np.meshgrid(x, y)
    pts = np.column_stack([X.ravel(), Y.ravel()])
    cells = [
        [j * 4 + i, j * 4 + i + 1, (j + 1) * 4 + i + 1, (j + 1) * 4 + i]
        for j in range(2)
        for i in range(3)
    ]
    thin = Mesh.from_cells(pts, cells)
    rep = quality_report(thin)
    assert not rep.ok
    assert len(rep.bad_rho) == 2 and len(rep.bad_vertex) == 2
    assert any("rho_K / h_K" in w for w in rep.warnings)
    assert "WARNING" in str(rep)
    # a comb-shaped cell is not star-shaped
    comb = np.array(
        [
            [0, 0],
            [3, 0],
            [3, 2],
            [2.5, 2],
            [2.5, 0.5],
            [2, 0.5],
            [2, 2],
            [1, 2],
            [1, 0.5],
            [0.5, 0.5],
            [0.5, 2],
            [0, 2],
        ],
        dtype=float,
    )
    rep = quality_report(Mesh.from_cells(comb, [list(range(12))]))
    assert rep.rho[0] == 0.0 and not rep.star_shaped[0]
    assert any("not star-shaped" in w for w in rep.warnings)


def test_quality_voronoi_2048_within_a1():
    rep = quality_report(voronoi_mesh(RECT, 2048, seed=0))
    assert rep.ok
    assert rep.gamma1 > 0.2
    assert rep.gamma2 > 0.02
    assert np.all(rep.convex)
