"""Quadrature on polygons and the norms of vemwear.post.norms."""

from __future__ import annotations

import math

import numpy as np
import pytest

import vemwear.mesh as vm
from vemwear.contact import contact_boundary
from vemwear.mesh import nested_cells, rectangle_squares, rectangle_triangles, tag_rectangle
from vemwear.post.norms import (
    ProjectedNorms,
    contact_l2_norm,
    displacement_error,
    exact_errors,
    nested_difference_norms_sq,
    projected_norm,
    wear_error,
)
from vemwear.vem import LinearFields, Projection, polygon_moments, polygon_quadrature

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
def test_polygon_quadrature_degree5(name: str) -> None:
    """x^a y^b with a + b <= 5 over (0, 2) x (0, 1): 2^(a+1) / (a+1) / (b+1)."""
    x, w, cell = polygon_quadrature(MESHES[name], 5)
    assert np.all((cell >= 0) & (cell < MESHES[name].n_cells))
    for a in range(6):
        for b in range(6 - a):
            exact = 2.0 ** (a + 1) / (a + 1) / (b + 1)
            got = np.sum(w * x[:, 0] ** a * x[:, 1] ** b)
            assert got == pytest.approx(exact, rel=1e-12), (a, b)
    with pytest.raises(ValueError, match="no triangle rule of degree 3"):
        polygon_quadrature(MESHES[name], 3)


@pytest.mark.parametrize("name", list(MESHES))
def test_linear_field_difference_exact(name: str) -> None:
    """Pi reproduces linear fields, so the error of a linear difference is known exactly."""
    m = MESHES[name]
    u_ref = np.array([0.1, 0.05]) + m.points @ np.array([[0.2, -0.1], [0.3, 0.4]]).T
    u_h = u_ref + C + m.points @ D.T
    pn = ProjectedNorms(m)
    l2, semi = pn.norms_sq(u_h - u_ref)
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
    assert projected_norm(m, u_h - u_ref, "H1semi") == pytest.approx(semi_e.error, rel=1e-12)
    with pytest.raises(ValueError, match="norm must be one of"):
        projected_norm(m, u_h, "L1")


def test_projected_norm_against_quadrature() -> None:
    """The moment formula equals a degree-5 quadrature of |Pi v|^2 for a random v."""
    m = MESHES["nonconvex"]
    v = np.random.default_rng(0).standard_normal((m.n_points, 2))
    f = Projection(m)(v)
    x, w, cell = polygon_quadrature(m, 5)
    l2, semi = ProjectedNorms(m).norms_sq(f)
    assert l2.sum() == pytest.approx(np.sum(w * np.sum(f.at(x, cell) ** 2, axis=1)), rel=1e-12)
    assert semi.sum() == pytest.approx(np.sum(w * np.sum(f.gradient[cell] ** 2, axis=(1, 2))))


@pytest.mark.parametrize("name", sorted(MESHES))
def test_seminorms_alone_are_those_of_norms_sq(name: str) -> None:
    """The seminorm without the L2 part: the same numbers, bitwise, as from norms_sq."""
    m = MESHES[name]
    pn = ProjectedNorms(m)
    v = np.random.default_rng(3).standard_normal((m.n_points, 2))
    _l2, semi = pn.norms_sq(v)
    np.testing.assert_array_equal(pn.seminorms_sq(v), semi)
    assert semi.sum() > 0


def test_nested_difference_norms() -> None:
    """Two piecewise linear fields on nested meshes: the difference integrated over the fine
    cells equals a quadrature over the fine cells of the two fields evaluated pointwise;
    a coarse field restricted to the fine cells has zero difference."""
    coarse = rectangle_squares(SIZE, (4, 2))
    fine = vm.squares_with_hanging_nodes(SIZE, (8, 4))
    cells = nested_cells(coarse, fine)
    rng = np.random.default_rng(4)
    fc = Projection(coarse)(rng.standard_normal((coarse.n_points, 2)))
    ff = Projection(fine)(rng.standard_normal((fine.n_points, 2)))
    area, _xbar, M1, M2 = polygon_moments(fine)
    l2, semi = nested_difference_norms_sq(fc, ff, cells, (area, M1, M2))
    x, w, cell = polygon_quadrature(fine, 5)
    diff = fc.at(x, cells[cell]) - ff.at(x, cell)
    assert l2.sum() == pytest.approx(np.sum(w * np.sum(diff**2, axis=1)), rel=1e-12)
    dG = fc.gradient[cells[cell]] - ff.gradient[cell]
    assert semi.sum() == pytest.approx(np.sum(w * np.sum(dG**2, axis=(1, 2))), rel=1e-12)
    # the coarse field, re-expanded about the fine vertex averages, differs by nothing
    same = LinearFields(
        ff.xbar,
        fc.at(ff.xbar, cells),
        fc.gradient[cells],
    )
    l2, semi = nested_difference_norms_sq(fc, same, cells, (area, M1, M2))
    assert l2.max() < 1e-28 and semi.max() < 1e-28


def test_wear_l2_exact_with_clamped_end() -> None:
    """w = beta x along Gamma_C: the clamped end (0, 0) carries 0 and closes the first edge."""
    m = MESHES["squares"]
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
    assert math.isnan(wear_error(m, cb.nodes, w, 0 * w).relative)
    with pytest.raises(ValueError):
        contact_l2_norm(m, cb.nodes, w, "simpson")


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
    # Pi u_h - u = h^2 / 4 - (x - x_mid)^2 on every cell:
    # int_{-h/2}^{h/2} (h^2/4 - s^2)^2 ds / h = h^4 (1/16 - 1/24 + 1/80) = h^4 / 30
    assert e["L2"] == pytest.approx(h * h / math.sqrt(30.0), rel=1e-10)
