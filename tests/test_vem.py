"""Lowest-order VEM: local matrices, projection, patch tests and loads.

Every expected value is computed here from the definitions (paper 3.3, 3.8-3.11,
design.md section 2), not from the code under test: polygon areas, centroids and
moments by Green's formula, eps(Pi v) from its boundary integral, exact linear fields,
exact edge integrals of linear tractions against hat functions.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from scipy.spatial import Voronoi

from conftest import is_convex, moments, polygon
from vemwear.mesh import Mesh, check_mesh, tag_rectangle
from vemwear.vem import (
    STABILIZATIONS,
    Material,
    Projection,
    body_force_vector,
    cell_means,
    edge_load_vector,
    element_matrices,
    project,
    stiffness,
    traction_vector,
    triangle_matrices,
)

MAT = Material(lam=4.0, eta=4.0)
MAT_B = Material(lam=7.5, eta=1.3)  # lam != eta catches a swapped Lamé pair


# ----------------------------------------------------------------------------- geometry
def shoelace(X):
    """Signed area of a polygon (k, 2), in coordinates relative to its first vertex."""
    X = X - X[0]
    x, y = X[:, 0], X[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def centroid(X):
    m = moments(X)
    return m[1:3] / m[0]


def boundary_strain(X, V):
    """eps(Pi v) = 1/|K| sum_e int_e sym(v (x) n) ds, v linear on each edge (paper 3.8)."""
    Xn, Vn = np.roll(X, -1, axis=0), np.roll(V, -1, axis=0)
    d = Xn - X
    nl = np.column_stack([d[:, 1], -d[:, 0]])  # |e| n_e for a counter-clockwise polygon
    vm = 0.5 * (V + Vn)  # int_e v ds = |e| v(midpoint)
    M = np.einsum("ea,eb->ab", vm, nl) / shoelace(X)
    return 0.5 * (M + M.T)


def energy(E1, E2, mat):
    """C E1 : E2 with C tau = 2 eta tau + lam tr(tau) I."""
    return 2 * mat.eta * np.sum(E1 * E2) + mat.lam * np.trace(E1) * np.trace(E2)


def cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def rigid_modes(X):
    """Vertex values of the translations and the infinitesimal rotation, (3, 2n)."""
    n = len(X)
    c = X.mean(axis=0)
    R = np.zeros((3, n, 2))
    R[0, :, 0] = 1.0
    R[1, :, 1] = 1.0
    R[2, :, 0] = -(X[:, 1] - c[1])
    R[2, :, 1] = X[:, 0] - c[0]
    return R.reshape(3, 2 * n)


def random_polygons(kind, n, count, rng):
    return np.stack([polygon(rng, n, kind) for _ in range(count)])


# ----------------------------------------------------------------------------- meshes
def voronoi_mesh(n_sites=40, lloyd=3, seed=0):
    """Voronoi diagram of random sites clipped to the unit square by mirroring the
    sites across the four sides (the clipped cells are exactly the cells of the
    original sites), relaxed by a few Lloyd steps."""
    rng = np.random.default_rng(seed)
    sites = rng.uniform(0.02, 0.98, (n_sites, 2))
    for it in range(lloyd + 1):
        mir = [sites]
        for axis, val in ((0, 0.0), (0, 1.0), (1, 0.0), (1, 1.0)):
            s = sites.copy()
            s[:, axis] = 2 * val - s[:, axis]
            mir.append(s)
        vor = Voronoi(np.vstack(mir))
        V = vor.vertices.copy()
        V[np.abs(V) < 1e-12] = 0.0
        V[np.abs(V - 1) < 1e-12] = 1.0
        cells = []
        for i in range(n_sites):
            reg = vor.regions[vor.point_region[i]]
            assert -1 not in reg and len(reg) >= 3
            reg = list(reg)
            if shoelace(V[reg]) < 0:
                reg = reg[::-1]
            cells.append(reg)
        if it < lloyd:
            sites = np.array([centroid(V[c]) for c in cells])
    used = np.unique(np.concatenate(cells))
    new = -np.ones(len(V), dtype=int)
    new[used] = np.arange(len(used))
    return Mesh.from_cells(V[used], [new[c] for c in cells])


def grid_nodes(n):
    """(n+1)^2 lattice nodes of the unit square; node (i, j) has id j (n + 1) + i."""
    x = np.linspace(0, 1, n + 1)
    X, Y = np.meshgrid(x, x)
    return np.column_stack([X.ravel(), Y.ravel()])


def perturb_interior(P, amount, rng):
    P = P.copy()
    inner = np.all((P > 1e-12) & (P < 1 - 1e-12), axis=1)
    P[inner] += rng.uniform(-amount, amount, (int(inner.sum()), 2))
    return P


def perturbed_polygon_mesh(n=6, seed=1):
    """Perturbed grid; cells are quadrilaterals, pairs merged into hexagons,
    and quadrilaterals cut into two triangles."""
    rng = np.random.default_rng(seed)
    P = perturb_interior(grid_nodes(n), 0.2 / n, rng)
    nid = lambda i, j: j * (n + 1) + i  # noqa: E731
    cells = []
    for j in range(n):
        i = 0
        while i < n:
            r = rng.uniform()
            if r < 0.35 and i + 1 < n:
                cells.append(
                    [
                        nid(i, j),
                        nid(i + 1, j),
                        nid(i + 2, j),
                        nid(i + 2, j + 1),
                        nid(i + 1, j + 1),
                        nid(i, j + 1),
                    ]
                )
                i += 2
                continue
            a, b, c, d = nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1)
            if r < 0.6:
                cells += [[a, b, c], [a, c, d]]
            else:
                cells.append([a, b, c, d])
            i += 1
    return Mesh.from_cells(P, cells)


def l_shaped_mesh(blocks=3, seed=2):
    """2x2 blocks of squares, each split into an L-shaped polygon of three squares
    (non-convex, reflex vertex at the block centre) and one square; interior nodes
    perturbed so that no angle stays straight."""
    rng = np.random.default_rng(seed)
    n = 2 * blocks
    P = perturb_interior(grid_nodes(n), 0.08 / n, rng)
    nid = lambda i, j: j * (n + 1) + i  # noqa: E731
    # counter-clockwise boundary of the 2x2 block (local lattice coordinates)
    ring = [(0, 0), (1, 0), (2, 0), (2, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    corner_sq = {  # the separate square at each corner, and the ring index of that corner
        (1, 1): 4,
        (0, 1): 6,
        (0, 0): 0,
        (1, 0): 2,
    }
    cells = []
    for bj in range(blocks):
        for bi in range(blocks):
            (ci, cj), k = list(corner_sq.items())[rng.integers(4)]
            # the L: the ring with its corner k replaced by the block centre
            Lring = [(1, 1) if m == k else ring[m] for m in range(8)]
            cells.append([nid(2 * bi + a, 2 * bj + b) for a, b in Lring])
            sq = [(ci, cj), (ci + 1, cj), (ci + 1, cj + 1), (ci, cj + 1)]
            cells.append([nid(2 * bi + a, 2 * bj + b) for a, b in sq])
    return Mesh.from_cells(P, cells)


def conformize(P, cells):
    """Insert every lattice point that lies strictly inside a cell edge into the cell
    (exact integer arithmetic); this turns a locally refined grid into hanging nodes."""
    out = []
    for c in cells:
        new = []
        for a, b in zip(c, c[1:] + c[:1], strict=True):
            new.append(a)
            d = P[b] - P[a]
            r = P - P[a]
            t = r @ d
            on = (r[:, 0] * d[1] - r[:, 1] * d[0] == 0) & (t > 0) & (t < d @ d)
            ids = np.flatnonzero(on)
            new += ids[np.argsort(t[ids])].tolist()
        out.append(new)
    return out


def hanging_node_mesh(n=4, refine=((1, 1), (2, 2), (3, 0))):
    """n x n squares; the listed squares split 2x2, their neighbours carry the edge
    midpoints as extra vertices (hanging nodes)."""
    m = 2 * n  # integer lattice at half spacing
    ids = {}

    def vid(i, j):
        return ids.setdefault((i, j), len(ids))

    cells = []
    for j in range(n):
        for i in range(n):
            if (i, j) in refine:
                for b in range(2):
                    for a in range(2):
                        x, y = 2 * i + a, 2 * j + b
                        cells.append([vid(x, y), vid(x + 1, y), vid(x + 1, y + 1), vid(x, y + 1)])
            else:
                x, y = 2 * i, 2 * j
                cells.append([vid(x, y), vid(x + 2, y), vid(x + 2, y + 2), vid(x, y + 2)])
    P = np.zeros((len(ids), 2), dtype=np.int64)
    for (i, j), k in ids.items():
        P[k] = (i, j)
    cells = conformize(P, cells)
    return Mesh.from_cells(P / m, cells)


MESHES = {
    "voronoi": voronoi_mesh,
    "perturbed": perturbed_polygon_mesh,
    "l-shaped": l_shaped_mesh,
    "hanging": hanging_node_mesh,
}


@pytest.fixture(scope="module", params=list(MESHES))
def poly_mesh(request):
    mesh = MESHES[request.param]()
    check_mesh(mesh.with_boundary({"clamped": "rest"}))
    return request.param, mesh


def test_meshes_are_what_they_claim():
    """The test meshes really contain general, non-convex and hanging-node cells."""
    vm = voronoi_mesh()
    assert len(vm.groups) >= 3 and max(vm.groups) >= 6
    assert np.isclose(vm.cell_areas.sum(), 1.0, rtol=1e-13)
    pm = perturbed_polygon_mesh()
    assert {3, 4, 6} <= set(pm.groups)
    lm = l_shaped_mesh()
    assert sum(not is_convex(lm.points[c]) for c in lm.cells) == 9
    hm = hanging_node_mesh()
    assert 5 in hm.groups or 6 in hm.groups  # neighbours with midpoints
    for mesh in (vm, pm, lm, hm):
        assert np.isclose(sum(shoelace(mesh.points[c]) for c in mesh.cells), 1.0, rtol=1e-13)


# ----------------------------------------------------------------------------- 1. kernel
@pytest.mark.parametrize("stab", STABILIZATIONS)
@pytest.mark.parametrize("kind", ["convex", "star"])
def test_element_stiffness_spsd_with_rigid_kernel(kind, stab):
    rng = np.random.default_rng([len(kind), STABILIZATIONS.index(stab)])
    worst_ratio = np.inf
    for n in range(3 if kind == "convex" else 4, 13):
        X = random_polygons(kind, n, 6, rng)
        for mat in (MAT, MAT_B):
            K, _B, _P, area = element_matrices(X, mat, stab)
            # areas, up to the eps (distance / size)^2 of a shoelace in absolute coordinates
            c = 1 + np.abs(X).max(axis=(1, 2)) / np.ptp(X, axis=1).max(axis=1)
            ref = np.array([shoelace(x) for x in X])
            assert np.all(np.abs(area - ref) <= 1e-15 * c**2 * np.abs(ref))
            for x, k in zip(X, K, strict=True):
                scale = np.abs(k).max()
                assert np.abs(k - k.T).max() <= 1e-13 * scale
                R = rigid_modes(x)
                Rn = R / np.linalg.norm(R, axis=1)[:, None]
                assert np.abs(k @ Rn.T).max() <= 1e-12 * scale, "a rigid motion has energy"
                ev = np.linalg.eigvalsh(0.5 * (k + k.T))
                assert ev[0] >= -1e-12 * ev[-1]
                assert np.abs(ev[:3]).max() <= 1e-12 * ev[-1]
                worst_ratio = min(worst_ratio, ev[3] / ev[-1])
    # the 4th eigenvalue is clearly away from zero: the kernel is exactly rigid
    assert worst_ratio > 5e-3, worst_ratio


@pytest.mark.parametrize("stab", STABILIZATIONS)
def test_element_stiffness_kernel_with_straight_angles(stab):
    """Squares with extra edge points (hanging nodes) keep the 3-dim rigid kernel."""
    X = np.array([[0, 0], [0.5, 0], [1, 0], [1, 1], [0.5, 1], [0, 1], [0, 0.5]], float)
    K = element_matrices(X[None], MAT, stab)[0][0]
    ev = np.linalg.eigvalsh(K)
    assert np.abs(ev[:3]).max() <= 1e-12 * ev[-1] and ev[3] > 1e-2 * ev[-1]


@pytest.mark.parametrize("stab", STABILIZATIONS)
def test_element_stiffness_frame_invariance_and_batching(stab):
    """K is invariant under translation and scaling (2D), rotates as R K R^T, follows a
    cyclic relabelling of the vertices, and a batch equals cell-by-cell evaluation."""
    rng = np.random.default_rng(7)
    X = np.stack([polygon(rng, 7, "star") for _ in range(4)])
    K = element_matrices(X, MAT, stab)[0]
    a = 0.7
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    Rb = np.kron(np.eye(7), R)
    for i, x in enumerate(X):
        k1 = element_matrices(x[None], MAT, stab)[0][0]
        assert np.allclose(k1, K[i], rtol=0, atol=1e-13 * np.abs(K[i]).max())
        y = 3.7 * (x - 2.0) @ R.T
        k2 = element_matrices(y[None], MAT, stab)[0][0]
        assert np.allclose(k2, Rb @ K[i] @ Rb.T, rtol=0, atol=1e-12 * np.abs(K[i]).max())
        perm = np.r_[2:7, 0:2]
        k3 = element_matrices(x[perm][None], MAT, stab)[0][0]
        dofs = np.column_stack([2 * perm, 2 * perm + 1]).ravel()
        assert np.allclose(k3, K[i][np.ix_(dofs, dofs)], rtol=0, atol=1e-12 * np.abs(K[i]).max())


def test_unknown_stabilization_rejected():
    X = np.array([[[0, 0], [1, 0], [0, 1]]], float)
    with pytest.raises(ValueError, match="stabilization"):
        element_matrices(X, MAT, "bogus")
    mesh = tag_rectangle(Mesh.from_cells(X[0], [[0, 1, 2]]))
    with pytest.raises(ValueError, match="stabilization"):
        stiffness(mesh, MAT, "bogus")


@pytest.mark.parametrize("stab", STABILIZATIONS)
def test_triangle_matrices_are_the_general_path_without_stabilization(stab):
    """On triangles Pi is the identity on P1: the general path's stabilization is
    round-off, and triangle_matrices gives its matrices, for every weight."""
    rng = np.random.default_rng(11)
    X = np.stack([polygon(rng, 3, "convex") for _ in range(50)])
    X *= rng.uniform(1e-3, 1e3, size=(50, 1, 1))  # scale-free: relative tolerances
    for mat in (MAT, MAT_B):
        K = element_matrices(X, mat, stab)[0]
        T = triangle_matrices(X, mat)
        scale = np.abs(K).max(axis=(1, 2))[:, None, None]
        assert (np.abs(T - K) <= 1e-13 * scale).all()
        ev = np.linalg.eigvalsh(T)
        assert (np.abs(ev[:, :3]) <= 1e-12 * ev[:, -1:]).all()  # rigid motions


# ----------------------------------------------------------------------------- 2. projection
@pytest.mark.parametrize("kind", ["convex", "star"])
def test_projection_definition_and_consistency(kind):
    rng = np.random.default_rng(11 if kind == "convex" else 12)
    for n in range(3 if kind == "convex" else 4, 13):
        X = random_polygons(kind, n, 4, rng)
        for stab in STABILIZATIONS:
            K, _B, P, _area = element_matrices(X, MAT_B, stab)
            for x, k, Pm in zip(X, K, P, strict=True):
                h = np.ptp(x, axis=0).max()
                area = shoelace(x)
                # Round-off grows with c = (distance from the origin) / size: the random
                # polygons sit up to ~500 diameters away from the origin. Tolerances are
                # linear in c (what the geometry in relative coordinates achieves).
                c = 1 + np.abs(x).max() / h
                tol = 1e-13 * c
                # linear fields are reproduced, and Pi is idempotent
                A, b = rng.normal(size=(2, 2)), rng.normal(size=2)
                q = (x @ A.T + b).ravel()
                assert np.allclose(Pm @ q, q, rtol=0, atol=tol * np.abs(q).max())
                assert np.allclose(Pm @ Pm, Pm, rtol=0, atol=tol * np.abs(Pm).max())
                # Pi v for a random v is determined by (3.8)-(3.10); check each condition
                v = rng.normal(size=2 * n)
                V, PV = v.reshape(n, 2), (Pm @ v).reshape(n, 2)
                fit = np.column_stack([x - x.mean(axis=0), np.ones(n)])
                coef = np.linalg.lstsq(fit, PV, rcond=None)[0]
                assert np.abs(fit @ coef - PV).max() <= tol * np.abs(PV).max()  # Pi v is linear
                G = coef[:2].T  # gradient of Pi v
                E = boundary_strain(x, V)
                assert np.allclose(0.5 * (G + G.T), E, rtol=0, atol=tol * np.abs(V).max() / h)
                assert np.allclose(PV.mean(axis=0), V.mean(axis=0), rtol=0, atol=tol)  # (3.9)
                d = x - x.mean(axis=0)
                assert np.isclose(
                    cross2(d, PV).sum(),
                    cross2(d, V).sum(),  # (3.10)
                    rtol=0,
                    atol=tol * h * n,
                )
                # consistency (3.6): a_h(v, q) = |K| eps(Pi v) : C eps(q), any stabilization
                eq = 0.5 * (A + A.T)
                lhs = v @ k @ q
                rhs = area * energy(E, eq, MAT_B)
                scale = abs(area) * 2 * (MAT_B.lam + MAT_B.eta) * np.abs(E).max() * np.abs(A).max()
                assert abs(lhs - rhs) <= 1e-12 * c * scale
                # and the energy of a linear field is exact: a_h(q, q) = |K| C eps(q) : eps(q);
                # vemwear's areas (shoelace in absolute coordinates) add an eps c^2 error
                assert np.isclose(
                    q @ k @ q, area * energy(eq, eq, MAT_B), rtol=1e-12 * c + 2e-13 * c**2, atol=0
                )


# ----------------------------------------------------------------------------- 3. patch tests
def linear_field(seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(2, 2))
    b = rng.normal(size=2)
    return A, b


def on_square_boundary(P, tol=1e-12):
    return np.any((P < tol) | (P > 1 - tol), axis=1)


def solve_prescribed(K, F, fixed_dofs, values):
    """Solve K u = F on the free dofs with u = values on fixed_dofs (own elimination)."""
    ndof = K.shape[0]
    u = np.zeros(ndof)
    u[fixed_dofs] = values
    free = np.setdiff1d(np.arange(ndof), fixed_dofs)
    Kc = K.tocsr()
    rhs = F[free] - Kc[free][:, fixed_dofs] @ values
    u[free] = spla.spsolve(Kc[free][:, free].tocsc(), rhs)
    return u


@pytest.mark.parametrize("stab", STABILIZATIONS)
def test_patch_test_dirichlet(poly_mesh, stab):
    name, mesh = poly_mesh
    A, b = linear_field(3)
    exact = mesh.points @ A.T + b
    K = stiffness(mesh, MAT_B, stab)
    assert abs(K - K.T).max() <= 1e-13 * abs(K).max()
    bnd = np.flatnonzero(on_square_boundary(mesh.points))
    fixed = np.column_stack([2 * bnd, 2 * bnd + 1]).ravel()
    u = solve_prescribed(K, np.zeros(K.shape[0]), fixed, exact[bnd].ravel())
    err = np.abs(u.reshape(-1, 2) - exact).max() / np.abs(exact).max()
    assert err < 1e-11, f"{name}/{stab}: patch test error {err:.2e}"


SIDES = {  # outward normals of the unit square's sides, and a selector on points
    "left": (np.array([-1.0, 0.0]), lambda m: np.abs(m[:, 0]) < 1e-12),
    "right": (np.array([1.0, 0.0]), lambda m: np.abs(m[:, 0] - 1) < 1e-12),
    "bottom": (np.array([0.0, -1.0]), lambda m: np.abs(m[:, 1]) < 1e-12),
    "top": (np.array([0.0, 1.0]), lambda m: np.abs(m[:, 1] - 1) < 1e-12),
}


def stress(A, mat):
    E = 0.5 * (A + A.T)
    return 2 * mat.eta * E + mat.lam * np.trace(E) * np.eye(2)


def outward_normal_at(x):
    """Normal of the unit square's side through each (non-corner) point."""
    n = np.zeros_like(x)
    for nrm, on in SIDES.values():
        n[on(x)] = nrm
    assert np.all(np.abs(n).sum(axis=1) == 1), "point not on exactly one side"
    return n


