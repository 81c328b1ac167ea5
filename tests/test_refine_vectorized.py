"""refine_cells on arrays gives the same bits as the loop over cells and sides it replaced.

The reference (``tests/refine_reference.py``) is the loop-based implementation; every
case refines random subsets of cells for several rounds, so that hanging nodes of
several levels, sides made of several edges and midpoints shared by two cells occur,
and compares points (bitwise), cells (with their vertex order), tags, part names and
the parent map.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from refine_reference import refine_cells_reference
from vemwear.mesh import (
    Mesh,
    MeshError,
    distorted_quads,
    hexagons,
    l_shape_domain,
    nonconvex_mesh,
    rectangle_squares,
    rectangle_triangles,
    rectangle_voronoi,
    squares_with_hanging_nodes,
    tag_rectangle,
    voronoi_mesh,
)
from vemwear.mesh import refine as refine_mod
from vemwear.mesh.adapt import graded_closure, refine_graded
from vemwear.mesh.checks import check_cells, check_conforming, check_vertices
from vemwear.mesh.refine import corners, refine_cells


def _assert_same(mesh: Mesh, cells: np.ndarray) -> Mesh:
    """Refine ``cells`` of ``mesh`` both ways, check every array is equal, return it."""
    new, parent = refine_cells(mesh, cells, return_parent=True)
    ref, ref_parent = refine_cells_reference(mesh, cells, return_parent=True)
    assert new.points.shape == ref.points.shape
    assert new.points.tobytes() == ref.points.tobytes()  # bitwise, -0.0 and all
    assert np.array_equal(new.cell_offsets, ref.cell_offsets)
    assert np.array_equal(new.cell_vertices, ref.cell_vertices)
    assert np.array_equal(new.boundary_tags, ref.boundary_tags)
    assert new.part_names == ref.part_names
    assert parent.dtype == ref_parent.dtype
    assert np.array_equal(parent, ref_parent)
    assert np.array_equal(new.boundary_edges, ref.boundary_edges)
    return new


def _check_geometry(mesh: Mesh) -> None:
    """A valid geometry: vertices, star-shaped cells, conforming (tags not required)."""
    check_vertices(mesh)
    check_cells(mesh)
    check_conforming(mesh)


def _slide_hanging(mesh: Mesh, rng: np.random.Generator) -> Mesh:
    """Move every hanging node between two corners of its cell along that side, to a
    random place between 30 % and 70 % of it (so that side midpoints are new points and
    two cells may put two points on one edge)."""
    P = mesh.points.copy()
    moved = np.zeros(mesh.n_points, dtype=bool)
    for c in range(mesh.n_cells):
        V = mesh.cell(c)
        flat = ~corners(mesh.points[V][None])[0]
        for i in np.flatnonzero(flat):
            a, v, b = V[i - 1], V[i], V[(i + 1) % len(V)]
            if flat[i - 1] or flat[(i + 1) % len(V)] or moved[v]:
                continue
            P[v] = P[a] + rng.uniform(0.3, 0.7) * (P[b] - P[a])
            moved[v] = True
    return Mesh(P, mesh.cell_offsets, mesh.cell_vertices, mesh.boundary_tags, mesh.part_names)


def _turn_cells(mesh: Mesh, rng: np.random.Generator) -> Mesh:
    """The same cells, each vertex list started at a random vertex (often a hanging node,
    so that the first corner is not the first vertex)."""
    off, n = mesh.cell_offsets, mesh.cell_sizes
    shift = np.repeat(rng.integers(0, n), n)
    local = np.arange(mesh.cell_vertices.size) - np.repeat(off[:-1], n)
    rows = np.repeat(off[:-1], n) + (local + shift) % np.repeat(n, n)
    # the boundary edges keep their canonical order, so the tags stay as they are
    return Mesh(mesh.points, off, mesh.cell_vertices[rows], mesh.boundary_tags, mesh.part_names)


def _offset_sides() -> Mesh:
    """Three cells whose shared vertical line carries a hanging node at 0.3 of the left
    cell's side: refining the left and upper right cells puts two points on one edge."""
    pts = [[0, 0], [1, 0], [1, 0.3], [1, 1], [0, 1], [2, 0.3], [2, 1], [2, 0]]
    cells = [[0, 1, 2, 3, 4], [2, 5, 6, 3], [1, 7, 5, 2]]
    return tag_rectangle(Mesh.from_cells(np.array(pts, dtype=float), cells))


