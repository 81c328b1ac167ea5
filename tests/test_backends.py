"""Sparse backends: the Schur block, block solves, the same results from every backend.

The backend-specific tests skip when their backend is not installed; the fallback to
SciPy's SuperLU is tested with PARDISO hidden, so both paths run wherever the suite
runs.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from vemwear.paper import ex52
from vemwear.simulate import SolverOptions, simulate
from vemwear.solvers import backends
from vemwear.solvers.backends import (
    BACKENDS,
    PARDISO_MIN_SIZE,
    available_backends,
    compliance_from_schur,
    factorize,
    resolve_backend,
    schur_factorize,
)
from vemwear.solvers.backends.superlu import SuperLUFactor

INSTALLED = available_backends()
needs_pardiso = pytest.mark.skipif("pardiso" not in INSTALLED, reason="pypardiso not installed")


def rel(a, b) -> float:
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


@pytest.fixture(scope="module")
def small_problem():
    return ex52.problem(0.2, 2.0, divisions=(16, 8), steps=8)


@pytest.fixture
def no_pardiso(monkeypatch):
    """PARDISO reported as not installed, as on a machine without MKL wheels."""
    from vemwear.solvers.backends import pardiso

    monkeypatch.setattr(pardiso, "available", lambda: False)


def test_auto_backend_choice():
    assert INSTALLED[-1] == "scipy"
    assert resolve_backend("auto") == INSTALLED[0]
    assert resolve_backend("auto", 10, many_factorizations=True) == "scipy"
    assert resolve_backend("scipy", 10**6, True) == "scipy"
    with pytest.raises(ValueError, match="unknown linear-algebra backend"):
        resolve_backend("superlu-mt")


def test_auto_falls_back_to_scipy(no_pardiso):
    assert available_backends() == ["scipy"]
    assert resolve_backend("auto") == "scipy"
    assert resolve_backend("auto", 10**6, many_factorizations=True) == "scipy"
    with pytest.raises(ValueError, match="'pardiso' asked for but it is not installed"):
        resolve_backend("pardiso")


@pytest.mark.parametrize("backend", INSTALLED)
@pytest.mark.parametrize("reverse", [False, True])
def test_schur_factor_gives_the_block_of_the_inverse(small_problem, backend, reverse):
    s = small_problem.discrete.system
    c = s.contact_dofs.ravel()
    if reverse:  # the Schur dofs in an order of the caller's choosing
        c = c[::-1].copy()
    f = schur_factorize(s.K, c, s.dof_points, backend)
    assert f.name == backend and f.n == s.n_free
    assert set(f.timings) >= {"ordering", "factorization", "schur"}
    E = np.zeros((s.n_free, len(c)))
    E[c, np.arange(len(c))] = 1.0
    Kinv_cc = SuperLUFactor(s.K).solve(E)[c]
    assert rel(f.S_inv, Kinv_cc) <= 1e-12
    assert np.array_equal(f.S_inv, f.S_inv.T)
    rng = np.random.default_rng(0)
    b = rng.normal(size=s.n_free)
    assert rel(s.K @ f.solve(b), b) <= 1e-12
    B = rng.normal(size=(s.n_free, 5))
    X = f.solve(B)
    assert X.shape == B.shape and rel(s.K @ X, B) <= 1e-12
    assert rel(X[:, 2], f.solve(B[:, 2])) <= 1e-14


def test_compliance_from_schur_reads_the_lower_triangle():
    rng = np.random.default_rng(3)
    G = rng.normal(size=(40, 40))
    S = G @ G.T + 40 * np.eye(40)
    C = compliance_from_schur(S)
    assert np.array_equal(C, C.T)
    assert rel(C @ S, np.eye(40)) <= 1e-12
    garbage_upper = np.tril(S) + np.triu(rng.normal(size=(40, 40)), 1)
    assert np.array_equal(compliance_from_schur(garbage_upper), C)
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        compliance_from_schur(-S)


@pytest.mark.parametrize("backend", INSTALLED)
def test_factorize_solves_vectors_and_blocks(small_problem, backend):
    K = small_problem.discrete.system.K
    rng = np.random.default_rng(1)
    b, B = rng.normal(size=K.shape[0]), rng.normal(size=(K.shape[0], 3))
    for symmetric in (True, False):
        f = factorize(K, backend, symmetric=symmetric)
        assert rel(K @ f.solve(b), b) <= 1e-12
        assert rel(K @ f.solve(B), B) <= 1e-12


@needs_pardiso
def test_pardiso_full_and_partial_solves_agree(small_problem):
    s = small_problem.discrete.system
    f = schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, "pardiso")
    B = np.random.default_rng(2).normal(size=(s.n_free, 4))
    assert rel(f.solve_partial(B), f.solve(B)) <= 1e-12
    assert rel(s.K @ f.solve_partial(B), B) <= 1e-12


@needs_pardiso
@pytest.mark.parametrize(("factor_threads", "solve_threads"), [(2, 1), (1, 2)])
def test_pardiso_solves_whatever_mkl_threads_the_caller_sets(factor_threads, solve_threads):
    """MKL's one-column solve after a Schur factorization is wrong when MKL's thread
    count changed since the factorization (seen with MKL 2026.2 from 4,224 unknowns
    on); the handle pins it."""
    from threadpoolctl import ThreadpoolController

    s = ex52.problem(0.2, 2.0, divisions=(64, 32), steps=1).discrete.system
    schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, "pardiso")  # MKL loaded
    mkl = ThreadpoolController().select(internal_api="mkl")
    assert mkl.lib_controllers, "MKL is not seen by threadpoolctl"
    with mkl.limit(limits=factor_threads):
        f = schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, "pardiso")
    rng = np.random.default_rng(5)
    for k in (1, 3):
        b = rng.normal(size=s.n_free) if k == 1 else rng.normal(size=(s.n_free, k))
        with mkl.limit(limits=solve_threads):
            x = f.solve(b)
        assert rel(s.K @ x, b) <= 1e-12


@needs_pardiso
def test_auto_factorizes_small_matrices_on_one_mkl_thread(small_problem):
    """Below SCHUR_SERIAL_MAX unknowns "auto" makes PARDISO's Schur factorization on one
    MKL thread, keeps that count for its solves, leaves the caller's count as it was,
    and gives the results of PARDISO on its threads to round-off."""
    from vemwear.solvers.backends.pardiso import _thread_functions

    get_threads = _thread_functions()[0]
    s = small_problem.discrete.system
    assert s.K.shape[0] < backends.SCHUR_SERIAL_MAX
    before = get_threads()
    f = schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, "auto")
    assert f.name == "pardiso" and f._h.threads == 1 and get_threads() == before
    g = schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, "pardiso")
    assert g._h.threads == before
    assert rel(f.S_inv, g.S_inv) <= 1e-12
    b = np.random.default_rng(3).normal(size=(s.n_free, 3))
    assert rel(f.solve(b), g.solve(b)) <= 1e-12 and rel(s.K @ f.solve(b), b) <= 1e-12


@needs_pardiso
def test_pardiso_rejects_a_matrix_that_is_not_spd(small_problem):
    s = small_problem.discrete.system
    with pytest.raises(RuntimeError, match="not positive definite"):
        schur_factorize(-s.K, s.contact_dofs.ravel(), s.dof_points, "pardiso")


@needs_pardiso
def test_backends_give_the_same_results(small_problem):
    """Condensed Newton with every backend: u, wear and both pressures to 1e-12."""
    ref = simulate(small_problem, SolverOptions("newton", backend="scipy"))
    for backend in INSTALLED[:-1]:
        r = simulate(small_problem, SolverOptions("newton", backend=backend))
        for k in ("u", "wear", "p_rigid", "p_soft", "u_nu"):
            assert rel(getattr(r, k), getattr(ref, k)) <= 1e-12, (backend, k)


@needs_pardiso
def test_pardiso_full_newton_and_uzawa(small_problem):
    pr = small_problem
    r1 = simulate(pr, SolverOptions("newton-full", backend="pardiso"))
    r2 = simulate(pr, SolverOptions("newton-full", backend="scipy"))
    r3 = simulate(pr, SolverOptions("uzawa", backend="pardiso"))
    for r in (r1, r3):
        for k in ("u", "wear", "p_rigid"):
            assert rel(getattr(r, k), getattr(r2, k)) <= 1e-8
    assert sp.issparse(pr.discrete.system.K) and pr.discrete.system.K.shape[0] < PARDISO_MIN_SIZE


def test_forced_scipy_fallback_runs_the_condensed_solver(small_problem, no_pardiso):
    solver = SolverOptions("newton", backend="auto").build(small_problem.discrete.system)
    assert solver.factor.name == "scipy"
    r = simulate(small_problem, SolverOptions("newton", backend="auto"))
    ref = simulate(small_problem, SolverOptions("newton-full", backend="scipy"))
    for k in ("u", "wear", "p_rigid", "p_soft"):
        assert rel(getattr(r, k), getattr(ref, k)) <= 1e-10, k


def test_backend_names_are_consistent():
    assert set(backends.PREFERENCE) | set(backends.ON_REQUEST) | {"auto"} == set(BACKENDS)
    assert not set(backends.PREFERENCE) & set(backends.ON_REQUEST)
    assert set(INSTALLED) <= set(backends.PREFERENCE)


def test_solver_threads_limit_the_openblas_pools(monkeypatch):
    from threadpoolctl import threadpool_info

    from vemwear.solvers.threads import solver_threads

    def openblas_threads() -> list[int]:
        return [d["num_threads"] for d in threadpool_info() if d["internal_api"] == "openblas"]

    before = openblas_threads()
    with solver_threads():
        assert all(t == 1 for t in openblas_threads())
    assert openblas_threads() == before
    monkeypatch.setenv("VEMWEAR_BLAS_THREADS", "keep")
    with solver_threads():
        assert openblas_threads() == before


def test_kept_factorizations_are_reused_only_for_the_same_matrix(monkeypatch):
    """With keep_factorizations, runs that change only contact data (kappa, mu) reuse one
    factorization and give bitwise the results of fresh ones; another mesh does not."""
    fresh = [simulate(ex52.problem(mu, k, divisions=(16, 8), steps=8)) for mu, k in CASES]
    made: list[str] = []
    for name, cls in (("scipy", "SuperLUSchur"), ("pardiso", "PardisoSchur")):
        mod = backends._module(name)
        base = getattr(mod, cls)
        monkeypatch.setattr(
            mod, cls, type(cls, (base,), {"__init__": _counted(base.__init__, made)})
        )
    try:
        backends.keep_factorizations(1)
        kept = [simulate(ex52.problem(mu, k, divisions=(16, 8), steps=8)) for mu, k in CASES]
        assert len(made) == 1  # the second run found the first one's factorization
        other = simulate(ex52.problem(0.2, 2.0, divisions=(8, 4), steps=8))
        assert len(made) == 2 and len(backends._KEPT) == 1
    finally:
        backends.keep_factorizations(0)
    assert not backends._KEPT
    for a, b in zip(kept, fresh, strict=True):
        for k in ("u", "wear", "p_rigid", "p_soft"):
            assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert other.wear.shape[1] < kept[0].wear.shape[1]


CASES = ((0.2, 2.0), (0.6, 10.0))


def _counted(init, made):
    def __init__(self, *args, **kwargs):
        made.append(type(self).__name__)
        init(self, *args, **kwargs)

    return __init__
