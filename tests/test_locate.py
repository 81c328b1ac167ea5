"""Point location in polygonal meshes (vemwear.mesh.locate)."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.path import Path as MplPath

import vemwear.mesh as vm
from vemwear.mesh import NonNestedMeshError, locate_cells, match_vertices, nested_cells

SIZE = (2.0, 1.0)
CHEVRONS = vm.nonconvex_mesh(SIZE, (4, 3))  # the nearest cell centre is often the wrong cell


def _on_boundary_of(p: np.ndarray, X: np.ndarray) -> float:
    A, B = X, np.roll(X, -1, axis=0)
    s = np.clip(np.sum((p - A) * (B - A), axis=1) / np.sum((B - A) ** 2, axis=1), 0, 1)
    return float(np.min(np.linalg.norm(p - (A + s[:, None] * (B - A)), axis=1)))


@pytest.mark.parametrize(
    "mesh",
    [CHEVRONS, vm.rectangle_voronoi(SIZE, 40, seed=3), vm.squares_with_hanging_nodes(SIZE, (4, 2))],
    ids=["nonconvex", "voronoi", "hanging"],
)
def test_locate_cells_finds_the_containing_polygon(mesh: vm.Mesh) -> None:
    pts = np.random.default_rng(2).uniform([0, 0], [2, 1], size=(500, 2))
    cells = locate_cells(mesh, pts)
    for p, c in zip(pts, cells, strict=True):
        assert MplPath(mesh.points[mesh.cell(c)]).contains_point(p)


def test_locate_cells_on_cell_boundaries_and_outside() -> None:
    """Vertices and edge midpoints (claimed by no crossing test on some cell) go to a cell
    whose boundary holds them; points outside the domain get -1."""
    mesh = CHEVRONS
    e = mesh.edges
    on = np.vstack([mesh.points, 0.5 * (mesh.points[e[:, 0]] + mesh.points[e[:, 1]])])
    pts = np.vstack([on, [[-0.5, 0.5], [2.5, 0.5], [1.0, 1.5]]])
    cells = locate_cells(mesh, pts)
    np.testing.assert_array_equal(cells[len(on) :], -1)
    assert np.all(cells[: len(on)] >= 0)
    for p, c in zip(on, cells[: len(on)], strict=True):
        assert _on_boundary_of(p, mesh.points[mesh.cell(c)]) < 1e-12


def test_match_vertices_nested_and_not() -> None:
    coarse = vm.rectangle_squares(SIZE, (4, 2))
    fine = vm.rectangle_squares(SIZE, (16, 8))
    idx = match_vertices(coarse.points, fine.points)
    np.testing.assert_array_equal(fine.points[idx], coarse.points)
    with pytest.raises(NonNestedMeshError, match="not nested"):
        match_vertices(vm.rectangle_squares(SIZE, (3, 2)).points, fine.points)


def test_nested_cells() -> None:
    """Every fine cell is found inside its coarse cell: squares in squares, and the
    refined cells of a hanging-node mesh in the squares they split."""
    coarse = vm.rectangle_squares(SIZE, (4, 2))
    for fine in (vm.rectangle_squares(SIZE, (16, 8)), vm.squares_with_hanging_nodes(SIZE, (8, 4))):
        cells = nested_cells(coarse, fine)
        for k, c in enumerate(cells):
            Xc = coarse.points[coarse.cell(c)]
            lo, hi = Xc.min(axis=0), Xc.max(axis=0)
            Xf = fine.points[fine.cell(k)]
            assert np.all((Xf >= lo - 1e-12) & (Xf <= hi + 1e-12)), k
        # every coarse cell is covered by the area of its fine cells
        np.testing.assert_allclose(
            np.bincount(cells, weights=fine.cell_areas, minlength=coarse.n_cells),
            coarse.cell_areas,
            rtol=1e-12,
        )
    # a fine cell that straddles two coarse cells is an error naming it
    with pytest.raises(NonNestedMeshError, match="fine cell"):
        nested_cells(coarse, vm.rectangle_squares(SIZE, (3, 2)))
    with pytest.raises(NonNestedMeshError, match="outside the coarse mesh"):
        nested_cells(coarse, vm.rectangle_squares((3.0, 1.0), (6, 2)))