@pytest.mark.parametrize("stab", STABILIZATIONS)
def test_patch_test_mixed_traction(poly_mesh, stab):
    """Left side prescribed, traction sigma n on the three other sides, no body force."""
    name, mesh = poly_mesh
    A, b = linear_field(4)
    S = stress(A, MAT)
    exact = mesh.points @ A.T + b
    be = mesh.boundary_edges
    mid = 0.5 * (mesh.points[be[:, 0]] + mesh.points[be[:, 1]])
    # the traction load side by side, with edge_load_vector ...
    F_sides = np.zeros(2 * mesh.n_points)
    for side in ("right", "bottom", "top"):
        nrm, on = SIDES[side]
        F_sides += edge_load_vector(mesh, be[on(mid)], S @ nrm)
    # ... and on the tagged traction part, with f2(x, t) = sigma n(x)
    tagged = tag_rectangle(mesh, {"clamped": "left", "traction": ["right", "bottom", "top"]})
    F = traction_vector(tagged, lambda x, t: outward_normal_at(x) @ S.T)
    assert np.allclose(F, F_sides, rtol=0, atol=1e-14 * np.abs(F).max())
    # global equilibrium of the load: total force and moment of sigma n over the boundary
    # equal those of the (missing) left side with opposite sign
    nL = SIDES["left"][0]
    assert np.allclose(F.reshape(-1, 2).sum(axis=0), -S @ nL, rtol=0, atol=1e-13)
    K = stiffness(mesh, MAT, stab)
    left = np.flatnonzero(np.abs(mesh.points[:, 0]) < 1e-12)
    fixed = np.column_stack([2 * left, 2 * left + 1]).ravel()
    u = solve_prescribed(K, F, fixed, exact[left].ravel())
    err = np.abs(u.reshape(-1, 2) - exact).max() / np.abs(exact).max()
    assert err < 1e-11, f"{name}/{stab}: mixed patch test error {err:.2e}"


