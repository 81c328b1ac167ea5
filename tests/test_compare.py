"""Errors against a reference solution on a nested mesh (vemwear.post.compare, Example 5.5)."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.contact import contact_boundary
from vemwear.mesh import NonNestedMeshError, rectangle_squares, squares_with_hanging_nodes
from vemwear.paper import ex55
from vemwear.post.compare import (
    DISPLACEMENT_VARIANTS,
    WEAR_VARIANTS,
    Comparison,
    Solution,
    common_levels,
    contact_prolongation,
    convergence_orders,
    prolongation,
    solution_errors,
)
from vemwear.simulate import TimeGrid, simulate

SIZE = (2.0, 1.0)
C = np.array([0.3, -0.2])
B = np.array([[1.0, 2.0], [-0.5, 0.7]])


def test_common_levels_and_orders() -> None:
    a = TimeGrid.uniform(1.0, 4).t
    b = TimeGrid.pattern(1.0, [1 / 8, 3 / 8]).t  # 0, 1/8, 1/2, 5/8, 1
    ic, ir = common_levels(a, b)
    np.testing.assert_array_equal(a[ic], [0.0, 0.5, 1.0])
    np.testing.assert_allclose(b[ir], a[ic])
    np.testing.assert_allclose(convergence_orders([4.0, 2.0, 0.5]), [1.0, 2.0])
    np.testing.assert_allclose(convergence_orders([1.0, 0.25], h=[0.5, 0.25]), [2.0])


def test_prolongation_reproduces_linear_fields() -> None:
    fine = rectangle_squares(SIZE, (16, 8))
    for coarse in (rectangle_squares(SIZE, (4, 2)), squares_with_hanging_nodes(SIZE, (4, 2))):
        P = prolongation(coarse, fine.points)
        up = (P @ (C + coarse.points @ B.T).ravel()).reshape(-1, 2)
        np.testing.assert_allclose(up, C + fine.points @ B.T, atol=1e-13)
    coarse = ex55.problem(2).mesh
    cbc = contact_boundary(coarse)
    xs = np.linspace(0.0, 2.0, 33)[1:]
    Pw = contact_prolongation(coarse, cbc.nodes, np.column_stack([xs, 0 * xs]))
    np.testing.assert_allclose(Pw @ (3.0 * cbc.points[:, 0]), 3.0 * xs, atol=1e-13)
    with pytest.raises(NonNestedMeshError):
        prolongation(coarse, np.array([[5.0, 5.0]]))


def test_prolongation_with_cell_hints_is_the_same_map() -> None:
    """The coarse cell of a fine cell around each fine vertex (what Comparison passes)
    gives the same matrix as the search among the nearest cells; hints that miss (a
    wrong cell, or -1) fall back to that search."""
    from vemwear.mesh import rectangle_triangles
    from vemwear.mesh.locate import nested_cells

    fine = rectangle_triangles(SIZE, (16, 8))
    for coarse in (rectangle_squares(SIZE, (4, 2)), squares_with_hanging_nodes(SIZE, (4, 2))):
        cells = nested_cells(coarse, fine)
        hint = np.full(fine.n_points, -1, dtype=np.int64)
        hint[fine.cell_vertices] = cells[fine.edge_cells]
        assert np.all(hint >= 0)
        P = prolongation(coarse, fine.points)
        for h in (hint, np.where(np.arange(fine.n_points) % 3 == 0, -1, hint), (hint + 3) % 8):
            Q = prolongation(coarse, fine.points, cells=h)
            assert abs(P - Q).max() <= 1e-15
        up = (Q @ (C + coarse.points @ B.T).ravel()).reshape(-1, 2)
        np.testing.assert_allclose(up, C + fine.points @ B.T, atol=1e-13)
    with pytest.raises(NonNestedMeshError):
        prolongation(coarse, np.array([[5.0, 5.0]]), cells=np.array([0]))


def test_identical_solutions_zero_error() -> None:
    r = simulate(ex55.problem(4), store="all")
    h = solution_errors(r, r)
    assert set(h.displacement) == set(DISPLACEMENT_VARIANTS)
    assert set(h.wear) == set(WEAR_VARIANTS)
    for v in DISPLACEMENT_VARIANTS:
        assert np.all(h.displacement[v] < 1e-13), v
    for v in WEAR_VARIANTS:
        assert np.isnan(h.wear[v][0])  # w = 0 at t = 0: relative error undefined
        assert np.all(h.wear[v][1:] < 1e-13), v
    assert h.at_T("displacement") < 1e-13 and h.max("wear") < 1e-13


def test_linear_displacements_on_nested_meshes() -> None:
    """Pi reproduces linear fields on both meshes, so the primary error of two linear
    displacements is the H1 norm of their difference, exactly, and the variant through
    I_h u_ref on the coarse mesh agrees."""
    fine_pr, coarse_pr = ex55.problem(8, 2), ex55.problem(2, 2)

    def sol(pr, c, b):
        m = pr.mesh
        u = np.broadcast_to(c + m.points @ b.T, (3, m.n_points, 2))
        nodes = contact_boundary(m).nodes
        w = np.outer(np.arange(3.0), m.points[nodes, 0])  # 0 at the clamped end
        return Solution(m, pr.time.t, np.arange(3), u, nodes, w)

    ref = sol(fine_pr, np.array([0.1, 0.05]), np.array([[0.2, -0.1], [0.3, 0.4]]))
    coarse = sol(coarse_pr, np.array([0.1, 0.05]) + C, np.array([[0.2, -0.1], [0.3, 0.4]]) + B)
    h = Comparison(ref).errors(coarse)
    # int over (0, 2) x (0, 1) of |C + B x|^2 + |B|^2 and of the reference
    M1, M2 = np.array([2.0, 1.0]), np.array([[8 / 3, 1.0], [1.0, 2 / 3]])

    def h1_sq(c, b):
        return 2.0 * c @ c + 2 * c @ b @ M1 + np.trace(b @ M2 @ b.T) + 2.0 * np.sum(b**2)

    rel = np.sqrt(h1_sq(C, B) / h1_sq(np.array([0.1, 0.05]), np.array([[0.2, -0.1], [0.3, 0.4]])))
    np.testing.assert_allclose(h.displacement["H1"], rel, rtol=1e-12)
    np.testing.assert_allclose(h.displacement["H1_coarse"], rel, rtol=1e-12)
    # the same wear (linear along Gamma_C) on both meshes: no wear error after t = 0
    assert np.all(h.wear["L2"][1:] < 1e-14) and np.all(h.wear["L2_coarse"][1:] < 1e-14)


def test_solution_roundtrip_and_reference_comparison() -> None:
    fine = simulate(ex55.problem(8), store=ex55.common_times([2, 4]))
    coarse = simulate(ex55.problem(4), store="all")
    sol = Solution.from_arrays(Solution.from_result(fine).arrays())
    cmp = Comparison(sol)
    h = cmp.errors(coarse)
    h2 = solution_errors(coarse, fine)
    np.testing.assert_allclose(h.displacement["H1"], h2.displacement["H1"])
    np.testing.assert_array_equal(h.t, np.linspace(0, 1, 5))
    assert 0 < h.at_T("displacement") < 0.2 and 0 < h.at_T("wear") < 0.2
    assert h.max("displacement") >= h.at_T("displacement")
    # I_h u_ref on the coarse mesh does not see u_ref - I_h u_ref: smaller
    assert h.at_T("displacement", "H1_coarse") < h.at_T("displacement")
    hf = cmp.errors(coarse, levels="final")
    assert hf.at_T("displacement") == h.at_T("displacement") and len(hf.t) == 1
    # a coarse run whose displacement was not stored at a level gives NaN there
    part = simulate(ex55.problem(4), store="final")
    hp = cmp.errors(part)
    assert np.isnan(hp.displacement["H1"][0]) and np.isfinite(hp.at_T("displacement"))
    # not nested
    with pytest.raises(NonNestedMeshError):
        cmp.errors(simulate(ex55.problem(3)))


def test_blocks_of_levels_give_the_numbers_of_single_levels(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Comparison.errors in blocks of levels (one block here) and level by level: the
    same numbers, bit for bit, every variant, NaN at the levels the coarse run did not
    store; Projection.many is the projection of every field."""
    import vemwear.post.compare as compare

    fine = simulate(ex55.problem(8), store=ex55.common_times([2, 4]))
    coarse = Solution.from_result(simulate(ex55.problem(4), store=[0.25, 0.75, 1.0]))
    assert compare._BLOCK // fine.problem.mesh.n_cells >= len(coarse.t)  # one block
    whole = Comparison(fine).errors(coarse)
    monkeypatch.setattr(compare, "_BLOCK", 1)  # one level at a time
    single = Comparison(fine).errors(coarse)
    assert np.isnan(whole.displacement["H1"][[0, 2]]).all()
    assert np.isfinite(whole.displacement["H1"][[1, 3, 4]]).all()
    for a, b in (
        (whole.displacement, single.displacement),
        (whole.wear, single.wear),
        (whole.absolute, single.absolute),
    ):
        assert a.keys() == b.keys()
        for k in a:
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    proj = Comparison(fine).fine.projection
    block = proj.many(fine.u)
    for i, u in enumerate(fine.u):
        one = proj(u)
        np.testing.assert_array_equal(block.value[i], one.value)
        np.testing.assert_array_equal(block.gradient[i], one.gradient)


