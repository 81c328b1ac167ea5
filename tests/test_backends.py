"""Linear-algebra backends give the same results; PARDISO is optional."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from vemwear.paper import ex52
from vemwear.simulate import SolverOptions, simulate
from vemwear.solvers.linalg import (
    PARDISO_MIN_SIZE,
    SchurFactor,
    SuperLUFactor,
    factorize,
    resolve_backend,
)


def test_auto_backend_choice():
    assert resolve_backend("auto", 10**6, many_factorizations=False) == "scipy"
    assert resolve_backend("auto", 10, many_factorizations=True) == "scipy"
    assert resolve_backend("scipy", 10**6, True) == "scipy"
    with pytest.raises(ValueError, match="unknown linear-algebra backend"):
        resolve_backend("mumps")


def test_schur_factor_gives_the_block_of_the_inverse():
    pr = ex52.problem(0.2, 2.0, divisions=(16, 8), steps=2)
    s = pr.discrete.system
    f = SchurFactor(s.K, s.contact_dofs.ravel(), s.dof_points)
    c = s.contact_dofs.ravel()
    E = np.zeros((s.n_free, len(c)))
    E[c, np.arange(len(c))] = 1.0
    Kinv_cc = SuperLUFactor(s.K).solve(E)[c]
    assert np.abs(f.S_inv - Kinv_cc).max() <= 1e-12 * np.abs(Kinv_cc).max()
    b = np.random.default_rng(0).normal(size=s.n_free)
    assert np.abs(s.K @ f.solve(b) - b).max() <= 1e-10 * np.abs(b).max()


def test_pardiso_backend_same_results():
    pytest.importorskip("pypardiso")
    pr = ex52.problem(0.2, 2.0, divisions=(16, 8), steps=8)
    K = pr.discrete.system.K
    b = np.random.default_rng(1).normal(size=(K.shape[0], 3))
    x1 = factorize(K, "pardiso").solve(b)
    x2 = factorize(K, "scipy").solve(b)
    assert np.abs(x1 - x2).max() <= 1e-10 * np.abs(x2).max()
    r1 = simulate(pr, SolverOptions("newton-full", backend="pardiso"))
    r2 = simulate(pr, SolverOptions("newton-full", backend="scipy"))
    r3 = simulate(pr, SolverOptions("uzawa", backend="pardiso"))
    for r in (r1, r3):
        for k in ("u", "wear", "p_rigid"):
            a, b_ = getattr(r, k), getattr(r2, k)
            assert np.abs(a - b_).max() <= 1e-8 * max(np.abs(b_).max(), 1e-300)
    assert sp.issparse(K) and K.shape[0] < PARDISO_MIN_SIZE
