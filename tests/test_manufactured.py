"""Elasticity alone against a manufactured solution: data, orders on every mesh family."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vemwear.cli.main import main
from vemwear.paper import manufactured as mf

FAMILIES = mf.available_families()


def test_hand_derived_data_symbolically() -> None:
    """f1 = -div sigma(u), sigma and grad u as written out in the module docstring."""
    import sympy  # in the test extras: this test must run, not skip

    x, y, lam, eta = sympy.symbols("x y lam eta")
    u = sympy.Matrix([sympy.sin(sympy.pi * x) * sympy.sin(sympy.pi * y), x**2 * y])
    grad = u.jacobian([x, y])
    eps = (grad + grad.T) / 2
    sig = 2 * eta * eps + lam * eps.trace() * sympy.eye(2)
    div = sympy.Matrix([sympy.diff(sig[i, 0], x) + sympy.diff(sig[i, 1], y) for i in range(2)])
    rng = np.random.default_rng(1)
    pts = rng.random((7, 2))
    L, E = 2.3, 0.7
    subs = {lam: L, eta: E}
    f = sympy.lambdify((x, y), -div.subs(subs), "numpy")
    s = sympy.lambdify((x, y), sig.subs(subs), "numpy")
    g = sympy.lambdify((x, y), grad, "numpy")
    for p in pts:
        np.testing.assert_allclose(
            mf.body_force(p[None], 0.0, L, E)[0],
            np.asarray(f(*p), float).ravel(),
            rtol=1e-12,
            atol=1e-12,
        )
        np.testing.assert_allclose(
            mf.exact_stress(p[None], L, E)[0], np.asarray(s(*p), float), rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(
            mf.exact_gradient(p[None])[0], np.asarray(g(*p), float), rtol=1e-12, atol=1e-12
        )
    top, bottom = np.array([[0.3, 1.0]]), np.array([[0.6, 0.0]])
    np.testing.assert_allclose(
        mf.traction(top, 0.0, L, E)[0], mf.exact_stress(top, L, E)[0] @ [0.0, 1.0]
    )
    np.testing.assert_allclose(
        mf.traction(bottom, 0.0, L, E)[0], mf.exact_stress(bottom, L, E)[0] @ [0.0, -1.0]
    )


def test_linear_solution_is_reproduced() -> None:
    """Patch test through the same assembly: a linear u with f1 = 0 and constant traction."""
    from vemwear.vem import Material, edge_load_vector, stiffness

    for fam in FAMILIES:
        m = mf.family_mesh(fam, 4)
        mat = Material(lam=mf.LAM, eta=mf.ETA)
        B = np.array([[0.01, 0.02], [-0.03, 0.015]])
        eps = 0.5 * (B + B.T)
        sig = 2 * mat.eta * eps + mat.lam * np.trace(eps) * np.eye(2)
        K = stiffness(m, mat).tocsr()

        def f2(x, t, sig=sig):
            return np.where(x[:, 1:2] > 0.5, 1.0, -1.0) * sig[:, 1][None, :]

        F = edge_load_vector(m, m.part_edges("traction"), f2)
        u_ex = m.points @ B.T
        fixed = np.zeros(2 * m.n_points, bool)
        dv = m.part_vertices("clamped")
        fixed[2 * dv] = fixed[2 * dv + 1] = True
        free = ~fixed
        import scipy.sparse.linalg as spla

        u = u_ex.ravel().copy()
        u[free] = spla.spsolve(K[free][:, free].tocsc(), F[free] - K[free][:, fixed] @ u[fixed])
        np.testing.assert_allclose(u, u_ex.ravel(), atol=1e-12, err_msg=fam)


@pytest.mark.parametrize("family", FAMILIES)
def test_orders_on_every_family(family: str) -> None:
    """H1 order 1 +- 0.2 and L2 order 2 +- 0.3 on n = 8 -> 16 (also 4 -> 8 for H1).

    Exception: the chevron (non-convex) cells. There the vertex average, on which the
    paper's load (Section 3.3, ``|K| P_0 f . (vertex average of v)``) is built, differs
    from the centroid by a fixed O(h) vector in every cell, so the load functional has a
    consistency error of O(h) that does not average out, and the L2 order falls towards 1
    (1.46 at n = 16, 1.30 at n = 32). Evaluating the load at the centroid through Pi
    restores order 2 (checked during development), so this is a property of the
    paper's scheme, not of the code; we assert L2 order >= 1.0 there.
    """
    rows = mf.convergence_study([family], levels=3, n0=4)
    h1 = [r["H1_order"] for r in rows[1:]]
    l2 = rows[-1]["L2_order"]
    nodal = rows[-1]["nodal_order"]
    assert all(abs(o - 1.0) <= 0.2 for o in h1), (family, h1)
    if family == "nonconvex":
        assert l2 >= 1.0, (family, l2)
    else:
        assert abs(l2 - 2.0) <= 0.3, (family, l2)
        assert abs(nodal - 2.0) <= 0.3, (family, nodal)
    assert rows[-1]["H1_rel"] < 0.2


def test_triangles_stabilization_free() -> None:
    """On triangles the VEM is P1: the stabilization does not change the solution."""
    m = mf.family_mesh("triangles", 4)
    np.testing.assert_allclose(
        mf.solve(m, stabilization="paper"), mf.solve(m, stabilization="eta"), atol=1e-12
    )


def test_cli_manufactured(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    csv = tmp_path / "t.csv"
    assert (
        main(
            ["manufactured", "--families", "squares,triangles", "--levels", "2", "--csv", str(csv)]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "squares" in out and "triangles" in out and "H1 error" in out
    assert len(csv.read_text().splitlines()) == 5
    assert main(["manufactured", "--families", "nope"]) == 2
    assert main(["manufactured", "--levels", "0"]) == 2
    assert math.isfinite(float(csv.read_text().splitlines()[2].split(",")[7]))