def test_errors_many_gives_the_errors_of_each_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """Several runs at once (a mesh located through a finer run's mesh when nested in it,
    directly otherwise; the reference's projection at a level shared): the numbers of
    each run alone, bit for bit, every variant."""
    import vemwear.post.nested_errors as ne

    ns = (3, 4, 6)  # 3 is nested in 6, not in 4
    fine = simulate(ex55.problem(12), store=ex55.common_times(ns))
    runs = [simulate(ex55.problem(n), store="all") for n in ns]
    cmp = Comparison(fine)
    searched: list[int] = []

    def spy(coarse, f, **kw):
        searched.append(f.n_cells)
        return nested_cells(coarse, f, **kw)

    from vemwear.mesh.locate import nested_cells

    monkeypatch.setattr(ne, "nested_cells", spy)
    many = cmp.errors_many(runs)
    # 6 and 4 in the reference, 3 in 6's mesh
    assert searched == [fine.problem.mesh.n_cells] * 2 + [72]
    monkeypatch.undo()
    for run, h in zip(runs, many, strict=True):
        one = Comparison(fine).errors(run)
        np.testing.assert_array_equal(h.t, one.t)
        np.testing.assert_array_equal(h.ref_levels, one.ref_levels)
        for a, b in (
            (h.displacement, one.displacement),
            (h.wear, one.wear),
            (h.absolute, one.absolute),
        ):
            assert a.keys() == b.keys()
            for k in a:
                assert np.isfinite(a[k][1:]).all(), k
                np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    # the secondary variants at t = T only: the same there, NaN before; the rest the same
    final = cmp.errors_many(runs, secondary="final")
    for h, f in zip(many, final, strict=True):
        for k in h.displacement:
            a, b = h.displacement[k], f.displacement[k]
            if k in ("H1_coarse", "H1semi_meanvalue"):
                assert np.isnan(b[:-1]).all() and b[-1] == a[-1], k
            else:
                np.testing.assert_array_equal(a, b, err_msg=k)
    with pytest.raises(NonNestedMeshError):
        cmp.errors_many([runs[2], simulate(ex55.problem(5))])


def test_prolongation_with_the_coarse_vertices_given_is_the_same_map() -> None:
    from vemwear.mesh.locate import match_vertices

    fine = rectangle_squares(SIZE, (16, 8))
    for coarse in (rectangle_squares(SIZE, (4, 2)), squares_with_hanging_nodes(SIZE, (4, 2))):
        P = prolongation(coarse, fine.points)
        Q = prolongation(coarse, fine.points, vertices=match_vertices(coarse.points, fine.points))
        assert (P != Q).nnz == 0
