"""The residual a posteriori estimator (docs/method.md section 11): its terms on fields
with known residuals, and its effectivity against a manufactured solution and a Hertz
contact."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vemwear import simulate
from vemwear.mesh import rectangle_squares
from vemwear.mesh.refine import refine_cells, refine_where
from vemwear.paper import manufactured as M
from vemwear.paper.hertz import line_contact
from vemwear.post.energy import energy_error_exact, energy_error_reference
from vemwear.simulate.estimate import TERMS, estimate
from vemwear.vem import Material
from vemwear.vem.estimator import (
    cell_stresses,
    elasticity_terms,
    jump_terms,
    stabilization_terms,
)

MAT = Material(lam=2.0, eta=1.0)


def _hanging_mesh():
    """4 x 2 squares of (0, 2) x (0, 1), the upper cells left of x = 1 refined, then the
    new cells touching x = 1 again: hanging nodes on the line x = 1."""
    mesh = rectangle_squares((2.0, 1.0), (4, 2))
    mesh = refine_where(mesh, lambda c: (c[:, 0] < 1.0) & (c[:, 1] > 0.5))
    return refine_where(mesh, lambda c: (c[:, 0] > 0.75) & (c[:, 0] < 1.0) & (c[:, 1] > 0.5))


def test_a_linear_field_has_no_jumps_and_no_stabilization() -> None:
    mesh = _hanging_mesh()
    G = np.array([[0.3, -0.2], [0.5, 0.1]])
    U = mesh.points @ G.T + np.array([0.1, -0.4])
    sig = cell_stresses(mesh, MAT, U)
    assert np.abs(jump_terms(mesh, sig)).max() < 1e-24
    assert np.abs(stabilization_terms(mesh, MAT, U)).max() < 1e-24
    eps = 0.5 * (G + G.T)
    exact = 2 * MAT.eta * eps + MAT.lam * np.trace(eps) * np.eye(2)
    assert np.allclose(sig, exact, atol=1e-13)


def test_the_jump_across_a_line_with_hanging_nodes() -> None:
    """u = ((x - 1)_+, 0): the stress jumps by (lam + 2 eta, 0) across x = 1, where the
    cells on the left have hanging nodes; the jump term is the sum over the pieces of
    |e|^2 (lam + 2 eta)^2, half to each side."""
    mesh = _hanging_mesh()
    U = np.column_stack([np.maximum(mesh.points[:, 0] - 1.0, 0.0), 0 * mesh.points[:, 0]])
    sig = cell_stresses(mesh, MAT, U)
    J = jump_terms(mesh, sig)
    on_line = np.sort(mesh.points[np.abs(mesh.points[:, 0] - 1.0) < 1e-12, 1])
    pieces = np.diff(on_line)
    assert len(pieces) > 2  # hanging nodes split the line's sides
    expected = np.sum(pieces**2) * (MAT.lam + 2 * MAT.eta) ** 2
    assert J.sum() == pytest.approx(expected, rel=1e-12)
    # half to the cells on each side
    xc = np.array([mesh.points[c].mean(axis=0)[0] for c in mesh.cells])
    assert J[xc < 1].sum() == pytest.approx(expected / 2, rel=1e-12)
    assert np.abs(stabilization_terms(mesh, MAT, U)).max() < 1e-24


@pytest.mark.parametrize("family", ["squares", "voronoi", "hanging", "distorted"])
def test_effectivity_on_the_manufactured_solution(family: str) -> None:
    """estimate / energy error between 0.3 and 3, and steady under refinement."""
    eff = []
    for n in (8, 16):
        mesh = M.family_mesh(family, n)
        U = M.solve(mesh)
        terms, _ = elasticity_terms(mesh, MAT, U, M.body_force, {"traction": M.traction})
        eta = np.sqrt(sum(float(v.sum()) for v in terms.values()))
        err = np.sqrt(energy_error_exact(mesh, MAT, U, M.exact_gradient).sum())
        eff.append(eta / err)
    assert all(0.3 < e < 3.0 for e in eff), eff
    assert abs(eff[1] / eff[0] - 1) < 0.1, eff


def _uniform(problem, k: int):
    mesh = problem.mesh
    for _ in range(k):
        mesh = refine_cells(mesh, np.arange(mesh.n_cells))
    return dataclasses.replace(problem, mesh=mesh)


def test_effectivity_on_a_hertz_contact() -> None:
    """The 2D Hertz line contact under load control (Signorini, rigid layer) against the
    same problem on the mesh refined uniformly twice."""
    pr = line_contact(0.05, 3, n=16)
    ref = _uniform(pr, 2)
    rr = simulate(ref, "newton")
    r = simulate(pr, "newton")
    est = estimate(pr, r.u[-1], r.p_rigid[-1])
    err2 = energy_error_reference(pr.mesh, pr.material, r.u[-1], ref.mesh, rr.u[-1])
    eff = est.total / np.sqrt(err2.sum())
    assert 0.3 < eff < 3.0, eff
    share = est.share()
    assert set(share) == set(TERMS)
    assert share["contact"] > 0.01 and share["complementarity"] > 0.0
    assert np.all(est.indicators >= 0)
    # the contact terms sit on the cells along Gamma_C
    cells = np.unique(pr.mesh.boundary_edge_cells[pr.mesh.boundary_tags == 3])
    off = np.setdiff1d(np.arange(pr.mesh.n_cells), cells)
    assert np.all(est.terms["contact"][off] == 0) and np.all(est.terms["complementarity"][off] == 0)


def test_the_estimate_refuses_a_wrong_pressure_array() -> None:
    pr = line_contact(0.05, 1, n=8)
    with pytest.raises(ValueError, match="one value per contact node"):
        estimate(pr, np.zeros((pr.mesh.n_points, 2)), np.zeros(3))