# ----------------------------------------------------------------------------- 4. loads
def test_cell_means_exact_for_linear_and_quadratic(poly_mesh):
    _name, mesh = poly_mesh
    c0, M = np.array([0.3, -1.2]), np.array([[1.5, -0.7], [0.4, 2.0]])
    lin = lambda x, t: c0 + x @ M.T  # noqa: E731
    means = cell_means(mesh, lin)
    exp = np.array([c0 + M @ centroid(mesh.points[c]) for c in mesh.cells])
    assert np.allclose(means, exp, rtol=0, atol=1e-13)
    # quadratic field (x^2 - 3 x y, y^2 + 2 x): the degree-2 rule is exact as documented
    quad = lambda x, t: np.column_stack(  # noqa: E731
        [x[:, 0] ** 2 - 3 * x[:, 0] * x[:, 1], x[:, 1] ** 2 + 2 * x[:, 0]]
    )
    mo = np.array([moments(mesh.points[c]) for c in mesh.cells])
    exp = np.column_stack([mo[:, 3] - 3 * mo[:, 4], mo[:, 5] + 2 * mo[:, 1]]) / mo[:, :1]
    assert np.allclose(cell_means(mesh, quad), exp, rtol=0, atol=1e-13)
    # a constant given as a plain vector
    assert np.array_equal(cell_means(mesh, (0.0, -0.06)), np.tile([0.0, -0.06], (mesh.n_cells, 1)))
    # time is passed through
    tdep = lambda x, t: np.tile([t, 2 * t], (len(x), 1))  # noqa: E731
    assert np.allclose(cell_means(mesh, tdep, t=0.5), np.tile([0.5, 1.0], (mesh.n_cells, 1)))


