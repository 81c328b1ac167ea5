"""Coarsening of adaptive meshes (docs/method.md section 11): families merged back, the
initial mesh recovered, levels of neighbours kept within one, a refined zone that moves."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.mesh import rectangle_squares, tag_rectangle
from vemwear.mesh.adapt import CellTree, neighbour_pairs, refine_tree
from vemwear.mesh.checks import check_mesh
from vemwear.mesh.coarsen import coarsen_tree, coarsening_marking
from vemwear.mesh.locate import locate_cells


def _start():
    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (8, 4)))
    return mesh, CellTree.initial(mesh.n_cells)


def _graded(mesh, tree) -> bool:
    p = neighbour_pairs(mesh)
    return bool(np.abs(tree.level[p[:, 0]] - tree.level[p[:, 1]]).max(initial=0) <= 1)


def _refine_at(mesh, tree, x, y, times):
    for _ in range(times):
        cell = locate_cells(mesh, np.array([[x, y]]))
        mesh, tree, _ = refine_tree(mesh, tree, cell)
        check_mesh(mesh)
        assert _graded(mesh, tree)
    return mesh, tree


def test_coarsening_everything_gives_back_the_initial_mesh() -> None:
    m0, t0 = _start()
    mesh, tree = _refine_at(m0, t0, 0.26, 0.01, 4)
    assert tree.level.max() == 4 and mesh.n_cells > m0.n_cells
    for _ in range(4):  # one level per pass
        mesh, tree, owner = coarsen_tree(mesh, tree, np.arange(mesh.n_cells))
        check_mesh(mesh)
        assert _graded(mesh, tree)
        assert owner.max() == mesh.n_cells - 1
    assert mesh.n_cells == m0.n_cells and mesh.n_points == m0.n_points
    assert np.all(tree.level == 0) and np.all(tree.family == -1)
    order = np.lexsort(mesh.points.T)
    order0 = np.lexsort(m0.points.T)
    assert np.array_equal(mesh.points[order], m0.points[order0])
    assert mesh.part_counts() == m0.part_counts()
    assert np.isclose(mesh.cell_areas.sum(), 2.0)
    # nothing left to merge
    same, _tree2, owner = coarsen_tree(mesh, tree, np.arange(mesh.n_cells))
    assert same is mesh and np.array_equal(owner, np.arange(mesh.n_cells))


def test_a_family_merges_only_when_all_its_children_are_marked_and_leaves() -> None:
    m0, t0 = _start()
    mesh, tree = _refine_at(m0, t0, 0.26, 0.01, 2)
    fam = tree.family
    f = int(fam[tree.level == 2][0])
    members = np.flatnonzero(fam == f)
    assert len(members) == 4
    # three of four marked: no change
    same, _, _ = coarsen_tree(mesh, tree, members[:3])
    assert same.n_cells == mesh.n_cells
    # a level-1 family with a refined child cannot merge before its grandchildren
    f1 = int(tree.parent_family[f])
    level1 = np.flatnonzero(fam == f1)
    same, _, _ = coarsen_tree(mesh, tree, level1)
    assert same.n_cells == mesh.n_cells
    merged, tree2, owner = coarsen_tree(mesh, tree, members)
    assert merged.n_cells == mesh.n_cells - 3
    assert len(set(owner[members].tolist())) == 1
    assert tree2.level[owner[members[0]]] == 1


def test_coarsening_keeps_neighbours_within_one_level() -> None:
    """A family next to cells two levels finer does not merge."""
    m0, t0 = _start()
    mesh, tree = _refine_at(m0, t0, 0.26, 0.01, 3)
    # mark everything except the finest cells: only families whose merge keeps the
    # grading may go
    fine = tree.level == tree.level.max()
    merged, tree2, _ = coarsen_tree(mesh, tree, np.flatnonzero(~fine))
    check_mesh(merged)
    assert _graded(merged, tree2)
    assert tree2.level.max() == 3


def test_the_refined_zone_follows_a_moving_point() -> None:
    """A point moving along Gamma_C: refine its cells to level 3, coarsen the cells far
    from it; the mesh stays bounded and its finest cells follow the point."""
    mesh, tree = _start()
    counts = []
    for x in np.linspace(0.2, 1.8, 9):
        for _ in range(3):
            cell = locate_cells(mesh, np.array([[x, 0.01]]))
            if tree.level[cell[0]] < 3:
                mesh, tree, _ = refine_tree(mesh, tree, cell)
        centre = np.zeros((mesh.n_cells, 2))
        np.add.at(centre, mesh.edge_cells, mesh.points[mesh.cell_vertices])
        centre /= mesh.cell_sizes[:, None]
        for _ in range(3):
            far = np.flatnonzero(np.abs(centre[:, 0] - x) > 0.3)
            mesh, tree, _owner = coarsen_tree(mesh, tree, far)
            centre = np.zeros((mesh.n_cells, 2))
            np.add.at(centre, mesh.edge_cells, mesh.points[mesh.cell_vertices])
            centre /= mesh.cell_sizes[:, None]
        check_mesh(mesh)
        assert _graded(mesh, tree)
        finest = tree.level == 3
        assert np.all(np.abs(centre[finest, 0] - x) < 0.3)
        assert np.all(tree.level[centre[:, 0] > x + 0.75] == 0)
        counts.append(mesh.n_cells)
    assert max(counts) <= 1.4 * counts[0], counts


def test_coarsening_marking_takes_the_smallest_indicators() -> None:
    eta2 = np.array([5.0, 0.1, 0.2, 3.0, 0.05])
    m = coarsening_marking(eta2, 0.05)
    assert sorted(m.tolist()) == [1, 2, 4]
    assert eta2[m].sum() <= 0.05 * eta2.sum()
    assert coarsening_marking(eta2, 0.0).size == 0
    with pytest.raises(ValueError, match="coarsening fraction"):
        coarsening_marking(eta2, 1.0)
