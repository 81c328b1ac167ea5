"""Second-order virtual elements (k = 2): element matrices, projection, patch tests, orders.

Expected values are computed here from the definitions (paper Section 3 with k = 2,
docs/method.md "Second order (k = 2)"): polygon moments by Green's formula, edge means by
Gauss rules, exact quadratic fields and their stresses, not from the code under test.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from conftest import moments, polygon
from vemwear.mesh import tag_rectangle
from vemwear.mesh.registry import FAMILIES
from vemwear.vem import STABILIZATIONS, Material
from vemwear.vem.dofs2 import (
    body_force_vector2,
    cell_dofs2,
    edge_load_vector2,
    edge_shape_functions,
    facet_dofs2,
    interpolate2,
    numbering2,
    project2,
    stiffness2,
    traction_vector2,
)
from vemwear.vem.local2 import (
    basis_gradients,
    basis_values,
    element_matrices2,
    local_projection2,
)
from vemwear.vem.quadrature import polygon_quadrature

MAT = Material(lam=7.5, eta=1.3)  # lam != eta catches a swapped Lamé pair


# ----------------------------------------------------------------------------- polygons
def batch(rng, n, kind, count=6):
    return np.stack([polygon(rng, n, kind) for _ in range(count)])


# ----------------------------------------------------------------------------- fields
def quad_field(C):
    """u(x) = C @ (1, x, y, x^2, xy, y^2) for C of shape (2, 6)."""

    def u(x, t=0.0):
        X, Y = x[:, 0], x[:, 1]
        return np.stack([np.ones_like(X), X, Y, X * X, X * Y, Y * Y], -1) @ C.T

    return u


def quad_gradient(C, x):
    """(q, 2, 2) gradient [i, j] = d_j u_i of quad_field(C)."""
    X, Y = x[:, 0], x[:, 1]
    o, z = np.ones_like(X), np.zeros_like(X)
    dx = np.stack([z, o, z, 2 * X, Y, z], -1) @ C.T
    dy = np.stack([z, z, o, z, X, 2 * Y], -1) @ C.T
    return np.stack([dx, dy], -1)


def stress(grad, mat):
    eps = 0.5 * (grad + np.swapaxes(grad, -1, -2))
    tr = eps[..., 0, 0] + eps[..., 1, 1]
    return 2 * mat.eta * eps + mat.lam * tr[..., None, None] * np.eye(2)


def quad_body_force(C, mat):
    """f1 = -div sigma(u), constant for quadratic u: eta lap u + (lam + eta) grad div u."""
    lap = 2 * C[:, 3] + 2 * C[:, 5]
    graddiv = np.array([2 * C[0, 3] + C[1, 4], C[0, 4] + 2 * C[1, 5]])
    return -(mat.eta * lap + (mat.lam + mat.eta) * graddiv)


def local_dofs(X, u):
    """The k = 2 dofs of a field on one polygon, in the local order: vertex values, edge
    means (5-point Gauss-Legendre), cell means (Green's formula moments; u quadratic)."""
    n = len(X)
    Xn = np.roll(X, -1, axis=0)
    s, w = np.polynomial.legendre.leggauss(5)
    s, w = 0.5 * (s + 1), 0.5 * w
    means = sum(w[q] * u((1 - s[q]) * X + s[q] * Xn) for q in range(5))
    return np.concatenate([u(X).ravel(), np.asarray(means).ravel(), np.zeros(2)]), n


def rigid_dofs(X):
    """The dofs (4 n + 2, 3) of the rigid motions e_x, e_y, (-y, x) (all linear: edge means
    are midpoint values, cell means are centroid values)."""
    M = moments(X)
    cen = M[1:3] / M[0]
    mid = 0.5 * (X + np.roll(X, -1, axis=0))
    pts = np.vstack([X, mid, cen[None]])
    R = np.zeros((len(pts), 2, 3))
    R[:, 0, 0] = R[:, 1, 1] = 1.0
    R[:, 0, 2], R[:, 1, 2] = -pts[:, 1], pts[:, 0]
    return R.reshape(-1, 3)


def mesh_of(family, **opts):
    return FAMILIES[family].generate(**opts)


FAMILY_MESHES = {
    "voronoi": ("voronoi", {"size": (1.0, 1.0), "n_cells": 40}),
    "nonconvex": ("nonconvex", {"size": (1.0, 1.0), "divisions": (4, 4)}),
    "hanging": ("hanging", {"size": (1.0, 1.0), "divisions": (4, 3)}),
    "distorted": ("distorted", {"size": (1.0, 1.0), "divisions": (5, 4), "amplitude": 0.2}),
    "squares": ("squares", {"size": (1.0, 1.0), "divisions": (3, 3)}),
}


@pytest.fixture(scope="module", params=list(FAMILY_MESHES))
def family_mesh(request):
    name, opts = FAMILY_MESHES[request.param]
    return mesh_of(name, **opts)


# ----------------------------------------------------------------------------- (a) kernels
def assert_rigid_kernel(K, X):
    """K symmetric, positive semidefinite, with exactly the rigid motions as kernel."""
    nd = K.shape[0]
    assert np.allclose(K, K.T, atol=1e-13 * np.abs(K).max())
    ev = np.linalg.eigvalsh(K)
    tol = 1e-10 * ev[-1]
    assert ev[0] > -tol
    assert np.sum(ev < tol) == 3, ev[:5] / ev[-1]
    assert np.linalg.matrix_rank(K, tol=tol) == nd - 3
    R = rigid_dofs(X)
    assert np.abs(K @ R).max() < 1e-10 * np.abs(K).max() * np.abs(R).max()


@pytest.mark.parametrize("stab", STABILIZATIONS)
@pytest.mark.parametrize(
    ("kind", "n"), [("convex", n) for n in (3, 4, 5, 8, 12)] + [("star", n) for n in (5, 8, 12)]
)
def test_element_kernel_random_polygons(kind, n, stab):
    rng = np.random.default_rng(100 * n + len(kind))
    X = batch(rng, n, kind)
    loc = element_matrices2(X, MAT, stab)
    assert loc.K.shape == (len(X), 4 * n + 2, 4 * n + 2)
    for K, Xk in zip(loc.K, X, strict=True):
        assert_rigid_kernel(K, Xk)


def test_element_kernel_on_mesh_families(family_mesh):
    mesh = family_mesh
    for _n, (_ids, verts) in mesh.groups.items():
        X = mesh.points[verts]
        for stab in STABILIZATIONS:
            for K, Xk in zip(element_matrices2(X, MAT, stab).K, X, strict=True):
                assert_rigid_kernel(K, Xk)


def test_unknown_stabilization_rejected():
    X = batch(np.random.default_rng(0), 4, "convex", 1)
    with pytest.raises(ValueError, match="stabilization"):
        element_matrices2(X, MAT, "nope")


def test_batching_and_frame_invariance():
    rng = np.random.default_rng(7)
    X = batch(rng, 6, "star", 4)
    K = element_matrices2(X, MAT).K
    for k in range(len(X)):
        assert np.allclose(element_matrices2(X[k : k + 1], MAT).K[0], K[k], rtol=1e-12, atol=0)
    # a translation does not change a_h^K; a rotation Q maps it to Q-blocks of the dofs
    a = 0.7
    Q = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    Y = X @ Q.T + np.array([3.0, -2.0])
    KY = element_matrices2(Y, MAT).K
    nd = K.shape[1]
    T = np.kron(np.eye(nd // 2), Q)
    assert np.allclose(KY, T @ K @ T.T, rtol=0, atol=1e-10 * np.abs(K).max())


# ----------------------------------------------------------------------------- (b) Pi
@pytest.mark.parametrize(("kind", "n"), [("convex", 3), ("convex", 5), ("star", 5), ("star", 9)])
def test_projection_reproduces_quadratics(kind, n):
    """Pi q = q for q in [P2]^2 given by its dofs computed here (Gauss, Green)."""
    rng = np.random.default_rng(n)
    X = batch(rng, n, kind, 4)
    lp = local_projection2(X, MAT)
    for k, Xk in enumerate(X):
        # a quadratic of O(1) in every part on the cell: q(x) = C m((x - c) / s)
        c, s = Xk.mean(axis=0), np.ptp(Xk, axis=0).max()
        C = rng.normal(size=(2, 6))

        def u(x, t=0.0, C=C, c=c, s=s):
            return quad_field(C)((x - c) / s)

        dofs, _ = local_dofs(Xk, u)
        M = moments((Xk - c) / s)
        dofs[-2:] = C @ M / M[0]  # cell means
        coef = lp.pi[k] @ dofs
        pts = c + rng.normal(size=(7, 2)) * s  # Pi q is q everywhere, not only in K
        xi = (pts - lp.center[k]) / lp.h[k]
        val = np.einsum("a,qac->qc", coef, basis_values(xi))
        scale = np.abs(u(pts)).max()
        assert np.abs(val - u(pts)).max() < 1e-11 * scale
        # the dofs of the basis reproduce the dofs computed here
        assert np.allclose(lp.dofs[k] @ coef, dofs, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("kind", ["convex", "star"])
def test_projection_rigid_conditions(kind):
    """For any dofs v: the cell mean of Pi v is the cell moment, and
    int_K rot Pi v = sum_e |e| mean_e . t_e (Green); Pi of a rigid motion is itself."""
    rng = np.random.default_rng(3)
    n = 7
    X = batch(rng, n, kind, 3)
    lp = local_projection2(X, MAT)
    for k, Xk in enumerate(X):
        v = rng.normal(size=4 * n + 2)
        coef = lp.pi[k] @ v
        # Pi v in the monomials of y = (x - c) / s, fitted from its values at 12 generic
        # points (it is quadratic), then integrated with the Green moments
        c, s = Xk.mean(axis=0), np.ptp(Xk, axis=0).max()
        M = moments((Xk - c) / s)  # int dy; int dx = s^2 int dy
        y = rng.normal(size=(12, 2))
        xi = (c + s * y - lp.center[k]) / lp.h[k]
        val = np.einsum("a,qac->qc", coef, basis_values(xi))
        V = np.column_stack(
            [np.ones(12), y[:, 0], y[:, 1], y[:, 0] ** 2, y[:, 0] * y[:, 1], y[:, 1] ** 2]
        )
        Cg = np.linalg.lstsq(V, val, rcond=None)[0].T  # (2, 6)
        assert np.allclose(Cg @ M / M[0], v[-2:], rtol=0, atol=1e-10 * np.abs(v).max())
        grad = np.einsum("a,qacd->qcd", coef, basis_gradients(xi, lp.h[k]))
        assert np.allclose(grad, quad_gradient(Cg, y) / s, atol=1e-9 * np.abs(grad).max())
        # rot_y of a quadratic is linear, r0 + r1 y1 + r2 y2; int_K rot_x dx = s int rot_y dy
        rot = np.array([Cg[1, 1] - Cg[0, 2], 2 * Cg[1, 3] - Cg[0, 4], Cg[1, 4] - 2 * Cg[0, 5]])
        d = np.roll(Xk, -1, axis=0) - Xk
        edge_means = v[2 * n : 4 * n].reshape(n, 2)
        assert np.isclose(s * rot @ M[:3], np.sum(edge_means * d), rtol=1e-9)
    # Pi of a rigid motion (exact dofs) is that motion: Pi v = v in dofs
    for k, Xk in enumerate(X):
        R = rigid_dofs(Xk)
        assert np.allclose(lp.dofs[k] @ (lp.pi[k] @ R), R, atol=1e-11 * np.abs(R).max())


# ----------------------------------------------------------------------------- numbering
def test_numbering_and_conformity(family_mesh):
    mesh = family_mesh
    num = numbering2(mesh)
    assert num.n_dofs == 2 * (mesh.n_points + len(mesh.edges) + mesh.n_cells)
    # every interior edge dof is shared by exactly two cells, boundary ones by one
    count = np.zeros(num.n_dofs, dtype=int)
    for _n, (ids, verts) in mesh.groups.items():
        d = cell_dofs2(mesh, ids, verts)
        for row in d:
            assert len(np.unique(row)) == len(row)
            count[row] += 1
    edge_count = count[num.edge_offset : num.cell_offset : 2]
    n_boundary = len(mesh.boundary_edges)
    assert np.sum(edge_count == 1) == n_boundary
    assert np.sum(edge_count == 2) == len(mesh.edges) - n_boundary
    assert np.all(count[num.cell_offset :] == 1)


# ----------------------------------------------------------------------------- assembly
def reference_stiffness2(mesh, mat, stab):
    """The plain assembly: scipy's COO of every local matrix at its cell dofs, summed."""
    rows, cols, vals = [], [], []
    for _n, (ids, verts) in mesh.groups.items():
        K = element_matrices2(mesh.points[verts], mat, stab).K
        d = cell_dofs2(mesh, ids, verts)
        rows.append(np.repeat(d, d.shape[1], axis=1).ravel())
        cols.append(np.tile(d, (1, d.shape[1])).ravel())
        vals.append(K.ravel())
    n = numbering2(mesh).n_dofs
    coo = sp.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), (n, n)
    )
    return coo.tocsr()


@pytest.mark.parametrize("stab", STABILIZATIONS)
@pytest.mark.parametrize(
    ("family", "opts"),
    [
        ("voronoi", {"size": (2.0, 1.0), "n_cells": 300, "seed": 3}),
        ("nonconvex", {"size": (1.0, 1.0), "divisions": (5, 4)}),
        ("hanging", {"size": (1.0, 1.0), "divisions": (4, 3)}),
    ],
)
def test_stiffness2_equals_reference_assembly(family, opts, stab):
    """The precomputed CSR pattern and the batched sums give the reference matrix: same
    pattern, canonical (sorted, no duplicates), exactly symmetric, values to 1e-12."""
    mesh = mesh_of(family, **opts)
    A = stiffness2(mesh, MAT, stab)
    R = reference_stiffness2(mesh, MAT, stab)
    assert A.shape == R.shape and A.has_canonical_format
    A.check_format(full_check=True)
    C = A.copy()
    C.sort_indices()
    C.sum_duplicates()
    assert np.array_equal(C.indptr, A.indptr) and np.array_equal(C.indices, A.indices)
    assert np.array_equal(A.indptr, R.indptr) and np.array_equal(A.indices, R.indices)
    assert np.abs(A.data - R.data).max() <= 1e-12 * np.abs(R.data).max()
    assert (A - A.T).count_nonzero() == 0


@pytest.mark.parametrize("pack_bits", [64, 0])
@pytest.mark.parametrize(
    ("family", "opts"),
    [
        ("voronoi", {"size": (2.0, 1.0), "n_cells": 200, "seed": 5}),
        ("hanging", {"size": (1.0, 1.0), "divisions": (4, 3)}),
    ],
)
def test_stiffness2_batches_and_argsort_pattern(monkeypatch, family, opts, pack_bits):
    """Small batches (partial last batches reuse the buffers with their constant entries),
    key, sort and column blocks (equal keys across blocks), and, with ``PACK_BITS = 0``,
    the argsort that meshes too large for the packed sort keys take (about 110,000 Voronoi
    cells and up): the reference matrix as well."""
    import vemwear.vem.dofs2 as dofs2
    import vemwear.vem.local2 as local2

    mesh = mesh_of(family, **opts)
    R = reference_stiffness2(mesh, MAT, "trace")
    monkeypatch.setattr(dofs2, "PACK_BITS", pack_bits)
    monkeypatch.setattr(dofs2, "CHUNK", 7)
    monkeypatch.setattr(dofs2, "_KEY_BLOCK", 5)
    monkeypatch.setattr(dofs2, "_SORT_BLOCK", 13)
    monkeypatch.setattr(local2, "_COLUMNS", 40)
    A = stiffness2(mesh, MAT, "trace")
    A.check_format(full_check=True)
    assert A.has_canonical_format
    assert np.array_equal(A.indptr, R.indptr) and np.array_equal(A.indices, R.indices)
    assert np.abs(A.data - R.data).max() <= 1e-12 * np.abs(R.data).max()
    assert (A - A.T).count_nonzero() == 0


# ----------------------------------------------------------------------------- loads
def test_edge_shape_functions():
    s = np.linspace(0, 1, 7)
    phi = edge_shape_functions(s)
    assert np.allclose(phi[0], [1, 0, 0]) and np.allclose(phi[-1], [0, 1, 0])
    g, w = np.polynomial.legendre.leggauss(4)
    mean = 0.5 * w @ edge_shape_functions(0.5 * (g + 1))
    assert np.allclose(mean, [0, 0, 1])


def test_edge_load_exact_for_quadratic_traction(family_mesh):
    """int_E f . v ds for f quadratic along the edges and v = a P2 field (its dofs)."""
    mesh = family_mesh
    rng = np.random.default_rng(5)
    f, v = quad_field(rng.normal(size=(2, 6))), quad_field(rng.normal(size=(2, 6)))
    edges = mesh.boundary_edges
    F = edge_load_vector2(mesh, edges, f)
    a, b = mesh.points[edges[:, 0]], mesh.points[edges[:, 1]]
    L = np.linalg.norm(b - a, axis=1)
    g, w = np.polynomial.legendre.leggauss(5)
    s, w = 0.5 * (g + 1), 0.5 * w
    exact = sum(
        w[q] * np.sum(L * np.sum(f((1 - s[q]) * a + s[q] * b) * v((1 - s[q]) * a + s[q] * b), 1))
        for q in range(5)
    )
    assert np.isclose(F @ interpolate2(mesh, v), exact, rtol=1e-12)


def test_body_force_paper_rule_loads_cell_dofs(family_mesh):
    mesh = family_mesh
    num = numbering2(mesh)
    C = np.random.default_rng(2).normal(size=(2, 6))
    f = quad_field(C)
    F = body_force_vector2(mesh, f)
    assert np.all(F[: num.cell_offset] == 0)
    expect = np.array([C @ moments(mesh.points[c]) for c in mesh.cells])  # int_K f
    assert np.allclose(F[num.cell_offset :].reshape(-1, 2), expect, rtol=1e-12, atol=1e-14)
    # the projection rule equals the paper's for f constant on cells
    F0 = body_force_vector2(mesh, [1.5, -0.5])
    F1 = body_force_vector2(mesh, [1.5, -0.5], rule="projection", material=MAT)
    assert np.allclose(F0, F1, atol=1e-13)
    with pytest.raises(ValueError, match="material"):
        body_force_vector2(mesh, f, rule="projection")
    with pytest.raises(ValueError, match="rule"):
        body_force_vector2(mesh, f, rule="vertex")


# ----------------------------------------------------------------------------- (c) patch
def solve_with(A, F, fixed, values):
    u = values.copy()
    free = np.setdiff1d(np.arange(A.shape[0]), fixed)
    u[free] = spla.spsolve(A[free][:, free].tocsc(), F[free] - A[free][:, fixed] @ values[fixed])
    return u


@pytest.mark.parametrize("stab", STABILIZATIONS)
@pytest.mark.parametrize("rule", ["paper", "projection"])
def test_patch_test_dirichlet(family_mesh, stab, rule):
    """A quadratic u with its constant body force, u prescribed at all boundary dofs."""
    mesh = family_mesh
    C = np.random.default_rng(11).normal(size=(2, 6))
    u = quad_field(C)
    A = stiffness2(mesh, MAT, stab)
    F = body_force_vector2(mesh, quad_body_force(C, MAT), rule=rule, material=MAT)
    ue = interpolate2(mesh, u)
    fixed = np.concatenate(facet_dofs2(mesh, mesh.boundary_edges))
    uh = solve_with(A, F, fixed, ue)
    assert np.abs(uh - ue).max() < 1e-10 * np.abs(ue).max()


def test_patch_test_mixed_tractions(family_mesh):
    """Clamped (prescribed u) on the left side only, the tractions sigma(u) n of the
    quadratic u on the three other sides (a linear f2 along each edge)."""
    mesh = tag_rectangle(family_mesh, {"clamped": "left", "traction": ["right", "top", "bottom"]})
    C = np.random.default_rng(12).normal(size=(2, 6))
    u = quad_field(C)
    A = stiffness2(mesh, MAT)
    F = body_force_vector2(mesh, quad_body_force(C, MAT))
    edges = mesh.part_edges("traction")
    a, b = mesh.points[edges[:, 0]], mesh.points[edges[:, 1]]
    d = b - a
    nrm = np.column_stack([d[:, 1], -d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
    # the outward normals of the sides are axis-aligned, so sigma n is a function of x
    side_normal = {
        "right": np.array([1.0, 0.0]),
        "top": np.array([0.0, 1.0]),
        "bottom": np.array([0.0, -1.0]),
    }
    for nv in side_normal.values():
        mask = np.all(np.isclose(nrm, nv), axis=1)
        F += edge_load_vector2(
            mesh,
            edges[mask],
            lambda x, t=0.0, nv=nv: stress(quad_gradient(C, x), MAT) @ nv,
        )
    assert np.allclose(traction_vector2(mesh, [0.0, 0.0]), 0.0)
    ue = interpolate2(mesh, u)
    fixed = np.concatenate(facet_dofs2(mesh, mesh.part_edges("clamped")))
    uh = solve_with(A, F, fixed, ue)
    assert np.abs(uh - ue).max() < 1e-10 * np.abs(ue).max()


# ----------------------------------------------------------------------------- (d) orders
PI = np.pi


def smooth_u(x, t=0.0):
    X, Y = x[:, 0], x[:, 1]
    return np.stack([np.sin(PI * X) * np.sin(PI * Y), np.cos(PI * X) * np.sin(PI * Y)], -1)


def smooth_grad(x):
    X, Y = x[:, 0], x[:, 1]
    sx, cx, sy, cy = np.sin(PI * X), np.cos(PI * X), np.sin(PI * Y), np.cos(PI * Y)
    return PI * np.stack(
        [np.stack([cx * sy, sx * cy], -1), np.stack([-sx * sy, cx * cy], -1)], axis=1
    )


def smooth_f1(x, t=0.0):
    """-div sigma = -eta lap u - (lam + eta) grad div u, div u = pi cos(pi x)(sin + cos)(pi y)."""
    X, Y = x[:, 0], x[:, 1]
    sx, cx, sy, cy = np.sin(PI * X), np.cos(PI * X), np.sin(PI * Y), np.cos(PI * Y)
    graddiv = PI**2 * np.stack([-sx * (sy + cy), cx * (cy - sy)], -1)
    return 2 * PI**2 * MAT.eta * smooth_u(x) - (MAT.lam + MAT.eta) * graddiv


def manufactured_errors(mesh, rule):
    """L2 and H1-seminorm errors of Pi u_h against u (degree-5 rule on the fan)."""
    A = stiffness2(mesh, MAT)
    F = body_force_vector2(mesh, smooth_f1, rule=rule, material=MAT)
    ue = interpolate2(mesh, smooth_u)
    uh = solve_with(A, F, np.concatenate(facet_dofs2(mesh, mesh.boundary_edges)), ue)
    pts, w, cells = polygon_quadrature(mesh, 5)
    val, grad = project2(mesh, MAT, uh).at(pts, cells)
    eL2 = np.sqrt(np.sum(w * np.sum((val - smooth_u(pts)) ** 2, axis=1)))
    eH1 = np.sqrt(np.sum(w * np.sum((grad - smooth_grad(pts)) ** 2, axis=(1, 2))))
    return mesh.h, eL2, eH1


def orders(family, levels, rule):
    errs = []
    for n in levels:
        opts = {"n_cells": n * n} if family == "voronoi" else {"divisions": (n, n)}
        errs.append(manufactured_errors(mesh_of(family, size=(1.0, 1.0), **opts), rule))
    e = np.array(errs)
    r = np.log(e[:-1, 1:] / e[1:, 1:]) / np.log(e[:-1, 0] / e[1:, 0])[:, None]
    return e, r  # r[:, 0] L2 orders, r[:, 1] H1 orders


@pytest.mark.parametrize("family", ["squares", "voronoi"])
def test_manufactured_orders(family):
    """H1 order 2 with either load; L2 order 3 with the projection load, and only 2 with the
    paper's P_0 load (its consistency error (f - P0 f, v - P0 v) is O(h^2) for k = 2)."""
    levels = [4, 8, 16, 24] if family == "voronoi" else [4, 8, 16]
    _e, r = orders(family, levels, "projection")
    assert np.all(r[-1] > [2.7, 1.8]), r
    _e, r = orders(family, levels, "paper")
    assert r[-1, 1] > 1.8, r
    assert 1.7 < r[-1, 0] < 2.4, r


def test_project2_checks_size(family_mesh):
    with pytest.raises(ValueError, match="entries"):
        project2(family_mesh, MAT, np.zeros(3))