def test_body_force_vector(poly_mesh):
    """Each vertex of K gets |K| P0 f / n_K (3.3); the sum is int f for linear f."""
    _name, mesh = poly_mesh
    c0, M = np.array([0.0, -0.06]), np.array([[0.2, 0.1], [-0.3, 0.5]])
    f = lambda x, t: c0 + x @ M.T  # noqa: E731
    F = body_force_vector(mesh, f).reshape(-1, 2)
    expect = np.zeros((mesh.n_points, 2))
    total = np.zeros(2)
    for c in mesh.cells:
        X = mesh.points[c]
        fK = shoelace(X) * (c0 + M @ centroid(X))  # int_K f, exact for linear f
        total += fK
        expect[c] += fK / len(c)
    assert np.allclose(F, expect, rtol=0, atol=1e-15)
    assert np.allclose(F.sum(axis=0), total, rtol=1e-13)
    # int over the unit square of c0 + M x = c0 + M (1/2, 1/2)
    assert np.allclose(F.sum(axis=0), c0 + M @ [0.5, 0.5], rtol=1e-13)
    # constant f: sum is f |Omega| and v . F = sum_K |K| f . (vertex average of v)
    Fc = body_force_vector(mesh, (0.3, -0.06))
    assert np.allclose(Fc.reshape(-1, 2).sum(axis=0), [0.3, -0.06], rtol=1e-13)
    v = np.random.default_rng(5).normal(size=(mesh.n_points, 2))
    direct = sum(
        shoelace(mesh.points[c]) * (np.array([0.3, -0.06]) @ v[c].mean(axis=0)) for c in mesh.cells
    )
    assert np.isclose(v.ravel() @ Fc, direct, rtol=1e-13)


