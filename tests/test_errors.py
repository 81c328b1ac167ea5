"""The error functionals of vemwear.post.errors (design note section 5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import vemwear.mesh as vm
from vemwear.mesh import rectangle_squares, rectangle_triangles, tag_rectangle
from vemwear.paper import ex55
from vemwear.post.errors import (
    Comparison,
    NonNestedMeshError,
    ProjectedNorms,
    Solution,
    common_levels,
    contact_l2_norm,
    contact_prolongation,
    convergence_orders,
    displacement_error,
    exact_errors,
    linear_field_norms,
    match_vertices,
    polygon_moments,
    projected_norm,
    prolongation,
    solution_errors,
    wear_error,
)
from vemwear.simulate import simulate

SIZE = (2.0, 1.0)
# int over (0, 2) x (0, 1) of 1, x, y, x^2, y^2, xy
AREA, IX, IY, IXX, IYY, IXY = 2.0, 2.0, 1.0, 8.0 / 3.0, 2.0 / 3.0, 1.0


def _meshes() -> dict[str, vm.Mesh]:
    out = {
        "squares": rectangle_squares(SIZE, (4, 2)),
        "triangles": rectangle_triangles(SIZE, (4, 2), diagonal="alternate"),
        "voronoi": vm.rectangle_voronoi(SIZE, 30, seed=1),
        "hanging": vm.squares_with_hanging_nodes(SIZE, (4, 2)),
        "nonconvex": vm.nonconvex_mesh(SIZE, (4, 2)),
    }
    return {k: tag_rectangle(m) for k, m in out.items()}


MESHES = _meshes()
C = np.array([0.3, -0.2])
D = np.array([[1.0, 2.0], [-0.5, 0.7]])


def _l2_sq_exact(c: np.ndarray, d: np.ndarray) -> float:
    """int over (0,2)x(0,1) of |c + D x|^2, by the moments above."""
    M1 = np.array([IX, IY])
    M2 = np.array([[IXX, IXY], [IXY, IYY]])
    return float(AREA * c @ c + 2 * c @ d @ M1 + np.trace(d @ M2 @ d.T))


@pytest.mark.parametrize("name", list(MESHES))
def test_moments_exact(name: str) -> None:
    m = MESHES[name]
    area, xbar, M1, M2 = polygon_moments(m)
    assert area.sum() == pytest.approx(AREA, rel=1e-13)
    # moments about the origin from moments about xbar
    first = (M1 + area[:, None] * xbar).sum(axis=0)
    second = (
        M2.sum(axis=0)
        + np.einsum("k,ki,kj->ij", area, xbar, xbar)
        + np.einsum("ki,kj->ij", M1, xbar)
        + np.einsum("ki,kj->ij", xbar, M1)
    )
    np.testing.assert_allclose(first, [IX, IY], rtol=1e-12)
    np.testing.assert_allclose(second, [[IXX, IXY], [IXY, IYY]], rtol=1e-12)


@pytest.mark.parametrize("name", list(MESHES))
def test_linear_field_difference_exact(name: str) -> None:
    """Pi reproduces linear fields, so the error of a linear difference is known exactly."""
    m = MESHES[name]
    u_ref = np.array([0.1, 0.05]) + m.points @ np.array([[0.2, -0.1], [0.3, 0.4]]).T
    u_h = u_ref + C + m.points @ D.T
    l2, semi = linear_field_norms(m, u_h - u_ref)
    assert l2.sum() == pytest.approx(_l2_sq_exact(C, D), rel=1e-12)
    assert semi.sum() == pytest.approx(AREA * np.sum(D**2), rel=1e-12)
    e = displacement_error(m, u_h, u_ref, "H1")
    assert e.error == pytest.approx(math.sqrt(_l2_sq_exact(C, D) + AREA * np.sum(D**2)), rel=1e-12)
    ref = np.array([0.1, 0.05]), np.array([[0.2, -0.1], [0.3, 0.4]])
    ref_norm = math.sqrt(_l2_sq_exact(*ref) + AREA * np.sum(ref[1] ** 2))
    assert e.reference == pytest.approx(ref_norm, rel=1e-12)
    assert e.relative == pytest.approx(e.error / ref_norm, rel=1e-12)
    semi_e = displacement_error(m, u_h, u_ref, "H1semi")
    assert semi_e.error == pytest.approx(math.sqrt(AREA * np.sum(D**2)), rel=1e-12)
    # the fast operator gives the same numbers
    pn = ProjectedNorms(m)
    for norm in ("H1", "H1semi"):
        assert pn.norm(u_h - u_ref, norm) == pytest.approx(
            projected_norm(m, u_h - u_ref, norm), rel=1e-12
        )
    rng = np.random.default_rng(0)
    v = rng.standard_normal((m.n_points, 2))
    a, b = pn.norms_sq(v), linear_field_norms(m, v)
    np.testing.assert_allclose(a[0], b[0], rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(a[1], b[1], rtol=1e-10, atol=1e-14)


def test_wear_l2_exact_with_clamped_end() -> None:
    """w = beta x along Gamma_C: the clamped end (0, 0) carries 0 and closes the first edge."""
    m = MESHES["squares"]
    from vemwear.contact import contact_boundary

    cb = contact_boundary(m)
    assert 0.0 not in cb.points[:, 0]  # the clamped corner is not a contact node
    beta = 0.7
    w = beta * cb.points[:, 0]
    assert contact_l2_norm(m, cb.nodes, w) == pytest.approx(beta * math.sqrt(8.0 / 3.0), rel=1e-13)
    # nodal (trapezoidal) rule for x^2 on h = 1/2: int + (b - a) h^2 f'' / 12
    h = 0.5
    assert contact_l2_norm(m, cb.nodes, w, "nodal") == pytest.approx(
        beta * math.sqrt(8.0 / 3.0 + 2.0 * h * h * 2.0 / 12.0), rel=1e-13
    )
    e = wear_error(m, cb.nodes, 2 * w, w)
    assert e.relative == pytest.approx(1.0, rel=1e-13)
    with pytest.raises(ValueError):
        contact_l2_norm(m, cb.nodes, w, "simpson")


def test_match_vertices_nested_and_not() -> None:
    coarse = rectangle_squares(SIZE, (4, 2))
    fine = rectangle_squares(SIZE, (16, 8))
    idx = match_vertices(coarse.points, fine.points)
    np.testing.assert_array_equal(fine.points[idx], coarse.points)
    with pytest.raises(NonNestedMeshError, match="not nested"):
        match_vertices(rectangle_squares(SIZE, (3, 2)).points, fine.points)
    if "voronoi" in MESHES:
        with pytest.raises(NonNestedMeshError):
            match_vertices(MESHES["voronoi"].points, fine.points)


def test_common_levels_and_orders() -> None:
    from vemwear.simulate import TimeGrid

    a = TimeGrid.uniform(1.0, 4).t
    b = TimeGrid.pattern(1.0, [1 / 8, 3 / 8]).t  # 0, 1/8, 1/2, 5/8, 1
    ic, ir = common_levels(a, b)
    np.testing.assert_array_equal(a[ic], [0.0, 0.5, 1.0])
    np.testing.assert_allclose(b[ir], a[ic])
    np.testing.assert_allclose(convergence_orders([4.0, 2.0, 0.5]), [1.0, 2.0])
    np.testing.assert_allclose(convergence_orders([1.0, 0.25], h=[0.5, 0.25]), [2.0])


def _small(n: int, steps: int | None = None):
    pr = ex55.problem(n) if steps is None else ex52_problem(n, steps)
    return simulate(pr, store="all")


def ex52_problem(n: int, steps: int):
    from vemwear.paper import ex52

    return ex52.problem(0.2, 2.0, divisions=(2 * n, n), steps=steps)


def test_identical_solutions_zero_error() -> None:
    r = _small(4)
    h = solution_errors(r, r)
    for n in ("H1", "H1semi"):
        assert np.all(h.displacement[n] == 0.0)
    assert np.isnan(h.wear["exact"][0])  # w = 0 at t = 0: relative error undefined
    assert np.all(h.wear["exact"][1:] == 0.0)
    assert h.at_T("displacement") == 0.0 and h.max("wear") == 0.0
    hf = solution_errors(r, r, on="fine")  # prolongation onto the same mesh is the identity
    assert hf.max("displacement") < 1e-13 and hf.max("wear") < 1e-13


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
    hf = cmp.errors(coarse, on="fine")
    assert hf.at_T("displacement") > h.at_T("displacement")  # includes u_ref - I_h u_ref
    # a coarse run whose displacement was not stored at a level gives NaN there
    part = simulate(ex55.problem(4), store="final")
    hp = cmp.errors(part)
    assert np.isnan(hp.displacement["H1"][0]) and np.isfinite(hp.at_T("displacement"))
    # not nested
    with pytest.raises(NonNestedMeshError):
        cmp.errors(simulate(ex55.problem(3)))


def test_prolongation_reproduces_linear_fields() -> None:
    fine = rectangle_squares(SIZE, (16, 8))
    B = np.array([[1.0, 2.0], [-0.5, 0.7]])
    for name in ("squares", "triangles", "hanging"):
        if name not in MESHES:
            continue
        coarse = MESHES[name]
        P = prolongation(coarse, fine.points)
        up = (P @ (C + coarse.points @ B.T).ravel()).reshape(-1, 2)
        np.testing.assert_allclose(up, C + fine.points @ B.T, atol=1e-13)
    coarse = MESHES["squares"]
    from vemwear.contact import contact_boundary

    cbc = contact_boundary(coarse)
    xs = np.linspace(0.0, 2.0, 33)[1:]
    Pw = contact_prolongation(coarse, cbc.nodes, np.column_stack([xs, 0 * xs]))
    np.testing.assert_allclose(Pw @ (3.0 * cbc.points[:, 0]), 3.0 * xs, atol=1e-13)
    with pytest.raises(NonNestedMeshError):
        prolongation(coarse, np.array([[5.0, 5.0]]))


def test_exact_errors_of_interpolant() -> None:
    m = rectangle_squares((1.0, 1.0), (8, 8))

    def u(x):
        return np.column_stack([x[:, 0] ** 2, 0 * x[:, 0]])

    def g(x):
        out = np.zeros((len(x), 2, 2))
        out[:, 0, 0] = 2 * x[:, 0]
        return out

    e = exact_errors(m, u(m.points), u, g)
    assert e["nodal"] == 0.0
    # Pi of the interpolant of (x^2, 0) on a square of side h is the mean gradient
    # (2 x_mid, no rotation by 3.10): the error of d_x u1 is 2 (x - x_mid), and
    # sum_K int_K 4 (x - x_mid)^2 = h^2 / 3
    h = 1.0 / 8
    assert e["H1semi"] == pytest.approx(h / math.sqrt(3.0), rel=1e-10)
    assert e["L2_u"] == pytest.approx(math.sqrt(1 / 5), rel=1e-12)
    # Pi u_h - u = x_mid^2 + 2 x_mid (x - x_mid) - x^2 + (vertex average - x_mid^2)
    #            = h^2 / 4 - (x - x_mid)^2; its L2 norm^2 per unit area: h^4 / 30 + ... exact:
    # int_{-h/2}^{h/2} (h^2/4 - s^2)^2 ds / h = h^4 (1/16 - 1/24 + 1/80) = h^4 / 30
    assert e["L2"] == pytest.approx(h * h / math.sqrt(30.0), rel=1e-10)
