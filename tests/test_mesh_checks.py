"""Mesh checks that need hand-made meshes: nested cells, separate bodies, messages."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.mesh import Mesh, MeshError, check_mesh, rectangle_squares, rectangle_triangles

LEFT_CLAMPED = {"clamped": lambda x: x[:, 0] < 1e-9, "traction": "rest"}


def test_a_cell_inside_another_is_rejected():
    m = rectangle_squares((2, 1), (4, 2))
    pts = np.vstack([m.points, [[0.1, 0.1], [0.3, 0.1], [0.3, 0.3]]])
    bad = Mesh.from_cells(pts, [*m.cells, np.array([15, 16, 17])])
    with pytest.raises(MeshError, match="cells overlap: vertex 15"):
        check_mesh(bad.with_boundary(LEFT_CLAMPED))


def test_two_separate_bodies_are_allowed():
    a = rectangle_squares((1, 1), (2, 2))
    b = rectangle_squares((1, 1), (2, 2), origin=(2.0, 0.0))
    two = Mesh.from_cells(
        np.vstack([a.points, b.points]), [*a.cells, *(c + a.n_points for c in b.cells)]
    )
    check_mesh(two.with_boundary(LEFT_CLAMPED))


def test_duplicate_vertices_are_named_in_pairs():
    m = rectangle_squares((1, 1), (1, 1))
    pts = np.vstack([m.points, m.points[:1]])
    cells = [np.array([4, 1, 3, 2])]  # uses the copy of vertex 0
    dup = Mesh.from_cells(pts, [*cells, np.array([0, 1, 2])])
    with pytest.raises(MeshError, match=r"pairs \[\[0, 4\]\]"):
        check_mesh(dup.with_boundary(LEFT_CLAMPED))


@pytest.mark.parametrize(
    "make",
    [
        lambda: rectangle_squares((2, 1), (32, 16)),
        lambda: rectangle_squares((1e-3, 7.0), (5, 300), origin=(-4.0, 1e6)),
        lambda: rectangle_triangles((2, 1), (32, 16)),
        lambda: rectangle_triangles((2, 1), (7, 3), diagonal="left"),
        lambda: rectangle_triangles((1, 50), (9, 400), diagonal="alternate"),
    ],
)
def test_generated_grids_are_valid_and_recorded_so(make):
    """The structured grids skip the geometry checks as valid by construction: the
    checks run directly must agree, for various sizes, aspect ratios and diagonals."""
    from vemwear.mesh import checks

    mesh = make()
    assert checks._geometry_digest(mesh) in checks._PASSED
    checks.check_vertices(mesh)
    checks.check_cells(mesh)
    checks.check_conforming(mesh)


def test_a_grid_that_rounding_collapses_is_still_checked():
    from vemwear.mesh import checks

    mesh = rectangle_triangles((1e-320, 1.0), (8, 4))
    assert checks._geometry_digest(mesh) not in checks._PASSED
    with pytest.raises(MeshError, match="duplicate vertices"):
        check_mesh(mesh.with_boundary(LEFT_CLAMPED))


def test_pieces_of_one_sloped_side_do_not_cross():
    """Hanging nodes on a sloped straight side are collinear only to round-off; two
    non-adjacent pieces of that side are parallel, not crossing (about 5 % of such
    random sides were reported as crossing before), while a bow tie still crosses."""
    from vemwear.mesh.checks import crossing_sides

    rng = np.random.default_rng(0)
    a = rng.random((2000, 2))
    d = rng.normal(size=(2000, 2))
    ts = np.sort(rng.random((2000, 2)), axis=1)
    n = np.column_stack([-d[:, 1], d[:, 0]])
    X = np.stack([a, a + ts[:, :1] * d, a + ts[:, 1:] * d, a + d, a + d + n, a + n], axis=1)
    assert not np.any(crossing_sides(X, eps=1e-12)[0])
    bow = np.array([[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]])
    hit, i, j = crossing_sides(bow, eps=1e-12)
    assert [(int(p), int(q)) for p, q in zip(i[hit[0]], j[hit[0]], strict=True)] == [(0, 2)]