def test_edge_load_exact_for_linear_traction(poly_mesh):
    _name, mesh = poly_mesh
    c0, M = np.array([0.7, -0.2]), np.array([[1.0, -2.0], [0.5, 3.0]])
    f = lambda x, t: c0 + x @ M.T  # noqa: E731
    edges = mesh.boundary_edges
    F = edge_load_vector(mesh, edges, f).reshape(-1, 2)
    expect = np.zeros((mesh.n_points, 2))
    for a, b in edges:  # int_e f phi_a ds = |e| (2 f(a) + f(b)) / 6 for f linear
        L = np.linalg.norm(mesh.points[b] - mesh.points[a])
        fa, fb = c0 + M @ mesh.points[a], c0 + M @ mesh.points[b]
        expect[a] += L * (2 * fa + fb) / 6
        expect[b] += L * (fa + 2 * fb) / 6
    assert np.allclose(F, expect, rtol=0, atol=1e-15)
    # total force: the boundary of the unit square, int f ds = 4 c0 + M int x ds = 4 c0 + 2 M 1
    assert np.allclose(F.sum(axis=0), 4 * c0 + M @ [2.0, 2.0], rtol=1e-13)
    # traction_vector only sees the traction part
    tagged = tag_rectangle(
        mesh, {"clamped": "left", "traction": "top", "contact": ["bottom", "right"]}
    )
    Ft = traction_vector(tagged, f).reshape(-1, 2)
    off = np.ones(mesh.n_points, bool)
    off[tagged.part_vertices("traction")] = False
    assert np.all(Ft[off] == 0)
    # int_top f . v ds for linear v, by Simpson per edge (exact for the quadratic integrand)
    v = lambda x: np.column_stack([1 + x[:, 0] - x[:, 1], 2 * x[:, 0] + 0.5])  # noqa: E731
    simpson = 0.0
    for a, b in tagged.part_edges("traction"):
        pa, pb = mesh.points[a], mesh.points[b]
        pts = np.array([pa, 0.5 * (pa + pb), pb])
        vals = np.sum(f(pts, 0.0) * v(pts), axis=1)
        simpson += np.linalg.norm(pb - pa) * (vals[0] + 4 * vals[1] + vals[2]) / 6
    assert np.isclose(v(mesh.points).ravel() @ Ft.ravel(), simpson, rtol=1e-13)


