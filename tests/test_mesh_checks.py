"""Mesh checks that need hand-made meshes: nested cells, separate bodies, messages."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.mesh import Mesh, MeshError, check_mesh, rectangle_squares

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