RECT = (2.0, 1.0)
MAKERS: dict[str, Callable[[], Mesh]] = {
    "squares": lambda: tag_rectangle(rectangle_squares(RECT, (8, 4))),
    "triangles": lambda: tag_rectangle(rectangle_triangles(RECT, (4, 2), diagonal="alternate")),
    "distorted": lambda: tag_rectangle(distorted_quads(RECT, (6, 3))),
    "hexagons": lambda: tag_rectangle(hexagons(RECT, 6)),
    "nonconvex": lambda: tag_rectangle(nonconvex_mesh(RECT, (4, 3), depth=0.7)),
    "voronoi": lambda: tag_rectangle(rectangle_voronoi(RECT, 40, seed=1)),
    "l_shape": lambda: voronoi_mesh(
        l_shape_domain((2.0, 2.0), (1.0, 1.0)), 60, seed=2
    ).with_boundary(
        {
            "clamped": lambda m: np.abs(m[:, 0]) < 1e-12,
            "contact": lambda m: np.abs(m[:, 1]) < 1e-12,
            "traction": "rest",
        }
    ),
    "hanging": lambda: tag_rectangle(squares_with_hanging_nodes(RECT, (6, 4), "random")),
    "untagged": lambda: rectangle_squares(RECT, (6, 3)),
    "named_parts": lambda: tag_rectangle(
        rectangle_squares(RECT, (6, 3)), {"rollers": ["left", "right"], "base": "bottom"}
    ),
    "offset_sides": _offset_sides,
}


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("name", sorted(MAKERS))
def test_random_rounds_match_the_loop(name, seed):
    rng = np.random.default_rng(seed)
    mesh = MAKERS[name]()
    for _ in range(4):
        fraction = rng.uniform(0.2, 0.6)
        cells = rng.choice(mesh.n_cells, size=max(1, int(fraction * mesh.n_cells)), replace=False)
        mesh = _assert_same(mesh, cells)


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("name", ["hanging", "squares", "voronoi"])
def test_slid_hanging_nodes_match_the_loop(name, seed):
    """Hanging nodes off the middle of their side: new midpoints on sides of several
    edges, two points on one edge, both inserted into both cells in their order; vertex
    lists that start anywhere."""
    rng = np.random.default_rng(seed)
    mesh = MAKERS[name]()
    two_on_one_edge = 0
    for _ in range(4):
        mesh = _turn_cells(_slide_hanging(mesh, rng), rng)
        cells = np.sort(rng.choice(mesh.n_cells, size=mesh.n_cells // 2, replace=False))
        mids = refine_mod._midpoints(
            mesh, refine_mod._sides(mesh, cells, refine_mod._batches(mesh, cells))
        )
        two_on_one_edge += mids.code.size - np.unique(mids.code).size
        mesh = _assert_same(mesh, cells)
        _check_geometry(mesh)
    assert two_on_one_edge > 0


def test_two_points_on_one_edge():
    mesh = _offset_sides()
    new = _assert_same(mesh, [0, 1])
    # the left cell's side gets (1, 0.5), the upper cell's (1, 0.65); both cells hold both
    on_line = np.flatnonzero(new.points[:, 0] == 1.0)
    assert np.allclose(np.sort(new.points[on_line, 1]), [0.0, 0.3, 0.5, 0.65, 1.0])
    _check_geometry(new)


@pytest.mark.parametrize("name", ["squares", "voronoi", "hanging"])
def test_graded_rounds_and_whole_meshes_match_the_loop(name):
    """Graded closure (neighbours one level apart), then every cell at once."""
    rng = np.random.default_rng(5)
    mesh = MAKERS[name]()
    level = np.zeros(mesh.n_cells, dtype=np.int64)
    for _ in range(4):
        marked = rng.choice(mesh.n_cells, size=max(1, mesh.n_cells // 5), replace=False)
        new = _assert_same(mesh, graded_closure(mesh, level, marked))
        mesh, level, _ = refine_graded(mesh, level, marked)
        assert np.array_equal(mesh.cell_vertices, new.cell_vertices)
    assert level.max() == 4
    _assert_same(mesh, np.arange(mesh.n_cells))


def test_repeated_and_unsorted_ids_and_empty_selection():
    mesh = MAKERS["hanging"]()
    _assert_same(mesh, [7, 3, 3, 12, 7, 0])
    same, parent = refine_cells(mesh, [], return_parent=True)
    assert same is mesh
    assert np.array_equal(parent, np.arange(mesh.n_cells))
    with pytest.raises(ValueError, match="cell ids must lie in"):
        refine_cells(mesh, [mesh.n_cells])


def test_too_few_corners_named_as_before():
    """A sliver whose apex is within the straightness tolerance has two corners."""
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [2, 0], [1.5, 1e-11]], dtype=float)
    mesh = Mesh.from_cells(pts, [[0, 1, 2, 3], [1, 4, 5]])
    with pytest.raises(MeshError) as new:
        refine_cells(mesh, [0, 1])
    with pytest.raises(MeshError) as ref:
        refine_cells_reference(mesh, [0, 1])
    assert str(new.value) == str(ref.value) == "cell 1 has fewer than three corners"


def test_every_midpoint_an_existing_vertex():
    """Squares whose four sides all carry a hanging node at their middle: no new point
    but the centres."""
    mesh = tag_rectangle(squares_with_hanging_nodes(RECT, (6, 4), "checkerboard"))
    cells = np.flatnonzero(mesh.cell_sizes == 8)
    assert cells.size > 0
    new = _assert_same(mesh, cells)
    assert new.n_points == mesh.n_points + cells.size
    assert new.n_cells == mesh.n_cells + 3 * cells.size
    _check_geometry(new)
