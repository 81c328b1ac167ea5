"""Wear carried along Gamma_C when an adaptive mesh changes (docs/method.md section 11)."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.contact.transfer import transfer_along_contact
from vemwear.mesh import MeshError, rectangle_squares, tag_rectangle
from vemwear.mesh.adapt import CellTree, refine_tree
from vemwear.mesh.coarsen import coarsen_tree
from vemwear.paper import ex52


def _nodes(mesh):
    return ex52.problem(0.2, 2.0, steps=1, tagged_mesh=mesh).contact


def test_kept_nodes_exactly_and_new_nodes_by_linear_interpolation() -> None:
    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (8, 4)))
    cb = _nodes(mesh)
    rng = np.random.default_rng(1)
    w = rng.random(len(cb.nodes))
    tree = CellTree.initial(mesh.n_cells)
    fine, tree, _ = refine_tree(mesh, tree, mesh.boundary_edge_cells[mesh.boundary_tags == 3][:5])
    cb2 = _nodes(fine)
    w2 = transfer_along_contact(mesh, cb.nodes, w, cb2.points)
    # kept vertices: bitwise the old values
    old_at = {tuple(p): x for p, x in zip(cb.points.tolist(), w.tolist(), strict=True)}
    kept = [i for i, p in enumerate(cb2.points.tolist()) if tuple(p) in old_at]
    assert len(kept) == len(cb.nodes)
    assert all(w2[i] == old_at[tuple(cb2.points[i].tolist())] for i in kept)
    # new midpoints: the mean of their edge's ends
    new = np.setdiff1d(np.arange(len(cb2.nodes)), kept)
    assert len(new) == 5
    order = np.argsort(cb.points[:, 0])
    xs, ws = cb.points[order, 0], w[order]
    for i in new:
        j = np.searchsorted(xs, cb2.points[i, 0])
        # the clamped corner (0, 0) is not a contact node: 0 there
        expected = 0.5 * ws[0] if j == 0 else 0.5 * (ws[j - 1] + ws[j])
        assert w2[i] == pytest.approx(expected, rel=1e-14)
    # and back after coarsening: the values of the kept nodes, bitwise
    back, _, _ = coarsen_tree(fine, tree, np.arange(fine.n_cells))
    cb3 = _nodes(back)
    w3 = transfer_along_contact(fine, cb2.nodes, w2, cb3.points)
    assert np.array_equal(np.sort(w3), np.sort(w))
    # the nodal quadrature of the wear is kept by refinement
    assert np.sum(cb2.weights * w2) == pytest.approx(np.sum(cb.weights * w), rel=1e-14)


def test_a_linear_wear_is_carried_exactly_and_a_stray_point_is_refused() -> None:
    mesh = tag_rectangle(rectangle_squares((2.0, 1.0), (8, 4)))
    cb = _nodes(mesh)
    w = 0.3 + 0.1 * cb.points[:, 0]
    X = np.column_stack([np.linspace(0.25, 2.0, 17), np.zeros(17)])  # from the first node
    assert np.allclose(transfer_along_contact(mesh, cb.nodes, w, X), 0.3 + 0.1 * X[:, 0])
    with pytest.raises(MeshError, match="lies on no contact edge"):
        transfer_along_contact(mesh, cb.nodes, w, [[1.0, 0.5]])
    with pytest.raises(ValueError, match="one entry per contact node"):
        transfer_along_contact(mesh, cb.nodes, w[:-1], X)