# ----------------------------------------------------------------------------- 5. Pi as an operator
def check_definition(X, V, G, value, tol):
    """Pi v = value + G (x - xbar) on the polygon X with vertex values V satisfies
    (3.8) (strain = boundary strain), (3.9) and (3.10) in the paper's form (with x_i)."""
    h = np.ptp(X, axis=0).max()
    PV = value + (X - X.mean(axis=0)) @ G.T
    E = boundary_strain(X, V)
    scale = np.abs(V).max()
    assert np.allclose(0.5 * (G + G.T), E, rtol=0, atol=tol * scale / h)  # (3.8)
    assert np.allclose(PV.mean(axis=0), V.mean(axis=0), rtol=0, atol=tol * scale)  # (3.9)
    lhs, rhs = cross2(X, PV).mean(), cross2(X, V).mean()  # (3.10)
    assert abs(lhs - rhs) <= tol * scale * np.abs(X).max()


@pytest.mark.parametrize("kind", ["convex", "star"])
def test_projection_operator_definition_on_random_polygons(kind):
    """The global operator on cells of 3 ... 12 vertices, all in one mesh (batched by
    vertex count), against (3.8)-(3.10); it reproduces linear fields."""
    rng = np.random.default_rng(21 if kind == "convex" else 22)
    polys = [random_polygons(kind, n, 3, rng) for n in range(3 if kind == "convex" else 4, 13)]
    X = np.concatenate([p.reshape(-1, 2) for p in polys])
    cells, start = [], 0
    for p in polys:
        for _ in range(len(p)):
            cells.append(np.arange(start, start + p.shape[1]))
            start += p.shape[1]
    # the vertex counts interleaved among the cell ids, each cell's vertices not in
    # ascending order: the matrix is written cell by cell with its columns sorted
    cells = [np.roll(cells[i], i) for i in rng.permutation(len(cells))]
    mesh = Mesh.from_cells(X, cells)
    pi = Projection(mesh)
    assert pi.matrix.has_canonical_format
    v = rng.normal(size=(mesh.n_points, 2))
    f = pi(v)
    for k, c in enumerate(mesh.cells):
        Xk = mesh.points[c]
        c_rel = 1 + np.abs(Xk).max() / np.ptp(Xk, axis=0).max()
        check_definition(Xk, v[c], f.gradient[k], f.value[k], 1e-12 * c_rel)
        assert np.allclose(f.xbar[k], Xk.mean(axis=0), rtol=0, atol=1e-13 * np.abs(Xk).max())
    # the strain and the rotation are the parts of the gradient
    np.testing.assert_allclose(pi.strain(v), 0.5 * (f.gradient + f.gradient.transpose(0, 2, 1)))
    np.testing.assert_allclose(f.rotation, 0.5 * (f.gradient[:, 1, 0] - f.gradient[:, 0, 1]))
    # linear fields are reproduced exactly, also at points inside the cells
    A, b = rng.normal(size=(2, 2)), rng.normal(size=2)
    lin = pi(mesh.points @ A.T + b)
    scale = 1 + np.abs(mesh.points).max()
    np.testing.assert_allclose(lin.gradient, np.broadcast_to(A, lin.gradient.shape), atol=1e-10)
    pts = mesh.points[[c[0] for c in mesh.cells]] * 0.5 + 0.5 * lin.xbar
    np.testing.assert_allclose(
        lin.at(pts, np.arange(mesh.n_cells)), pts @ A.T + b, atol=1e-11 * scale
    )


