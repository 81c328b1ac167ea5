"""The Schur factorization of the condensed solver on 3D stiffness matrices.

On small 3D problems (hexahedra 4 x 2 x 2, Voronoi polyhedra, tetrahedra; contact on
z = 0) every installed backend gives the block of ``K^{-1}`` on the contact dofs
(``S_inv``) and the solves with ``K`` to round-off of a dense inverse, the backends
agree with each other, and a singular or indefinite ``K`` raises FactorizationError
before any solve.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from vemwear.mesh.generate3d import box_hexahedra, box_tetrahedra
from vemwear.mesh.voronoi3d import box_voronoi
from vemwear.paper.ex3d import problem3d
from vemwear.solvers.backends import available_backends, schur_factorize
from vemwear.solvers.system import FactorizationError

INSTALLED = available_backends()
MESHES = {
    "hexahedra": lambda: box_hexahedra((2.0, 1.0, 1.0), (4, 2, 2)),
    "voronoi3d": lambda: box_voronoi((2.0, 1.0, 1.0), 24, seed=1),
    "tetrahedra": lambda: box_tetrahedra((2.0, 1.0, 1.0), (4, 2, 2)),
}


def rel(a, b) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


@pytest.fixture(scope="module", params=list(MESHES))
def system3d(request):
    """K on the free dofs, the contact dofs in the solver's order, the dof points."""
    s = problem3d(MESHES[request.param](), 2).discrete.system
    cd = s.contact_dofs.ravel()
    return sp.csr_matrix(s.K), cd[cd >= 0], s.dof_points


@pytest.mark.parametrize("backend", INSTALLED)
def test_schur_block_and_solves_match_a_dense_inverse(system3d, backend):
    K, last, points = system3d
    Kinv = np.linalg.inv(K.toarray())
    f = schur_factorize(K, last, points, backend)
    assert f.S_inv.shape == (len(last), len(last))
    assert rel(f.S_inv, Kinv[np.ix_(last, last)]) <= 1e-12
    assert np.array_equal(f.S_inv, f.S_inv.T)
    rng = np.random.default_rng(0)
    B = rng.normal(size=(K.shape[0], 4))
    assert rel(f.solve(B), Kinv @ B) <= 1e-12
    assert rel(f.solve(B[:, 1]), Kinv @ B[:, 1]) <= 1e-12
    # the contact dofs in another order give the same block, permuted
    order = rng.permutation(len(last))
    g = schur_factorize(K, last[order], points, backend)
    assert rel(g.S_inv, f.S_inv[np.ix_(order, order)]) <= 1e-12


def test_backends_agree_on_3d(system3d):
    K, last, points = system3d
    blocks = [schur_factorize(K, last, points, b).S_inv for b in INSTALLED]
    for S_inv in blocks[1:]:
        assert rel(S_inv, blocks[0]) <= 1e-12


@pytest.mark.parametrize("backend", INSTALLED)
@pytest.mark.parametrize("kind", ["indefinite", "singular"])
def test_singular_or_indefinite_stiffness_raises(system3d, backend, kind):
    K, last, points = system3d
    if kind == "indefinite":
        bad = -K
    else:  # a dof without stiffness: a zero row and column, as an unconstrained node
        keep = np.ones(K.shape[0])
        keep[last[0]] = 0.0
        D = sp.diags(keep)
        bad = sp.csr_matrix(D @ K @ D)
    with pytest.raises(FactorizationError, match="could not be factorized"):
        schur_factorize(bad, last, points, backend)


@pytest.mark.parametrize("c", [1, 7, 16, 37])
def test_pardiso_transposes_its_schur_output_in_place(c):
    from vemwear.solvers.backends.pardiso import _transpose_in_place

    A = np.random.default_rng(c).normal(size=(c, c))
    B = A.copy()
    _transpose_in_place(B, block=8)  # tiles that do not divide c
    assert np.array_equal(B, A.T)