def test_projection_operator_matches_element_projection(poly_mesh):
    """The global operator and the element matrices share one formula for the rotation:
    the vertex values of Pi v from either agree."""
    _name, mesh = poly_mesh
    v = np.random.default_rng(3).normal(size=(mesh.n_points, 2))
    f = project(mesh, v)
    for _n, (ids, verts) in mesh.groups.items():
        _K, _B, P, _a = element_matrices(mesh.points[verts], MAT)
        from_P = np.einsum("mij,mj->mi", P, v[verts].reshape(len(ids), -1))
        X = mesh.points[verts]
        from_f = f.value[ids, None, :] + np.einsum(
            "mab,mib->mia", f.gradient[ids], X - f.xbar[ids, None, :]
        )
        np.testing.assert_allclose(from_P, from_f.reshape(len(ids), -1), atol=1e-12)


def test_projection_operator_on_meshes(poly_mesh):
    name, mesh = poly_mesh
    A, b = linear_field(6)
    u = mesh.points @ A.T + b
    f = project(mesh, u.ravel())
    assert np.allclose(f.gradient, A[None], rtol=0, atol=1e-12 * np.abs(A).max()), name
    for k, c in enumerate(mesh.cells):
        X = mesh.points[c]
        assert np.allclose(f.xbar[k], X.mean(axis=0), rtol=0, atol=1e-15)
        assert np.allclose(f.at(X, np.full(len(c), k)), u[c], rtol=0, atol=1e-12)
    w = np.random.default_rng(8).normal(size=(mesh.n_points, 2))
    f = project(mesh, w)
    for k, c in enumerate(mesh.cells):
        check_definition(mesh.points[c], w[c], f.gradient[k], f.value[k], 1e-11)
    # evaluation at points located in the mesh; points outside are an error
    rng = np.random.default_rng(9)
    pts = rng.uniform(0.0, 1.0, (200, 2))
    pi = Projection(mesh)
    np.testing.assert_allclose(pi.evaluate(u, pts), pts @ A.T + b, atol=1e-12)
    with pytest.raises(ValueError, match="outside the mesh"):
        pi.evaluate(u, [[2.0, 0.5]])
    with pytest.raises(ValueError, match="expected 2 x"):
        pi(np.zeros(3))
